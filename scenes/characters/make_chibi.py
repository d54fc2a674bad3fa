#!/usr/bin/env python3
"""Writes scenes/characters/chibi.glb: Kodawari's own small rigged glTF 2.0 character.

    python3 scenes/characters/make_chibi.py [--out PATH]   # generate, verify, write
    python3 scenes/characters/make_chibi.py --check [--out PATH]   # verify a written file

"Chibi" is a stylised big-head figure, 1.11 m to the top of the head (1.22 m to the top
of its ahoge): a robe-like body without legs, two short arms, a head sphere (radius
0.2 m) with a hair cap and two eyes, and seven hair strands that the simulator animates
as rod chains (SPEC part A). Everything else is driven by three looping clips.

Units and axes: metres, +Y up, the character faces +Z, so +X is the character's left.
The rest pose is the bind pose; `root` is at the origin, between the feet.

Joint hierarchy (every node below is a joint of the one skin):

    root (0, 0, 0)
    └─ hips (0, 0.42, 0)
       └─ spine (0, 0.55, 0)
          ├─ neck (0, 0.68, 0)
          │  └─ head (0, 0.74, 0)   view directions are measured in this frame:
          │     │                   +Z forward (the face), +Y up; head sphere centre
          │     │                   0.17 m above the joint
          │     ├─ ahoge_0 … ahoge_4                 curl from the crown towards +X
          │     ├─ bang_L_0 … bang_L_4               front hair, down to the eyes
          │     ├─ bang_C_0 … bang_C_4
          │     ├─ bang_R_0 … bang_R_4
          │     ├─ hair_side_L_0 … hair_side_L_5     side locks beside the cheeks
          │     ├─ hair_side_R_0 … hair_side_R_5
          │     └─ tail_0 … tail_7                   ponytail down the back
          ├─ arm_L ─ hand_L   (shoulder at x = +0.115)
          └─ arm_R ─ hand_R

Each hair strand is a single-child chain whose first joint is a child of `head`; the
root names contain "ahoge", "bang", "hair" or "tail", the patterns the chain finder
(engine/gltf/chains.cpp) looks for, and no body joint name contains any of its patterns.
Body joints have identity rest rotations. Each hair joint's rest orientation is the
shortest arc taking +Y to its segment (the last joint: the last segment), the convention
the chain base shapes assume (engine/rods/synthetic.cpp does the same).

The mesh (one mesh, one primitive per material) is built in the bind pose:
skin (head sphere, neck, arms, hands) -- hair (cap + a tapered tube per strand, rings
weighted linearly between consecutive joints) -- clothes (a lathed robe, weights blended
by height hips -> spine -> neck -> head) -- eyes. Weights are multiples of 2^-16 that sum
to exactly 1, at most two influences per vertex.

Clips (all loop: the first key equals the last; they animate body joints only, never the
hair, which is simulated):

- idle (4 s, LINEAR): the spine sways (roll +-2.5 deg, once per 4 s) and leans with the
  breath, neck and head look round together (yaw 9 + 16 = +-25 deg, once per 4 s) with a
  small nod and tilt, and the hips bob 4 mm twice per 4 s (breathing). Slow and small, so
  the hair mostly hangs and only sways a little.
- walk (1 s cycle, LINEAR, in place): the hips bob 12 mm twice per cycle (one bump per
  step), roll +-4 deg and twist +-6 deg once per cycle, shift 8 mm sideways; the spine
  counter-twists and the head counter-rotates so that it stays level and faces forward
  (as a walker keeps the gaze steady); the arms swing +-22 deg in opposition. Fast
  periodic motion, so strands swing and lag.
- turn (3 s): the head snaps left (30 deg on the neck's 15: 45 deg) at 0.5 s, right at 1.5 s, back at 2.5 s with
  STEP keys -- the abrupt look that tests the simulator's response to discontinuous head
  motion -- while the neck follows smoothly (+-15 deg) on CUBICSPLINE keys with real
  in/out tangents (3 values per key) and the hips shift their weight sideways, also
  CUBICSPLINE. The files in this repository need a real STEP and CUBICSPLINE sampler.

Deterministic: no timestamps, no randomness, numbers rounded or stored as float32, JSON
in a fixed order; two runs give the same bytes. The file is written atomically. Before
writing, the bytes are parsed back and checked (inverse bind matrices times the joints'
rest world matrices = identity within 1e-6, weights, normals, winding, chains, loops).
"""
import argparse
import json
import math
import os
import struct
import sys
import tempfile

# --- small vector and quaternion helpers (tuples; quaternions are (x, y, z, w)) ------------


def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def scale(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def length(a):
    return math.sqrt(dot(a, a))


def normalize(a):
    n = length(a)
    return (a[0] / n, a[1] / n, a[2] / n)


def q_mul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz)


def q_conj(q):
    return (-q[0], -q[1], -q[2], q[3])


def q_normalize(q):
    n = math.sqrt(sum(c * c for c in q))
    return tuple(c / n for c in q)


def q_rotate(q, v):
    u = (q[0], q[1], q[2])
    t = scale(cross(u, v), 2.0)
    return add(add(v, scale(t, q[3])), cross(u, t))


def q_axis_angle(axis, degrees):
    h = math.radians(degrees) / 2.0
    s = math.sin(h)
    a = normalize(axis)
    return (a[0] * s, a[1] * s, a[2] * s, math.cos(h))


IDENTITY_Q = (0.0, 0.0, 0.0, 1.0)
X_AXIS, Y_AXIS, Z_AXIS = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)


def q_euler(yaw=0.0, pitch=0.0, roll=0.0):
    """Yaw about +Y (positive turns the face towards the character's left, +X), then pitch
    about +X (positive tips the face down), then roll about +Z (positive tilts the top of
    the head towards -X, the character's right); degrees."""
    return q_mul(q_mul(q_axis_angle(Y_AXIS, yaw), q_axis_angle(X_AXIS, pitch)), q_axis_angle(Z_AXIS, roll))


def q_shortest_arc(a, b):
    """The shortest-arc rotation taking unit `a` to unit `b`, as rods::shortest_arc computes
    it (through the half-way vector). The strands here never turn by nearly half a turn."""
    h = add(a, b)
    hl = length(h)
    assert hl > 1e-2, "segment points (nearly) straight down the parent's -Y"
    hn = scale(h, 1.0 / hl)
    c = cross(a, hn)
    return q_normalize((c[0], c[1], c[2], dot(a, hn)))


