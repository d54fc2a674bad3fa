"""bpy.ops.kodawari.flock_from_curve: the selected Bezier curves become Kodawari routes and
a flock flies each; the birds come into the scene as Kodawari's glTF export makes them, one
skinned armature with one action per bird.

Kodawari's routes are cubic Bezier curves (docs/scene-format.md, `route`), so a Blender
Bezier spline maps exactly: segment k of a spline is B0 = point k, B1 = its right handle,
B2 = the left handle of point k + 1, B3 = point k + 1 (a cyclic spline adds the segment
from the last point back to the first and loops). Blender's +Z up becomes Kodawari's +Y
up: (x, y, z) -> (x, z, -y), which Blender's glTF importer turns back.
"""
import os
import time

import bpy

from . import build, jobs

try:  # the zip's copy of the package, next to this file
    from . import kodawari
except ImportError:  # a development checkout with the package on sys.path
    import kodawari

WING_TYPES = (
    ("PIGEON", "Pigeon", "Short elliptical wings, 19.7 m/s cruise"),
    ("GULL", "Gull", "Long narrow wings, 12 m/s cruise"),
    ("HAWK", "Hawk", "Broad soaring wings, 11 m/s cruise"),
    ("HUMMINGBIRD", "Hummingbird", "Hovering wings, 8 m/s cruise"),
    ("STARLING", "Starling", "Short pointed wings of a flocking songbird, 15 m/s cruise"),
)


# The backends an operator offers (both operators: flock.py's and chains.py's).
BACKEND_ITEMS = (
    ("cpu", "CPU", "Vectorized, on every core"),
    ("vulkan", "Vulkan", "Compute shaders on a Vulkan device"),
    ("cpu-reference", "CPU Reference", "Scalar, one thread"))


class FlockError(Exception):
    """A problem with the user's selection or settings, said in Blender's words."""


def to_kodawari(v):
    """A Blender world point (+Z up) in Kodawari's frame (+Y up)."""
    return [float(v[0]), float(v[2]), -float(v[1])]


