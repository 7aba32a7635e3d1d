"""Symplectic Euler on the pendulum is Chirikov's standard map.

One step of symplectic Euler with step ``h`` on the simple pendulum,
``p1 = p - h m g l sin(theta)``, ``theta1 = theta + h p1 / (m l^2)``, becomes,
with

    phi = theta + pi,   I = h p / (m l^2),   K = (g / l) h^2,

the standard map ``I1 = I + K sin(phi)``, ``phi1 = phi + I1`` (the shift by
``pi`` turns ``-sin(theta)`` into ``+sin(phi)``). For small ``K`` most orbits
lie on invariant circles that wind around the cylinder and separate
``I`` below them from ``I`` above; the last of them, with golden-mean
rotation number, breaks at Greene's ``K_c = 0.971635...``. Beyond it an
orbit can travel through a whole period ``2 pi`` of ``I``: global transport.
Just above ``K_c`` the broken circle leaves a *cantorus* whose gaps let orbits
through slowly: the flux through it vanishes like ``(K - K_c)^eta`` with
``eta ~ 3.01`` [MMP], so crossing times grow like ``(K - K_c)^-3``.
:func:`crossing_times` measures the median crossing time of an ensemble, a
statistic that, unlike the fastest orbit's time, does not drift with the
number of orbits.
Greene's residue criterion locates ``K_c`` itself: :func:`residue` is the residue
``R = (2 - tr M) / 4`` of a symmetric periodic orbit of rotation number ``p / q``, and along
the golden mean's approximants ``F_(j-1) / F_j`` (Fibonacci numbers) the residues fall to 0
below ``K_c``, grow without bound above, and stay near ``1/4`` at it;
:func:`residue_crossing` gives the ``K`` where ``R = 1/4``, which tends to ``K_c`` as ``q``
grows.

References
----------
.. [Chirikov] B. V. Chirikov, "A universal instability of many-dimensional
   oscillator systems", Physics Reports 52 (1979) 263-379.
.. [Greene] J. M. Greene, "A method for determining a stochastic transition",
   J. Math. Phys. 20 (1979) 1183-1201.
.. [MacKay] R. S. MacKay, "A renormalization approach to invariant circles in
   area-preserving maps", Physica D 7 (1983) 283-300 (K_c = 0.971635406).
.. [MMP] R. S. MacKay, J. D. Meiss, I. C. Percival, "Transport in Hamiltonian
   systems", Physica D 13 (1984) 55-81 (the flux through cantori and its
   exponent).
.. [Meiss] J. D. Meiss, "Symplectic maps, variational principles, and
   transport", Rev. Mod. Phys. 64 (1992) 795-848 (transport through cantori).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import validation as check
from ..codegen.cache import cached_njit
from ..codegen.compile_status import compiling
from ..model.pendulum import PendulumModel
from .model_checks import simple_pendulum_model

__all__ = [
    "FLUX_EXPONENT",
    "GREENE_K",
    "CrossingTimes",
    "TransportThreshold",
    "critical_step",
    "crossing_times",
    "first_crossings",
    "from_standard_map",
    "iterate",
    "residue",
    "residue_crossing",
    "stochasticity_parameter",
    "to_standard_map",
    "transport_threshold",
]

#: Greene's critical value: the last invariant circle (golden-mean rotation number) breaks.
GREENE_K = 0.971635406
#: MacKay, Meiss and Percival's exponent: the flux through the golden cantorus ~ (K - K_c)^eta.
FLUX_EXPONENT = 3.01


def stochasticity_parameter(model: PendulumModel, h: float) -> float:
    """``K = (g / l) h^2``: the standard map that symplectic Euler with step ``h`` is.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> round(stochasticity_parameter(pl.simple_pendulum(length=1.0, g=9.81), 0.1), 6)
    0.0981
    """
    model = simple_pendulum_model(model)
    h = check.positive_number("h", h)
    return model.g / model.lengths[0] * h**2


def critical_step(model: PendulumModel, k: float = GREENE_K) -> float:
    """The step ``h = sqrt(K l / g)`` at which symplectic Euler's standard map has parameter ``k``.

    With ``k = GREENE_K`` this is the step beyond which the pendulum's
    numerical orbits have no invariant circle left.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> round(critical_step(pl.simple_pendulum(length=1.0, g=9.81)), 4)
    0.3147
    """
    model = simple_pendulum_model(model)
    k = check.positive_number("k", k)
    return float(np.sqrt(k * model.lengths[0] / model.g))


def to_standard_map(model: PendulumModel, theta, p, h: float):
    """``(phi, I) = (theta + pi, h p / (m l^2))``: pendulum state to standard-map state."""
    model = simple_pendulum_model(model)
    h = check.positive_number("h", h)
    inertia = model.masses[0] * model.lengths[0] ** 2
    return np.asarray(theta, float) + np.pi, h * np.asarray(p, float) / inertia


def from_standard_map(model: PendulumModel, phi, action, h: float):
    """The inverse of :func:`to_standard_map`: ``(theta, p)``."""
    model = simple_pendulum_model(model)
    h = check.positive_number("h", h)
    inertia = model.masses[0] * model.lengths[0] ** 2
    return np.asarray(phi, float) - np.pi, inertia * np.asarray(action, float) / h


def iterate(phi, action, k: float, iterations: int, wrap: bool = True):
    """Orbits of the standard map ``I1 = I + K sin(phi)``, ``phi1 = phi + I1``.

    Parameters
    ----------
    phi, action : array_like, same shape
        Initial angles and actions (any shape: many orbits at once).
    k : float
        ``K >= 0``.
    iterations : int
    wrap : bool
        Reduce ``phi`` to ``[0, 2 pi)`` (``I`` is never reduced).

    Returns
    -------
    phi, action : ndarray, shape (iterations + 1, ...)
        The starting shape after the iteration axis.

    Examples
    --------
    >>> phi, action = iterate([1.0], [0.5], 0.0, 2)
    >>> action[:, 0].tolist(), phi[:, 0].tolist()
    ([0.5, 0.5, 0.5], [1.0, 1.5, 2.0])
    """
    k = check.real_number("k", k)
    if k < 0:
        raise ValueError(f"`k` must be >= 0, got {k}")
    iterations = check.integer_at_least("iterations", iterations, 0)
    phi, action = np.asarray(phi, float), np.asarray(action, float)
    try:
        phi, action = np.broadcast_arrays(phi, action)
    except ValueError:
        raise ValueError(f"`phi` and `action` must have the same shape (or broadcast), got "
                         f"{phi.shape} and {action.shape}") from None
    phis = np.empty((iterations + 1, *phi.shape))
    actions = np.empty_like(phis)
    phis[0], actions[0] = phi, action
    for i in range(iterations):
        actions[i + 1] = actions[i] + k * np.sin(phis[i])
        phis[i + 1] = phis[i] + actions[i + 1]
        if wrap:
            phis[i + 1] %= 2 * np.pi
    return phis, actions


@cached_njit
def _first_crossings(ks, phis, actions, limit):
    out = np.full((ks.size, phis.size), -1, dtype=np.int64)
    period = 2.0 * np.pi
    for a in range(ks.size):
        k = ks[a]
        for b in range(phis.size):
            phi, action, start = phis[b], actions[b], actions[b]
            for step in range(1, limit + 1):
                action += k * np.sin(phi)
                phi += action
                if abs(action - start) >= period:
                    out[a, b] = step
                    break
    return out


def first_crossings(ks, phi0, action0, max_iterations: int) -> np.ndarray:
    """First iteration at which each orbit's ``I`` has moved by a full period ``2 pi``.

    Parameters
    ----------
    ks : array_like, shape (a,)
        Map parameters.
    phi0, action0 : array_like, shape (b,)
        Initial states.
    max_iterations : int

    Returns
    -------
    ndarray of int, shape (a, b)
        ``-1`` for an orbit that did not cross within ``max_iterations``.
    """
    ks = np.ascontiguousarray(np.atleast_1d(np.asarray(ks, float)))
    if ks.ndim != 1:
        raise ValueError(f"`ks` must be a number or a 1-d array, got shape {ks.shape}")
    phi0, action0 = (np.ascontiguousarray(np.atleast_1d(np.asarray(x, float)))
                     for x in (phi0, action0))
    if phi0.shape != action0.shape or phi0.ndim != 1:
        raise ValueError(f"`phi0` and `action0` must be 1-d of the same length, got "
                         f"{phi0.shape} and {action0.shape}")
    if np.any(ks < 0) or not np.all(np.isfinite(ks)):
        raise ValueError("`ks` must be finite and >= 0")
    max_iterations = check.integer_at_least("max_iterations", max_iterations, 1)
    if _first_crossings.signatures:
        return _first_crossings(ks, phi0, action0, max_iterations)
    # The first call in a process compiles the loop (or loads it from Numba's cache): say so.
    with compiling("the standard map's crossing counter"):
        return _first_crossings(ks, phi0, action0, max_iterations)


@dataclass(frozen=True)
class CrossingTimes:
    """First-crossing times of an ensemble of standard-map orbits, against ``K - K_c``.

    Attributes
    ----------
    excess : ndarray, shape (a,)
        ``K - K_c`` for each row.
    times : ndarray of int, shape (a, orbits)
        First iteration at which ``I`` has moved by ``2 pi`` (``-1``: not
        within ``max_iterations``).
    max_iterations : int
    median : ndarray, shape (a,)
        Median crossing time over all orbits (``nan`` when half of them or
        more did not cross in time: the median is then not known).
    half_medians : ndarray, shape (a, 2)
        The medians of the two halves of the ensemble (alternate orbits):
        they agree within the sampling error, about ``1 / sqrt(orbits)``.
    fastest, half_fastest : ndarray, shape (a,) and (a, 2)
        The fewest iterations any orbit of the ensemble (of each half)
        needed: this drifts with the number of orbits.
    slope : float
        Least-squares slope of ``log median`` against ``log (K - K_c)``
        over the rows with a known median; MMP's law: ``-FLUX_EXPONENT``.
    """

    excess: np.ndarray
    times: np.ndarray
    max_iterations: int
    median: np.ndarray
    half_medians: np.ndarray
    fastest: np.ndarray
    half_fastest: np.ndarray
    slope: float

    @property
    def orbits(self) -> int:
        """Orbits per ``K``."""
        return self.times.shape[1]


def _median(times: np.ndarray) -> np.ndarray:
    """Row medians with non-crossings (``-1``) counted as later than any crossing."""
    later = np.where(times < 0, np.inf, times.astype(float))
    median = np.median(later, axis=-1)
    return np.where(np.isfinite(median), median, np.nan)


def _fastest(times: np.ndarray) -> np.ndarray:
    later = np.where(times < 0, np.inf, times.astype(float))
    fastest = later.min(axis=-1)
    return np.where(np.isfinite(fastest), fastest, np.nan)


def crossing_times(excess, *, orbits: int = 256,
                   max_iterations: int = 2_000_000) -> CrossingTimes:
    """Median first-crossing time of ``I`` through a period ``2 pi`` at ``K = K_c + excess``.

    The orbits start at ``I = 0`` with ``phi`` geometrically spaced over
    ``10^-3 .. 10^-1``: next to the hyperbolic fixed point ``(0, 0)``, inside
    its chaotic layer. The median of a few hundred crossing times is a
    property of the map at ``K``, known to about ``1 / sqrt(orbits)``; the
    fastest orbit's time is not (it falls as orbits are added).

    Parameters
    ----------
    excess : array_like, shape (a,)
        ``K - K_c > 0``.
    orbits : int
        Orbits per ``K``, even, ``>= 16``.
    max_iterations : int
        The longest run; a row's median is known when more than half of its
        orbits crossed within it.

    Returns
    -------
    CrossingTimes

    References
    ----------
    MMP; Meiss; Chirikov.

    Examples
    --------
    >>> result = crossing_times([0.5, 1.0], orbits=16, max_iterations=10**5)
    >>> bool(result.median[1] < result.median[0])   # farther above K_c: quicker
    True
    """
    excess = np.atleast_1d(np.asarray(excess, float))
    if excess.ndim != 1 or not np.all(np.isfinite(excess)) or np.any(excess <= 0):
        raise ValueError(f"`excess` (K - K_c) must be a 1-d array of positive numbers, got "
                         f"{excess}")
    orbits = check.integer_at_least("orbits", orbits, 16)
    if orbits % 2:
        raise ValueError(f"`orbits` must be even (two halves are compared), got {orbits}")
    max_iterations = check.integer_at_least("max_iterations", max_iterations, 1)
    phi0 = np.geomspace(1e-3, 1e-1, orbits)
    times = first_crossings(GREENE_K + excess, phi0, np.zeros(orbits), max_iterations)
    halves = (times[:, 0::2], times[:, 1::2])
    median = _median(times)
    known = np.isfinite(median)
    slope = (float(np.polyfit(np.log(excess[known]), np.log(median[known]), 1)[0])
             if known.sum() >= 2 else np.nan)
    return CrossingTimes(excess, times, max_iterations, median,
                         np.stack([_median(x) for x in halves], axis=-1), _fastest(times),
                         np.stack([_fastest(x) for x in halves], axis=-1), slope)


@dataclass(frozen=True)
class TransportThreshold:
    """Finite-time threshold of global transport in the standard map, read off the fastest orbit.

    The threshold depends on how many orbits are started (the fastest of more
    orbits crosses sooner); :class:`CrossingTimes` has a statistic that does not.

    Attributes
    ----------
    ks : ndarray, shape (a,)
        The grid of ``K`` scanned.
    crossing : ndarray, shape (a,)
        Fewest iterations any orbit of the ensemble needed to cross ``2 pi``
        in ``I`` at each ``K`` (``-1``: none within the longest run).
    iterations : ndarray, shape (r,)
        Run lengths asked about.
    thresholds : ndarray, shape (r,)
        For each run length ``N``: the smallest grid ``K`` from which on every
        larger grid ``K`` sees a crossing within ``N`` iterations.
    orbits : int
        Orbits per ``K``.
    """

    ks: np.ndarray
    crossing: np.ndarray
    iterations: np.ndarray
    thresholds: np.ndarray
    orbits: int

    @property
    def excess(self) -> np.ndarray:
        """``threshold / K_c - 1`` per run length."""
        return self.thresholds / GREENE_K - 1


def transport_threshold(iterations=(100, 1000, 10_000, 100_000), *, ks=None,
                        orbits: int = 16) -> TransportThreshold:
    """Find, for each run length, the ``K`` above which some orbit crosses a period of ``I``.

    A statistic of the ensemble's fastest orbit: it falls as ``orbits`` grows,
    so it measures the ensemble as much as the map. :func:`crossing_times`
    gives the median crossing time, which does not drift with the number of
    orbits.

    The orbits start in the chaotic layer of the main resonance, next to its
    hyperbolic fixed point ``(phi, I) = (0, 0)`` (``phi = 10^-3 .. 10^-1``),
    which is where a crossing is quickest wherever one is possible.

    Parameters
    ----------
    iterations : sequence of int
        Run lengths ``N``.
    ks : array_like, optional
        Increasing grid of ``K``; by default ``0.90 .. 2.0`` in steps of 0.005.
    orbits : int
        Orbits per ``K``, ``>= 1``.

    Returns
    -------
    TransportThreshold
    """
    if isinstance(iterations, str) or not np.iterable(iterations) or len(iterations) == 0:
        raise TypeError(f"`iterations` must be a non-empty sequence of run lengths (integers "
                        f">= 1), got {iterations!r}")
    iterations = np.array([check.integer_at_least("iterations", n, 1) for n in iterations])
    ks = np.arange(0.90, 2.0 + 1e-9, 0.005) if ks is None else np.asarray(ks, float)
    if ks.ndim != 1 or ks.size < 2 or np.any(np.diff(ks) <= 0):
        raise ValueError("`ks` must be an increasing 1-d grid of at least two values")
    orbits = check.integer_at_least("orbits", orbits, 1)
    phi0 = np.geomspace(1e-3, 1e-1, orbits)
    steps = first_crossings(ks, phi0, np.zeros(orbits), int(iterations.max()))
    fastest = np.where(steps < 0, np.iinfo(np.int64).max, steps).min(axis=1)
    crossing = np.where(fastest == np.iinfo(np.int64).max, -1, fastest)
    thresholds = []
    for n in iterations:
        fails = np.flatnonzero((crossing < 0) | (crossing > n))
        if fails.size == 0:
            thresholds.append(ks[0])
        elif fails[-1] == ks.size - 1:
            thresholds.append(np.nan)  # not even the largest K crossed in time
        else:
            thresholds.append(ks[fails[-1] + 1])
    return TransportThreshold(ks, crossing, iterations, np.array(thresholds), orbits)


# ---------------------------------------------------------------- Greene's residues
#: Largest step of ``K`` in continuing a periodic orbit from ``K = 0``.
_CONTINUATION_STEP = 0.0025


def _orbit_tangent(phi: float, action: float, k: float, iterations: int):
    """``iterations`` steps of the map from ``(phi, I)`` and the product of their Jacobians.

    The Jacobian of one step in ``(phi, I)`` is ``[[1 + c, 1], [c, 1]]``, ``c = K cos(phi)``.
    """
    a, b, c, d = 1.0, 0.0, 0.0, 1.0
    for _ in range(iterations):
        kc = k * math.cos(phi)
        action += k * math.sin(phi)
        phi += action
        a, b, c, d = (1 + kc) * a + c, (1 + kc) * b + d, kc * a + c, kc * b + d
    return phi, action, ((a, b), (c, d))


def _symmetry_gap(action0: float, k: float, p: int, q: int):
    """How far the orbit from ``(pi, I0)`` misses its symmetry line, and its slope in ``I0``.

    The map ``T = R2 R1`` is the product of the involutions
    ``R1(phi, I) = (-phi, I + K sin phi)`` (fixed on ``phi = 0, pi``) and
    ``R2(phi, I) = (I - phi, I)`` (fixed on ``phi = I / 2``). An orbit from
    ``phi = pi`` that reaches ``Fix(R1)`` after ``q / 2`` steps (``q`` even)
    or ``Fix(R2)`` after ``(q + 1) / 2`` (``q`` odd) has period ``q``; the
    lifted targets ``pi (1 + p)`` are those of ``K = 0``.
    """
    half = (q + 1) // 2
    phi, action, ((_, dphi), (_, daction)) = _orbit_tangent(math.pi, action0, k, half)
    if q % 2:
        return phi - action / 2 - math.pi * (1 + p), dphi - daction / 2
    return phi - math.pi * (1 + p), dphi


def _symmetric_action(k: float, p: int, q: int, guess: float) -> float | None:
    """Newton's method on the symmetry condition for the initial action ``I0``.

    None unless it converges to an orbit that closes with rotation number ``p / q``.
    """
    action = guess
    for _ in range(50):
        gap, slope = _symmetry_gap(action, k, p, q)
        step = gap / slope
        action -= step
        if not math.isfinite(action):
            return None
        if abs(step) <= 1e-14 * max(1.0, abs(action)):
            phi, end, _ = _orbit_tangent(math.pi, action, k, q)
            closes = abs(phi - math.pi - 2 * math.pi * p) < 1e-8 and abs(end - action) < 1e-8
            return action if closes else None
    return None


def _continued_action(k: float, p: int, q: int, start: tuple | None = None) -> float:
    """``I0`` of the symmetric ``p/q`` orbit through ``phi = pi``, continued from ``K = 0``.

    ``start = (K, I0)`` continues from a known orbit instead. A step of ``K``
    after which Newton's method fails, or finds an orbit that does not close
    with rotation number ``p / q``, is halved (down to ``1e-7``).
    """
    here, action = start if start is not None else (0.0, 2 * math.pi * p / q)
    step = _CONTINUATION_STEP
    while here != k:
        ahead = here + max(-step, min(step, k - here))
        found = _symmetric_action(ahead, p, q, action)
        if found is None:
            step /= 2
            if step < 1e-7:
                raise RuntimeError(f"the symmetric orbit of rotation number {p}/{q} could not "
                                   f"be continued beyond K = {here:.8g}")
            continue
        here, action = ahead, found
        step = min(2 * step, _CONTINUATION_STEP)
    return action


def _rotation(p, q) -> tuple[int, int]:
    p = check.integer_at_least("p", p, 0)
    q = check.integer_at_least("q", q, 1)
    if math.gcd(p, q) != 1:
        raise ValueError(f"`p` / `q` must be in lowest terms, got {p}/{q}")
    return p, q


def residue(k: float, p: int, q: int) -> float:
    """Greene's residue of the symmetric periodic orbit of rotation number ``p / q``.

    The orbit is the one through the symmetry line ``phi = pi`` (the
    pendulum's hanging position; elliptic for small ``K``), continued in
    ``K`` from the orbit of ``K = 0`` (``I = 2 pi p / q``). With ``M`` the
    product of the ``q`` Jacobians along it, ``R = (2 - tr M) / 4``: the
    orbit is elliptic for ``0 < R < 1``, hyperbolic for ``R < 0`` or ``R > 1``.

    Parameters
    ----------
    k : float
        ``K >= 0``.
    p, q : int
        Rotation number ``p / q`` in lowest terms (``I`` advances ``2 pi p``
        in ``q`` steps).

    Returns
    -------
    float

    References
    ----------
    J. M. Greene, J. Math. Phys. 20 (1979) 1183-1201.

    Examples
    --------
    >>> round(residue(0.5, 0, 1), 12)  # the fixed point at phi = pi: R = K / 4
    0.125
    """
    k = check.real_number("k", k)
    if k < 0:
        raise ValueError(f"`k` must be >= 0, got {k}")
    p, q = _rotation(p, q)
    action = _continued_action(k, p, q)
    _, _, ((a, _), (_, d)) = _orbit_tangent(math.pi, action, k, q)
    return (2 - (a + d)) / 4


def residue_crossing(p: int, q: int, level: float = 0.25, bracket=(0.9, 1.1),
                     xtol: float = 1e-13) -> float:
    """The ``K`` in ``bracket`` where the residue of the ``p/q`` orbit first reaches ``level``.

    The orbit is continued from ``K = 0`` to ``bracket[0]``, then in steps of
    ``K`` until the residue passes ``level``; Brent's method narrows the
    step. For the golden mean's approximants ``F_(j-1) / F_j`` with
    ``level = 1/4`` these values converge to Greene's ``K_c``, from
    alternate sides.

    Parameters
    ----------
    p, q : int
    level : float
    bracket : (float, float)
        ``0 <= K_low < K_high``.
    xtol : float

    Returns
    -------
    float

    Raises
    ------
    ValueError
        If the residue does not reach ``level`` inside ``bracket``.

    Examples
    --------
    >>> round(residue_crossing(1, 1, bracket=(0.5, 1.5)), 10)  # 1/1: R = K / 4
    1.0
    """
    from scipy.optimize import brentq

    p, q = _rotation(p, q)
    level = check.real_number("level", level)
    low, high = (check.real_number("bracket", b) for b in bracket)
    if not 0 <= low < high:
        raise ValueError(f"`bracket` must be (K_low, K_high) with 0 <= K_low < K_high, "
                         f"got {bracket!r}")
    known = {low: _continued_action(low, p, q)}

    def excess(k):
        near = min(known, key=lambda kk: abs(kk - k))
        known[k] = _continued_action(k, p, q, (near, known[near]))
        _, _, ((a, _), (_, d)) = _orbit_tangent(math.pi, known[k], k, q)
        return (2 - (a + d)) / 4 - level

    a, fa = low, excess(low)
    while True:
        b = min(a + 0.002, high)
        fb = excess(b)
        if fa * fb <= 0:
            return float(brentq(excess, a, b, xtol=xtol))
        if b == high:
            raise ValueError(f"the residue of the {p}/{q} orbit does not reach {level:g} for K in "
                             f"{bracket!r}")
        a, fa = b, fb

