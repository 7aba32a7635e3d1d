// The course's methods in the browser, by their names in pendulum_lab's registry. Each step is
// step(field, t, q, p, h[, memory]) -> [q1, p1] in canonical variables; `hamiltonian` marks the
// methods that need dp/dt = -H_q (no damping, no drive).
import * as explicitEuler from "./explicit_euler.js";
import * as glrk4 from "./glrk4.js";
import * as leapfrog from "./leapfrog.js";
import * as rk4 from "./rk4.js";
import * as symplecticEuler from "./symplectic_euler.js";

export { ConvergenceError, makeField } from "./field.js";

export const METHODS = {
  explicit_euler: { step: explicitEuler.step, hamiltonian: false, implicit: false },
  semi_implicit_euler: { step: symplecticEuler.step, hamiltonian: true, implicit: true },
  leapfrog: { step: leapfrog.step, hamiltonian: true, implicit: true },
  rk4: { step: rk4.step, hamiltonian: false, implicit: false },
  glrk4: { step: glrk4.step, hamiltonian: false, implicit: true },
};
