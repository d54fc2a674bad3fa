#!/usr/bin/env python3
"""Writes Kodawari's own VRoid-class test avatar (VRM 1.0 and VRM 0.x) and three VRM Animation clips.

    python3 scenes/characters/make_avatar.py                  # generate, verify, write the five files
    python3 scenes/characters/make_avatar.py --out-dir DIR    # the same five files, flat into DIR
    python3 scenes/characters/make_avatar.py --check          # verify the committed files only
    python3 scenes/characters/make_avatar.py --variant NAME --out FILE   # one bad-input file

Files (paths relative to the repository root):

- scenes/characters/avatar.vrm: a VRM 1.0 avatar (GLB with VRMC_vrm and VRMC_springBone 1.0),
  structured as VRoid Studio exports one: a `Root` node above `J_Bip_C_Hips`, humanoid bones
  named J_Bip_* / J_Adj_*, spring joints J_Sec_*, every node with identity rotation (a
  T-pose facing +Z, +Y up, metres, 1.48 m to the top of the hair). 24 hair springs
  (J_Sec_Hair<joint>_<strand>) rooted on J_Bip_C_Head, 6 skirt springs on the hips, 2 bust
  springs on the upper chest; 16 colliders in 4 groups (Head, Body, Arms, Legs); one skinned
  mesh (body capsules, head sphere, hair ribbons and skirt panels skinned along their joints).
- scenes/characters/avatar-vrm0.vrm: the same avatar as VRM 0.x (extensions.VRM), laid out as
  UniVRM 0.x writes it: the model faces -Z in glTF space, collider offsets in Unity's
  left-handed frame (see vrm0_offset below), capsules as runs of spheres.
- scenes/motions/walk.vrma (1.1 s walk cycle in place), scenes/motions/walk-turn.vrma (the
  same walk, 8 cycles = 8.8 s, travelling once round a circle of radius 1.681 m at 1.2 m/s
  with the hips translating and turning along it: root motion that closes the loop) and
  scenes/motions/idle.vrma (4 s breathing, sway, head turn): VRMC_vrm_animation 1.0 on a
  skeleton of its own -- a taller,
  longer-legged rig named like a motion-capture export ("mocap:Hips", ...), whose rest
  rotations are NOT identity (bones point along their local +Y), so that a reader has to
  retarget (normalise the rotations, scale the hips translation by 0.78 / 1.00).

Variants (--variant NAME --out FILE), for the bad-input tests; each is a good file with
one defect:

  vrma-no-humanoid     walk.vrma whose VRMC_vrm_animation.humanoid.humanBones is empty ({})
  vrma-jaw             walk.vrma with a `jaw` humanoid bone (a node under the head, animated)
                       that the avatar does not have
  vrma-missing-node    walk.vrma whose humanBones.hips.node names a node past the last one
  vrm-missing-collider avatar.vrm whose "Head" collider group lists a collider index that
                       does not exist (one past the last collider)
  vrm-zero-plane       avatar.vrm whose first head collider carries the extended collider
                       VRMC_springBone_extended_collider with shape.plane.normal [0, 0, 0]

Deterministic (no time stamps, no randomness, JSON in a fixed order, numbers rounded or
stored as float32): the same command gives the same bytes. Files are written atomically,
after their bytes have been parsed back and checked (see verify_avatar, verify_vrma).
Standard library only; the glTF, quaternion and mesh helpers are the character generator's
(make_chibi.py). Everything here is the project's own work, dedicated to the public domain
(CC0 1.0): no third-party asset or code.
"""
import argparse
import math
import os
import sys
import tempfile

# The vector/quaternion helpers, the mesh builders and the glTF buffer and GLB writers of the
# project's character generator, so that both generators write glTF the same way.
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from make_chibi import (  # noqa: E402
    ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER, FLOAT, IDENTITY_Q, UBYTE, USHORT, X_AXIS, Y_AXIS, Z_AXIS,
    Gltf, Primitive, add, capsule, catmull_rom, clean, cross, dot, ellipsoid, ladder_weights, lathe, length, mat_inverse, mat_mul, mat_trs,
    node_worlds, normalize, parse_glb, q_axis_angle, q_conj, q_euler, q_mul, q_normalize, q_rotate, q_shortest_arc,
    read_accessor, scale, strand_samples, sub, to_glb, world_matrices)

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
OUTPUTS = [  # (file name, path in the repository)
    ("avatar.vrm", os.path.join("scenes", "characters", "avatar.vrm")),
    ("avatar-vrm0.vrm", os.path.join("scenes", "characters", "avatar-vrm0.vrm")),
    ("walk.vrma", os.path.join("scenes", "motions", "walk.vrma")),
    ("walk-turn.vrma", os.path.join("scenes", "motions", "walk-turn.vrma")),
    ("idle.vrma", os.path.join("scenes", "motions", "idle.vrma")),
]
VARIANTS = ["vrma-no-humanoid", "vrma-jaw", "vrma-missing-node", "vrm-missing-collider", "vrm-zero-plane"]
LICENSE_NOTE = "CC0 1.0: Kodawari's own test avatar, dedicated to the public domain"
CC0_URL = "https://creativecommons.org/publicdomain/zero/1.0/"

# --- the avatar's skeleton (VRM 1.0 frame: +Z forward, +X the avatar's left, +Y up) -------------

HEAD = (0.0, 1.26, 0.0)
HEAD_CENTER = (0.0, 0.10, 0.005)  # head sphere centre, in the head joint's frame
HEAD_R = 0.11


def mirror(p):
    return (-p[0], p[1], p[2])


def body_design():
    """[(name, parent, world position)]: the humanoid skeleton, parents first."""
    b = [
        ("Root", None, (0.0, 0.0, 0.0)),
        ("J_Bip_C_Hips", "Root", (0.0, 0.78, 0.0)),
        ("J_Bip_C_Spine", "J_Bip_C_Hips", (0.0, 0.86, 0.0)),
        ("J_Bip_C_Chest", "J_Bip_C_Spine", (0.0, 0.96, 0.0)),
        ("J_Bip_C_UpperChest", "J_Bip_C_Chest", (0.0, 1.06, 0.0)),
        ("J_Bip_C_Neck", "J_Bip_C_UpperChest", (0.0, 1.20, 0.0)),
        ("J_Bip_C_Head", "J_Bip_C_Neck", HEAD),
    ]
    for side, f in (("L", lambda p: p), ("R", mirror)):
        eye = add(add(HEAD, HEAD_CENTER), scale(head_dir(98.0, 20.0), 0.07))
        b.append(("J_Adj_%s_FaceEye" % side, "J_Bip_C_Head", f(eye)))
    for side, f in (("L", lambda p: p), ("R", mirror)):
        s = "J_Bip_%s_" % side
        b += [
            (s + "Shoulder", "J_Bip_C_UpperChest", f((0.02, 1.17, 0.0))),
            (s + "UpperArm", s + "Shoulder", f((0.09, 1.17, 0.0))),
            (s + "LowerArm", s + "UpperArm", f((0.33, 1.17, 0.0))),
            (s + "Hand", s + "LowerArm", f((0.55, 1.17, 0.0))),
            (s + "Thumb1", s + "Hand", f((0.57, 1.165, 0.025))),
            (s + "Thumb2", s + "Thumb1", f((0.595, 1.165, 0.05))),
            (s + "Thumb3", s + "Thumb2", f((0.615, 1.165, 0.07))),
            (s + "Index1", s + "Hand", f((0.635, 1.17, 0.02))),
            (s + "Index2", s + "Index1", f((0.67, 1.17, 0.02))),
            (s + "Index3", s + "Index2", f((0.695, 1.17, 0.02))),
        ]
    for side, f in (("L", lambda p: p), ("R", mirror)):
        s = "J_Bip_%s_" % side
        b += [
            (s + "UpperLeg", "J_Bip_C_Hips", f((0.075, 0.74, 0.0))),
            (s + "LowerLeg", s + "UpperLeg", f((0.075, 0.41, 0.0))),
            (s + "Foot", s + "LowerLeg", f((0.075, 0.07, 0.0))),
            (s + "ToeBase", s + "Foot", f((0.075, 0.035, 0.10))),
        ]
    return b


# VRM 1.0 humanoid bone -> node name. VRM 0.x uses the same names except for the thumb
# (THUMB_0X below).
HUMANOID = {
    "hips": "J_Bip_C_Hips", "spine": "J_Bip_C_Spine", "chest": "J_Bip_C_Chest",
    "upperChest": "J_Bip_C_UpperChest", "neck": "J_Bip_C_Neck", "head": "J_Bip_C_Head",
    "leftEye": "J_Adj_L_FaceEye", "rightEye": "J_Adj_R_FaceEye",
}
for _side, _s in (("left", "L"), ("right", "R")):
    for _bone, _node in (("Shoulder", "Shoulder"), ("UpperArm", "UpperArm"), ("LowerArm", "LowerArm"),
                         ("Hand", "Hand"), ("UpperLeg", "UpperLeg"), ("LowerLeg", "LowerLeg"), ("Foot", "Foot"),
                         ("Toes", "ToeBase"), ("ThumbMetacarpal", "Thumb1"), ("ThumbProximal", "Thumb2"),
                         ("ThumbDistal", "Thumb3"), ("IndexProximal", "Index1"), ("IndexIntermediate", "Index2"),
                         ("IndexDistal", "Index3")):
        HUMANOID[_side + _bone] = "J_Bip_%s_%s" % (_s, _node)
# VRM 1.0 renamed the thumb's bones (metacarpal, proximal, distal were proximal,
# intermediate, distal in VRM 0.x).
THUMB_0X = {"ThumbMetacarpal": "ThumbProximal", "ThumbProximal": "ThumbIntermediate", "ThumbDistal": "ThumbDistal"}


def vrm0_bone_name(bone):
    for side in ("left", "right"):
        if bone.startswith(side) and bone[len(side):] in THUMB_0X:
            return side + THUMB_0X[bone[len(side):]]
    return bone


