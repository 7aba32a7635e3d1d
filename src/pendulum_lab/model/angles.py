"""Angles modulo a full turn."""

from __future__ import annotations

import numpy as np

__all__ = ["wrap_angle"]


def wrap_angle(theta):
    """Angles mapped into ``(-pi, pi]``.

    Examples
    --------
    >>> wrap_angle([3 * np.pi / 2, -np.pi]).round(6).tolist()
    [-1.570796, 3.141593]
    """
    wrapped = np.mod(np.asarray(theta, dtype=float) + np.pi, 2 * np.pi) - np.pi
    return np.where(wrapped == -np.pi, np.pi, wrapped)
