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
when the links spin fast. It is even in ``p``, as reversibility requires.

References
----------
.. [HLW] E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*,
   2nd ed., Springer 2006, Sect. VIII.2 (Sundman and Poincare
   transformations), VIII.3 (reversible variable steps), XI (reversible
   perturbation theory).
.. [HS] E. Hairer, G. Soderlind, "Explicit, time reversible, adaptive step
   size control", SIAM J. Sci. Comput. 26 (2005) 1838-1851.
"""

from __future__ import annotations

import functools
import time

import numpy as np
import sympy as sp

from .. import validation as check
from ..analysis import AdaptiveRun, finite_difference_jacobian, symplectic_form_defect
from ..driver.simulate import step
from ..model.pendulum import PendulumModel
from ..symbolic.mechanics import derive_chain
from .model_checks import conservative_model

__all__ = [
    "naive_adaptive_leapfrog",
    "poincare_adaptive_midpoint",
    "reversible_adaptive_leapfrog",
    "round_trip_error",
    "state_dependent_step_defect",
    "step_density",
]


def _start(model, theta0, p0, links=None):
    model = conservative_model(model, links)
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
    model = conservative_model(model)
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
    error analysis applies again. ``K`` is not separable: the price is an
    implicit method and the derivatives of ``sigma``.

    Parameters
    ----------
    model : PendulumModel
        A simple or double pendulum (``sigma`` as in :func:`step_density`).
    theta0, p0 : array_like, shape (n,)
    t_end, epsilon : float
    frequency : float, optional

    References
    ----------
    HLW, Sect. VIII.2.1 (Poincare transformation); VI.3 (implicit midpoint rule).
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
