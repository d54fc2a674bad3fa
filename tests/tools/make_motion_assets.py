#!/usr/bin/env python3
"""Writes the small files tests/motion_cli_test.sh retargets (issue 18), into OUT_DIR:

    python3 tests/tools/make_motion_assets.py OUT_DIR

- avatar.vrm       a VRM 1.0 humanoid (GLB, VRMC_vrm), 1.3 m, facing +Z, every required
                   bone plus chest, neck and left toes, and a 4-joint hair strand under the
                   head ("hair_0".."hair_3", found by `kodawari rig`'s name patterns)
- avatar-vrm0.vrm  the same as VRM 0.x (extensions.VRM), facing -Z
- handless.vrm     avatar.vrm without a leftHand bone in its humanoid
- walk.vrma        VRM Animation 1.0, 1.6 m source in T-pose: 1 s of walking (hips bob and
                   sway forward, legs and arms swing), keys at 30 per second
- idle.vrma        2 s of breathing (spine) and a head turn
- wave.vrma        the left hand waves (a required bone handless.vrm lacks)
- toes.vrma        names only leftToes (no bone in common with a hips-only map)
- bones.vrma       a VRM Animation without humanoid bones
- run.gltf         the walk on a skeleton named like Mixamo's, no VRM extension, clip "Run"
- mixamo-map.json  its humanoid bone -> node name map
- bad-map.json     a map naming a node run.gltf does not have
- hips-map.json    a map naming only the hips

Standard library only; the output is the same bytes on every run.
"""
import base64
import json
import math
import struct
import sys
from pathlib import Path

# (bone, parent index, T-pose position of a 1.6 m figure facing +Z, +X its left)
BONES = [
    ("root", -1, (0, 0, 0)),
    ("hips", 0, (0, 1.0, 0)),
    ("spine", 1, (0, 1.2, 0)),
    ("chest", 2, (0, 1.35, 0)),
    ("neck", 3, (0, 1.5, 0)),
    ("head", 4, (0, 1.6, 0)),
    ("leftUpperArm", 3, (0.2, 1.45, 0)),
    ("leftLowerArm", 6, (0.45, 1.45, 0)),
    ("leftHand", 7, (0.7, 1.45, 0)),
    ("rightUpperArm", 3, (-0.2, 1.45, 0)),
    ("rightLowerArm", 9, (-0.45, 1.45, 0)),
    ("rightHand", 10, (-0.7, 1.45, 0)),
    ("leftUpperLeg", 1, (0.1, 0.95, 0)),
    ("leftLowerLeg", 12, (0.1, 0.5, 0)),
    ("leftFoot", 13, (0.1, 0.08, 0)),
    ("rightUpperLeg", 1, (-0.1, 0.95, 0)),
    ("rightLowerLeg", 15, (-0.1, 0.5, 0)),
    ("rightFoot", 16, (-0.1, 0.08, 0)),
    ("leftToes", 14, (0.1, 0.02, 0.1)),
]
HAIR = [(0, 1.78, -0.05), (0, 1.7, -0.14), (0, 1.6, -0.18), (0, 1.5, -0.2)]


def quat(axis, degrees):
    x, y, z = axis
    n = math.sqrt(x * x + y * y + z * z)
    h = math.radians(degrees) / 2
    s = math.sin(h) / n
    return [x * s, y * s, z * s, math.cos(h)]


