"""A flock's armatures and actions made directly with bpy.data, from the simulation's poses.

Blender's glTF importer takes time that grows with the square of the objects in the file
(1 000 birds: 201 s), so it makes one bird only, the template: its armature and skinned
mesh, which every bird of the flock shares (one armature data-block and one mesh per wing
type; each bird is an armature object with its own pose and action, and a mesh object
deformed by it). The actions are written from the poses with foreach_set, the way the
importer would have keyed them:

- Kodawari's world transforms (x right, y up) become Blender's (z up) by the rotation
  K = (x, y, z) -> (x, -z, y): a transform (R, p) becomes (K R K^T, K p);
- the importer gives each bone a rest orientation of its own (its bone axis), so a bone's
  pose matrix is the part's world transform times a constant correction, which is read off
  the template at its first frame: correction = W^-1 (template's world transform) x the
  bone's posed matrix there;
- a bone's basis (its F-curves' location, rotation, scale) is
  (parent_rest^-1 rest)^-1 parent_pose^-1 pose, Blender's own composition inverted.
"""
import numpy

import bpy

PARTS = ("Body", "Head", "Tail", "LeftArm1", "LeftArm2", "RightArm1", "RightArm2")
PARENTS = (-1, 0, 0, 0, 3, 0, 5)
TAIL = 2
# Kodawari (+Y up) to Blender (+Z up).
K = numpy.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def quaternion_matrices(q):
    """(..., 4) quaternions x, y, z, w -> (..., 3, 3) rotation matrices."""
    x, y, z, w = (q[..., i].astype(numpy.float64) for i in range(4))
    m = numpy.empty(q.shape[:-1] + (3, 3))
    m[..., 0, 0] = 1 - 2 * (y * y + z * z)
    m[..., 0, 1] = 2 * (x * y - z * w)
    m[..., 0, 2] = 2 * (x * z + y * w)
    m[..., 1, 0] = 2 * (x * y + z * w)
    m[..., 1, 1] = 1 - 2 * (x * x + z * z)
    m[..., 1, 2] = 2 * (y * z - x * w)
    m[..., 2, 0] = 2 * (x * z - y * w)
    m[..., 2, 1] = 2 * (y * z + x * w)
    m[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return m


def matrix_quaternions(m):
    """(..., 3, 3) rotation matrices -> (..., 4) quaternions w, x, y, z (Shepperd's method:
    the largest of the four squares is taken, so no division is by a small number)."""
    m00, m01, m02 = m[..., 0, 0], m[..., 0, 1], m[..., 0, 2]
    m10, m11, m12 = m[..., 1, 0], m[..., 1, 1], m[..., 1, 2]
    m20, m21, m22 = m[..., 2, 0], m[..., 2, 1], m[..., 2, 2]
    squares = numpy.stack([1 + m00 + m11 + m22, 1 + m00 - m11 - m22, 1 - m00 + m11 - m22, 1 - m00 - m11 + m22])
    pick = numpy.argmax(squares, axis=0)
    r = numpy.sqrt(numpy.maximum(numpy.take_along_axis(squares, pick[None], axis=0)[0], 1e-30)) * 2  # 4 |component|
    candidates = numpy.stack([
        numpy.stack([r / 4, (m21 - m12) / r, (m02 - m20) / r, (m10 - m01) / r], -1),
        numpy.stack([(m21 - m12) / r, r / 4, (m01 + m10) / r, (m02 + m20) / r], -1),
        numpy.stack([(m02 - m20) / r, (m01 + m10) / r, r / 4, (m12 + m21) / r], -1),
        numpy.stack([(m10 - m01) / r, (m02 + m20) / r, (m12 + m21) / r, r / 4], -1),
    ])
    return numpy.take_along_axis(candidates, pick[None, ..., None], axis=0)[0]


def world_matrices(poses, spreads):
    """Kodawari world transforms (..., 7, 7) and tail spreads (...) -> Blender world
    matrices (..., 7, 4, 4), the Tail scaled by 1 + spread along its own x."""
    rotation = quaternion_matrices(poses[..., 3:7])
    rotation[..., TAIL, :, 0] *= (1.0 + spreads.astype(numpy.float64))[..., None]
    out = numpy.zeros(poses.shape[:-1] + (4, 4))
    out[..., :3, :3] = K @ rotation @ K.T
    out[..., :3, 3] = poses[..., :3].astype(numpy.float64) @ K.T
    out[..., 3, 3] = 1.0
    return out


class Template:
    """One imported bird: its armature and mesh objects, the rest matrices of its bones and
    the corrections from the parts' transforms to the bones' matrices."""

    def __init__(self, armature, mesh, poses, spreads):
        self.armature, self.mesh = armature, mesh
        bones = [next(b for b in armature.data.bones if b.name.rsplit("/", 1)[-1] == part) for part in PARTS]
        self.rest = numpy.array([numpy.array(b.matrix_local) for b in bones])
        # Each part's world transform at the template's frame 0, and its bone's matrix there.
        world = world_matrices(poses, spreads)
        posed = numpy.array([numpy.array(armature.matrix_world @ armature.pose.bones[b.name].matrix) for b in bones])
        self.correction = numpy.linalg.inv(world) @ posed
        # Plain part names: every bird shares this armature, so its bone names are the parts'
        # (Blender renames the mesh's vertex groups with the bones).
        for bone, part in zip(bones, PARTS):
            old = bone.name
            bone.name = part
            group = mesh.vertex_groups.get(old)
            if group is not None:
                group.name = part

    def bases(self, world):
        """(..., 7, 4, 4) world matrices -> each bone's basis (..., 7, 4, 4) for an armature
        object at the origin."""
        pose = world @ self.correction
        basis = numpy.empty_like(pose)
        for k, parent in enumerate(PARENTS):
            if parent < 0:
                basis[..., k, :, :] = numpy.linalg.inv(self.rest[k]) @ pose[..., k, :, :]
            else:
                rest = numpy.linalg.inv(self.rest[parent]) @ self.rest[k]
                basis[..., k, :, :] = numpy.linalg.inv(rest) @ numpy.linalg.inv(pose[..., parent, :, :]) @ pose[..., k, :, :]
        return basis


def channels(basis):
    """Bases (frames, 7, 4, 4) -> per part: location (frames, 3), rotation (frames, 4, w x y
    z, continuous in sign from frame to frame so that interpolation takes the short way),
    scale (frames, 3)."""
    location = basis[..., :3, 3]
    linear = basis[..., :3, :3]
    scale = numpy.linalg.norm(linear, axis=-2)
    rotation = matrix_quaternions(linear / scale[..., None, :])
    for f in range(1, rotation.shape[0]):
        flip = numpy.sum(rotation[f] * rotation[f - 1], axis=-1) < 0
        rotation[f][flip] *= -1
    return location, rotation, scale


def key(action, part, path, values, frames):
    """Keys `values` (frames, n) into action's F-curves pose.bones[part].path[0..n), linear."""
    count = len(frames)
    for index in range(values.shape[1]):
        curve = action.fcurves.new(f'pose.bones["{part}"].{path}', index=index, action_group=part)
        points = curve.keyframe_points
        points.add(count)
        co = numpy.empty(2 * count, numpy.float32)
        co[0::2] = frames
        co[1::2] = values[:, index]
        points.foreach_set("co", co)
        points.foreach_set("interpolation", numpy.full(count, 1, numpy.int32))  # 'LINEAR', as glTF's samplers
        curve.update()


def make_birds(template, names, poses, spreads, first_frame, collection, chunk=64):
    """One armature object (sharing the template's armature), one mesh object and one action
    per bird. poses: (frames, birds, 7, 7) world transforms; spreads: (frames, birds)."""
    frame_count, birds = poses.shape[:2]
    frames = numpy.arange(frame_count, dtype=numpy.float32) + first_frame
    modifier = next(m for m in template.mesh.modifiers if m.type == 'ARMATURE').name
    made = []
    for begin in range(0, birds, chunk):
        end = min(birds, begin + chunk)
        bases = template.bases(world_matrices(poses[:, begin:end], spreads[:, begin:end]))
        for b in range(begin, end):
            location, rotation, scale = channels(bases[:, b - begin])
            action = bpy.data.actions.new(f"flight_{names[b]}")
            for k, part in enumerate(PARTS):
                if k == 0:
                    key(action, part, "location", location[:, k], frames)
                key(action, part, "rotation_quaternion", rotation[:, k], frames)
                if k == TAIL:
                    key(action, part, "scale", scale[:, k], frames)
            armature = template.armature.copy()
            armature.name = names[b]
            armature.parent = None
            armature.matrix_world.identity()
            armature.animation_data_create().action = action
            mesh = template.mesh.copy()
            mesh.name = f"{names[b]}/mesh"
            mesh.parent = armature
            mesh.modifiers[modifier].object = armature
            collection.objects.link(armature)
            collection.objects.link(mesh)
            made.append(armature)
    return made
