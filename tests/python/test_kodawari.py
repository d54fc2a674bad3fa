"""ctest `python`: the Python package `kodawari` (python/kodawari, issue 33) from the build
tree, in Debian's /usr/bin/python3 with Debian's numpy, on every backend kind this machine
has (cpu-reference, cpu, and vulkan where a Vulkan device opens: lavapipe here), with
figures checked against each other and against the scene:

- scenes/flock.json (270 birds, 30 frames): poses of shape (270, 7, 7), unit quaternions,
  cpu against cpu-reference and vulkan against cpu-reference within the bird parity
  tolerances (BirdTolerances, kodawari/backends/compare.hpp);
- scenes/ahoge.json (one 12-joint chain, 40 frames): cpu's joints are cpu-reference's bits,
  vulkan's within 1e-3 of the chain length;
- arrays are copies; a bad path raises kodawari.Error naming the file; a bake writes a
  glTF binary file; help() shows the methods' documentation.

- a bake writes the bytes `kodawari run` writes for the same scene, backend and frames;
- bench() returns what `kodawari bench --json` writes, with the command's keys and settings.

Usage: /usr/bin/python3 test_kodawari.py BUILD_PYTHON_DIR SOURCE_DIR TEMP_DIR VERSION KODAWARI_CLI
Exit status 0 when every check passed.
"""
import json
import os
import pydoc
import subprocess
import sys
import time

build_python, source, temp, version, cli = sys.argv[1:6]
sys.path.insert(0, build_python)

failures = []


def check(condition, what):
    if not condition:
        failures.append(what)
        print("FAILED:", what, flush=True)


# The interpreter ctest runs is Debian's, whatever else is on PATH (pyenv, conda).
check(sys.executable == "/usr/bin/python3", f"running in {sys.executable}, not /usr/bin/python3")
try:
    import numpy
except ImportError:
    print("test_kodawari: Debian's python3-numpy is missing (bash scripts/setup installs it)", file=sys.stderr)
    sys.exit(1)
import kodawari  # noqa: E402

check(os.path.dirname(kodawari.__file__) == os.path.join(build_python, "kodawari"), f"imported {kodawari.__file__}")
check(kodawari.library_path.startswith(os.path.join(build_python, "kodawari")), f"library {kodawari.library_path}")
check(kodawari.__version__ == version == kodawari.library_version(),
      f"versions: package {kodawari.__version__}, project {version}, library {kodawari.library_version()}")

FLOCK = os.path.join(source, "scenes", "flock.json")
AHOGE = os.path.join(source, "scenes", "ahoge.json")
validation = os.environ.get("KODAWARI_VALIDATION", "0") not in ("", "0")


def open_or_none(path, backend, frames):
    try:
        return kodawari.Simulation.open(path, backend, frames=frames, validation=validation and backend == "vulkan")
    except kodawari.Error as error:
        if backend == "vulkan" and error.status == "KODAWARI_UNAVAILABLE":
            print(f"vulkan: not available here, skipped ({error})")
            return None
        raise


