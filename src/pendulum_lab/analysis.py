"""Measurements of integrators: observed order, symplecticity, reversibility, energy.

Each function returns numbers a test or a notebook can assert on; none
prints or plots.
"""

from __future__ import annotations

import inspect
import time
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.linalg import expm
from scipy.special import ellipk

from . import _validation as check
from .integrators import get_method
from .model import PendulumModel
from .simulate import Trajectory, simulate, step

__all__ = [
    "OrderResult",
    "dominant_frequencies",
    "energy_growth",
    "exact_period",
    "linearized_solution",
    "normal_mode_frequencies",
    "observed_order",
    "oscillation_period",
    "reference_solution",
    "rest_state_at_energy",
    "reversibility_error",
    "spectrum",
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


# --------------------------------------------------------------------------- periods, spectra
def exact_period(model: PendulumModel, amplitude):
    """Exact period of the simple pendulum released at rest from ``amplitude``.

    ``T = 4 sqrt(l / g) K(k^2)`` with ``k = sin(amplitude / 2)`` and ``K`` the
    complete elliptic integral of the first kind (``scipy.special.ellipk``
    takes the parameter ``m = k^2``). At small amplitude it tends to
    ``2 pi sqrt(l / g)``; it diverges as the amplitude approaches ``pi``.

    Parameters
    ----------
    model : PendulumModel
        A simple pendulum (``n = 1``) with ``g > 0``.
    amplitude : float or array_like
        Release angle(s) [rad], ``0 <= |amplitude| < pi``.

    Returns
    -------
    float or ndarray
        Period(s) [s], the shape of ``amplitude``.

    References
    ----------
    G. L. Baker, J. A. Blackburn, *The Pendulum*, Oxford 2005, ch. 1.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> sp_ = pl.simple_pendulum(length=1.0, g=9.81)
    >>> round(float(exact_period(sp_, 1e-8) / (2 * np.pi * np.sqrt(1 / 9.81))), 12)
    1.0
    """
    if not isinstance(model, PendulumModel) or model.n != 1:
        raise ValueError("`model` must be a simple pendulum (n = 1) for the exact period")
    if model.g <= 0:
        raise ValueError(f"the model's `g` must be positive for oscillations, got {model.g}")
    amplitude = np.asarray(amplitude, dtype=float)
    if not np.all(np.isfinite(amplitude)) or np.any(np.abs(amplitude) >= np.pi):
        raise ValueError(
            f"`amplitude` must lie in (-pi, pi) (a release below the top), got {amplitude}"
        )
    period = 4.0 * np.sqrt(model.lengths[0] / model.g) * ellipk(np.sin(amplitude / 2) ** 2)
    return float(period) if period.ndim == 0 else period


def _upward_crossings(t: np.ndarray, signal: np.ndarray) -> np.ndarray:
    """Times where ``signal`` crosses zero upwards, by linear interpolation."""
    below = signal[:-1] < 0
    k = np.nonzero(below & (signal[1:] >= 0))[0]
    frac = signal[k] / (signal[k] - signal[k + 1])
    return t[k] + frac * (t[k + 1] - t[k])


def oscillation_period(traj: Trajectory, arm: int = 0):
    """Mean period of a libration, from the upward zero crossings of ``theta[arm]``.

    The crossing times are found by linear interpolation between saved
    steps; at a crossing of a libration about the downward vertical the angle
    has no curvature (``theta'' ~ -sin(theta) = 0``), so the interpolation
    error is third order in the step.

    Parameters
    ----------
    traj : Trajectory
        One trajectory or an ensemble, angles of shape ``(N+1, ..., n)``.
    arm : int
        Which angle to time (0-based).

    Returns
    -------
    float or ndarray
        The period [s]; an array of the ensemble shape for an ensemble.

    Raises
    ------
    ValueError
        If some trajectory has fewer than two upward crossings (it did not
        complete a full oscillation, or it rotates instead of swinging).
    """
    n = traj.theta.shape[-1]
    arm = check.integer_at_least("arm", arm, 0)
    if arm >= n:
        raise ValueError(f"`arm` must be in [0, {n - 1}], got {arm}")
    angles = traj.theta[..., arm]
    flat = angles.reshape(len(traj.t), -1)
    periods = np.empty(flat.shape[1])
    for j in range(flat.shape[1]):
        times = _upward_crossings(traj.t, flat[:, j])
        if len(times) < 2:
            raise ValueError(
                f"trajectory {j} has {len(times)} upward zero crossing(s) of theta[{arm}]; "
                "a period needs at least two (run longer, or the arm rotates)"
            )
        periods[j] = (times[-1] - times[0]) / (len(times) - 1)
    periods = periods.reshape(angles.shape[1:])
    return float(periods) if periods.ndim == 0 else periods


def spectrum(traj: Trajectory, arm: int | None = None, pad: int = 8):
    """Power spectrum of the angles of one trajectory.

    The mean is removed, a Hann window applied and the signal zero-padded to
    ``pad`` times its length (a finer frequency grid for locating peaks; it
    adds no resolution).

    Parameters
    ----------
    traj : Trajectory
        A single trajectory (angles of shape ``(N+1, n)``).
    arm : int, optional
        One angle (0-based); by default the power of all angles is summed.
    pad : int
        Zero-padding factor, ``>= 1``.

    Returns
    -------
    omega : ndarray, shape (M,)
        Angular frequencies [rad/s].
    power : ndarray, shape (M,)
        Power, normalised to a maximum of 1.
    """
    if traj.theta.ndim != 2:
        raise ValueError(
            "`traj` must be a single trajectory (angles of shape (N+1, n)), "
            f"got angles of shape {traj.theta.shape}"
        )
    pad = check.integer_at_least("pad", pad, 1)
    angles = traj.theta if arm is None else traj.theta[:, [arm]]
    if len(traj.t) < 16:
        raise ValueError(f"`traj` is too short for a spectrum ({len(traj.t)} samples)")
    spacing = traj.t[1] - traj.t[0]
    signal = (angles - angles.mean(axis=0)) * np.hanning(len(traj.t))[:, None]
    size = pad * len(traj.t)
    power = np.sum(np.abs(np.fft.rfft(signal, n=size, axis=0)) ** 2, axis=1)
    omega = 2 * np.pi * np.fft.rfftfreq(size, d=spacing)
    return omega, power / power.max()


def dominant_frequencies(traj: Trajectory, count: int = 2, arm: int | None = None) -> np.ndarray:
    """Angular frequencies [rad/s] of the ``count`` strongest peaks of :func:`spectrum`.

    Each peak is refined by a parabola through the logarithm of the power at
    the highest bin and its two neighbours. The accuracy is limited by the
    length ``T`` of the run (peaks are about ``4 pi / T`` wide with the Hann
    window), not by the step.

    Returns
    -------
    ndarray, shape (count,)
        Ascending.
    """
    count = check.integer_at_least("count", count, 1)
    omega, power = spectrum(traj, arm=arm)
    inner = np.arange(1, len(power) - 1)
    peaks = inner[(power[inner] > power[inner - 1]) & (power[inner] >= power[inner + 1])]
    if len(peaks) < count:
        raise ValueError(f"the spectrum has {len(peaks)} peak(s), fewer than `count` = {count}")
    strongest = peaks[np.argsort(power[peaks])[::-1][:count]]
    logp = np.log(power)
    left, mid, right = logp[strongest - 1], logp[strongest], logp[strongest + 1]
    shift = 0.5 * (left - right) / (left - 2 * mid + right)
    return np.sort(omega[strongest] + shift * (omega[1] - omega[0]))


# --------------------------------------------------------------------------- equilibria
def _equilibrium(model: PendulumModel, equilibrium):
    names = [eq.name for eq in model.chain.equilibria]
    if isinstance(equilibrium, str):
        if equilibrium not in names:
            raise ValueError(f"`equilibrium` must be one of {names}, got {equilibrium!r}")
        return model.chain.equilibria[names.index(equilibrium)]
    if equilibrium in model.chain.equilibria:
        return equilibrium
    raise TypeError(f"`equilibrium` must be a name in {names} or one of model.chain.equilibria")


def normal_mode_frequencies(model: PendulumModel) -> np.ndarray:
    """Small-oscillation angular frequencies [rad/s] about the all-down equilibrium.

    They are ``sqrt(-mu)`` for the eigenvalues ``mu`` of ``M^-1 dF/dq`` there,
    i.e. the imaginary parts of the Jacobian's eigenvalues ``+-i omega``.

    Returns
    -------
    ndarray, shape (n,)
        Ascending.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> np.round(normal_mode_frequencies(pl.simple_pendulum(length=1.0, g=4.0)), 12)
    array([2.])
    """
    down = model.chain.equilibria[0]
    ratio = np.array(down.stiffness_ratio.subs(model.parameter_values), dtype=float)
    mus = np.linalg.eigvals(ratio).real
    if np.any(mus >= 0):
        raise ValueError(f"the all-down equilibrium is not a center for g = {model.g}")
    return np.sort(np.sqrt(-mus))


def linearized_solution(model: PendulumModel, equilibrium, theta0, omega0, t):
    """Solution of the equations linearised about an equilibrium.

    With ``x = (theta - theta*, omega)`` and the Jacobian ``A`` at the
    equilibrium, ``x(t) = exp(A t) x(0)``.

    Parameters
    ----------
    model : PendulumModel
    equilibrium : str or Equilibrium
        A name from ``[eq.name for eq in model.chain.equilibria]``
        (``"down"``, ``"up"`` for one link; ``"down-up"`` and so on for two).
    theta0, omega0 : array_like, shape (n,)
        Initial angles (absolute, not offsets) and angular velocities.
    t : array_like, shape (N,)
        Times [s].

    Returns
    -------
    theta, omega : ndarray, shape (N, n)
        Absolute angles and angular velocities of the linear motion.
    """
    eq = _equilibrium(model, equilibrium)
    n = model.n
    theta0 = check.state_array("theta0", theta0, n)
    omega0 = check.state_array("omega0", omega0, n)
    if theta0.ndim != 1 or omega0.ndim != 1:
        raise ValueError("`theta0` and `omega0` must have shape (n,)")
    t = np.asarray(t, dtype=float)
    if t.ndim != 1:
        raise ValueError(f"`t` must be a 1-D array of times, got shape {t.shape}")
    angles = np.array([float(a) for a in eq.angles])
    jac = np.array(eq.jacobian.subs(model.parameter_values), dtype=float)
    x = np.empty((len(t), 2 * n))
    if len(t):
        x[0] = expm(jac * t[0]) @ np.concatenate([theta0 - angles, omega0])
    spacing = np.diff(t)
    if len(t) > 1 and np.allclose(spacing, spacing[0], rtol=1e-9, atol=0):
        # A uniform grid: one matrix exponential, then repeated products.
        propagator = expm(jac * spacing[0])
        for k in range(1, len(t)):
            x[k] = propagator @ x[k - 1]
    else:
        for k in range(1, len(t)):
            x[k] = expm(jac * (t[k] - t[0])) @ x[0]
    return angles + x[:, :n], x[:, n:]


def rest_state_at_energy(model: PendulumModel, energy: float) -> np.ndarray:
    """Angles of a state at rest with total energy ``energy``, all arms at one angle.

    With every ``theta_i = phi`` the potential energy is ``-c cos(phi)``, where
    ``c = -V(0)`` (``V`` is zero at the pivot's height), so
    ``phi = arccos(-energy / c)``. Use it to start runs on a chosen energy
    level, from the bottom (``energy = -c``) to everything straight up
    (``energy = c``).

    Returns
    -------
    ndarray, shape (n,)

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> dp = pl.double_pendulum()
    >>> theta = rest_state_at_energy(dp, 0.0)
    >>> bool(np.allclose(theta, np.pi / 2)), bool(abs(dp.potential_energy(theta)) < 1e-12)
    (True, True)
    """
    energy = check.real_number("energy", energy)
    depth = -float(model.potential_energy(np.zeros(model.n)))
    if depth <= 0:
        raise ValueError(f"the model's `g` must be positive, got {model.g}")
    if abs(energy) > depth:
        raise ValueError(
            f"`energy` must lie in [{-depth:.6g}, {depth:.6g}] J for a state at rest "
            f"(all down to all up), got {energy}"
        )
    return np.full(model.n, np.arccos(-energy / depth))


# --------------------------------------------------------------------------- comparing methods
__all__ += [
    "ComparisonRow",
    "ReferenceRun",
    "WorkPrecision",
    "compare_trajectory",
    "dop853_run",
    "dop853_work_precision",
    "markdown_table",
    "method_source",
    "order_steps",
    "pendulum_name",
    "windowed_energy_error",
    "work_precision",
]

#: Step sizes of :func:`compare_trajectory`'s order fit: in the asymptotic
#: regime on the double pendulum (``dt <= 0.025``) and well above round-off
#: for the fourth-order methods over one second.
ORDER_DTS = (0.01, 0.005, 0.0025, 0.00125)
#: The same for eighth-order methods, whose errors at ORDER_DTS are round-off:
#: on the simple pendulum from 2 rad they run from 3e-9 down to 2e-12.
HIGH_ORDER_DTS = (0.125, 0.1, 0.0625, 0.05)


def order_steps(method) -> tuple[float, ...]:
    """The step sizes :func:`compare_trajectory` fits ``method``'s order over."""
    return HIGH_ORDER_DTS if get_method(method).order > 4 else ORDER_DTS


def _python_function(obj):
    """The Python function behind a compiled (Numba) or wrapped callable."""
    obj = getattr(obj, "py_func", obj)
    return inspect.unwrap(obj) if callable(obj) else obj


def _code_names(code) -> list[str]:
    """Global names a code object uses, including those of nested functions."""
    names = list(code.co_names)
    for const in code.co_consts:
        if inspect.iscode(const):
            names.extend(_code_names(const))
    return names


def method_source(method, helpers: bool = True) -> str:
    """The source code of a method's one-step function, as the library runs it.

    Notebooks show this next to the derivation, so text and code cannot drift
    apart.

    Parameters
    ----------
    method : str or Method
        A key of :data:`pendulum_lab.METHODS`.
    helpers : bool
        Also append the source of the functions of the same module that the
        step calls (the Runge-Kutta stage loop, the fixed-point stopping
        rule), each once, in order of first use.

    Returns
    -------
    str

    Examples
    --------
    >>> "def leapfrog_step" in method_source("leapfrog")
    True
    """
    main = _python_function(get_method(method).kernel)
    module = inspect.getmodule(main)
    found, queue = [main], [main]
    while helpers and queue:
        fn = queue.pop(0)
        for name in _code_names(fn.__code__):
            candidate = _python_function(getattr(module, name, None))
            if (inspect.isfunction(candidate) and candidate.__module__ == module.__name__
                    and candidate not in found):
                found.append(candidate)
                queue.append(candidate)
    return "\n\n".join(inspect.getsource(fn).rstrip() for fn in found) + "\n"


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


@dataclass(frozen=True)
class WorkPrecision:
    """Cost and energy accuracy of one run.

    Attributes
    ----------
    method : str
    setting : float
        The step ``dt`` for a fixed-step method, the tolerance ``rtol`` for DOP853.
    energy_error : float
        ``max |H - H(0)|`` over the saved states of the run.
    wall_time : float
        Seconds spent integrating.
    evaluations : int
        Vector-field evaluations (both of Hamilton's equations, or the
        acceleration, at one state count as one).
    completed : bool
    """

    method: str
    setting: float
    energy_error: float
    wall_time: float
    evaluations: int
    completed: bool


def work_precision(model: PendulumModel, method, theta0, omega0, t_end: float,
                   dts, repeats: int = 1) -> list[WorkPrecision]:
    """Energy error against cost for a fixed-step method at several step sizes.

    Parameters
    ----------
    model : PendulumModel
    method : str or Method
    theta0, omega0 : array_like, shape (n,)
    t_end : float
    dts : sequence of float
        Step sizes, each ``> 0``.
    repeats : int
        Run each step size this many times and keep the shortest wall time
        (runs of a few milliseconds are noisy), ``>= 1``.

    Returns
    -------
    list of WorkPrecision
        One per step size, in the order given.
    """
    method = get_method(method)
    repeats = check.integer_at_least("repeats", repeats, 1)
    points = []
    for dt in dts:
        runs = [simulate(model, theta0, omega0, t_end=t_end, dt=dt, method=method,
                         progress=False) for _ in range(repeats)]
        traj = runs[0]
        points.append(WorkPrecision(method.name, float(dt),
                                    float(np.max(np.abs(traj.energy_error))),
                                    min(run.wall_time for run in runs), traj.evaluations,
                                    traj.completed))
    return points


@dataclass(frozen=True)
class ReferenceRun:
    """A run of SciPy's adaptive DOP853.

    Attributes
    ----------
    t : ndarray, shape (N+1,)
        The solver's accepted step times.
    theta, omega : ndarray, shape (N+1, n)
    energy_error : ndarray, shape (N+1,)
        ``E(t) - E(0)``.
    rtol : float
    wall_time : float
    evaluations : int
        Right-hand-side evaluations (``nfev``), each one acceleration.
    """

    t: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    energy_error: np.ndarray
    rtol: float
    wall_time: float
    evaluations: int


def dop853_run(model: PendulumModel, theta0, omega0, t_end: float,
               rtol: float = 1e-10) -> ReferenceRun:
    """Integrate with ``scipy.integrate.solve_ivp(method="DOP853")``.

    This is the general-purpose adaptive eighth-order method a student would
    otherwise reach for; it is neither symplectic nor fixed-step. It steps
    ``(theta, omega)`` with the model's accelerations (one evaluation per
    right-hand side, as for the velocity methods); ``atol`` equals ``rtol``.

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0 : array_like, shape (n,)
    t_end : float
        ``> 0``.
    rtol : float
        Relative (and absolute) tolerance, in ``[1e-14, 1e-2]``.

    Returns
    -------
    ReferenceRun
    """
    n = model.n
    theta0 = check.state_array("theta0", theta0, n)
    omega0 = check.state_array("omega0", omega0, n)
    if theta0.ndim != 1 or omega0.ndim != 1:
        raise ValueError("`theta0` and `omega0` must have shape (n,) (one trajectory)")
    t_end = check.positive_number("t_end", t_end)
    rtol = check.positive_number("rtol", rtol)
    if not 1e-14 <= rtol <= 1e-2:
        raise ValueError(f"`rtol` must be in [1e-14, 1e-2], got {rtol}")

    def rhs(_t, y):
        return np.concatenate([y[n:], model.accelerations(y[:n], y[n:])])

    start = time.perf_counter()
    sol = solve_ivp(rhs, (0.0, t_end), np.concatenate([theta0, omega0]), method="DOP853",
                    rtol=rtol, atol=rtol)
    wall = time.perf_counter() - start
    theta, omega = sol.y[:n].T, sol.y[n:].T
    energy = model.energy(theta, omega)
    return ReferenceRun(sol.t, theta, omega, energy - energy[0], rtol, wall, int(sol.nfev))


def dop853_work_precision(model: PendulumModel, theta0, omega0, t_end: float,
                          rtols, repeats: int = 1) -> list[WorkPrecision]:
    """:func:`work_precision` for DOP853 at several tolerances ``rtols``."""
    repeats = check.integer_at_least("repeats", repeats, 1)
    points = []
    for rtol in rtols:
        runs = [dop853_run(model, theta0, omega0, t_end, rtol) for _ in range(repeats)]
        points.append(WorkPrecision("DOP853", float(rtol),
                                    float(np.max(np.abs(runs[0].energy_error))),
                                    min(run.wall_time for run in runs), runs[0].evaluations, True))
    return points


@dataclass(frozen=True)
class ComparisonRow:
    """One method on one problem: the numbers of the comparison table.

    Attributes
    ----------
    pendulum : str
        ``"simple"``, ``"double"`` or ``"n=3"`` and so on.
    method : str
    variables : str
        ``"canonical"`` or ``"velocity"``.
    order : int
        The method's classical order.
    observed_order : float
        Fitted slope of the global error at ``order_t_end`` against ``dt``.
    energy_first, energy_last : float
        Largest ``|E - E0|`` in the first and last tenth of the run
        (:func:`energy_growth`).
    max_relative_energy_error : float
        Largest ``|E - E0| / |E0|`` over the run.
    symplecticity_defect, reversibility_error : float
        At the run's initial state, step ``check_dt``.
    t_end, dt : float
    wall_time : float
    evaluations : int
    mean_iterations : float
    completed : bool
    """

    pendulum: str
    method: str
    variables: str
    order: int
    observed_order: float
    energy_first: float
    energy_last: float
    max_relative_energy_error: float
    symplecticity_defect: float
    reversibility_error: float
    t_end: float
    dt: float
    wall_time: float
    evaluations: int
    mean_iterations: float
    completed: bool


def pendulum_name(model: PendulumModel) -> str:
    """``"simple"``, ``"double"``, or ``"n=3"`` and so on."""
    return {1: "simple", 2: "double"}.get(model.n, f"n={model.n}")


def compare_trajectory(model: PendulumModel, traj: Trajectory, *, order_t_end: float = 1.0,
                       order_dts=None, reference=None,
                       check_dt: float = 0.1) -> ComparisonRow:
    """Measure the method that made ``traj``: energy behaviour, order, structure.

    The energy columns come from ``traj``. The observed order is fitted by
    :func:`observed_order` from ``traj``'s initial state over ``order_t_end``;
    the symplecticity defect and reversibility error are those of one step of
    size ``check_dt`` from the same initial state.

    Parameters
    ----------
    model : PendulumModel
        The model ``traj`` was computed with.
    traj : Trajectory
        A single trajectory (not an ensemble).
    order_t_end : float
    order_dts : sequence of float, optional
        Each must divide ``order_t_end`` into whole steps; by default
        :func:`order_steps` of the method.
    reference : tuple of ndarray, optional
        ``(theta, omega)`` at ``order_t_end`` from ``traj``'s initial state;
        computed by :func:`reference_solution` if not given. Pass it to reuse
        one reference for several methods.
    check_dt : float
        Step of the symplecticity and reversibility checks, ``> 0``. At the
        default 0.1 s the symplectic methods show defects of about 1e-10
        (finite-difference noise) and RK4, the least non-symplectic method
        here, 1e-7 on the simple pendulum: a wide gap. At smaller steps
        RK4's defect, which shrinks like ``h**6``, comes close to the noise.

    Returns
    -------
    ComparisonRow
    """
    if traj.theta.ndim != 2:
        raise ValueError("`traj` must be a single trajectory (angles of shape (N+1, n)), "
                         f"got angles of shape {traj.theta.shape}")
    if traj.theta.shape[1] != model.n:
        raise ValueError(f"`traj` has {traj.theta.shape[1]} angle(s) but `model` has "
                         f"{model.n} link(s)")
    check_dt = check.positive_number("check_dt", check_dt)
    theta0, omega0, p0 = traj.theta[0], traj.omega[0], traj.p[0]
    if order_dts is None:
        order_dts = order_steps(traj.method)
    order = observed_order(model, traj.method, theta0, omega0, order_t_end, order_dts,
                           reference=reference)
    first, last = energy_growth(traj)
    return ComparisonRow(
        pendulum=pendulum_name(model),
        method=traj.method.name,
        variables=traj.method.variables,
        order=traj.method.order,
        observed_order=order.slope,
        energy_first=first,
        energy_last=last,
        max_relative_energy_error=float(np.max(np.abs(traj.relative_energy_error))),
        symplecticity_defect=symplecticity_defect(model, traj.method, theta0, p0, check_dt),
        reversibility_error=reversibility_error(model, traj.method, theta0, p0, check_dt),
        t_end=float(traj.t[-1]),
        dt=traj.dt,
        wall_time=traj.wall_time,
        evaluations=traj.evaluations,
        mean_iterations=traj.mean_iterations,
        completed=traj.completed,
    )


#: Columns of :func:`markdown_table`: header, attribute, format.
COMPARISON_COLUMNS = (
    ("pendulum", "pendulum", "{}"),
    ("method", "method", "{}"),
    ("variables", "variables", "{}"),
    ("order", "order", "{}"),
    ("observed order", "observed_order", "{:.2f}"),
    ("max abs(dE), first tenth", "energy_first", "{:.2e}"),
    ("max abs(dE), last tenth", "energy_last", "{:.2e}"),
    ("max abs(dE)/abs(E0)", "max_relative_energy_error", "{:.2e}"),
    ("symplecticity defect", "symplecticity_defect", "{:.1e}"),
    ("reversibility error", "reversibility_error", "{:.1e}"),
    ("iterations/step", "mean_iterations", "{:.1f}"),
    ("evaluations", "evaluations", "{}"),
    ("wall time [s]", "wall_time", "{:.3f}"),
)


def markdown_table(rows, columns=COMPARISON_COLUMNS) -> str:
    """A Markdown (GitHub) table of dataclass rows.

    Parameters
    ----------
    rows : sequence of ComparisonRow, WorkPrecision or any dataclass
    columns : sequence of (header, attribute, format)
        ``format`` is a :meth:`str.format` pattern such as ``"{:.2e}"``.

    Returns
    -------
    str
        Header, separator and one line per row, ending in a newline.
    """
    lines = ["| " + " | ".join(h for h, _, _ in columns) + " |",
             "|" + "|".join("---" for _ in columns) + "|"]
    for row in rows:
        cells = []
        for header, attribute, fmt in columns:
            if not hasattr(row, attribute):
                raise ValueError(f"column {header!r}: a row of type {type(row).__name__} has no "
                                 f"attribute {attribute!r}")
            cells.append(fmt.format(getattr(row, attribute)))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
