"""How many field evaluations a Gauss-Legendre step needs under three stage solvers.

A study for item 11, not a method of the package: it counts, it does not
time. The package solves the stage equations ``K_i = f(y + h sum_j a_ij K_j)``
by fixed-point iteration, every stage from the previous iterate (Jacobi).
Two alternatives a reader might expect to be cheaper:

- Gauss-Seidel: each stage is evaluated from the newest slopes, those of
  the stages before it in this sweep included;
- simplified Newton [HW II, Sect. IV.8]: the Jacobian ``J`` of the field at
  the step's start (forward differences: ``2n + 1`` evaluations), then
  ``K <- K - (I - h A (x) J)^-1 (K - F(K))`` until converged, one sweep of
  evaluations per iteration.

All three start from the package's starting values (the previous step's
collocation polynomial, :attr:`ButcherTableau.extrapolation`) and stop by the
package's own rule (:func:`pendulum_lab.integrators.fixed_point_status`, to
round-off), so the counts differ only by the solver.
"""

from __future__ import annotations

import functools

import numba
import numpy as np

from pendulum_lab.driver.simulate import hamiltonian_field
from pendulum_lab.integrators import MAX_SWEEPS, fixed_point_status

SOLVERS = ("fixed point (ours)", "Gauss-Seidel", "simplified Newton")


@functools.cache  # item 11 counts for each requirement: compile once per kernel
def _make_counter(hamilton):
    """A compiled ``count(y0, h, steps, solver, params, a, b, c, e)`` for one field kernel."""

    @numba.njit
    def field(t, y, out, params):
        n = y.size // 2
        hamilton(t, y[:n], y[n:], params, out[:n], out[n:])

    @numba.njit
    def count(y0, h, steps, solver, params, a, b, c, e):
        s, d = b.size, y0.size
        y, slopes, old, previous = y0.copy(), np.zeros((s, d)), np.zeros((s, d)), np.zeros((s, d))
        stage, value, start_slope = np.empty(d), np.empty((s, d)), np.empty(d)
        jacobian, inverse = np.empty((d, d)), np.empty((s * d, s * d))
        evaluations = 0
        for k in range(steps):
            t = k * h
            if k == 0:
                field(t, y, start_slope, params)
                evaluations += 1
                for i in range(s):
                    slopes[i] = start_slope
            else:
                slopes[:] = e @ previous
            if solver == 2:  # the Jacobian at the step's start, and (I - h A (x) J)^-1
                field(t, y, start_slope, params)
                for col in range(d):
                    shifted = y.copy()
                    delta = 1e-7 * (1.0 + abs(y[col]))
                    shifted[col] += delta
                    field(t, shifted, stage, params)
                    jacobian[:, col] = (stage - start_slope) / delta
                evaluations += d + 1
                system = np.zeros((s * d, s * d))
                for i in range(s):
                    for j in range(s):
                        system[i * d:(i + 1) * d, j * d:(j + 1) * d] = -h * a[i, j] * jacobian
                    for m in range(d):
                        system[i * d + m, i * d + m] += 1.0
                inverse[:] = np.linalg.inv(system)
            smallest = np.full(s * d, np.inf)
            status, sweeps = 0, 0
            while status == 0 and sweeps < MAX_SWEEPS:
                sweeps += 1
                old[:] = slopes
                for i in range(s):
                    # Jacobi and Newton evaluate from the last iterate, Gauss-Seidel from the newest
                    source = slopes if solver == 1 else old
                    stage[:] = y + h * (a[i] @ source)
                    field(t + c[i] * h, stage, value[i], params)
                    if solver == 1:
                        slopes[i] = value[i]
                if solver == 0:
                    slopes[:] = value
                elif solver == 2:
                    residual = (old - value).reshape(s * d)
                    slopes[:] = old - (inverse @ residual).reshape(s, d)
                status = fixed_point_status(slopes.reshape(s * d), old.reshape(s * d), smallest)
            if status != 1:
                return -1.0
            evaluations += s * sweeps
            y = y + h * (b @ slopes)
            previous[:] = slopes
        return evaluations / steps

    return count


def evaluations_per_step(model, theta0, p0, tableau, dt: float, t_end: float) -> dict:
    """Mean field evaluations per step of each solver in :data:`SOLVERS` (-1: no convergence)."""
    field = hamiltonian_field(model)
    count = _make_counter(field.hamilton)
    y0 = np.concatenate([np.asarray(theta0, float), np.asarray(p0, float)])
    params = np.array(field.params, dtype=float)
    steps = int(round(t_end / dt))
    return {name: count(y0, dt, steps, solver, params, tableau.a, tableau.b, tableau.c,
                        tableau.extrapolation)
            for solver, name in enumerate(SOLVERS)}
