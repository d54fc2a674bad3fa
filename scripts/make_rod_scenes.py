#!/usr/bin/env python3
"""Writes scenes/bunny.json, bangs.json, crowd.json, ponytail.json and nod.json (scenes/README.md
says what they show; docs/scene-format.md defines the keys). Their shapes are computed
here (strands that hug the head sphere, sampled at equal arc length), so edit this
script and rerun it rather than the JSON:

    python3 scripts/make_rod_scenes.py [output directory, default: scenes]

scenes/ahoge.json is written by hand. The output is deterministic (numbers rounded to
3 or 4 decimals)."""
import json
import math
import os
import re
import sys

# --- small vector helpers -----------------------------------------------------------


def r3(v, nd=3):
    if isinstance(v, (list, tuple)):
        return [r3(x, nd) for x in v]
    x = round(v, nd)
    return 0 if x == 0 else (int(x) if x == int(x) else x)


def norm(v):
    length = math.sqrt(sum(x * x for x in v))
    return [x / length for x in v]


def add(a, b):
    return [x + y for x, y in zip(a, b)]


def scale(a, s):
    return [x * s for x in a]


# --- the shared character -----------------------------------------------------------

SKELETON = [
    {"name": "body", "position": [0, 0.9, 0]},
    {"name": "neck", "parent": "body", "position": [0, 0.45, 0]},
    {"name": "head", "parent": "neck", "position": [0, 0.12, 0]},
]
HEAD_C = [0, 0.1, 0]  # head sphere centre in the head joint's frame
HEAD_R = 0.11
COLLIDERS = [
    {"type": "sphere", "joint": "head", "center": HEAD_C, "radius": HEAD_R},
    {"type": "capsule", "joint": "body", "a": [0, 0.05, 0], "b": [0, 0.35, 0], "radius": 0.16},
]


def sphere_normal(az_deg, el_deg):
    """Unit vector at azimuth az (0 = the face, +90 = the character's left) and elevation el."""
    az, el = math.radians(az_deg), math.radians(el_deg)
    return [math.cos(el) * math.sin(az), math.sin(el), math.cos(el) * math.cos(az)]


def arc(joints, length, direction, bend_axis, curl_deg):
    return {"arc": {"joints": joints, "length": length, "direction": r3(direction), "bend_axis": r3(bend_axis),
                    "curl_deg": r3(curl_deg, 1)}}


def on_sphere(radius, az, el):
    return add(HEAD_C, scale(sphere_normal(az, el), radius))


def sample(curve, n, length):
    """n points at equal arc length along a dense polyline, up to `length`."""
    cum = [0.0]
    for a, b in zip(curve, curve[1:]):
        cum.append(cum[-1] + math.dist(a, b))
    assert cum[-1] >= length, (cum[-1], length)
    out = []
    for i in range(n):
        s = length * i / (n - 1)
        k = min(max(j for j in range(len(cum)) if cum[j] <= s), len(curve) - 2)
        t = (s - cum[k]) / (cum[k + 1] - cum[k])
        out.append([curve[k][m] + t * (curve[k + 1][m] - curve[k][m]) for m in range(3)])
    return out


def sphere_path(radius, p0, p1, p2, steps=2000):
    """A quadratic Bezier in (azimuth, elevation) degrees, on the sphere of `radius`."""
    pts = []
    for i in range(steps + 1):
        t = i / steps
        az = (1 - t) ** 2 * p0[0] + 2 * t * (1 - t) * p1[0] + t * t * p2[0]
        el = (1 - t) ** 2 * p0[1] + 2 * t * (1 - t) * p1[1] + t * t * p2[1]
        pts.append(on_sphere(radius, az, el))
    return pts