def head_dir(theta, phi):
    """Unit vector from the head centre at polar angle theta from +Y and azimuth phi (0 = the
    face, +90 = the avatar's left, 180 = the back); degrees."""
    t, p = math.radians(theta), math.radians(phi)
    return (math.sin(t) * math.sin(p), math.cos(t), math.sin(t) * math.cos(p))


def on_head(theta, phi, lift):
    """A point `lift` m outside the head sphere, in the head joint's frame."""
    return add(HEAD_CENTER, scale(head_dir(theta, phi), HEAD_R + lift))


# --- colliders (VRMC_springBone 1.0 shapes; offsets in their node's frame) -----------------------
# Every node has identity rotation, so offsets are also world directions (VRM 1.0 frame).

GROUPS = ["Head", "Body", "Arms", "Legs"]


def colliders_design():
    """[{node, group, shape, offset, tail, radius}] in file order: the head's first."""
    c = []
    for offset, radius in (((0.0, 0.105, -0.005), 0.095),   # cranium
                           ((0.0, 0.085, 0.035), 0.08),      # forehead and face
                           ((0.0, 0.09, -0.04), 0.07),       # back of the head
                           ((0.035, 0.085, -0.005), 0.075),  # left temple
                           ((-0.035, 0.085, -0.005), 0.075),  # right temple
                           ((0.0, 0.03, 0.025), 0.055)):     # jaw
        c.append({"node": "J_Bip_C_Head", "group": "Head", "shape": "sphere", "offset": offset, "radius": radius})
    c.append({"node": "J_Bip_C_Neck", "group": "Body", "shape": "sphere", "offset": (0.0, 0.03, 0.0), "radius": 0.05})
    c.append({"node": "J_Bip_C_UpperChest", "group": "Body", "shape": "capsule", "offset": (0.0, 0.0, -0.01),
              "tail": (0.0, 0.10, -0.01), "radius": 0.09})
    for side, f in (("L", lambda p: p), ("R", mirror)):
        c.append({"node": "J_Bip_%s_UpperArm" % side, "group": "Arms", "shape": "capsule", "offset": f((0.01, 0.0, 0.0)),
                  "tail": f((0.22, 0.0, 0.0)), "radius": 0.04})
        c.append({"node": "J_Bip_%s_LowerArm" % side, "group": "Arms", "shape": "capsule", "offset": f((0.01, 0.0, 0.0)),
                  "tail": f((0.20, 0.0, 0.0)), "radius": 0.035})
    for side, f in (("L", lambda p: p), ("R", mirror)):
        c.append({"node": "J_Bip_%s_Hand" % side, "group": "Arms", "shape": "sphere", "offset": f((0.05, 0.0, 0.0)),
                  "radius": 0.045})
    for side, f in (("L", lambda p: p), ("R", mirror)):
        c.append({"node": "J_Bip_%s_UpperLeg" % side, "group": "Legs", "shape": "capsule", "offset": (0.0, -0.02, 0.0),
                  "tail": (0.0, -0.29, 0.0), "radius": 0.07})
    for x in c:
        x.setdefault("tail", x["offset"])
    return c


# --- springs --------------------------------------------------------------------------------------
# Per part: VRoid-like defaults. Hair: stiffness about 1, a little gravity, drag 0.4,
# hitRadius 2 cm; per joint, the stiffness eases off and the gravity grows towards the tip
# (VRM 1.0 keeps per-joint values; VRM 0.x keeps one set per bone group: the base values).
PARTS = {  # part: (base stiffness, gravityPower, dragForce, hitRadius, collider groups, comment)
    "hair_front": (1.2, 0.05, 0.4, 0.02, ["Head", "Body"], "Hair front"),
    "hair_side": (1.0, 0.1, 0.4, 0.02, ["Head", "Body"], "Hair side"),
    "hair_back": (0.8, 0.2, 0.4, 0.02, ["Head", "Body"], "Hair back"),
    "bust": (0.5, 0.0, 0.3, 0.03, ["Body", "Arms"], "Bust"),
    "skirt": (0.8, 0.1, 0.5, 0.025, ["Legs"], "Skirt"),
}
CENTER_SPRING = "J_Sec_L_SkirtBack0_01"  # the one spring with a `center` (the hips)
HAIR_MARGIN = 0.004  # hair joints at rest lie this much beyond radius + hitRadius of every head sphere


def hair_strands():
    """[(part, [joint positions in the head joint's frame])]: 24 strands, in VRoid's order of
    strand numbers (01 = the first)."""
    strands = []
    # Front bangs: from the top of the forehead down over it to the brows, 4 joints.
    for phi in (-48.0, -32.0, -16.0, 0.0, 16.0, 32.0, 48.0):
        strands.append(("hair_front", [on_head(22.0 + 20.0 * k, phi * (1.0 + 0.08 * k), 0.02 + 0.008 * k)
                                       for k in range(4)]))
    # Side locks: over the temple and the ear, then down beside the cheek to the jaw, 5 joints.
    for sign in (1.0, -1.0):
        for phi in (64.0, 80.0, 96.0):
            p = [on_head(40.0, sign * phi, 0.02), on_head(65.0, sign * phi, 0.022), on_head(90.0, sign * phi, 0.026)]
            out = normalize((p[-1][0], 0.0, p[-1][2] - HEAD_CENTER[2]))
            for k in range(2):
                p.append(add(p[-1], add((0.0, -0.055, 0.0), scale(out, 0.004))))
            strands.append(("hair_side", p))
    # Back: over the crown and the back of the head, then down to the shoulder blades, 6 joints.
    for i in range(11):
        phi = 125.0 + 11.0 * i
        p = [on_head(30.0, phi, 0.02), on_head(60.0, phi, 0.024), on_head(95.0, phi, 0.028)]
        out = normalize((p[-1][0], 0.0, p[-1][2] - HEAD_CENTER[2]))
        for k in range(3):
            p.append(add(p[-1], add((0.0, -0.065, 0.0), scale(out, 0.012))))
        strands.append(("hair_back", p))
    return strands


def hair_name(joint, strand):
    """VRoid's hair joint names: J_Sec_Hair<joint, from 1>_<strand, two digits>."""
    return "J_Sec_Hair%d_%02d" % (joint + 1, strand + 1)


# Skirt: 6 strands of 4 joints from the waist down (azimuth from +Z towards +X).
SKIRT_LEVELS = [(0.84, 0.13), (0.74, 0.175), (0.64, 0.215), (0.54, 0.25)]  # (y, radius)
SKIRT_STRANDS = [("R", "Back", -150.0), ("R", "Side", -90.0), ("R", "Front", -30.0),
                 ("L", "Front", 30.0), ("L", "Side", 90.0), ("L", "Back", 150.0)]


def skirt_name(side, part, k):
    return "J_Sec_%s_Skirt%s%d_01" % (side, part, k)


def skirt_point(azimuth, y, r):
    a = math.radians(azimuth)
    return (r * math.sin(a), y, r * math.cos(a))


def bust_points(side):
    f = (lambda p: p) if side == "L" else mirror
    return [f((0.055, 1.04, 0.06)), f((0.055, 1.035, 0.125))]


def push_clear(point, spheres, hit):
    """Moves `point` (world) radially out of the head until it clears every sphere (world
    centre, radius) by radius + hit + HAIR_MARGIN."""
    center = add(HEAD, HEAD_CENTER)
    for _ in range(200):
        worst = min(length(sub(point, c)) - r - hit for c, r in spheres)
        if worst > HAIR_MARGIN:
            return point
        point = add(point, scale(normalize(sub(point, center)), 0.001))
    raise AssertionError("could not clear a hair joint of the head colliders")


def skeleton_design():
    """(design, springs): design = [(name, parent, world position)], parents first; springs =
    [{name, part, joints: [node names]}] in file order."""
    design = body_design()
    springs = []
    head_spheres = [(add(HEAD, c["offset"]), c["radius"]) for c in colliders_design() if c["group"] == "Head"]
    for s, (part, pts) in enumerate(hair_strands()):
        hit = PARTS[part][3]
        names = []
        for k, p in enumerate(pts):
            world = push_clear(add(HEAD, p), head_spheres, hit)
            names.append(hair_name(k, s))
            design.append((names[-1], "J_Bip_C_Head" if k == 0 else names[-2], world))
        springs.append({"name": names[0], "part": part, "joints": names})
    for side in ("L", "R"):
        pts = bust_points(side)
        names = ["J_Sec_%s_Bust1" % side, "J_Sec_%s_Bust2" % side]
        design += [(names[0], "J_Bip_C_UpperChest", pts[0]), (names[1], names[0], pts[1])]
        springs.append({"name": names[0], "part": "bust", "joints": names})
    for side, part, azimuth in SKIRT_STRANDS:
        names = [skirt_name(side, part, k) for k in range(len(SKIRT_LEVELS))]
        for k, (y, r) in enumerate(SKIRT_LEVELS):
            design.append((names[k], "J_Bip_C_Hips" if k == 0 else names[k - 1], skirt_point(azimuth, y, r)))
        springs.append({"name": names[0], "part": "skirt", "joints": names})
    return design, springs


def joint_settings(part, k, n):
    """Per-joint VRMC_springBone settings of joint k of n."""
    stiffness, gravity, drag, hit = PARTS[part][:4]
    f = k / (n - 1)
    return {"hitRadius": hit, "stiffness": round(stiffness * (1.0 - 0.2 * f), 4),
            "gravityPower": round(gravity * (1.0 + 0.5 * f), 4), "gravityDir": [0.0, -1.0, 0.0], "dragForce": drag}


def build_nodes(design, flip):
    """Nodes {name, parent, t, r} (translations rounded to 1e-7 m, identity rotations). `flip`:
    VRM 0.x's frame, the VRM 1.0 model turned half a turn about +Y ((x, y, z) -> (-x, y, -z))."""
    by_name = {d[0]: d for d in design}
    nodes = []
    for name, parent, pos in design:
        t = pos if parent is None else sub(pos, by_name[parent][2])
        if flip:
            t = (-t[0], t[1], -t[2])
        nodes.append({"name": name, "parent": parent, "t": tuple(clean(c, 7) for c in t), "r": IDENTITY_Q})
    return nodes


