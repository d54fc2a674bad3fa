// ctest `meshopt_readers` (tests/meshopt/meshopt_test.sh; docs/compact.md, "--meshopt"):
// a `--compact --meshopt` file read by two real readers that decode EXT_meshopt_compression,
// each compared with the uncompacted bake of the same scene at every frame, node by node
// (by name):
//
// - three.js: GLTFLoader with its MeshoptDecoder; every track of the loaded clip sampled
//   with the track's own interpolant (what AnimationMixer evaluates: lerp, slerpFlat);
// - gltf-transform: NodeIO with EXT_meshopt_compression and meshoptimizer's decoder; the
//   decoded accessors interpolated as glTF 2.0 Appendix C says (lerp; slerp the short way).
//
// Prints the worst translation distance, rotation angle and relative scale error of each
// reader, and fails when one passes the bound plus float rounding (below), or when the two
// files do not animate the same nodes.
//
//   node readers.mjs FULL.glb MESHOPT.glb METRES RADIANS TOOLS_DIR
import { readFileSync } from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';

const [fullPath, meshoptPath, metresText, radiansText, toolsDir] = process.argv.slice(2);
if (!toolsDir) {
  console.error('usage: node readers.mjs FULL.glb MESHOPT.glb METRES RADIANS TOOLS_DIR');
  process.exit(2);
}
const bound = { translation: Number(metresText), rotation: Number(radiansText), scale: Number(radiansText) };
const url = (p) => pathToFileURL(path.join(toolsDir, 'node_modules', p)).href;
let THREE, GLTFLoader, MeshoptDecoder, core, extensions, meshoptimizer;
try {
  THREE = await import(url('three/build/three.module.js'));
  ({ GLTFLoader } = await import(url('three/examples/jsm/loaders/GLTFLoader.js')));
  ({ MeshoptDecoder } = await import(url('three/examples/jsm/libs/meshopt_decoder.module.js')));
  core = await import(url('@gltf-transform/core/dist/index.js'));
  extensions = await import(url('@gltf-transform/extensions/dist/index.js'));
  meshoptimizer = await import(url('meshoptimizer/index.js'));
} catch (error) {
  console.error(`meshopt_readers: cannot load three, @gltf-transform and meshoptimizer from ${toolsDir} (run scripts/setup): ${error.message}`);
  process.exit(1);
}

// Float rounding beyond the bound, which the reducer measures in double precision on the
// float keys: a reader interpolates in float32 (three.js stores every sampled value in a
// Float32Array; gltf-transform's arrays are Float32Arrays, interpolated here in doubles).
// A float32 result is within half an ulp (2^-24 relative) of the double one, and its
// inputs too: two ulps of the largest coordinate, 2^-22 x |x|max per component, covers
// a translation (flock.json's birds stay within 100 m: 4e-5 m); a rotation's unit
// components give 1e-6 rad; a scale near 1, 1e-6.
const slack = { translation: 0, rotation: 1e-6, scale: 1e-6 };

function angle(a, b) {
  const na = Math.hypot(...a);
  const nb = Math.hypot(...b);
  const d = Math.min(1, Math.abs((a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]) / (na * nb)));
  return 2 * Math.acos(d);
}
function errorOf(pathName, value, original) {
  if (pathName === 'rotation') return angle(value, original);
  if (pathName === 'translation') return Math.hypot(value[0] - original[0], value[1] - original[1], value[2] - original[2]);
  let worst = 0;
  for (let c = 0; c < 3; ++c) worst = Math.max(worst, Math.abs(value[c] - original[c]) / Math.abs(original[c]));
  return worst;
}

// glTF 2.0 Appendix C's LINEAR sampler: lerp, or slerp along the short arc.
function sample(times, values, width, t, rotation) {
  const n = times.length;
  let k = 0;
  let lo = 0;
  let hi = n;
  while (lo < hi) {
    const mid = (lo + hi) >> 1;
    if (times[mid] <= t) lo = mid + 1;
    else hi = mid;
  }
  k = lo;
  const at = (i) => Array.from(values.subarray(i * width, i * width + width));
  if (k === 0) return at(0);
  if (k === n) return at(n - 1);
  const a = at(k - 1);
  const b = at(k);
  const u = (t - times[k - 1]) / (times[k] - times[k - 1]);
  if (!rotation) return a.map((v, c) => v + (b[c] - v) * u);
  const na = Math.hypot(...a);
  const nb = Math.hypot(...b);
  let d = 0;
  for (let c = 0; c < 4; ++c) d += (a[c] / na) * (b[c] / nb);
  const s = d < 0 ? -1 : 1;
  const theta = Math.acos(Math.min(1, Math.abs(d)));
  let wa = 1 - u;
  let wb = u;
  if (theta > 1e-9) {
    wa = Math.sin(theta * (1 - u)) / Math.sin(theta);
    wb = Math.sin(theta * u) / Math.sin(theta);
  }
  return a.map((v, c) => wa * (v / na) + s * wb * (b[c] / nb));
}

