"""Adaptive step sizes, and why they break the long-time behaviour of symplectic methods.

Three ways to vary the step, measured by what they do to the energy:

* SciPy's ``solve_ivp`` (RK45, DOP853): local error control, no structure;
  the energy error drifts linearly in time
  (:func:`pendulum_lab.analysis.scipy_run`, whose :class:`AdaptiveRun` every
  function here returns).
* A *naive* variable-step leapfrog: the step comes from a local error
  estimate (leapfrog against symplectic Euler). Each step is a symplectic
  map, but the sequence of maps depends on the past in a way that is neither
  symplectic nor time-symmetric: the bounded energy error is lost
  (:func:`naive_adaptive_leapfrog`).
* A *reversible* adaptive leapfrog by a Sundman time transformation
  ``dt/dtau = sigma(q, p)``: the control variable ``rho = 1/sigma`` is advanced
  by half steps around a leapfrog step of size ``epsilon / rho``, with
  ``G = -d(log sigma)/dt`` odd under ``p -> -p`` [HS]. The method is
  time-reversible (not symplectic); on integrable, reversible problems it
  keeps the energy bounded like a fixed-step symplectic method, while its
  steps shrink where the motion is fast (:func:`reversible_adaptive_leapfrog`).
  Reversibility alone gives no such guarantee on chaotic motion.

The step-size function here is ``sigma = (1 + |omega|^2 / w^2)^(-1/2)``
(``w = sqrt(g / l_1)``): steps about ``epsilon`` at rest and ``epsilon w / |omega|``
when the links spin fast. It is even in ``p``, as reversibility requires. On
a libration of the simple pendulum ``|omega| <= 2 sqrt(g / l)``, so this ``sigma``
varies by at most a factor ``sqrt(5)`` along the orbit
(:func:`libration_step_ratio`): it follows the speed, it does not resolve the
slow passage near the top of a near-separatrix swing.

References
----------
.. [HLW] E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*,
   2nd ed., Springer 2006, Sect. VIII.2 (Sundman and Poincare
   transformations), VIII.3 (reversible variable steps), XI (reversible
   perturbation theory).
.. [HS] E. Hairer, G. Soderlind, "Explicit, time reversible, adaptive step
   size control", SIAM J. Sci. Comput. 26 (2005) 1838-1851.
.. [MT] S. Mikkola, K. Tanikawa, "Explicit symplectic algorithms for
   time-transformed Hamiltonians", Celest. Mech. Dyn. Astron. 74 (1999)
   287-295.
.. [PT] M. Preto, S. Tremaine, "A class of symplectic integrators with
   adaptive time step for separable Hamiltonian systems", Astron. J. 118
   (1999) 2532-2541.
"""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass

import numpy as np
import sympy as sp

from .. import validation as check
from ..analysis import AdaptiveRun, finite_difference_jacobian, symplectic_form_defect
from ..driver.simulate import simulate, step
from ..model.pendulum import PendulumModel
from ..symbolic.mechanics import derive_chain
from .model_checks import conservative_model, simple_pendulum_model

__all__ = [
    "LevelSpreads",
    "level_spreads",
    "libration_step_ratio",
    "naive_adaptive_leapfrog",
    "poincare_adaptive_midpoint",
    "reversible_adaptive_leapfrog",
    "round_trip_error",
    "state_dependent_step_defect",
    "step_density",
    "window_means",
]


def _start(model, theta0, p0, links=None):
    model = conservative_model(model, links, chain=True)
    theta0 = check.state_array("theta0", theta0, model.n)
    p0 = check.state_array("p0", p0, model.n)
    if theta0.ndim != 1 or p0.ndim != 1:
        raise ValueError("`theta0` and `p0` must have shape (n,): one trajectory")
    return model, theta0.copy(), p0.copy()


def _finish(label, model, times, thetas, ps, evaluations, start) -> AdaptiveRun:
    theta, p = np.array(thetas), np.array(ps)
    energy = model.hamiltonian_value(theta, p)
    return AdaptiveRun(label, np.array(times), theta, p, energy - energy[0], len(times) - 1,
                       evaluations, time.perf_counter() - start)


