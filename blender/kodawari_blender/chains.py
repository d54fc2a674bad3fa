"""bpy.ops.kodawari.bake_chains: the active armature's chains (hair, tails, ears, VRM spring
bones) set up as `kodawari rig` sets them up, simulated with the armature's own
animation as input, and baked into a new action on the chain bones, in an NLA track of
its own ("Kodawari chains") above the armature's animation: the user's keys are never
touched.

The armature (with its meshes and its animation) goes to Kodawari as Blender's glTF
exporter writes it; Kodawari rigs and simulates it and writes the character back with the
chain bones animated (the rigged export); Blender's importer reads that into a temporary
armature, whose chain bones' matrices are carried over onto the user's bones (each
bone's constant difference of rest orientation between the two taken out), frame by
frame, and keyed; the temporary objects are removed.

With `vrm_path`, the chains, their physics and the colliders are read from the .vrm file
the armature was imported from (its VRMC_springBone / VRM 0.x secondaryAnimation, which
Blender's glTF importer drops), as `kodawari rig` reads them, and set on the exported
armature: the two files name the same nodes, but Blender's round trip gives the bones
rest orientations of its own, so each collider's shape (in its joint's frame) is turned
from the VRM joint's frame into the exported one's.

The work runs as a jobs.Job: in chunks, cancellable with nothing left behind.
"""
import json
import os
import struct
import time

import bpy
import numpy
from mathutils import Vector

from . import build, jobs
from .flock import BACKEND_ITEMS, FlockError, import_gltf, kodawari, to_kodawari


def chain_bones(armature, root, joints):
    """The bone names of a chain: its root bone, then first children down to `joints`."""
    bone = armature.data.bones.get(root)
    if bone is None:
        raise FlockError(f"armature '{armature.name}' has no bone '{root}', which Kodawari found as a chain root")
    names = [bone.name]
    while len(names) < joints and bone.children:
        bone = bone.children[0]
        names.append(bone.name)
    return names


def set_camera(description, scene):
    """The scene's active camera as Kodawari's: the view examples are chosen by it."""
    camera = scene.camera
    if camera is None:
        return  # the rig's orbit around the head
    m = camera.matrix_world
    forward = m.to_3x3() @ Vector((0.0, 0.0, -1.0))  # a camera looks down its -Z
    position = m.translation
    description["camera"] = {"position": to_kodawari(position), "target": to_kodawari(position + forward * 10.0)}


def glb_json(path):
    """The JSON chunk of a glTF binary (.glb, .vrm): the 12-byte header, then the first
    chunk, which the glTF 2.0 specification requires to be the JSON."""
    with open(path, "rb") as file:
        head = file.read(20)
        if len(head) < 20 or head[:4] != b"glTF":
            raise FlockError(f"'{path}' is not a glTF binary (.vrm, .glb)")
        length, kind = struct.unpack_from("<II", head, 12)
        if kind != 0x4E4F534A:  # "JSON"
            raise FlockError(f"'{path}': its first chunk is not JSON")
        return json.loads(file.read(length))


def rest_rotations(document, roots):
    """name -> the node's rest rotation (3x3, scale removed) relative to the parent of the
    node named first in `roots` that the file has (the armature's frame: Blender's exporter
    writes the armature object as that parent; a VRM's skeleton root may have one or not)."""
    nodes = document.get("nodes", [])
    parent = {}
    for index, node in enumerate(nodes):
        for child in node.get("children", []):
            parent[child] = index

    def local(node):
        if "matrix" in node:
            m = numpy.array(node["matrix"], numpy.float64).reshape(4, 4).T  # column-major
            return m[:3, :3] / numpy.linalg.norm(m[:3, :3], axis=0)
        q = numpy.array(node.get("rotation", [0.0, 0.0, 0.0, 1.0]), numpy.float64)
        return build.quaternion_matrices(q / numpy.linalg.norm(q))

    world = {}

    def rotation(index):
        if index not in world:
            above = rotation(parent[index]) if index in parent else numpy.eye(3)
            world[index] = above @ local(nodes[index])
        return world[index]

    names = {node.get("name"): index for index, node in enumerate(nodes)}
    top = next((names[r] for r in roots if r in names), None)
    frame = rotation(parent[top]) if top is not None and top in parent else numpy.eye(3)
    return {node.get("name"): frame.T @ rotation(index) for index, node in enumerate(nodes) if node.get("name")}


