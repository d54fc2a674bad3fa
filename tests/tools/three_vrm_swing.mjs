#!/usr/bin/env node
// Drives three-vrm's own spring bones (pixiv's @pixiv/three-vrm-springbone, the reference
// implementation of VRMC_springBone) through a prescribed motion of a spring's root node,
// headless in Node, and writes every joint's world position per frame (issue 18).
//
//   node three_vrm_swing.mjs SAMPLE.gltf --out JOINTS.json [--copy COPY.glb] [options]
//
// SAMPLE is one of tests/assets/vrm-springbone/{sphere,plane,inside}-collider.gltf (a
// 5-joint spring "Spring A".."Spring E" rooted at node 0, a "Collider" node, no animation).
// The copy gets a node "Motion", at the origin, as the parent of the spring's root node;
// the motion moves it, and with it the spring's root: Motion's translation is d(t) along
// --axis,
//   d(t) = A sin(2 pi f t) for t <= swing, then d(swing) (a hold: the free decay shows),
// over --seconds at 60 frames per second. A parent moves, not the root node itself,
// because three-vrm turns a joint's node about the translation it had at load time (its
// initial local matrix): a joint node is a bone whose own translation stays put, and a
// spring hangs from a moving parent (a head, a hip), as here. Options:
//   --axis x|y|z  (x)   --amplitude A m (0.25)   --frequency f Hz (1)   --swing s (2.75)
//   --seconds T (6)     --drag D (every joint's dragForce; default: the file's)
//   --gravity-power P   (every joint's gravityPower; default: the file's)
//   --horizontal        (turn the root node 90 degrees about +z: the spring then points
//                        along +x, so gravity (gravityDir -y) bends it: the sag case)
//   --no-colliders      (the spring collides with nothing)
//   --joints N          (the spring's first N joints only: 2 is one bone, the case the
//                        documented mapping is about)
//   --collider-scale S  (the collider nodes' scale: three-vrm uses collider radii as
//                        written, we scale them by the node's world scale; at 1 the two
//                        agree)
//   --copy COPY.glb     also write the modified file as one .glb with a glTF animation
//                       "root_motion" carrying exactly this motion (a LINEAR key per frame
//                       on Motion's translation), for `kodawari rig` (the other side of
//                       the comparison, tests/three_vrm/compare.mjs)
//
// The file is loaded with three.js's GLTFLoader and three-vrm's VRMSpringBoneLoaderPlugin
// through parse(), as an application loads it. The sample's external .bin buffers are read
// from disk and packed with the JSON into one in-memory .glb (one BIN chunk, the buffer
// views moved), because GLTFLoader fetches external and data: buffers with three's
// FileLoader, which needs the browser's ProgressEvent that Node does not have. Frame 0 is
// the file's rest pose; each later frame sets Motion's translation and calls
// VRMSpringBoneManager.update(1/60) once (VRM's reference rate), then reads the world
// positions. Output JSON: {"fps":60,"frames":N,"joints":["Spring A",...],"hit_radius":[..],
// "positions":[[[x,y,z] per joint] per frame],"motion":{...},"colliders":[...]}, where
// hit_radius and colliders are what three-vrm built (world space; radii as three-vrm uses
// them: as written in the file, not scaled by the nodes' scale).
//
// Tools: three and @pixiv/three-vrm-springbone from .tools/npm (scripts/setup), or the
// folder KODAWARI_NODE_TOOLS names. Exit status: 0 written, 2 usage, I/O or load error.
import { readFileSync, writeFileSync } from 'node:fs';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

export const FPS = 60;

function fail(message) {
  console.error(`three_vrm_swing: ${message}`);
  process.exit(2);
}

/// Motion's (the spring root's) offset along the motion axis at time t (s).
export function displacement(motion, t) {
  const { amplitude, frequency, swing } = motion;
  return amplitude * Math.sin(2 * Math.PI * frequency * Math.min(t, swing));
}

export function frameCount(motion) {
  return Math.round(motion.seconds * FPS) + 1;
}