def _momentum_scale(model) -> float:
    """A typical momentum, ``m l^2 sqrt(g / l)`` of the first link, to weigh errors in p."""
    return model.masses[0] * model.lengths[0] ** 2 * np.sqrt(model.g / model.lengths[0])


def _naive_step(model, theta, p, h, tol, cap):
    """One accepted step of the naive controller, trying steps ``min(h, cap)`` and smaller.

    Returns the new state, the step taken, the step proposed for next time
    and the number of one-step calls made.
    """
    scale, calls = _momentum_scale(model), 0
    while True:
        taken = min(h, cap)
        theta1, p1 = step(model, theta, p0=p, dt=taken, method="leapfrog")
        theta_e, p_e = step(model, theta, p0=p, dt=taken, method="semi_implicit_euler")
        calls += 2
        err = max(np.max(np.abs(theta1 - theta_e)), np.max(np.abs(p1 - p_e)) / scale)
        h = taken * (float(np.clip(0.9 * np.sqrt(tol / err), 0.5, 2.0)) if err > 0 else 2.0)
        if err <= tol:
            return theta1, p1, taken, h, calls


def naive_adaptive_leapfrog(model: PendulumModel, theta0, p0, *, t_end: float, tol: float,
                            h_initial: float = 0.01, h_max: float = 0.5) -> AdaptiveRun:
    """Leapfrog with the step chosen from a local error estimate, as a general-purpose code would.

    Each attempt takes one leapfrog step and one symplectic Euler step from
    the same state; their distance (angles in rad, momenta divided by
    ``m l^2 sqrt(g/l)``) estimates the local error, ``O(h^2)``. The step is
    accepted (keeping the leapfrog result) when the estimate is at most
    ``tol``; either way the next attempt is ``h * clip(0.9 sqrt(tol / err), 0.5, 2)``.

    Parameters
    ----------
    model : PendulumModel
    theta0, p0 : array_like, shape (n,)
        Initial angles and canonical momenta.
    t_end, tol, h_initial, h_max : float

    Returns
    -------
    AdaptiveRun
    """
    model, theta, p = _start(model, theta0, p0)
    t_end = check.positive_number("t_end", t_end)
    tol = check.positive_number("tol", tol)
    h = check.positive_number("h_initial", h_initial)
    h_max = check.positive_number("h_max", h_max)
    start, t, calls = time.perf_counter(), 0.0, 0
    times, thetas, ps = [0.0], [theta], [p]
    while t < t_end * (1 - 1e-12):
        theta, p, taken, h, used = _naive_step(model, theta, p, h, tol, min(h_max, t_end - t))
        t, calls = t + taken, calls + used
        times.append(t)
        thetas.append(theta)
        ps.append(p)
    return _finish(f"naive adaptive leapfrog, tol {tol:g}", model, times, thetas, ps, calls,
                   start)


def step_density(model: PendulumModel, theta, p, frequency: float | None = None) -> np.ndarray:
    """``sigma = (1 + |omega|^2 / w^2)^(-1/2)`` and its control ``G = -d(log sigma)/dt``.

    Returns an array of shape ``(2, ...)``: ``sigma`` and ``G`` at each state
    ``(theta, p)`` of shape ``(..., n)``. ``G`` uses the exact time
    derivative ``omega . alpha / (w^2 + |omega|^2)`` with the accelerations
    ``alpha``; it changes sign with ``p``, which makes the adaptive method
    reversible.
    """
    model = conservative_model(model, chain=True)
    w2 = (model.g / model.lengths[0] if frequency is None
          else check.positive_number("frequency", frequency) ** 2)
    theta = check.state_array("theta", theta, model.n)
    p = check.state_array("p", p, model.n)
    check.same_shape("theta", theta, "p", p)
    omega = model.velocities(theta, p)
    alpha = model.accelerations(theta, omega)
    speed2 = np.sum(omega**2, axis=-1)
    return np.stack([1.0 / np.sqrt(1.0 + speed2 / w2), np.sum(omega * alpha, axis=-1) /
                     (w2 + speed2)])