# --- the mesh -----------------------------------------------------------------------------------

MATERIALS = [  # name, linear base colour, double sided
    ("skin", (0.95, 0.74, 0.64), False),
    ("hair", (0.55, 0.33, 0.62), True),
    ("clothes", (0.18, 0.24, 0.5), True),
    ("eyes", (0.08, 0.1, 0.25), False),
]


def ribbon(prim, joints, pts, w_root, w_tip, center, per_segment=4):
    """A flat strip along a Catmull-Rom curve through the joint positions `pts` (world), facing
    away from `center`, its width tapering from w_root to w_tip. A vertex pair at fraction f
    of segment i is weighted (1 - f) to joint i and f to joint i + 1."""
    n = len(pts)
    samples = strand_samples(pts, joints, per_segment)
    pairs = []
    for k, (pos, t, influences) in enumerate(samples):
        out = normalize(sub(pos, center))
        w = normalize(cross(t, out))
        nrm = cross(w, t)
        half = 0.5 * (w_root + (w_tip - w_root) * k / (len(samples) - 1))
        pairs.append((prim.vertex(sub(pos, scale(w, half)), nrm, influences),
                      prim.vertex(add(pos, scale(w, half)), nrm, influences)))
    for (l0, r0), (l1, r1) in zip(pairs, pairs[1:]):
        prim.indices += [l0, r0, r1, l0, r1, l1]


def skirt_mesh(prim, index, pos, sides=36, per_segment=3):
    """The skirt: a flared cone from the waist to the hem through the skirt joints. A vertex
    between two strands is weighted by angle between them and by height between the two
    joints of its level: up to 4 influences."""
    azimuths = [a for _, _, a in SKIRT_STRANDS]  # ascending, from -150 to 150
    chains = [[index[skirt_name(side, part, k)] for k in range(len(SKIRT_LEVELS))] for side, part, _ in SKIRT_STRANDS]
    levels = []  # (segment, fraction), from the hem up
    for k in range(len(SKIRT_LEVELS) - 1):
        for s in range(per_segment):
            levels.append((k, s / per_segment))
    levels.append((len(SKIRT_LEVELS) - 2, 1.0))
    levels.reverse()
    rings = []
    for k, f in levels:
        (y0, r0), (y1, r1) = SKIRT_LEVELS[k], SKIRT_LEVELS[k + 1]
        y, r = y0 + (y1 - y0) * f, r0 + (r1 - r0) * f
        ring = []
        for i in range(sides):
            a = -180.0 + 360.0 * i / sides
            # The two strands around azimuth a (cyclic) and the fraction between them.
            j = max([m for m in range(len(azimuths)) if azimuths[m] <= a], default=len(azimuths) - 1)
            a0, a1 = azimuths[j], azimuths[(j + 1) % len(azimuths)]
            span = (a1 - a0) % 360.0
            u = ((a - a0) % 360.0) / span
            c0, c1 = chains[j], chains[(j + 1) % len(chains)]
            influences = [(c0[k], (1 - u) * (1 - f)), (c1[k], u * (1 - f)), (c0[k + 1], (1 - u) * f), (c1[k + 1], u * f)]
            radial = (math.sin(math.radians(a)), 0.0, math.cos(math.radians(a)))
            normal = add(scale(radial, y0 - y1), (0.0, r1 - r0, 0.0))
            ring.append(prim.vertex((r * radial[0], y, r * radial[2]), normal, influences))
        rings.append(ring)
    prim.grid(rings)  # open at the waist and the hem; the material is double sided


def build_mesh(nodes, world, springs):
    """The avatar's primitives (skin, hair, clothes, eyes) in the VRM 1.0 frame."""
    index = {n["name"]: i for i, n in enumerate(nodes)}
    pos = {n["name"]: (world[i][0][3], world[i][1][3], world[i][2][3]) for i, n in enumerate(nodes)}
    skin, hair, clothes, eyes = Primitive(0), Primitive(1), Primitive(2), Primitive(3)
    head = [(index["J_Bip_C_Head"], 1.0)]
    head_center = add(pos["J_Bip_C_Head"], HEAD_CENTER)

    ladder = [(pos[n][1], index[n]) for n in ("J_Bip_C_Hips", "J_Bip_C_Spine", "J_Bip_C_Chest", "J_Bip_C_UpperChest",
                                               "J_Bip_C_Neck")]

    def body_weights(y):
        return ladder_weights(ladder, y)

    # Skin: head, neck, arms, hands, fingers, legs, feet.
    ellipsoid(skin, head_center, Z_AXIS, X_AXIS, Y_AXIS, (HEAD_R, HEAD_R, HEAD_R), 14, 24, head)
    neck = pos["J_Bip_C_Neck"]
    capsule(skin, sub(neck, (0.0, 0.03, 0.0)), add(neck, (0.0, 0.08, 0.0)), 0.035, 12,
            [(index["J_Bip_C_Neck"], 1.0)])
    for side in ("L", "R"):
        s = "J_Bip_%s_" % side

        def bone(a, b, r, joint, sides=10):
            capsule(skin, pos[s + a] if isinstance(a, str) else a, pos[s + b] if isinstance(b, str) else b, r, sides,
                    [(index[s + joint], 1.0)])

        bone("Shoulder", "UpperArm", 0.04, "Shoulder")
        bone("UpperArm", "LowerArm", 0.035, "UpperArm")
        bone("LowerArm", "Hand", 0.03, "LowerArm")
        d = normalize(sub(pos[s + "LowerArm"], pos[s + "UpperArm"]))
        ellipsoid(skin, add(pos[s + "Hand"], scale(d, 0.045)), Y_AXIS, cross(d, Y_AXIS), d, (0.014, 0.04, 0.05), 6, 10,
                  [(index[s + "Hand"], 1.0)])
        for finger in ("Thumb", "Index"):
            for k in (1, 2, 3):
                a = pos[s + finger + str(k)]
                b = pos[s + finger + str(k + 1)] if k < 3 else add(a, scale(normalize(sub(a, pos[s + finger + "2"])), 0.02))
                capsule(skin, a, b, 0.009, 6, [(index[s + finger + str(k)], 1.0)], cap_rings=2, body_rings=2)
        bone("UpperLeg", "LowerLeg", 0.06, "UpperLeg", 12)
        bone("LowerLeg", "Foot", 0.045, "LowerLeg", 12)
        bone("Foot", "ToeBase", 0.035, "Foot")
        capsule(skin, pos[s + "ToeBase"], add(pos[s + "ToeBase"], (0.0, 0.0, 0.05)), 0.035, 10,
                [(index[s + "ToeBase"], 1.0)])

    # Hair: a cap on the skull (the head) and one ribbon per hair spring.
    cap_rings, cap_sides = 8, 24
    cap = []
    for k in range(cap_rings):
        ring = []
        for i in range(cap_sides):
            phi = 360.0 * i / cap_sides
            theta_max = 62.0 + 48.0 * (1.0 - math.cos(math.radians(phi))) / 2.0  # lower at the back
            d = head_dir(theta_max * (cap_rings - k) / cap_rings, phi)
            ring.append(hair.vertex(add(head_center, scale(d, HEAD_R + 0.008)), d, head))
        cap.append(ring)
    hair.grid(cap, None, hair.vertex(add(head_center, (0.0, HEAD_R + 0.008, 0.0)), Y_AXIS, head))
    widths = {"hair_front": (0.045, 0.01), "hair_side": (0.04, 0.01), "hair_back": (0.05, 0.014)}
    for spring in springs:
        if spring["part"] in widths:
            w0, w1 = widths[spring["part"]]
            ribbon(hair, [index[j] for j in spring["joints"]], [pos[j] for j in spring["joints"]], w0, w1, head_center)

    # Clothes: the torso (a lathed body from the crotch to the collar), the skirt, the bust.
    profile = [(0.68, 0.0), (0.69, 0.06), (0.72, 0.112), (0.78, 0.125), (0.86, 0.118), (0.92, 0.105),
               (0.98, 0.108), (1.04, 0.115), (1.10, 0.115), (1.15, 0.105), (1.19, 0.08), (1.22, 0.045), (1.235, 0.0)]
    lathe(clothes, profile, 24, body_weights)
    skirt_mesh(clothes, index, pos)
    for side in ("L", "R"):
        a, b = pos["J_Sec_%s_Bust1" % side], pos["J_Sec_%s_Bust2" % side]
        d = normalize(sub(b, a))
        ellipsoid(clothes, add(a, scale(sub(b, a), 0.55)), X_AXIS, cross(d, X_AXIS), d, (0.045, 0.042, 0.04), 8, 12,
                  [(index["J_Sec_%s_Bust1" % side], 1.0)])

    # Eyes: flat ellipsoids on the face, each on its eye joint.
    for side, phi in (("L", 20.0), ("R", -20.0)):
        n = head_dir(98.0, phi)
        up = normalize(sub(Y_AXIS, scale(n, dot(Y_AXIS, n))))
        ellipsoid(eyes, add(head_center, scale(n, HEAD_R - 0.002)), up, cross(n, up), n, (0.022, 0.016, 0.006), 6, 12,
                  [(index["J_Adj_%s_FaceEye" % side], 1.0)])
    return [skin, hair, clothes, eyes]


# --- VRM documents -------------------------------------------------------------------------------


def vec(v, digits=6):
    return [clean(c, digits) for c in v]


def vrm0_offset(offset):
    """A collider offset of the VRM 1.0 model as UniVRM 0.x writes it. UniVRM 0.x exports the
    Unity scene (left-handed, the model facing +Z) by negating z of every node translation and
    vertex, so the model faces -Z in glTF space: glTF-0 = (-x, y, -z) of VRM 1.0's glTF space.
    But it writes VRMSpringBoneColliderGroup offsets as Unity's local vectors, unconverted
    (VRMSpringUtility.ExportSecondary: `offset = x.Offset`), i.e. with z negated against
    glTF-0 space; readers negate z back (three-vrm's VRMSpringBoneLoaderPlugin: "z is opposite
    in VRM0.0"; engine/gltf/vrm.cpp). So the JSON holds (-x, y, z) of the VRM 1.0 offset."""
    return {"x": clean(-offset[0], 6), "y": clean(offset[1], 6), "z": clean(offset[2], 6)}


