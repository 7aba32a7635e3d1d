"""The one place where :mod:`pendulum_lab.geometric` calls the core's run functions.

Single steps of a registered method, the finite-difference Jacobian of one
step, and the model check all go through here, so a change of their calling
conventions is adapted in this file and nowhere else. (Whole runs use
:func:`pendulum_lab.simulate` directly, always with keyword arguments after
the state.)
"""

from __future__ import annotations

import numpy as np

from ..analysis import step_jacobian
from ..model import check_model
from ..simulate import step

__all__ = ["check_model", "one_step", "one_step_jacobian"]


def one_step(model, method, theta, p, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """One step of ``method`` from ``(theta, p)`` (shape ``(..., n)``); returns ``(theta1, p1)``."""
    return step(model, method, theta, p, dt)


def one_step_jacobian(model, method, theta, p, dt: float) -> np.ndarray:
    """Jacobian of one step in ``(theta, p)`` by central differences, shape ``(2n, 2n)``."""
    return step_jacobian(model, method, np.asarray(theta, float), np.asarray(p, float), dt)
