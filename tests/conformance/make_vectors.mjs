#!/usr/bin/env node
// Writes the spring-bone conformance vectors (tests/conformance/README.md): for each case
// of cases.mjs, its setup (setups/NAME.gltf: nodes and a VRMC_springBone 1.0 extension,
// no meshes, no buffers) and the world position of every spring joint at every frame as
// pixiv's three-vrm simulates it (vectors/NAME.json).
//
//   node make_vectors.mjs [--out DIR] [--cases a,b,..]
//
// DIR defaults to this folder (tests/conformance); the test (conformance.mjs) writes to a
// temporary one and compares the bytes with the stored files. The run is deterministic:
// the same three-vrm and three.js write the same bytes.
//
// How three-vrm is driven, frame by frame (the same as tests/tools/three_vrm_swing.mjs):
// the setup is loaded with three.js's GLTFLoader and three-vrm's VRMSpringBoneLoaderPlugin
// (parse(), as an application loads a file); then the scene's world matrices are updated
// and setInitState() called again (see simulate()): frame 0 is the rest pose, every joint
// still. For each later frame f, each motion channel sets its
// node's local translation or rotation to its value at t = f / 60 s, then
// VRMSpringBoneManager.update(1 / 60) runs once, then every joint's world position is
// read. Positions are rounded to 1e-5 m (0.01 mm).
//
// Tools: three and @pixiv/three-vrm-springbone from .tools/npm (scripts/setup), or the
// folder KODAWARI_NODE_TOOLS names. Exit status: 0 written, 2 usage or a tool missing.
import { mkdirSync, readFileSync, writeFileSync } from 'node:fs';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';
import { CASES, FPS, channelValue, frameCount } from './cases.mjs';

const here = path.dirname(fileURLToPath(import.meta.url));
export const DIGITS = 5; // positions rounded to 1e-5 m

function fail(message) {
  console.error(`make_vectors: ${message}`);
  process.exit(2);
}

/// The Node modules and their versions from the tools folder.
export async function loadTools(toolsDir) {
  const modules = path.join(toolsDir, 'node_modules');
  const url = (p) => pathToFileURL(path.join(modules, p)).href;
  const version = (p) => JSON.parse(readFileSync(path.join(modules, p, 'package.json'), 'utf8')).version;
  try {
    const THREE = await import(url('three/build/three.module.js'));
    const { GLTFLoader } = await import(url('three/examples/jsm/loaders/GLTFLoader.js'));
    const springbone = await import(url('@pixiv/three-vrm-springbone/lib/three-vrm-springbone.module.js'));
    return { THREE, GLTFLoader, springbone, versions: { three: version('three'), '@pixiv/three-vrm-springbone': version('@pixiv/three-vrm-springbone') } };
  } catch (error) {
    throw new Error(`cannot load three and @pixiv/three-vrm-springbone from ${modules} (run scripts/setup): ${error.message}`);
  }
}

export function defaultToolsDir() {
  return process.env.KODAWARI_NODE_TOOLS || path.resolve(here, '..', '..', '.tools', 'npm');
}

/// A number as the files write it: at most `digits` decimals, no trailing zeros, no -0.
export function num(v, digits = DIGITS) {
  const s = v.toFixed(digits).replace(/\.?0+$/, '');
  return s === '-0' ? '0' : s;
}

