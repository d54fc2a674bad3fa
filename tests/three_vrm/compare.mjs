#!/usr/bin/env node
// Our VRM spring-bone mapping measured against three-vrm's own spring bones (issue 18;
// ctest three_vrm_comparison; docs/rigged-characters.md, "Measured against three-vrm").
//
//   node compare.mjs KODAWARI_BINARY SOURCE_DIR [--backends a,b,..] [--cases a,b,..]
//                    [--keep DIR] [--scale-gravity F] [--scale-damping F] [--json FILE]
//
// Each case takes one of three-vrm's sample springs (tests/assets/vrm-springbone/),
// changes it as the case says (tests/tools/three_vrm_swing.mjs: one bone or the whole
// 5-joint spring, drag, gravity, colliders), moves the spring's root by the case's motion
// and simulates it twice: in three-vrm (VRMSpringBoneManager.update(1/60) per frame, the
// reference implementation), and with `kodawari rig` + `kodawari run --trace` on every
// backend, the motion a glTF animation clip in the same .glb. The two models differ by
// design (engine/include/kodawari/gltf/vrm.hpp), so features are compared, not
// trajectories: a swing's gain and phase lag, the free decay after the root stops, the
// sag under gravity, the colliders' clearance.
//
// Our side runs in up to two variants: `rig`, the scene exactly as `kodawari rig` writes
// it (what users get), and `sm0`, the same with shape matching off (physics.stiffness 0),
// which leaves exactly the terms vrm.hpp maps (rest_stiffness, damping, gravity), so that
// its formulas can be checked on their own.
//
// Each check says what kind its bound is:
//   claim     vrm.hpp's mapping claims equality (one bone's swing frequency); the bound is
//             the error the header's approximations allow.
//   derived   a difference that follows from the two update rules, predicted below from
//             their one-bone linearisations (predict()) with our parameters computed by
//             the documented mapping formulas from VRM's, never read from the scene (so a
//             broken mapping or solver moves the measurement and not the prediction); the
//             bound is the linearisation's error at the case's amplitude.
//   measured  a difference beyond the mapping's claim (docs: expected differences), bound
//             to a band round today's measured value that a regression leaves: our gravity
//             or damping off by 25% takes at least one check of every case it acts in out
//             of its band. A fix of the difference fails it too: then move the check to
//             `claim` or `derived` and the docs' figure with it.
//   pending   what a collider kind our solver does not have yet must satisfy (plane,
//             inside): measured and printed, not enforced, until that support lands
//             (then: set `pending` to false in the case).
// --scale-gravity / --scale-damping multiply our side's mapped gravity / damping in the
// generated scenes: the way to watch this test fail. --json writes every measurement.
// Exit status: 0 every enforced check passed, 1 a check failed, 2 usage, a tool missing or
// a run that failed.
import { spawnSync } from 'node:child_process';
import { mkdirSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const swing = await import(pathToFileURL(path.join(here, '..', 'tools', 'three_vrm_swing.mjs')).href);
const { FPS } = swing;

function usage(message) {
  console.error(`three_vrm_comparison: ${message}`);
  process.exit(2);
}

// ---------------------------------------------------------------------------------------
// Features. P is [frame][joint][xyz]; `axis` the motion's axis index.

const AXIS = { x: 0, y: 1, z: 2 };

/// Least-squares fit of x_j(t) = G A sin(w t - lag) + c over frames [f0, f1]: {gain, lag}
/// (lag in degrees, positive: the joint follows the root late).
function transfer(P, j, motion, f0, f1) {
  const a = AXIS[motion.axis];
  const w = 2 * Math.PI * motion.frequency;
  // Normal equations of the basis (sin, cos, 1).
  const M = [[0, 0, 0], [0, 0, 0], [0, 0, 0]];
  const r = [0, 0, 0];
  for (let f = f0; f <= f1; ++f) {
    const t = f / FPS;
    const b = [Math.sin(w * t), Math.cos(w * t), 1];
    for (let i = 0; i < 3; ++i) {
      r[i] += b[i] * P[f][j][a];
      for (let k = 0; k < 3; ++k) M[i][k] += b[i] * b[k];
    }
  }
  const c = solve3(M, r);
  const gain = Math.hypot(c[0], c[1]) / motion.amplitude;
  // In [0, 360): a chain's tip can lag its root by more than half a period.
  const lag = (((Math.atan2(-c[1], c[0]) * 180) / Math.PI) % 360 + 360) % 360;
  return { gain, lag };
}

function solve3(M, r) {
  const m = M.map((row, i) => [...row, r[i]]);
  for (let i = 0; i < 3; ++i) {
    let p = i;
    for (let k = i + 1; k < 3; ++k) if (Math.abs(m[k][i]) > Math.abs(m[p][i])) p = k;
    [m[i], m[p]] = [m[p], m[i]];
    for (let k = 0; k < 3; ++k) {
      if (k === i) continue;
      const s = m[k][i] / m[i][i];
      for (let c = i; c < 4; ++c) m[k][c] -= s * m[i][c];
    }
  }
  return m.map((row, i) => row[3] / row[i]);
}

/// The joint's offset from the root along the motion axis, per frame.
function relative(P, j, motion) {
  const a = AXIS[motion.axis];
  return P.map((frame) => frame[j][a] - frame[0][a]);
}

/// Largest |offset from the root| along the axis over frames [f0, f1], m.
function peakDeflection(P, j, motion, f0, f1) {
  const rel = relative(P, j, motion);
  let peak = 0;
  for (let f = f0; f <= f1; ++f) peak = Math.max(peak, Math.abs(rel[f]));
  return peak;
}

/// The free decay after the hold begins (frame h): {frequency (Hz; null when the joint
/// crosses the rest line fewer than 3 times while its offset is above 2% of its largest),
/// rate (1/s: the offset's envelope falls as exp(-rate t))}. Oscillating: the frequency
/// from the mean spacing of the crossings, the rate from a line through ln |peak| of the
/// half swings between them. Not oscillating: the rate from a line through ln |offset|
/// while it falls from 30% to 3% of its largest.
function decay(P, j, motion, h) {
  const rel = relative(P, j, motion).slice(h);
  const big = Math.max(...rel.map(Math.abs));
  let end = rel.length - 1;
  while (end > 0 && Math.abs(rel[end]) < 0.02 * big) --end;
  const crossings = [];
  for (let f = 1; f <= end; ++f) {
    if ((rel[f - 1] < 0 && rel[f] >= 0) || (rel[f - 1] > 0 && rel[f] <= 0)) {
      crossings.push(f - 1 + rel[f - 1] / (rel[f - 1] - rel[f]));
    }
  }
  if (crossings.length >= 3) {
    const spacing = (crossings[crossings.length - 1] - crossings[0]) / (crossings.length - 1);
    const peaks = [];
    for (let i = 0; i + 1 < crossings.length; ++i) {
      let best = Math.ceil(crossings[i]);
      for (let f = best; f <= Math.floor(crossings[i + 1]); ++f) if (Math.abs(rel[f]) > Math.abs(rel[best])) best = f;
      peaks.push([best / FPS, Math.log(Math.abs(rel[best]))]);
    }
    return { frequency: FPS / (2 * spacing), rate: -slope(peaks) };
  }
  const start = rel.findIndex((v) => Math.abs(v) === big);
  const points = [];
  for (let f = start; f <= end; ++f) {
    const v = Math.abs(rel[f]);
    if (v <= 0.3 * big && v >= 0.03 * big) points.push([f / FPS, Math.log(v)]);
  }
  return { frequency: null, rate: points.length >= 3 ? -slope(points) : NaN };
}

function slope(points) {
  const n = points.length;
  const mx = points.reduce((s, p) => s + p[0], 0) / n;
  const my = points.reduce((s, p) => s + p[1], 0) / n;
  let sxy = 0;
  let sxx = 0;
  for (const [x, y] of points) {
    sxy += (x - mx) * (y - my);
    sxx += (x - mx) * (x - mx);
  }
  return sxy / sxx;
}

/// Mean angle (degrees) below the horizontal of the line from joint i to joint j over the
/// last second: the sag of a spring that points along +x at rest.
function sagAngle(P, i, j) {
  let sum = 0;
  const from = P.length - FPS;
  for (let f = from; f < P.length; ++f) {
    const [dx, dy] = [P[f][j][0] - P[f][i][0], P[f][j][1] - P[f][i][1]];
    sum += (Math.atan2(-dy, dx) * 180) / Math.PI;
  }
  return sum / (P.length - from);
}

/// Smallest clearance of the simulated joints (all but the root) from a collider, m: the
/// distance from the joint's centre to the shape's surface less the joint's radius,
/// negative inside (for an `inside` sphere: inside is allowed, beyond it is not).
function clearance(P, shape, jointRadius) {
  let least = Infinity;
  for (const frame of P) {
    for (let j = 1; j < frame.length; ++j) {
      const p = frame[j];
      const d = [p[0] - shape.centre[0], p[1] - shape.centre[1], p[2] - shape.centre[2]];
      let c;
      if (shape.type === 'plane') c = d[0] * shape.normal[0] + d[1] * shape.normal[1] + d[2] * shape.normal[2] - jointRadius;
      else if (shape.inside) c = shape.radius - jointRadius - Math.hypot(...d);
      else c = Math.hypot(...d) - shape.radius - jointRadius;
      least = Math.min(least, c);
    }
  }
  return least;
}

// ---------------------------------------------------------------------------------------
// One bone, linearised: the predictions of the `derived` checks.
//
// VRM (vrm.hpp's file comment): per 60 Hz frame the tail moves by its inertia
// (1 - drag)(tail - prevTail) plus stiffness dt along the rest direction and is put back
// at the bone's length L from the head. For a small lateral offset y - u of the tail from
// the head (u: the head's, i.e. the root's, lateral position), the rest term stretches the
// bone by stiffness dt and the length projection scales the whole lateral step by
// rho = L / (L + stiffness dt):
//   y[n+1] - u[n+1] = rho (y[n] - u[n+1] + (1 - drag)(y[n] - y[n-1])).
// So VRM's rest term damps too (rho < 1 multiplies the inertia), which the mapping's
// damping formula does not count. Under gravity (a horizontal bone) the tail's direction
// at rest is along stiffness * rest + gravityPower * gravityDir: tan(sag) = gP / s.
//
// Ours (rods/solver.hpp; solver.cpp's substep), shape matching off, per substep h =
// 1/120 s (SolverParams' default, which rig keeps): v <- e (v + h g) with e =
// exp(-damping h), p = x + h v, p moves k = rest_stiffness of the way to its rest place
// (compounded over the iterations), the distance constraint acts along the bone (no
// lateral change to first order), v = (p - x) / h:
//   x[n+1] = (1 - k)(x[n] + e (x[n] - x[n-1])) + k u[n+1].
// The rest projection damps too (1 - k multiplies the inertia). At rest under gravity the
// substep's displacement is g h^2 e, held by k / (1 - k): the sag's offset is
// g h^2 e (1 - k) / k, which with the mapping's k and g is L (gP / s) e: tan(sag) =
// e gP / s. The damping factor e is not in vrm.hpp's sag formula.
//
// Both recurrences are z^2 + a1 z + a0 with input c z^2 U: the transfer function at
// z = exp(i w step) gives a sinusoidal swing's gain and lag; the roots give the free
// decay (complex: frequency arg(z) / (2 pi step), envelope rate -ln(a0) / (2 step); real:
// the slow root's rate -ln(z) / step).
function recurrence(a1, a0, c, step, frequency) {
  const w = 2 * Math.PI * frequency * step;
  const [zr, zi] = [Math.cos(w), Math.sin(w)];
  const z2 = [zr * zr - zi * zi, 2 * zr * zi];
  const den = [z2[0] + a1 * zr + a0, z2[1] + a1 * zi];
  const d2 = den[0] * den[0] + den[1] * den[1];
  const h = [(c * (z2[0] * den[0] + z2[1] * den[1])) / d2, (c * (z2[1] * den[0] - z2[0] * den[1])) / d2];
  const disc = a1 * a1 - 4 * a0;
  const free = disc < 0
    ? { frequency: Math.acos(-a1 / (2 * Math.sqrt(a0))) / (2 * Math.PI * step), rate: -Math.log(a0) / (2 * step) }
    : { frequency: null, rate: -Math.log((-a1 + Math.sqrt(disc)) / 2) / step };
  return { gain: Math.hypot(h[0], h[1]), lag: (-Math.atan2(h[1], h[0]) * 180) / Math.PI, ...free };
}

/// The one-bone predictions for VRM parameters {stiffness, drag, gravityPower, length}
/// at the swing frequency: {three, ours}, each {gain, lag, frequency, rate, sag_deg}.
function predict(vrm, frequency) {
  const { stiffness: s, drag, gravityPower: gp, length: L } = vrm;
  const rho = L / (L + s / FPS);
  const three = recurrence(-rho * (2 - drag), rho * (1 - drag), 1 - rho, 1 / FPS, frequency);
  three.sag_deg = (Math.atan(gp / s) * 180) / Math.PI;
  // The documented mapping (vrm.hpp): k = a s / (a s + L), a = 60 h^2; damping =
  // -60 ln(1 - drag); gravity = 60 gP.
  const h = 1 / 120;
  const a = FPS * h * h;
  const k = (a * s) / (a * s + L);
  const e = Math.exp(FPS * Math.log(1 - drag) * h);
  const ours = recurrence(-(1 - k) * (1 + e), (1 - k) * e, k, h, frequency);
  ours.sag_deg = (Math.atan((e * gp) / s) * 180) / Math.PI;
  return { three, ours };
}

// ---------------------------------------------------------------------------------------
// The cases. Motion defaults: along z (away from the samples' colliders), A = 0.25 m (half
// a bone), 1 Hz (below the bone's 1.74 Hz: omega^2 = 60 s / L = 120 /s^2 for stiffness 1,
// L = 0.5 m), 2.75 s of swing, which ends at an extreme (velocity 0), then a hold to 6 s.
// The steady swing is fitted over frames [45, 165] (two whole periods after the first
// 0.75 s, when the start's transient has fallen below 2% at the sample's drag 0.4); the
// hold begins at frame 165.
const SWING = { axis: 'z', amplitude: 0.25, frequency: 1, swing: 2.75, seconds: 6 };
const FIT = [45, 165];
const HOLD = 165;
const BOTH = { rig: {}, sm0: { stiffness: 0 } };

// Check constructors: `expect` is a number (a measured band's centre) or a function of
// the one-bone predictions (derived).
const ratio = (feature, variant, kind, expect, tol, why) => ({ feature, variant, how: 'ratio', kind, expect, tol, why });
const difference = (feature, variant, kind, expect, tol, why) => ({ feature, variant, how: 'difference', kind, expect, tol, why });
const bound = (feature, variant, side, kind, limits, why) => ({ feature, variant, how: 'bound', side, kind, ...limits, why });

// Why the `measured` bands are as wide as they are, and the `derived` ones as narrow.
const BAND = 'measured difference (docs); band +-5%: wide enough for float differences between platforms (the three backends agree to the last printed digit), narrow enough that our gravity or damping off by 25% takes at least one check of every case it acts in out of its band (--scale-gravity / --scale-damping 1.25 and 0.8)';
const BAND_DECAY = 'measured difference (docs); band +-10%: a decay rate is fitted over a few frames of a fast decay, so it carries more fitting noise than the other features';
const LINEAR = 'the one-bone linearisation; +-3% is its error at the swing\'s 22 degrees (both models are nonlinear at that angle, and alike)';

const CASES = [
  // One bone (the spring's first two joints): what vrm.hpp's mapping is about.
  {
    name: 'bone-swing',
    sample: 'sphere-collider.gltf',
    changes: { joints: 2, noColliders: true },
    variants: BOTH,
    motion: SWING,
    features: (P, m) => ({
      gain: transfer(P, 1, m, ...FIT).gain,
      lag: transfer(P, 1, m, ...FIT).lag,
      peak: peakDeflection(P, 1, m, ...FIT),
      decay_rate: decay(P, 1, m, HOLD).rate,
    }),
    checks: [
      ratio('gain', 'sm0', 'derived', (p) => p.ours.gain / p.three.gain, 0.03, LINEAR),
      difference('lag', 'sm0', 'derived', (p) => p.ours.lag - p.three.lag, 2, 'the one-bone linearisation; +-2 degrees is its error at 22 degrees'),
      ratio('decay_rate', 'sm0', 'derived', (p) => p.ours.rate / p.three.rate, 0.03, 'the slow root of the two overdamped recurrences (drag 0.4 is past critical); +-3% for the fit'),
      ratio('gain', 'rig', 'measured', 1.543, 0.05, BAND),
      difference('lag', 'rig', 'measured', -49.31, 3, 'measured difference (docs); +-3 degrees'),
      ratio('peak', 'rig', 'measured', 0.05957, 0.05, BAND),
    ],
  },
  {
    name: 'bone-ring',
    sample: 'sphere-collider.gltf',
    changes: { joints: 2, noColliders: true, drag: 0.05 },
    variants: BOTH,
    // A short swing, then a long free decay: drag 0.05 rings (damping 3.1/s).
    motion: { ...SWING, swing: 0.75, seconds: 4 },
    features: (P, m) => {
      const d = decay(P, 1, m, 45);
      return { frequency: d.frequency, decay_rate: d.rate };
    },
    checks: [
      ratio('frequency', 'sm0', 'claim', (p) => p.ours.frequency / p.three.frequency, 0.02,
        'vrm.hpp: equal swing frequency for small k (k = 0.008 here: 0.4%; the two discretisations add 0.4%); +-2% also covers the 14-degree swing\'s nonlinearity'),
      ratio('decay_rate', 'sm0', 'derived', (p) => p.ours.rate / p.three.rate, 0.03,
        'drag is the same velocity loss per frame on both sides, but VRM\'s length projection (rho) and our rest projection (1 - k) damp too, by different amounts; +-3% for the fit'),
      ratio('frequency', 'rig', 'measured', 5.270, 0.05, BAND),
      ratio('decay_rate', 'rig', 'measured', 5.469, 0.1, BAND_DECAY),
    ],
  },
  {
    name: 'bone-sag',
    sample: 'sphere-collider.gltf',
    // The bone turned to point along +x, gravityPower 0.1: VRM sags atan(0.1) = 5.7 degrees.
    changes: { joints: 2, noColliders: true, horizontal: true, gravityPower: 0.1 },
    variants: BOTH,
    motion: { ...SWING, amplitude: 0, seconds: 4 },
    features: (P) => ({ sag_deg: sagAngle(P, 0, 1) }),
    checks: [
      ratio('sag_deg', 'sm0', 'derived', (p) => p.ours.sag_deg / p.three.sag_deg, 0.02,
        'an equilibrium: exact but for the solver\'s iterations; +-2%'),
      ratio('sag_deg', 'rig', 'measured', 0.02481, 0.05, BAND),
    ],
  },
  // The whole 5-joint spring: VRM's bones bend one by one, each towards its rest direction
  // in its parent's current frame; ours bends towards a rest shape in the root's frame
  // (vrm.hpp: "not the trajectory"). No claim: bands round what is measured.
  {
    name: 'chain-swing',
    sample: 'sphere-collider.gltf',
    changes: { noColliders: true },
    variants: BOTH,
    motion: SWING,
    features: (P, m) => ({
      tip_gain: transfer(P, 4, m, ...FIT).gain,
      tip_lag: transfer(P, 4, m, ...FIT).lag,
      tip_peak: peakDeflection(P, 4, m, ...FIT),
      tip_decay_rate: decay(P, 4, m, HOLD).rate,
      j1_gain: transfer(P, 1, m, ...FIT).gain,
    }),
    checks: [
      ratio('tip_gain', 'rig', 'measured', 0.6178, 0.05, BAND),
      difference('tip_lag', 'rig', 'measured', -227.5, 3, 'measured difference (docs); +-3 degrees (damping 1.25x moves it by 9)'),
      ratio('tip_peak', 'rig', 'measured', 0.6794, 0.05, BAND),
      ratio('tip_decay_rate', 'rig', 'measured', 2.219, 0.1, BAND_DECAY),
    ],
  },
  {
    name: 'chain-sag',
    sample: 'sphere-collider.gltf',
    changes: { noColliders: true, horizontal: true, gravityPower: 0.1 },
    variants: BOTH,
    motion: { ...SWING, amplitude: 0, seconds: 4 },
    features: (P) => ({ bone1_sag_deg: sagAngle(P, 0, 1), tip_sag_deg: sagAngle(P, 0, 4) }),
    checks: [
      ratio('bone1_sag_deg', 'rig', 'measured', 0.1028, 0.05, BAND),
      ratio('tip_sag_deg', 'rig', 'measured', 0.07580, 0.05, BAND),
    ],
  },
  // Colliders: the samples as they are, the root swung along x into the collider. Each
  // side is held to its own geometry: three-vrm 3.5.5 uses radii as written (hitRadius
  // 0.25, collider 0.5), ours scales them by the nodes' world scale as UniVRM does
  // (vrm.hpp: 0.0625 and 0.25 here).
  colliderCase('sphere-collider', 0.75, false),
  colliderCase('plane-collider', 0.5,
    'plane colliders: our reader keeps the base shape, the sample\'s fallback sphere 10 km away, which the scene then skips (over 1000 m from its node): no collider at all'),
  // The inside sample's collider node has scale 1.35: our sphere (1.25 x 1.35 = 1.69 m)
  // would be so much larger than three-vrm's (1.25 m) that no swing three-vrm can follow
  // (its root must stay within 1.5 m of the centre) reaches ours. At scale 1 both are 1.25 m.
  colliderCase('inside-collider', 1,
    'inside colliders: our reader keeps them flagged inside, and the scene drops them (rods::step() has outside colliders only)',
    { colliderScale: 1 }),
];

function colliderCase(name, amplitude, pending, changes = {}) {
  const kind = pending ? 'pending' : 'claim';
  return {
    name,
    sample: `${name}.gltf`,
    changes,
    variants: { rig: {} },
    motion: { ...SWING, axis: 'x', amplitude },
    collider: true,
    pending,
    checks: [
      bound('clearance', 'rig', 'ours', kind, { min: -1e-4 },
        'colliders keep the joints out (in), the last projection of every iteration: 0.1 mm is far above float error at 1 m and far below the 62.5 mm joint radius'),
      bound('clearance', 'rig', 'ours', kind, { max: 0.01 },
        'the swing reaches the collider (within 1 cm of touching), or the check above says nothing'),
      bound('clearance', 'rig', 'three', 'claim', { max: 0.01, min: -0.125 },
        'three-vrm reaches it too, and keeps its joints out but for its re-projection to the bone\'s length after a push, a fraction of its 0.25 m radius (beyond half of it, this harness read its collider wrong)'),
    ],
  };
}

// ---------------------------------------------------------------------------------------
// Our side.

function nodeWorld(json, index) {
  // The samples' collider nodes are roots of the scene: world = their own TRS.
  const n = json.nodes[index];
  return { t: n.translation || [0, 0, 0], r: n.rotation || [0, 0, 0, 1], s: n.scale || [1, 1, 1] };
}

function rotate(q, v) {
  const [x, y, z, w] = q;
  const u = [x, y, z];
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const t = cross(u, v).map((c) => 2 * c);
  const c2 = cross(u, t);
  return [v[0] + w * t[0] + c2[0], v[1] + w * t[1] + c2[1], v[2] + w * t[2] + c2[2]];
}

/// The file's colliders as our side reads them (vrm.hpp): the extended shape when present,
/// radii times the node's largest world scale; for a plane, through the node's origin plus
/// offset with the normal turned by the node. What our solver does with it is another
/// matter (pending cases).
function ourColliderShapes(json) {
  const ext = json.extensions.VRMC_springBone;
  return (ext.colliders || []).map((c) => {
    const w = nodeWorld(json, c.node);
    const scale = Math.max(...w.s.map(Math.abs));
    const shape = c.extensions?.VRMC_springBone_extended_collider?.shape || c.shape;
    const kind = Object.keys(shape)[0];
    const s = shape[kind];
    const offset = (s.offset || [0, 0, 0]).map((v, i) => v * w.s[i]);
    const centre = rotate(w.r, offset).map((v, i) => v + w.t[i]);
    if (kind === 'plane') return { type: 'plane', centre, normal: rotate(w.r, s.normal || [0, 0, 1]) };
    return { type: kind, centre, radius: (s.radius || 0) * scale, inside: Boolean(s.inside) };
  });
}

/// Runs `bin args`; its stdout, or an Error with its stderr.
function run(bin, args) {
  const r = spawnSync(bin, args, { encoding: 'utf8' });
  if (r.error) throw new Error(`${bin} ${args.join(' ')}: ${r.error.message}`);
  if (r.status !== 0) throw new Error(`${path.basename(bin)} ${args.join(' ')} exited ${r.status}: ${r.stderr.trim()}`);
  return { stdout: r.stdout, stderr: r.stderr };
}

function readTrace(file) {
  const frames = [];
  for (const line of readFileSync(file, 'utf8').split('\n')) {
    if (!line) continue;
    const record = JSON.parse(line);
    if (record.kind === 'chain') frames[record.frame] = record.joints;
  }
  return frames;
}

function parseArgs(argv) {
  const [bin, sourceDir, ...rest] = argv;
  if (!bin || !sourceDir) {
    usage('usage: node compare.mjs KODAWARI_BINARY SOURCE_DIR [--backends a,b] [--cases a,b] [--keep DIR] [--scale-gravity F] [--scale-damping F] [--json FILE]');
  }
  const o = { bin, sourceDir, backends: ['cpu-reference', 'cpu', 'vulkan'], cases: null, keep: null, json: null, scaleGravity: 1, scaleDamping: 1 };
  for (let i = 0; i < rest.length; ++i) {
    const a = rest[i];
    const value = () => {
      if (rest[i + 1] === undefined) usage(`${a} needs a value`);
      return rest[++i];
    };
    if (a === '--backends') o.backends = value().split(',');
    else if (a === '--cases') o.cases = value().split(',');
    else if (a === '--keep') o.keep = value();
    else if (a === '--json') o.json = value();
    else if (a === '--scale-gravity') o.scaleGravity = Number(value());
    else if (a === '--scale-damping') o.scaleDamping = Number(value());
    else usage(`unknown option ${a}`);
  }
  if (!(o.scaleGravity >= 0) || !(o.scaleDamping >= 0)) usage('--scale-gravity and --scale-damping need numbers >= 0');
  for (const name of o.cases || []) if (!CASES.some((c) => c.name === name)) usage(`no case ${name} (cases: ${CASES.map((c) => c.name).join(', ')})`);
  return o;
}

const fmt = (v) => (v === null || v === undefined ? '-' : Number.isFinite(v) ? Number(v.toPrecision(4)).toString() : String(v));

/// One case: both sides simulated, features measured. {three, ours: {"variant/backend"}, ...}.
async function runCase(c, options, tools, work) {
  const samplePath = path.join(options.sourceDir, 'tests', 'assets', 'vrm-springbone', c.sample);
  const { json, buffers } = swing.readSample(samplePath);
  const modified = swing.modify(json, c.changes);
  const glb = swing.packGlb(modified, buffers, c.motion);
  const glbPath = path.join(work, `${c.name}.glb`);
  writeFileSync(glbPath, glb);
  const theirs = await swing.simulate(tools, glb, c.motion);

  const scenePath = path.join(work, `${c.name}.json`);
  const rig = run(options.bin, ['rig', glbPath, '--out', scenePath]);
  const warnings = rig.stderr.split('\n').filter((line) => line.startsWith('warning:') && !line.includes('no "head" node'));
  const scene = JSON.parse(readFileSync(scenePath, 'utf8'));
  const chain = scene.characters[0].chains[0];
  chain.physics.gravity = chain.physics.gravity.map((g) => g * options.scaleGravity);
  chain.physics.damping *= options.scaleDamping;
  const ours = {};
  for (const [variant, physics] of Object.entries(c.variants)) {
    const v = structuredClone(scene);
    Object.assign(v.characters[0].chains[0].physics, physics);
    const variantScene = path.join(work, `${c.name}.${variant}.json`);
    writeFileSync(variantScene, JSON.stringify(v, null, 2));
    for (const backend of options.backends) {
      const tracePath = path.join(work, `${c.name}.${variant}.${backend}.jsonl`);
      run(options.bin, ['run', variantScene, '--frames', String(theirs.frames), '--no-export', '--trace', tracePath, '--backend', backend]);
      const frames = readTrace(tracePath);
      if (frames.length !== theirs.frames) throw new Error(`${tracePath}: ${frames.length} frames, expected ${theirs.frames}`);
      ours[`${variant}/${backend}`] = frames;
    }
  }

  const result = { name: c.name, physics: chain.physics, warnings, three: {}, ours: {} };
  if (c.features) {
    result.three = c.features(theirs.positions, c.motion);
    for (const [key, frames] of Object.entries(ours)) result.ours[key] = c.features(frames, c.motion);
  }
  if (c.collider) {
    const ourShapes = ourColliderShapes(modified);
    result.three.clearance = Math.min(...theirs.colliders.map((s) => clearance(theirs.positions, s, theirs.hit_radius[0])));
    for (const [key, frames] of Object.entries(ours)) {
      result.ours[key] = { clearance: Math.min(...ourShapes.map((s) => clearance(frames, s, chain.thickness))) };
    }
    result.shapes = { three: theirs.colliders, three_hit_radius: theirs.hit_radius[0], ours: ourShapes, ours_thickness: chain.thickness };
  }
  // The one-bone predictions, from the file's VRM parameters (the spring's first joint)
  // and the bone's length in the world.
  const joint = modified.extensions.VRMC_springBone.springs[0].joints[0];
  const [p0, p1] = theirs.positions[0];
  result.predicted = predict({
    stiffness: joint.stiffness ?? 1,
    drag: joint.dragForce ?? 0.4,
    gravityPower: joint.gravityPower ?? 0,
    length: Math.hypot(p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]),
  }, c.motion.frequency);
  return result;
}