/// The clip holds one second more than the run: a scene character's clip loops, and the
/// run's last frame must not wrap round to the clip's start.
const CLIP_EXTRA_FRAMES = FPS;

const AXES = { x: [1, 0, 0], y: [0, 1, 0], z: [0, 0, 1] };

/// The sample's JSON with its external buffers read from beside it: {json, buffers}.
export function readSample(file) {
  const json = JSON.parse(readFileSync(file, 'utf8'));
  const buffers = json.buffers.map((b) => {
    if (!b.uri) throw new Error(`${file}: a buffer without uri`);
    const bytes = readFileSync(path.join(path.dirname(file), decodeURIComponent(b.uri)));
    if (bytes.length < b.byteLength) throw new Error(`${file}: ${b.uri} is shorter than its byteLength`);
    return bytes.subarray(0, b.byteLength);
  });
  return { json, buffers };
}

/// The case's changes to the sample: the Motion node above the spring's root, spring
/// parameters, the horizontal turn of the root, colliders off. Returns a new JSON object.
export function modify(json, options) {
  const out = structuredClone(json);
  const ext = out.extensions.VRMC_springBone;
  const rootNode = ext.springs[0].joints[0].node;
  const scene = out.scenes[out.scene || 0];
  if (!scene.nodes.includes(rootNode)) throw new Error('the spring\'s root node is not a root of the scene');
  out.nodes.push({ name: 'Motion', children: [rootNode] });
  scene.nodes = scene.nodes.map((n) => (n === rootNode ? out.nodes.length - 1 : n));
  for (const spring of ext.springs) {
    for (const joint of spring.joints) {
      if (options.drag !== undefined) joint.dragForce = options.drag;
      if (options.gravityPower !== undefined) joint.gravityPower = options.gravityPower;
    }
    if (options.joints !== undefined) spring.joints = spring.joints.slice(0, options.joints);
    if (options.noColliders) delete spring.colliderGroups;
  }
  if (options.colliderScale !== undefined) {
    for (const collider of ext.colliders || []) out.nodes[collider.node].scale = [1, 1, 1].map(() => options.colliderScale);
  }
  if (options.horizontal) {
    const root = out.nodes[ext.springs[0].joints[0].node];
    root.rotation = [0, 0, Math.SQRT1_2, Math.SQRT1_2]; // +90 degrees about +z: -y -> +x
  }
  return out;
}

function pad4(n) {
  return (n + 3) & ~3;
}

/// The node modify() added above the spring's root.
export function motionNode(json) {
  const index = json.nodes.findIndex((node) => node.name === 'Motion');
  if (index < 0) throw new Error('no Motion node (the file did not go through modify())');
  return index;
}

/// One .glb from the JSON and its buffers (all buffers merged into the BIN chunk), and,
/// when `motion` is given, an animation "root_motion" with a LINEAR translation key per
/// frame on the Motion node.
export function packGlb(json, buffers, motion) {
  const out = structuredClone(json);
  const parts = [];
  const starts = [];
  let length = 0;
  for (const bytes of buffers) {
    starts.push(length);
    parts.push(bytes);
    const padded = pad4(bytes.length);
    if (padded > bytes.length) parts.push(Buffer.alloc(padded - bytes.length));
    length += padded;
  }
  for (const view of out.bufferViews) {
    view.byteOffset = (view.byteOffset || 0) + starts[view.buffer];
    view.buffer = 0;
  }
  if (motion) {
    const target = motionNode(out);
    const axis = AXES[motion.axis];
    const n = frameCount(motion) + CLIP_EXTRA_FRAMES;
    const times = new Float32Array(n);
    const translations = new Float32Array(3 * n);
    const lo = [Infinity, Infinity, Infinity];
    const hi = [-Infinity, -Infinity, -Infinity];
    for (let f = 0; f < n; ++f) {
      times[f] = f / FPS;
      const d = displacement(motion, f / FPS);
      for (let c = 0; c < 3; ++c) {
        translations[3 * f + c] = d * axis[c];
        lo[c] = Math.min(lo[c], translations[3 * f + c]);
        hi[c] = Math.max(hi[c], translations[3 * f + c]);
      }
    }
    const views = [times, translations].map((array) => {
      const bytes = Buffer.from(array.buffer, array.byteOffset, array.byteLength);
      parts.push(bytes);
      out.bufferViews.push({ buffer: 0, byteOffset: length, byteLength: bytes.length });
      length += bytes.length; // float arrays: already a multiple of 4
      return out.bufferViews.length - 1;
    });
    const accessors = out.accessors;
    // glTF wants min/max as the float32 values stored.
    const f32 = (v) => Math.fround(v);
    accessors.push({ bufferView: views[0], componentType: 5126, count: n, type: 'SCALAR',
      min: [0], max: [f32(times[n - 1])] });
    accessors.push({ bufferView: views[1], componentType: 5126, count: n, type: 'VEC3',
      min: lo.map(f32), max: hi.map(f32) });
    out.animations = [{
      name: 'root_motion',
      samplers: [{ input: accessors.length - 2, output: accessors.length - 1, interpolation: 'LINEAR' }],
      channels: [{ sampler: 0, target: { node: target, path: 'translation' } }],
    }];
  }
  out.buffers = [{ byteLength: length }];
  return glbBytes(out, Buffer.concat(parts, length));
}

