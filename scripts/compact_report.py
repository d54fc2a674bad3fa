#!/usr/bin/env python3
"""Re-imports a compact .glb and the uncompacted .glb of the same bake and reports what
compaction did (docs/compact.md): file sizes, their ratio and the bytes per animated node
and frame, keys kept per channel kind (and per node-name group with --groups), and the
largest error of every kind, measured by evaluating the compact file's LINEAR samplers
(lerp; slerp along the short arc on the rotations decoded from normalized shorts as
max(c / 32767, -1) or bytes as max(c / 127, -1), glTF 2.0 §3.11 and Appendix C) at every
key time of the uncompacted file.

Channels are matched by node name and path, so the compact file may come from another
tool that renumbers nodes (gltfpack); a node the compact file does not animate holds its
own translation, rotation and scale there (gltfpack drops constant channels). A file with
EXT_meshopt_compression (ours with --meshopt, gltfpack's -c and -cc) is decoded first by
gltf-transform (scripts/gltf_plain.mjs; Node.js and scripts/setup's .tools/npm); the rest
is pure Python (no numpy), so plain files are read anywhere.

    python3 scripts/compact_report.py FULL.glb COMPACT.glb [--groups]
"""
import json
import math
import os
import struct
import subprocess
import sys
import tempfile
from bisect import bisect_right
from collections import defaultdict

COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}
FORMATS = {5126: ("f", 4), 5122: ("h", 2), 5123: ("H", 2), 5120: ("b", 1), 5121: ("B", 1)}


def load(path):
    with open(path, "rb") as f:
        data = f.read()
    magic, _, _ = struct.unpack_from("<III", data, 0)
    if magic != 0x46546C67:
        sys.exit(f"{path}: not a .glb")
    json_length, _ = struct.unpack_from("<II", data, 12)
    gltf = json.loads(data[20:20 + json_length])
    at = 20 + json_length
    bin_length, _ = struct.unpack_from("<II", data, at)
    return gltf, data[at + 8:at + 8 + bin_length]


def accessor(gltf, binary, index):
    a = gltf["accessors"][index]
    view = gltf["bufferViews"][a["bufferView"]]
    code, size = FORMATS[a["componentType"]]
    n = COMPONENTS[a["type"]]
    start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
    values = struct.unpack_from(f"<{a['count'] * n}{code}", binary, start)
    if a.get("normalized") and code == "h":
        values = [max(v / 32767.0, -1.0) for v in values]
    elif a.get("normalized") and code == "b":
        values = [max(v / 127.0, -1.0) for v in values]
    return [tuple(values[i * n:(i + 1) * n]) for i in range(a["count"])]


def tracks(gltf, binary):
    """Every animated (node name, path): (key times, values)."""
    out = {}
    for animation in gltf.get("animations", []):
        for channel in animation["channels"]:
            sampler = animation["samplers"][channel["sampler"]]
            node = gltf["nodes"][channel["target"]["node"]]
            key = (node.get("name", str(channel["target"]["node"])), channel["target"]["path"])
            out[key] = (accessor(gltf, binary, sampler["input"]), accessor(gltf, binary, sampler["output"]))
    return out


REST = {"translation": (0.0, 0.0, 0.0), "rotation": (0.0, 0.0, 0.0, 1.0), "scale": (1.0, 1.0, 1.0)}


def rest_values(gltf):
    """(node name, path): the node's own value, for the channels a file leaves out."""
    out = {}
    for index, node in enumerate(gltf.get("nodes", [])):
        for path, default in REST.items():
            out[(node.get("name", str(index)), path)] = tuple(node.get(path, default))
    return out


def uses_meshopt(gltf):
    return any(e.endswith("meshopt_compression") for e in gltf.get("extensionsUsed", []))


def load_plain(path):
    """load(), decoding meshopt compression through gltf-transform when the file uses it."""
    gltf, binary = load(path)
    if not uses_meshopt(gltf):
        return gltf, binary
    helper = os.path.join(os.path.dirname(os.path.abspath(__file__)), "gltf_plain.mjs")
    with tempfile.TemporaryDirectory() as work:
        plain = os.path.join(work, "plain.glb")
        result = subprocess.run(["node", helper, path, plain], capture_output=True, text=True)
        if result.returncode != 0:
            sys.exit(f"{path}: uses meshopt compression, and decoding it failed: {result.stderr.strip()}")
        return load(plain)