/// Evaluates a check on every backend: [{backend, value, ok, enforced}].
function evaluate(check, result, backends) {
  const expect = typeof check.expect === 'function' ? check.expect(result.predicted) : check.expect;
  return backends.map((backend) => {
    const ours = result.ours[`${check.variant}/${backend}`]?.[check.feature];
    const three = result.three[check.feature];
    let value;
    let ok;
    let target;
    if (check.how === 'bound') {
      value = check.side === 'three' ? three : ours;
      ok = !(value < check.min) && !(value > check.max) && Number.isFinite(value);
      target = [check.min !== undefined ? `>= ${check.min}` : null, check.max !== undefined ? `<= ${check.max}` : null].filter(Boolean).join(' and ');
    } else if (check.how === 'ratio') {
      value = ours / three;
      ok = Math.abs(value / expect - 1) <= check.tol;
      target = `x${fmt(expect)} +-${check.tol * 100}%`;
    } else {
      value = ours - three;
      ok = Math.abs(value - expect) <= check.tol;
      target = `${fmt(expect)} +-${check.tol}`;
    }
    return { backend, value, ok: Boolean(ok), target, enforced: check.kind !== 'pending' };
  });
}

const options = parseArgs(process.argv.slice(2));
const toolsDir = process.env.KODAWARI_NODE_TOOLS || path.join(options.sourceDir, '.tools', 'npm');
let tools;
try {
  tools = await swing.loadTools(toolsDir);
} catch (error) {
  usage(error.message);
}