// Every animated (node name, path) of a file read with gltf-transform: {times, values, width}.
async function transformTracks(file) {
  const io = new core.NodeIO()
    .registerExtensions(extensions.ALL_EXTENSIONS)
    .registerDependencies({ 'meshopt.decoder': meshoptimizer.MeshoptDecoder });
  await meshoptimizer.MeshoptDecoder.ready;
  const document = await io.read(file);
  const tracks = new Map();
  for (const animation of document.getRoot().listAnimations()) {
    for (const channel of animation.listChannels()) {
      const sampler = channel.getSampler();
      const node = channel.getTargetNode();
      const output = sampler.getOutput();
      // getArray() is the stored array (Int16Array for normalized shorts): decode as §3.11.
      let values = output.getArray();
      if (output.getNormalized()) values = Float32Array.from(values, (v) => core.MathUtils.decodeNormalizedInt(v, output.getComponentType()));
      tracks.set(`${node.getName()}|${channel.getTargetPath()}`, {
        times: sampler.getInput().getArray(),
        values,
        width: output.getElementSize(),
      });
    }
  }
  return tracks;
}

// The same from three.js: {interpolant, width} by "name|path".
async function threeTracks(file) {
  const loader = new GLTFLoader();
  loader.setMeshoptDecoder(MeshoptDecoder);
  const bytes = readFileSync(file);
  const gltf = await loader.parseAsync(bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength), '');
  const paths = { position: 'translation', quaternion: 'rotation', scale: 'scale' };
  const tracks = new Map();
  for (const clip of gltf.animations) {
    for (const track of clip.tracks) {
      const dot = track.name.lastIndexOf('.');
      tracks.set(`${track.name.slice(0, dot)}|${paths[track.name.slice(dot + 1)]}`, {
        interpolant: track.createInterpolant(),
        width: track.getValueSize(),
        times: track.times,
      });
    }
  }
  return tracks;
}

let failed = false;
function compare(reader, reference, evaluate) {
  const worst = { translation: 0, rotation: 0, scale: 0 };
  const where = {};
  let samples = 0;
  for (const [key, ref] of reference) {
    const pathName = key.split('|')[1];
    for (let f = 0; f < ref.times.length; ++f) {
      const t = ref.times[f];
      const original = Array.from(ref.values.subarray(f * ref.width, f * ref.width + ref.width));
      const value = evaluate(key, t);
      if (value === null) {
        console.error(`meshopt_readers: ${reader}: ${key} is animated in the uncompacted file only`);
        failed = true;
        return;
      }
      const e = errorOf(pathName, value, original);
      if (!(e <= worst[pathName])) {
        worst[pathName] = e;
        where[pathName] = `${key} at ${t.toFixed(4)} s`;
      }
      ++samples;
    }
  }
  const largest = {};
  for (const ref of reference.values()) {
    for (const v of ref.values) largest.translation = Math.max(largest.translation ?? 0, Math.abs(v));
  }
  const tolerance = {
    translation: bound.translation + Math.sqrt(3) * 2 ** -22 * largest.translation,
    rotation: bound.rotation + slack.rotation,
    scale: bound.scale + slack.scale,
  };
  console.log(`${reader}: ${samples} samples; worst translation ${(worst.translation * 1e3).toFixed(4)} mm (bound ${(tolerance.translation * 1e3).toFixed(4)}), ` +
    `rotation ${(worst.rotation * 1e3).toFixed(4)} mrad (bound ${(tolerance.rotation * 1e3).toFixed(4)}), scale ${(worst.scale * 1e2).toFixed(4)} % (bound ${(tolerance.scale * 1e2).toFixed(4)})`);
  for (const kind of Object.keys(worst)) {
    if (!(worst[kind] <= tolerance[kind])) {
      console.error(`meshopt_readers: ${reader}: ${kind} error ${worst[kind]} past ${tolerance[kind]} (${where[kind]})`);
      failed = true;
    }
  }
}

const reference = await transformTracks(fullPath);
if (reference.size === 0) {
  console.error(`meshopt_readers: ${fullPath} has no animation`);
  process.exit(1);
}
const transform = await transformTracks(meshoptPath);
const three = await threeTracks(meshoptPath);
for (const [name, tracks] of [['gltf-transform', transform], ['three.js', three]]) {
  if (tracks.size !== reference.size) {
    console.error(`meshopt_readers: ${name} reads ${tracks.size} animated channels, the uncompacted file has ${reference.size}`);
    failed = true;
  }
}
compare('gltf-transform', reference, (key, t) => {
  const track = transform.get(key);
  return track ? sample(track.times, track.values, track.width, t, key.endsWith('|rotation')) : null;
});
compare('three.js', reference, (key, t) => {
  // GLTFLoader names objects and tracks by sanitized node names ('/' is a path character
  // to three's PropertyBinding).
  const [name, pathName] = key.split('|');
  const track = three.get(`${THREE.PropertyBinding.sanitizeNodeName(name)}|${pathName}`);
  return track ? Array.from(track.interpolant.evaluate(t)) : null;
});
process.exit(failed ? 1 : 0);
