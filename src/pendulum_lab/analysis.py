"""Measurements of integrators: observed order, symplecticity, reversibility, energy.

Each function returns numbers a test or a notebook can assert on; none
prints or plots.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from . import _validation as check
from .integrators import get_method
from .model import PendulumModel
from .simulate import Trajectory, simulate, step

__all__ = [
    "OrderResult",
    "energy_growth",
    "observed_order",
    "reference_solution",
    "reversibility_error",
    "step_jacobian",
    "symplecticity_defect",
]


def _canonical_j(n: int) -> np.ndarray:
    return np.block([[np.zeros((n, n)), np.eye(n)], [-np.eye(n), np.zeros((n, n))]])


def step_jacobian(model: PendulumModel, method, q, p, dt: float, eps: float = 1e-6) -> np.ndarray:
    """Jacobian of one step ``(theta, p) -> (theta1, p1)`` by central differences.

    Returns an array of shape ``(2n, 2n)``.
    """
    n = model.n
    z = np.concatenate([np.asarray(q, float), np.asarray(p, float)])
    jac = np.empty((2 * n, 2 * n))
    for k in range(2 * n):
        dz = np.zeros(2 * n)
        dz[k] = eps
        plus = np.concatenate(step(model, method, (z + dz)[:n], (z + dz)[n:], dt))
        minus = np.concatenate(step(model, method, (z - dz)[:n], (z - dz)[n:], dt))
        jac[:, k] = (plus - minus) / (2 * eps)
    return jac


def symplecticity_defect(model: PendulumModel, method, q, p, dt: float) -> float:
    """``max |Psi^T J Psi - J|`` for the Jacobian ``Psi`` of one step in ``(theta, p)``.

    Zero (to the finite-difference accuracy, about 1e-10) for a symplectic map.
    """
    psi = step_jacobian(model, method, q, p, dt)
    j = _canonical_j(model.n)
    return float(np.max(np.abs(psi.T @ j @ psi - j)))


def reversibility_error(model: PendulumModel, method, q, p, dt: float) -> float:
    """``max |Phi_{-h}(Phi_h(z)) - z|``: zero for a symmetric (time-reversible) method."""
    q = np.asarray(q, float)
    p = np.asarray(p, float)
    q1, p1 = step(model, method, q, p, dt)
    q2, p2 = step(model, method, q1, p1, -dt)
    return float(max(np.max(np.abs(q2 - q)), np.max(np.abs(p2 - p))))


def reference_solution(model: PendulumModel, theta0, omega0, t_end: float,
                       rtol: float = 1e-13) -> tuple[np.ndarray, np.ndarray]:
    """``(theta, omega)`` at ``t_end`` by SciPy's DOP853 at a tight tolerance."""
    theta0 = check.state_array("theta0", theta0, model.n)
    omega0 = check.state_array("omega0", omega0, model.n)
    n = model.n

    def rhs(_t, y):
        return np.concatenate([y[n:], model.accelerations(y[:n], y[n:])])

    sol = solve_ivp(rhs, (0.0, t_end), np.concatenate([theta0, omega0]), method="DOP853",
                    rtol=rtol, atol=rtol)
    return sol.y[:n, -1], sol.y[n:, -1]


@dataclass(frozen=True)
class OrderResult:
    """Errors at the final time for a sequence of step sizes, and the fitted slope."""

    dts: np.ndarray
    errors: np.ndarray
    slope: float
    method: str


def observed_order(model: PendulumModel, method, theta0, omega0, t_end: float = 1.0,
                   dts=(0.02, 0.01, 0.005, 0.0025), reference=None) -> OrderResult:
    """Fit the slope of log(error) against log(dt) at ``t_end``.

    The error is the max-norm distance in ``(theta, omega)`` from ``reference``
    (by default :func:`reference_solution`). Keep ``dt`` small enough to be in
    the asymptotic regime (on the double pendulum ``dt <= 0.025``) and the
    errors well above round-off.
    """
    method = get_method(method)
    if reference is None:
        reference = reference_solution(model, theta0, omega0, t_end)
    ref = np.concatenate(reference)
    dts = np.asarray(dts, float)
    errors = []
    for dt in dts:
        traj = simulate(model, theta0, omega0, t_end=t_end, dt=dt, method=method)
        if not np.isclose(traj.t[-1], t_end, rtol=0, atol=1e-9):
            raise ValueError(f"`t_end` ({t_end}) must be a whole number of steps of dt = {dt}")
        errors.append(np.max(np.abs(np.concatenate([traj.theta[-1], traj.omega[-1]]) - ref)))
    errors = np.asarray(errors)
    slope = float(np.polyfit(np.log(dts), np.log(errors), 1)[0])
    return OrderResult(dts, errors, slope, method.name)


def energy_growth(traj: Trajectory, fraction: float = 0.1) -> tuple[float, float]:
    """Largest ``|E - E0|`` in the first and in the last ``fraction`` of the run.

    A ratio last/first near 1 means bounded energy error; a large ratio, drift.
    """
    err = np.abs(traj.energy_error)
    k = max(1, int(len(err) * fraction))
    return float(np.max(err[1 : k + 1])), float(np.max(err[-k:]))
