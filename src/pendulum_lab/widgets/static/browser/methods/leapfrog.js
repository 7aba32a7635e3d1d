// The leapfrog (Stormer-Verlet) for a general H(t, q, p) [HLW, eq. VI.3.4], each implicit
// equation iterated from its explicit guess (exact for a separable H):
//   p_half = p - h/2 H_q(t, q, p_half)                          (implicit in p_half)
//   q1 = q + h/2 [H_p(t, q, p_half) + H_p(t + h, q1, p_half)]   (implicit in q1)
//   p1 = p_half - h/2 H_q(t + h, q1, p_half)
import { fixedPoint, plus } from "./field.js";

export function step(field, t, q, p, h) {
  const kick = (x) => plus(p, -h / 2, field.H_q(t, q, x));
  const pHalf = fixedPoint(kick, kick(p));
  const velocity = field.H_p(t, q, pHalf);
  const drift = (x) => plus(plus(q, h / 2, velocity), h / 2, field.H_p(t + h, x, pHalf));
  const q1 = fixedPoint(drift, plus(q, h, velocity));
  return [q1, plus(pHalf, -h / 2, field.H_q(t + h, q1, pHalf))];
}
