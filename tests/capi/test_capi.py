#!/usr/bin/env python3
"""The C API from Python through ctypes alone (issue 11, section 3): what a Blender add-on
or any Python tool would do with libkodawari.so.

The C++ path (tests/capi/write_chain_reference.cpp, the cpu-reference RodBackend) runs the
ahoge scene's chain and writes its inputs (the chain template as the scene file gives it,
and every frame's camera, reference joint, root and colliders) with its outputs. This
script checks that those inputs are the scene file's, builds the same chain world through
the C API from plain arrays, steps it with the same frames and compares the joint
positions and orientations with the C++ path's: cpu-reference and cpu to the bit (the same
code on the same inputs; floats travel as 9-digit decimals, which read back as the same
float32 values), vulkan (where a Vulkan device exists; the script says when there is none)
within 1e-5 of the chain's length for positions and 1e-4 for the orientation quaternions
(measured over the scene's 840 frames on lavapipe: 1.8e-6 of the length and 7.9e-6: GLSL's
sin, cos, pow and division are not correctly rounded). A wrong field order, type or size in
a ctypes struct, or a wrong mapping inside the library, moves joints by millimetres.
It also checks a rejected call's status and message, and the version.

Usage: test_capi.py LIBKODAWARI.so REFERENCE_WRITER SCENE.json
Exit status 0 when every check passed.
"""
import ctypes as C
import json
import os
import subprocess
import sys
import tempfile

FRAMES = 240  # 4 s of the 12 s camera orbit

# ---- kodawari.h, field for field ---------------------------------------------------------

OK, INVALID_ARGUMENT, BUFFER_TOO_SMALL, UNAVAILABLE = 0, 1, 2, 3
BACKENDS = {"cpu-reference": 1, "cpu": 2, "vulkan": 3}
WEIGHTS_PER_CHAIN = 8
Float3, Float4 = C.c_float * 3, C.c_float * 4


class BackendOptions(C.Structure):
    _fields_ = [("backend", C.c_int), ("device", C.c_char_p), ("validation", C.c_uint32), ("threads", C.c_uint32),
                ("vulkan_device", C.c_void_p), ("isa", C.c_char_p), ("workgroup_size", C.c_uint32)]


class Transform(C.Structure):
    _fields_ = [("position", Float3), ("rotation", Float4)]


class Capsule(C.Structure):
    _fields_ = [("a", Float3), ("b", Float3), ("radius", C.c_float)]


class Camera(C.Structure):
    _fields_ = [("orthographic", C.c_uint32), ("position", Float3), ("forward", Float3)]


class ChainShape(C.Structure):
    _fields_ = [("positions", C.POINTER(C.c_float)), ("orientations", C.POINTER(C.c_float))]


class ViewExample(C.Structure):
    _fields_ = [("direction", Float3), ("influence", C.c_float), ("shape", ChainShape)]


class SolverParams(C.Structure):
    _fields_ = [("max_substep", C.c_float), ("iterations", C.c_uint32), ("stiffness", C.c_float),
                ("rest_stiffness", C.c_float), ("damping", C.c_float), ("gravity", Float3), ("wind", Float3),
                ("momentum_suppression", C.c_float), ("settle_start", C.c_uint32), ("teleport_distance", C.c_float),
                ("normal_drag", C.c_float), ("tangent_drag", C.c_float)]


class AngleLimit(C.Structure):
    _fields_ = [("kind", C.c_uint32), ("angle", C.c_float), ("yaw", C.c_float), ("rotation", Float4)]


class ChainTemplateDesc(C.Structure):
    _fields_ = [("joint_count", C.c_uint32), ("base", ChainShape), ("views", C.POINTER(ViewExample)),
                ("view_count", C.c_uint32), ("thickness", C.c_float), ("mass", C.c_float), ("solver", SolverParams),
                ("limits", C.POINTER(AngleLimit)), ("limit_count", C.c_uint32)]


class ChainDesc(C.Structure):
    _fields_ = [("template_index", C.c_uint32), ("character", C.c_uint32), ("collider_begin", C.c_uint32),
                ("collider_count", C.c_uint32)]


class ColliderDesc(C.Structure):
    _fields_ = [("character", C.c_uint32), ("local", Capsule)]