META_NAME = "Kodawari test avatar"
META_VERSION = "1.0"
AUTHOR = "Kodawari project"


def vrm1_extensions(node_index, springs, colliders, variant):
    humanoid = {bone: {"node": node_index[node]} for bone, node in HUMANOID.items()}
    vrm = {
        "specVersion": "1.0",
        "meta": {
            "name": META_NAME, "version": META_VERSION, "authors": [AUTHOR],
            "copyrightInformation": LICENSE_NOTE,
            "licenseUrl": "https://vrm.dev/licenses/1.0/",
            "avatarPermission": "everyone",
            "allowExcessivelyViolentUsage": True, "allowExcessivelySexualUsage": True,
            "commercialUsage": "corporation",
            "allowPoliticalOrReligiousUsage": True, "allowAntisocialOrHateUsage": True,
            "creditNotation": "unnecessary", "allowRedistribution": True,
            "modification": "allowModificationRedistribution",
            "otherLicenseUrl": CC0_URL,
        },
        "humanoid": {"humanBones": humanoid},
        "lookAt": {
            "type": "bone", "offsetFromHeadBone": [0.0, 0.085, 0.09],
            "rangeMapHorizontalInner": {"inputMaxValue": 90.0, "outputScale": 10.0},
            "rangeMapHorizontalOuter": {"inputMaxValue": 90.0, "outputScale": 10.0},
            "rangeMapVerticalDown": {"inputMaxValue": 90.0, "outputScale": 10.0},
            "rangeMapVerticalUp": {"inputMaxValue": 90.0, "outputScale": 10.0},
        },
        "firstPerson": {"meshAnnotations": [{"node": node_index["Avatar"], "type": "auto"}]},
    }
    out_colliders = []
    for c in colliders:
        shape = ({"sphere": {"offset": vec(c["offset"]), "radius": c["radius"]}} if c["shape"] == "sphere" else
                 {"capsule": {"offset": vec(c["offset"]), "radius": c["radius"], "tail": vec(c["tail"])}})
        out_colliders.append({"node": node_index[c["node"]], "shape": shape})
    groups = [{"name": g, "colliders": [i for i, c in enumerate(colliders) if c["group"] == g]} for g in GROUPS]
    out_springs = []
    for s in springs:
        n = len(s["joints"])
        joints = [dict({"node": node_index[j]}, **joint_settings(s["part"], k, n)) for k, j in enumerate(s["joints"])]
        spring = {"name": s["name"], "joints": joints,
                  "colliderGroups": [GROUPS.index(g) for g in PARTS[s["part"]][4]]}
        if s["name"] == CENTER_SPRING:
            spring["center"] = node_index["J_Bip_C_Hips"]
        out_springs.append(spring)
    used = ["VRMC_springBone", "VRMC_vrm"]
    if variant == "vrm-missing-collider":
        groups[0]["colliders"].append(len(out_colliders))
    if variant == "vrm-zero-plane":
        out_colliders[0]["extensions"] = {"VRMC_springBone_extended_collider": {
            "specVersion": "1.0", "shape": {"plane": {"offset": vec(colliders[0]["offset"]), "normal": [0.0, 0.0, 0.0]}}}}
        used = ["VRMC_springBone", "VRMC_springBone_extended_collider", "VRMC_vrm"]
    spring_bone = {"specVersion": "1.0", "colliders": out_colliders, "colliderGroups": groups, "springs": out_springs}
    return {"VRMC_vrm": vrm, "VRMC_springBone": spring_bone}, used


def vrm0_extensions(node_index, springs, colliders, materials):
    """extensions.VRM (VRM 0.x) for the same avatar: per-node collider groups of spheres
    (a capsule becomes spheres at its ends and its middle), one bone group per part with
    its roots, the skirt spring with a center in a group of its own."""
    humanoid = [{"bone": vrm0_bone_name(bone), "node": node_index[node], "useDefaultValues": True}
                for bone, node in HUMANOID.items()]
    collider_groups, groups_of = [], {}
    for c in colliders:
        if c["node"] not in groups_of:
            groups_of[c["node"]] = len(collider_groups)
            collider_groups.append({"node": node_index[c["node"]], "colliders": []})
        spheres = [c["offset"]] if c["shape"] == "sphere" else [
            c["offset"], scale(add(c["offset"], c["tail"]), 0.5), c["tail"]]
        for o in spheres:
            collider_groups[groups_of[c["node"]]]["colliders"].append({"offset": vrm0_offset(o), "radius": c["radius"]})
    group_nodes = {g: [] for g in GROUPS}
    for c in colliders:
        if groups_of[c["node"]] not in group_nodes[c["group"]]:
            group_nodes[c["group"]].append(groups_of[c["node"]])
    bone_groups = []
    for part in ("hair_front", "hair_side", "hair_back", "bust", "skirt", "center"):
        members = [s for s in springs if (s["name"] == CENTER_SPRING) == (part == "center") and
                   (part == "center" or s["part"] == part)]
        p = PARTS["skirt" if part == "center" else part]
        bone_groups.append({
            "comment": p[5] + (" (back left, in the hips' frame)" if part == "center" else ""),
            "stiffiness": p[0], "gravityPower": p[1], "gravityDir": {"x": 0.0, "y": -1.0, "z": 0.0},
            "dragForce": p[2], "center": node_index["J_Bip_C_Hips"] if part == "center" else -1, "hitRadius": p[3],
            "bones": [node_index[s["joints"][0]] for s in members],
            "colliderGroups": [i for g in p[4] for i in group_nodes[g]],
        })
    return {"VRM": {
        "exporterVersion": "Kodawari-make_avatar-1.0",
        "specVersion": "0.0",
        "meta": {
            "title": META_NAME, "version": META_VERSION, "author": AUTHOR, "contactInformation": "",
            "reference": LICENSE_NOTE, "texture": -1,
            "allowedUserName": "Everyone", "violentUssageName": "Allow", "sexualUssageName": "Allow",
            "commercialUssageName": "Allow", "otherPermissionUrl": "", "licenseName": "CC0", "otherLicenseUrl": CC0_URL,
        },
        "humanoid": {"humanBones": humanoid, "armStretch": 0.05, "legStretch": 0.05, "upperArmTwist": 0.5,
                     "lowerArmTwist": 0.5, "upperLegTwist": 0.5, "lowerLegTwist": 0.5, "feetSpacing": 0.0,
                     "hasTranslationDoF": False},
        "firstPerson": {"firstPersonBone": node_index["J_Bip_C_Head"],
                        "firstPersonBoneOffset": {"x": 0.0, "y": 0.085, "z": 0.09},
                        "meshAnnotations": [{"mesh": 0, "firstPersonFlag": "Auto"}], "lookAtTypeName": "Bone"},
        "blendShapeMaster": {"blendShapeGroups": []},
        "secondaryAnimation": {"boneGroups": bone_groups, "colliderGroups": collider_groups},
        "materialProperties": [{"name": name, "shader": "VRM_USE_GLTFSHADER", "renderQueue": 2000, "floatProperties": {},
                                "vectorProperties": {}, "textureProperties": {}, "keywordMap": {}, "tagMap": {}}
                               for name, _, _ in materials],
    }}


def build_avatar(version=1, variant=None):
    """The avatar's GLB bytes: VRM 1.0 (version 1) or VRM 0.x (version 0)."""
    design, springs = skeleton_design()
    colliders = colliders_design()
    nodes = build_nodes(design, flip=(version == 0))
    world1 = world_matrices(build_nodes(design, flip=False))
    prims = build_mesh(build_nodes(design, flip=False), world1, springs)
    world = world_matrices(nodes)
    g = Gltf()

    def frame(v):  # the VRM 1.0 frame into the file's
        return (-v[0], v[1], -v[2]) if version == 0 else v

    gltf_prims = []
    for p in prims:
        assert len(p.positions) < 65536
        attributes = {
            "POSITION": g.accessor("f", [frame(v) for v in p.positions], FLOAT, "VEC3", ARRAY_BUFFER, bounds=True),
            "NORMAL": g.accessor("f", [frame(v) for v in p.normals], FLOAT, "VEC3", ARRAY_BUFFER),
            "JOINTS_0": g.accessor("B", p.joints, UBYTE, "VEC4", ARRAY_BUFFER),
            "WEIGHTS_0": g.accessor("f", p.weights, FLOAT, "VEC4", ARRAY_BUFFER),
        }
        gltf_prims.append({"attributes": attributes, "indices": g.accessor("H", p.indices, USHORT, "SCALAR",
                                                                           ELEMENT_ARRAY_BUFFER),
                           "material": p.material, "mode": 4})
    ibms = []
    for m in world:
        inv = mat_inverse(m)
        inv[3] = [0.0, 0.0, 0.0, 1.0]
        ibms.append(tuple(inv[r][c] + 0.0 for c in range(4) for r in range(4)))
    ibm_accessor = g.accessor("f", ibms, FLOAT, "MAT4")

    gltf_nodes = []
    for n in nodes:
        node = {"name": n["name"]}
        children = [j for j, c in enumerate(nodes) if c["parent"] == n["name"]]
        if children:
            node["children"] = children
        if n["t"] != (0.0, 0.0, 0.0):
            node["translation"] = list(n["t"])
        gltf_nodes.append(node)
    node_index = {n["name"]: i for i, n in enumerate(nodes)}
    node_index["Avatar"] = len(gltf_nodes)
    gltf_nodes.append({"name": "Avatar", "mesh": 0, "skin": 0})
    scene_nodes = [node_index["Root"], node_index["Avatar"]]
    if version == 0:  # UniVRM 0.x keeps its VRMSpringBone components on an empty node, "secondary"
        node_index["secondary"] = len(gltf_nodes)
        gltf_nodes.append({"name": "secondary"})
        scene_nodes.append(node_index["secondary"])

    materials = [{"name": name, "pbrMetallicRoughness": {"baseColorFactor": list(color) + [1.0], "metallicFactor": 0.0,
                                                         "roughnessFactor": 0.85}, "doubleSided": double}
                 for name, color, double in MATERIALS]
    for m in materials:
        if not m["doubleSided"]:
            del m["doubleSided"]
    if version == 1:
        extensions, used = vrm1_extensions(node_index, springs, colliders, variant)
        generator = "Kodawari make_avatar.py (VRM 1.0, VRoid Studio's layout)"
    else:
        extensions, used = vrm0_extensions(node_index, springs, colliders, MATERIALS), ["VRM"]
        generator = "Kodawari make_avatar.py (VRM 0.x, UniVRM 0.x's layout)"
    doc = {
        "asset": {"version": "2.0", "generator": generator, "copyright": LICENSE_NOTE},
        "extensionsUsed": used,
        "extensions": extensions,
        "scene": 0,
        "scenes": [{"name": "avatar", "nodes": scene_nodes}],
        "nodes": gltf_nodes,
        "meshes": [{"name": "Avatar", "primitives": gltf_prims}],
        "skins": [{"name": "Avatar", "inverseBindMatrices": ibm_accessor, "skeleton": node_index["Root"],
                   "joints": list(range(len(nodes)))}],
        "materials": materials,
        "accessors": g.accessors,
        "bufferViews": g.views,
        "buffers": [{"byteLength": len(g.bin)}],
    }
    return to_glb(doc, bytes(g.bin))