def mat_trs(t, q):
    """Row-major 4x4 matrix of translation t and rotation q."""
    x, y, z, w = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w), t[0]],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w), t[1]],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y), t[2]],
            [0.0, 0.0, 0.0, 1.0]]


def mat_mul(a, b):
    return [[sum(a[r][k] * b[k][c] for k in range(4)) for c in range(4)] for r in range(4)]


def mat_inverse(m):
    """General 4x4 inverse (Gauss-Jordan with partial pivoting), in double precision."""
    a = [list(row) + [1.0 if r == c else 0.0 for c in range(4)] for r, row in enumerate(m)]
    for col in range(4):
        pivot = max(range(col, 4), key=lambda r: abs(a[r][col]))
        a[col], a[pivot] = a[pivot], a[col]
        p = a[col][col]
        a[col] = [v / p for v in a[col]]
        for r in range(4):
            if r != col and a[r][col] != 0.0:
                f = a[r][col]
                a[r] = [v - f * w for v, w in zip(a[r], a[col])]
    return [row[4:] for row in a]


def f32(x):
    """x rounded to the nearest float32 (as a Python float, which holds it exactly)."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


def clean(x, digits):
    """x rounded for the JSON, without a negative zero."""
    return round(x, digits) + 0.0


# --- the skeleton -------------------------------------------------------------------

HEAD_POS = (0.0, 0.74, 0.0)
HEAD_CENTER = (0.0, 0.17, 0.0)  # head sphere centre, in the head joint's frame
HEAD_R = 0.2

BODY = [  # name, parent, world position in the rest pose; identity rotations
    ("root", None, (0.0, 0.0, 0.0)),
    ("hips", "root", (0.0, 0.42, 0.0)),
    ("spine", "hips", (0.0, 0.55, 0.0)),
    ("neck", "spine", (0.0, 0.68, 0.0)),
    ("head", "neck", HEAD_POS),
    ("arm_L", "spine", (0.115, 0.645, 0.0)),
    ("hand_L", "arm_L", (0.205, 0.425, 0.015)),
    ("arm_R", "spine", (-0.115, 0.645, 0.0)),
    ("hand_R", "arm_R", (-0.205, 0.425, 0.015)),
]


def head_dir(theta, phi):
    """Unit vector from the head centre at polar angle theta from +Y and azimuth phi
    (0 = the face, +90 = the character's left, 180 = the back); degrees."""
    t, p = math.radians(theta), math.radians(phi)
    return (math.sin(t) * math.sin(p), math.cos(t), math.sin(t) * math.cos(p))


def on_head(theta, phi, lift):
    """A point `lift` m outside the head sphere, in the head joint's frame."""
    return add(HEAD_CENTER, scale(head_dir(theta, phi), HEAD_R + lift))


def polyline(start, steps):
    pts = [start]
    for s in steps:
        pts.append(add(pts[-1], s))
    return pts


def mirror_x(points):
    return [(-p[0], p[1], p[2]) for p in points]


def hair_strands():
    """[(chain name prefix, joint points in the head joint's frame, root radius, tip
    radius, tube sides, bulge)]: the shapes of the seven strands in the rest pose."""
    strands = []
    # Ahoge: rises from the crown, then curls over towards the character's left (+X),
    # in the XY plane, so that seen from the front it reads as a sideways curl.
    strands.append(("ahoge", polyline(on_head(4.0, 0.0, -0.004),
                                      [(0.004, 0.055, 0.0), (0.022, 0.042, 0.0), (0.042, 0.008, 0.0),
                                       (0.026, -0.032, 0.0)]), 0.011, 0.003, 6, 0.0))
    # Bangs: from the top of the forehead down over the face to eye level (polar angle
    # 100 deg: the eyes' height), hugging the head sphere and lifting off it towards the tip.
    for side, phi in (("L", 26.0), ("C", 0.0), ("R", -26.0)):
        pts = []
        for k in range(5):
            s = k / 4.0
            pts.append(on_head(18.0 + 82.0 * s, phi * (1.0 + 0.15 * s), 0.010 + 0.014 * s * s))
        strands.append(("bang_" + side, pts, 0.019, 0.004, 6, 0.0))
    # Side locks: from above the ear down the side of the head, then straight down beside
    # the cheek, slightly forward and in, to the jaw line and below.
    side_l = [on_head(48.0, 80.0, 0.008), on_head(72.0, 80.0, 0.014), on_head(96.0, 78.0, 0.020)]
    side_l = polyline(side_l[0], [sub(side_l[1], side_l[0]), sub(side_l[2], side_l[1]),
                                  (-0.006, -0.065, 0.006), (-0.008, -0.065, 0.008), (-0.006, -0.055, 0.010)])
    strands.append(("hair_side_L", side_l, 0.017, 0.004, 6, 0.0))
    strands.append(("hair_side_R", mirror_x(side_l), 0.017, 0.004, 6, 0.0))
    # Ponytail: tied high on the back of the head, sticks out backwards, then falls down
    # the back, curving in a little towards its tip.
    strands.append(("tail", polyline(on_head(60.0, 180.0, 0.005),
                                     [(0.0, 0.015, -0.055), (0.0, -0.035, -0.060), (0.0, -0.075, -0.030),
                                      (0.0, -0.080, -0.006), (0.0, -0.080, 0.012), (0.0, -0.075, 0.020),
                                      (0.0, -0.070, 0.022)]), 0.027, 0.006, 8, 0.45))
    return strands


def joint_name(prefix, k):
    return "%s_%d" % (prefix, k)


def build_skeleton():
    """The joints as nodes: [{name, parent, t, r}] with local TRS rounded for the file
    (translations to 1e-7 m, rotations to 1e-9), parents before children."""
    design = []  # (name, parent, world position, world rotation)
    for name, parent, pos in BODY:
        design.append((name, parent, pos, IDENTITY_Q))
    for prefix, pts, *_ in hair_strands():
        world = [add(HEAD_POS, p) for p in pts]
        rots = []
        for k in range(len(world)):
            a, b = (k, k + 1) if k + 1 < len(world) else (k - 1, k)
            rots.append(q_shortest_arc(Y_AXIS, normalize(sub(world[b], world[a]))))
        for k in range(len(world)):
            parent = "head" if k == 0 else joint_name(prefix, k - 1)
            design.append((joint_name(prefix, k), parent, world[k], rots[k]))
    by_name = {d[0]: d for d in design}
    nodes = []
    for name, parent, pos, rot in design:
        if parent is None:
            t, r = pos, rot
        else:
            _, _, ppos, prot = by_name[parent]
            t = q_rotate(q_conj(prot), sub(pos, ppos))
            r = q_mul(q_conj(prot), rot)
        if r[3] < 0.0:
            r = tuple(-c for c in r)
        nodes.append({"name": name, "parent": parent,
                      "t": tuple(clean(c, 7) for c in t), "r": tuple(clean(c, 9) for c in r)})
    return nodes


def world_matrices(nodes):
    """Rest-pose world matrices (row-major, double) from the nodes' local TRS, as a glTF
    reader computes them from the file."""
    index = {n["name"]: i for i, n in enumerate(nodes)}
    world = []
    for n in nodes:
        local = mat_trs(n["t"], n["r"])
        world.append(local if n["parent"] is None else mat_mul(world[index[n["parent"]]], local))
    return world


# --- mesh building ------------------------------------------------------------------


def quantize_weights(influences):
    """[(joint, weight)] -> at most 4 (joint, weight) pairs with weights that are multiples
    of 2^-16 summing to exactly 1 (so also in float32), largest first, zeros dropped."""
    merged = {}
    for j, w in influences:
        if w > 0.0:
            merged[j] = merged.get(j, 0.0) + w
    items = sorted(merged.items(), key=lambda jw: (-jw[1], jw[0]))[:4]
    total = sum(w for _, w in items)
    q = [(j, round(w / total * 65536.0) / 65536.0) for j, w in items]
    q = [(j, w) for j, w in q[1:] if w > 0.0]
    return [(items[0][0], 1.0 - sum(w for _, w in q))] + q


class Primitive:
    def __init__(self, material):
        self.material = material
        self.positions, self.normals, self.joints, self.weights, self.indices = [], [], [], [], []

    def vertex(self, pos, normal, influences):
        jw = quantize_weights(influences)
        jw += [(0, 0.0)] * (4 - len(jw))
        self.positions.append(pos)
        self.normals.append(normalize(normal))
        self.joints.append(tuple(j for j, _ in jw))
        self.weights.append(tuple(w for _, w in jw))
        return len(self.positions) - 1

    def grid(self, rings, start=None, end=None, closed=True):
        """Triangles between consecutive rings of vertex indices. The winding is
        counter-clockwise seen from outside when the ring index runs anticlockwise about
        the direction from ring k to ring k+1. `start` / `end`: pole vertices closing
        the first / last ring."""
        sides = len(rings[0])
        last = sides if closed else sides - 1
        for k in range(len(rings) - 1):
            r0, r1 = rings[k], rings[k + 1]
            for i in range(last):
                i1 = (i + 1) % sides
                self.indices += [r0[i], r0[i1], r1[i1], r0[i], r1[i1], r1[i]]
        for i in range(last):
            i1 = (i + 1) % sides
            if start is not None:
                self.indices += [start, rings[0][i1], rings[0][i]]
            if end is not None:
                self.indices += [end, rings[-1][i], rings[-1][i1]]


def perpendicular(t):
    """A unit vector perpendicular to unit t (deterministic)."""
    ref = Z_AXIS if abs(t[2]) < 0.9 else X_AXIS
    return normalize(cross(t, ref))


def ellipsoid(prim, center, u, v, t, radii, rings, sides, influences):
    """An ellipsoid with semi-axes radii = (along u, along v, along t); u x v = t."""
    au, av, at = radii
    idx = []
    for k in range(1, rings):
        theta = math.pi * (1.0 - k / rings)  # from the -t pole to the +t pole
        ring = []
        for i in range(sides):
            a = 2.0 * math.pi * i / sides
            lx, ly, lz = au * math.sin(theta) * math.cos(a), av * math.sin(theta) * math.sin(a), at * math.cos(theta)
            pos = add(center, add(add(scale(u, lx), scale(v, ly)), scale(t, lz)))
            normal = add(add(scale(u, lx / au ** 2), scale(v, ly / av ** 2)), scale(t, lz / at ** 2))
            ring.append(prim.vertex(pos, normal, influences))
        idx.append(ring)
    south = prim.vertex(sub(center, scale(t, at)), scale(t, -1.0), influences)
    north = prim.vertex(add(center, scale(t, at)), t, influences)
    prim.grid(idx, south, north)


def capsule(prim, a, b, radius, sides, influences, cap_rings=4, body_rings=4):
    t = normalize(sub(b, a))
    u = perpendicular(t)
    v = cross(t, u)
    stations = []  # (centre, polar angle)
    for k in range(1, cap_rings + 1):
        stations.append((a, math.pi - 0.5 * math.pi * k / cap_rings))
    for k in range(1, body_rings):
        stations.append((add(a, scale(sub(b, a), k / body_rings)), 0.5 * math.pi))
    for k in range(cap_rings):
        stations.append((b, 0.5 * math.pi - 0.5 * math.pi * k / cap_rings))
    rings = []
    for c, theta in stations:
        ring = []
        for i in range(sides):
            ang = 2.0 * math.pi * i / sides
            radial = add(scale(u, math.cos(ang)), scale(v, math.sin(ang)))
            normal = add(scale(radial, math.sin(theta)), scale(t, math.cos(theta)))
            ring.append(prim.vertex(add(c, scale(normal, radius)), normal, influences))
        rings.append(ring)
    south = prim.vertex(sub(a, scale(t, radius)), scale(t, -1.0), influences)
    north = prim.vertex(add(b, scale(t, radius)), t, influences)
    prim.grid(rings, south, north)


def lathe(prim, profile, sides, weights_at):
    """A surface of revolution about +Y; profile = [(y, r)] from bottom to top, with r = 0
    at the two ends (the poles). weights_at(y) gives each ring's influences."""
    rings = []
    for k in range(1, len(profile) - 1):
        y, r = profile[k]
        dr = profile[k + 1][1] - profile[k - 1][1]
        dy = profile[k + 1][0] - profile[k - 1][0]
        nr, ny = dy, -dr  # outward normal of the profile curve, (radial, up)
        ring = []
        for i in range(sides):
            a = 2.0 * math.pi * i / sides
            radial = (math.sin(a), 0.0, math.cos(a))  # anticlockwise about +Y
            ring.append(prim.vertex((r * radial[0], y, r * radial[2]),
                                    add(scale(radial, nr), (0.0, ny, 0.0)), weights_at(y)))
        rings.append(ring)
    south = prim.vertex((0.0, profile[0][0], 0.0), (0.0, -1.0, 0.0), weights_at(profile[0][0]))
    north = prim.vertex((0.0, profile[-1][0], 0.0), (0.0, 1.0, 0.0), weights_at(profile[-1][0]))
    prim.grid(rings, south, north)


def catmull_rom(p0, p1, p2, p3, f):
    """Point and derivative of the uniform Catmull-Rom segment p1 -> p2 at f in [0, 1]."""
    pos, der = [], []
    for c in range(3):
        a, b, cc, d = p0[c], p1[c], p2[c], p3[c]
        c1, c2, c3 = -a + cc, 2 * a - 5 * b + 4 * cc - d, -a + 3 * b - 3 * cc + d
        pos.append(0.5 * (2 * b + c1 * f + c2 * f * f + c3 * f ** 3))
        der.append(0.5 * (c1 + 2 * c2 * f + 3 * c3 * f * f))
    return tuple(pos), tuple(der)


def ladder_weights(ladder, y):
    """Skin weights by height: `ladder` is [(height, joint), ...] from the bottom; below the
    first joint all to it, above the last all to it, between two a smoothstepped blend."""
    if y <= ladder[0][0]:
        return [(ladder[0][1], 1.0)]
    for (y0, j0), (y1, j1) in zip(ladder, ladder[1:]):
        if y <= y1:
            f = (y - y0) / (y1 - y0)
            f = f * f * (3.0 - 2.0 * f)
            return [(j0, 1.0 - f), (j1, f)]
    return [(ladder[-1][1], 1.0)]


def strand_samples(pts, joints, per_segment):
    """Points along a Catmull-Rom spline through the joints `pts`, `per_segment` a segment,
    each (position, unit tangent, influences): at fraction f of segment i, weighted
    (1 - f) to joint i and f to joint i + 1; the last joint alone at the tip."""
    n = len(pts)
    samples = []
    for i in range(n - 1):
        p0 = pts[i - 1] if i > 0 else sub(scale(pts[0], 2.0), pts[1])
        p3 = pts[i + 2] if i + 2 < n else sub(scale(pts[-1], 2.0), pts[-2])
        for s in range(per_segment):
            f = s / per_segment
            pos, der = catmull_rom(p0, pts[i], pts[i + 1], p3, f)
            samples.append((pos if s else pts[i], normalize(der), [(joints[i], 1.0 - f), (joints[i + 1], f)]))
    _, der = catmull_rom(pts[-3] if n > 2 else sub(scale(pts[0], 2.0), pts[1]), pts[-2], pts[-1],
                         sub(scale(pts[-1], 2.0), pts[-2]), 1.0)
    samples.append((pts[-1], normalize(der), [(joints[-1], 1.0)]))
    return samples


def strand_tube(prim, joints, pts, r_root, r_tip, sides, bulge, per_segment=4):
    """A tapered tube along a smooth curve through the strand's joint positions `pts`
    (world, rest pose). A ring at fraction f of segment i is weighted (1 - f) to joint i
    and f to joint i+1. Frames are rotation-minimizing (double reflection), so the tube
    does not twist; the root end gets a small dome, the tip a point."""
    n = len(pts)
    samples = strand_samples(pts, joints, per_segment)

    arc = [0.0]
    for k in range(1, len(samples)):
        arc.append(arc[-1] + length(sub(samples[k][0], samples[k - 1][0])))
    u = perpendicular(samples[0][1])
    rings = []
    for k, (pos, t, influences) in enumerate(samples):
        if k > 0:  # double reflection (Wang et al. 2008)
            prev_pos, prev_t, _ = samples[k - 1]
            v1 = sub(pos, prev_pos)
            c1 = dot(v1, v1)
            r_l = sub(u, scale(v1, 2.0 / c1 * dot(v1, u)))
            t_l = sub(prev_t, scale(v1, 2.0 / c1 * dot(v1, prev_t)))
            v2 = sub(t, t_l)
            c2 = dot(v2, v2)
            u = sub(r_l, scale(v2, 2.0 / c2 * dot(v2, r_l))) if c2 > 1e-20 else r_l
            u = normalize(sub(u, scale(t, dot(u, t))))
        v = cross(t, u)
        s = arc[k] / arc[-1]
        radius = (r_root + (r_tip - r_root) * s) * (1.0 + bulge * math.sin(math.pi * min(1.0, 2.0 * s)) * (1.0 - s))
        ring = []
        for i in range(sides):
            a = 2.0 * math.pi * i / sides
            radial = add(scale(u, math.cos(a)), scale(v, math.sin(a)))
            ring.append(prim.vertex(add(pos, scale(radial, radius)), radial, influences))
        rings.append(ring)
    t0, t1 = samples[0][1], samples[-1][1]
    root = prim.vertex(sub(pts[0], scale(t0, 0.5 * r_root)), scale(t0, -1.0), samples[0][2])
    tip = prim.vertex(add(pts[-1], scale(t1, 2.0 * r_tip)), t1, samples[-1][2])
    prim.grid(rings, root, tip)


def hair_cap(prim, head_center, influences, rings=8, sides=24, lift=0.006):
    """The hair on the skull: the head sphere's upper part, lifted by `lift`, down to 58 deg
    from the top at the face, 85 deg at the sides and 112 deg at the back. Open at its edge."""
    idx = []
    for k in range(rings):
        ring = []
        for i in range(sides):
            phi = 360.0 * i / sides
            theta_max = 58.0 + 54.0 * (1.0 - math.cos(math.radians(phi))) / 2.0
            d = head_dir(theta_max * (rings - k) / rings, phi)
            ring.append(prim.vertex(add(head_center, scale(d, HEAD_R + lift)), d, influences))
        idx.append(ring)
    top = prim.vertex(add(head_center, (0.0, HEAD_R + lift, 0.0)), Y_AXIS, influences)
    prim.grid(idx, None, top)


def build_mesh(nodes, world):
    index = {n["name"]: i for i, n in enumerate(nodes)}
    pos = {n["name"]: (world[i][0][3], world[i][1][3], world[i][2][3]) for i, n in enumerate(nodes)}
    head = [(index["head"], 1.0)]
    head_center = add(pos["head"], HEAD_CENTER)

    # Body weights by height: hips below the hips joint, then linear (smoothstepped)
    # blends hips -> spine -> neck -> head between the joints' heights.
    ladder = [(pos[n][1], index[n]) for n in ("hips", "spine", "neck", "head")]

    def body_weights(y):
        return ladder_weights(ladder, y)

    skin, hair, clothes, eyes = Primitive(0), Primitive(1), Primitive(2), Primitive(3)

    # Skin: head sphere, neck, arms and hands.
    ellipsoid(skin, head_center, Z_AXIS, X_AXIS, Y_AXIS, (HEAD_R, HEAD_R, HEAD_R), 14, 24, head)
    neck_rings = []
    for y in (0.64, 0.67, 0.69, 0.71, 0.73, 0.76, 0.80):
        ring = []
        for i in range(16):
            a = 2.0 * math.pi * i / 16
            radial = (math.sin(a), 0.0, math.cos(a))
            ring.append(skin.vertex((0.045 * radial[0], y, 0.045 * radial[2]), radial, body_weights(y)))
        neck_rings.append(ring)
    skin.grid(neck_rings)  # open ends, inside the robe and the head
    for side in ("L", "R"):
        a, b = pos["arm_" + side], pos["hand_" + side]
        d = normalize(sub(b, a))
        capsule(skin, sub(a, scale(d, 0.015)), b, 0.03, 10, [(index["arm_" + side], 1.0)])
        c = add(b, scale(d, 0.03))
        ellipsoid(skin, c, perpendicular(d), cross(d, perpendicular(d)), d, (0.034, 0.03, 0.038), 6, 10,
                  [(index["hand_" + side], 1.0)])

    # Hair: the cap and the strands.
    hair_cap(hair, head_center, head)
    for prefix, pts, r_root, r_tip, sides, bulge in hair_strands():
        names = [joint_name(prefix, k) for k in range(len(pts))]
        strand_tube(hair, [index[nm] for nm in names], [pos[nm] for nm in names], r_root, r_tip, sides, bulge)

    # Clothes: a robe from the ground to the collar (a bell at the hem, a waist, a chest).
    profile = [(0.0, 0.0), (0.004, 0.09), (0.02, 0.145), (0.06, 0.165), (0.14, 0.163), (0.24, 0.152),
               (0.34, 0.138), (0.42, 0.124), (0.48, 0.12), (0.54, 0.126), (0.59, 0.13), (0.63, 0.122),
               (0.655, 0.1), (0.672, 0.07), (0.682, 0.04), (0.686, 0.0)]
    lathe(clothes, profile, 24, body_weights)

    # Eyes: flat dark ellipsoids half sunk into the face at eye level, under the bangs.
    for phi in (21.0, -21.0):
        n = head_dir(100.0, phi)
        up = normalize(sub(Y_AXIS, scale(n, dot(Y_AXIS, n))))
        ellipsoid(eyes, add(head_center, scale(n, HEAD_R - 0.002)), up, cross(n, up), n, (0.03, 0.02, 0.01),
                  6, 12, head)
    return [skin, hair, clothes, eyes]


# --- animation clips ------------------------------------------------------------------


def sampled(duration, keys, fn):
    """LINEAR keys of fn(t) at keys+1 evenly spaced times; the last key is a copy of the
    first, so the clip loops seamlessly."""
    times = [duration * k / keys for k in range(keys + 1)]
    values = [fn(t) for t in times[:-1]]
    return times, values + [values[0]]


def yaw_spline(keys):
    """CUBICSPLINE rotation keys from [(time s, yaw deg, yaw rate deg/s)]: the value is the
    yaw quaternion, both tangents its time derivative dq/dt = dq/dyaw * rate (glTF tangents
    are per second; the sampler scales them by the key interval). The first key's
    in-tangent and the last key's out-tangent are unused and zero."""
    times, values = [], []
    for k, (t, yaw, rate) in enumerate(keys):
        h = math.radians(yaw) / 2.0
        q = (0.0, math.sin(h), 0.0, math.cos(h))
        w = 0.5 * math.radians(rate)
        dq = (0.0, math.cos(h) * w, 0.0, -math.sin(h) * w)
        zero = (0.0, 0.0, 0.0, 0.0)
        times.append(t)
        values += [zero if k == 0 else dq, q, zero if k == len(keys) - 1 else dq]
    return times, values


def vec_spline(rest, keys):
    """CUBICSPLINE translation keys from [(time s, offset from rest, velocity m/s)]."""
    times, values = [], []
    for k, (t, off, vel) in enumerate(keys):
        times.append(t)
        values += [(0.0, 0.0, 0.0) if k == 0 else vel, add(rest, off),
                   (0.0, 0.0, 0.0) if k == len(keys) - 1 else vel]
    return times, values


def build_clips(nodes):
    hips_rest = next(n["t"] for n in nodes if n["name"] == "hips")
    tau = 2.0 * math.pi

    # idle: 4 s, keys every 0.1 s.
    def idle_w(t):
        return tau * t / 4.0

    idle = [
        ("spine", "rotation", "LINEAR", sampled(4.0, 40, lambda t: q_euler(
            pitch=1.5 * math.sin(2 * idle_w(t)), roll=2.5 * math.sin(idle_w(t))))),
        ("neck", "rotation", "LINEAR", sampled(4.0, 40, lambda t: q_euler(
            yaw=9.0 * math.sin(idle_w(t)), pitch=2.0 * math.sin(2 * idle_w(t) + 0.8)))),
        ("head", "rotation", "LINEAR", sampled(4.0, 40, lambda t: q_euler(
            yaw=16.0 * math.sin(idle_w(t)), pitch=4.0 * math.sin(2 * idle_w(t)),
            roll=3.0 * math.sin(idle_w(t) + 1.0)))),
        ("hips", "translation", "LINEAR", sampled(4.0, 40, lambda t: add(
            hips_rest, (0.0, 0.004 * math.sin(2 * idle_w(t)), 0.0)))),
    ]

    # walk: 1 s cycle, 24 keys. Phase w: the left foot would strike at w = 0.
    walk = [
        ("hips", "translation", "LINEAR", sampled(1.0, 24, lambda t: add(
            hips_rest, (0.008 * math.sin(tau * t), 0.012 * math.cos(2 * tau * t), 0.0)))),
        ("hips", "rotation", "LINEAR", sampled(1.0, 24, lambda t: q_euler(
            yaw=6.0 * math.cos(tau * t), roll=4.0 * math.sin(tau * t)))),
        ("spine", "rotation", "LINEAR", sampled(1.0, 24, lambda t: q_euler(
            yaw=-8.0 * math.cos(tau * t), pitch=2.0, roll=-2.0 * math.sin(tau * t)))),
        ("head", "rotation", "LINEAR", sampled(1.0, 24, lambda t: q_euler(
            yaw=2.0 * math.cos(tau * t), pitch=-2.0 + 1.5 * math.cos(2 * tau * t), roll=-3.0 * math.sin(tau * t)))),
        ("arm_L", "rotation", "LINEAR", sampled(1.0, 24, lambda t: q_euler(
            pitch=22.0 * math.cos(tau * t), roll=4.0))),
        ("arm_R", "rotation", "LINEAR", sampled(1.0, 24, lambda t: q_euler(
            pitch=-22.0 * math.cos(tau * t), roll=-4.0))),
    ]

    # turn: 3 s. The head snaps (STEP); the neck follows on a smooth spline and the hips
    # shift the weight (CUBICSPLINE).
    turn = [
        ("head", "rotation", "STEP", ([0.0, 0.5, 1.5, 2.5, 3.0],
                                      [IDENTITY_Q, q_euler(yaw=30.0), q_euler(yaw=-30.0), IDENTITY_Q, IDENTITY_Q])),
        ("neck", "rotation", "CUBICSPLINE", yaw_spline([
            (0.0, 0.0, 0.0), (0.5, 10.0, 40.0), (0.8, 15.0, 0.0), (1.5, 0.0, -60.0),
            (1.8, -15.0, 0.0), (2.5, -5.0, 40.0), (2.8, 0.0, 0.0), (3.0, 0.0, 0.0)])),
        ("hips", "translation", "CUBICSPLINE", vec_spline(hips_rest, [
            (0.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)), (0.8, (0.012, 0.0, 0.0), (0.0, 0.0, 0.0)),
            (1.3, (0.0, -0.004, 0.0), (-0.05, 0.0, 0.0)), (1.8, (-0.012, 0.0, 0.0), (0.0, 0.0, 0.0)),
            (2.8, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)), (3.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))])),
    ]
    return [("idle", idle), ("walk", walk), ("turn", turn)]


