"""ctest `blender_addon_ui`: the add-on's operators as a user runs them, in Blender's own
window (on a virtual X display, xvfb-run), with events Blender simulates
(--enable-event-simulate):

    xvfb-run -a blender --factory-startup --enable-event-simulate --python-exit-code 1 \\
        -P test_addon_ui.py -- kodawari_blender.zip chibi.glb

- Flock from Curve invoked (INVOKE_DEFAULT: modal, under a timer), Esc pressed once it has
  made birds: the file is back as it was (the same data-blocks of every kind);
- the same run to the end, then Edit > Undo: the flock is gone (one undo step);
- Bake Chains on the chibi invoked, Esc once the baked file is imported: nothing left, the
  chibi's own action, keys and NLA tracks unchanged;
- the same run to the end: the new NLA track; Undo removes it.

The steps run from bpy.app.timers, so Blender's event loop (and the operators' modal
handlers) runs between them. Each step waits for what it needs (polling, within 60 s),
not for a fixed time.
"""
import os
import sys
import time

import bpy

zip_path, chibi_path = sys.argv[sys.argv.index("--") + 1:][:2]
failures = []
KINDS = ("objects", "armatures", "meshes", "actions", "materials", "collections", "images", "textures",
         "node_groups", "cameras", "lights", "curves")


def check(condition, what):
    if not condition:
        failures.append(what)
        print("FAILED:", what, flush=True)


def counts():
    return {name: len(getattr(bpy.data, name)) for name in KINDS}


def made():
    return sum(counts().values()) - sum(state["before"].values())


def window_override():
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == 'VIEW_3D')
    region = next(r for r in area.regions if r.type == 'WINDOW')
    return window, {"window": window, "area": area, "region": region, "screen": window.screen}


def invoke(operator, **properties):
    _, override = window_override()
    with bpy.context.temp_override(**override):
        result = operator('INVOKE_DEFAULT', **properties)
    check(result == {'RUNNING_MODAL'}, f"{operator.idname()} invoked: {result}, not running modal")


def undo():
    _, override = window_override()
    with bpy.context.temp_override(**override):
        bpy.ops.ed.undo()


def press_esc():
    window, _ = window_override()
    window.event_simulate(type='ESC', value='PRESS')
    window.event_simulate(type='ESC', value='RELEASE')


def finish():
    print(f"test_addon_ui: {len(failures)} failures", flush=True)
    bpy.ops.wm.quit_blender()
    os._exit(1 if failures else 0)  # quit_blender's exit status is 0 whatever happened


state = {}


def wait(condition, then, what, timeout=60.0):
    """Calls `then` once condition() holds (polled every 0.05 s by a timer)."""
    started = time.perf_counter()

    def poll():
        if condition():
            then()
            return None
        if time.perf_counter() - started > timeout:
            check(False, f"waited {timeout} s for {what}")
            finish()
            return None
        return 0.05
    bpy.app.timers.register(poll, first_interval=0.05)


def settle(then):
    """Calls `then` after Blender has handled the events queued now (Esc) and redrawn."""
    bpy.app.timers.register(lambda: then(), first_interval=0.5)


def setup_route():
    curve = bpy.data.curves.new("route", "CURVE")
    curve.dimensions = "3D"
    spline = curve.splines.new("BEZIER")
    spline.bezier_points.add(2)
    for point, (co, left, right) in zip(spline.bezier_points, [
            ((0, 0, 20), (-10, 0, 20), (10, 0, 20)), ((40, 10, 25), (30, 8, 24), (50, 12, 26)),
            ((80, 0, 20), (70, 2, 20), (90, -2, 20))]):
        point.handle_left_type = point.handle_right_type = "FREE"
        point.co, point.handle_left, point.handle_right = co, left, right
    route = bpy.data.objects.new("route", curve)
    bpy.context.scene.collection.objects.link(route)
    route.select_set(True)
    bpy.context.view_layer.objects.active = route
    bpy.ops.ed.undo_push(message="route")