def libration_step_ratio(model: PendulumModel, amplitude: float,
                         frequency: float | None = None) -> float:
    """Largest over smallest ``sigma`` along a libration of the simple pendulum released at rest.

    On the libration of amplitude ``a`` the speed runs from 0 at the turning
    points to ``|omega|_max = 2 sqrt(g/l) sin(a/2)`` at the bottom (energy
    conservation), so with :func:`step_density`'s ``sigma``

    ``sigma(rest) / sigma(bottom) = sqrt(1 + 4 (g / l) sin^2(a/2) / w^2)``.

    The steps of :func:`reversible_adaptive_leapfrog` and
    :func:`poincare_adaptive_midpoint` follow ``epsilon sigma`` (the first up to
    the error of integrating ``rho``), so their largest-to-smallest step ratio
    is close to this number. With ``amplitude = pi`` (the separatrix) it is
    the supremum over all librations: ``sqrt(5)`` for the default ``w``.

    Parameters
    ----------
    model : PendulumModel
        A simple pendulum.
    amplitude : float
        ``0 < |amplitude| <= pi`` [rad].
    frequency : float, optional
        ``w`` of the step-size function; ``sqrt(g / l)`` by default.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> round(libration_step_ratio(pl.simple_pendulum(), np.pi) ** 2, 12)
    5.0
    """
    model = simple_pendulum_model(model)
    amplitude = check.real_number("amplitude", amplitude)
    if not 0 < abs(amplitude) <= np.pi:
        raise ValueError(f"`amplitude` must be in (0, pi] in size (a libration), got {amplitude}")
    w0_squared = model.g / model.lengths[0]
    w2 = w0_squared if frequency is None else check.positive_number("frequency", frequency) ** 2
    return float(np.sqrt(1.0 + 4.0 * w0_squared * np.sin(amplitude / 2) ** 2 / w2))


def _sundman_step(model, theta, p, rho, control, epsilon, frequency):
    """One step of the reversible adaptive leapfrog.

    ``control`` is ``G`` at the current state (the end of the previous step
    computed it). Returns ``(theta, p, rho, control, h)``.
    """
    rho_half = rho + 0.5 * epsilon * control
    h = epsilon / rho_half
    theta, p = step(model, theta, p0=p, dt=h, method="leapfrog")
    control = step_density(model, theta, p, frequency)[1]
    return theta, p, rho_half + 0.5 * epsilon * control, control, h


def reversible_adaptive_leapfrog(model: PendulumModel, theta0, p0, *, t_end: float,
                                 epsilon: float, frequency: float | None = None) -> AdaptiveRun:
    """The time-reversible adaptive leapfrog of Hairer and Soderlind (a Sundman transform).

    With ``rho = 1 / sigma(y)`` at the start, each step is

    ``rho_half = rho + epsilon/2 G(y)``;  ``y1 = leapfrog(y, h = epsilon / rho_half)``;
    ``rho1 = rho_half + epsilon/2 G(y1)``,

    with ``sigma`` and ``G`` from :func:`step_density`. Steps are about
    ``epsilon sigma``.

    Parameters
    ----------
    model : PendulumModel
    theta0, p0 : array_like, shape (n,)
    t_end : float
        The run stops at the first step ending at or after ``t_end``.
    epsilon : float
        The step in the fictive time ``tau`` (the step at rest).
    frequency : float, optional
        ``w`` of the step-size function; ``sqrt(g / l_1)`` by default.

    References
    ----------
    HS, Sect. 3; HLW, Sect. VIII.3.2.
    """
    model, theta, p = _start(model, theta0, p0)
    t_end = check.positive_number("t_end", t_end)
    epsilon = check.positive_number("epsilon", epsilon)
    if frequency is not None:
        frequency = check.positive_number("frequency", frequency)
    start, t = time.perf_counter(), 0.0
    times, thetas, ps = [0.0], [theta], [p]
    sigma, control = step_density(model, theta, p, frequency)
    rho = 1.0 / sigma
    while t < t_end * (1 - 1e-12):
        theta, p, rho, control, h = _sundman_step(model, theta, p, rho, control, epsilon,
                                                  frequency)
        t += h
        times.append(t)
        thetas.append(theta)
        ps.append(p)
    return _finish(f"reversible adaptive leapfrog, epsilon {epsilon:g}", model, times, thetas,
                   ps, len(times) - 1, start)