class Gltf:
    def __init__(self):
        self.doc = {"asset": {"version": "2.0", "generator": "make_motion_assets.py"},
                    "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [],
                    "bufferViews": [], "accessors": []}
        self.bin = bytearray()

    def accessor(self, values, kind):
        offset = len(self.bin)
        self.bin += struct.pack("<%df" % len(values), *values)
        comps = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[kind]
        self.doc["bufferViews"].append({"buffer": 0, "byteOffset": offset, "byteLength": 4 * len(values)})
        acc = {"bufferView": len(self.doc["bufferViews"]) - 1, "componentType": 5126,
               "count": len(values) // comps, "type": kind}
        if kind == "SCALAR":
            acc["min"] = [min(values)]
            acc["max"] = [max(values)]
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def skeleton(self, scale=1.0, flip=False, names=None, hair=False):
        """Nodes with identity rotations; returns the node index of each bone name."""
        sign = -1.0 if flip else 1.0
        pos = [(sign * x * scale, y * scale, sign * z * scale) for _, _, (x, y, z) in BONES]
        index = {}
        for i, (bone, parent, _) in enumerate(BONES):
            p = pos[parent] if parent >= 0 else (0, 0, 0)
            node = {"name": names(bone) if names else bone,
                    "translation": [round(a - b, 6) for a, b in zip(pos[i], p)]}
            self.doc["nodes"].append(node)
            index[bone] = i
            if parent >= 0:
                self.doc["nodes"][parent].setdefault("children", []).append(i)
        if hair:
            parent, p = index["head"], pos[index["head"]]
            for k, (x, y, z) in enumerate(HAIR):
                q = (sign * x * scale, y * scale, sign * z * scale)
                self.doc["nodes"].append({"name": "hair_%d" % k, "translation": [round(a - b, 6) for a, b in zip(q, p)]})
                self.doc["nodes"][parent].setdefault("children", []).append(len(self.doc["nodes"]) - 1)
                parent, p = len(self.doc["nodes"]) - 1, q
        return index

    def clip(self, name, tracks):
        """tracks: (node, path, times, values as lists)."""
        samplers, channels = [], []
        for node, path, times, values in tracks:
            flat = [v for value in values for v in value]
            samplers.append({"input": self.accessor(times, "SCALAR"),
                             "output": self.accessor(flat, "VEC4" if path == "rotation" else "VEC3"),
                             "interpolation": "LINEAR"})
            channels.append({"sampler": len(samplers) - 1, "target": {"node": node, "path": path}})
        self.doc.setdefault("animations", []).append({"name": name, "samplers": samplers, "channels": channels})

    def extension(self, name, value):
        self.doc.setdefault("extensions", {})[name] = value
        self.doc.setdefault("extensionsUsed", []).append(name)

    def write_glb(self, path):
        doc = dict(self.doc)
        if self.bin:
            doc["buffers"] = [{"byteLength": len(self.bin)}]
        else:
            for key in ("bufferViews", "accessors"):
                doc.pop(key)
        text = json.dumps(doc, separators=(",", ":")).encode()
        text += b" " * (-len(text) % 4)
        data = bytes(self.bin) + b"\0" * (-len(self.bin) % 4)
        chunks = struct.pack("<II", len(text), 0x4E4F534A) + text
        if data:
            chunks += struct.pack("<II", len(data), 0x004E4942) + data
        Path(path).write_bytes(struct.pack("<III", 0x46546C67, 2, 12 + len(chunks)) + chunks)

    def write_gltf(self, path):
        doc = dict(self.doc)
        doc["buffers"] = [{"byteLength": len(self.bin),
                           "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(self.bin)).decode()}]
        Path(path).write_text(json.dumps(doc))


def human_bones(index, leave_out=()):
    return {b: {"node": i} for b, i in index.items() if b != "root" and b not in leave_out}


def avatar(out, name, vrm0=False, leave_out=()):
    g = Gltf()
    index = g.skeleton(scale=1.3 / 1.6, flip=vrm0, hair=True)
    if vrm0:
        g.extension("VRM", {"specVersion": "0.0", "humanoid": {"humanBones": [
            {"bone": b, "node": n["node"]} for b, n in human_bones(index, leave_out).items()]}})
    else:
        g.extension("VRMC_vrm", {"specVersion": "1.0", "meta": {"name": name},
                                 "humanoid": {"humanBones": human_bones(index, leave_out)}})
    g.write_glb(out / (name + ".vrm"))


def walk_tracks(index, hips_rest):
    times = [k / 30 for k in range(31)]
    tracks = []
    hips = []
    for t in times:
        phase = 2 * math.pi * t
        hips.append([hips_rest[0] + 0.02 * math.sin(phase), hips_rest[1] + 0.03 * math.cos(2 * phase), hips_rest[2] + 0.6 * t])
    tracks.append((index["hips"], "translation", times, hips))
    swings = {"leftUpperLeg": ((1, 0, 0), 30), "rightUpperLeg": ((1, 0, 0), -30),
              "leftUpperArm": ((1, 0, 0), -25), "rightUpperArm": ((1, 0, 0), 25)}
    for bone, (axis, amplitude) in swings.items():
        tracks.append((index[bone], "rotation", times, [quat(axis, amplitude * math.sin(2 * math.pi * t)) for t in times]))
    # The arms hang down from the T-pose, turned about the forward axis.
    for bone, sign in (("leftUpperArm", -1), ("rightUpperArm", 1)):
        rot = tracks[[i for i, tr in enumerate(tracks) if tr[0] == index[bone]][0]]
        down = quat((0, 0, 1), sign * 70)
        rot[3][:] = [mul(down, q) for q in rot[3]]
    knees = [quat((1, 0, 0), 30 * max(0.0, math.sin(2 * math.pi * t))) for t in times]
    tracks.append((index["leftLowerLeg"], "rotation", times, knees))
    return tracks


def mul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return [aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz]


def vrma(out, name, tracks_of, bones=True, only=None):
    g = Gltf()
    index = g.skeleton()
    g.clip(name, tracks_of(index))
    ext = {"specVersion": "1.0"}
    if bones:
        mapped = {b: n for b, n in human_bones(index).items() if only is None or b in only}
        ext["humanoid"] = {"humanBones": mapped}
    g.extension("VRMC_vrm_animation", ext)
    g.write_glb(out / (name + ".vrma"))


def main():
    out = Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    avatar(out, "avatar")
    avatar(out, "avatar-vrm0", vrm0=True)
    avatar(out, "handless", leave_out=("leftHand",))
    hips_rest = [0, 1.0, 0]
    vrma(out, "walk", lambda index: walk_tracks(index, hips_rest))
    times = [0, 0.5, 1, 1.5, 2]
    vrma(out, "idle", lambda index: [
        (index["spine"], "rotation", times, [quat((1, 0, 0), 3 * math.sin(math.pi * t)) for t in times]),
        (index["head"], "rotation", times, [quat((0, 1, 0), 20 * math.sin(math.pi * t)) for t in times])])
    vrma(out, "wave", lambda index: [
        (index["leftHand"], "rotation", times, [quat((0, 0, 1), 30 * math.sin(2 * math.pi * t)) for t in times])])
    vrma(out, "toes", lambda index: [
        (index["leftToes"], "rotation", times, [quat((1, 0, 0), 20 * math.sin(math.pi * t)) for t in times])], only=("leftToes",))
    vrma(out, "bones", lambda index: walk_tracks(index, hips_rest), bones=False)

    g = Gltf()
    mixamo = lambda bone: "mixamorig:" + bone[0].upper() + bone[1:] if bone != "root" else "Armature"
    index = g.skeleton(names=mixamo)
    g.clip("Run", walk_tracks(index, hips_rest))
    g.write_gltf(out / "run.gltf")
    (out / "mixamo-map.json").write_text(json.dumps({b: mixamo(b) for b in index if b != "root"}, indent=1))
    (out / "bad-map.json").write_text(json.dumps({"hips": "mixamorig:Hips", "leftHand": "mixamorig:LeftPalm"}))
    (out / "hips-map.json").write_text(json.dumps({"hips": "hips"}))


if __name__ == "__main__":
    main()