# --- glTF assembly --------------------------------------------------------------------

FLOAT, UBYTE, USHORT, UINT = 5126, 5121, 5123, 5125
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
MATERIALS = [  # name, linear base colour
    ("skin", (0.95, 0.72, 0.6)),
    ("hair", (0.22, 0.36, 0.8)),
    ("clothes", (0.8, 0.22, 0.2)),
    ("eyes", (0.05, 0.04, 0.08)),
]


class Gltf:
    def __init__(self):
        self.bin = bytearray()
        self.views, self.accessors = [], []
        self.time_accessors = {}

    def accessor(self, fmt, rows, component, kind, target=None, bounds=False):
        """Appends the rows (tuples, or numbers for SCALAR) packed with struct format
        `fmt` per component to a new 4-byte aligned buffer view; returns the accessor."""
        flat = [c for row in rows for c in (row if isinstance(row, tuple) else (row,))]
        data = struct.pack("<%d%s" % (len(flat), fmt), *flat)
        while len(self.bin) % 4:
            self.bin.append(0)
        view = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if target is not None:
            view["target"] = target
        self.bin += data
        self.views.append(view)
        acc = {"bufferView": len(self.views) - 1, "componentType": component, "count": len(rows), "type": kind}
        if bounds:  # the float32 values exactly, as the reader sees them
            width = len(rows[0]) if isinstance(rows[0], tuple) else 1
            cols = [[f32(c) for c in flat[i::width]] for i in range(width)]
            acc["min"] = [min(c) for c in cols]
            acc["max"] = [max(c) for c in cols]
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def times(self, values):
        key = tuple(values)
        if key not in self.time_accessors:
            self.time_accessors[key] = self.accessor("f", list(values), FLOAT, "SCALAR", bounds=True)
        return self.time_accessors[key]