def vrm_scene(vrm, exported, armature, scene_path, duration, clip):
    """The scene of `kodawari rig VRM` made to simulate `exported` (the armature as
    Blender exported it, with its animation): returns (chains, description)."""
    try:
        chains = kodawari.rig(vrm, scene_path, duration=duration)
    except kodawari.Error as error:
        raise FlockError(f"VRM file: {error}") from error
    with open(scene_path) as file:
        description = json.load(file)
    character = description["characters"][0]
    theirs, ours = glb_json(vrm), glb_json(exported)
    roots = [b.name for b in armature.data.bones if b.parent is None]
    source, target = rest_rotations(theirs, roots), rest_rotations(ours, roots)

    def node(name, where):
        if not isinstance(name, str) or name not in target or name not in source:
            raise FlockError(f"the VRM file's spring data names node {name!r} ({where}), which armature "
                             f"'{armature.name}' has no bone of: is it the armature imported from this file?")
        return name

    node(character.get("reference_joint", roots[0] if roots else None), "reference_joint")
    for chain in character["chains"]:
        for name in ([chain["root"]] if "root" in chain else chain["nodes"]):
            node(name, f"chain {chain['name']}")
        if "center" in chain:
            node(chain["center"], f"chain {chain['name']} center")
    for collider in character.get("colliders", []):
        joint = node(collider["joint"], f"collider {collider.get('name', '')}")
        # A shape in the VRM joint's frame, v, is at R_vrm v from the joint in the
        # armature's frame; in the exported joint's frame that is R_ours^T R_vrm v.
        turn = target[joint].T @ source[joint]
        for key in ("center", "a", "b", "point", "normal"):
            if key in collider:
                collider[key] = [float(x) for x in turn @ numpy.array(collider[key], numpy.float64)]
    character["gltf"] = exported
    character.pop("animate", None)
    character.pop("animation", None)
    clips = [a.get("name", f"animation{i}") for i, a in enumerate(ours.get("animations", []))]
    if clip in clips:
        character["animation"] = clip
    elif not clips:
        character["animate"] = False  # the rest pose: an armature without animation
    return chains, description


