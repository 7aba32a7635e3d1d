"""Angles modulo a full turn."""

from __future__ import annotations

import math

import mpmath
import numpy as np

__all__ = ["reduce_turns", "wrap_angle"]


def wrap_angle(theta):
    """Angles mapped into ``(-pi, pi]``.

    Examples
    --------
    >>> wrap_angle([3 * np.pi / 2, -np.pi]).round(6).tolist()
    [-1.570796, 3.141593]
    """
    wrapped = np.mod(np.asarray(theta, dtype=float) + np.pi, 2 * np.pi) - np.pi
    return np.where(wrapped == -np.pi, np.pi, wrapped)


def _reduced(x: float) -> float:
    """``x - 2 pi k`` in ``[-pi, pi]`` for the nearest whole ``k``, rounded once."""
    # Every bit of x counts (it is an exact binary number), so 2 pi carries as many bits as
    # x has before its binary point, and 64 more for the angle left over.
    with mpmath.workprec(max(math.frexp(x)[1], 0) + 64 + 53):
        value, turn = mpmath.mpf(x), 2 * mpmath.pi
        return float(value - turn * mpmath.nint(value / turn))


def reduce_turns(theta) -> np.ndarray:
    """Angles less whole turns, in ``[-pi, pi]``, correct to the last bit even for huge angles.

    ``np.mod(theta, 2 * np.pi)`` divides by the float nearest to ``2 pi``, which is
    ``2.4e-16`` short of it, so its error grows with the number of turns taken off: 0.02 rad
    at ``theta = 1e15``. Here the turns are taken off in exact arithmetic (mpmath, with as many
    bits of pi as ``theta`` needs) and the result is rounded once. Meant for a few values (an
    initial state), not for every step of a run.

    Examples
    --------
    >>> float(reduce_turns(1e15)), float(np.mod(1e15 + np.pi, 2 * np.pi) - np.pi)
    (2.1096981170701126, 2.132087181805513)
    >>> bool(np.sin(reduce_turns(1e15)) == np.sin(1e15))  # the same angle on the circle
    True
    """
    values = np.asarray(theta, dtype=float)
    flat = [_reduced(float(x)) for x in values.reshape(-1)]
    return np.array(flat, dtype=float).reshape(values.shape)