def build_document():
    nodes = build_skeleton()
    world = world_matrices(nodes)
    prims = build_mesh(nodes, world)
    clips = build_clips(nodes)
    g = Gltf()
    index = {n["name"]: i for i, n in enumerate(nodes)}

    gltf_prims = []
    for p in prims:
        attributes = {
            "POSITION": g.accessor("f", p.positions, FLOAT, "VEC3", ARRAY_BUFFER, bounds=True),
            "NORMAL": g.accessor("f", p.normals, FLOAT, "VEC3", ARRAY_BUFFER),
            "JOINTS_0": g.accessor("B", p.joints, UBYTE, "VEC4", ARRAY_BUFFER),
            "WEIGHTS_0": g.accessor("f", p.weights, FLOAT, "VEC4", ARRAY_BUFFER),
        }
        assert len(p.positions) < 65536
        indices = g.accessor("H", p.indices, USHORT, "SCALAR", ELEMENT_ARRAY_BUFFER)
        gltf_prims.append({"attributes": attributes, "indices": indices, "material": p.material, "mode": 4})

    ibms = []
    for m in world:
        inv = mat_inverse(m)
        inv[3] = [0.0, 0.0, 0.0, 1.0]  # exactly affine
        ibms.append(tuple(inv[r][c] + 0.0 for c in range(4) for r in range(4)))  # column-major
    ibm_accessor = g.accessor("f", ibms, FLOAT, "MAT4")

    animations = []
    for name, channels in clips:
        samplers, gchannels = [], []
        for node, path, interpolation, (times, values) in channels:
            kind = "VEC4" if path == "rotation" else "VEC3"
            samplers.append({"input": g.times(times), "interpolation": interpolation,
                             "output": g.accessor("f", [tuple(v) for v in values], FLOAT, kind)})
            gchannels.append({"sampler": len(samplers) - 1, "target": {"node": index[node], "path": path}})
        animations.append({"name": name, "channels": gchannels, "samplers": samplers})

    gltf_nodes = []
    for i, n in enumerate(nodes):
        node = {"name": n["name"]}
        children = [j for j, c in enumerate(nodes) if c["parent"] == n["name"]]
        if children:
            node["children"] = children
        if n["r"] != IDENTITY_Q:
            node["rotation"] = list(n["r"])
        if n["t"] != (0.0, 0.0, 0.0):
            node["translation"] = list(n["t"])
        gltf_nodes.append(node)
    mesh_node = len(gltf_nodes)
    gltf_nodes.append({"name": "chibi", "mesh": 0, "skin": 0})

    doc = {
        "asset": {"version": "2.0", "generator": "Kodawari make_chibi.py",
                  "copyright": "Part of Kodawari, same terms as the repository"},
        "scene": 0,
        "scenes": [{"name": "chibi", "nodes": [index["root"], mesh_node]}],
        "nodes": gltf_nodes,
        "meshes": [{"name": "chibi", "primitives": gltf_prims}],
        "skins": [{"name": "chibi", "inverseBindMatrices": ibm_accessor, "skeleton": index["root"],
                   "joints": list(range(len(nodes)))}],
        "materials": [{"name": name, "pbrMetallicRoughness": {
            "baseColorFactor": list(color) + [1.0], "metallicFactor": 0.0, "roughnessFactor": 0.8}}
            for name, color in MATERIALS],
        "animations": animations,
        "accessors": g.accessors,
        "bufferViews": g.views,
        "buffers": [{"byteLength": len(g.bin)}],
    }
    return doc, bytes(g.bin)