def bake_steps(job, armature, frames, backend, vrm="", frames_per_chunk=10, bones_per_chunk=8):
    """Bakes `armature`'s chains as a Job's operation (jobs.py); returns (the action, its
    NLA track, the chains). Chunks: export, rig, simulation and bake, import, then
    `frames_per_chunk` frames read and `bones_per_chunk` bones keyed at a time."""
    scene = job.scene
    fps = scene.render.fps / scene.render.fps_base
    action = armature.animation_data.action if armature.animation_data else None
    folder = job.folder
    yield 0.0, "exporting the armature"
    exported = os.path.join(folder, f"{armature.name}.glb")
    for obj in job.view_layer.objects:
        if obj is not None and obj.select_get():
            obj.select_set(False)
    armature.select_set(True)
    for child in armature.children:
        child.select_set(True)
    job.view_layer.objects.active = armature
    if armature.animation_data is None:
        armature.animation_data_create()  # Blender 3.4's exporter fails on an armature without it
        job.on_cancel(armature.animation_data_clear)
    result = bpy.ops.export_scene.gltf(filepath=exported, export_format='GLB', use_selection=True)
    if 'FINISHED' not in result:
        raise FlockError(f"Blender's glTF exporter did not finish ({sorted(result)})")
    yield 0.1, "finding the chains"
    scene_path = os.path.join(folder, "chains.json")
    # The exporter names an animation after the NLA track that holds the action, else
    # after the action.
    clip = ""
    if action is not None:
        clip = next((t.name for t in armature.animation_data.nla_tracks
                     if any(strip.action == action for strip in t.strips)), action.name)
    if vrm:
        chains, description = vrm_scene(vrm, exported, armature, scene_path, frames / fps, clip)
    else:
        try:
            try:
                chains = kodawari.rig(exported, scene_path, clip=clip, duration=frames / fps)
            except kodawari.Error as error:
                if not clip or "no animation is called" not in str(error):
                    raise
                chains = kodawari.rig(exported, scene_path, duration=frames / fps)  # the file's first
        except kodawari.Error as error:
            raise FlockError(f"armature '{armature.name}': {error}") from error
        with open(scene_path) as file:
            description = json.load(file)
    description["fps"] = fps
    set_camera(description, scene)
    with open(scene_path, "w") as file:
        json.dump(description, file)
    yield 0.15, f"simulating {frames} frames"
    baked = os.path.join(folder, "baked.glb")
    with kodawari.Simulation.open(scene_path, backend, frames=frames) as sim:
        files = sim.bake(baked)
    yield 0.4, "importing the baked chains"
    before = {o.as_pointer() for o in bpy.data.objects}
    before_import = jobs.snapshot()
    import_gltf(files[0])
    imported = [o for o in bpy.data.objects if o.as_pointer() not in before]
    source = next((o for o in imported if o.type == 'ARMATURE'), None)
    if source is None:
        raise FlockError("the baked file has no armature")
    # Only the armature's pose is read: its meshes would be skinned again at every frame_set.
    for obj in [o for o in imported if o is not source]:
        bpy.data.objects.remove(obj)
    imported = [source]
    prefix = source.data.bones[0].name.split("/", 1)[0] + "/"

    names = [n for chain in chains for n in chain_bones(armature, chain[1], chain[2])]
    parents = [armature.data.bones[n].parent.name if armature.data.bones[n].parent else None for n in names]
    needed = sorted(set(names) | {p for p in parents if p})
    # The constant difference between the imported bone's rest and the user's, world space.
    correction = {}
    for n in needed:
        theirs = source.matrix_world @ source.data.bones[prefix + n].matrix_local
        ours = armature.matrix_world @ armature.data.bones[n].matrix_local
        correction[n] = numpy.array(theirs.inverted() @ ours)
    inverse_world = numpy.array(armature.matrix_world.inverted())
    posed = {n: numpy.empty((frames, 4, 4)) for n in needed}
    for f in range(frames):
        if f % frames_per_chunk == 0:
            yield 0.45 + 0.4 * f / frames, f"reading frame {f + 1} of {frames}"
        scene.frame_set(f)  # the importer keys time 0 at frame 0
        for n in needed:
            posed[n][f] = inverse_world @ numpy.array(source.matrix_world @ source.pose.bones[prefix + n].matrix) @ correction[n]
    bases = numpy.empty((frames, len(names), 4, 4))
    for i, (n, p) in enumerate(zip(names, parents)):
        rest = numpy.array(armature.data.bones[n].matrix_local)
        if p is None:
            bases[:, i] = numpy.linalg.inv(rest) @ posed[n]
        else:
            local_rest = numpy.linalg.inv(numpy.array(armature.data.bones[p].matrix_local)) @ rest
            bases[:, i] = numpy.linalg.inv(local_rest) @ numpy.linalg.inv(posed[p]) @ posed[n]
    location, rotation, scale = build.channels(bases)

    baked_action = bpy.data.actions.new(f"{armature.name} kodawari chains")
    baked_action.id_root = 'OBJECT'  # an armature object's; unset, Blender warns on every read of it
    # Kodawari's frame f is glTF time f / fps, which Blender's exporter wrote for frame f
    # (its times are frame / fps, from frame 0) and its importer reads back at frame f.
    keys = numpy.arange(frames, dtype=numpy.float32)
    modes = {}
    job.on_cancel(lambda: [setattr(armature.pose.bones[n], "rotation_mode", m) for n, m in modes.items()])
    for i, n in enumerate(names):
        if i % bones_per_chunk == 0:
            yield 0.85 + 0.15 * i / len(names), f"keying bone {i + 1} of {len(names)}"
        modes.setdefault(n, armature.pose.bones[n].rotation_mode)
        armature.pose.bones[n].rotation_mode = 'QUATERNION'
        build.key(baked_action, n, "location", location[:, i], keys)
        build.key(baked_action, n, "rotation_quaternion", rotation[:, i], keys)
        build.key(baked_action, n, "scale", scale[:, i], keys)
    for obj in imported:
        bpy.data.objects.remove(obj)
    data = armature.animation_data
    track = data.nla_tracks.new()
    track.name = "Kodawari chains"
    track.strips.new(baked_action.name, 0, baked_action)
    # What the import made and nothing uses now (the baked file's armature, mesh, action
    # and materials; the baked action is the strip's): left, they would pile up in the
    # file at every bake.
    jobs.remove_unused_new(before_import)
    return baked_action, track, chains