def spline_route(obj, index, spline):
    """The route of one Bezier spline of curve object `obj`, in world space."""
    where = f"curve '{obj.name}' spline {index}"
    if spline.type != 'BEZIER':
        raise FlockError(f"{where} is a {spline.type.lower()} spline; Kodawari's routes are Bezier curves "
                         "(Curve > Set Spline Type > Bezier)")
    points = list(spline.bezier_points)
    if len(points) < 2:
        raise FlockError(f"{where} has {len(points)} control point; a route needs at least 2")
    m = obj.matrix_world
    pts = [(m @ p.co, m @ p.handle_left, m @ p.handle_right) for p in points]
    loop = bool(spline.use_cyclic_u)
    order = list(range(len(pts))) + ([0] if loop else [])
    control = [pts[order[0]][0]]
    for a, b in zip(order, order[1:]):
        control += [pts[a][2], pts[b][1], pts[b][0]]
    # The loader refuses coincident consecutive control points (no heading there): name
    # the point here, as the user sees it, rather than a JSON path of a file they never saw.
    for k in range(len(control) - 1):
        if (control[k] - control[k + 1]).length < 1e-6:
            point = order[(k + 1) // 3]
            raise FlockError(f"{where} point {point}: a handle sits on its point; move the handle off it "
                             "(a route needs a direction at every control point)")
    return {"points": [to_kodawari(v) for v in control], "loop": loop}, len(order) - 1


def scene_dict(curves, props, fps, frames):
    """The Kodawari scene (docs/scene-format.md, version 1) for the selected curves."""
    flocks = []
    for obj in curves:
        for index, spline in enumerate(obj.data.splines):
            route, segments = spline_route(obj, index, spline)
            modes = ["auto"] * segments
            if props.takeoff or props.landing:
                if route["loop"]:
                    raise FlockError(f"curve '{obj.name}' spline {index} is cyclic; take-off and landing need "
                                     "an open curve (they happen at its ends)")
                if props.takeoff and props.landing and segments < 2:
                    raise FlockError(f"curve '{obj.name}' spline {index} has one segment; take-off and landing "
                                     "each need one of their own: add a control point")
                if props.takeoff:
                    modes[0] = "takeoff"
                if props.landing:
                    modes[-1] = "landing"
            route["modes"] = modes
            # A flocking flock takes off and lands by the curve too: its perches
            # (docs/flocking.md, "Perches").
            flocking = getattr(props, "flocking", False)
            flock = {
                "name": f"{obj.name}.{index}" if len(obj.data.splines) > 1 else obj.name,
                "wing_type": props.wing_type.lower(),
                "count": props.count,
                "seed": props.seed,
                "route": route,
                # Spread in Blender's axes: x, y across and z up; Kodawari's y is up.
                "formation": {"spread": [props.spread, props.spread / 2, props.spread], "trail": props.trail},
            }
            if props.speed > 0:
                flock["speed"] = props.speed
            if flocking:
                # The flocking rules' defaults (docs/flocking.md); the curve draws the flock.
                flock["flocking"] = {}
            flocks.append(flock)
    if not flocks:
        names = ", ".join(f"'{obj.name}'" for obj in curves)
        raise FlockError(f"curve {names} has no splines: draw a Bezier spline in it (two points at least)"
                         if len(curves) == 1 else f"curves {names} have no splines: draw a Bezier spline in one")
    return {"format": "kodawari-scene", "version": 1, "name": "blender", "fps": fps,
            "duration": frames / fps, "flocks": flocks}


# What a flock holds per bird and frame while it is made: its poses (7 parts of 7 floats)
# and tail spread from the simulation, and Blender's keyframes (34 F-curves a bird: the
# Body's location, the 7 parts' rotations, the Tail's scale; a keyframe is a 72-byte
# BezTriple).
BYTES_PER_BIRD_FRAME = (7 * 7 + 1) * 4 + 34 * 72


def available_memory():
    """Bytes of memory free for new work (Linux's MemAvailable), or None where unknown."""
    try:
        with open("/proc/meminfo") as file:
            for line in file:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def check_size(birds, frames, available=None):
    """Raises FlockError when `birds` x `frames` would need more than half the memory free
    (the poses, then the keyframes): refused before anything is made, rather than ending
    in a MemoryError or the system's out-of-memory killer."""
    available = available_memory() if available is None else available
    need = birds * frames * BYTES_PER_BIRD_FRAME
    if available is not None and need > available // 2:
        raise FlockError(f"{birds} birds x {frames} frames would take about {need / 2**30:.1f} GiB (poses and "
                         f"keyframes), more than half the {available / 2**30:.1f} GiB of memory free: make fewer "
                         "birds or frames, or bake the flock with `kodawari run` and import its glTF")


def flock_steps(job, description, backend, frames, curves, birds_per_chunk=64, frames_per_chunk=25):
    """The flock as a Job's operation (jobs.py): simulates the scene `description` and
    makes its birds in a new collection; returns the number of birds and the seconds the
    simulation took. One bird of the first flock is baked and imported as the template
    (build.Template); the rest is made from the poses. Chunks: the template, then
    `frames_per_chunk` frames simulated, then `birds_per_chunk` armatures made, at a time."""
    import json
    import numpy
    scene = job.scene
    folder = job.folder
    yield 0.0, "making the template bird"
    template_description = dict(description, flocks=[dict(description["flocks"][0], count=1)])
    template_path = os.path.join(folder, "template.json")
    with open(template_path, "w") as file:
        json.dump(template_description, file)
    glb = os.path.join(folder, "template.glb")
    with kodawari.Simulation.open(template_path, backend, frames=1) as sim:
        sim.bake(glb)
        sim.step(1)
        template_poses, template_spreads = sim.bird_poses("world")[0], sim.bird_tail_spreads()[0]
    before = {o.as_pointer() for o in bpy.data.objects}
    import_gltf(glb)
    imported = [o for o in bpy.data.objects if o.as_pointer() not in before]
    path = os.path.join(folder, "flock.json")
    with open(path, "w") as file:
        json.dump(description, file)
    simulated = 0.0
    with kodawari.Simulation.open(path, backend, frames=frames) as sim:
        poses = numpy.empty((frames, sim.bird_count, 7, 7), numpy.float32)
        spreads = numpy.empty((frames, sim.bird_count), numpy.float32)
        for f in range(frames):
            if f % frames_per_chunk == 0:
                yield 0.05 + 0.25 * f / frames, f"simulating frame {f + 1} of {frames}"
            started = time.perf_counter()
            sim.step(1)
            poses[f] = sim.bird_poses("world")
            spreads[f] = sim.bird_tail_spreads()
            simulated += time.perf_counter() - started
    armature = next(o for o in imported if o.type == 'ARMATURE')
    mesh = next(o for o in imported if o.type == 'MESH')
    template_actions = {armature.animation_data.action} if armature.animation_data else set()
    scene.frame_set(0)  # the template's one frame, at time 0
    template = build.Template(armature, mesh, template_poses, template_spreads)
    names = [f"{flock['name']}_{i}" for flock in description["flocks"] for i in range(flock["count"])]
    collection = bpy.data.collections.new("Flock " + ", ".join(c.name for c in curves))
    scene.collection.children.link(collection)
    for begin in range(0, len(names), birds_per_chunk):
        yield 0.3 + 0.7 * begin / len(names), f"making bird {begin + 1} of {len(names)}"
        end = min(len(names), begin + birds_per_chunk)
        build.make_birds(template, names[begin:end], poses[:, begin:end], spreads[:, begin:end], scene.frame_start,
                         collection)
    template.mesh.data.name = template.armature.data.name = f"kodawari {description['flocks'][0]['wing_type']}"
    for obj in imported:
        bpy.data.objects.remove(obj)
    for action in template_actions:
        bpy.data.actions.remove(action)
    return len(names), simulated


def restore_numpy_bool():
    """Blender 3.4's own glTF importer (File > Import > glTF 2.0) uses numpy.bool, an alias
    of Python's bool that NumPy 1.24 removed (Debian 12 ships both): every import of a
    file with a mesh then fails with "module 'numpy' has no attribute 'bool'". Puts the
    alias back where it is missing; the add-on does so when enabled (register()), so the
    importer works for the user's own imports too, and before its own imports."""
    import numpy
    if 'bool' not in numpy.__dict__:
        numpy.bool = bool


def import_gltf(path):
    restore_numpy_bool()
    result = bpy.ops.import_scene.gltf(filepath=path)
    if 'FINISHED' not in result:
        raise FlockError(f"Blender's glTF importer did not finish ({sorted(result)})")


def start_flock(context, curves, settings):
    """The flock from `curves` with the operator's `settings` (its properties, or any
    object with the same attributes) as a jobs.Job: nothing is made until it runs. Raises
    FlockError for a curve or setting Kodawari refuses."""
    scene = context.scene
    fps = scene.render.fps / scene.render.fps_base
    frames = settings.frames or (scene.frame_end - scene.frame_start + 1)
    description = scene_dict(curves, settings, fps, frames)
    check_size(sum(flock["count"] for flock in description["flocks"]), frames)
    job = jobs.Job(context, "Flock from Curve",
                   lambda job: flock_steps(job, description, settings.backend, frames, curves))
    job.frames = frames
    return job


class KODAWARI_OT_flock_from_curve(jobs.ModalJob, bpy.types.Operator):
    """Make a flock of Kodawari birds fly along each selected Bezier curve: one skinned
    armature with one action per bird, in a new collection"""
    bl_idname = "kodawari.flock_from_curve"
    bl_label = "Flock from Curve"
    bl_options = {'REGISTER', 'UNDO'}

    count: bpy.props.IntProperty(name="Count", description="Birds per spline of each selected curve", default=20, min=1, max=100000)
    wing_type: bpy.props.EnumProperty(name="Wing Type", items=WING_TYPES, default="PIGEON")
    spread: bpy.props.FloatProperty(name="Spread", description="Each bird's offset from the curve, uniform in "
                                    "+-spread across and +-spread/2 up", default=2.0, min=0.0, max=10000.0,
                                    unit='LENGTH')
    speed: bpy.props.FloatProperty(name="Speed", description="m/s along the curve; 0: the wing type's cruise speed",
                                   default=0.0, min=0.0, max=1000.0)
    trail: bpy.props.FloatProperty(name="Trail", description="Each bird starts up to this many seconds later "
                                   "(take-off) or further along", default=0.0, min=0.0, max=3600.0)
    takeoff: bpy.props.BoolProperty(name="Take Off", description="Start from rest at the curve's start",
                                    default=False)
    landing: bpy.props.BoolProperty(name="Land", description="Come to rest at the curve's end", default=False)
    flocking: bpy.props.BoolProperty(name="Flocking", description="Fly by the neighbours (separation, alignment, "
                                     "cohesion over the 7 nearest), drawn to the curve, instead of following it "
                                     "(docs/flocking.md)", default=False)
    frames: bpy.props.IntProperty(name="Frames", description="Frames to simulate from the scene's start frame; "
                                  "0: the scene's frame range", default=0, min=0, max=1000000)
    seed: bpy.props.IntProperty(name="Seed", description="Seed of the birds' offsets, speeds and phases",
                                default=1, min=0)
    backend: bpy.props.EnumProperty(name="Backend", items=BACKEND_ITEMS, default="cpu")

    ERRORS = (kodawari.Error, FlockError, RuntimeError, OSError)

    def start(self, context):
        """The job of this call (jobs.Job), or None when the selection or the settings are
        refused (reported)."""
        curves = [o for o in context.selected_objects if o.type == 'CURVE']
        if not curves:
            self.report({'ERROR'}, "Flock from Curve: select one or more Bezier curve objects (the routes)")
            return None
        try:
            return start_flock(context, curves, self)
        except FlockError as error:
            self.report({'ERROR'}, f"Flock from Curve: {error}")
            return None

    def finish(self, context, job):
        birds, simulated = job.result
        self.report({'INFO'}, f"Flock from Curve: {birds} birds, {job.frames} frames in "
                              f"{time.perf_counter() - job.started:.1f} s (simulated in {simulated:.2f} s)")
        return {'FINISHED'}


class KODAWARI_PT_flock(bpy.types.Panel):
    """The flock operator with its settings, in the 3D view's sidebar."""
    bl_label = "Kodawari Flock"
    bl_space_type = 'VIEW_3D'
    bl_region_type = 'UI'
    bl_category = "Kodawari"

    def draw(self, context):
        layout = self.layout
        curves = [o for o in context.selected_objects if o.type == 'CURVE']
        layout.label(text=f"{len(curves)} curve(s) selected" if curves else "Select Bezier curves (routes)")
        row = layout.row()
        row.enabled = bool(curves)
        row.operator(KODAWARI_OT_flock_from_curve.bl_idname)