def to_glb(doc, binary):
    text = json.dumps(doc, separators=(",", ":"), ensure_ascii=True).encode("ascii")
    text += b" " * (-len(text) % 4)
    binary += b"\0" * (-len(binary) % 4)
    total = 12 + 8 + len(text) + 8 + len(binary)
    return (struct.pack("<4sII", b"glTF", 2, total) + struct.pack("<I4s", len(text), b"JSON") + text
            + struct.pack("<I4s", len(binary), b"BIN\0") + binary)


# --- verification (of the file's bytes) -------------------------------------------------

CHAIN_PATTERNS = ["hair", "bang", "ahoge", "ear", "tail", "ribbon", "skirt", "antenna", "spring"]
CHAIN_EXCLUDES = ["forearm"]
EXPECTED_CHAINS = {"ahoge_0": 5, "bang_L_0": 5, "bang_C_0": 5, "bang_R_0": 5,
                   "hair_side_L_0": 6, "hair_side_R_0": 6, "tail_0": 8}
EXPECTED_CLIPS = {"idle": 4.0, "walk": 1.0, "turn": 3.0}
BODY_JOINTS = {name for name, _, _ in BODY}


def parse_glb(data):
    magic, version, total = struct.unpack_from("<4sII", data, 0)
    assert magic == b"glTF" and version == 2 and total == len(data), "bad GLB header"
    jlen, jtype = struct.unpack_from("<I4s", data, 12)
    assert jtype == b"JSON"
    doc = json.loads(data[20:20 + jlen].decode("ascii"))
    blen, btype = struct.unpack_from("<I4s", data, 20 + jlen)
    assert btype == b"BIN\0"
    return doc, data[28 + jlen:28 + jlen + blen]