/// A glTF binary file of `json` and its one buffer `bin` (4-byte aligned).
export function glbBytes(json, bin) {
  let text = Buffer.from(JSON.stringify(json), 'utf8');
  text = Buffer.concat([text, Buffer.alloc(pad4(text.length) - text.length, 0x20)]);
  const header = Buffer.alloc(12);
  header.writeUInt32LE(0x46546c67, 0); // "glTF"
  header.writeUInt32LE(2, 4);
  header.writeUInt32LE(12 + 8 + text.length + 8 + bin.length, 8);
  const chunk = (bytes, type) => {
    const h = Buffer.alloc(8);
    h.writeUInt32LE(bytes.length, 0);
    h.writeUInt32LE(type, 4);
    return [h, bytes];
  };
  return Buffer.concat([header, ...chunk(text, 0x4e4f534a), ...chunk(bin, 0x004e4942)]);
}

/// The Node modules from the tools folder.
export async function loadTools(toolsDir) {
  const url = (p) => pathToFileURL(path.join(toolsDir, 'node_modules', p)).href;
  try {
    const THREE = await import(url('three/build/three.module.js'));
    const { GLTFLoader } = await import(url('three/examples/jsm/loaders/GLTFLoader.js'));
    const springbone = await import(url('@pixiv/three-vrm-springbone/lib/three-vrm-springbone.module.js'));
    return { THREE, GLTFLoader, springbone };
  } catch (error) {
    throw new Error(`cannot load three and @pixiv/three-vrm-springbone from ${toolsDir}/node_modules (run scripts/setup): ${error.message}`);
  }
}

