"""The one place where this package calls :func:`pendulum_lab.step`.

Everything in :mod:`pendulum_lab.geometric` that needs a single step of a
registered method goes through :func:`one_step`, so a change of ``step``'s
calling convention is adapted here and nowhere else.
"""

from __future__ import annotations

import numpy as np

from ..simulate import step


def one_step(model, method, theta, p, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """One step of ``method`` from ``(theta, p)`` (shape ``(..., n)``); returns ``(theta1, p1)``."""
    return step(model, method, theta, p, dt)