def read_accessor(doc, binary, i):
    acc = doc["accessors"][i]
    view = doc["bufferViews"][acc["bufferView"]]
    width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4, "MAT4": 16}[acc["type"]]
    fmt = {FLOAT: "f", UBYTE: "B", USHORT: "H", UINT: "I"}[acc["componentType"]]
    flat = struct.unpack_from("<%d%s" % (acc["count"] * width, fmt), binary,
                              view["byteOffset"] + acc.get("byteOffset", 0))
    return [flat[k:k + width] if width > 1 else flat[k] for k in range(0, len(flat), width)]


def node_worlds(doc):
    """Every node's world matrix from its translation and rotation (the generators write no
    scale or matrix), and each node's parent; asserts the nodes form trees."""
    nodes = doc["nodes"]
    parent = {}
    for i, n in enumerate(nodes):
        for c in n.get("children", []):
            assert c not in parent, "node %d has two parents" % c
            parent[c] = i
    world = [None] * len(nodes)

    def world_of(i):
        if world[i] is None:
            n = nodes[i]
            assert "scale" not in n and "matrix" not in n, "node %s has a scale or matrix" % n.get("name")
            local = mat_trs(n.get("translation", (0.0, 0.0, 0.0)), n.get("rotation", IDENTITY_Q))
            world[i] = local if i not in parent else mat_mul(world_of(parent[i]), local)
        return world[i]

    for i in range(len(nodes)):
        world_of(i)
    return world, parent