def normalize(q):
    n = math.sqrt(sum(c * c for c in q))
    return tuple(c / n for c in q)


def slerp(a, b, t):
    d = sum(x * y for x, y in zip(a, b))
    s = -1.0 if d < 0 else 1.0
    angle = math.acos(min(1.0, abs(d)))
    if angle < 1e-9:
        wa, wb = 1 - t, t
    else:
        wa, wb = math.sin(angle * (1 - t)) / math.sin(angle), math.sin(angle * t) / math.sin(angle)
    return tuple(wa * x + s * wb * y for x, y in zip(a, b))


def evaluate(times, values, time, rotation):
    k = bisect_right(times, time)
    if k == 0:
        v = values[0]
    elif k == len(times):
        v = values[-1]
    else:
        t0, t1 = times[k - 1], times[k]
        t = (time - t0) / (t1 - t0)
        a, b = values[k - 1], values[k]
        v = slerp(normalize(a), normalize(b), t) if rotation else tuple(x + (y - x) * t for x, y in zip(a, b))
    return normalize(v) if rotation else v


def error(path, value, original):
    if path == "rotation":
        d = min(1.0, abs(sum(x * y for x, y in zip(value, normalize(original)))))
        return 2.0 * math.acos(d)
    if path == "translation":
        return math.sqrt(sum((x - y) ** 2 for x, y in zip(value, original)))
    return max((abs(x - y) / abs(y) if x != y else 0.0) for x, y in zip(value, original))


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    groups = "--groups" in sys.argv
    if len(args) != 2:
        sys.exit(__doc__)
    full_path, compact_path = args
    full_gltf, full_bin = load_plain(full_path)
    compact_gltf, compact_bin = load_plain(compact_path)
    full = tracks(full_gltf, full_bin)
    compact = tracks(compact_gltf, compact_bin)
    rest = rest_values(compact_gltf)
    extra = set(compact) - set(full)
    if extra:
        sys.exit(f"{compact_path} animates {len(extra)} channels the uncompacted file does not, e.g. {sorted(extra)[0]}")
    worst = defaultdict(float)
    keys = defaultdict(int)
    kept = defaultdict(int)
    frames = 0
    for (name, path), (times, values) in full.items():
        frames = max(frames, len(times))
        if (name, path) in compact:
            ctimes, cvalues = compact[(name, path)]
        elif (name, path) in rest:
            ctimes, cvalues = [(times[0][0],)], [rest[(name, path)]]
        else:
            sys.exit(f"{compact_path} has no node named {name!r}")
        group = path + (" " + name.rstrip("0123456789").rstrip("_/") if groups else "")
        keys[group] += len(times)
        kept[group] += len(ctimes) if (name, path) in compact else 0
        flat = [t[0] for t in ctimes]
        for (time,), original in zip(times, values):
            value = evaluate(flat, cvalues, time, path == "rotation")
            worst[path] = max(worst[path], error(path, value, original))
    a, b = os.path.getsize(full_path), os.path.getsize(compact_path)
    nodes = len({name for name, _ in full})
    per = nodes * frames
    print(f"{full_path}: {a} bytes; {compact_path}: {b} bytes; ratio {a / b:.2f}x")
    print(f"  {nodes} animated nodes x {frames} frames: {a / per:.2f} -> {b / per:.2f} bytes per animated node and frame")
    for group in sorted(keys):
        print(f"  {group}: {kept[group]} of {keys[group]} keys kept ({100.0 * kept[group] / keys[group]:.1f}%)")
    units = {"translation": ("mm", 1e3), "rotation": ("mrad", 1e3), "scale": ("%", 1e2)}
    for path in sorted(worst):
        unit, factor = units[path]
        print(f"  largest {path} error: {worst[path] * factor:.6g} {unit}")


if __name__ == "__main__":
    main()