const work = options.keep ? path.resolve(options.keep) : mkdtempSync(path.join(os.tmpdir(), 'kodawari-three-vrm-'));
mkdirSync(work, { recursive: true });
const started = Date.now();
let failures = 0;
const report = [];
try {
  for (const c of CASES) {
    if (options.cases && !options.cases.includes(c.name)) continue;
    let result;
    try {
      result = await runCase(c, options, tools, work);
    } catch (error) {
      console.error(`three_vrm_comparison: ${c.name}: ${error.message}`);
      process.exitCode = 2;
      continue;
    }
    console.log(`\n${c.name}${c.pending ? ` (pending: ${c.pending})` : ''}`);
    for (const w of result.warnings) console.log(`  rig ${w}`);
    const first = options.backends[0];
    for (const feature of Object.keys(result.three)) {
      const columns = Object.keys(c.variants).map((v) => `${v} ${fmt(result.ours[`${v}/${first}`][feature])}`);
      console.log(`  ${feature.padEnd(15)} three-vrm ${fmt(result.three[feature]).padEnd(10)} ours (${first}): ${columns.join('  ')}`);
    }
    result.checks = [];
    for (const check of c.checks) {
      const outcomes = evaluate(check, result, options.backends);
      const values = outcomes.map((o) => `${o.backend} ${fmt(o.value)}`).join(', ');
      const bad = outcomes.filter((o) => !o.ok);
      const verdict = bad.length ? (check.kind === 'pending' ? 'not yet (pending, not enforced)' : 'FAIL') : 'ok';
      if (bad.length && check.kind !== 'pending') failures += 1;
      const what = check.how === 'bound' ? `${check.side} ${check.feature}` : `${check.feature} ${check.how} ours/three`;
      console.log(`  [${check.kind}] ${check.variant} ${what}: ${values}; expected ${outcomes[0].target}: ${verdict}`);
      if (verdict === 'FAIL') console.log(`      why this bound: ${check.why}`);
      result.checks.push({ ...check, expect: typeof check.expect === 'function' ? check.expect(result.predicted) : check.expect, outcomes });
    }
    if (c.pending && result.checks.every((k) => k.outcomes.every((o) => o.ok))) {
      console.log('  every pending check passes: switch this case on (pending: false)');
    }
    report.push(result);
  }
} finally {
  if (!options.keep) rmSync(work, { recursive: true, force: true });
}
if (options.json) writeFileSync(options.json, JSON.stringify(report, null, 1));
console.log(`\nthree_vrm_comparison: ${report.length} cases, backends ${options.backends.join(', ')}, ${((Date.now() - started) / 1000).toFixed(1)} s: ` +
  (failures ? `${failures} check(s) failed` : 'every enforced check passed'));
if (failures) process.exitCode = 1;