# ---- The flock on every backend.
poses = {}
for backend in ("cpu-reference", "cpu", "vulkan"):
    sim = open_or_none(FLOCK, backend, 30)
    if sim is None:
        continue
    with sim:
        check(sim.backend == backend, f"{backend}: runs {sim.backend}")
        check((sim.bird_count, sim.chain_count, sim.frame_count, sim.frame) == (270, 0, 30, None),
              f"{backend}: {sim!r}")
        start = time.perf_counter()
        sim.step(10)
        early = sim.bird_poses("world")
        sim.step(20)
        seconds = time.perf_counter() - start
        local = sim.bird_poses()
        world = sim.bird_poses("world")
        check(sim.frame == 29, f"{backend}: frame {sim.frame} after 30 frames")
        check(local.shape == (270, 7, 7) and local.dtype == numpy.float32, f"{backend}: shape {local.shape}")
        # Body is in world space in both spaces.
        check(numpy.array_equal(local[:, 0], world[:, 0]), f"{backend}: Body differs between spaces")
        # "local": a child part sits at its rig offset, the same for every bird of a wing
        # type (the first 120 are pigeons); "world": at that distance from its parent.
        check(numpy.array_equal(local[:120, 1, :3], numpy.broadcast_to(local[0, 1, :3], (120, 3))),
              f"{backend}: the pigeons' Head offsets differ in local space")
        reach = numpy.linalg.norm(world[:, 1, :3] - world[:, 0, :3], axis=1)
        check(numpy.abs(reach - numpy.linalg.norm(local[:, 1, :3], axis=1)).max() < 1e-5,
              f"{backend}: Head's world distance from Body is not its offset's length")
        norms = numpy.linalg.norm(local[:, :, 3:], axis=2)
        check(numpy.abs(norms - 1).max() < 1e-5, f"{backend}: quaternion lengths off by {numpy.abs(norms - 1).max()}")
        # 20 frames at 60 fps: every bird flies between 1 and 40 m/s (cruise speeds 8-20 m/s).
        speeds = numpy.linalg.norm(world[:, 0, :3] - early[:, 0, :3], axis=1) / (20 / 60)
        check(speeds.min() > 1 and speeds.max() < 40, f"{backend}: speeds {speeds.min()} to {speeds.max()} m/s")
        # The Tail's spread (its scale is 1 + s): the looks of wingbeat.cpp spread 0 to 0.9.
        spreads = sim.bird_tail_spreads()
        check(spreads.shape == (270,) and spreads.min() >= 0 and spreads.max() <= 1, f"{backend}: spreads {spreads}")
        # A copy: stepping on does not change it.
        before = local.copy()
        check(not numpy.shares_memory(local, sim.bird_poses()), f"{backend}: two calls share memory")
        print(f"{backend}: 270 birds, 30 frames in {seconds * 1000:.1f} ms on {sim.device}; "
              f"speeds {speeds.min():.2f} to {speeds.max():.2f} m/s")
        poses[backend] = local
    check(numpy.array_equal(before, local), f"{backend}: an array changed after close()")

reference = poses["cpu-reference"]
for backend in ("cpu", "vulkan"):
    if backend not in poses:
        continue
    got = poses[backend]
    position = float(numpy.abs(got[:, :, :3] - reference[:, :, :3]).max())
    rotation = float(numpy.abs(got[:, :, 3:] - reference[:, :, 3:]).max())
    print(f"{backend} against cpu-reference: positions within {position:g} m, quaternion components within {rotation:g}")
    # BirdTolerances: rotations within 1e-4 rad, which moves a unit quaternion's components
    # by at most 5e-5; positions within 1e-5 of the longest route, 2e-3 m on flock.json's
    # ~200 m routes. (The cpu backend's poses are not cpu-reference's bits: it takes its
    # own vectorized sines of the wingbeat phase; tests/backends/test_backends.cpp.)
    check(position <= 2e-3, f"{backend}: positions {position} m off cpu-reference")
    check(rotation <= 5e-5, f"{backend}: rotations {rotation} off cpu-reference")

# ---- The ahoge's chain on every backend.
joints = {}
for backend in ("cpu-reference", "cpu", "vulkan"):
    sim = open_or_none(AHOGE, backend, 40)
    if sim is None:
        continue
    with sim:
        check((sim.chain_count, sim.joint_count, sim.bird_count) == (1, 12, 0), f"{backend}: {sim!r}")
        check(sim.chain_ranges().tolist() == [[0, 12]], f"{backend}: ranges {sim.chain_ranges().tolist()}")
        sim.step(40)
        positions, orientations = sim.chain_joints()
        check(positions.shape == (12, 3) and orientations.shape == (12, 4), f"{backend}: {positions.shape}")
        segments = numpy.linalg.norm(numpy.diff(positions, axis=0), axis=1)
        # 0.14 m in 11 segments; the distance constraints hold each within 2 % while the
        # head turns (the C test's bound).
        check(numpy.abs(segments / (0.14 / 11) - 1).max() < 0.02, f"{backend}: segments {segments}")
        joints[backend] = positions
for backend in ("cpu", "vulkan"):
    if backend not in joints:
        continue
    worst = float(numpy.linalg.norm(joints[backend] - joints["cpu-reference"], axis=1).max())
    print(f"ahoge on {backend} against cpu-reference: joints within {worst:g} m")
    if backend == "cpu":
        check(numpy.array_equal(joints["cpu"], joints["cpu-reference"]), "cpu's joints are not cpu-reference's bits")
    else:
        # The rod backends' trajectory parity (tests/backends/test_rod_backends.cpp): within
        # 1e-3 of the chain length, 1.4e-4 m.
        check(worst < 1e-3 * 0.14, f"vulkan's joints {worst} m off cpu-reference")

