"""The add-on's timings (docs/blender.md, "Timing"), from the operator's call to the
finished actions, in a headless Blender:

    blender -b --factory-startup -P scripts/blender_timing.py -- build/release/kodawari_blender.zip [RUNS]

1. scenes/avatars.json's first avatar (scenes/characters/avatar.vrm walking
   scenes/motions/walk-turn.vrma, 60 fps) baked over 600 frames by
   bpy.ops.kodawari.bake_chains(vrm_path=...): the .vrm imported as .glb (Blender 3.4 has
   no VRM importer), its action the walk as Kodawari retargets it (the humanoid bones'
   keys of a Kodawari bake of the .vrm playing the motion), its spring bones read from the
   .vrm;
2. a flock of 1 000 pigeons over 250 frames from a Bezier curve of three control points
   (spread 4) by bpy.ops.kodawari.flock_from_curve.

The add-on is loaded from the zip extracted to a temporary folder: the user's Blender
preferences and add-ons are not touched. Each is run RUNS times (default 2), the file
emptied in between; every run's time is printed, then the avatar's bake once more chunk by
chunk (as the operator runs it) with the seconds of each phase.
"""
import json
import os
import shutil
import sys
import tempfile
import time
import zipfile

import bpy

arguments = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
if not arguments:
    sys.exit("usage: blender -b --factory-startup -P scripts/blender_timing.py -- kodawari_blender.zip [RUNS]")
runs = int(arguments[1]) if len(arguments) > 1 else 2
repo = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
work = tempfile.mkdtemp(prefix="kodawari-timing-")
with zipfile.ZipFile(arguments[0]) as archive:
    archive.extractall(work)
sys.path.insert(0, work)
import kodawari_blender  # noqa: E402
from kodawari_blender import flock  # noqa: E402

kodawari_blender.register()
kodawari = flock.kodawari
print(f"Blender {bpy.app.version_string}, library {kodawari.library_path}", flush=True)


def empty_file():
    bpy.ops.wm.read_factory_settings(use_empty=True)


