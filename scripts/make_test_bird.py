#!/usr/bin/env python3
"""Writes a small rigged bird (.glb) for the tests of `kodawari rig --bird` (issue 14).

    python3 scripts/make_test_bird.py OUT.glb [--variant good|noskin|nomesh|zerospan|oddnames]

Its bones point along their own +Y, as Blender exports them (the 7-part rig's parts have
+Z forward, +Y up, +X the bird's left), and are named as Blender users name them: an
"Armature" root (not a joint), "spine", "head", "tail", "wing.L" > "forearm.L",
"wing.R" > "forearm.R". The skin lists the joints in another order than the rig's parts.
The mesh is boxes, each vertex on one bone with weight 1: a body, a head, a tail plate
and four wing panels whose planform is known exactly (KNOWN below: span 1.12 m, area
0.1248 m^2 for both wings, so a mean chord of 0.11143 m and an aspect ratio of 10.051).

Variants, for the bad-input tests: noskin (the same nodes and mesh, no skin), nomesh
(the skin without any mesh), zerospan (the wing panels flattened onto the wing roots),
oddnames (bones renamed so that no name pattern finds them: a mapping file is needed).

Deterministic (same arguments, same bytes) and made from nothing but this file and the
project's character generator (its quaternion and glTF writing helpers): no licence
question. Standard library only.
"""
import json
import os
import sys

# The quaternion helpers and the glTF buffer and GLB writers of the project's character
# generator, so that both generators write glTF the same way.
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'scenes', 'characters'))
from make_chibi import Gltf, q_axis_angle, q_conj, q_mul, q_rotate, to_glb  # noqa: E402

# The wing planform the tests compare the measurement with.
KNOWN = {
    'wingspan': 1.12,          # 2 x 0.56: tip to tip
    'wing_area': 2 * 0.52 * 0.12,  # two wings, each root x = 0.04 to tip 0.56, chord 0.12
    'body_length': 0.3 + 0.06 + 0.1,  # body 0.30, head box reaches 0.06 ahead, tail plate 0.10 behind
}
KNOWN['mean_chord'] = KNOWN['wing_area'] / KNOWN['wingspan']
KNOWN['aspect_ratio'] = KNOWN['wingspan'] ** 2 / KNOWN['wing_area']


# Bones: name, parent, world rest position, world rest rotation (local +Y along the bone).
Y_TO_Z = q_axis_angle((1, 0, 0), 90)      # +Y -> +Z: forward
Y_TO_MINUS_Z = q_axis_angle((1, 0, 0), -90)
Y_TO_X = q_axis_angle((0, 0, 1), -90)     # +Y -> +X: the bird's left
Y_TO_MINUS_X = q_axis_angle((0, 0, 1), 90)
BONES = [
    ('spine', None, (0.0, 0.0, -0.1), Y_TO_Z),
    ('head', 'spine', (0.0, 0.03, 0.15), Y_TO_Z),
    ('tail', 'spine', (0.0, 0.0, -0.15), Y_TO_MINUS_Z),
    ('wing.L', 'spine', (0.04, 0.02, 0.0), Y_TO_X),
    ('forearm.L', 'wing.L', (0.30, 0.02, 0.0), Y_TO_X),
    ('wing.R', 'spine', (-0.04, 0.02, 0.0), Y_TO_MINUS_X),
    ('forearm.R', 'wing.R', (-0.30, 0.02, 0.0), Y_TO_MINUS_X),
]
ODD_NAMES = {'spine': 'B0', 'head': 'B1', 'tail': 'B2', 'wing.L': 'B3', 'forearm.L': 'B4', 'wing.R': 'B5',
             'forearm.R': 'B6'}
# The skin's joint order: not the rig's part order.
SKIN_ORDER = ['wing.L', 'spine', 'forearm.R', 'head', 'wing.R', 'tail', 'forearm.L']


def box(lo, hi):
    """A closed box, 24 vertices (flat normals), 12 triangles facing outward."""
    positions, normals, indices = [], [], []
    for axis in range(3):
        for side in (0, 1):
            n = [0.0, 0.0, 0.0]
            n[axis] = 1.0 if side else -1.0
            u, v = (axis + 1) % 3, (axis + 2) % 3
            base = len(positions)
            for a, b in ((0, 0), (1, 0), (1, 1), (0, 1)):
                p = [0.0, 0.0, 0.0]
                p[axis] = hi[axis] if side else lo[axis]
                p[u] = hi[u] if a else lo[u]
                p[v] = hi[v] if b else lo[v]
                positions.append(tuple(p))
                normals.append(tuple(n))
            quad = [base, base + 1, base + 2, base, base + 2, base + 3]
            if not side:  # u x v points along +axis: the low side turns round
                quad = [base, base + 2, base + 1, base, base + 3, base + 2]
            indices += quad
    return positions, normals, indices