# ---- Wind from the application: the ahoge in a 10 m/s gusty wind from frame 10 ends elsewhere
# than in the scene's calm air; a gust out of range raises Error naming the member and
# changes nothing; set_wind(None) gives the scene's calm air back (the same bits as never set).
def ahoge_joints(wind):
    with kodawari.Simulation.open(AHOGE, "cpu", frames=40) as sim:
        sim.step(10)
        if wind == "bad-then-none":
            try:
                sim.set_wind((5.0, 0.0, 0.0), gust=9.0)
                check(False, "a gust of 9 raised nothing")
            except kodawari.Error as error:
                check("wind.gust: 9" in str(error), f"set_wind(gust=9): {error}")
            sim.set_wind((5.0, 0.0, 0.0))
            sim.set_wind(None)
        elif wind is not None:
            sim.set_wind(wind, gust=0.5, gust_period=2.0, gust_size=4.0, seed=7)
        sim.step(30)
        return sim.chain_joints()[0]


calm = ahoge_joints(None)
blown = ahoge_joints((10.0, 0.0, 0.0))
restored = ahoge_joints("bad-then-none")
moved = float(numpy.abs(blown - calm).max())
print(f"set_wind: a 10 m/s wind moved a joint by {moved:.4f} m in 30 frames")
check(moved > 1e-3, f"set_wind: the wind moved nothing ({moved} m)")
check(numpy.array_equal(restored, calm), "set_wind(None) did not give the scene's calm air back")

# ---- The levels of detail's budget from the application: refused where it cannot be (a
# budget that is no positive finite number raises ValueError; a scene whose lod is off
# raises Error naming it), taken otherwise.
with kodawari.Simulation.open(AHOGE, "cpu", frames=4) as sim:
    for bad in (0.0, -1.0, float("inf"), float("nan")):
        try:
            sim.set_lod_budget(bad)
            check(False, f"set_lod_budget({bad}) raised nothing")
        except ValueError as error:
            check("budget_ms" in str(error), f"set_lod_budget({bad}): {error}")
    try:
        sim.set_lod_budget(16.0)
        check(False, "set_lod_budget on a scene without levels of detail raised nothing")
    except kodawari.Error as error:
        check("levels of detail are off" in str(error), f"set_lod_budget without lod: {error}")
    sim.step(4)

# ---- Every chain's level of detail and whether it kept its state: crowd-10k cut to 40
# characters (camera 90 m out: every chain posed, far ones keeping their state between their
# turns), the same on cpu-reference and cpu; a scene without levels of detail is all full.
crowd_scene = os.path.join(temp, "crowd-40.json")
with open(os.path.join(source, "scenes", "crowd-10k.json")) as f:
    crowd = json.load(f)
crowd["lod"]["enabled"] = True
crowd["crowds"][0]["count"] = 40
crowd["characters"][0]["gltf"] = os.path.join(source, "scenes", "characters", "chibi.glb")
with open(crowd_scene, "w") as f:
    json.dump(crowd, f)
level_runs = []
for backend in ("cpu-reference", "cpu"):
    with kodawari.Simulation.open(crowd_scene, backend, frames=9) as sim:
        try:
            sim.chain_levels()
            check(False, "chain_levels() before the first step raised nothing")
        except kodawari.Error as error:
            check("kodawari_simulation_step" in str(error), f"chain_levels() before a step: {error}")
        sim.step(6)
        levels, kept = sim.chain_levels()
        check(levels.shape == (sim.chain_count,) and levels.dtype == numpy.uint8, f"levels {levels.shape} {levels.dtype}")
        check(kept.shape == (sim.chain_count,) and kept.dtype == bool, f"kept {kept.shape} {kept.dtype}")
        check(bool((levels == kodawari.LEVEL_POSED).all()), f"{backend}: levels {numpy.bincount(levels)}, every chain posed expected")
        check(0 < int(kept.sum()) < sim.chain_count, f"{backend}: {int(kept.sum())} of {sim.chain_count} chains kept their state")
        level_runs.append((levels, kept))
        # The budget's state: none, then a roomy model budget that takes every character the
        # rule makes full (so full_distance is +inf) and priced the frame.
        check(sim.lod_budget() is None, f"{backend}: a budget before set_lod_budget: {sim.lod_budget()}")
        sim.set_lod_budget(100.0)
        sim.step(1)
        budget = sim.lod_budget()
        check(budget is not None and budget["budget_ms"] == 100.0 and budget["measured"] is False and budget["scale"] == 1.0
              and budget["full_distance"] == float("inf") and 0.0 < budget["modelled_ms"] < 100.0, f"{backend}: {budget}")
