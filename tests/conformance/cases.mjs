// The spring setups of the conformance vectors (tests/conformance/README.md): each a small
// glTF with nodes only (no meshes, no buffers) and a VRMC_springBone 1.0 extension, and
// the motion its animated nodes make. make_vectors.mjs writes the setups to setups/ and
// three-vrm's joint positions to vectors/; conformance.mjs (ctest spring_conformance)
// reads them back from disk, and takes from here only packGlb() and the motion helpers
// (which it applies to what it read) and the cases' order.
//
// The parameters are those of pixiv's three-vrm samples (tests/assets/vrm-springbone:
// stiffness 1, dragForce 0.4, gravityDir -y), on a hair-sized spring: 0.25 m bones,
// hitRadius 0.05 m (a fifth of a bone, so our chain thickness, which is at most half the
// shortest segment, is the same radius). Every scale is 1, so that three-vrm (which uses
// radii as written) and we (who scale them by the node's world scale, as UniVRM does;
// engine/include/kodawari/gltf/vrm.hpp) collide the same shapes.

import { glbBytes } from '../tools/three_vrm_swing.mjs';

export const FPS = 60;
const L = 0.25; // bone length, m
const HIT = 0.05; // hitRadius, m
const ROOT_Y = 1.5; // the spring root's height, m

const round = (v) => Number(v.toFixed(9)) + 0; // + 0: no -0 in the files

/// A motion channel's value at time t: `rest` plus, for a translation, `axis` times
/// amplitude sin(2 pi frequency min(t, until)); for a rotation, the turn by that many
/// degrees about the unit `axis` (then rest, a quaternion, after it: q = turn * rest).
export function channelValue(channel, t) {
  const s = channel.amplitude * Math.sin(2 * Math.PI * channel.frequency * Math.min(t, channel.until));
  if (channel.path === 'translation') return channel.rest.map((r, i) => r + s * channel.axis[i]);
  const half = (s * Math.PI) / 360;
  const turn = [...channel.axis.map((a) => a * Math.sin(half)), Math.cos(half)];
  return quatMultiply(turn, channel.rest);
}

export function quatMultiply(a, b) {
  const [ax, ay, az, aw] = a;
  const [bx, by, bz, bw] = b;
  return [
    aw * bx + ax * bw + ay * bz - az * by,
    aw * by - ax * bz + ay * bw + az * bx,
    aw * bz + ax * by - ay * bx + az * bw,
    aw * bw - ax * bx - ay * by - az * bz,
  ];
}

export function rotate(q, v) {
  const [x, y, z, w] = q;
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const t = cross([x, y, z], v).map((c) => 2 * c);
  const c2 = cross([x, y, z], t);
  return [v[0] + w * t[0] + c2[0], v[1] + w * t[1] + c2[1], v[2] + w * t[2] + c2[2]];
}

export function frameCount(motion) {
  return Math.round(motion.seconds * FPS) + 1;
}

/// The nodes' local {t, r} at frame f: the file's, with the motion's channels applied.
export function localPose(json, motion, f) {
  const pose = json.nodes.map((n) => ({ t: n.translation ?? [0, 0, 0], r: n.rotation ?? [0, 0, 0, 1] }));
  for (const c of motion.channels) {
    const i = json.nodes.findIndex((n) => n.name === c.node);
    pose[i] = { ...pose[i], [c.path === 'translation' ? 't' : 'r']: channelValue(c, f / FPS) };
  }
  return pose;
}

/// World {t, r} of every node at frame f (the setups have no scale).
export function worldPose(json, motion, f) {
  const local = localPose(json, motion, f);
  const parent = new Array(json.nodes.length).fill(-1);
  json.nodes.forEach((n, i) => (n.children ?? []).forEach((c) => (parent[c] = i)));
  const world = [];
  const get = (i) => {
    if (world[i]) return world[i];
    const l = local[i];
    if (parent[i] < 0) return (world[i] = l);
    const p = get(parent[i]);
    return (world[i] = { t: rotate(p.r, l.t).map((v, k) => v + p.t[k]), r: quatMultiply(p.r, l.r) });
  };
  return json.nodes.map((_, i) => get(i));
}