/// Runs three-vrm on the .glb bytes with the motion: the per-frame joint positions.
export async function simulate(tools, glb, motion) {
  const { THREE, GLTFLoader, springbone } = tools;
  const loader = new GLTFLoader();
  loader.register((parser) => new springbone.VRMSpringBoneLoaderPlugin(parser));
  const bytes = new Uint8Array(glb);
  const gltf = await loader.parseAsync(bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength), '');
  const manager = gltf.userData.vrmSpringBoneManager;
  if (!manager) throw new Error('three-vrm found no spring bones in the file');
  const json = gltf.parser.json;
  const spring = json.extensions.VRMC_springBone.springs[0];
  const nodes = await gltf.parser.getDependencies('node');
  const chain = spring.joints.map((j) => nodes[j.node]);
  const mover = nodes[motionNode(json)];
  const axis = new THREE.Vector3(...AXES[motion.axis]);
  const n = frameCount(motion);
  const world = new THREE.Vector3();
  const read = () => chain.map((node) => {
    node.getWorldPosition(world);
    return [world.x, world.y, world.z];
  });
  const positions = [read()];
  for (let f = 1; f < n; ++f) {
    mover.position.copy(axis).multiplyScalar(displacement(motion, f / FPS));
    manager.update(1 / FPS);
    positions.push(read());
  }
  const colliders = manager.colliders.map((collider) => {
    collider.updateWorldMatrix(true, false);
    const centre = new THREE.Vector3().setFromMatrixPosition(collider.colliderMatrix);
    const shape = collider.shape;
    const entry = { type: shape.type, centre: centre.toArray() };
    if (shape.type === 'plane') {
      entry.normal = shape.normal.clone().applyNormalMatrix(new THREE.Matrix3().getNormalMatrix(collider.colliderMatrix)).normalize().toArray();
    } else {
      entry.radius = shape.radius;
      entry.inside = Boolean(shape.inside);
    }
    return entry;
  });
  const joints = [...manager.joints];
  return {
    fps: FPS,
    frames: n,
    joints: spring.joints.map((j) => json.nodes[j.node].name ?? `node ${j.node}`),
    hit_radius: joints.map((j) => j.settings.hitRadius),
    positions,
    motion,
    colliders,
  };
}

/// Command-line options to {sample, out, copy, motion, modify}.
export function parseArgs(args) {
  const motion = { axis: 'x', amplitude: 0.25, frequency: 1, swing: 2.75, seconds: 6 };
  const changes = {};
  let sample = null;
  let out = null;
  let copy = null;
  const number = (i, name) => {
    const v = Number(args[i]);
    if (args[i] === undefined || !Number.isFinite(v)) throw new Error(`${name} needs a number`);
    return v;
  };
  for (let i = 0; i < args.length; ++i) {
    const a = args[i];
    if (a === '--out') out = args[++i];
    else if (a === '--copy') copy = args[++i];
    else if (a === '--axis') {
      motion.axis = args[++i];
      if (!AXES[motion.axis]) throw new Error('--axis is x, y or z');
    } else if (a === '--amplitude') motion.amplitude = number(++i, a);
    else if (a === '--frequency') motion.frequency = number(++i, a);
    else if (a === '--swing') motion.swing = number(++i, a);
    else if (a === '--seconds') motion.seconds = number(++i, a);
    else if (a === '--drag') changes.drag = number(++i, a);
    else if (a === '--gravity-power') changes.gravityPower = number(++i, a);
    else if (a === '--horizontal') changes.horizontal = true;
    else if (a === '--no-colliders') changes.noColliders = true;
    else if (a === '--collider-scale') changes.colliderScale = number(++i, a);
    else if (a === '--joints') {
      changes.joints = number(++i, a);
      if (!Number.isInteger(changes.joints) || changes.joints < 2) throw new Error('--joints needs a whole number >= 2');
    }
    else if (a.startsWith('-')) throw new Error(`unknown option ${a}`);
    else if (sample === null) sample = a;
    else throw new Error('more than one sample given');
  }
  if (sample === null || out === null) throw new Error('usage: node three_vrm_swing.mjs SAMPLE.gltf --out JOINTS.json [--copy COPY.glb] [options]');
  return { sample, out, copy, motion, changes };
}

export function defaultToolsDir() {
  const here = path.dirname(fileURLToPath(import.meta.url));
  return process.env.KODAWARI_NODE_TOOLS || path.resolve(here, '..', '..', '.tools', 'npm');
}

if (process.argv[1] && path.resolve(process.argv[1]) === fileURLToPath(import.meta.url)) {
  let options;
  try {
    options = parseArgs(process.argv.slice(2));
  } catch (error) {
    fail(error.message);
  }
  try {
    const tools = await loadTools(defaultToolsDir());
    const { json, buffers } = readSample(options.sample);
    const glb = packGlb(modify(json, options.changes), buffers, options.motion);
    if (options.copy) writeFileSync(options.copy, glb);
    const result = await simulate(tools, glb, options.motion);
    writeFileSync(options.out, JSON.stringify(result));
  } catch (error) {
    fail(error.message);
  }
}
