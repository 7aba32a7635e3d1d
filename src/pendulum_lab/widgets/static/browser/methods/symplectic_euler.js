// Symplectic Euler for a general H(t, q, p) [HLW, Thm VI.3.3], iterated from the explicit
// guess (exact for a separable H):
//   p1 = p - h H_q(t, q, p1)   (implicit in p1)
//   q1 = q + h H_p(t, q, p1)
import { fixedPoint, plus } from "./field.js";

export function step(field, t, q, p, h) {
  const kick = (x) => plus(p, -h, field.H_q(t, q, x));
  const p1 = fixedPoint(kick, kick(p));
  return [plus(q, h, field.H_p(t, q, p1)), p1];
}