# ---- Flock from Curve: Esc, then a whole run and undo.
def flock_esc():
    setup_route()
    state["before"] = counts()
    # 1 000 birds x 250 frames take about 8 s here: Esc comes long before the end.
    invoke(bpy.ops.kodawari.flock_from_curve, count=1000, frames=250)
    wait(lambda: made() > 50, flock_pressed, "the flock's first birds")


def flock_pressed():
    state["held"] = made()
    press_esc()
    settle(flock_after_esc)


def flock_after_esc():
    print(f"flock_from_curve: Esc with {state['held']} new data-blocks made; after it {made()}", flush=True)
    check(counts() == state["before"], f"Esc left the flock: {state['before']} -> {counts()}")
    check(not any(o.type == 'ARMATURE' for o in bpy.data.objects), "an armature is left after Esc")
    invoke(bpy.ops.kodawari.flock_from_curve, count=30, frames=48)
    wait(lambda: sum(1 for o in bpy.data.objects if o.type == 'ARMATURE') == 30, flock_done, "30 birds")


def flock_done():
    settle(flock_undo)


def flock_undo():
    undo()
    print(f"flock_from_curve: 30 birds made, undone: {counts() == state['before']}", flush=True)
    check(counts() == state["before"], f"undo left {counts()} (before the flock: {state['before']})")
    bake_esc()


# ---- Bake Chains on the chibi: Esc, then a whole run and undo.
def chibi_state(chibi):
    data = chibi.animation_data
    return (data.action.name, [(f.data_path, f.array_index, [tuple(k.co) for k in f.keyframe_points])
                               for f in data.action.fcurves],
            [(t.name, [s.name for s in t.strips]) for t in data.nla_tracks])


def bake_esc():
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    scene = bpy.context.scene
    scene.render.fps, scene.frame_start, scene.frame_end = 60, 0, 599
    import numpy
    if 'bool' not in numpy.__dict__:
        numpy.bool = bool  # Blender 3.4's importer and NumPy 1.24 (kodawari_blender/flock.py)
    bpy.ops.import_scene.gltf(filepath=chibi_path)
    chibi = next(o for o in bpy.data.objects if o.type == 'ARMATURE')
    bpy.context.view_layer.objects.active = chibi
    bpy.ops.ed.undo_push(message="chibi")
    state["before"], state["chibi"] = counts(), chibi_state(chibi)
    invoke(bpy.ops.kodawari.bake_chains, frames=600)
    # Esc once the baked file is in (its armature, while the frames are read).
    wait(lambda: counts()["armatures"] > state["before"]["armatures"], bake_pressed, "the baked file's import")


def bake_pressed():
    state["held"] = made()
    press_esc()
    settle(bake_after_esc)


def bake_after_esc():
    chibi = next(o for o in bpy.data.objects if o.type == 'ARMATURE')
    print(f"bake_chains: Esc with {state['held']} new data-blocks made; after it {made()}", flush=True)
    check(counts() == state["before"], f"Esc left the bake: {state['before']} -> {counts()}")
    check(chibi_state(chibi) == state["chibi"], "Esc changed the chibi's action, keys or NLA tracks")
    invoke(bpy.ops.kodawari.bake_chains, frames=48)
    wait(lambda: any(t.name == "Kodawari chains" for t in chibi.animation_data.nla_tracks), bake_done,
         "the baked NLA track")


def bake_done():
    settle(bake_undo)


def bake_undo():
    undo()
    chibi = next(o for o in bpy.data.objects if o.type == 'ARMATURE')
    print(f"bake_chains: baked, undone: {counts() == state['before'] and chibi_state(chibi) == state['chibi']}",
          flush=True)
    check(counts() == state["before"] and chibi_state(chibi) == state["chibi"],
          f"undo left {counts()} (before the bake: {state['before']}) or the chibi changed")
    finish()


def start():
    scripts = os.environ.get("BLENDER_USER_SCRIPTS", "")
    check(scripts != "", "BLENDER_USER_SCRIPTS is not set: the test would install into the user's own folder")
    bpy.ops.preferences.addon_install(filepath=zip_path, overwrite=True)
    bpy.ops.preferences.addon_enable(module="kodawari_blender")
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    flock_esc()


bpy.app.timers.register(start, first_interval=1.0)