def bang(name, mirror, radius, az, joints, length, temple):
    """A strand rooted on the hairline (elevation 40) at azimuth az. Base: straight down the
    forehead, over the eye. Front example: sideways over the forehead to the temple, then
    down beside the eye (a curtain that hangs with gravity)."""
    root = on_sphere(radius, az, 40)
    base = sample(sphere_path(radius, (az, 40), (az, 0), (az, -60)), joints, length)
    front = sample(sphere_path(radius, (az, 40), (temple, 36), (temple, -60)), joints, length)

    def rel(pts):
        out = [r3([p[m] - root[m] for m in range(3)], 4) for p in pts]
        out[0] = [0, 0, 0]
        return out

    return {
        "name": name, "mirror": mirror, "joint": "head", "offset": {"position": r3(root, 4)},
        "thickness": 0.004, "mass": 0.001,
        "shape": {"positions": rel(base)},
        "views": [{"name": "front", "direction": [0, 0, 1], "influence": 3, "shape": {"positions": rel(front)}}],
    }


def ears(joints, length, thickness):
    """Bunny ears on the crown. Base: upright; front: a V; seen from this ear's side: swept
    back; from the other side: tilted forward (so from either side both ears show)."""
    root = add(HEAD_C, scale(norm([0.42, 1, 0]), 0.112))

    def ear(d, a, c):
        return arc(joints, length, norm(d), norm(a), c)

    return {
        "name": "ear_l", "mirror": "ear_r", "joint": "head", "offset": {"position": r3(root)},
        "thickness": thickness, "mass": 0.002,
        "shape": ear([0.12, 1, 0], [-1, 0, 0], 15),
        "views": [
            {"name": "front", "direction": [0, 0, 1], "influence": 4, "shape": ear([0.6, 1, 0], [0, 0, -1], 35)},
            {"name": "left", "direction": [1, 0, 0], "influence": 4, "shape": ear([0.1, 1, -0.45], [-1, 0, 0], 40)},
            {"name": "right", "direction": [-1, 0, 0], "influence": 4, "shape": ear([0.1, 1, 0.4], [1, 0, 0], 20)},
        ],
    }


def ahoge(joints, length):
    """A 150-degree curl that opens to the camera's right from every side: seen from
    direction d it bends about -d (scenes/README.md)."""
    def curl(axis):
        return arc(joints, length, [0, 1, 0], axis, 150)

    return {
        "name": "ahoge", "joint": "head", "offset": {"position": [0, 0.21, 0]},
        "thickness": 0.004, "mass": 0.001,
        "shape": curl([0, 0, -1]),
        "views": [
            {"name": "front", "direction": [0, 0, 1], "influence": 4, "shape": curl([0, 0, -1])},
            {"name": "back", "direction": [0, 0, -1], "influence": 4, "shape": curl([0, 0, 1])},
            {"name": "left", "direction": [1, 0, 0], "influence": 4, "shape": curl([-1, 0, 0])},
            {"name": "right", "direction": [-1, 0, 0], "influence": 4, "shape": curl([1, 0, 0])},
            {"name": "top", "direction": [0, 1, 0], "influence": 8, "shape": curl([0, 0, -1])},
        ],
    }


def character(name, motions, physics, chains):
    return {"name": name, "skeleton": SKELETON, "reference_joint": "head", "motions": motions,
            "colliders": COLLIDERS, "physics": physics, "chains": chains}


def scene(name, fps, duration, camera, characters, crowds=None):
    doc = {"format": "kodawari-scene", "version": 2, "name": name, "fps": fps, "duration": duration,
           "camera": camera, "characters": characters}
    if crowds:
        doc["crowds"] = crowds
    return doc


def bunny():
    return scene("bunny", 60, 12, {"fov_deg": 35, "orbit": {"target": [0, 1.65, 0], "radius": 1.6, "height": 0.15, "period": 12}}, [
        character("bunny", [
            {"type": "sway", "joint": "body", "axis": [0, 0, 1], "amplitude_deg": 3, "frequency": 0.4},
            {"type": "head_turn", "amplitude_deg": 30, "frequency": 0.125, "sharpness": 2, "start": 1, "fade": 1},
        ], {"stiffness": 0.6, "damping": 2.5, "iterations": 4}, [ears(11, 0.26, 0.012)])])