def mesh_parts(variant):
    """(bone, lo, hi) of each box, in the bird's (the model's) frame."""
    tip = 0.56 if variant != 'zerospan' else 0.04
    elbow = 0.30 if variant != 'zerospan' else 0.04
    h = 0.005  # half the wing thickness
    return [
        ('spine', (-0.05, -0.04, -0.15), (0.05, 0.04, 0.15)),
        ('head', (-0.03, 0.0, 0.15), (0.03, 0.06, 0.21)),
        ('tail', (-0.06, -0.005, -0.25), (0.06, 0.005, -0.15)),
        ('wing.L', (0.04, 0.02 - h, -0.08), (elbow, 0.02 + h, 0.04)),
        ('forearm.L', (elbow, 0.02 - h, -0.08), (tip, 0.02 + h, 0.04)),
        ('wing.R', (-elbow, 0.02 - h, -0.08), (-0.04, 0.02 + h, 0.04)),
        ('forearm.R', (-tip, 0.02 - h, -0.08), (-elbow, 0.02 + h, 0.04)),
    ]


def build(variant):
    names = {b[0]: (ODD_NAMES[b[0]] if variant == 'oddnames' else b[0]) for b in BONES}
    # Node 0: the armature root; then the bones in BONES order; then the mesh node.
    nodes = [{'name': 'Armature', 'children': []}]
    index = {}
    world = {}
    for name, parent, position, rotation in BONES:
        index[name] = len(nodes)
        world[name] = (position, rotation)
        if parent is None:
            t, r = position, rotation
            nodes[0]['children'].append(index[name])
        else:
            pp, pr = world[parent]
            d = (position[0] - pp[0], position[1] - pp[1], position[2] - pp[2])
            t = q_rotate(q_conj(pr), d)
            r = q_mul(q_conj(pr), rotation)
            nodes[index[parent]].setdefault('children', []).append(index[name])
        nodes.append({'name': names[name], 'translation': [round(x, 9) for x in t],
                      'rotation': [round(x, 9) for x in r]})

    buf = Gltf()
    gltf = {'asset': {'version': '2.0', 'generator': 'kodawari scripts/make_test_bird.py'},
            'scene': 0, 'scenes': [{'name': 'bird', 'nodes': [0]}], 'nodes': nodes}
    joint_of = {name: SKIN_ORDER.index(name) for name in SKIN_ORDER}
    if variant != 'nomesh':
        positions, normals, indices, joints = [], [], [], []
        for bone, lo, hi in mesh_parts(variant):
            p, n, i = box(lo, hi)
            base = len(positions)
            positions += p
            normals += n
            indices += [base + k for k in i]
            joints += [joint_of[bone]] * len(p)
        attributes = {
            'POSITION': buf.accessor('f', positions, 5126, 'VEC3', 34962, bounds=True),
            'NORMAL': buf.accessor('f', normals, 5126, 'VEC3', 34962),
        }
        if variant != 'noskin':
            attributes['JOINTS_0'] = buf.accessor('B', [(j, 0, 0, 0) for j in joints], 5121, 'VEC4', 34962)
            attributes['WEIGHTS_0'] = buf.accessor('f', [(1.0, 0.0, 0.0, 0.0)] * len(joints), 5126, 'VEC4', 34962)
        index_accessor = buf.accessor('H', indices, 5123, 'SCALAR', 34963)
        gltf['materials'] = [{'name': 'feathers', 'pbrMetallicRoughness': {
            'baseColorFactor': [0.55, 0.35, 0.2, 1.0], 'metallicFactor': 0.0, 'roughnessFactor': 0.9}}]
        gltf['meshes'] = [{'name': 'bird', 'primitives': [{'attributes': attributes, 'indices': index_accessor,
                                                           'material': 0}]}]
        mesh_node = {'name': 'bird_mesh', 'mesh': 0}
        if variant != 'noskin':
            mesh_node['skin'] = 0
        nodes.append(mesh_node)
        gltf['scenes'][0]['nodes'].append(len(nodes) - 1)
    if variant != 'noskin':
        # Inverse bind matrices: the inverse of each joint's world rest transform (a
        # rotation and a translation), column major.
        ibm = []
        for name in SKIN_ORDER:
            position, rotation = world[name]
            inv = q_conj(rotation)
            cols = [q_rotate(inv, axis) for axis in ((1, 0, 0), (0, 1, 0), (0, 0, 1))]
            t = q_rotate(inv, position)
            m = [cols[0][0], cols[0][1], cols[0][2], 0.0,
                 cols[1][0], cols[1][1], cols[1][2], 0.0,
                 cols[2][0], cols[2][1], cols[2][2], 0.0,
                 -t[0], -t[1], -t[2], 1.0]
            ibm.append(tuple(m))
        gltf['skins'] = [{'name': 'bird_skin', 'skeleton': 0,
                          'joints': [index[name] for name in SKIN_ORDER],
                          'inverseBindMatrices': buf.accessor('f', ibm, 5126, 'MAT4')}]
    gltf['buffers'] = [{'byteLength': len(buf.bin)}]
    gltf['bufferViews'] = buf.views
    gltf['accessors'] = buf.accessors
    return to_glb(gltf, bytes(buf.bin))


def main(argv):
    if len(argv) not in (2, 4) or (len(argv) == 4 and argv[2] != '--variant'):
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    variant = argv[3] if len(argv) == 4 else 'good'
    if variant not in ('good', 'noskin', 'nomesh', 'zerospan', 'oddnames'):
        print(f'make_test_bird: unknown variant {variant}', file=sys.stderr)
        return 2
    with open(argv[1], 'wb') as out:
        out.write(build(variant))
    if variant == 'good':
        print(json.dumps(KNOWN, sort_keys=True))
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
