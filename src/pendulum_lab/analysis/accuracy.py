"""Accuracy of integrators: observed order against a reference, energy error over time.

Each function returns numbers a test or a notebook can assert on; none
prints or plots.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from .. import validation as check
from ..driver.simulate import Trajectory, simulate, velocity_state
from ..integrators import get_method
from ..model.pendulum import PendulumModel

__all__ = [
    "HIGH_ORDER_DTS",
    "ORDER_DTS",
    "OrderResult",
    "energy_growth",
    "global_error",
    "observed_order",
    "order_steps",
    "reference_solution",
    "windowed_energy_error",
]

#: Step sizes of an order fit: in the asymptotic regime on the double pendulum
#: (``dt <= 0.025``) and well above round-off for the fourth-order Runge-Kutta methods
#: over one second. The optimised compositions are more accurate: ``blanes_moan4`` is at
#: 1e-13 at the smallest step, the reference's level, so fit it on the first three.
ORDER_DTS = (0.01, 0.005, 0.0025, 0.00125)
#: The same for eighth-order methods, whose errors at ORDER_DTS are round-off:
#: on the simple pendulum from 2 rad they run from 3e-9 down to 2e-12.
HIGH_ORDER_DTS = (0.125, 0.1, 0.0625, 0.05)


def order_steps(method) -> tuple[float, ...]:
    """The step sizes of an order fit of ``method``: :data:`ORDER_DTS` or :data:`HIGH_ORDER_DTS`."""
    return HIGH_ORDER_DTS if get_method(method).order > 4 else ORDER_DTS


def reference_solution(model: PendulumModel, theta0, omega0=None, *, t_end: float,
                       rtol: float = 1e-13, p0=None,
                       t0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """``(theta, omega)`` at ``t0 + t_end`` by SciPy's DOP853 at a tight tolerance.

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0, p0 : array_like, shape (n,)
        The initial state (give ``omega0`` or ``p0``).
    t_end : float
        Length of the run [s].
    rtol : float
        Relative and absolute tolerance of DOP853.
    t0 : float
        The time the run starts at [s] (where the equations depend on the time).
    """
    t0 = check.real_number("t0", t0)
    theta0, omega0 = velocity_state(model, theta0, omega0, p0, t0=t0)
    sol = scipy_solution(model, theta0, omega0, t_end, rtol, t0=t0)
    return sol.y[: model.n, -1], sol.y[model.n :, -1]


def scipy_solution(model: PendulumModel, theta0: np.ndarray, omega0: np.ndarray, t_end: float,
                   rtol: float, method: str = "DOP853", t0: float = 0.0):
    """``scipy.integrate.solve_ivp`` on ``(theta, omega)`` over ``[t0, t0 + t_end]`` with
    ``atol = rtol`` (checked inputs).

    The one place the package calls SciPy's adaptive solvers; ``method`` is
    a SciPy method name (``"DOP853"``, ``"RK45"``).
    """
    n = model.n

    def rhs(t, y):
        return np.concatenate([y[n:], model.accelerations(y[:n], y[n:], t)])

    return solve_ivp(rhs, (t0, t0 + t_end), np.concatenate([theta0, omega0]), method=method,
                     rtol=rtol, atol=rtol)


def global_error(theta, omega, reference) -> float:
    """The global error of a computed state: max-norm distance in ``(theta, omega)``.

    Parameters
    ----------
    theta, omega : array_like, shape (n,)
        The computed state at some time ``T``.
    reference : (ndarray, ndarray)
        ``(theta, omega)`` at ``T`` from an accurate run
        (:func:`reference_solution`).

    Examples
    --------
    >>> global_error([1.0, 2.0], [0.5, 0.0], ([1.0, 2.0 + 1e-6], [0.5, -3e-6]))
    3e-06
    """
    computed = np.concatenate([np.asarray(theta, float), np.asarray(omega, float)])
    return float(np.max(np.abs(computed - np.concatenate(reference))))


def final_state_at(traj: Trajectory, t_end: float) -> tuple[np.ndarray, np.ndarray]:
    """``(theta, omega)`` of the last saved state, which must be the state at ``t_end``."""
    if not np.isclose(traj.t[-1], t_end, rtol=0, atol=1e-9):
        raise ValueError(f"`t_end` ({t_end}) must be a whole number of steps of dt = {traj.dt}")
    return traj.theta[-1], traj.omega[-1]


@dataclass(frozen=True)
class OrderResult:
    """Errors at the final time for a sequence of step sizes, and the fitted slope; ``model``
    is the pendulum they were measured on (a figure's legend names it)."""

    dts: np.ndarray
    errors: np.ndarray
    slope: float
    method: str
    model: PendulumModel | None = None


def observed_order(model: PendulumModel, theta0, omega0=None, *, t_end: float = 1.0,
                   dts=(0.02, 0.01, 0.005, 0.0025), method="glrk4", p0=None,
                   reference=None, t0: float = 0.0) -> OrderResult:
    """Fit the slope of log(error) against log(dt) at ``t_end``.

    The error is the global error at ``t_end``, the max-norm distance in
    ``(theta, omega)`` from ``reference`` (:func:`global_error`; by default
    the reference is :func:`reference_solution`). Keep ``dt`` small enough to be in
    the asymptotic regime (on the double pendulum ``dt <= 0.025``) and the
    errors well above round-off.

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0, p0 : array_like, shape (n,)
        The initial state (give ``omega0`` or ``p0``).
    t_end : float
        Time of the comparison [s]; each ``dt`` must divide it into whole steps.
    dts : sequence of float
        Step sizes, ``> 0``, at least two different ones (a slope needs two).
    method : str or Method
    reference : tuple of ndarray, optional
        ``(theta, omega)`` at ``t0 + t_end``.
    t0 : float
        The time the runs start at [s].

    Returns
    -------
    OrderResult
    """
    method = get_method(method)
    t0 = check.real_number("t0", t0)
    theta0, omega0 = velocity_state(model, theta0, omega0, p0, t0=t0)
    dts = check.real_sequence("dts", dts)
    for dt in dts:
        check.positive_number("dts", float(dt))
    if np.unique(dts).size < 2:
        raise ValueError(f"`dts` must hold at least two different step sizes (a slope needs two "
                         f"points), got {dts.tolist()}")
    t_end = check.positive_number("t_end", t_end)
    if reference is None:
        reference = reference_solution(model, theta0, omega0, t_end=t_end, t0=t0)
    errors = []
    for dt in dts:
        traj = simulate(model, theta0, omega0, t_end=t_end, dt=dt, method=method, keep="final",
                        t0=t0)
        errors.append(global_error(*final_state_at(traj, t0 + t_end), reference))
    errors = np.asarray(errors)
    slope = float(np.polyfit(np.log(dts), np.log(errors), 1)[0])
    return OrderResult(dts, errors, slope, method.name, model)


def energy_growth(traj: Trajectory, fraction: float = 0.1) -> tuple[float, float]:
    """Largest ``|E - E0|`` in the first and in the last ``fraction`` of the run.

    A ratio last/first near 1 means bounded energy error; a large ratio, drift.
    """
    err = np.abs(traj.energy_error)
    k = max(1, int(len(err) * fraction))
    return float(np.max(err[1 : k + 1])), float(np.max(err[-k:]))


def windowed_energy_error(traj: Trajectory, edges) -> np.ndarray:
    """Largest ``|E - E0|`` in each time window ``[edges[i], edges[i+1]]``.

    A bounded error gives about the same value in every window; a drifting
    one grows from window to window. Log-spaced edges (``[0, 10, 100,
    1000]``) show growth over decades of time.

    Parameters
    ----------
    traj : Trajectory
        One trajectory (energy of shape ``(N+1,)``).
    edges : array_like, shape (k+1,)
        Increasing times within ``[0, traj.t[-1]]``.

    Returns
    -------
    ndarray, shape (k,)
        NaN for a window that holds no saved time.
    """
    if traj.energy.ndim != 1:
        raise ValueError("`traj` must be a single trajectory, got an ensemble of shape "
                         f"{traj.energy.shape[1:]}")
    edges = np.asarray(edges, dtype=float)
    if edges.ndim != 1 or edges.size < 2 or np.any(np.diff(edges) <= 0):
        raise ValueError(f"`edges` must be at least two increasing times, got {edges}")
    if edges[0] < 0 or edges[-1] > traj.t[-1] * (1 + 1e-12):
        raise ValueError(f"`edges` must lie in [0, {traj.t[-1]:g}] (the run), got {edges}")
    err = np.abs(traj.energy_error)
    out = np.full(edges.size - 1, np.nan)
    for i, (lo, hi) in enumerate(zip(edges[:-1], edges[1:])):
        inside = (traj.t >= lo) & (traj.t <= hi)
        if np.any(inside):
            out[i] = np.max(err[inside])
    return out