# --- the VRM Animation skeleton: a taller motion-capture rig --------------------------------------

MOCAP = "mocap:"
ROT_ARM_L = q_axis_angle(Z_AXIS, -90.0)  # +Y along +X
ROT_ARM_R = q_axis_angle(Z_AXIS, 90.0)   # +Y along -X
ROT_LEG = q_axis_angle(Z_AXIS, 180.0)    # +Y down
ROT_TOE = q_axis_angle(X_AXIS, 90.0)     # +Y forward


def vrma_design(jaw=False):
    """[(node name, parent, world position, world rest rotation, humanoid bone or None)]. A T-pose
    facing +Z (VRM T-pose), 1.00 m to the hips (the avatar: 0.78 m), each bone's +Y along the
    bone (as motion-capture and Blender rigs have it), so rest rotations are not identity."""
    d = [("mocap:Reference", None, (0.0, 0.0, 0.0), IDENTITY_Q, None),
         ("mocap:Hips", "mocap:Reference", (0.0, 1.00, 0.0), IDENTITY_Q, "hips"),
         ("mocap:Spine", "mocap:Hips", (0.0, 1.10, 0.0), IDENTITY_Q, "spine"),
         ("mocap:Spine1", "mocap:Spine", (0.0, 1.22, 0.0), IDENTITY_Q, "chest"),
         ("mocap:Spine2", "mocap:Spine1", (0.0, 1.34, 0.0), IDENTITY_Q, "upperChest"),
         ("mocap:Neck", "mocap:Spine2", (0.0, 1.50, 0.0), IDENTITY_Q, "neck"),
         ("mocap:Head", "mocap:Neck", (0.0, 1.58, 0.0), IDENTITY_Q, "head"),
         ("mocap:HeadTop_End", "mocap:Head", (0.0, 1.78, 0.0), IDENTITY_Q, None)]
    if jaw:
        d.append(("mocap:Jaw", "mocap:Head", (0.0, 1.60, 0.06), ROT_TOE, "jaw"))
    for side, name, f, rot in (("left", "Left", lambda p: p, ROT_ARM_L), ("right", "Right", mirror, ROT_ARM_R)):
        m = MOCAP + name
        foot, toe = f((0.095, 0.09, 0.0)), f((0.095, 0.02, 0.13))
        d += [(m + "Shoulder", "mocap:Spine2", f((0.03, 1.46, 0.0)), rot, side + "Shoulder"),
              (m + "Arm", m + "Shoulder", f((0.17, 1.46, 0.0)), rot, side + "UpperArm"),
              (m + "ForeArm", m + "Arm", f((0.46, 1.46, 0.0)), rot, side + "LowerArm"),
              (m + "Hand", m + "ForeArm", f((0.72, 1.46, 0.0)), rot, side + "Hand"),
              (m + "UpLeg", "mocap:Hips", f((0.095, 0.95, 0.0)), ROT_LEG, side + "UpperLeg"),
              (m + "Leg", m + "UpLeg", f((0.095, 0.52, 0.0)), ROT_LEG, side + "LowerLeg"),
              (m + "Foot", m + "Leg", foot, q_shortest_arc(Y_AXIS, normalize(sub(toe, foot))), side + "Foot"),
              (m + "ToeBase", m + "Foot", toe, ROT_TOE, side + "Toes")]
    return d


VRMA_HIPS_HEIGHT = 1.00
AVATAR_HIPS_HEIGHT = 0.78


def g_bump(x, power=4):
    """A smooth periodic bump, 1 at x = 0 (mod 2 pi), falling to 0 half a period away."""
    return ((1.0 + math.cos(x)) / 2.0) ** power


def q_x(deg):
    return q_axis_angle(X_AXIS, deg)


def q_y(deg):
    return q_axis_angle(Y_AXIS, deg)


def q_z(deg):
    return q_axis_angle(Z_AXIS, deg)


def legs(phase, hips, flex0=8.0, swing=20.0, knee_swing=55.0, knee_stance=10.0, push=22.0, heel=8.0, toe=25.0):
    """Normalised leg rotations for a walk whose left heel strikes at phase 0 (the right one
    half a cycle later). Each thigh cancels the hips' rotation, so the legs swing in the
    sagittal plane; the foot's world pitch follows its own profile (flat in stance, toe down
    at push-off, toe up at heel strike) whatever the thigh and knee do."""
    out = {}
    for side, p in (("left", phase), ("right", phase + math.pi)):
        flex = flex0 + swing * math.cos(p - 0.1)  # thigh forward (+) / back (-)
        knee = 5.0 + knee_stance * g_bump(p - 0.2 * math.pi) + knee_swing * g_bump(p - 1.55 * math.pi)
        foot = push * g_bump(p - 1.25 * math.pi) - heel * g_bump(p)  # world pitch, toe down (+)
        out[side + "UpperLeg"] = q_mul(q_conj(hips), q_x(-flex))
        out[side + "LowerLeg"] = q_x(knee)
        out[side + "Foot"] = q_x(foot + flex - knee)
        out[side + "Toes"] = q_x(-toe * g_bump(p - 1.2 * math.pi))
    return out


def walk_pose(t, period=1.1):
    """Normalised local rotations {bone: q} and the hips' translation (VRMA scale) at time t."""
    p = 2.0 * math.pi * t / period
    hips = q_euler(yaw=-5.0 * math.cos(p), pitch=2.0, roll=3.0 * math.sin(p))
    pose = {"hips": hips,
            "spine": q_euler(yaw=2.0 * math.cos(p), pitch=-1.0),
            "chest": q_euler(yaw=3.0 * math.cos(p), roll=-1.5 * math.sin(p)),
            "upperChest": q_euler(yaw=3.0 * math.cos(p), pitch=-1.0),
            "neck": q_euler(yaw=-1.0 * math.cos(p))}
    chain = IDENTITY_Q
    for b in ("hips", "spine", "chest", "upperChest", "neck"):
        chain = q_mul(chain, pose[b])
    pose["head"] = q_conj(chain)  # the head keeps its rest orientation in the world: steady
    for side, sign, arm in (("left", 1.0, math.cos(p)), ("right", -1.0, -math.cos(p))):
        # The arm hangs 70 degrees down from the T-pose and swings opposite its leg (back (+)
        # when the leg on its side is forward); the elbow bends more as the arm comes forward.
        pose[side + "Shoulder"] = q_x(2.0 * arm)
        pose[side + "UpperArm"] = q_mul(q_x(16.0 * arm), q_z(-sign * 70.0))
        pose[side + "LowerArm"] = q_y(-sign * (15.0 + 12.0 * (1.0 - arm) / 2.0))
        pose[side + "Hand"] = q_z(-sign * 5.0)
    pose.update(legs(p, hips))
    hips_t = (0.022 * math.sin(p), VRMA_HIPS_HEIGHT - 0.01 - 0.015 * math.cos(2.0 * p), 0.008 * math.sin(2.0 * p))
    return pose, hips_t


# walk-turn: the walk's stride cycle, 8 of them, while the hips go once round a circle to
# the left (the centre TURN_RADIUS along +X, the avatar's left, from where the clip starts)
# at TURN_SPEED: the circumference is the distance walked, so the loop closes exactly.
WALK_CYCLE = 1.1
TURN_CYCLES = 8
TURN_PERIOD = TURN_CYCLES * WALK_CYCLE  # 8.8 s
TURN_SPEED = 1.2  # m/s, in the clip's (the mocap rig's) metres
TURN_RADIUS = TURN_SPEED * TURN_PERIOD / (2.0 * math.pi)  # 1.6807 m


def turn_of(t, period):
    """(yaw quaternion, heading angle rad, hips' path point (x, z)) of walk-turn at time t:
    the heading is the circle's tangent, turning left at a constant rate."""
    a = 2.0 * math.pi * t / period
    return q_y(math.degrees(a)), a, (TURN_RADIUS * (1.0 - math.cos(a)), TURN_RADIUS * math.sin(a))


def walk_turn_pose(t, period=TURN_PERIOD):
    """The walk (same stride, same legs and arms) carried round the circle: the hips' rotation
    and their sway, bob and surge turn with the heading, and the path's point is added to the
    hips' translation. The head's local rotation is the walk's: its world rotation is then
    the heading's yaw alone, level and facing along the walk."""
    pose, (sx, hy, sz) = walk_pose(t, WALK_CYCLE)
    yaw, _, (px, pz) = turn_of(t, period)
    pose["hips"] = q_mul(yaw, pose["hips"])  # the legs' and spine's local rotations are relative to it
    off = q_rotate(yaw, (sx, 0.0, sz))
    return pose, (px + off[0], hy, pz + off[2])