class ChainWorldDesc(C.Structure):
    _fields_ = [("templates", C.POINTER(ChainTemplateDesc)), ("template_count", C.c_uint32),
                ("chains", C.POINTER(ChainDesc)), ("chain_count", C.c_uint32), ("character_count", C.c_uint32),
                ("collider_count", C.c_uint32), ("colliders", C.POINTER(ColliderDesc)), ("backend", BackendOptions)]


class ChainFrame(C.Structure):
    _fields_ = [("dt", C.c_float), ("camera", Camera), ("references", C.POINTER(Transform)),
                ("reference_count", C.c_uint32), ("roots", C.POINTER(Transform)), ("root_count", C.c_uint32),
                ("colliders", C.POINTER(Capsule)), ("collider_count", C.c_uint32)]


class ChainOutput(C.Structure):
    _fields_ = [(name, kind) for array in ("positions", "orientations", "rest_positions", "view_directions", "weights")
                for name, kind in ((array, C.POINTER(C.c_float)), (array + "_capacity", C.c_size_t))]


class ChainWorldInfo(C.Structure):
    _fields_ = [("template_count", C.c_uint32), ("chain_count", C.c_uint32), ("joint_count", C.c_uint32),
                ("character_count", C.c_uint32), ("collider_count", C.c_uint32), ("backend", C.c_int),
                ("validation_messages", C.c_uint32), ("device", C.c_char * 256), ("fallback_reason", C.c_char * 1024)]


def load_library(path):
    lib = C.CDLL(path)
    World = C.c_void_p  # kodawari_chain_world*, opaque
    for name, restype, argtypes in [
        ("kodawari_version", C.c_char_p, []),
        ("kodawari_version_major", C.c_int, []),
        ("kodawari_version_minor", C.c_int, []),
        ("kodawari_version_patch", C.c_int, []),
        ("kodawari_status_name", C.c_char_p, [C.c_int]),
        ("kodawari_last_error", C.c_char_p, []),
        ("kodawari_solver_params_default", C.c_int, [C.POINTER(SolverParams)]),
        ("kodawari_chain_world_create", C.c_int, [C.POINTER(ChainWorldDesc), C.POINTER(ChainFrame), C.POINTER(World)]),
        ("kodawari_chain_world_destroy", None, [World]),
        ("kodawari_chain_world_last_error", C.c_char_p, [World]),
        ("kodawari_chain_world_step", C.c_int, [World, C.POINTER(ChainFrame)]),
        ("kodawari_chain_world_read", C.c_int, [World, C.POINTER(ChainOutput)]),
        ("kodawari_chain_world_get_info", C.c_int, [World, C.POINTER(ChainWorldInfo)]),
    ]:
        function = getattr(lib, name)
        function.restype = restype
        function.argtypes = argtypes
    return lib


# ---- the check ---------------------------------------------------------------------------

failures = []


def check(condition, message):
    if not condition:
        failures.append(message)
        print("FAIL:", message, file=sys.stderr)


def floats(values):
    """A ctypes float array of a flat list, kept alive by whoever holds it."""
    return (C.c_float * len(values))(*values)


def distance(a, b):
    return sum((x - y) ** 2 for x, y in zip(a, b)) ** 0.5


def flat(rows):
    return [x for row in rows for x in row]


def transform(values):
    return Transform(Float3(*values[:3]), Float4(*values[3:]))


class ChainWorldInputs:
    """kodawari.h's description of the reference's world; owns every array it points to."""

    def __init__(self, ref, backend):
        self.keep = []
        templates = []
        for t in ref["templates"]:
            views = (ViewExample * max(1, len(t["views"])))()
            for k, v in enumerate(t["views"]):
                views[k] = ViewExample(direction=Float3(*v["direction"]), influence=v["influence"], shape=self.shape(v["shape"]))
            s = t["solver"]
            solver = SolverParams(**{name: Float3(*s[name]) if name in ("gravity", "wind") else s[name]
                                     for name, _ in SolverParams._fields_})
            self.keep.append(views)
            templates.append(ChainTemplateDesc(len(t["base"]["positions"]), self.shape(t["base"]), views, len(t["views"]),
                                               t["thickness"], t["mass"], solver))
        self.templates = (ChainTemplateDesc * len(templates))(*templates)
        self.chains = (ChainDesc * len(ref["chains"]))(
            *[ChainDesc(c["template"], c["character"], c["collider_begin"], c["collider_count"]) for c in ref["chains"]])
        validation = 1 if os.environ.get("KODAWARI_VALIDATION", "0") not in ("", "0") else 0
        self.desc = ChainWorldDesc(self.templates, len(templates), self.chains, len(ref["chains"]), ref["character_count"],
                                   ref["collider_count"], None, BackendOptions(BACKENDS[backend], None, validation, 2))

    def shape(self, s):
        positions, orientations = floats(flat(s["positions"])), floats(flat(s["orientations"]))
        self.keep += [positions, orientations]
        return ChainShape(positions, orientations)