print(f"chain_levels: {len(level_runs[1][0])} chains posed, {int(level_runs[1][1].sum())} kept their state at frame 6")
check(all(numpy.array_equal(a, b) for a, b in zip(*level_runs)), "chain_levels: cpu and cpu-reference disagree")
with kodawari.Simulation.open(AHOGE, "cpu", frames=2) as sim:
    sim.step(1)
    levels, kept = sim.chain_levels()
    check(bool((levels == kodawari.LEVEL_FULL).all()) and not kept.any(), f"ahoge (no lod): {levels}, {kept}")
check((kodawari.LEVEL_FULL, kodawari.LEVEL_POSED, kodawari.LEVEL_HIDDEN, kodawari.LEVEL_REDUCED) == (0, 1, 2, 3),
      "the levels' values are the C API's kodawari_level")

# ---- Flock agents from the application: named errors, and a flocking flock flies round an
# obstacle placed in its way (no bird inside the 3 m sphere; without it, birds pass its centre).
flocking_scene = os.path.join(temp, "flocking.json")
with open(flocking_scene, "w") as f:
    f.write('{"format": "kodawari-scene", "version": 1, "fps": 60, "duration": 4, '
            '"camera": {"position": [0, 60, -160], "target": [0, 45, 0]}, "flocks": [{"name": "s", "wing_type": "pigeon", "count": 301, '
            '"seed": 3, "speed": 15, "generated_route": {"seed": 7, "segments": 8, "center": [0, 45, 0], '
            '"extent": [45, 8, 45], "loop": true}, "formation": {"spread": [10, 5, 10]}, "flocking": {}}]}')


def flock_positions(agents):
    with kodawari.Simulation.open(flocking_scene, "cpu", frames=180) as sim:
        if agents:
            sim.set_flock_agents(agents)
        out = []
        for _ in range(180):
            sim.step(1)
            out.append(sim.bird_poses(space="world")[:, 0, :3].copy())
        return numpy.stack(out)


free_flight = flock_positions(None)
middle = free_flight[120].mean(axis=0)
placed = flock_positions([{"kind": "obstacle", "position": tuple(float(v) for v in middle), "radius": 3.0,
                           "margin": 12.0, "weight": 80.0}])
near_free = float(numpy.linalg.norm(free_flight[90:150] - middle, axis=2).min())
near_placed = float(numpy.linalg.norm(placed[90:150] - middle, axis=2).min())
print(f"set_flock_agents: nearest bird to a 3 m obstacle's centre {near_free:.2f} m without it, {near_placed:.2f} m with it")
# No bird inside the sphere (docs/flocking.md: a 12 m margin leaves room to turn aside).
check(near_placed > 3.0 and near_placed > near_free, "set_flock_agents: the flock did not keep out of the obstacle")
# A plane 2 m under the flock's middle (a cliff top): the birds keep above it.
floor_y = float(middle[1]) - 2.0
walled = flock_positions([{"kind": "plane", "position": (float(middle[0]), floor_y, float(middle[2])), "normal": (0, 1, 0),
                           "margin": 6.0, "weight": 80.0}])