def idle_pose(t, period=4.0):
    p = 2.0 * math.pi * t / period
    breath = math.sin(2.0 * p)  # two breaths per loop
    hips = q_euler(yaw=2.0 * math.sin(p), roll=1.5 * math.sin(p))
    pose = {"hips": hips,
            "spine": q_euler(roll=-1.0 * math.sin(p)),
            "chest": q_euler(pitch=-1.2 * breath, roll=-0.5 * math.sin(p)),
            "upperChest": q_euler(pitch=-1.0 * breath),
            "neck": q_euler(yaw=8.0 * math.sin(p), pitch=1.0 * math.sin(2.0 * p + 0.5)),
            "head": q_euler(yaw=22.0 * math.sin(p), pitch=4.0 * math.sin(2.0 * p + 0.5), roll=3.0 * math.sin(p + 1.0))}
    for side, sign in (("left", 1.0), ("right", -1.0)):
        pose[side + "Shoulder"] = q_z(sign * 1.5 * (1.0 + breath) / 2.0)
        pose[side + "UpperArm"] = q_mul(q_x(3.0 * math.sin(p + sign)), q_z(-sign * 72.0))
        pose[side + "LowerArm"] = q_y(-sign * 10.0)
        pose[side + "Hand"] = q_z(-sign * 8.0)
        pose[side + "UpperLeg"] = q_mul(q_conj(hips), q_x(-2.0))
        pose[side + "LowerLeg"] = q_x(4.0)
        pose[side + "Foot"] = q_x(-2.0)
        pose[side + "Toes"] = IDENTITY_Q
    hips_t = (0.012 * math.sin(p), VRMA_HIPS_HEIGHT - 0.004 + 0.002 * breath, 0.0)
    return pose, hips_t


CLIPS = {  # name: (pose function, period s, keys, blink times s)
    "walk": (walk_pose, 1.1, 33, [0.55]),
    "walk-turn": (walk_turn_pose, TURN_PERIOD, 264, [1.6, 4.5, 7.4]),
    "idle": (idle_pose, 4.0, 120, [1.3, 3.1]),
}


def vrma_rest(design):
    """{name: (world position, world rotation, local translation, local rotation)}."""
    by_name = {d[0]: d for d in design}
    out = {}
    for name, parent, pos, rot, _ in design:
        if parent is None:
            out[name] = (pos, rot, pos, rot)
        else:
            _, _, ppos, prot, _ = by_name[parent]
            out[name] = (pos, rot, q_rotate(q_conj(prot), sub(pos, ppos)), q_mul(q_conj(prot), rot))
    return out


def positive(q):
    return q if q[3] >= 0.0 else tuple(-c for c in q)


def build_vrma(clip, variant=None):
    """The GLB bytes of one VRM Animation clip ("walk", "walk-turn" or "idle")."""
    design = vrma_design(jaw=(variant == "vrma-jaw"))
    rest = vrma_rest(design)
    by_name = {d[0]: d for d in design}
    bone_node = {d[4]: d[0] for d in design if d[4]}
    names = [d[0] for d in design]
    index = {n: i for i, n in enumerate(names)}
    pose_fn, period, keys, blinks = CLIPS[clip]
    times = [period * k / keys for k in range(keys + 1)]
    poses = [pose_fn(t, period) for t in times[:-1]]
    g = Gltf()
    time_acc = g.times([round(t, 6) for t in times])
    samplers, channels = [], []

    def channel(node, path, values, input_acc=time_acc):
        kind = "VEC4" if path == "rotation" else "VEC3"
        samplers.append({"input": input_acc, "interpolation": "LINEAR",
                         "output": g.accessor("f", [tuple(v) for v in values], FLOAT, kind)})
        channels.append({"sampler": len(samplers) - 1, "target": {"node": index[node], "path": path}})

    bones = [b for b in poses[0][0]] + (["jaw"] if variant == "vrma-jaw" else [])
    for bone in bones:
        node = bone_node[bone]
        parent = by_name[node][1]
        w_parent = rest[parent][1]
        local_rest = rest[node][3]
        values = []
        for pose, _ in poses:
            n = pose.get(bone, q_x(8.0 * math.sin(2.0 * math.pi * len(values) / keys)))  # the jaw: chewing
            # Normalised -> this rig's local rotation (how_to_transform_human_pose.md):
            # local = W_parent^-1 * N * W_parent * L_rest.
            q = q_normalize(q_mul(q_mul(q_mul(q_conj(w_parent), n), w_parent), local_rest))
            q = tuple(clean(c, 9) for c in q)
            if values and dot(q[:3], values[-1][:3]) + q[3] * values[-1][3] < 0.0:
                q = tuple(-c for c in q)  # keep the keys on one side, for LINEAR (slerp) between them
            values.append(q if values else positive(q))
        # The last key is the first one's rotation. The hips of walk-turn turn by a whole turn,
        # which brings their quaternion round to minus the first key: that one, so that the
        # keys stay on one side all the way (the same rotation, exactly, for any reader).
        if dot(values[-1][:3], values[0][:3]) + values[-1][3] * values[0][3] > 0.0:
            last = values[0]
        else:
            assert clip == "walk-turn" and bone == "hips", "%s: the loop's last step turns by over half a turn" % bone
            last = tuple(-c for c in values[0])
        channel(node, "rotation", values + [last])
    translations = [tuple(clean(c, 7) for c in hips_t) for _, hips_t in poses]
    channel(bone_node["hips"], "translation", translations + [translations[0]])

    # The blink expression: a node whose translation x is the weight (VRMC_vrm_animation 1.0,
    # Expressions). Closes in 0.05 s, opens in 0.1 s; 0 at both ends.
    btimes, bvalues = [0.0], [(0.0, 0.0, 0.0)]
    for b in blinks:
        btimes += [b - 0.05, b, b + 0.1]
        bvalues += [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, 0.0)]
    btimes.append(period)
    bvalues.append((0.0, 0.0, 0.0))
    names.append("expression:blink")
    index["expression:blink"] = len(names) - 1
    channel("expression:blink", "translation", bvalues, g.times([round(t, 6) for t in btimes]))

    nodes = []
    for name, parent, _, _, _ in design:
        _, _, t, r = rest[name]
        node = {"name": name}
        children = [index[d[0]] for d in design if d[1] == name]
        if children:
            node["children"] = children
        t = tuple(clean(c, 7) for c in t)
        r = positive(tuple(clean(c, 9) for c in r))
        if r != IDENTITY_Q:
            node["rotation"] = list(r)
        if t != (0.0, 0.0, 0.0):
            node["translation"] = list(t)
        nodes.append(node)
    nodes.append({"name": "expression:blink"})

    humanoid = {d[4]: {"node": index[d[0]]} for d in design if d[4]}
    if variant == "vrma-no-humanoid":
        humanoid = {}
    if variant == "vrma-missing-node":
        humanoid["hips"] = {"node": len(nodes)}
    doc = {
        "asset": {"version": "2.0", "generator": "Kodawari make_avatar.py (VRM Animation 1.0)",
                  "copyright": LICENSE_NOTE},
        "extensionsUsed": ["VRMC_vrm_animation"],
        "extensions": {"VRMC_vrm_animation": {
            "specVersion": "1.0",
            "humanoid": {"humanBones": humanoid},
            "expressions": {"preset": {"blink": {"node": index["expression:blink"]}}},
        }},
        "scene": 0,
        "scenes": [{"name": clip, "nodes": [index["mocap:Reference"], index["expression:blink"]]}],
        "nodes": nodes,
        "animations": [{"name": clip, "channels": channels, "samplers": samplers}],
        "accessors": g.accessors,
        "bufferViews": g.views,
        "buffers": [{"byteLength": len(g.bin)}],
    }
    return to_glb(doc, bytes(g.bin))


# --- verification (of the files' bytes) -----------------------------------------------------------


def position(m):
    return (m[0][3], m[1][3], m[2][3])


def near(a, b, tol=1e-5):
    return length(sub(a, b)) <= tol