class Frame:
    """A reference frame's input as kodawari.h's frame; owns its arrays."""

    def __init__(self, f):
        self.references = (Transform * len(f["references"]))(*[transform(t) for t in f["references"]])
        self.roots = (Transform * len(f["roots"]))(*[transform(t) for t in f["roots"]])
        self.colliders = (Capsule * max(1, len(f["colliders"])))(
            *[Capsule(Float3(*c[:3]), Float3(*c[3:6]), c[6]) for c in f["colliders"]])
        camera = Camera(f["camera"]["orthographic"], Float3(*f["camera"]["position"]), Float3(*f["camera"]["forward"]))
        self.frame = ChainFrame(f["dt"], camera, self.references, len(f["references"]), self.roots, len(f["roots"]),
                                self.colliders if f["colliders"] else None, len(f["colliders"]))


def check_reference_is_the_scene(ref, scene_path):
    """The reference's template is the scene file's chain (its views, physics, counts)."""
    with open(scene_path) as file:
        scene = json.load(file)
    chain = scene["characters"][0]["chains"][0]
    t = ref["templates"][0]
    check(len(ref["templates"]) == 1 and len(ref["chains"]) == 1, "the ahoge scene has one chain")
    check(len(t["base"]["positions"]) == chain["shape"]["arc"]["joints"], "joints as in the scene file")
    check([v["direction"] for v in t["views"]] == [v["direction"] for v in chain["views"]], "view directions as in the file")
    check([v["influence"] for v in t["views"]] == [v["influence"] for v in chain["views"]], "influences as in the file")
    check(abs(t["thickness"] - chain["thickness"]) < 1e-9 and abs(t["mass"] - chain["mass"]) < 1e-9, "thickness and mass")
    physics = scene["characters"][0]["physics"]
    check(abs(t["solver"]["stiffness"] - physics["stiffness"]) < 1e-7 and t["solver"]["iterations"] == physics["iterations"],
          "physics as in the file")
    check(ref["collider_count"] == len(scene["characters"][0]["colliders"]), "colliders as in the file")


