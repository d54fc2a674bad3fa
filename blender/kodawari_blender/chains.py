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
"""
import json
import os
import tempfile
import time

import bpy
import numpy
from mathutils import Vector

from . import build
from .flock import BACKEND_ITEMS, FlockError, import_gltf, kodawari, remove_new, to_kodawari


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


def bake(context, armature, frames, backend, progress):
    """Bakes `armature`'s chains; returns (the action, its NLA track, the chains)."""
    scene = context.scene
    fps = scene.render.fps / scene.render.fps_base
    action = armature.animation_data.action if armature.animation_data else None
    with tempfile.TemporaryDirectory(prefix="kodawari-") as folder:
        exported = os.path.join(folder, f"{armature.name}.glb")
        for obj in context.selected_objects:
            obj.select_set(False)
        armature.select_set(True)
        for child in armature.children:
            child.select_set(True)
        context.view_layer.objects.active = armature
        if armature.animation_data is None:
            armature.animation_data_create()  # Blender 3.4's exporter fails on an armature without it
        result = bpy.ops.export_scene.gltf(filepath=exported, export_format='GLB', use_selection=True)
        if 'FINISHED' not in result:
            raise FlockError(f"Blender's glTF exporter did not finish ({sorted(result)})")
        progress(0.1)
        scene_path = os.path.join(folder, "chains.json")
        # The exporter names an animation after the NLA track that holds the action, else
        # after the action.
        clip = ""
        if action is not None:
            clip = next((t.name for t in armature.animation_data.nla_tracks
                         if any(strip.action == action for strip in t.strips)), action.name)
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
        baked = os.path.join(folder, "baked.glb")
        with kodawari.Simulation.open(scene_path, backend, frames=frames) as sim:
            files = sim.bake(baked)
        progress(0.4)
        before = {o.as_pointer() for o in bpy.data.objects}
        import_gltf(files[0])
    imported = [o for o in bpy.data.objects if o.as_pointer() not in before]
    source = next((o for o in imported if o.type == 'ARMATURE'), None)
    if source is None:
        raise FlockError("the baked file has no armature")
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
        scene.frame_set(f)  # the importer keys time 0 at frame 0
        for n in needed:
            posed[n][f] = inverse_world @ numpy.array(source.matrix_world @ source.pose.bones[prefix + n].matrix) @ correction[n]
        if f % 16 == 0:
            progress(0.4 + 0.5 * f / frames)
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
    # Kodawari's frame f is glTF time f / fps, which Blender's exporter wrote for frame f
    # (its times are frame / fps, from frame 0) and its importer reads back at frame f.
    keys = numpy.arange(frames, dtype=numpy.float32)
    for i, n in enumerate(names):
        armature.pose.bones[n].rotation_mode = 'QUATERNION'
        build.key(baked_action, n, "location", location[:, i], keys)
        build.key(baked_action, n, "rotation_quaternion", rotation[:, i], keys)
        build.key(baked_action, n, "scale", scale[:, i], keys)
    for obj in imported:
        bpy.data.objects.remove(obj)
    data = armature.animation_data or armature.animation_data_create()
    track = data.nla_tracks.new()
    track.name = "Kodawari chains"
    track.strips.new(baked_action.name, 0, baked_action)
    progress(1.0)
    return baked_action, track, chains


class KODAWARI_OT_bake_chains(bpy.types.Operator):
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

    def execute(self, context):
        start = time.perf_counter()
        armature = context.active_object
        if armature is None or armature.type != 'ARMATURE':
            self.report({'ERROR'}, "Bake Chains: make a rigged character's armature the active object")
            return {'CANCELLED'}
        scene = context.scene
        frames = self.frames or (scene.frame_end + 1)
        had_animation = armature.animation_data is not None
        before = {name: {b.as_pointer() for b in getattr(bpy.data, name)}
                  for name in ("objects", "armatures", "meshes", "actions", "materials", "collections", "images")}
        selected = list(context.selected_objects)
        current = scene.frame_current
        modes = {b.name: b.rotation_mode for b in armature.pose.bones}
        wm = context.window_manager
        wm.progress_begin(0.0, 1.0)
        try:
            action, track, chains = bake(context, armature, frames, self.backend, wm.progress_update)
        except (kodawari.Error, FlockError, RuntimeError, OSError) as error:
            remove_new(before)
            for name, mode in modes.items():
                armature.pose.bones[name].rotation_mode = mode
            if not had_animation:
                armature.animation_data_clear()
            self.report({'ERROR'}, f"Bake Chains: {error}")
            return {'CANCELLED'}
        finally:
            wm.progress_end()
            scene.frame_set(current)
            for obj in context.selected_objects:
                obj.select_set(False)
            for obj in selected:
                obj.select_set(True)
            context.view_layer.objects.active = armature
        self.report({'INFO'}, f"Bake Chains: {len(chains)} chains of '{armature.name}', {frames} frames, into "
                              f"'{action.name}' (NLA track '{track.name}') in {time.perf_counter() - start:.1f} s")
        return {'FINISHED'}