def verify_avatar(data, version):
    """Checks an avatar's bytes; returns a summary; raises AssertionError on a defect."""
    assert len(data) < 1_500_000, "%d bytes" % len(data)
    doc, binary = parse_glb(data)
    nodes = doc["nodes"]
    names = [n.get("name", "") for n in nodes]
    assert len(set(names)) == len(names), "node names are not unique"
    world, parent = node_worlds(doc)
    idx = {n: i for i, n in enumerate(names)}
    for n in nodes:
        assert "rotation" not in n, "%s has a rest rotation (VRoid writes none)" % n["name"]
    forward = 1.0 if version == 1 else -1.0  # VRM 1.0 faces +Z, VRM 0.x -Z
    left = 1.0 if version == 1 else -1.0     # the avatar's left: +X in VRM 1.0, -X in VRM 0.x
    assert names[parent[idx["J_Bip_C_Hips"]]] == "Root" and idx["Root"] not in parent
    # Humanoid mapping.
    if version == 1:
        ext = doc["extensions"]["VRMC_vrm"]
        assert ext["specVersion"] == "1.0"
        bones = {b: v["node"] for b, v in ext["humanoid"]["humanBones"].items()}
        assert {b: names[i] for b, i in bones.items()} == HUMANOID
        assert ext["meta"]["licenseUrl"] == "https://vrm.dev/licenses/1.0/"
    else:
        ext = doc["extensions"]["VRM"]
        bones = {e["bone"]: e["node"] for e in ext["humanoid"]["humanBones"]}
        assert {b: names[i] for b, i in bones.items()} == {vrm0_bone_name(b): n for b, n in HUMANOID.items()}
        assert ext["meta"]["licenseName"] == "CC0"
        bones = {b: bones[vrm0_bone_name(b)] for b in HUMANOID}
    p = {b: position(world[i]) for b, i in bones.items()}
    # T-pose: arms level along the avatar's left/right, legs straight down, feet forward.
    for side, s in (("left", 1.0), ("right", -1.0)):
        chain = [p[side + b] for b in ("UpperArm", "LowerArm", "Hand")]
        for a, b in zip(chain, chain[1:]):
            d = normalize(sub(b, a))
            assert abs(d[0] - s * left) < 1e-6, "%s arm is not along X" % side
        leg = [p[side + b] for b in ("UpperLeg", "LowerLeg", "Foot")]
        for a, b in zip(leg, leg[1:]):
            assert abs(normalize(sub(b, a))[1] + 1.0) < 1e-6, "%s leg is not vertical" % side
        assert (p[side + "Toes"][2] - p[side + "Foot"][2]) * forward > 0.05, "%s foot does not point forward" % side
        assert p[side + "UpperArm"][0] * left * s > 0.0
    assert abs(p["hips"][1] - AVATAR_HIPS_HEIGHT) < 1e-6

    # Skin: inverse bind matrices, weights, normals, winding.
    skin = doc["skins"][0]
    ibms = read_accessor(doc, binary, skin["inverseBindMatrices"])
    worst = 0.0
    for j, ibm in zip(skin["joints"], ibms):
        m = [[ibm[c * 4 + r] for c in range(4)] for r in range(4)]
        prod = mat_mul(m, world[j])
        worst = max(worst, max(abs(prod[r][c] - (1.0 if r == c else 0.0)) for r in range(4) for c in range(4)))
    assert worst <= 1e-6, "IBM x rest world matrix is off identity by %g" % worst
    vertices = triangles = 0
    top = 0.0
    for prim in doc["meshes"][0]["primitives"]:
        a = prim["attributes"]
        pos = read_accessor(doc, binary, a["POSITION"])
        nrm = read_accessor(doc, binary, a["NORMAL"])
        jnt = read_accessor(doc, binary, a["JOINTS_0"])
        wgt = read_accessor(doc, binary, a["WEIGHTS_0"])
        ind = read_accessor(doc, binary, prim["indices"])
        acc = doc["accessors"][a["POSITION"]]
        assert acc["min"] == [min(v[c] for v in pos) for c in range(3)]
        assert acc["max"] == [max(v[c] for v in pos) for c in range(3)]
        for v in range(len(pos)):
            assert abs(length(nrm[v]) - 1.0) < 1e-6, "normal %d not unit" % v
            assert abs(sum(wgt[v]) - 1.0) <= 2e-7
            used = [jj for jj, ww in zip(jnt[v], wgt[v]) if ww != 0.0]
            assert used and len(set(used)) == len(used) and all(jj < len(skin["joints"]) for jj in jnt[v])
            assert all(jj == 0 for jj, ww in zip(jnt[v], wgt[v]) if ww == 0.0)
        for t in range(0, len(ind), 3):
            i0, i1, i2 = ind[t:t + 3]
            fn = cross(sub(pos[i1], pos[i0]), sub(pos[i2], pos[i0]))
            assert length(fn) > 1e-12, "degenerate triangle"
            assert dot(fn, add(add(nrm[i0], nrm[i1]), nrm[i2])) > 0.0, "a triangle faces against its normals"
        top = max(top, acc["max"][1])
        vertices += len(pos)
        triangles += len(ind) // 3
    assert 1.45 < top < 1.55, "height %.3f m" % top

    # Springs and colliders, read back into one form (world-space collider spheres/capsules).
    if version == 1:
        sb = doc["extensions"]["VRMC_springBone"]
        assert sb["specVersion"] == "1.0"
        colliders = []
        for c in sb["colliders"]:
            assert "extensions" not in c, "an extended collider (VRoid writes none)"
            shape = c["shape"]
            kind = "sphere" if "sphere" in shape else "capsule"
            s = shape[kind]
            tail = s.get("tail", s["offset"])
            colliders.append((c["node"], add(position(world[c["node"]]), tuple(s["offset"])),
                              add(position(world[c["node"]]), tuple(tail)), s["radius"]))
        groups = [g["colliders"] for g in sb["colliderGroups"]]
        for g in groups:
            assert all(0 <= i < len(colliders) for i in g)
        springs = []
        for s in sb["springs"]:
            joints = [j["node"] for j in s["joints"]]
            hits = [j["hitRadius"] for j in s["joints"]]
            members = sorted({i for g in s["colliderGroups"] for i in groups[g]})
            springs.append((names[joints[0]], joints, hits, members, s.get("center")))
        assert sum(1 for s in springs if s[4] is not None) == 1
        group_sets = {tuple(s[3]) for s in springs}
        assert len(group_sets) >= 3, "per-spring collider groups should differ"
    else:
        sa = doc["extensions"]["VRM"]["secondaryAnimation"]
        colliders, groups = [], []
        for g in sa["colliderGroups"]:
            members = []
            for c in g["colliders"]:
                o = c["offset"]
                local = (o["x"], o["y"], -o["z"])  # stored z-negated (UniVRM 0.x); see vrm0_offset
                center = add(position(world[g["node"]]), local)
                members.append(len(colliders))
                colliders.append((g["node"], center, center, c["radius"]))
            groups.append(members)
        springs = []
        for bg in sa["boneGroups"]:
            members = sorted({i for g in bg["colliderGroups"] for i in groups[g]})
            for root in bg["bones"]:
                joints = [root]
                while len(nodes[joints[-1]].get("children", [])) == 1:
                    joints.append(nodes[joints[-1]]["children"][0])
                assert not nodes[joints[-1]].get("children"), "a spring branches"
                springs.append((names[root], joints, [bg["hitRadius"]] * len(joints), members,
                                bg["center"] if bg["center"] >= 0 else None))
        assert sum(1 for s in springs if s[4] is not None) == 1

    head = idx["J_Bip_C_Head"]
    head_spheres = [(c[1], c[3]) for c in colliders if c[0] == head]
    assert len(head_spheres) >= 4 and all(not near(c, position(world[head]), 1e-3) for c, _ in head_spheres)
    hair = [s for s in springs if s[0].startswith("J_Sec_Hair")]
    assert len(hair) >= 20 and all(3 <= len(s[1]) <= 6 for s in hair), "hair springs"
    worst_margin = 1.0
    for s in springs:
        joints = s[1]
        for a, b in zip(joints, joints[1:]):
            assert parent[b] == a, "%s: not a parent-to-child path" % s[0]
        if s in hair:
            assert names[parent[joints[0]]] == "J_Bip_C_Head"
            for j, hit in zip(joints, s[2]):
                for c, r in head_spheres:
                    margin = length(sub(position(world[j]), c)) - r - hit
                    worst_margin = min(worst_margin, margin)
                    assert margin > 0.0, "%s lies inside a head collider" % names[j]
    # The skirt's and the bust's joints clear the colliders they use, too (below the root).
    for s in springs:
        if s not in hair:
            for j in s[1][1:]:
                for ci in s[3]:
                    _, a, b, r = colliders[ci]
                    ab = sub(b, a)
                    t = 0.0 if dot(ab, ab) == 0.0 else max(0.0, min(1.0, dot(sub(position(world[j]), a), ab) / dot(ab, ab)))
                    d = length(sub(position(world[j]), add(a, scale(ab, t))))
                    assert d > r + s[2][0], "%s lies inside collider %d" % (names[j], ci)
    return {"nodes": len(nodes), "joints": len(skin["joints"]), "humanoid": len(bones), "vertices": vertices,
            "triangles": triangles, "bytes": len(data), "springs": len(springs), "hair": len(hair),
            "spring_joints": sum(len(s[1]) for s in springs), "colliders": len(colliders), "groups": len(groups),
            "hair_margin": worst_margin, "ibm_error": worst}


def q_angle(a, b):
    """The angle (rad) of the rotation between unit quaternions a and b (well conditioned near 0)."""
    d = q_mul(a, q_conj(b))
    return 2.0 * math.atan2(length(d[:3]), abs(d[3]))