// ---------------------------------------------------------------------------------------
// Building the setups.

function joint(node, extra = {}) {
  return { node, hitRadius: HIT, stiffness: 1, gravityPower: 0, gravityDir: [0, -1, 0], dragForce: 0.4, ...extra };
}

/// A straight spring of n joints named prefix_0.., the first at `start` in its parent's
/// frame, each next one L along `dir` (unit). Returns {nodes (to append), first, joints}.
function strand(prefix, first, start, dir, n, params = {}) {
  const nodes = [];
  for (let i = 0; i < n; ++i) {
    nodes.push({ name: `${prefix}_${i}`, translation: (i === 0 ? start : dir.map((d) => d * L)).map(round) });
    if (i + 1 < n) nodes[i].children = [first + i + 1];
  }
  // VRM 1.0 reads the last joint's parameters from nowhere (it is the tail): write none.
  const joints = nodes.map((_, i) => (i + 1 < n ? joint(first + i, params) : { node: first + i }));
  return { nodes, first, joints };
}

/// A setup: the scene root "Motion" (animated), optionally under "Center", the spring(s)
/// below it, and collider nodes at the scene's root.
function setup({ springs, colliders = [], center = false, branch = false }) {
  const nodes = [];
  const roots = [];
  if (center) {
    nodes.push({ name: 'Center', children: [1] });
    roots.push(0);
  }
  const motion = nodes.length;
  nodes.push({ name: 'Motion', children: [] });
  if (!center) roots.push(motion);
  let holder = motion;
  if (branch) {
    // The branching joint: a kinematic node with two springs below it.
    nodes.push({ name: 'Branch', translation: [0, ROOT_Y, 0], children: [] });
    nodes[motion].children.push(nodes.length - 1);
    holder = nodes.length - 1;
  }
  const ext = { specVersion: '1.0', springs: [] };
  for (const s of springs) {
    const built = strand(s.name, nodes.length, s.start, s.dir, s.joints, s.params);
    nodes[holder].children.push(nodes.length);
    nodes.push(...built.nodes);
    const spring = { name: s.name, joints: built.joints };
    if (colliders.length) spring.colliderGroups = [0];
    if (center) spring.center = 0;
    ext.springs.push(spring);
  }
  if (colliders.length) {
    ext.colliders = [];
    for (const c of colliders) {
      roots.push(nodes.length);
      ext.colliders.push({ node: nodes.length, ...c.shape });
      nodes.push({ name: 'Collider', translation: c.at.map(round) });
    }
    ext.colliderGroups = [{ name: 'colliders', colliders: ext.colliders.map((_, i) => i) }];
  }
  const extended = ext.colliders?.some((c) => c.extensions);
  return {
    asset: { version: '2.0', generator: 'kodawari tests/conformance/make_vectors.mjs' },
    extensionsUsed: ['VRMC_springBone', ...(extended ? ['VRMC_springBone_extended_collider'] : [])],
    scene: 0,
    scenes: [{ nodes: roots }],
    nodes,
    extensions: { VRMC_springBone: ext },
  };
}

const DOWN = [0, -1, 0];
const chainSpring = (params) => ({ name: 'chain', start: [0, ROOT_Y, 0], dir: DOWN, joints: 5, params });

/// The sideways sway of the chain cases (along x): a tenth of a bone, where both sides'
/// swings are linear (the conformance test's models), 1 Hz (below the bone's 2.5 Hz:
/// omega^2 = 60 stiffness / L), then a hold from 2.75 s (an extreme of the sway: the
/// chain is let go with the root still) to 5 s, so the free decay shows.
const SWAY = { node: 'Motion', path: 'translation', rest: [0, 0, 0], axis: [1, 0, 0], amplitude: 0.025, frequency: 1, until: 2.75 };

