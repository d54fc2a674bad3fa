"""Kodawari from Python: scene files simulated on any backend, read as numpy arrays, baked
to glTF.

    import kodawari
    with kodawari.Simulation.open("scenes/flock.json", backend="cpu", frames=120) as sim:
        sim.step(120)
        poses = sim.bird_poses()          # (birds, 7, 7) float32: per part x y z qx qy qz qw
        sim.bake("out/flock.glb")         # every frame from frame 0, as `kodawari run`

The package calls libkodawari.so (the C API, kodawari.h) through ctypes: no compiled
Python module, so it works in any Python 3 of the machine (Debian's /usr/bin/python3,
Blender's) without being built for it. Every array it returns is a copy (numpy memory of
its own, valid for as long as you keep it); see docs/python.md.

Errors raise kodawari.Error, whose message is the library's (it names the function, the
argument or the file, and what was expected).
"""
import ctypes
import json
import math
import numbers
import os
import shutil
import subprocess
import tempfile
import threading

import numpy

from . import _config
from . import _native

__all__ = ["Simulation", "Error", "rig", "bench", "BENCH_KINDS", "command_path", "BACKENDS", "PARTS", "LEVEL_FULL", "LEVEL_POSED", "LEVEL_HIDDEN", "LEVEL_REDUCED", "__version__", "library_version", "library_path"]

#: The package's version: the project's (CMake's project version, as the library's).
__version__ = _config.VERSION
#: The backends a Simulation can run on ("auto": vulkan when a GPU opens, else cpu).
BACKENDS = tuple(_native.BACKENDS)
#: The parts of a bird, in the order of bird_poses()' second axis.
PARTS = ("Body", "Head", "Tail", "LeftArm1", "LeftArm2", "RightArm1", "RightArm2")
#: A chain's levels of detail as chain_levels() gives them (kodawari.h kodawari_level).
LEVEL_FULL, LEVEL_POSED, LEVEL_HIDDEN, LEVEL_REDUCED = 0, 1, 2, 3
#: Where the library was loaded from.
library_path = _native.library_path


def library_version():
    """The loaded libkodawari.so's version ("0.3.0"); the same as __version__ unless the
    library next to the package was replaced."""
    return _native.lib.kodawari_version().decode()


class Error(Exception):
    """A call into the library failed. str(error) is the library's message; `status` is the
    C status' name ("KODAWARI_INVALID_ARGUMENT", "KODAWARI_UNAVAILABLE", ...)."""

    def __init__(self, status, message):
        super().__init__(message)
        self.status = status


def _whole_number(name, value, low, high, expected):
    """`value` as an int when it is a whole number in [low, high]; else ValueError naming
    `name`, the value given and what was `expected` (also for None, text and the like, which
    int() would refuse with a message naming neither)."""
    try:
        whole = int(value) == value and low <= value <= high
    except (TypeError, ValueError, OverflowError):  # None, text; infinity
        whole = False
    if not whole:
        raise ValueError(f"{name}: {value!r}; expected {expected}")
    return int(value)


def _point(name, value, unit):
    """`value` as 3 C floats when it holds 3 numbers (a list, a tuple, a NumPy array); else
    ValueError naming `name`."""
    try:
        numbers = [float(v) for v in value]
    except (TypeError, ValueError):
        numbers = []
    if len(numbers) != 3:
        raise ValueError(f"{name}: {value!r}; expected 3 numbers ({unit})")
    return (ctypes.c_float * 3)(*numbers)