low_free = float((free_flight[90:180, :, 1] - floor_y).min())
low_walled = float((walled[90:180, :, 1] - floor_y).min())
print(f"set_flock_agents: lowest bird against a plane 2 m under the flock {low_free:.2f} m without it, {low_walled:.2f} m with it")
check(low_free < -1.0 and low_walled > -0.5, "set_flock_agents: the flock did not keep above the plane")
with kodawari.Simulation.open(flocking_scene, "cpu", frames=2) as sim:
    try:
        sim.set_flock_agents([{"kind": "plane", "position": (0, 0, 0), "normal": (0, 0, 0)}])
        check(False, "a plane's zero normal raised nothing")
    except kodawari.Error as error:
        check("agents[0].normal" in str(error), f"set_flock_agents(normal=0): {error}")
    try:
        sim.set_flock_agents([{"kind": "predator", "position": (0, 40, 0)}, {"kind": "obstacle", "position": (0, 0, 0), "radius": -1}])
        check(False, "a radius of -1 raised nothing")
    except kodawari.Error as error:
        check("agents[1].radius" in str(error), f"set_flock_agents(radius=-1): {error}")
    try:
        sim.set_flock_agents([{"kind": "hawk", "position": (0, 0, 0)}])
        check(False, "a kind of hawk raised nothing")
    except ValueError as error:
        check("agents[0].kind" in str(error), f"set_flock_agents(kind=hawk): {error}")
    # Shapes Python gives that are not a list of agent dicts: ValueError naming where.
    for bad, expected in (({"kind": "predator", "position": (0, 40, 0)}, "agents:"), ([{}], "agents[0].position: missing"),
                          ([(0, 0, 0)], "agents[0]:"), ([{"position": 5}], "agents[0].position: 5"),
                          ([{"position": (0, 0, 0), "radius": "big"}], "agents[0].radius")):
        try:
            sim.set_flock_agents(bad)
            check(False, f"set_flock_agents({bad!r}) raised nothing")
        except ValueError as error:
            check(expected in str(error), f"set_flock_agents({bad!r}): {error}")
    # NumPy's scalars and arrays are numbers (a float32 radius, a position from an array).
    sim.set_flock_agents([{"kind": "obstacle", "position": numpy.array([0, 40, 0], numpy.float32),
                           "radius": numpy.float32(3.0), "margin": numpy.int64(2)}])
    try:
        sim.bake(os.path.join(temp, "agents.glb"), compact="no")
        check(False, "bake(compact='no') raised nothing")
    except ValueError as error:
        check("compact" in str(error), f"bake(compact='no'): {error}")
    sim.set_flock_agents([])
try:
    kodawari.Simulation.open(flocking_scene, "cpu", frames=10_000_001)
    check(False, "frames=10 000 001 raised nothing")
except ValueError as error:
    check("frames" in str(error), f"open(frames=10 000 001): {error}")

# ---- Errors carry the library's message.
missing = os.path.join(temp, "no-such-scene.json")
try:
    kodawari.Simulation.open(missing)
    check(False, "opening a missing file raised nothing")
except kodawari.Error as error:
    print(f"a missing file: {error.status}: {error}")
    check(error.status == "KODAWARI_INVALID_ARGUMENT" and missing in str(error), f"the error says {error}")
with kodawari.Simulation.open(FLOCK, "cpu", frames=3) as sim:
    for call in (sim.bird_poses, sim.chain_joints):
        try:
            call()
            check(False, f"{call.__name__} before a step raised nothing")
        except kodawari.Error as error:
            check("no frame simulated yet" in str(error), f"{call.__name__}: {error}")
    try:
        sim.step(4)
        check(False, "stepping past the end raised nothing")
    except kodawari.Error as error:
        check("frames: 4" in str(error) and "expected 1 to 3" in str(error), f"step(4): {error}")
    check(sim.frame is None, "a rejected step changed the frame")
    # A bake: its own simulation from frame 0; this one keeps its frame.
    sim.step(2)
    out = os.path.join(temp, "flock-python.glb")
    written = sim.bake(out)
    check(written == [out], f"bake wrote {written}")
    with open(out, "rb") as file:
        check(file.read(4) == b"glTF", f"{out} is not a glTF binary file")
    check(sim.frame == 1, f"frame {sim.frame} after a bake")
    # The command line's file for the same scene, backend and frames, byte for byte.
    out_cli = os.path.join(temp, "flock-cli.glb")
    # Without the sanitizer runtime the asan lane preloads into Python (the command carries
    # its own).
    environment = {k: v for k, v in os.environ.items() if k != "LD_PRELOAD"}
    subprocess.run([cli, "run", FLOCK, "--backend", "cpu", "--frames", "3", "--out", out_cli], check=True,
                   stdout=subprocess.DEVNULL, env=environment)
    with open(out, "rb") as a, open(out_cli, "rb") as b:
        check(a.read() == b.read(), f"{out} differs from `kodawari run`'s {out_cli}")
    try:
        sim.bake(os.path.join(temp, "no-such-folder", "x.glb"))
        check(False, "a bake into a missing folder raised nothing")
    except kodawari.Error as error:
        check("no-such-folder" in str(error), f"bake: {error}")