def start_bake(context, armature, settings):
    """The bake of `armature`'s chains with the operator's `settings` (its properties, or
    any object with the same attributes) as a jobs.Job: nothing changes until it runs."""
    scene = context.scene
    frames = settings.frames or (scene.frame_end + 1)
    vrm = bpy.path.abspath(settings.vrm_path) if getattr(settings, "vrm_path", "") else ""
    if vrm and not os.path.isfile(vrm):
        raise FlockError(f"VRM file '{vrm}' not found")
    if vrm:
        glb_json(vrm)  # a .vrm (a glTF binary), checked before the export and the rig run
    job = jobs.Job(context, "Bake Chains", lambda job: bake_steps(job, armature, frames, settings.backend, vrm))
    job.frames, job.armature = frames, armature
    return job


class KODAWARI_OT_bake_chains(jobs.ModalJob, bpy.types.Operator):
    """Simulate the active armature's hair, tail and ear chains (or VRM spring bones) with
    its own animation and the active camera, and bake them into a new action in an NLA
    track of their own"""
    bl_idname = "kodawari.bake_chains"
    bl_label = "Bake Chains"
    bl_options = {'REGISTER', 'UNDO'}

    frames: bpy.props.IntProperty(name="Frames", description="Frames to bake from frame 0 (the armature's "
                                  "animation's time 0); 0: up to the scene's end frame", default=0, min=0,
                                  max=1000000)
    backend: bpy.props.EnumProperty(name="Backend", items=BACKEND_ITEMS, default="cpu")
    vrm_path: bpy.props.StringProperty(name="VRM File", description="The .vrm file the armature was imported "
                                       "from: its spring bones and colliders, read as `kodawari rig` reads "
                                       "them (empty: chains found by bone names)", default="", subtype='FILE_PATH')

    ERRORS = (kodawari.Error, FlockError, RuntimeError, OSError)

    def start(self, context):
        armature = context.active_object
        if armature is None or armature.type != 'ARMATURE':
            self.report({'ERROR'}, "Bake Chains: make a rigged character's armature the active object")
            return None
        try:
            return start_bake(context, armature, self)
        except (FlockError, OSError, ValueError) as error:  # the VRM file's check: unreadable, a broken JSON chunk
            self.report({'ERROR'}, f"Bake Chains: {error}")
            return None

    def finish(self, context, job):
        action, track, chains = job.result
        self.report({'INFO'}, f"Bake Chains: {len(chains)} chains of '{job.armature.name}', {job.frames} frames, "
                              f"into '{action.name}' (NLA track '{track.name}') in "
                              f"{time.perf_counter() - job.started:.1f} s")
        return {'FINISHED'}
