"""Long-time behaviour of the global error on the simple pendulum.

The global error of an oscillation is mostly a phase error. A symplectic
method follows a level set of its modified Hamiltonian with a slightly wrong,
fixed frequency, so its phase error grows linearly in time [HLW, Sect. X.3].
RK4's energy drifts (see :func:`pendulum_lab.geometric.backward_error.energy_drift`);
as the pendulum's frequency depends on its energy, the frequency error then
grows too and the phase error becomes ``c1 t + c2 t^2`` with ``c1 = O(h^4)``
and ``c2 = O(h^5)``. The exact motion needed to measure this is known in
closed form (:func:`exact_libration`).

References
----------
.. [HLW] E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*,
   2nd ed., Springer 2006, Sect. X.3 (linear error growth for integrable systems).
.. [BB] G. L. Baker, J. A. Blackburn, *The Pendulum: A Case Study in Physics*,
   Oxford University Press 2005, ch. 1 (the exact solution).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import ellipj, ellipk

from .. import validation as check
from ..analysis import exact_period
from ..driver.simulate import simulate
from ..integrators import get_method
from ..model.pendulum import PendulumModel
from .model_checks import simple_pendulum_model

__all__ = ["ErrorGrowth", "exact_libration", "global_error_growth"]



def exact_libration(model: PendulumModel, amplitude: float, t) -> tuple[np.ndarray, np.ndarray]:
    """The exact motion of a simple pendulum released at rest from ``amplitude``.

    ``sin(theta/2) = k sn(K - w t | k^2)`` with ``k = sin(amplitude/2)``,
    ``w = sqrt(g/l)``, ``K = K(k^2)``, and ``p = m l^2 theta' = -2 k w m l^2
    cn(K - w t | k^2)`` (Jacobi elliptic functions, ``scipy.special.ellipj``).

    Returns
    -------
    theta, p : ndarray, shape (len(t), 1)

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> theta, p = exact_libration(pl.simple_pendulum(), 1.0, [0.0])
    >>> bool(theta[0, 0] == 1.0), bool(abs(p[0, 0]) < 1e-14)
    (True, True)
    """
    model = simple_pendulum_model(model)
    amplitude = check.real_number("amplitude", amplitude)
    if not 0 < abs(amplitude) < np.pi:
        raise ValueError(f"`amplitude` must be in (-pi, pi) and non-zero, got {amplitude}")
    k = np.sin(amplitude / 2)
    parameter = k**2
    w = np.sqrt(model.g / model.lengths[0])
    quarter = ellipk(parameter)
    u = np.mod(quarter - w * np.asarray(t, float), 4 * quarter)  # sn, cn have period 4K
    sn, cn, _, _ = ellipj(u, parameter)
    inertia = model.masses[0] * model.lengths[0] ** 2
    theta = 2 * np.arcsin(np.clip(k * sn, -1.0, 1.0))
    theta = np.where(np.isclose(u, quarter, rtol=0, atol=1e-15), amplitude, theta)
    return theta[..., None], (-2 * k * w * inertia * cn)[..., None]



@dataclass(frozen=True)
class ErrorGrowth:
    """Growth of the global error of one run against the exact libration.

    The error ``y_n - y(t_n)`` splits into a part along the orbit (a timing,
    or phase, error) and a part across it (an energy error). The phase error
    is what grows: ``phase(t) ~ c1 t + c2 t^2``, where ``c1`` comes from the
    method's frequency error at fixed energy (``O(h^order)``) and ``c2`` from
    a drift of the energy (zero for a symplectic method, ``O(h^5)`` for RK4).

    Attributes
    ----------
    method : str
    dt, amplitude, t_end : float
    t : ndarray, shape (w,)
        Right ends of log-spaced time windows.
    error : ndarray, shape (w,)
        Largest phase-space distance to the exact solution in each window,
        ``sqrt(dtheta^2 + (dp / (m l^2 w0))^2)`` [rad].
    phase : ndarray, shape (w,)
        Signed phase error [rad] at the end of each window (positive: ahead).
    early_exponent, late_exponent : float
        Slopes of ``log error`` against ``log t`` over the first and last
        third of the windows: 1 for linear growth, 2 for quadratic.
    linear, quadratic : float
        ``c1`` [rad/s], ``c2`` [rad/s^2] of a least-squares fit of the phase error.
    crossover : float
        ``|c1 / c2|``: beyond it the quadratic part dominates.
    """

    method: str
    dt: float
    amplitude: float
    t_end: float
    t: np.ndarray
    error: np.ndarray
    phase: np.ndarray
    early_exponent: float
    late_exponent: float
    linear: float
    quadratic: float
    crossover: float


def global_error_growth(model: PendulumModel, method, amplitude: float, *, dt: float,
                        t_end: float, windows: int = 30, t_start: float = 5.0) -> ErrorGrowth:
    """Measure how the global error grows with time on a libration from rest.

    The phase error is the displacement projected on the flow direction,
    ``(dy . f) / |f|^2`` (a time lag), times ``2 pi / T``, with ``T`` the
    exact period.

    Parameters
    ----------
    model : PendulumModel
        A simple pendulum.
    method : str or Method
    amplitude : float
        Release angle [rad], ``0 < |amplitude| < pi``.
    dt, t_end : float
        Choose them so that the error stays far below a radian: beyond, the
        distance saturates and the exponents mean nothing.
    windows : int
        Number of log-spaced windows between ``t_start`` and ``t_end``, ``>= 6``.
    t_start : float
        Start of the first window [s].
    """
    model = simple_pendulum_model(model)
    windows = check.integer_at_least("windows", windows, 6)
    t_start = check.positive_number("t_start", t_start)
    t_end = check.positive_number("t_end", t_end)
    if t_end <= 2 * t_start:
        raise ValueError(f"`t_end` must exceed 2 * t_start = {2 * t_start}, got {t_end}")
    run = simulate(model, [amplitude], [0.0], t_end=t_end, dt=dt, method=get_method(method),
                   save_every=max(1, int(round(0.05 / dt))))
    theta, p = (x[:, 0] for x in exact_libration(model, amplitude, run.t))
    inertia = model.masses[0] * model.lengths[0] ** 2
    scale = inertia * np.sqrt(model.g / model.lengths[0])
    d_theta, d_p = run.theta[:, 0] - theta, (run.p[:, 0] - p) / scale
    distance = np.hypot(d_theta, d_p)
    # Hamilton's field at the exact point, in the same scaled coordinates.
    f_theta = p / inertia
    f_p = -model.masses[0] * model.g * model.lengths[0] * np.sin(theta) / scale
    lag = (d_theta * f_theta + d_p * f_p) / (f_theta**2 + f_p**2)
    phase = 2 * np.pi * lag / exact_period(model, amplitude)
    edges = np.geomspace(t_start, run.t[-1], windows + 1)
    inside = [(run.t >= lo) & (run.t <= hi) for lo, hi in zip(edges[:-1], edges[1:])]
    error = np.array([np.max(distance[w]) for w in inside])
    t = edges[1:]
    third = windows // 3
    early = float(np.polyfit(np.log(t[:third]), np.log(error[:third]), 1)[0])
    late = float(np.polyfit(np.log(t[-third:]), np.log(error[-third:]), 1)[0])
    keep = run.t >= t_start
    (c1, c2), *_ = np.linalg.lstsq(np.column_stack([run.t[keep], run.t[keep] ** 2]),
                                   phase[keep], rcond=None)
    crossover = abs(c1 / c2) if c2 != 0 else np.inf
    return ErrorGrowth(get_method(method).name, float(dt), float(amplitude), float(run.t[-1]), t,
                       error, np.array([phase[w][-1] for w in inside]), early, late, float(c1),
                       float(c2), float(crossover))