def _real(name, value):
    """`value` as a float when it is a real number (NumPy's scalars too, not a bool); else
    ValueError naming `name`."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name}: {value!r}; expected a number")
    return float(value)


def _check(status, handle=None):
    if status == 0:
        return
    lib = _native.lib
    message = lib.kodawari_simulation_last_error(handle) if handle else lib.kodawari_last_error()
    raise Error(lib.kodawari_status_name(status).decode(), message.decode(errors="replace"))


def rig(character_path, scene_path, clip="", duration=10.0):
    """Sets up the chains of a rigged .glb/.gltf/.vrm character as `kodawari rig` does and
    writes a scene file that simulates it at `scene_path` (docs/rigged-characters.md):
    VRM spring bones, else bones named like hair, tails and ears. `clip`: the animation to
    play ("" = the file's first); `duration`: the scene's, in seconds. Returns the chains
    as (name, root node, joint count) tuples. Raises Error naming the file when it has no
    chains or cannot be read."""
    chains = _native.ctypes.create_string_buffer(256 * 1024)
    _check(_native.lib.kodawari_rig_scene(os.fsencode(character_path), os.fsencode(scene_path),
                                          clip.encode() if clip else None, float(duration), chains, len(chains)))
    out = []
    for line in chains.value.decode(errors="replace").split("\n"):
        if line:
            name, root, joints = line.split("\t")
            out.append((name, root, int(joints)))
    return out


def command_path():
    """The `kodawari` command that bench() runs: the one built or installed with this
    package (build/<preset>/host/kodawari beside build/<preset>/python, or
    <prefix>/bin/kodawari beside <prefix>/lib/python3/dist-packages), else the first on
    PATH. Raises Error when there is none (the Blender add-on's zip carries no command)."""
    here = os.path.dirname(os.path.abspath(__file__))
    for candidate in (os.path.join(here, "..", "..", "host", "kodawari"),
                      os.path.join(here, "..", "..", "..", "..", "bin", "kodawari")):
        if os.path.isfile(candidate) and os.access(candidate, os.X_OK):
            return os.path.realpath(candidate)
    found = shutil.which("kodawari")
    if found is None:
        raise Error("KODAWARI_UNAVAILABLE", "kodawari.bench: no `kodawari` command beside the package "
                    f"({here}) or on PATH; build the project or install it")
    return found


BENCH_KINDS = ("birds", "chains", "crowd", "flock", "view", "ceilings")
"""What `kodawari bench` times (docs/performance.md)."""


def bench(kind, *, command=None, **options):
    """Runs `kodawari bench KIND ... --json` and returns what it writes, as a dict
    (docs/performance.md: "benchmark", the settings, and "results", one dict per backend
    with per_second, min, max, ms_per_frame, gpu_ms_per_frame, vs_cpu_reference, vs_cpu,
    isa, threads).

    kind: one of BENCH_KINDS ("birds", "chains", "crowd", "flock", "view", "ceilings";
    ValueError for another; "ceilings" gives the machine's fp32_flops and
    triad_bytes_per_second, each with median, min and max, instead of "results"). options: the command's options with _ for
    - (count=1000, frames=30, backends=["cpu", "vulkan"], repetitions=3, readback=True,
    threads=2, isa="avx2", device=..., validation=True; `kodawari bench KIND --help` lists
    them); True gives a flag, a list is joined with commas, None and False are left out.
    command: the `kodawari` executable (default: command_path()).

    The benchmark runs in the command, a process of its own, exactly as from the shell: the
    timings are the command's, not this Python's. Blocks until it ends (seconds to minutes).
    Raises Error with the command's message when it refuses an option or fails, and when
    the command's version is not this package's.
    """
    if kind not in BENCH_KINDS:
        raise ValueError(f"kind: {kind!r}; expected one of {', '.join(BENCH_KINDS)}")
    command = command or command_path()
    arguments = [command, "bench", str(kind)]
    for name, value in options.items():
        if value is None or value is False:
            continue
        flag = "--" + name.replace("_", "-")
        if value is True:
            arguments.append(flag)
        elif isinstance(value, (list, tuple)):
            arguments += [flag, ",".join(str(v) for v in value)]
        else:
            arguments += [flag, str(value)]
    version = subprocess.run([command, "--version"], capture_output=True, text=True)
    if version.returncode != 0 or version.stdout.split()[-1:] != [__version__]:
        raise Error("KODAWARI_UNAVAILABLE", f"kodawari.bench: {command} is {version.stdout.strip() or 'not kodawari'}, "
                    f"this package is {__version__}")
    with tempfile.TemporaryDirectory(prefix="kodawari-bench-") as folder:
        path = os.path.join(folder, "bench.json")
        run = subprocess.run(arguments + ["--json", path], capture_output=True, text=True)
        if run.returncode != 0:
            message = run.stderr.strip() or run.stdout.strip()
            raise Error("KODAWARI_INVALID_ARGUMENT" if run.returncode == 2 else "KODAWARI_INTERNAL",
                        f"{' '.join(arguments[1:])}: {message}")
        with open(path) as file:
            return json.load(file)


class Simulation:
    """A scene file simulated frame after frame on one backend kind, as `kodawari run`
    runs it: its flocks' birds and its characters' chains.

    Make one with Simulation.open(). It holds the library's simulation (and, on vulkan, a
    Vulkan device) until close(), the end of a `with` block, or garbage collection. Calls on
    one Simulation are serialized by a lock; different Simulations may run on different
    threads at once.
    """

    def __init__(self, handle):
        # Use Simulation.open(); this takes the library's handle.
        self._handle = handle
        self._lock = threading.Lock()

    @classmethod
    def open(cls, path, backend="cpu", *, frames=None, threads=0, device=None, validation=False):
        """Loads the scene file `path` (SCENE.json, docs/scene-format.md) and opens its
        backends.

        backend: "cpu-reference" (scalar, one thread: the oracle), "cpu" (vectorized, on
        `threads` threads, 0 = one per hardware thread), "vulkan" (compute shaders; Mesa's
        lavapipe without a GPU) or "auto".
        frames: how many frames to simulate, at most 10 000 000 (None: the scene's
        duration x fps).
        device: for vulkan, a device index ("0") or part of its name ("llvmpipe").
        validation: for vulkan, run under the Khronos validation layer.

        Raises Error naming the file when it cannot be read or is not a valid scene, and
        with status KODAWARI_UNAVAILABLE when the backend cannot run here (no Vulkan device).
        """
        if backend not in _native.BACKENDS:
            raise ValueError(f"backend: {backend!r}; expected one of {', '.join(BACKENDS)}")
        if frames is not None:
            _whole_number("frames", frames, 1, 10_000_000, "a whole number in [1, 10 000 000], or None for the scene's")
        threads = _whole_number("threads", threads, 0, 1024, "a whole number from 0 (one per hardware thread) to 1024")
        options = _native.BackendOptions()
        options.backend = _native.BACKENDS[backend]
        options.device = device.encode() if device else None
        options.validation = 1 if validation else 0
        options.threads = threads
        handle = _native.ctypes.c_void_p()
        _check(_native.lib.kodawari_simulation_open(os.fsencode(path), options, int(frames or 0),
                                                    _native.ctypes.byref(handle)))
        return cls(handle)

    # ---- lifetime

    def close(self):
        """Frees the library's simulation (and its device). Calling it again does nothing;
        any other call afterwards raises Error. Arrays already returned stay valid."""
        with self._lock:
            if self._handle:
                _native.lib.kodawari_simulation_destroy(self._handle)
                self._handle = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        handle = getattr(self, "_handle", None)
        if handle:
            _native.lib.kodawari_simulation_destroy(handle)
            self._handle = None

    def _live(self):
        if not self._handle:
            raise Error("KODAWARI_INVALID_ARGUMENT", "sim: this Simulation was closed")
        return self._handle

    def _info(self):
        with self._lock:
            handle = self._live()
            info = _native.SimulationInfo()
            _check(_native.lib.kodawari_simulation_get_info(handle, _native.ctypes.byref(info)), handle)
            return info

    # ---- stepping

    def step(self, frames=1):
        """Simulates the next `frames` frames (the first call simulates frame 0). Raises
        Error (naming `frames`) past the last frame; nothing changes then."""
        frames = _whole_number("frames", frames, 1, 0xFFFFFFFF, "a whole number >= 1")
        with self._lock:
            handle = self._live()
            _check(_native.lib.kodawari_simulation_step(handle, int(frames)), handle)

    def set_wind(self, velocity=None, *, gust=0.0, gust_period=3.0, gust_size=6.0, seed=0):
        """The wind the characters' chains feel from the next frame on, in place of the
        scene's `wind` (characters with a wind of their own keep theirs): the mean air
        `velocity` (m/s, 3 numbers, each within 100), gusts up to `gust` (0 to 4) times
        its speed, rising and falling over `gust_period` s and `gust_size` m, from noise
        `seed`. `velocity=None`: the scene's wind again. Raises Error naming the member
        out of range; nothing changes then."""
        wind = None
        if velocity is not None:
            air = _point("velocity", velocity, "m/s")
            seed = _whole_number("seed", seed, 0, 0xFFFFFFFF, "a whole number in [0, 4294967295]")
            wind = _native.Wind(air, float(gust), float(gust_period),
                                float(gust_size), int(seed))
        with self._lock:
            handle = self._live()
            _check(_native.lib.kodawari_simulation_set_wind(handle, ctypes.byref(wind) if wind is not None else None),
                   handle)

    def set_lod_budget(self, budget_ms, *, measured=False):
        """The budget mode of the levels of detail: from the next frame, fewer characters
        are fully simulated, nearest first, so that a frame's clips and chains stay within
        `budget_ms` milliseconds. `measured=False` prices frames by the scene's cost model
        (the same bits on every run); True scales it by what the frames took. Raises
        ValueError for a budget that is not a positive finite number, Error when the scene
        has no characters, its `lod` is off, or (Unsupported) after the first step with
        the rod input on the device."""
        budget = float(budget_ms)
        if not math.isfinite(budget) or budget <= 0.0:
            raise ValueError(f"budget_ms: {budget_ms!r}; expected a positive finite number of milliseconds")
        with self._lock:
            handle = self._live()
            _check(_native.lib.kodawari_simulation_set_lod_budget(handle, budget, 1 if measured else 0), handle)

    FLOCK_AGENT_KINDS = ("predator", "attractor", "obstacle", "capsule", "plane")

    def lod_budget(self):
        """The levels' budget and what it did at the last step, or None without a budget: a
        dict of budget_ms, measured (bool), scale (what measured frames put on the cost
        model), full_distance (m: the depth within which characters could be full; inf
        when the budget took every character the projected-size rule makes full, -inf when
        it took none) and modelled_ms (the frame as the model priced it)."""
        with self._lock:
            handle = self._live()
            out = _native.LodBudget()
            _check(_native.lib.kodawari_simulation_lod_budget(handle, _native.ctypes.byref(out)), handle)
            if not out.active:
                return None
            return {"budget_ms": out.budget_ms, "measured": bool(out.measured), "scale": out.scale,
                    "full_distance": out.full_distance, "modelled_ms": out.modelled_ms}

    def set_flock_agents(self, agents=()):
        """Places agents among the scene's flocking birds from the next frame on, beside the
        scene's predators, until called again (no agents: removes them). Each agent is a
        dict: `kind` ("predator": fled across its path; "attractor": drawn to; "obstacle":
        a sphere kept out of; "capsule": one from `position` to `end`; "plane": the one
        through `position` with `normal`, birds kept on the normal's side), `position` (3
        numbers, m), and optionally `velocity` (m/s, a predator's), `radius` (m, default
        15), `weight` (m/s^2, default 40), `margin` (m, an obstacle's, default 2), `end`
        (m, a capsule's) and `normal` (a plane's, default up). At most 64. Raises
        ValueError naming agents[i] and the key for a missing position, an unknown key or
        kind, or a value of the wrong shape, and Error naming agents[i] and the member out
        of range; nothing changes then."""
        if isinstance(agents, (dict, str, bytes)):
            raise ValueError(f"agents: {agents!r}; expected a list of dicts, one per agent")
        agents = list(agents)
        array = (_native.FlockAgent * max(len(agents), 1))()
        keys = ("kind", "position", "velocity", "radius", "weight", "margin", "end", "normal")
        for i, agent in enumerate(agents):
            if not isinstance(agent, dict):
                raise ValueError(f"agents[{i}]: {agent!r}; expected a dict with `kind` and `position`")
            unknown = set(agent) - set(keys)
            if unknown:
                raise ValueError(f"agents[{i}]: unknown key(s) {', '.join(sorted(map(str, unknown)))}")
            kind = agent.get("kind", "predator")
            if kind not in self.FLOCK_AGENT_KINDS:
                raise ValueError(f"agents[{i}].kind: {kind!r}; expected one of {', '.join(self.FLOCK_AGENT_KINDS)}")
            if "position" not in agent:
                raise ValueError(f"agents[{i}].position: missing; expected 3 numbers (m)")

            def point(key, default, unit="m"):
                return _point(f"agents[{i}].{key}", agent.get(key, default), unit)

            def number(key, default):
                return _real(f"agents[{i}].{key}", agent.get(key, default))

            array[i] = _native.FlockAgent(self.FLOCK_AGENT_KINDS.index(kind), point("position", None),
                                          point("velocity", (0, 0, 0), "m/s"), number("radius", 15.0),
                                          number("weight", 40.0), number("margin", 2.0), point("end", (0, 0, 0)),
                                          point("normal", (0, 1, 0), "a direction"))
        with self._lock:
            handle = self._live()
            _check(_native.lib.kodawari_simulation_set_flock_agents(handle, array if agents else None, len(agents)), handle)

    # ---- outputs

    def bird_poses(self, space="local"):
        """The last simulated frame's birds: a new float32 array of shape (birds, 7, 7), one
        row per bird (in the scene's order, flock by flock), one entry per part (PARTS
        order), each x, y, z, qx, qy, qz, qw.

        space="local": each part relative to its parent (its rig offset and rotation; Body
        in world space), what drives an armature's bones. space="world": each part in world
        space. Metres, +Y up; quaternions unit length.

        The array is a copy: the next step() does not change it, and it stays valid after
        close(). Raises Error before the first step().
        """
        if space not in ("local", "world"):
            raise ValueError(f"space: {space!r}; expected 'local' or 'world'")
        with self._lock:
            handle = self._live()
            info = _native.SimulationInfo()
            _check(_native.lib.kodawari_simulation_get_info(handle, _native.ctypes.byref(info)), handle)
            poses = numpy.empty((info.bird_count, _native.BIRD_PARTS, _native.TRANSFORM_FLOATS), numpy.float32)
            out = _native.BirdOutput()
            if space == "local":
                out.local_transforms, out.local_transforms_capacity = poses.ctypes.data, poses.size
            else:
                out.world_transforms, out.world_transforms_capacity = poses.ctypes.data, poses.size
            _check(_native.lib.kodawari_simulation_bird_poses(handle, _native.ctypes.byref(out)), handle)
            return poses

    def bird_tail_spreads(self):
        """The last simulated frame's tail spread of every bird: a new float32 array of shape
        (birds,). The Tail's scale along its width (its local x) is 1 + spread, as in the
        glTF export. A copy, as bird_poses(). Raises Error before the first step()."""
        with self._lock:
            handle = self._live()
            info = _native.SimulationInfo()
            _check(_native.lib.kodawari_simulation_get_info(handle, _native.ctypes.byref(info)), handle)
            spreads = numpy.empty(info.bird_count, numpy.float32)
            _check(_native.lib.kodawari_simulation_bird_tail_spreads(handle, spreads.ctypes.data, spreads.size), handle)
            return spreads

    def chain_joints(self):
        """The chains' joints after the last step: (positions, orientations), new float32
        arrays of shape (joints, 3) (world, metres) and (joints, 4) (the particles' world
        orientations, x, y, z, w). Chain c's joints are rows chain_ranges()[c]. A scene
        without characters gives 0 rows.

        Copies, read back from the device on vulkan: valid after the next step() and after
        close(). Raises Error before the first step().
        """
        with self._lock:
            handle = self._live()
            info = _native.SimulationInfo()
            _check(_native.lib.kodawari_simulation_get_info(handle, _native.ctypes.byref(info)), handle)
            positions = numpy.empty((info.joint_count, 3), numpy.float32)
            orientations = numpy.empty((info.joint_count, 4), numpy.float32)
            out = _native.ChainOutput()
            out.positions, out.positions_capacity = positions.ctypes.data, positions.size
            out.orientations, out.orientations_capacity = orientations.ctypes.data, orientations.size
            _check(_native.lib.kodawari_simulation_read_chains(handle, _native.ctypes.byref(out)), handle)
            return positions, orientations

    def chain_levels(self):
        """Every chain's level of detail at the last step (docs/level-of-detail.md): (levels,
        kept), new arrays of shape (chains,): levels uint8, LEVEL_FULL, LEVEL_POSED,
        LEVEL_HIDDEN or LEVEL_REDUCED (where the scene's lod.reduced_pixels turns it on);
        kept bool, True where the chain kept its state at that step instead of stepping
        (a far posed or hidden chain between its turns). Every chain
        LEVEL_FULL while the scene's `lod` is off. Raises Error before the first step()."""
        with self._lock:
            handle = self._live()
            info = _native.SimulationInfo()
            _check(_native.lib.kodawari_simulation_get_info(handle, _native.ctypes.byref(info)), handle)
            levels = numpy.zeros(info.chain_count, numpy.uint8)
            kept = numpy.zeros(info.chain_count, numpy.uint8)
            _check(_native.lib.kodawari_simulation_chain_levels(handle, levels.ctypes.data, kept.ctypes.data,
                                                                 levels.size), handle)
            return levels, kept.astype(bool)

    def chain_ranges(self):
        """Where each chain's joints are in chain_joints()' rows: a new uint32 array of
        shape (chains, 2), each row (first joint, joint count)."""
        with self._lock:
            handle = self._live()
            info = _native.SimulationInfo()
            _check(_native.lib.kodawari_simulation_get_info(handle, _native.ctypes.byref(info)), handle)
            ranges = numpy.empty((info.chain_count, 2), numpy.uint32)
            begin, count = _native.ctypes.c_uint32(), _native.ctypes.c_uint32()
            for c in range(info.chain_count):
                _check(_native.lib.kodawari_simulation_chain_joints(handle, c, _native.ctypes.byref(begin),
                                                                     _native.ctypes.byref(count)), handle)
                ranges[c] = (begin.value, count.value)
            return ranges

    def bake(self, path, compact=False):
        """Bakes the scene to glTF binary files as `kodawari run --out PATH` does and
        returns the paths written. Every frame from frame 0 is simulated anew on a
        simulation of its own (same scene, backend and frame count): this one keeps its
        frame. The flock goes to `path`, the characters to `path` when the scene has no
        birds, else to PATH-without-.glb + "-characters.glb". compact=True drops the keys
        that linear interpolation reproduces within 1 mm / 0.001 rad (docs/compact.md).
        Files are written whole or not at all; Error names a path that cannot be written.

        The bake is the scene's own: what was set on this simulation (set_flock_agents,
        set_wind, set_lod_budget) is not applied to it, since the new simulation starts
        from the scene file. Step this one and read its outputs to keep them.
        """
        if not isinstance(compact, bool):
            raise ValueError(f"compact: {compact!r}; expected True or False")
        with self._lock:
            handle = self._live()
            written = _native.ctypes.create_string_buffer(64 * 1024)
            _check(_native.lib.kodawari_simulation_bake(handle, os.fsencode(path), 1 if compact else 0, written,
                                                        len(written)), handle)
            return [os.fsdecode(line) for line in written.value.split(b"\n") if line]

    # ---- what it is

    @property
    def backend(self):
        """The backend running ("cpu-reference", "cpu" or "vulkan"; "auto" resolved)."""
        return _native.BACKEND_NAMES[self._info().backend]

    @property
    def device(self):
        """What it runs on ("llvmpipe (LLVM 15.0.6, 256 bits)", "2 threads")."""
        return self._info().device.decode(errors="replace")

    @property
    def fallback_reason(self):
        """Why backend="auto" runs on the CPU ("" when it did not fall back)."""
        return self._info().fallback_reason.decode(errors="replace")

    @property
    def name(self):
        """The scene's name."""
        return self._info().name.decode(errors="replace")

    @property
    def bird_count(self):
        """Birds of every flock."""
        return self._info().bird_count

    @property
    def character_count(self):
        """Character instances."""
        return self._info().character_count

    @property
    def chain_count(self):
        """Chains of every character instance."""
        return self._info().chain_count

    @property
    def joint_count(self):
        """Joints of every chain: chain_joints()' rows."""
        return self._info().joint_count

    @property
    def frame_count(self):
        """Frames in all: open()'s `frames`, else the scene's."""
        return self._info().frame_count

    @property
    def frame(self):
        """The frame simulated last (0 after the first step), or None before it."""
        done = self._info().next_frame
        return done - 1 if done else None

    @property
    def fps(self):
        """Frames per second of the scene."""
        return self._info().fps

    def __repr__(self):
        if not self._handle:
            return "<kodawari.Simulation (closed)>"
        info = self._info()
        return (f"<kodawari.Simulation {info.name.decode(errors='replace')!r}: {info.bird_count} birds, "
                f"{info.chain_count} chains, {info.next_frame} of {info.frame_count} frames simulated on "
                f"{_native.BACKEND_NAMES[info.backend]}>")