def run(lib, ref, backend):
    """Steps the reference's frames through the C API; the number of frames that matched."""
    inputs = ChainWorldInputs(ref, backend)
    frames = [Frame(f) for f in ref["frames"]]
    world = C.c_void_p()
    status = lib.kodawari_chain_world_create(C.byref(inputs.desc), C.byref(frames[0].frame), C.byref(world))
    if backend == "vulkan" and status == UNAVAILABLE:
        print("test_capi.py: vulkan skipped, no Vulkan device here:", lib.kodawari_last_error().decode())
        return None
    check(status == OK, f"{backend}: create: {lib.kodawari_status_name(status).decode()} {lib.kodawari_last_error().decode()}")
    if status != OK:
        return 0
    info = ChainWorldInfo()
    check(lib.kodawari_chain_world_get_info(world, C.byref(info)) == OK, "get_info")
    check(info.joint_count == ref["joint_count"] and info.backend == BACKENDS[backend], f"{backend}: info")
    joints = info.joint_count
    positions, orientations = (C.c_float * (3 * joints))(), (C.c_float * (4 * joints))()
    out = ChainOutput()
    out.positions, out.positions_capacity = positions, 3 * joints
    out.orientations, out.orientations_capacity = orientations, 4 * joints
    matched = 0
    worst_position = worst_rotation = 0.0
    first = ref["frames"][0]["positions"]
    length = sum(distance(first[j], first[j + 1]) for j in range(joints - 1))
    try:
        for index, (frame, expected) in enumerate(zip(frames, ref["frames"])):
            if index > 0:
                status = lib.kodawari_chain_world_step(world, C.byref(frame.frame))
                if status != OK:
                    check(False, f"{backend} frame {index}: step: {lib.kodawari_last_error().decode()}")
                    break
            check(lib.kodawari_chain_world_read(world, C.byref(out)) == OK, f"{backend}: read")
            got_p, got_q = list(positions), list(orientations)
            # The 9-digit decimals as the float32 values they were written from.
            want_p, want_q = list(floats(flat(expected["positions"]))), list(floats(flat(expected["orientations"])))
            if backend != "vulkan":
                if got_p != want_p or got_q != want_q:
                    worst = max(abs(a - b) for a, b in zip(got_p + got_q, want_p + want_q))
                    check(False, f"{backend} frame {index}: differs from the C++ path by up to {worst:.3g}")
                    break
            else:
                position = max(distance(got_p[3 * j:3 * j + 3], want_p[3 * j:3 * j + 3]) for j in range(joints))
                # q and -q are the same rotation.
                rotation = max(min(distance(got_q[4 * j:4 * j + 4], want_q[4 * j:4 * j + 4]),
                                   distance(got_q[4 * j:4 * j + 4], [-x for x in want_q[4 * j:4 * j + 4]]))
                               for j in range(joints))
                worst_position, worst_rotation = max(worst_position, position), max(worst_rotation, rotation)
                if not (position <= 1e-5 * length and rotation <= 1e-4):
                    check(False, f"vulkan frame {index}: {position:.3g} m and {rotation:.3g} from the C++ path")
                    break
            matched += 1

        # A rejected call: the status, the message naming the argument, the state unchanged.
        bad = Frame(ref["frames"][1])
        bad.frame.dt = 0.0
        before = list(positions)
        status = lib.kodawari_chain_world_step(world, C.byref(bad.frame))
        message = lib.kodawari_last_error().decode()
        check(status == INVALID_ARGUMENT and "kodawari_chain_world_step: frame->dt: 0; expected a number in [1e-05, 1]" in message,
              f"{backend}: dt 0 gave {status}: {message!r}")
        check(lib.kodawari_chain_world_last_error(world).decode() == message, "the handle keeps the message")
        small = ChainOutput()
        small.positions, small.positions_capacity = positions, 3 * joints - 1
        status = lib.kodawari_chain_world_read(world, C.byref(small))
        check(status == BUFFER_TOO_SMALL and f"needs {3 * joints}" in lib.kodawari_last_error().decode(),
              f"{backend}: a small buffer gave {status}: {lib.kodawari_last_error().decode()!r}")
        check(lib.kodawari_chain_world_read(world, C.byref(out)) == OK and list(positions) == before,
              f"{backend}: rejected calls changed the state")
        check(lib.kodawari_chain_world_get_info(world, C.byref(info)) == OK and info.validation_messages == 0,
              f"{backend}: {info.validation_messages} validation messages")
        agree = "the C++ path's bits" if backend != "vulkan" else \
            f"the C++ path's joints within {worst_position / length:.2g} of the length, orientations within {worst_rotation:.2g}"
        print(f"test_capi.py: {backend} on {info.device.decode()}: {matched} of {len(frames)} frames have {agree}")
    finally:
        lib.kodawari_chain_world_destroy(world)
    return matched


def main():
    if len(sys.argv) != 4:
        print(__doc__, file=sys.stderr)
        return 2
    library, writer, scene = sys.argv[1:]
    lib = load_library(library)
    version = lib.kodawari_version().decode()
    check(version == f"{lib.kodawari_version_major()}.{lib.kodawari_version_minor()}.{lib.kodawari_version_patch()}",
          f"version {version}")
    defaults = SolverParams()
    check(lib.kodawari_solver_params_default(C.byref(defaults)) == OK and defaults.iterations == 4, "solver defaults")
    check(lib.kodawari_solver_params_default(None) == INVALID_ARGUMENT and "out: is NULL" in lib.kodawari_last_error().decode(),
          "NULL out")

    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "reference.json")
        # LD_PRELOAD (the sanitizer runtime under the asan preset) is for this interpreter;
        # the writer is a program that brings its own.
        env = {k: v for k, v in os.environ.items() if k != "LD_PRELOAD"}
        subprocess.run([writer, scene, str(FRAMES), path], check=True, env=env)
        with open(path) as file:
            ref = json.load(file)
    check_reference_is_the_scene(ref, scene)
    check(len(ref["frames"]) == FRAMES + 1, "frames")
    for backend in ("cpu-reference", "cpu", "vulkan"):
        matched = run(lib, ref, backend)
        if matched is not None:
            check(matched == FRAMES + 1, f"{backend}: {matched} of {FRAMES + 1} frames matched")
    print(f"test_capi.py: Kodawari {version}, {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
