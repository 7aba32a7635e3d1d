"""Benchmark item 4's peer: THE COURSE REPORT'S APPROACH to GLRK4, not pendulum_lab's.

The course report (Kanoun, Cowley, Ivachtchenko, MAT332, 2024, section 4.6.5)
integrates the double pendulum with the two-stage Gauss-Legendre method on the
state ``y = (theta_1, theta_2, omega_1, omega_2)`` and solves the implicit stage
equations at every step with ``scipy.optimize.fsolve``. This file is a
reference implementation of that approach, written for the benchmark only:

* the unknowns are the two stage slopes ``k_1, k_2`` (8 numbers), the residual
  is ``k_i - f(y_n + h sum_j a_ij k_j)``, the first guess ``k_1 = k_2 = f(y_n)``;
* ``f(y) = (omega, alpha(theta, omega))`` with the accelerations from the
  NumPy model function :meth:`pendulum_lab.PendulumModel.accelerations`
  (lambdified SymPy; both stages in one batched call, which is kinder to
  this peer than two separate calls);
* ``fsolve`` with its default tolerance (``xtol = 1.49e-8``); the report names
  no tolerance.

pendulum_lab's own GLRK4 works on ``(theta, p)`` with compiled kernels and a
fixed-point iteration run to round-off; see ``pendulum_lab.integrators``.
"""

from __future__ import annotations

import math
import time

import numpy as np
from scipy.optimize import fsolve

__all__ = ["GAUSS_A", "GAUSS_B", "integrate"]

_R3 = math.sqrt(3.0)
GAUSS_A = np.array([[1 / 4, 1 / 4 - _R3 / 6], [1 / 4 + _R3 / 6, 1 / 4]])
GAUSS_B = np.array([1 / 2, 1 / 2])


def integrate(model, theta0, omega0, t_end: float, dt: float):
    """The report's GLRK4 from ``(theta0, omega0)`` over ``floor(t_end / dt)`` steps.

    Returns
    -------
    t : ndarray, shape (N+1,)
    theta, omega : ndarray, shape (N+1, n)
    energy : ndarray, shape (N+1,)
    wall_time : float
        Seconds spent stepping (energies excluded).
    """
    n = model.n
    n_steps = int(np.floor(t_end / dt * (1 + 1e-12)))

    def field(y):
        """``f(y)`` for a batch of states ``y`` of shape (..., 2n)."""
        theta, omega = y[..., :n], y[..., n:]
        return np.concatenate([omega, model.accelerations(theta, omega)], axis=-1)

    def residual(k_flat, y):
        k = k_flat.reshape(2, 2 * n)
        stages = y + dt * (GAUSS_A @ k)
        return (k - field(stages)).ravel()

    states = np.empty((n_steps + 1, 2 * n))
    states[0] = np.concatenate([np.asarray(theta0, float), np.asarray(omega0, float)])
    start = time.perf_counter()
    for i in range(n_steps):
        y = states[i]
        guess = np.tile(field(y), 2)
        k = fsolve(residual, guess, args=(y,)).reshape(2, 2 * n)
        states[i + 1] = y + dt * (GAUSS_B @ k)
    wall = time.perf_counter() - start
    theta, omega = states[:, :n], states[:, n:]
    return np.arange(n_steps + 1) * dt, theta, omega, model.energy(theta, omega), wall
