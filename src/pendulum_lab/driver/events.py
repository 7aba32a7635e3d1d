"""Events: where a function of the state crosses zero, located apart from the solvers.

An event is a scalar function ``g`` of the state (an angle passing a value, an
arm passing over the top, later the phase of a periodic drive). The solvers
know nothing of events; as in SciPy's ``solve_ivp(events=...)`` and diffrax's
``Event``, locating one takes two steps on a computed trajectory:

1. **Detection** (:func:`find_crossings`): ``g`` sampled at consecutive saved
   steps changes sign, in the requested direction: upwards when
   ``g_k < 0 <= g_{k+1}``, downwards when ``g_k >= 0 > g_{k+1}``. With a
   ``period``, every level ``m * period`` counts (an angle passing ``value +
   2 pi m``).
2. **Location** inside the step: :meth:`Crossings.fraction` interpolates
   linearly, or, given the rates ``dg/dt`` at both ends, finds the root of the
   cubic Hermite interpolant (fourth-order accurate between steps).
3. **Landing** on the surface, in one of two ways:

   * :func:`land`: Newton's method on the length ``tau`` of one extra step
     of the integrator from the saved state before the crossing, started
     from the interpolated time. Every iterate is a genuine step of the
     integrator's flow in time; it needs the event's rate and a few steps.
   * Henon's trick [Henon]_, :func:`pendulum_lab.henon_step`, for an event
     that is a coordinate (an angle passing a value): that coordinate
     becomes the independent variable, and one step of the same integrator
     on the rescaled field goes exactly to the surface, without iteration.

   Both land on the surface to round-off, with an error of the integrator's
   local order; :func:`pendulum_lab.chaos.landing_errors` measures it.

:func:`hermite` is the cubic Hermite interpolant between two saved states,
written once: the root finder and the tangent propagators of
:func:`pendulum_lab.chaos.lyapunov_variational` both use it.

References
----------
.. [Henon] M. Henon, "On the numerical computation of Poincare maps",
   Physica D 5 (1982) 412-414.
.. [HNW] E. Hairer, S. P. Norsett, G. Wanner, *Solving Ordinary Differential
   Equations I*, 2nd ed., Springer 1993, sect. II.6 (dense output).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .. import validation as check

__all__ = ["Crossings", "check_direction", "find_crossings", "hermite", "hermite_slope", "land"]


def check_direction(direction, allow_both: bool = True) -> int:
    """``direction`` as an int: ``1`` (upwards), ``-1`` (downwards) or, if allowed, ``0`` (both)."""
    allowed = (1, -1, 0) if allow_both else (1, -1)
    return int(check.choice("direction", direction, allowed))


def hermite(s, y0, y1, d0, d1):
    """The cubic Hermite interpolant at ``s`` in ``[0, 1]``.

    Parameters
    ----------
    s : float or ndarray
        Position in the step, 0 at ``y0`` and 1 at ``y1``.
    y0, y1 : array_like
        Values at both ends.
    d0, d1 : array_like
        Derivatives at both ends with respect to ``s`` (the step length
        times the time derivative).

    Returns
    -------
    ndarray
        The broadcast shape of the arguments.

    Examples
    --------
    >>> import numpy as np
    >>> # exact for a cubic: y = s**3 has y(0) = 0, y(1) = 1, y'(0) = 0, y'(1) = 3
    >>> float(hermite(0.5, 0.0, 1.0, 0.0, 3.0))
    0.125
    """
    s2, s3 = s * s, s * s * s
    return (
        (2 * s3 - 3 * s2 + 1) * y0
        + (s3 - 2 * s2 + s) * d0
        + (-2 * s3 + 3 * s2) * y1
        + (s3 - s2) * d1
    )


def hermite_slope(s, y0, y1, d0, d1):
    """Derivative with respect to ``s`` of :func:`hermite`."""
    s2 = s * s
    return (
        (6 * s2 - 6 * s) * y0
        + (3 * s2 - 4 * s + 1) * d0
        + (-6 * s2 + 6 * s) * y1
        + (3 * s2 - 2 * s) * d1
    )


@dataclass(frozen=True)
class Crossings:
    """Steps over which an event function crossed a level.

    Attributes
    ----------
    step : ndarray of int, shape (C,)
        Index ``k`` of the saved step before the crossing (it lies between
        samples ``k`` and ``k + 1``).
    member : ndarray of int, shape (C,)
        Flat index of the ensemble member (0 for a single trajectory).
    level : ndarray, shape (C,)
        The level crossed: ``level``, or ``level + m * period``.
    before, after : ndarray, shape (C,)
        ``g`` at samples ``k`` and ``k + 1``, on either side of the level.
    """

    step: np.ndarray
    member: np.ndarray
    level: np.ndarray
    before: np.ndarray
    after: np.ndarray

    def __len__(self) -> int:
        return len(self.step)

    def fraction(self, rate_before=None, rate_after=None, iterations: int = 8) -> np.ndarray:
        """Where in its step each crossing lies, as a fraction in ``[0, 1]``.

        Without rates: linear interpolation between the two samples. With
        ``rate_before`` and ``rate_after`` (the derivatives of ``g`` with
        respect to the fraction, i.e. ``dt * dg/dt``, at both samples):
        Newton's method on the cubic Hermite interpolant, from the linear
        guess, kept inside the step.

        Returns
        -------
        ndarray, shape (C,)
        """
        if rate_before is None:
            return (self.level - self.before) / (self.after - self.before)
        f0, f1 = self.before - self.level, self.after - self.level
        s = np.clip(f0 / (f0 - f1), 0.0, 1.0)
        for _ in range(iterations):
            value = hermite(s, f0, f1, rate_before, rate_after)
            slope = hermite_slope(s, f0, f1, rate_before, rate_after)
            s = np.clip(s - value / np.where(slope == 0, 1.0, slope), 0.0, 1.0)
        return s

    def nearest(self) -> tuple[np.ndarray, np.ndarray]:
        """``(index, distance)``: the sample closer to the level, and ``|g - level|`` there."""
        before, after = np.abs(self.before - self.level), np.abs(self.after - self.level)
        later = after < before
        return self.step + later, np.where(later, after, before)

    def first(self) -> Crossings:
        """Only the first crossing of each member."""
        order = np.lexsort((self.step, self.member))
        member = self.member[order]
        keep = order[np.r_[True, member[1:] != member[:-1]]] if member.size else order
        return Crossings(self.step[keep], self.member[keep], self.level[keep],
                         self.before[keep], self.after[keep])


def find_crossings(values, direction: int = 0, *, level: float = 0.0,
                   period: float | None = None) -> Crossings:
    """Detect the steps over which ``g`` crosses ``level`` (or ``level + m * period``).

    Parameters
    ----------
    values : array_like, shape (L+1, ...)
        ``g`` at consecutive saved steps (time axis first); the trailing axes
        index ensemble members.
    direction : {1, -1, 0}
        ``1``: upwards (``g_k < level <= g_{k+1}``), ``-1``: downwards
        (``g_{k+1} < level <= g_k``), ``0``: both.
    level : float
        The value ``g`` crosses.
    period : float, optional
        Count every level ``level + m * period`` for integer ``m`` (an angle
        modulo ``2 pi``); a step that passes several counts once, at the
        highest.

    Returns
    -------
    Crossings
        Sorted by step, then member.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0.0, 2 * np.pi, 9)
    >>> hits = find_crossings(np.sin(t), direction=-1)
    >>> k = hits.step[0]
    >>> int(k), round(float(t[k] + hits.fraction()[0] * (t[k + 1] - t[k])), 6)
    (4, 3.141593)
    """
    direction = check_direction(direction)
    level = check.real_number("level", level)
    values = np.asarray(values, dtype=float)
    if values.ndim == 0 or values.shape[0] < 2:
        raise ValueError(f"`values` must hold at least two samples, got shape {values.shape}")
    flat = values.reshape(values.shape[0], -1)
    if period is None:
        up = (flat[:-1] < level) & (flat[1:] >= level)
        down = (flat[:-1] >= level) & (flat[1:] < level)
    else:
        period = check.positive_number("period", period)
        sheet = np.floor((flat - level) / period)
        up = sheet[1:] > sheet[:-1]
        down = sheet[1:] < sheet[:-1]
    hits = up if direction == 1 else down if direction == -1 else up | down
    step, member = np.nonzero(hits)
    if period is None:
        levels = np.full(step.size, level)
    else:
        levels = level + period * np.maximum(sheet[step, member], sheet[step + 1, member])
    return Crossings(step, member, levels, flat[step, member], flat[step + 1, member])


def land(
    advance: Callable[[float], tuple],
    miss: Callable[[tuple], float],
    rate: Callable[[tuple], float],
    tau: float,
    bounds: tuple[float, float],
    *,
    scale: float = 1.0,
    max_iterations: int = 12,
) -> tuple[float, tuple, float, int]:
    """Newton's method on the length ``tau`` of one extra step, until the event is met.

    ``advance(tau)`` returns the state one integrator step of length ``tau``
    after the saved state (the saved state itself, without a step, for
    ``tau = 0``), ``miss(state)``
    the event function there and ``rate(state)`` its time derivative. Each
    iterate is a genuine state of the integrator's numerical flow, so the
    landed state is as accurate as the integrator and lies on the surface to
    round-off. This is a root solve in time; Henon's trick, which changes the
    independent variable instead and needs one step, is
    :func:`pendulum_lab.henon_step`.

    Parameters
    ----------
    tau : float
        First guess (for example from :meth:`Crossings.fraction` times ``dt``).
    bounds : (float, float)
        Interval ``tau`` is kept in.
    scale : float
        Size of the level, for the stopping rule ``|miss| <= 4 eps max(1, scale)``.

    Returns
    -------
    (abs_miss, state, tau, steps)
        The best iterate: how far it lies from the surface, the state and the
        step length; and how many integrator steps the iteration took.
    """
    best = (np.inf, advance(0.0), 0.0)
    tolerance = 4 * np.finfo(float).eps * max(1.0, abs(scale))
    steps = 0
    for _ in range(max_iterations):
        state = advance(tau)
        steps += 1
        off = miss(state)
        if abs(off) < best[0]:
            best = (abs(off), state, tau)
        if abs(off) <= tolerance:
            break
        speed = rate(state)
        if speed == 0:
            break
        tau = float(np.clip(tau - off / speed, *bounds))
    return (*best, steps)