#: Options of :func:`round_trip_error` per method: (required, optional).
ROUND_TRIP_OPTIONS = {"reversible": (("epsilon",), ("frequency",)),
                      "naive": (("tol",), ("h_initial",))}


def round_trip_error(model: PendulumModel, method: str, theta0, p0, *, steps: int,
                     **options) -> float:
    """Run ``steps`` steps forward, reverse the momenta, run ``steps`` again: distance to the start.

    A time-reversible method returns to the start (with reversed momenta) to
    round-off. ``method`` is ``"reversible"`` (:func:`reversible_adaptive_leapfrog`,
    option ``epsilon``, optional ``frequency``; ``rho`` is carried over) or
    ``"naive"`` (:func:`naive_adaptive_leapfrog`, options ``tol`` and
    ``h_initial``; the backward leg starts with the step the forward leg
    proposed last).
    """
    model, theta, p = _start(model, theta0, p0)
    steps = check.integer_at_least("steps", steps, 1)
    method = check.choice("method", method, ROUND_TRIP_OPTIONS)
    required, optional = ROUND_TRIP_OPTIONS[method]
    missing = [name for name in required if name not in options]
    unknown = sorted(set(options) - set(required) - set(optional))
    if missing or unknown:
        raise TypeError(f"round_trip_error(method={method!r}) takes the options "
                        f"{list(required) + list(optional)} ({', '.join(required)} required); "
                        + (f"missing {missing}" if missing else f"unknown {unknown}"))
    if method == "reversible":
        epsilon = check.positive_number("epsilon", options["epsilon"])
        frequency = options.get("frequency")
        sigma, control = step_density(model, theta, p, frequency)
        state = (theta, p, 1.0 / sigma, control)
        for leg in range(2):
            if leg:  # reverse the momenta; G is odd in p
                state = (state[0], -state[1], state[2], -state[3])
            for _ in range(steps):
                state = _sundman_step(model, *state, epsilon, frequency)[:4]
        theta2, p2 = state[0], state[1]
    elif method == "naive":
        tol = check.positive_number("tol", options["tol"])
        h = check.positive_number("h_initial", options.get("h_initial", 0.01))
        theta2, p2 = theta, p
        for leg in range(2):
            if leg:
                p2 = -p2
            for _ in range(steps):
                theta2, p2, _, h, _ = _naive_step(model, theta2, p2, h, tol, np.inf)
    return float(max(np.max(np.abs(theta2 - theta)), np.max(np.abs(-p2 - p))))


def state_dependent_step_defect(model: PendulumModel, theta, p, *, epsilon: float,
                                frequency: float | None = None,
                                delta: float = 1e-6) -> tuple[float, float]:
    """Why a step chosen from the state spoils symplecticity, in one number.

    Compares the maps ``y -> leapfrog_{h(y)}(y)`` with ``h(y) = epsilon sigma(y)``
    (the step follows the state) and ``y -> leapfrog_{h0}(y)`` with the step
    frozen at ``h0 = h(y0)``: the Jacobian of the first picks up
    ``(d leapfrog / dh) grad h(y)^T``, which is not symplectic.

    Returns
    -------
    variable, frozen : float
        ``max |Psi^T J Psi - J|`` of the two maps at ``(theta, p)``, from
        central differences with spacing ``delta``.
    """
    model, theta, p = _start(model, theta, p)
    epsilon = check.positive_number("epsilon", epsilon)
    n, z0 = model.n, np.concatenate([theta, p])
    frozen = epsilon * step_density(model, theta, p, frequency)[0]

    def leapfrog_with(step_of):
        return lambda z: np.concatenate(
            step(model, z[:n], p0=z[n:], dt=step_of(z), method="leapfrog"))

    def variable(z):
        return epsilon * step_density(model, z[:n], z[n:], frequency)[0]

    return tuple(symplectic_form_defect(finite_difference_jacobian(leapfrog_with(rule), z0, delta))
                 for rule in (variable, lambda z: frozen))


