// A generated model's field as the methods see it, and the one solver of every implicit
// equation: pendulum_lab.integrators.reference (ReferenceField, fixed_point) in JavaScript.
// The state is q (coordinates) and p (canonical momenta), each a Float64Array of n numbers.

export const MAX_SWEEPS = 100; // integrators.stopping.MAX_SWEEPS
export const ROUNDOFF_TOLERANCE = 1e-11; // integrators.stopping.ROUNDOFF_TOLERANCE
export const EPSILON = 2 ** -52; // the spacing of doubles at 1

export class ConvergenceError extends Error {}

// The field of `model` (a generated module) at the parameters `params`.
export function makeField(model, params) {
  const n = model.COORDINATES;
  const field = {
    n,
    params: Float64Array.from(params),
    evaluations: 0,
    // [dq/dt, dp/dt] = [H_p, -H_q + Q] at (t, q, p).
    hamilton(t, q, p) {
      const dq = new Float64Array(n);
      const dp = new Float64Array(n);
      model.hamilton(t, q, p, field.params, dq, dp);
      field.evaluations += 1;
      return [dq, dp];
    },
    // dy/dt for the state y = (q, p) as one array.
    f(t, y) {
      const [dq, dp] = field.hamilton(t, y.subarray(0, n), y.subarray(n));
      const out = new Float64Array(2 * n);
      out.set(dq);
      out.set(dp, n);
      return out;
    },
    H_p(t, q, p) {
      return field.hamilton(t, q, p)[0];
    },
    // dH/dq = -dp/dt: a field without damping or drive (the symplectic methods refuse others).
    H_q(t, q, p) {
      return field.hamilton(t, q, p)[1].map((rate) => -rate);
    },
  };
  return field;
}

// x + h * v, elementwise (a new array).
export function plus(x, h, v) {
  return x.map((value, i) => value + h * v[i]);
}

export function joined(q, p) {
  const y = new Float64Array(q.length + p.length);
  y.set(q);
  y.set(p, q.length);
  return y;
}

export function halves(y) {
  const n = y.length / 2;
  return [y.slice(0, n), y.slice(n)];
}

// Iterate x <- update(x) from the guess x to round-off, by the package's stopping rule: every
// increment tiny, and none shrinking any more or the contraction seen so far predicting the
// rest below half an ulp. `floor` is added to each component's size where "tiny" is judged.
export function fixedPoint(update, x, floor = 0) {
  let smallest = new Float64Array(x.length).fill(Infinity); // each component's smallest increment
  for (let sweep = 0; sweep < MAX_SWEEPS; sweep++) {
    const old = x;
    x = update(x);
    const delta = x.map((value, i) => Math.abs(value - old[i]));
    const size = x.map(Math.abs);
    const previous = smallest;
    smallest = previous.map((value, i) => Math.min(value, delta[i]));
    if (!x.every(Number.isFinite)) break;
    if (delta.some((d, i) => d > ROUNDOFF_TOLERANCE * (1 + floor + size[i]))) continue;
    const shrinking = Array.from(delta, (d, i) => d < previous[i] && d > 0);
    if (!shrinking.includes(true)) return x; // every component stalled
    let measured = false; // a component whose previous increment was above round-off noise
    let rate = 0; // the contraction
    let worst = 0;
    for (let i = 0; i < x.length; i++) {
      if (Number.isFinite(previous[i]) && previous[i] > 256 * EPSILON * size[i]) {
        measured = true;
        rate = Math.max(rate, delta[i] / previous[i]);
      }
      if (shrinking[i]) worst = Math.max(worst, delta[i] / size[i]);
    }
    if (measured && rate < 1 && rate * worst <= 0.5 * EPSILON * (1 - rate)) return x;
  }
  throw new ConvergenceError(`the fixed-point iteration did not converge in ${MAX_SWEEPS} sweeps`);
}
