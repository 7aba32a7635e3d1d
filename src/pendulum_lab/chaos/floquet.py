"""Periodic orbits of a driven pendulum, their Floquet multipliers, and where they bifurcate.

A response of period ``k T`` to a drive of period ``T`` is a fixed point of
the ``k``-th power of the period map ``P`` (the state at ``t0 + T`` as a
function of the state at ``t0``; :mod:`.stroboscopic`). :func:`periodic_orbit`
finds it by Newton's method on ``P^k(z) - z`` (shooting), with the
derivative of ``P^k``, the monodromy matrix ``M``, from the variational
equations solved along the computed orbit
(:func:`~pendulum_lab.chaos.tangent.magnus_propagators`). The eigenvalues of
``M``, the orbit's Floquet multipliers, decide its stability: it attracts
while every one lies inside the unit circle. For one damped link
``det M = exp(-gamma k T)`` exactly (Liouville), and the two multipliers of an
attracting orbit are either a complex pair of modulus ``exp(-gamma k T / 2)``
or two real numbers whose product is that determinant.

A bifurcation is where a multiplier leaves the unit circle as a parameter
changes: through ``-1`` the orbit gives way to one of twice the period (a
flip, or period doubling), through ``+1`` it folds or, for an orbit that is
its own mirror image, breaks the symmetry in a pitchfork.
:func:`locate_bifurcation` continues an orbit in one parameter and finds the
value where ``det(M - mu I)`` (``mu = -1`` or ``+1``) changes sign, by Brent's
method [Brent]_. :func:`period_doubling_cascade` follows a cascade of flips:
each flip, then the orbit of twice the period born there, to its own flip.

Errors
------
The located value carries three errors. Newton's method stops when the
periodic orbit closes to ``tolerance`` (``1e-11`` by default) and Brent's
method when the bracket is narrower than ``xtol``: both far below the
third, the discretisation error of the period map and of its derivative.
With RK4 both are fourth order in the step, so the error of a value
located with ``N`` steps per period falls like ``N^-4``;
:func:`period_doubling_cascade` locates every value with ``N`` and ``2 N``
steps and states the difference as the error. With a fourth-order error
that difference is about 15/16 of the coarse value's error and about 15
times the fine value's: a safe bound for the fine values it reports.

Symmetry
--------
The equations of every driven model of the package are unchanged by
``(theta, p, t) -> (-theta, -p, t + T/2)``: the drive ``A cos(Omega t)``
changes sign over half a period, gravity's torque and the damping are odd
in ``(theta, p)``. An orbit is symmetric when this map takes it onto itself
(:attr:`PeriodicOrbit.symmetry_gap` is 0). A symmetric orbit of a
dissipative one-link pendulum cannot double its period: its period map is
the square of the map ``G(z) = -P_{T/2}(z)`` (half a period, then the
mirror), so a multiplier ``-1`` of ``P`` needs a multiplier ``+-i`` of ``G``,
a complex pair of modulus 1, while ``det DG = exp(-gamma T / 2) < 1``. It
must lose its symmetry first, in a pitchfork (a multiplier ``+1``)
[SW]_; the two mirror-image orbits born there can then double.

References
----------
.. [Brent] R. P. Brent, *Algorithms for Minimization without Derivatives*,
   Prentice-Hall 1973, ch. 4 (:func:`scipy.optimize.brentq`).
.. [SW] J. W. Swift, K. Wiesenfeld, "Suppression of period doubling in
   symmetric systems", Phys. Rev. Lett. 52 (1984) 705-708.
.. [F] M. J. Feigenbaum, "Quantitative universality for a class of nonlinear
   transformations", J. Stat. Phys. 19 (1978) 25-52.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from .. import validation as check
from ..driver.simulate import canonical_state, simulate
from ..integrators import get_method
from ..model import family_parameter, require_model
from ..model.angles import wrap_angle
from ..model.pendulum import PendulumModel
from .common import require_finite
from .stroboscopic import drive_period
from .tangent import magnus_propagators, ordered_product

__all__ = [
    "Bifurcation",
    "DoublingCascade",
    "PeriodicOrbit",
    "continue_orbit",
    "locate_bifurcation",
    "period_doubling_cascade",
    "periodic_orbit",
]

#: Newton's method on ``P^k(z) - z`` stops once the orbit closes to this (max-norm).
CLOSING_TOLERANCE = 1e-11


@dataclass(frozen=True)
class PeriodicOrbit:
    """A periodic orbit of a driven pendulum and its Floquet multipliers.

    Attributes
    ----------
    theta, omega, p : ndarray, shape (k, n)
        The orbit's ``k`` stroboscopic points, at ``t0, t0 + T, ...``;
        angles wrapped to ``(-pi, pi]``.
    t0 : float
        The drive's phase: the time of the first point [s].
    periods : int
        ``k``: the orbit's period in drive periods.
    turns : ndarray of int, shape (n,)
        Full turns of each link per orbit period (0 for an oscillation).
    monodromy : ndarray, shape (2n, 2n)
        The derivative of ``P^k`` at the first point, in ``(theta, p)``.
    multipliers : ndarray of complex, shape (2n,)
        Its eigenvalues, the Floquet multipliers, largest modulus first.
    mean_theta : ndarray, shape (n,)
        Time average of each angle over the orbit (turns taken out): 0 on a
        symmetric orbit.
    symmetry_gap : float
        Distance (max-norm, wrapped angles) from the first point's mirror
        image half a period later, ``(-theta, -p)(t0 + T/2)``, to the
        nearest point of the orbit: 0 (to round-off) on an orbit that is
        its own mirror image; NaN for an odd ``steps_per_period``.
    residual : float
        How closely the computed orbit closes, ``max |P^k(z) - z|``.
    iterations : int
        Newton iterations taken.
    drive_period : float
    steps_per_period : int
    method : str
    """

    theta: np.ndarray
    omega: np.ndarray
    p: np.ndarray
    t0: float
    periods: int
    turns: np.ndarray
    monodromy: np.ndarray
    multipliers: np.ndarray
    mean_theta: np.ndarray
    symmetry_gap: float
    residual: float
    iterations: int
    drive_period: float
    steps_per_period: int
    method: str

    @property
    def stable(self) -> bool:
        """Every multiplier inside the unit circle: the orbit attracts its neighbours."""
        return bool(np.max(np.abs(self.multipliers)) < 1)

    @property
    def exponents(self) -> np.ndarray:
        """``log |mu| / (k T)``, largest first [1/s]: the orbit's Lyapunov exponents."""
        return np.log(np.abs(self.multipliers)) / (self.periods * self.drive_period)

    def closing_gap(self, periods: int) -> float:
        """How far the orbit is from closing after ``periods`` drive periods (max-norm, wrapped).

        0 when ``periods`` is a multiple of :attr:`periods`; for an orbit of twice
        ``periods``, the distance between the two halves of its splitting.
        """
        periods = check.integer_at_least("periods", periods, 1)
        later = (np.arange(self.periods) + periods) % self.periods
        return float(max(np.max(np.abs(wrap_angle(self.theta[later] - self.theta))),
                         np.max(np.abs(self.p[later] - self.p))))

    def crossing(self, multiplier: int) -> float:
        """``det(M - multiplier I)``: it changes sign where a multiplier passes ``multiplier``."""
        eye = np.eye(len(self.monodromy))
        return float(np.linalg.det(self.monodromy - multiplier * eye))