@functools.cache
def _poincare_field(n: int):
    """``J^-1 grad K`` and ``sigma`` for ``K = sigma (H - E0)``, lambdified for floats.

    Arguments: angles, momenta, parameters, ``E0``, ``w^2``.
    """
    chain = derive_chain(n)
    energy, w2 = sp.symbols("E_0 w2", positive=True)
    omega = chain.inverse_mass_matrix * chain.p
    sigma = 1 / sp.sqrt(1 + (omega.T * omega)[0, 0] / w2)
    k = sigma * (chain.hamiltonian - energy)
    field = [k.diff(x) for x in chain.p] + [-k.diff(x) for x in chain.q]
    args = (*chain.q, *chain.p, *chain.parameters, energy, w2)
    return sp.lambdify(args, [*field, sigma], modules="math", cse=True)


def poincare_adaptive_midpoint(model: PendulumModel, theta0, p0, *, t_end: float,
                               epsilon: float, frequency: float | None = None) -> AdaptiveRun:
    """The symplectic route to variable steps: a Poincare time transformation.

    The Hamiltonian ``K(y) = sigma(y) (H(y) - E0)`` with ``E0 = H(y0)`` has the
    level set ``K = 0``, on which its flow is ``dy/dtau = sigma(y) f(y)``: the
    pendulum's motion with the clock ``dt/dtau = sigma``. Integrating ``K`` with
    constant steps ``epsilon`` by a symplectic method (the implicit midpoint
    rule here, solved by fixed-point iteration to round-off) gives variable
    steps ``h ~ epsilon sigma`` in ``t`` and a symplectic map, so backward
    error analysis applies again. With this ``sigma`` (a function of the
    momenta and the angles) ``K`` is not separable, so a general symplectic
    method for it is implicit, and it needs the derivatives of ``sigma``.
    For a separable ``H = T(p) + U(q)`` and special time transformations
    (the logarithmic Hamiltonian ``log(T + p_t) - log(-U)`` in an extended phase
    space, among others) the transformed problem splits into explicit parts
    and the leapfrog stays explicit [MT, PT].

    Parameters
    ----------
    model : PendulumModel
        A simple or double pendulum (``sigma`` as in :func:`step_density`).
    theta0, p0 : array_like, shape (n,)
    t_end, epsilon : float
    frequency : float, optional

    References
    ----------
    HLW, Sect. VIII.2.1 (Poincare transformation); VI.3 (implicit midpoint rule);
    MT and PT (explicit alternatives for special ``sigma``).
    """
    model, theta, p = _start(model, theta0, p0, links=(1, 2))
    t_end = check.positive_number("t_end", t_end)
    epsilon = check.positive_number("epsilon", epsilon)
    w2 = model.g / model.lengths[0] if frequency is None else (
        check.positive_number("frequency", frequency) ** 2)
    field, n = _poincare_field(model.n), model.n
    constants = (*model.masses, *model.lengths, model.g,
                 float(model.hamiltonian_value(theta, p)), w2)
    start, t, calls = time.perf_counter(), 0.0, 0
    z = np.concatenate([theta, p])
    times, thetas, ps = [0.0], [theta], [p]
    while t < t_end * (1 - 1e-12):
        z1, previous, sweeps = z.copy(), np.inf, 0
        while True:
            sweeps += 1
            *slope, sigma = field(*(0.5 * (z + z1)), *constants)
            new = z + epsilon * np.asarray(slope)
            change = float(np.max(np.abs(new - z1)))
            z1 = new
            if change == 0.0 or change >= previous:  # converged, or jittering at round-off
                break
            if sweeps == 100:
                raise RuntimeError(f"the implicit midpoint step did not converge (epsilon = "
                                   f"{epsilon:g}): use a smaller epsilon")
            previous = change
        calls += sweeps
        t += epsilon * sigma
        z = z1
        times.append(t)
        thetas.append(z[:n])
        ps.append(z[n:])
    return _finish(f"Poincare transform + implicit midpoint, epsilon {epsilon:g}", model, times,
                   thetas, ps, calls, start)