# A bake never writes over its scene file or a file the scene reads (a copy of the scene
# here, so that a failure cannot replace the checkout's).
scene_copy = os.path.join(temp, "flock-copy.json")
with open(FLOCK, "rb") as original, open(scene_copy, "wb") as copy:
    scene_bytes = original.read()
    copy.write(scene_bytes)
with kodawari.Simulation.open(scene_copy, "cpu", frames=2) as sim:
    # (A .json is no bake's name before it is the scene's; the model case is the rig's below.)
    for wrong in (scene_copy, os.path.join(temp, "flock.gltf")):
        try:
            sim.bake(wrong)
            check(False, f"a bake to {wrong} raised nothing")
        except kodawari.Error as error:
            check("name it .glb" in str(error) and "path" in str(error), f"bake to {wrong}: {error}")
    check(not os.path.exists(os.path.join(temp, "flock.gltf")), "a refused bake wrote flock.gltf")
# kodawari.rig never writes its scene over the file it rigs (nor over its motions).
model_copy = os.path.join(temp, "chibi-copy.glb")
with open(os.path.join(source, "scenes", "characters", "chibi.glb"), "rb") as original, open(model_copy, "wb") as copy:
    model_bytes = original.read()
    copy.write(model_bytes)
try:
    kodawari.rig(model_copy, model_copy, duration=1.0)
    check(False, "rig over its own model raised nothing")
except kodawari.Error as error:
    check("scene_path" in str(error) and "the model of character" in str(error), f"rig over its model: {error}")
with open(model_copy, "rb") as copy:
    check(copy.read() == model_bytes, "a refused rig changed the model")
with open(scene_copy, "rb") as copy:
    check(copy.read() == scene_bytes, "a refused bake changed the scene file")
try:
    sim.step()
    check(False, "a closed simulation stepped")
except kodawari.Error as error:
    check("closed" in str(error), f"after close: {error}")

# ---- kodawari.rig: the chibi's chains as the README's `kodawari rig` lists them.
chains = kodawari.rig(os.path.join(source, "scenes", "characters", "chibi.glb"), os.path.join(temp, "chibi.json"),
                      duration=1.0)
check(len(chains) == 7 and ("tail_0", "tail_0", 8) in chains, f"rig: {chains}")
with kodawari.Simulation.open(os.path.join(temp, "chibi.json"), "cpu") as sim:
    check((sim.chain_count, sim.joint_count, sim.frame_count) == (7, 40, 60), f"the rigged scene: {sim!r}")
try:
    kodawari.rig(missing, os.path.join(temp, "x.json"))
    check(False, "rig of a missing file raised nothing")
except kodawari.Error as error:
    check(missing in str(error), f"rig: {error}")

# ---- kodawari.bench: what `kodawari bench birds ... --json` writes, run by the command built
# with the package (the same executable ctest names), as a dict with the command's own
# keys. 1 001 birds x 3 frames on the two cpu kinds: milliseconds. The same options given
# to the command directly write a file of the same keys and settings (the rates differ:
# they are timings).
check(os.path.realpath(kodawari.command_path()) == os.path.realpath(cli),
      f"bench runs {kodawari.command_path()}, not the build's {cli}")
# Under the asan lane this Python runs with the shared ASan runtime preloaded (it loads
# the sanitized library); the sanitized command links its own runtime statically and
# refuses a second one, so the preload, which is this process's and not the command's,
# is not handed to the commands run below.
if "asan" in os.environ.get("LD_PRELOAD", ""):
    print("the ASan runtime preloaded for Python is not passed to the kodawari command")
    del os.environ["LD_PRELOAD"]
result = kodawari.bench("birds", count=1001, frames=3, backends=["cpu-reference", "cpu"], repetitions=3,
                        readback=True, threads=2)
