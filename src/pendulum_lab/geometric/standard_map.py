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
In a finite run the crossing is seen only once ``K`` exceeds ``K_c`` by
enough, since the crossing time diverges as ``K -> K_c`` (Chirikov: roughly
like ``(K - K_c)^-3``); :func:`transport_threshold` measures that
finite-time threshold.

References
----------
.. [Chirikov] B. V. Chirikov, "A universal instability of many-dimensional
   oscillator systems", Physics Reports 52 (1979) 263-379.
.. [Greene] J. M. Greene, "A method for determining a stochastic transition",
   J. Math. Phys. 20 (1979) 1183-1201.
.. [MacKay] R. S. MacKay, "A renormalization approach to invariant circles in
   area-preserving maps", Physica D 7 (1983) 283-300 (K_c = 0.971635406).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from .. import validation as check
from ..model.pendulum import PendulumModel
from .model_checks import simple_pendulum_model

__all__ = [
    "GREENE_K",
    "TransportThreshold",
    "critical_step",
    "first_crossings",
    "from_standard_map",
    "iterate",
    "stochasticity_parameter",
    "to_standard_map",
    "transport_threshold",
]

#: Greene's critical value: the last invariant circle (golden-mean rotation number) breaks.
GREENE_K = 0.971635406



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


@numba.njit(cache=True)
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
    return _first_crossings(ks, phi0, action0, max_iterations)


@dataclass(frozen=True)
class TransportThreshold:
    """Finite-time threshold of global transport in the standard map.

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
    """Find, for each run length, the ``K`` above which orbits cross a period of ``I``.

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