/// three-vrm's joint positions for the setup `json` moved by `motion`:
/// {joints: names, positions: [frame][joint][xyz], colliders, hitRadius}.
export async function simulate(tools, json, motion) {
  const { THREE, GLTFLoader, springbone } = tools;
  const loader = new GLTFLoader();
  loader.register((parser) => new springbone.VRMSpringBoneLoaderPlugin(parser));
  const gltf = await loader.parseAsync(JSON.stringify(json), '');
  const manager = gltf.userData.vrmSpringBoneManager;
  if (!manager) throw new Error('three-vrm found no spring bones in the setup');
  // The loader's setInitState() runs before the scene's world matrices exist (three-vrm
  // 3.5.5's VRMC_springBone import does not update them first, its VRM 0.x import does):
  // a spring whose root hangs from a node away from the origin (the branch case) would
  // start with its tails where they would be were that node at the origin, and whip on
  // the first frame. An application updates its scene before the first frame; so do we,
  // and take the rest state again: frame 0 is the rest pose, every joint still.
  gltf.scene.updateMatrixWorld(true);
  manager.setInitState();
  const nodes = await gltf.parser.getDependencies('node');
  const springs = json.extensions.VRMC_springBone.springs;
  const jointNodes = springs.flatMap((s) => s.joints.map((j) => j.node));
  const byName = (name) => nodes[json.nodes.findIndex((n) => n.name === name)];
  const world = new THREE.Vector3();
  const read = () => jointNodes.map((i) => {
    nodes[i].getWorldPosition(world);
    return [world.x, world.y, world.z];
  });
  const positions = [read()];
  for (let f = 1; f < frameCount(motion); ++f) {
    for (const c of motion.channels) {
      const v = channelValue(c, f / FPS);
      const node = byName(c.node);
      if (c.path === 'translation') node.position.set(...v);
      else node.quaternion.set(...v);
    }
    manager.update(1 / FPS);
    positions.push(read());
  }
  const colliders = manager.colliders.map((collider) => {
    collider.updateWorldMatrix(true, false);
    const m = collider.colliderMatrix;
    const shape = collider.shape;
    const entry = { type: shape.type, centre: new THREE.Vector3().setFromMatrixPosition(m).toArray() };
    if (shape.type === 'plane') {
      entry.normal = shape.normal.clone().applyNormalMatrix(new THREE.Matrix3().getNormalMatrix(m)).normalize().toArray();
    } else {
      if (shape.type === 'capsule') entry.tail = shape.tail.clone().sub(shape.offset).applyMatrix4(m).toArray();
      entry.radius = shape.radius;
      entry.inside = Boolean(shape.inside);
    }
    return entry;
  });
  return {
    joints: jointNodes.map((i) => json.nodes[i].name),
    positions,
    colliders,
    hitRadius: [...manager.joints].map((j) => j.settings.hitRadius),
  };
}

/// Least clearance over all frames of every joint but each spring's first from the
/// colliders: distance to the surface less the joint's radius, negative where the
/// collider forbids (inside an outside shape, outside an inside one, behind a plane).
export function clearance(positions, isRoot, colliders, radius) {
  let least = Infinity;
  for (const frame of positions) {
    frame.forEach((p, j) => {
      if (isRoot[j]) return;
      for (const c of colliders) least = Math.min(least, shapeClearance(c, p, radius));
    });
  }
  return least;
}

export function shapeClearance(c, p, radius) {
  const d = p.map((v, i) => v - c.centre[i]);
  if (c.type === 'plane') return d[0] * c.normal[0] + d[1] * c.normal[1] + d[2] * c.normal[2] - radius;
  let q = d;
  if (c.type === 'capsule') {
    const axis = c.tail.map((v, i) => v - c.centre[i]);
    const t = Math.min(1, Math.max(0, (d[0] * axis[0] + d[1] * axis[1] + d[2] * axis[2]) / (axis[0] ** 2 + axis[1] ** 2 + axis[2] ** 2)));
    q = d.map((v, i) => v - t * axis[i]);
  }
  const r = Math.hypot(...q);
  return c.inside ? c.radius - radius - r : r - c.radius - radius;
}

