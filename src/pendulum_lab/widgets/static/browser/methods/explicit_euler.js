// Explicit Euler [HLW, Sect. I.1]: y1 = y + h f(t, y) for the state y = (q, p).
import { halves, joined, plus } from "./field.js";

export function step(field, t, q, p, h) {
  const y = joined(q, p);
  return halves(plus(y, h, field.f(t, y)));
}