subprocess.run([cli, "bench", "birds", "--count", "1001", "--frames", "3", "--backends", "cpu-reference,cpu",
                "--repetitions", "3", "--readback", "--threads", "2", "--json", os.path.join(temp, "bench.json")],
               check=True, capture_output=True)
with open(os.path.join(temp, "bench.json")) as file:
    direct = json.load(file)
settings = ("benchmark", "count", "frames", "readback", "threads", "repetitions")
check(isinstance(result, dict) and [result.get(k) for k in settings] == ["birds", 1001, 3, True, 2, 3] and
      [direct.get(k) for k in settings] == [result.get(k) for k in settings],
      f"bench settings {[result.get(k) for k in settings]}, the command's {[direct.get(k) for k in settings]}")
rows = result.get("results", [])
check([r.get("backend") for r in rows] == ["cpu-reference", "cpu"] and
      all(sorted(r) == sorted(d) for r, d in zip(rows, direct["results"])) and
      all(r["per_second"] > 0 and r["min"] <= r["per_second"] <= r["max"] for r in rows),
      f"bench results {rows}")
print(f"bench: {[(r['backend'], r['per_second']) for r in rows]} bird-frames/s")
ceilings = kodawari.bench("ceilings", threads=1, repetitions=1, triad_mib=12)
check(ceilings.get("benchmark") == "ceilings" and ceilings.get("threads") == 1 and
      ceilings["fp32_flops"]["median"] > 0 and ceilings["triad_bytes_per_second"]["median"] > 0,
      f"bench ceilings {ceilings}")
try:
    kodawari.bench("birds", count=0)
    check(False, "bench with count=0 raised nothing")
except kodawari.Error as error:
    check("--count" in str(error) and error.status == "KODAWARI_INVALID_ARGUMENT", f"bench count=0: {error}")
try:
    kodawari.bench("birds", command=sys.executable)
    check(False, "bench with another program as the command raised nothing")
except kodawari.Error as error:
    check("this package is" in str(error), f"bench with python as the command: {error}")

try:
    kodawari.bench("fish")
    check(False, "bench('fish') raised nothing")
except ValueError as error:
    check("kind: 'fish'" in str(error) and "flock" in str(error), f"bench('fish'): {error}")
# BENCH_KINDS is the command's list of benchmarks.
help_text = subprocess.run([cli, "bench", "--help"], capture_output=True, text=True).stdout
listed = help_text.split("Subcommands:", 1)[-1].strip().split("\n\n", 1)[0]
check(tuple(line.split()[0] for line in listed.splitlines() if line.strip()) == kodawari.BENCH_KINDS,
      f"BENCH_KINDS {kodawari.BENCH_KINDS} against `kodawari bench --help`: {listed!r}")
# Whole-number arguments: a ValueError naming the argument and the value given, for a
# negative count of threads, None and text as for a number out of range.
for call, needle in ((lambda: kodawari.Simulation.open(FLOCK, "cpu", threads=-1), "threads: -1"),
                     (lambda: kodawari.Simulation.open(FLOCK, "cpu", frames="ten"), "frames: 'ten'"),
                     (lambda: kodawari.Simulation.open(FLOCK, "cpu", threads=float("inf")), "threads: inf")):
    try:
        call()
        check(False, f"{needle}: raised nothing")
    except ValueError as error:
        check(needle in str(error), f"{needle}: {error}")
with kodawari.Simulation.open(FLOCK, "cpu", frames=2) as sim:
    try:
        sim.step(None)
        check(False, "step(None) raised nothing")
    except ValueError as error:
        check("frames: None" in str(error), f"step(None): {error}")

# ---- help() is readable: the docstrings are there.
text = pydoc.render_doc(kodawari.Simulation, renderer=pydoc.plaintext)
for needle in ("bird_poses", "a copy", "chain_joints", "bake", "Simulation.open", "Error naming the file"):
    check(needle in text, f"help(kodawari.Simulation) lacks {needle!r}")
text = pydoc.render_doc(kodawari.bench, renderer=pydoc.plaintext)
check("--json" in text and "per_second" in text, "help(kodawari.bench) lacks its documentation")

print(f"test_kodawari: {len(failures)} failures")
sys.exit(1 if failures else 0)
