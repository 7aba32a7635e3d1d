// The classical fourth-order Runge-Kutta method from its Butcher tableau [HLW, Sect. II.1]
// (`memory` is not used: an explicit step keeps nothing):
//   k_i = f(t + c_i h, y + h sum_{j<i} a_ij k_j);   y1 = y + h sum_i b_i k_i.
import { halves, joined, plus } from "./field.js";

export const TABLEAU = {
  a: [
    [0, 0, 0, 0],
    [0.5, 0, 0, 0],
    [0, 0.5, 0, 0],
    [0, 0, 1, 0],
  ],
  b: [1 / 6, 1 / 3, 1 / 3, 1 / 6],
  c: [0, 0.5, 0.5, 1],
};

export function step(field, t, q, p, h, memory = null, tableau = TABLEAU) {
  const { a, b, c } = tableau;
  const y = joined(q, p);
  const k = [];
  for (let i = 0; i < b.length; i++) {
    let stage = y;
    for (let j = 0; j < i; j++) stage = plus(stage, h * a[i][j], k[j]);
    k.push(field.f(t + c[i] * h, stage));
  }
  let y1 = y;
  for (let i = 0; i < b.length; i++) y1 = plus(y1, h * b[i], k[i]);
  return halves(y1);
}