/// A collider case's swing: along x, 1 Hz, 2.5 s (ending at a zero crossing, the root
/// moving fastest: the chain swings on and settles back onto its rest shape, clear of the
/// collider) and a hold to 4.5 s.
const swingX = (amplitude) => ({ channels: [{ ...SWAY, amplitude, until: 2.5 }], seconds: 4.5 });

// The base shapes of the extended colliders, for readers without the extension (as in
// three-vrm's samples): for the plane a big sphere behind it, for the inside shapes a
// point far away (such a reader cannot keep a joint inside anything).
const BEHIND_PLANE = { sphere: { offset: [707.106781187, -707.106781187, 0], radius: 1000 } };
const NOWHERE = { sphere: { offset: [10000, 0, 0], radius: 0 } };
const extended = (shape, fallback) => ({
  shape: fallback,
  extensions: { VRMC_springBone_extended_collider: { specVersion: '1.0', shape } },
});

// Each case: name, what it is for, the setup's glTF, the motion {channels, seconds}.
export const CASES = [
  {
    name: 'chain',
    about: 'One spring of 5 joints (4 bones of 0.25 m) hanging from a root that sways sideways (x) by 2.5 cm at 1 Hz, then holds from 2.75 s.',
    gltf: setup({ springs: [chainSpring()] }),
    motion: { channels: [SWAY], seconds: 5 },
  },
  {
    name: 'chain-sag',
    about: 'The same spring pointing along +x (horizontal), gravityPower 0.1, the root still: it sags from its rest shape to equilibrium.',
    gltf: setup({ springs: [{ ...chainSpring({ gravityPower: 0.1 }), dir: [1, 0, 0] }] }),
    motion: { channels: [{ ...SWAY, amplitude: 0 }], seconds: 3 },
  },
  {
    name: 'branch',
    about: 'A branching joint ("Branch", kinematic) with two springs of 4 joints below it in a horizontal V, each 30 degrees to its side of +z and starting 2 cm to its side, gravityPower 0.1; the root bobs up and down (y) by 2.5 cm at 1 Hz, then holds.',
    gltf: setup({
      branch: true,
      springs: [-1, 1].map((side) => ({
        name: side < 0 ? 'left' : 'right',
        start: [0.02 * side, 0, 0],
        dir: [0.5 * side, 0, Math.sqrt(3) / 2],
        joints: 4,
        params: { gravityPower: 0.1 },
      })),
    }),
    motion: { channels: [{ ...SWAY, axis: [0, 1, 0] }], seconds: 5 },
  },
  {
    name: 'sphere',
    about: 'The chain and a sphere collider (r 0.2 m) beside it; the root swings into it along x by 0.35 m at 1 Hz for 2.5 s, then holds.',
    gltf: setup({ springs: [chainSpring()], colliders: [{ at: [0.42, 0.85, 0], shape: { shape: { sphere: { offset: [0, 0, 0], radius: 0.2 } } } }] }),
    motion: swingX(0.35),
  },
  {
    name: 'capsule',
    about: 'The chain and a tilted capsule collider (r 0.1 m, 0.6 m long) beside it; the root swings into it along x by 0.35 m at 1 Hz for 2.5 s, then holds.',
    gltf: setup({ springs: [chainSpring()], colliders: [{ at: [0.35, 0.6, 0], shape: { shape: { capsule: { offset: [0, 0, -0.15], tail: [0, 0.55, 0.15], radius: 0.1 } } } }] }),
    motion: swingX(0.35),
  },
  {
    name: 'plane',
    about: 'The chain and a plane collider (extended collider) slanting under it, normal up and towards -x; the root swings along x by 0.35 m at 1 Hz for 2.5 s, then holds.',
    gltf: setup({
      springs: [chainSpring()],
      colliders: [{ at: [0.3, 0.6, 0], shape: extended({ plane: { offset: [0, 0, 0], normal: [-Math.SQRT1_2, Math.SQRT1_2, 0].map(round) } }, BEHIND_PLANE) }],
    }),
    motion: swingX(0.35),
  },
  {
    name: 'inside-sphere',
    about: 'The chain inside a sphere collider (extended collider, inside; r 1 m, its centre 0.35 m to the chain\'s -x side and 0.2 m below the root); the root swings along x by 0.35 m at 1 Hz for 2.5 s, then holds.',
    gltf: setup({
      springs: [chainSpring()],
      colliders: [{ at: [-0.35, 1.3, 0], shape: extended({ sphere: { offset: [0, 0, 0], radius: 1, inside: true } }, NOWHERE) }],
    }),
    motion: swingX(0.35),
  },
  {
    name: 'inside-capsule',
    about: 'The chain inside a leaning capsule collider (extended collider, inside; r 0.4 m, its axis from above the root down to 0.25 m on the chain\'s -x side below the tip); the root swings along x by 0.3 m at 1 Hz for 2.5 s, then holds.',
    gltf: setup({
      springs: [chainSpring()],
      colliders: [{ at: [0, 1.6, 0], shape: extended({ capsule: { offset: [0, 0, 0], tail: [-0.25, -1.2, 0], radius: 0.4, inside: true } }, NOWHERE) }],
    }),
    motion: swingX(0.3),
  },
  {
    name: 'center',
    about: 'The chain case below a "Center" node (the spring\'s center) that runs 0.5 m along z and turns 30 degrees about y at 0.5 Hz (with the sway, then the same hold): relative to Center, the chain must move as in the chain case.',
    gltf: setup({ springs: [chainSpring()], center: true }),
    motion: {
      channels: [
        { node: 'Center', path: 'translation', rest: [0, 0, 0], axis: [0, 0, 1], amplitude: 0.5, frequency: 0.5, until: 2.75 },
        { node: 'Center', path: 'rotation', rest: [0, 0, 0, 1], axis: [0, 1, 0], amplitude: 30, frequency: 0.5, until: 2.75 },
        SWAY,
      ],
      seconds: 5,
    },
  },
];