def avatar_run(frames=600, fps=60, breakdown=False):
    """Returns the seconds bake_chains took."""
    empty_file()
    scene = bpy.context.scene
    scene.render.fps, scene.frame_start, scene.frame_end = fps, 0, frames - 1
    vrm = os.path.join(repo, "scenes", "characters", "avatar.vrm")
    folder = tempfile.mkdtemp(dir=work)
    walk_scene = os.path.join(folder, "walk.json")
    kodawari.rig(vrm, walk_scene, duration=frames / fps)
    with open(walk_scene) as file:
        description = json.load(file)
    character = description["characters"][0]
    character.pop("animate", None)
    character.update(gltf=vrm, animation="walk-turn",
                     motions=[{"name": "walk-turn", "file": os.path.join(repo, "scenes", "motions", "walk-turn.vrma")}])
    description["fps"] = fps
    with open(walk_scene, "w") as file:
        json.dump(description, file)
    # One frame past the bake: a clip loops at its end.
    with kodawari.Simulation.open(walk_scene, "cpu", frames=frames + 1) as sim:
        sim.bake(os.path.join(folder, "walk.glb"))
    shutil.copy(vrm, os.path.join(folder, "avatar.glb"))
    flock.import_gltf(os.path.join(folder, "avatar.glb"))
    avatar = next(o for o in bpy.data.objects if o.type == "ARMATURE")
    before = {o.as_pointer() for o in bpy.data.objects}
    flock.import_gltf(os.path.join(folder, "walk.glb"))
    walked = [o for o in bpy.data.objects if o.as_pointer() not in before]
    source = next(o for o in walked if o.type == "ARMATURE")
    prefix = source.data.bones[0].name.split("/", 1)[0] + "/"
    walk = bpy.data.actions.new("walk-turn")
    for curve in source.animation_data.action.fcurves:
        bone = curve.data_path.split('"')[1][len(prefix):]
        if bone.startswith("J_Sec_"):
            continue
        copy = walk.fcurves.new(curve.data_path.replace(prefix, ""), index=curve.array_index, action_group=bone)
        co = [0.0] * (2 * len(curve.keyframe_points))
        curve.keyframe_points.foreach_get("co", co)
        copy.keyframe_points.add(len(curve.keyframe_points))
        copy.keyframe_points.foreach_set("co", co)
        copy.update()
    bpy.data.actions.remove(source.animation_data.action)  # else Blender's exporter tries it on the avatar too
    for obj in walked:
        bpy.data.objects.remove(obj)
    avatar.animation_data_create().action = walk
    bpy.ops.object.select_all(action="DESELECT")
    avatar.select_set(True)
    bpy.context.view_layer.objects.active = avatar
    if breakdown:
        # The same work chunk by chunk (what the operator runs), timed per phase.
        from types import SimpleNamespace
        from kodawari_blender import chains
        phases, started = {}, time.perf_counter()
        job = chains.start_bake(bpy.context, avatar, SimpleNamespace(frames=frames, backend="cpu", vrm_path=vrm))
        doing, mark = "starting", started
        while job.step():
            phase = job.doing.split(" ")[0] + " " + job.doing.split(" ")[1]
            now = time.perf_counter()
            phases[doing] = phases.get(doing, 0.0) + now - mark
            doing, mark = phase, now
        phases[doing] = phases.get(doing, 0.0) + time.perf_counter() - mark
        print("  by phase: " + ", ".join(f"{k} {v:.2f} s" for k, v in phases.items()), flush=True)
        return time.perf_counter() - started
    started = time.perf_counter()
    result = bpy.ops.kodawari.bake_chains(frames=frames, vrm_path=vrm)
    seconds = time.perf_counter() - started
    if result != {"FINISHED"}:
        sys.exit(f"bake_chains returned {result}")
    baked = avatar.animation_data.nla_tracks[-1].strips[0].action
    bones = len({f.data_path.split('"')[1] for f in baked.fcurves})
    print(f"avatar.vrm walking, {frames} frames at {fps} fps: bake_chains(vrm_path) {seconds:.2f} s, "
          f"{bones} bones keyed", flush=True)
    return seconds


def flock_run(count=1000, frames=250):
    empty_file()
    scene = bpy.context.scene
    scene.render.fps, scene.frame_start, scene.frame_end = 24, 1, frames
    curve = bpy.data.curves.new("route", "CURVE")
    curve.dimensions = "3D"
    spline = curve.splines.new("BEZIER")
    spline.bezier_points.add(2)
    points = [((0, 0, 20), (-10, 0, 20), (10, 0, 20)),
              ((40, 10, 25), (30, 8, 24), (50, 12, 26)),
              ((80, 0, 20), (70, 2, 20), (90, -2, 20))]
    for point, (co, left, right) in zip(spline.bezier_points, points):
        point.handle_left_type = point.handle_right_type = "FREE"
        point.co, point.handle_left, point.handle_right = co, left, right
    route = bpy.data.objects.new("route", curve)
    scene.collection.objects.link(route)
    route.select_set(True)
    bpy.context.view_layer.objects.active = route
    started = time.perf_counter()
    result = bpy.ops.kodawari.flock_from_curve(count=count, wing_type="PIGEON", spread=4.0, frames=frames)
    seconds = time.perf_counter() - started
    if result != {"FINISHED"}:
        sys.exit(f"flock_from_curve returned {result}")
    armatures = sum(1 for o in bpy.data.objects if o.type == "ARMATURE")
    print(f"flock of {armatures} pigeons x {frames} frames: flock_from_curve {seconds:.2f} s", flush=True)
    return seconds


avatar = [avatar_run() for _ in range(runs)]
avatar_run(breakdown=True)
birds = [flock_run() for _ in range(runs)]
print(f"avatar 600 frames: {', '.join(f'{s:.2f}' for s in avatar)} s; "
      f"1000 birds x 250 frames: {', '.join(f'{s:.2f}' for s in birds)} s")
kodawari_blender.unregister()
shutil.rmtree(work, ignore_errors=True)
