// Two-stage Gauss-Legendre collocation (order 4, implicit) [HLW, Sect. II.1.3]:
//   K_i = f(t + c_i h, y + h sum_j a_ij K_j)   by fixed-point iteration to round-off,
//   y1 = y + h sum_i b_i K_i.
// It starts as the Python step does: from the last step's slopes continued (K^0 = E K_prev,
// [HLW, VIII.6.1]) when `memory` holds them for the same h, else from f(t, y).
import { fixedPoint, halves, joined, plus } from "./field.js";

const ROOT = Math.sqrt(3) / 6;
export const TABLEAU = {
  a: [
    [1 / 4, 1 / 4 - ROOT],
    [1 / 4 + ROOT, 1 / 4],
  ],
  b: [1 / 2, 1 / 2],
  c: [1 / 2 - ROOT, 1 / 2 + ROOT],
};

// E_ij = l_j(1 + c_i), l_j the Lagrange polynomial of node j.
function extrapolation(c) {
  return c.map((ci) =>
    c.map((cj, j) => c.reduce((product, ck, k) => (k === j ? product : (product * (1 + ci - ck)) / (cj - ck)), 1)),
  );
}

export function step(field, t, q, p, h, memory = null, tableau = TABLEAU) {
  const { a, b, c } = tableau;
  const s = b.length;
  const y = joined(q, p);
  const m = y.length;
  const slope = (K, i) => K.subarray(i * m, (i + 1) * m);
  // every stage evaluated at the latest slopes
  const sweep = (K) => {
    const next = new Float64Array(s * m);
    for (let i = 0; i < s; i++) {
      let stage = y;
      for (let j = 0; j < s; j++) stage = plus(stage, h * a[i][j], slope(K, j));
      next.set(field.f(t + c[i] * h, stage), i * m);
    }
    return next;
  };
  let K = new Float64Array(s * m);
  if (memory && memory.h === h && memory.slopes) {
    const E = extrapolation(c);
    for (let i = 0; i < s; i++) {
      let guess = new Float64Array(m);
      for (let j = 0; j < s; j++) guess = plus(guess, E[i][j], slope(memory.slopes, j));
      K.set(guess, i * m);
    }
  } else {
    const f0 = field.f(t, y);
    for (let i = 0; i < s; i++) K.set(f0, i * m);
  }
  // a slope's round-off follows the state it is added to: "tiny" is judged against |y| / h
  const floor = Math.max(...Array.from(y, Math.abs)) / Math.abs(h);
  K = fixedPoint(sweep, K, floor);
  if (memory) Object.assign(memory, { h, slopes: K });
  let y1 = y;
  for (let i = 0; i < s; i++) y1 = plus(y1, h * b[i], slope(K, i));
  return halves(y1);
}