// ---------------------------------------------------------------------------------------
// The .glb our side reads: the setup with a glTF animation "motion" that carries exactly
// the motion (a LINEAR key per frame on each channel, one second beyond the run: a
// rigged character's clip loops, and the run's last frame must not wrap round).

export function packGlb(json, motion) {
  const out = structuredClone(json);
  const n = frameCount(motion) + FPS;
  const parts = [];
  let length = 0;
  out.bufferViews = [];
  out.accessors = [];
  const add = (array, type) => {
    const bytes = Buffer.from(array.buffer, array.byteOffset, array.byteLength);
    parts.push(bytes);
    out.bufferViews.push({ buffer: 0, byteOffset: length, byteLength: bytes.length });
    length += bytes.length; // float arrays: a multiple of 4
    const width = type === 'SCALAR' ? 1 : type === 'VEC3' ? 3 : 4;
    const lo = new Array(width).fill(Infinity);
    const hi = new Array(width).fill(-Infinity);
    for (let i = 0; i < array.length; ++i) {
      lo[i % width] = Math.min(lo[i % width], array[i]);
      hi[i % width] = Math.max(hi[i % width], array[i]);
    }
    out.accessors.push({ bufferView: out.bufferViews.length - 1, componentType: 5126, count: array.length / width, type, min: lo, max: hi });
    return out.accessors.length - 1;
  };
  const times = new Float32Array(n);
  for (let f = 0; f < n; ++f) times[f] = f / FPS;
  const input = add(times, 'SCALAR');
  const animation = { name: 'motion', samplers: [], channels: [] };
  for (const c of motion.channels) {
    const width = c.path === 'translation' ? 3 : 4;
    const values = new Float32Array(width * n);
    for (let f = 0; f < n; ++f) values.set(channelValue(c, f / FPS), width * f);
    animation.samplers.push({ input, output: add(values, width === 3 ? 'VEC3' : 'VEC4'), interpolation: 'LINEAR' });
    animation.channels.push({ sampler: animation.samplers.length - 1, target: { node: out.nodes.findIndex((x) => x.name === c.node), path: c.path } });
  }
  out.animations = [animation];
  out.buffers = [{ byteLength: length }];
  return glbBytes(out, Buffer.concat(parts, length));
}