# --------------------------------------------------------------------------- wandering levels
def window_means(t, error, width: float, t_end: float | None = None) -> np.ndarray:
    """Means of ``error`` over consecutive windows ``[a, a + width)`` from 0 to ``t_end``.

    A bounded energy error oscillates about a fixed level, so its window
    means agree; an error with no conserved quantity to oscillate about
    wanders, and so do its window means.

    Parameters
    ----------
    t, error : array_like, shape (m,)
        Saved times (increasing, from 0) and the energy error there.
    width : float
        Window length [s].
    t_end : float, optional
        Only windows that start before ``t_end`` (default: the run's end).

    Returns
    -------
    ndarray
        One mean per window that holds a saved time.

    Examples
    --------
    >>> window_means([0.0, 1.0, 2.0, 3.0], [1.0, 3.0, 5.0, 7.0], 2.0).tolist()
    [2.0, 6.0]
    """
    t, error = np.asarray(t, float), np.asarray(error, float)
    if t.ndim != 1 or t.shape != error.shape or t.size < 2:
        raise ValueError(f"`t` and `error` must be 1-d of the same length >= 2, got shapes "
                         f"{t.shape} and {error.shape}")
    width = check.positive_number("width", width)
    t_end = t[-1] if t_end is None else check.positive_number("t_end", t_end)
    starts = np.arange(0.0, t_end - 1e-9 * width, width)
    means = [error[(t >= a) & (t < a + width)] for a in starts]
    return np.array([m.mean() for m in means if m.size])


@dataclass(frozen=True)
class LevelSpreads:
    """How far the window means of the energy error wander, by start and run length.

    Attributes
    ----------
    starts : ndarray, shape (s, n)
        Release angles (at rest).
    lengths : ndarray, shape (r,)
        Run lengths [s]: each spread is over the windows of ``[0, length]``
        of one run of the longest length.
    width : float
        Window length [s].
    epsilon : float
        The reversible method's step in the fictive time.
    reversible, fixed : ndarray, shape (s, r)
        ``max - min`` of the window means of ``E - E0`` [J] for the
        reversible adaptive leapfrog and for the fixed-step leapfrog with the
        same mean step over the longest run.
    steps : ndarray of int, shape (s,)
        Steps of each reversible run (and of its fixed-step twin).
    """

    starts: np.ndarray
    lengths: np.ndarray
    width: float
    epsilon: float
    reversible: np.ndarray
    fixed: np.ndarray
    steps: np.ndarray


def level_spreads(model: PendulumModel, starts, *, lengths, epsilon: float,
                  width: float = 20.0) -> LevelSpreads:
    """Spreads of the window means of the energy error, reversible adaptive against fixed step.

    For each release (at rest) one run of :func:`reversible_adaptive_leapfrog`
    and one fixed-step leapfrog run with the same number of steps, both of the
    longest length; the spread of the window means (:func:`window_means`) is
    measured over the first ``length`` seconds for each ``length``.

    Parameters
    ----------
    model : PendulumModel
    starts : array_like, shape (s, n)
        Release angles [rad].
    lengths : sequence of float
        Increasing run lengths [s], each at least two windows long.
    epsilon : float
    width : float
        Window length [s].

    Returns
    -------
    LevelSpreads
    """
    model = conservative_model(model, chain=True)
    starts = check.state_array("starts", starts, model.n)
    if starts.ndim != 2:
        raise ValueError(f"`starts` must have shape (s, {model.n}), got {starts.shape}")
    lengths = np.asarray([check.positive_number("lengths", x) for x in lengths])
    width = check.positive_number("width", width)
    if lengths.size == 0 or np.any(np.diff(lengths) <= 0) or lengths[0] < 2 * width:
        raise ValueError(f"`lengths` must be increasing, each at least 2 * width = "
                         f"{2 * width:g} s, got {lengths}")
    epsilon = check.positive_number("epsilon", epsilon)
    t_end, rest = float(lengths[-1]), np.zeros(model.n)
    reversible, fixed, steps = [], [], []
    for start in starts:
        run = reversible_adaptive_leapfrog(model, start, rest, t_end=t_end, epsilon=epsilon)
        twin = simulate(model, start, rest, t_end=t_end, dt=t_end / run.steps, method="leapfrog",
                        progress=False)
        steps.append(run.steps)
        for out, (t, error) in ((reversible, (run.t, run.energy_error)),
                                (fixed, (twin.t, twin.energy_error))):
            out.append([np.ptp(window_means(t, error, width, length)) for length in lengths])
    return LevelSpreads(starts, lengths, width, epsilon, np.array(reversible), np.array(fixed),
                        np.array(steps))
