// The chest under the bar from the patient's coefficient table (docs/planner.md): the response to 1 N at
// bar levels every step_mm along the sternum is U c_k (U: the orthonormal modes, rows = 3 x (bone
// vertices, skin vertices, skin landmarks)); between levels c is interpolated linearly, and the
// displacement under force F is F U c. The server checks the table against the C++ deform call
// (/api/deform) and the page's test does too (0.01 mm). No allocation per call.

/// The table from /api/patients/ID/basis (float32: lift per newton [K], coefficients [K x rank], modes
/// [rows x rank], row-major).
export function makeBasis(info, buffer) {
  const { levels: K, rank: r, rows, first_mm: first, step_mm: step } = info.basis;
  const f = new Float32Array(buffer);
  if (f.length !== K + K * r + rows * r) throw new Error(`basis: ${f.length} floats, expected ${K + K * r + rows * r}`);
  return {
    K, r, rows, first, step,
    liftPerN: f.subarray(0, K),
    coefficients: f.subarray(K, K + K * r),
    modes: f.subarray(K + K * r),
    boneRows: 3 * info.bone.vertices,
    skinRows: 3 * info.skin.vertices,
    c: new Float64Array(r),
  };
}

/// Whether the bar at `mm` from the notch is within the table (on the sternum).
export function onSternum(b, mm) {
  return mm >= b.first - 1e-9 && mm <= b.first + (b.K - 1) * b.step + 1e-9;
}

// Sets b.c to the coefficients per newton at `mm`; returns the sternal lift per newton there.
function interpolate(b, mm) {
  const t = Math.min(Math.max((mm - b.first) / b.step, 0), b.K - 1);
  const k = Math.min(Math.floor(t), b.K - 2);
  const a = t - k;
  const c0 = k * b.r, c1 = (k + 1) * b.r;
  for (let j = 0; j < b.r; ++j) b.c[j] = (1 - a) * b.coefficients[c0 + j] + a * b.coefficients[c1 + j];
  return (1 - a) * b.liftPerN[k] + a * b.liftPerN[k + 1];
}

/// Sternal lift per newton at `mm`, mm/N.
export function liftPerNewton(b, mm) {
  return interpolate(b, mm);
}

/// Displacements (mm) of rows [from, from + out.length) under `force` N at `mm` into `out`; returns the
/// sternal lift, mm.
export function deform(b, mm, force, from, out) {
  const lift = interpolate(b, mm) * force;
  const r = b.r, modes = b.modes, c = b.c, n = out.length;
  // Four rows at a time, each coefficient read once for the four (twice as fast as row by row in V8).
  let i = 0, row = from * r;
  for (; i + 4 <= n; i += 4, row += 4 * r) {
    let s0 = 0, s1 = 0, s2 = 0, s3 = 0;
    for (let j = 0, a = row; j < r; ++j, ++a) {
      const cj = c[j];
      s0 += modes[a] * cj;
      s1 += modes[a + r] * cj;
      s2 += modes[a + 2 * r] * cj;
      s3 += modes[a + 3 * r] * cj;
    }
    out[i] = force * s0;
    out[i + 1] = force * s1;
    out[i + 2] = force * s2;
    out[i + 3] = force * s3;
  }
  for (; i < n; ++i, row += r) {
    let sum = 0;
    for (let j = 0; j < r; ++j) sum += modes[row + j] * c[j];
    out[i] = force * sum;
  }
  return lift;
}