def verify(data):
    """Checks the file's bytes; returns a summary dict, raises AssertionError on a defect."""
    doc, binary = parse_glb(data)
    nodes = doc["nodes"]
    world, parent = node_worlds(doc)

    def world_of(i):
        return world[i]

    skin = doc["skins"][0]
    joints = skin["joints"]
    ibms = read_accessor(doc, binary, skin["inverseBindMatrices"])
    worst = 0.0
    for j, ibm in zip(joints, ibms):
        m = [[ibm[c * 4 + r] for c in range(4)] for r in range(4)]
        prod = mat_mul(m, world_of(j))
        worst = max(worst, max(abs(prod[r][c] - (1.0 if r == c else 0.0)) for r in range(4) for c in range(4)))
    assert worst <= 1e-6, "inverse bind matrix x rest world matrix is off identity by %g" % worst

    names = [n.get("name", "") for n in nodes]
    pos = [(world_of(j)[0][3], world_of(j)[1][3], world_of(j)[2][3]) for j in joints]
    for j in joints:  # consecutive joints at least 1 cm apart
        if j in parent and parent[j] in joints:
            d = length(sub(pos[joints.index(j)], pos[joints.index(parent[j])]))
            assert d >= 0.01, "%s is %.4f m from its parent" % (names[j], d)

    # The chain finder's walk (engine/gltf/chains.cpp): roots in parent-first order whose
    # name contains a pattern, down single-child nodes.
    order, stack = [], [r for r in doc["scenes"][0]["nodes"]]
    while stack:
        i = stack.pop(0)
        order.append(i)
        stack = nodes[i].get("children", []) + stack
    claimed, chains = set(), {}
    for i in order:
        low = names[i].lower()
        if i in claimed or not any(p in low for p in CHAIN_PATTERNS) or any(e in low for e in CHAIN_EXCLUDES):
            continue
        strand = [i]
        while len(nodes[strand[-1]].get("children", [])) == 1:
            strand.append(nodes[strand[-1]]["children"][0])
        claimed.update(strand)
        chains[names[i]] = strand
    assert {k: len(v) for k, v in chains.items()} == EXPECTED_CHAINS, "chains found: %r" % chains
    for name, strand in chains.items():
        assert names[parent[strand[0]]] == "head", name
        for k, j in enumerate(strand):  # +Y along the segment
            a, b = (k, k + 1) if k + 1 < len(strand) else (k - 1, k)
            seg = normalize(sub(pos[joints.index(strand[b])], pos[joints.index(strand[a])]))
            w = world_of(j)
            y_axis = normalize((w[0][1], w[1][1], w[2][1]))
            assert dot(y_axis, seg) > 1.0 - 1e-6, "%s: +Y is not along its segment" % names[j]

    vertices = triangles = 0
    for prim in doc["meshes"][0]["primitives"]:
        attrs = prim["attributes"]
        p = read_accessor(doc, binary, attrs["POSITION"])
        nrm = read_accessor(doc, binary, attrs["NORMAL"])
        jnt = read_accessor(doc, binary, attrs["JOINTS_0"])
        wgt = read_accessor(doc, binary, attrs["WEIGHTS_0"])
        idx = read_accessor(doc, binary, prim["indices"])
        acc = doc["accessors"][attrs["POSITION"]]
        assert acc["min"] == [min(v[c] for v in p) for c in range(3)], "POSITION min"
        assert acc["max"] == [max(v[c] for v in p) for c in range(3)], "POSITION max"
        for v in range(len(p)):
            assert abs(length(nrm[v]) - 1.0) < 1e-6, "normal %d not unit" % v
            assert abs(sum(wgt[v]) - 1.0) <= 2e-7, "weights of vertex %d sum to %r" % (v, sum(wgt[v]))
            used = [jj for jj, ww in zip(jnt[v], wgt[v]) if ww != 0.0]
            assert used and len(set(used)) == len(used), "vertex %d influences" % v
            assert all(jj == 0 for jj, ww in zip(jnt[v], wgt[v]) if ww == 0.0)
            assert all(jj < len(joints) for jj in jnt[v])
        for t in range(0, len(idx), 3):  # winding: the face normal agrees with the vertex normals
            a, b, c = idx[t:t + 3]
            fn = cross(sub(p[b], p[a]), sub(p[c], p[a]))
            assert length(fn) > 1e-12, "degenerate triangle %d" % (t // 3)
            assert dot(fn, add(add(nrm[a], nrm[b]), nrm[c])) > 0.0, "triangle %d faces inwards" % (t // 3)
        vertices += len(p)
        triangles += len(idx) // 3

    clips = {}
    for anim in doc["animations"]:
        duration = 0.0
        for ch in anim["channels"]:
            target = names[ch["target"]["node"]]
            assert target in BODY_JOINTS, "%s animates %s" % (anim["name"], target)
            s = anim["samplers"][ch["sampler"]]
            times = read_accessor(doc, binary, s["input"])
            values = read_accessor(doc, binary, s["output"])
            assert all(b > a for a, b in zip(times, times[1:])) and times[0] == 0.0
            if s["interpolation"] == "CUBICSPLINE":
                assert len(values) == 3 * len(times)
                keys = values[1::3]
            else:
                keys = values
            assert keys[0] == keys[-1], "%s/%s does not loop" % (anim["name"], target)
            if ch["target"]["path"] == "rotation":
                assert all(abs(math.sqrt(sum(c * c for c in q)) - 1.0) < 1e-6 for q in keys)
            duration = max(duration, times[-1])
        clips[anim["name"]] = duration
    assert clips == EXPECTED_CLIPS, clips
    samplers = sorted({s["interpolation"] for a in doc["animations"] for s in a["samplers"]})
    assert samplers == ["CUBICSPLINE", "LINEAR", "STEP"], samplers
    return {"joints": len(joints), "vertices": vertices, "triangles": triangles, "bytes": len(data),
            "chains": {k: len(v) for k, v in chains.items()}, "clips": clips, "ibm_error": worst}


def main(argv):
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default=os.path.join(here, "chibi.glb"),
                        help="output path (default: chibi.glb next to this script)")
    parser.add_argument("--check", action="store_true", help="only verify the file at --out")
    args = parser.parse_args(argv)

    if args.check:
        with open(args.out, "rb") as f:
            data = f.read()
    else:
        data = to_glb(*build_document())
    summary = verify(data)
    if not args.check:
        directory = os.path.dirname(os.path.abspath(args.out))
        fd, tmp = tempfile.mkstemp(prefix=os.path.basename(args.out) + ".tmp-", dir=directory)
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(data)
            os.chmod(tmp, 0o644)
            os.replace(tmp, args.out)
        except BaseException:
            if os.path.exists(tmp):
                os.remove(tmp)
            raise
    print("%s %s: %d joints, %d vertices, %d triangles, %d bytes; IBM x world - I <= %.2g" % (
        "checked" if args.check else "wrote", args.out, summary["joints"], summary["vertices"],
        summary["triangles"], summary["bytes"], summary["ibm_error"]))
    print("  chains: " + ", ".join("%s (%d)" % kv for kv in summary["chains"].items()))
    print("  clips: " + ", ".join("%s %.3g s" % kv for kv in summary["clips"].items()))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