/// The vectors file: its fields in a fixed order, one frame per line.
function vectorsText(c, result, freeClearance, versions) {
  const json = c.gltf;
  const springs = json.extensions.VRMC_springBone.springs;
  const isRoot = springs.flatMap((s) => s.joints.map((_, i) => i === 0));
  const head = {
    format: 'kodawari spring conformance vectors 1',
    case: c.name,
    about: c.about,
    setup: `setups/${c.name}.gltf`,
    made_by: { script: 'tests/conformance/make_vectors.mjs', ...versions },
    fps: FPS,
    dt: 1 / FPS,
    frames: frameCount(c.motion),
    start: 'frame 0 is the rest pose with every joint still (three-vrm setInitState); frame f >= 1: the channels set at t = f / fps, then one update(dt)',
    motion: {
      channels: c.motion.channels,
      seconds: c.motion.seconds,
      value: 'translation: rest + axis * amplitude * sin(2 pi frequency min(t, until)); rotation: the turn of amplitude * sin(2 pi frequency min(t, until)) degrees about axis, times rest',
    },
    springs: springs.map((s) => ({
      name: s.name,
      joints: s.joints.map((j) => json.nodes[j.node].name),
      parameters: s.joints.slice(0, -1).map(({ node, ...p }) => p),
      center: s.center === undefined ? null : json.nodes[s.center].name,
      colliders: (s.colliderGroups ?? []).flatMap((g) => json.extensions.VRMC_springBone.colliderGroups[g].colliders),
    })),
    colliders_world: result.colliders,
    ...(result.colliders.length ? { least_clearance: Number(num(clearance(result.positions, isRoot, result.colliders, result.hitRadius[0]))), least_clearance_without_colliders: Number(num(freeClearance)) } : {}),
    joints: result.joints,
    rounding_m: Number(`1e-${DIGITS}`),
  };
  const lines = compact(head).split('\n');
  lines.pop(); // the closing brace
  lines[lines.length - 1] += ',';
  lines.push(' "positions": [');
  result.positions.forEach((frame, f) => {
    const text = frame.map((p) => `[${p.map((v) => num(v)).join(',')}]`).join(',');
    lines.push(`  [${text}]${f + 1 < result.positions.length ? ',' : ''}`);
  });
  lines.push(' ]', '}', '');
  return lines.join('\n');
}

/// JSON with one member per line but arrays of numbers and strings on one line.
export function compact(value) {
  return JSON.stringify(value, null, 1).replace(/\[\s*([^[\]{}]*?)\s*\]/g, (_, inner) => `[${inner.split(/,\s*/).join(', ')}]`);
}

function setupText(json) {
  return `${compact(json)}\n`;
}

/// Writes the chosen cases' setups and vectors under `out`.
export async function makeVectors(tools, out, names = null) {
  mkdirSync(path.join(out, 'setups'), { recursive: true });
  mkdirSync(path.join(out, 'vectors'), { recursive: true });
  const written = [];
  for (const c of CASES) {
    if (names && !names.includes(c.name)) continue;
    const result = await simulate(tools, c.gltf, c.motion);
    let free = null;
    if (result.colliders.length) {
      // The same swing without the colliders: how far they had to push (the file records it).
      const json = structuredClone(c.gltf);
      for (const s of json.extensions.VRMC_springBone.springs) delete s.colliderGroups;
      const freeRun = await simulate(tools, json, c.motion);
      const isRoot = json.extensions.VRMC_springBone.springs.flatMap((s) => s.joints.map((_, i) => i === 0));
      free = clearance(freeRun.positions, isRoot, result.colliders, result.hitRadius[0]);
    }
    const setupPath = path.join(out, 'setups', `${c.name}.gltf`);
    const vectorsPath = path.join(out, 'vectors', `${c.name}.json`);
    writeFileSync(setupPath, setupText(c.gltf));
    writeFileSync(vectorsPath, vectorsText(c, result, free, tools.versions));
    written.push(setupPath, vectorsPath);
  }
  return written;
}

if (process.argv[1] && path.resolve(process.argv[1]) === fileURLToPath(import.meta.url)) {
  let out = here;
  let names = null;
  const args = process.argv.slice(2);
  for (let i = 0; i < args.length; ++i) {
    if (args[i] === '--out' && args[i + 1]) out = args[++i];
    else if (args[i] === '--cases' && args[i + 1]) names = args[++i].split(',');
    else fail('usage: node make_vectors.mjs [--out DIR] [--cases a,b,..]');
  }
  for (const name of names ?? []) if (!CASES.some((c) => c.name === name)) fail(`no case ${name} (cases: ${CASES.map((c) => c.name).join(', ')})`);
  let tools;
  try {
    tools = await loadTools(defaultToolsDir());
  } catch (error) {
    fail(error.message);
  }
  const written = await makeVectors(tools, out, names);
  for (const file of written) console.log(`wrote ${path.relative(process.cwd(), file) || file}`);
}