def bangs():
    # The roots and strands ride 1 cm outside the head sphere.
    chains = [bang(f"bang_l{k + 1}", f"bang_r{k + 1}", 0.12, az, 10, 0.13, 52 + 6 * k) for k, az in enumerate([7, 21, 35])]
    return scene("bangs", 60, 12, {"fov_deg": 30, "orbit": {"target": [0, 1.57, 0], "radius": 1.0, "height": 0.05, "period": 12}}, [
        character("girl", [
            {"type": "sway", "joint": "body", "axis": [0, 0, 1], "amplitude_deg": 2, "frequency": 0.3},
            {"type": "sway", "joint": "neck", "axis": [1, 0, 0], "amplitude_deg": 3, "frequency": 0.2, "phase_deg": 90},
        ], {"stiffness": 0.6, "damping": 3, "iterations": 4}, chains)])


def crowd():
    chains = [ears(10, 0.2, 0.01), ahoge(10, 0.12)]
    # Bangs 1.6 cm off the head collider: the run-and-stop presses them against it, and
    # collisions are projected after the distance constraints (scenes/README.md).
    chains += [bang(f"bang_l{k + 1}", f"bang_r{k + 1}", 0.13, az, 8, 0.12, 52 + 8 * k) for k, az in enumerate([9, 27])]
    # A tail on the body's back: hangs down; seen from either side it hooks up.
    chains.append({
        "name": "tail", "joint": "body", "offset": {"position": [0, 0.05, -0.17]},
        "thickness": 0.02, "mass": 0.004,
        "shape": arc(12, 0.35, [0, -0.5, -1], [1, 0, 0], 40),
        "views": [
            {"name": "left", "direction": [1, 0, 0], "influence": 3, "shape": arc(12, 0.35, [0, -0.3, -1], [-1, 0, 0], 150)},
            {"name": "right", "direction": [-1, 0, 0], "influence": 3, "shape": arc(12, 0.35, [0, -0.3, -1], [-1, 0, 0], 150)},
        ]})
    return scene("crowd", 30, 5, {"fov_deg": 45, "orbit": {"target": [0, 1, 0], "radius": 38, "height": 16, "period": 20}}, [
        character("critter", [
            {"type": "sway", "joint": "body", "axis": [0, 0, 1], "amplitude_deg": 3, "frequency": 0.5},
            {"type": "head_turn", "amplitude_deg": 30, "frequency": 0.25, "sharpness": 2},
            {"type": "walk", "speed": 0.8, "start": 0, "end": 2, "ramp_in": 0.3, "ramp_out": 0.3, "bob": 0.03, "step_frequency": 2.2},
            {"type": "stop", "speed": 2.2, "turn_rate_deg": 45, "start": 2.3, "stop_time": 3.6, "ramp_in": 0.3, "bob": 0.04,
             "step_frequency": 3},
        ], {"stiffness": 0.6, "damping": 2.5, "iterations": 4}, chains)], [
        {"name": "field", "character": "critter", "count": 1024, "layout": "grid", "columns": 32, "spacing": 1.6,
         "yaw_jitter_deg": 20, "position_jitter": 0.2, "time_offset": 1.5, "seed": 7}])


def envelope(t, start, end, ramp_in, ramp_out):
    """A locomotion's trapezoid envelope e(t) (rods::locomotion_envelope)."""
    if t <= start or t >= end:
        return 0.0
    e = 1.0
    if ramp_in > 0:
        e = min(e, (t - start) / ramp_in)
    if ramp_out > 0:
        e = min(e, (end - t) / ramp_out)
    return e


def travelled(t, walks, step=1e-3):
    """How far straight locomotions have taken the character by time t (m)."""
    n = int(round(t / step))
    return sum(w["speed"] * step * envelope((i + 0.5) * step, w["start"], w["end"], w["ramp_in"], w["ramp_out"])
               for i in range(n) for w in walks)