def verify_vrma(data, clip):
    doc, binary = parse_glb(data)
    ext = doc["extensions"]["VRMC_vrm_animation"]
    assert ext["specVersion"] == "1.0"
    nodes = doc["nodes"]
    names = [n["name"] for n in nodes]
    world, parent = node_worlds(doc)
    bones = {b: v["node"] for b, v in ext["humanoid"]["humanBones"].items()}
    assert set(bones) <= set(HUMANOID) and all(names[i].startswith(MOCAP) for i in bones.values())
    assert set(bones) >= {"hips", "spine", "head", "leftUpperArm", "leftLowerArm", "leftHand", "rightUpperArm",
                          "rightLowerArm", "rightHand", "leftUpperLeg", "leftLowerLeg", "leftFoot", "rightUpperLeg",
                          "rightLowerLeg", "rightFoot"}  # VRM 1.0's required bones
    p = {b: position(world[i]) for b, i in bones.items()}
    for side, s in (("left", 1.0), ("right", -1.0)):  # the VRM T-pose
        for a, b in (("UpperArm", "LowerArm"), ("LowerArm", "Hand")):
            assert abs(normalize(sub(p[side + b], p[side + a]))[0] - s) < 1e-6
        for a, b in (("UpperLeg", "LowerLeg"), ("LowerLeg", "Foot")):
            assert abs(normalize(sub(p[side + b], p[side + a]))[1] + 1.0) < 1e-6
        assert p[side + "Toes"][2] - p[side + "Foot"][2] > 0.05
    assert abs(p["hips"][1] - VRMA_HIPS_HEIGHT) < 1e-6
    rotated = sum(1 for i in bones.values() if "rotation" in nodes[i])
    assert rotated >= 8, "the rig's rest rotations should not be identity"

    # Rest world rotations W and local L, from the file.
    def q_of(i):  # the JSON holds 9 decimals: unit within 1e-9
        return q_normalize(tuple(nodes[i].get("rotation", IDENTITY_Q)))

    def world_q(i):
        q = q_of(i)
        while i in parent:
            i = parent[i]
            q = q_mul(q_of(i), q)
        return q

    anim = doc["animations"][0]
    assert anim["name"] == clip and len(doc["animations"]) == 1
    period = CLIPS[clip][1]
    tracks = {}
    for ch in anim["channels"]:
        node, path = ch["target"]["node"], ch["target"]["path"]
        s = anim["samplers"][ch["sampler"]]
        times = read_accessor(doc, binary, s["input"])
        values = read_accessor(doc, binary, s["output"])
        assert s["interpolation"] == "LINEAR" and times[0] == 0.0 and abs(times[-1] - period) < 1e-6
        assert all(b > a for a, b in zip(times, times[1:]))
        first, last = tuple(values[0]), tuple(values[-1])
        if clip == "walk-turn" and names[node] == "mocap:Hips" and path == "rotation":
            last = tuple(-c for c in last)  # a whole turn: minus the first key, the same rotation
        assert first == last, "%s %s does not loop" % (names[node], path)
        assert path in ("rotation", "translation"), "a humanoid animation never scales"
        # Seamless: the step from the last-but-one key round to the first (the loop's wrap) is
        # a step like the others: at most 1.5 times the largest inside the loop.
        if path == "rotation":
            steps = [q_angle(q_normalize(tuple(a)), q_normalize(tuple(b))) for a, b in zip(values, values[1:])]
        else:
            steps = [length(sub(tuple(b), tuple(a))) for a, b in zip(values, values[1:])]
        assert steps[-1] <= 1.5 * max(steps[:-1]) + 1e-6, "%s %s jumps at the loop" % (names[node], path)
        if path == "translation" and node not in (bones["hips"],):
            assert names[node] == "expression:blink", "translation on a bone other than the hips"
            assert all(0.0 <= v[0] <= 1.0 for v in values)
        tracks[(node, path)] = (times, values)
    expr = ext["expressions"]["preset"]["blink"]["node"]
    assert (expr, "translation") in tracks

    # Normalise (how_to_transform_human_pose.md: N = W * L^-1 * local * W^-1) and compare with
    # the design; retarget onto the avatar (identity rest rotations: local = N) and check the
    # walk's look: head steady, knees bend backwards, arms swing opposite the legs.
    pose_fn = CLIPS[clip][0]
    times = tracks[(bones["hips"], "rotation")][0]
    worst = 0.0
    keys = CLIPS[clip][2]
    assert len(times) == keys + 1
    walking = clip in ("walk", "walk-turn")
    path_points = []
    for k in range(keys):
        assert abs(times[k] - period * k / keys) < 1e-6
        design, hips_t = pose_fn(period * k / keys, period)  # the key's exact time (the file's is float32)
        heading = turn_of(period * k / keys, period)[0] if clip == "walk-turn" else IDENTITY_Q
        normalised = {}
        for bone, i in bones.items():
            if (i, "rotation") not in tracks:
                continue
            q = q_normalize(tuple(tracks[(i, "rotation")][1][k]))  # float32 keys: unit within 1e-7
            w, lq = world_q(i), q_of(i)
            n = q_mul(q_mul(q_mul(w, q_conj(lq)), q), q_conj(w))
            normalised[bone] = n
            worst = max(worst, q_angle(n, design[bone]))
        hips_key = tuple(tracks[(bones["hips"], "translation")][1][k])
        assert near(hips_key, hips_t, 1e-6)
        path_points.append(hips_key)
        if walking:  # the head's world rotation is the heading's: level, facing along the walk
            chain = IDENTITY_Q
            for b in ("hips", "spine", "chest", "upperChest", "neck", "head"):
                chain = q_mul(chain, normalised[b])
            assert q_angle(chain, heading) < 1e-6, "the head turns in the world"
            # the hips face along the walk, give or take the stride's twist (5 degrees)
            assert q_angle(q_mul(q_conj(heading), normalised["hips"]), q_euler(pitch=2.0)) < math.radians(6.0)
    assert worst < 1e-6, "normalised rotations differ from the design by %g rad" % worst
    if clip == "walk-turn":
        # The hips' keys go once round the circle: each stride cycle's mean is the mean of the
        # circle's points at the same times (the sway and surge, turning with the hips, average
        # out within 3 mm), the angle round the centre grows by a whole turn, and the distance
        # walked (the circumference) is TURN_SPEED * period.
        per = keys // TURN_CYCLES
        assert per * TURN_CYCLES == keys
        for c in range(TURN_CYCLES):
            pts = path_points[c * per:(c + 1) * per]
            ring = [turn_of(period * k / keys, period)[2] for k in range(c * per, (c + 1) * per)]
            off = (sum(q[0] for q in pts) / per - sum(q[0] for q in ring) / per,
                   sum(q[2] for q in pts) / per - sum(q[1] for q in ring) / per)
            assert math.hypot(*off) < 3e-3, "stride cycle %d: off the circle by %.4f m" % (c, math.hypot(*off))
        turned = 0.0
        for a, b in zip(path_points, path_points[1:] + path_points[:1]):
            ang = [math.atan2(q[2], TURN_RADIUS - q[0]) for q in (a, b)]
            d = (ang[1] - ang[0] + math.pi) % (2.0 * math.pi) - math.pi
            assert d > 0.0, "the hips go back round the circle"
            turned += d
        assert abs(turned - 2.0 * math.pi) < 1e-9, "the path does not close after one turn"
        assert abs(2.0 * math.pi * TURN_RADIUS - TURN_SPEED * period) < 1e-9
    if walking:
        pose, _ = pose_fn(0.0, period)  # left heel strike: left leg forward, left arm back (heading +Z)

        def limb_end(bones_, offsets):
            q, pos = IDENTITY_Q, (0.0, 0.0, 0.0)
            for b, o in zip(bones_, offsets):
                q = q_mul(q, pose[b])
                pos = add(pos, q_rotate(q, o))
            return pos
        for side, s in (("left", 1.0), ("right", -1.0)):
            hand = limb_end(["hips", "spine", "chest", "upperChest", side + "Shoulder", side + "UpperArm"],
                            [(0, 0, 0)] * 5 + [(s * 0.24, 0.0, 0.0)])
            assert hand[1] < -0.15, "%s arm does not hang" % side
            assert (hand[2] < 0.0) == (side == "left"), "%s arm swings with its leg" % side
        for t in [period * k / (44 * round(period / WALK_CYCLE)) for k in range(44 * round(period / WALK_CYCLE))]:
            pose, _ = pose_fn(t, period)  # knees bend backwards: the ankle behind the knee (the body's frame)
            body = q_mul(q_conj(turn_of(t, period)[0]), pose["hips"]) if clip == "walk-turn" else pose["hips"]
            for side in ("left", "right"):
                q = q_mul(q_mul(body, pose[side + "UpperLeg"]), pose[side + "LowerLeg"])
                shin = q_rotate(q, (0.0, -0.33, 0.0))
                thigh_q = q_mul(body, pose[side + "UpperLeg"])
                thigh_dir = q_rotate(thigh_q, (0.0, -1.0, 0.0))
                assert dot(cross(thigh_dir, normalize(shin)), X_AXIS) >= -1e-9, "%s knee bends forwards" % side
    return {"nodes": len(nodes), "bones": len(bones), "channels": len(anim["channels"]), "keys": len(times),
            "duration": period, "bytes": len(data), "normalise_error": worst}


# --- output ---------------------------------------------------------------------------------------


def write_atomic(path, data):
    directory = os.path.dirname(os.path.abspath(path))
    os.makedirs(directory, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=os.path.basename(path) + ".tmp-", dir=directory)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise


def build(name):
    return {"avatar.vrm": lambda: build_avatar(1), "avatar-vrm0.vrm": lambda: build_avatar(0),
            "walk.vrma": lambda: build_vrma("walk"), "walk-turn.vrma": lambda: build_vrma("walk-turn"),
            "idle.vrma": lambda: build_vrma("idle")}[name]()


def verify(name, data):
    if name.endswith(".vrma"):
        s = verify_vrma(data, name[:-5])
        return "%d nodes, %d humanoid bones, %d channels of %d keys, %.3g s, %d bytes" % (
            s["nodes"], s["bones"], s["channels"], s["keys"], s["duration"], s["bytes"])
    s = verify_avatar(data, 0 if "vrm0" in name else 1)
    return ("%d nodes (%d joints, %d humanoid bones), %d vertices, %d triangles, %d bytes; %d springs (%d hair) of "
            "%d joints, %d colliders in %d groups; hair clears the head colliders by >= %.1f mm" % (
                s["nodes"], s["joints"], s["humanoid"], s["vertices"], s["triangles"], s["bytes"], s["springs"],
                s["hair"], s["spring_joints"], s["colliders"], s["groups"], 1000.0 * s["hair_margin"]))


def build_variant(name):
    if name.startswith("vrma-"):
        return build_vrma("walk", name)
    return build_avatar(1, name)


def main(argv):
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="variants (--variant NAME --out FILE):\n" + __doc__.split("one defect:\n\n")[1].split("\n\n")[0])
    parser.add_argument("--out-dir", help="write the five files flat into this folder instead of the repository")
    parser.add_argument("--check", action="store_true", help="only verify the committed files")
    parser.add_argument("--variant", choices=VARIANTS, help="write one bad-input file (needs --out)")
    parser.add_argument("--out", help="the variant's output path")
    args = parser.parse_args(argv)
    if args.variant:
        if not args.out:
            parser.error("--variant needs --out")
        write_atomic(args.out, build_variant(args.variant))
        print("wrote %s (variant %s)" % (args.out, args.variant))
        return 0
    for name, repo_path in OUTPUTS:
        path = os.path.join(args.out_dir, name) if args.out_dir else os.path.join(ROOT, repo_path)
        if args.check:
            with open(path, "rb") as f:
                data = f.read()
        else:
            data = build(name)
        summary = verify(name, data)
        if not args.check:
            write_atomic(path, data)
        print("%s %s: %s" % ("checked" if args.check else "wrote", os.path.relpath(path), summary))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
