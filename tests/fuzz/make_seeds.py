#!/usr/bin/env python3
"""Writes the fuzz targets' seed corpora (corpus/<target>/) from the project's own files:
the shipped scenes, the test assets, and the kinds of bad input the hand-written tests
cover. Run from anywhere; the files are committed, so this runs only when seeds change.
Inputs that libFuzzer finds worth keeping are added with `scripts/fuzz --merge`."""
import os
import random
import shutil
import struct
from pathlib import Path

here = Path(__file__).resolve().parent
root = here.parent.parent


def reset(name):
    """The target's corpus folder, its files kept: beside the seeds written here it holds
    hand-written ones (bunny-limits.json, flocking-obstacles.json, ...) and inputs that
    `scripts/fuzz --merge` kept, which a fresh folder would lose (it did lose five)."""
    d = here / "corpus" / name
    d.mkdir(parents=True, exist_ok=True)
    return d


def number(v, rng):
    """The bytes ByteReader::number(rng) reads back as v (fuzz_support.hpp)."""
    u = round((v / rng + 1.0) / 2.0 * 4294967295.0)
    return bytes([1]) + struct.pack(">I", max(0, min(u, 4294967295)))


# The scene loader: every shipped scene, and the bad inputs test_scene.cpp checks by kind.
scene = reset("scene")
# Not copied: scenes whose keys smaller seeds beside them already reach, whose size only
# slows each mutation (the limited bunny took fuzz_scene's 40 000 executions from 37 s to
# 159 s for 0.6% more coverage: bunny-limits.json is one antenna instead).
covered_elsewhere = {
    "limits.json": "bunny-limits.json",
    "windy.json": "bunny-wind.json",
    "crowd-10k.json": "crowd.json",
}
for f in sorted((root / "scenes").glob("*.json")) + sorted((root / "scenes/bench").glob("*.json")):
    if f.name not in covered_elsewhere:
        shutil.copy(f, scene / f.name)
bad_scenes = {
    "empty.json": "",
    "not-object.json": "[1, 2, 3]",
    "truncated.json": '{"version": 2, "fps": 30, "characters": [{"name": "a"',
    "bad-version.json": '{"version": 9}',
    "nan.json": '{"version": 1, "fps": 1e999, "duration": 1, "flocks": []}',
    "v1-minimal.json": '{"version": 1, "fps": 30, "duration": 0.1, "flocks": [{"wing_type": "gull", "count": 3,'
                       ' "route": {"points": [[0,0,0],[10,0,0],[20,5,0],[30,5,0]]}}]}',
}
for name, text in bad_scenes.items():
    (scene / name).write_text(text)
# VRM's collider model (issue 18): named colliders of every kind, chains' own lists, a center.
(scene / "collider-kinds.json").write_text(
    '{"format": "kodawari-scene", "version": 2, "fps": 30, "duration": 0.2, "characters": [{"name": "p",'
    ' "skeleton": [{"name": "body", "position": [0, 0.9, 0]}, {"name": "head", "parent": "body", "position": [0, 0.6, 0]}],'
    ' "colliders": [{"name": "s", "type": "sphere", "joint": "head", "radius": 0.1},'
    ' {"name": "i", "type": "capsule", "joint": "head", "a": [-0.1, 0, 0], "b": [0.1, 0, 0], "radius": 0.3, "inside": true},'
    ' {"name": "f", "type": "plane", "joint": "body", "point": [0, 0.2, 0], "normal": [0, 1, 0.3]}],'
    ' "chains": [{"name": "c", "joint": "head", "colliders": ["s", "i", "f"], "center": "body",'
    ' "shape": {"arc": {"joints": 5, "length": 0.3, "direction": [0, -1, 0]}}}]}]}')

# The glTF importer: the test assets and the sample character.
gltf = reset("gltf")
for f in sorted((root / "tests/assets").rglob("*.gltf")) + [root / "scenes/characters/chibi.glb"]:
    shutil.copy(f, gltf / f.name)
(gltf / "bad-magic.glb").write_bytes(b"glTF" + struct.pack("<II", 7, 20) + b"\0" * 8)
(gltf / "empty.gltf").write_text('{"asset": {"version": "2.0"}}')

# The stroke reader: a good stroke, and the errors the sketch tests check.
stroke = reset("stroke")
strokes = {
    "good.json": '{"points": [[640, 300], [660, 260], [700, 240], [740, 250]]}',
    "two.json": '{"points": [[1, 2], [3.5, -4e1]]}',
    "short.json": '{"points": [[640, 300]]}',
    "not-number.json": '{"points": [[640, 300], [1, "x"]]}',
    "extra-key.json": '{"points": [[0, 0], [1, 1]], "pen": 1}',
    "zero-length.json": '{"points": [[5, 5], [5, 5], [5, 5]]}',
}
for name, text in strokes.items():
    (stroke / name).write_text(text)

# The scene editor: a 24-byte header (chain 0, a direction, influence 4, a bend of 0.05;
# fuzz_scene_edit.cpp reads it) before every scene with characters.
edit = reset("scene_edit")
for k, (d, infl, bend) in enumerate([((1.0, 0.0, 0.0), 4.0, 0.05), ((0.0, 0.0, 1.0), 2.0, -0.03)]):
    header = (bytes([0]) + b"".join(number(c, 1.5) for c in d) + number(infl, 20.0) + number(bend, 0.1))[:24]
    for f in ["ahoge.json", "bangs.json", "bunny.json", "crowd.json"]:
        (edit / f"{k}-{f}").write_bytes(header + (root / "scenes" / f).read_bytes())

# The C API: random descriptions (fuzz_capi.cpp decodes any bytes), a fixed seed.
capi = reset("capi")
r = random.Random(16)
for k in range(12):
    (capi / f"random-{k:02}.bin").write_bytes(bytes(r.randrange(256) for _ in range(64 + 48 * k)))
# The scene simulation's inputs (first byte 2 mod 3: fuzz_capi.cpp's third kind): agents,
# wind and steps in random order, so the seed corpus reaches kodawari_simulation_*.
for k in range(6):
    (capi / f"simulation-{k:02}.bin").write_bytes(bytes([2]) + bytes(r.randrange(256) for _ in range(96 + 64 * k)))