def ponytail():
    """Seed A's first wish, "when the character moves violently": a ponytail that hangs at
    rest and streams behind in a sprint, from a motion example keyed by the head's speed."""
    walks = [
        {"speed": 1.4, "start": 0.5, "end": 6.5, "ramp_in": 0.5, "ramp_out": 0.4},  # walk, then stop
        {"speed": 4.6, "start": 3.0, "end": 6.5, "ramp_in": 0.8, "ramp_out": 0.4},  # the sprint on top
    ]
    motions = [{"type": "walk", **w, "bob": 0.03, "step_frequency": 2} for w in walks[:1]]
    motions += [{"type": "walk", **walks[1], "bob": 0.02, "step_frequency": 1.2, "roll_deg": 0}]
    tail = {
        "name": "ponytail", "joint": "head", "offset": {"position": [0, 0.16, -0.1]},
        "thickness": 0.012, "mass": 0.002,
        "shape": arc(10, 0.32, [0, 0.3, -1], [1, 0, 0], -150),
        "keyed": [{
            "name": "sprint", "key": "motion", "measure": "speed", "value": 6, "influence": 1.5, "smoothing": 0.3,
            "shape": arc(10, 0.32, [0, 0.2, -1], [1, 0, 0], -22),
        }],
    }
    # The camera keeps level with the head on the character's left, 2.2 m off its path.
    keys = []
    for i in range(0, 41):
        t = i * 0.25
        z = round(travelled(t, walks), 3)
        keys.append({"time": t, "position": [2.2, 1.5, z], "target": [0, 1.45, z]})
    return scene("ponytail", 60, 10, {"fov_deg": 30, "keyframes": {"keys": keys, "interpolation": "linear"}}, [
        character("runner", motions, {"stiffness": 0.5, "damping": 2, "iterations": 4}, [tail])])


def nod():
    """Seed A's second wish, "when the character takes a particular pose": bangs that fall
    over the eyes when she looks down (a pose example keyed by the head's pitch against the
    neck) and part off them when she looks up (the front view example of bangs.json)."""
    chains = [bang(f"bang_l{k + 1}", f"bang_r{k + 1}", 0.12, az, 10, 0.13, 52 + 6 * k) for k, az in enumerate([7, 21, 35])]
    for k, az in enumerate([7, 21, 35]):
        # Looking down, the strands fall forward off the brow and hang over the eyes.
        root = on_sphere(0.12, az, 40)
        down = sample(sphere_path(0.135, (az, 40), (az * 0.7, 5), (az * 0.6, -60)), 10, 0.13)
        rel = [r3([p[m] - root[m] for m in range(3)], 4) for p in down]
        rel[0] = [0, 0, 0]
        chains[k]["keyed"] = [{"name": "look_down", "key": "pose", "pose": [{"joint": "head", "axis": [1, 0, 0], "angle_deg": 30}],
                               "influence": 12, "shape": {"positions": rel}}]
    return scene("nod", 60, 12, {"fov_deg": 30, "position": [0, 1.62, 1.0], "target": [0, 1.57, 0]}, [
        character("girl", [
            {"type": "sway", "joint": "body", "axis": [0, 0, 1], "amplitude_deg": 2, "frequency": 0.3},
            # Looks down (+X turns the face down), holds, looks up, holds: 8 s a nod.
            {"type": "sway", "joint": "head", "axis": [1, 0, 0], "amplitude_deg": 30, "frequency": 0.125, "sharpness": 3,
             "start": 1, "fade": 0.5},
        ], {"stiffness": 0.6, "damping": 3, "iterations": 4}, chains)])


def dump(path, doc):
    # "$schema" first, relative to the output folder, so an editor that opens the scene
    # finds docs/scene.schema.json from wherever the scene was written.
    schema = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "docs", "scene.schema.json")
    reference = os.path.relpath(schema, os.path.dirname(os.path.abspath(path))).replace(os.sep, "/")
    text = json.dumps({"$schema": reference, **doc}, indent=2)

    # Short arrays and small objects on one line each.
    def collapse(m):
        inner = re.sub(r"\s+", " ", m.group(0))
        return inner.replace("[ ", "[").replace(" ]", "]")

    text = re.sub(r"\[[^\[\]\{\}]*\]", collapse, text)

    def collapse_object(m):
        inner = re.sub(r"\s+", " ", m.group(0)).replace("{ ", "{").replace(" }", "}")
        return inner if len(inner) < 150 else m.group(0)

    for _ in range(3):
        text = re.sub(r"\{[^\{\}]*\}", collapse_object, text)
    with open(path, "w") as f:
        f.write(text + "\n")


if __name__ == "__main__":
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "scenes")
    for name, make in (("bunny", bunny), ("bangs", bangs), ("crowd", crowd), ("ponytail", ponytail), ("nod", nod)):
        dump(os.path.join(out, name + ".json"), make())