def _period_run(model, theta, p, periods, steps, t0, method):
    """A run of ``periods`` drive periods (a half-integer allowed), every step saved, and
    its propagator of the variational equations."""
    period = model.drive_period
    dt = period / steps
    run = simulate(model, theta, p0=p, t_end=periods * period, dt=dt, method=method, t0=t0,
                   progress=False)
    require_finite(run, "periodic_orbit")
    monodromy = ordered_product(magnus_propagators(model, run, dt)[None])[0]
    return run, monodromy


def _orbit_from(model, run, monodromy, periods, steps, residual, iterations, method, t0):
    """The :class:`PeriodicOrbit` of a closed run."""
    n = model.n
    points = slice(0, periods * steps, steps)
    theta = run.theta[points]
    turns = np.rint((run.theta[-1] - run.theta[0]) / (2 * np.pi)).astype(int)
    # the mean angle with the turns taken out (a rotation advances 2 pi turns per orbit)
    fraction = (run.t[:-1] - run.t[0]) / (run.t[-1] - run.t[0])
    mean_theta = np.mean(run.theta[:-1] - 2 * np.pi * turns * fraction[:, None], axis=0)
    gap = np.nan
    if steps % 2 == 0:
        mirror = -np.concatenate([run.theta[steps // 2], run.p[steps // 2]])
        orbit = np.concatenate([theta, run.p[points]], axis=-1)
        distance = np.abs(mirror - orbit)
        distance[:, :n] = np.abs(wrap_angle(mirror[:n] - orbit[:, :n]))
        gap = float(distance.max(axis=-1).min())
    multipliers = np.linalg.eigvals(monodromy)
    multipliers = multipliers[np.argsort(-np.abs(multipliers), kind="stable")]
    return PeriodicOrbit(wrap_angle(theta), run.omega[points], run.p[points], float(t0), periods,
                         turns, monodromy, multipliers, mean_theta, gap, float(residual),
                         iterations, model.drive_period, steps, method)


def periodic_orbit(
    model: PendulumModel,
    theta0,
    omega0=None,
    *,
    periods: int = 1,
    p0=None,
    t0: float = 0.0,
    steps_per_period: int = 400,
    method="rk4",
    tolerance: float = CLOSING_TOLERANCE,
    max_iterations: int = 25,
    symmetric: bool = False,
) -> PeriodicOrbit:
    """The periodic orbit of ``periods`` drive periods through (or near) a state, by shooting.

    Newton's method on ``F(z) = P^k(z) - z - 2 pi m`` (``m`` the whole turns
    of the angles over the orbit, read from each run): ``z <- z - (M - I)^-1
    F(z)`` with the monodromy matrix ``M = DP^k(z)`` from the variational
    equations along the run. Newton converges to a nearby fixed point of
    ``P^k`` whether it attracts or not, so the orbit may be unstable (see
    :attr:`PeriodicOrbit.stable`); it needs a start near the orbit, for
    example a state after a transient (:func:`~pendulum_lab.chaos.stroboscopic_section`).

    With ``symmetric=True`` the orbit sought is its own mirror image (see the
    module's description): Newton's method then solves
    ``G^k(z) = -P_{kT/2}(z) = z`` (``k`` periods odd: half the orbit, then the
    mirror), whose derivative ``-DP_{kT/2}`` has the eigenvalue ``-1``
    where ``DP^k`` has ``+1``. So it converges quadratically through a
    pitchfork of the symmetric orbit, where Newton's method on ``P^k`` slows
    down (``M - I`` is singular there).

    Parameters
    ----------
    model : PendulumModel
        A driven model (one, not a family).
    theta0, omega0, p0 : array_like, shape (n,)
        The start, as for :func:`~pendulum_lab.simulate`.
    periods : int
        ``k``, the orbit's period in drive periods, ``>= 1``.
    t0 : float
        The time of the start, which fixes the drive's phase.
    steps_per_period : int
        Steps of ``method`` per drive period, ``>= 2``.
    method : str or Method
    tolerance : float
        Stop once ``max |F(z)| <= tolerance``.
    max_iterations : int
    symmetric : bool
        Seek an orbit that is its own mirror image (``periods`` odd,
        ``steps_per_period`` even).

    Returns
    -------
    PeriodicOrbit

    Raises
    ------
    RuntimeError
        If Newton's method does not close the orbit within ``max_iterations``
        (no periodic orbit of that period near the start, or one too
        unstable to find from it).

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> orbit = periodic_orbit(pl.driven_pendulum(drive_amplitude=0.9), [-0.56], [1.93],
    ...                        steps_per_period=200)
    >>> orbit.stable, bool(orbit.residual < 1e-10), round(float(abs(orbit.multipliers[0])), 4)
    (True, True, 0.0948)
    """
    require_model(model)
    drive_period(model)
    if model.shape != ():
        raise ValueError("`model` must be one model, not a family: find the orbits of a family's "
                         "members one at a time")
    periods = check.integer_at_least("periods", periods, 1)
    steps = check.integer_at_least("steps_per_period", steps_per_period, 2)
    tolerance = check.positive_number("tolerance", tolerance)
    max_iterations = check.integer_at_least("max_iterations", max_iterations, 1)
    t0 = check.real_number("t0", t0)
    method = get_method(method)
    theta, p = canonical_state(model, theta0, omega0, p0, t0=t0)
    if theta.shape != (model.n,):
        raise ValueError(f"`theta0` must be one state of shape ({model.n},), got {theta.shape}")
    if symmetric and (periods % 2 == 0 or steps % 2):
        raise ValueError(f"a symmetric orbit needs an odd `periods` and an even "
                         f"`steps_per_period`, got {periods} and {steps}")
    n = model.n
    # the map whose fixed point is sought: P^k, or the mirror S = -I after half the orbit
    span, mirror = (periods / 2, -1.0) if symmetric else (periods, 1.0)
    z = np.concatenate([theta, p]).astype(float)
    for iteration in range(1, max_iterations + 1):
        run, propagator = _period_run(model, z[:n], z[n:], span, steps, t0, method)
        end = mirror * np.concatenate([run.theta[-1], run.p[-1]])
        turns = np.rint((end[:n] - z[:n]) / (2 * np.pi))
        gap = end - z
        gap[:n] -= 2 * np.pi * turns
        residual = float(np.max(np.abs(gap)))
        if residual <= tolerance:
            if symmetric:  # the whole orbit, for its points and its monodromy matrix
                run, propagator = _period_run(model, z[:n], z[n:], periods, steps, t0, method)
            return _orbit_from(model, run, propagator, periods, steps, residual, iteration,
                               method.name, t0)
        z = z - np.linalg.solve(mirror * propagator - np.eye(2 * n), gap)
        if not np.all(np.isfinite(z)):
            break
    raise RuntimeError(f"periodic_orbit: no orbit of {periods} drive period(s) closed to "
                       f"{tolerance:g} within {max_iterations} Newton iterations (last gap "
                       f"{residual:.2e}); start nearer the orbit, e.g. after a transient")


def _model_at(model: PendulumModel, parameter: str, value: float) -> PendulumModel:
    return model.replace(**{parameter: value})


def _bracket(bracket) -> tuple[float, float]:
    """``(start, stop)``, two different finite numbers."""
    values = check.real_sequence("bracket", bracket)
    if len(values) != 2 or values[0] == values[1]:
        raise ValueError(f"`bracket` must be two different values (start, stop), got {bracket!r}")
    return float(values[0]), float(values[1])


def continue_orbit(
    model: PendulumModel,
    parameter: str,
    values,
    theta0,
    omega0=None,
    *,
    periods: int = 1,
    p0=None,
    t0: float = 0.0,
    steps_per_period: int = 400,
    method="rk4",
    tolerance: float = CLOSING_TOLERANCE,
    symmetric: bool = False,
) -> list[PeriodicOrbit]:
    """One periodic orbit followed through the values of a parameter (natural continuation).

    The orbit at ``values[0]`` is found from the start ``(theta0, omega0)``
    (:func:`periodic_orbit`), the orbit at each next value from the one
    before. Steps of the parameter small enough for Newton's method follow
    one branch, stable or not, through flips and pitchforks (where it loses
    stability but goes on); a fold, where the branch turns back, ends it
    with a ``RuntimeError``.

    Parameters
    ----------
    model : PendulumModel
    parameter : {"damping", "drive_amplitude", "drive_frequency", "g"}
        For a system that is not a chain, one of its own parameters (see
        :func:`~pendulum_lab.model.family_parameter`).
    values : array_like, shape (V,)
    theta0, omega0, p0, periods, t0, steps_per_period, method, tolerance, symmetric
        As for :func:`periodic_orbit`.

    Returns
    -------
    list of PeriodicOrbit
        One per value.
    """
    require_model(model)
    parameter = family_parameter(model, parameter)
    values = check.real_sequence("values", values)
    options = dict(periods=periods, t0=t0, steps_per_period=steps_per_period, method=method,
                   tolerance=tolerance, symmetric=symmetric)
    orbits = [periodic_orbit(_model_at(model, parameter, values[0]), theta0, omega0, p0=p0,
                             **options)]
    for value in values[1:]:
        last = orbits[-1]
        orbits.append(periodic_orbit(_model_at(model, parameter, value), last.theta[0],
                                     p0=last.p[0], **options))
    return orbits


@dataclass(frozen=True)
class Bifurcation:
    """Where a periodic orbit's Floquet multiplier passes ``-1`` or ``+1``.

    Attributes
    ----------
    parameter : str
    value : float
        The parameter's value at the crossing.
    multiplier : int
        -1 (a flip: period doubling) or +1 (a fold, or a pitchfork on a
        symmetric orbit).
    orbit : PeriodicOrbit
        The orbit at ``value``.
    rate : float
        ``d det(M - multiplier I) / d parameter`` there (by central
        differences): how fast the multiplier crosses.
    evaluations : int
        Periodic orbits computed to find it.
    """

    parameter: str
    value: float
    multiplier: int
    orbit: PeriodicOrbit
    rate: float
    evaluations: int

    @property
    def kind(self) -> str:
        """``"period doubling"`` for -1, ``"fold or pitchfork"`` for +1."""
        return "period doubling" if self.multiplier == -1 else "fold or pitchfork"


def locate_bifurcation(
    model: PendulumModel,
    parameter: str,
    bracket,
    theta0,
    omega0=None,
    *,
    multiplier: int = -1,
    periods: int = 1,
    p0=None,
    t0: float = 0.0,
    first_step: float | None = None,
    steps_per_period: int = 400,
    method="rk4",
    tolerance: float = CLOSING_TOLERANCE,
    xtol: float = 1e-13,
    symmetric: bool = False,
) -> Bifurcation:
    """The parameter value where an orbit's multiplier first passes ``multiplier``.

    The orbit through (or near) ``(theta0, omega0)`` at ``start`` is
    continued towards ``stop`` (each value's orbit by Newton's method from
    the nearest one computed) in steps guided by the secant of
    ``g = det(M - multiplier I)``, until ``g`` changes sign; Brent's method
    then narrows that bracket to ``xtol``. ``g`` is a smooth function of the
    parameter whether the multipliers are real or complex, and it vanishes
    exactly when ``multiplier`` is one of them.

    Parameters
    ----------
    model : PendulumModel
    parameter : {"damping", "drive_amplitude", "drive_frequency", "g"}
        For a system that is not a chain, one of its own parameters (see
        :func:`~pendulum_lab.model.family_parameter`).
    bracket : (float, float)
        ``(start, stop)``: where the orbit is known and where to stop looking.
    theta0, omega0, p0 : array_like, shape (n,)
        A state on or near the orbit at ``start``.
    multiplier : {-1, 1}
    periods, t0, steps_per_period, method, tolerance, symmetric
        As for :func:`periodic_orbit`; ``symmetric=True`` follows a symmetric
        orbit through its pitchfork (``multiplier=1``).
    first_step : float, optional
        The first step of the parameter, towards ``stop``; by default a
        twentieth of the bracket.
    xtol : float
        Absolute width of the final bracket.

    Returns
    -------
    Bifurcation

    Raises
    ------
    ValueError
        If ``g`` keeps its sign all the way to ``stop``.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> flip = locate_bifurcation(pl.driven_pendulum(), "drive_amplitude", (1.06, 1.07),
    ...                           [-0.25], [1.97], steps_per_period=200)
    >>> flip.kind, round(flip.value, 4), round(float(flip.orbit.multipliers[0].real), 6)
    ('period doubling', 1.0664, -1.0)
    """
    require_model(model)
    parameter = family_parameter(model, parameter)
    if multiplier not in (-1, 1):
        raise ValueError(f"`multiplier` must be -1 (period doubling) or +1 (fold or pitchfork), "
                         f"got {multiplier!r}")
    start, stop = _bracket(bracket)
    step = (stop - start) / 20 if first_step is None else check.positive_number(
        "first_step", first_step) * np.sign(stop - start)
    xtol = check.positive_number("xtol", xtol)
    options = dict(periods=periods, t0=t0, steps_per_period=steps_per_period, method=method,
                   tolerance=tolerance, symmetric=symmetric)
    known = {float(start): periodic_orbit(_model_at(model, parameter, start), theta0, omega0,
                                          p0=p0, **options)}

    def orbit_at(value):
        value = float(value)
        if value not in known:
            near = known[min(known, key=lambda v: abs(v - value))]
            known[value] = periodic_orbit(_model_at(model, parameter, value), near.theta[0],
                                          p0=near.p[0], **options)
        return known[value]

    def g(value):
        return orbit_at(value).crossing(multiplier)

    direction = np.sign(stop - start)
    a, ga = float(start), g(start)
    b = float(start + step) if abs(step) < abs(stop - start) else float(stop)
    gb = g(b)
    while ga * gb > 0:
        if b == stop:
            raise ValueError(f"no multiplier of the {periods}-period orbit passes {multiplier:+d} "
                             f"between {parameter} = {start:g} and {stop:g} (det(M - mu I) keeps "
                             f"its sign, {gb:+.3g} at the end)")
        h = b - a
        ahead = -gb * h / (gb - ga) if gb != ga else h  # the secant's step to its root
        if ahead * direction <= 0:
            ahead = h
        ahead = np.clip(abs(ahead), 0.25 * abs(h), 2 * abs(h)) * direction
        c = b + ahead
        if (c - stop) * direction > 0:
            c = float(stop)
        a, ga, b, gb = b, gb, float(c), g(c)
    value = brentq(g, min(a, b), max(a, b), xtol=xtol, rtol=4 * np.finfo(float).eps)
    orbit = orbit_at(value)
    h = max(abs(b - a) * 1e-3, 1e-9 * max(1.0, abs(value)))
    rate = (g(value + h) - g(value - h)) / (2 * h)
    return Bifurcation(parameter, float(value), multiplier, orbit, float(rate), len(known))


@dataclass(frozen=True)
class DoublingCascade:
    """Successive period doublings of a driven pendulum, each located twice.

    Attributes
    ----------
    parameter : str
    values : ndarray, shape (D,)
        The flips, located with ``2 steps_per_period`` steps per drive period.
    errors : ndarray, shape (D,)
        ``|values - coarse|``: the stated error of ``values`` (see the
        module's description; about 15 times the expected error with RK4).
    coarse : ndarray, shape (D,)
        The same flips located with ``steps_per_period`` steps.
    periods : ndarray of int, shape (D,)
        The period (in drive periods) of the orbit that doubles at each.
    bifurcations : tuple of Bifurcation
        The fine flips, with their orbits.
    steps_per_period : int
    method : str
    xtol : float
    """

    parameter: str
    values: np.ndarray
    errors: np.ndarray
    coarse: np.ndarray
    periods: np.ndarray
    bifurcations: tuple
    steps_per_period: int
    method: str
    xtol: float

    @property
    def gaps(self) -> np.ndarray:
        """``values[j+1] - values[j]``, shape (D-1,)."""
        return np.diff(self.values)

    @property
    def gap_ratios(self) -> np.ndarray:
        """``gaps[j] / gaps[j+1]``, shape (D-2,): Feigenbaum's ratios, tending to ``delta``."""
        gaps = self.gaps
        return gaps[:-1] / gaps[1:]

    @property
    def ratio_errors(self) -> np.ndarray:
        """The errors of :attr:`gap_ratios` from :attr:`errors`, to first order, shape (D-2,).

        For ``r = (a1 - a0) / (a2 - a1)``: ``|dr/da0| e0 + |dr/da1| e1 + |dr/da2| e2``.
        """
        a0, a1, a2 = self.values[:-2], self.values[1:-1], self.values[2:]
        e = self.errors + self.xtol
        e0, e1, e2 = e[:-2], e[1:-1], e[2:]
        g1, g2 = a1 - a0, a2 - a1
        return e0 / np.abs(g2) + e1 * np.abs(1 / g2 + g1 / g2**2) + e2 * np.abs(g1) / g2**2


def period_doubling_cascade(
    model: PendulumModel,
    parameter: str,
    bracket,
    theta0,
    omega0=None,
    *,
    doublings: int = 4,
    p0=None,
    t0: float = 0.0,
    settle_periods: int = 300,
    steps_per_period: int = 400,
    method="rk4",
    tolerance: float = CLOSING_TOLERANCE,
    xtol: float = 1e-13,
) -> DoublingCascade:
    """The first ``doublings`` period doublings of a cascade, with stated errors.

    From ``(theta0, omega0)`` the model at ``start`` runs ``settle_periods``
    drive periods onto its attractor, a periodic orbit that
    :func:`periodic_orbit` then closes. Each flip is located by
    :func:`locate_bifurcation` along the parameter towards ``stop``. Past a
    flip, at the value where the normal form puts the orbit of twice the
    period well inside its window (``det(M + I)`` there about ``-0.2``),
    the pendulum runs again from the flip's orbit, nudged along the flip's
    direction, onto that orbit, and the search goes on from it. Finally
    every flip is located again with twice the steps per period, starting
    from the first location: the difference is the stated error.

    Parameters
    ----------
    model : PendulumModel
        A driven model.
    parameter : {"damping", "drive_amplitude", "drive_frequency", "g"}
        For a system that is not a chain, one of its own parameters (see
        :func:`~pendulum_lab.model.family_parameter`).
    bracket : (float, float)
        ``(start, stop)``: the attractor at ``start`` must be the first
        periodic orbit of the cascade, and the doublings must lie before
        ``stop``.
    theta0, omega0, p0 : array_like, shape (n,)
        A release that ends on that attractor.
    doublings : int
        How many flips to locate, ``>= 1`` (``>= 3`` for a gap ratio).
    t0 : float
    settle_periods : int
        Drive periods run onto an attractor, ``>= 1``.
    steps_per_period : int
        Steps per drive period of the first location (the second takes twice as many).
    method, tolerance, xtol
        As for :func:`locate_bifurcation`.

    Returns
    -------
    DoublingCascade

    Raises
    ------
    RuntimeError
        If the orbit found past a flip is not one of twice the period (it
        closes after half its period).

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> cascade = period_doubling_cascade(pl.driven_pendulum(), "drive_amplitude", (1.06, 1.09),
    ...                                   [0.0], [0.0], doublings=2, steps_per_period=200)
    >>> cascade.periods.tolist(), cascade.values.round(4).tolist()
    ([1, 2], [1.0664, 1.0793])
    """
    require_model(model)
    parameter = family_parameter(model, parameter)
    start, stop = _bracket(bracket)
    doublings = check.integer_at_least("doublings", doublings, 1)
    settle_periods = check.integer_at_least("settle_periods", settle_periods, 1)
    steps = check.integer_at_least("steps_per_period", steps_per_period, 2)
    method = get_method(method)
    period = drive_period(model)
    direction = np.sign(stop - start)

    def settle(value, theta, p, periods):
        run = simulate(_model_at(model, parameter, value), theta, p0=p,
                       t_end=settle_periods * periods * period, dt=period / steps, method=method,
                       t0=t0, keep="final", progress=False)
        require_finite(run, "period_doubling_cascade")
        return run.theta[-1], run.p[-1]

    theta, p = canonical_state(model, theta0, omega0, p0, t0=t0)
    theta, p = settle(start, theta, p, 1)
    options = dict(t0=t0, method=method, tolerance=tolerance, xtol=xtol)
    here, periods, n = start, 1, model.n
    coarse = []
    while True:
        first_step = abs(stop - here) / 20
        if len(coarse) >= 2:  # the next window is narrower than the last gap
            first_step = min(first_step, abs(coarse[-1].value - coarse[-2].value) / 4)
        flip = locate_bifurcation(model, parameter, (here, stop), theta, p0=p, periods=periods,
                                  first_step=first_step, steps_per_period=steps, **options)
        coarse.append(flip)
        if len(coarse) == doublings:
            break
        # the orbit of twice the period, well inside its window (normal form of a flip)
        here = flip.value + direction * 0.2 / max(abs(flip.rate), 1e-12)
        if (here - stop) * direction >= 0:
            raise ValueError(f"`bracket` ends at {stop:g}, before the orbit of period "
                             f"{2 * periods} born at {flip.value:.6g} could be followed")
        values, vectors = np.linalg.eig(flip.orbit.monodromy)
        nudge = 1e-3 * np.real(vectors[:, np.argmin(np.abs(values + 1))])
        theta, p = settle(here, flip.orbit.theta[0] + nudge[:n], flip.orbit.p[0] + nudge[n:],
                          2 * periods)
        doubled = periodic_orbit(_model_at(model, parameter, here), theta, p0=p,
                                 periods=2 * periods, t0=t0, steps_per_period=steps,
                                 method=method, tolerance=tolerance)
        if doubled.closing_gap(periods) < 1e3 * tolerance:
            raise RuntimeError(f"period_doubling_cascade: past the flip at {flip.value:.6g} the "
                               f"pendulum is back on the orbit of period {periods}")
        theta, p, periods = doubled.theta[0], doubled.p[0], 2 * periods
    fine = [_relocate(model, parameter, flip, direction, 2 * steps, options) for flip in coarse]
    values = np.array([f.value for f in fine])
    coarse_values = np.array([f.value for f in coarse])
    return DoublingCascade(parameter, values, np.abs(values - coarse_values), coarse_values,
                           np.array([f.orbit.periods for f in fine]), tuple(fine), steps,
                           method.name, xtol)


def _relocate(model, parameter, flip: Bifurcation, direction, steps, options) -> Bifurcation:
    """``flip`` located again with ``steps`` steps per period, from its own orbit.

    The search starts just before the first location and widens tenfold
    until the crossing lies inside.
    """
    width = max(1e4 * options["xtol"], 1e-7 * max(1.0, abs(flip.value)))
    for _ in range(6):
        try:
            return locate_bifurcation(model, parameter, (flip.value - direction * width,
                                                         flip.value + direction * width),
                                      flip.orbit.theta[0], p0=flip.orbit.p[0],
                                      periods=flip.orbit.periods, multiplier=flip.multiplier,
                                      first_step=2 * width, steps_per_period=steps, **options)
        except ValueError:
            width *= 10
    raise RuntimeError(f"the flip at {flip.value:.8g} moved by more than {width / 10:.1g} when "
                       f"located again with {steps} steps per period: use more steps")
