// The swing features both VRM spring comparisons measure (tests/three_vrm/compare.mjs,
// tests/conformance/conformance.mjs): one definition of the least-squares fits.

/// Least-squares fit of x(f) = G A sin(w f / fps - lag) + c over frames [f0, f1], `x(f)`
/// the joint's displacement along the motion's axis at frame f, `amplitude` A and
/// `frequency` (Hz) the root's: {gain G, lag in degrees in [0, 360): positive, the joint
/// follows the root late; a chain's tip can lag its root by more than half a period}.
export function sineFit(x, amplitude, frequency, fps, f0, f1) {
  const w = 2 * Math.PI * frequency;
  // Normal equations of the basis (sin, cos, 1).
  const M = [[0, 0, 0], [0, 0, 0], [0, 0, 0]];
  const r = [0, 0, 0];
  for (let f = f0; f <= f1; ++f) {
    const t = f / fps;
    const b = [Math.sin(w * t), Math.cos(w * t), 1];
    const value = x(f);
    for (let i = 0; i < 3; ++i) {
      r[i] += b[i] * value;
      for (let k = 0; k < 3; ++k) M[i][k] += b[i] * b[k];
    }
  }
  const c = solve3(M, r);
  const gain = Math.hypot(c[0], c[1]) / amplitude;
  const lag = (((Math.atan2(-c[1], c[0]) * 180) / Math.PI) % 360 + 360) % 360;
  return { gain, lag };
}

/// M x = r for a 3x3 M, by Gauss-Jordan elimination with partial pivoting.
export function solve3(M, r) {
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

/// The least-squares slope of the line through `points` ([x, y] pairs).
export function slope(points) {
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
