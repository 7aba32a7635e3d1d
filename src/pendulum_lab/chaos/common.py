"""Helpers shared by the chaos measurements."""

from __future__ import annotations

import numpy as np

from ..driver.simulate import Trajectory
from ..model.angles import wrap_angle


def require_finite(traj: Trajectory, what: str) -> None:
    """A ``FloatingPointError`` if ``traj`` reached a non-finite state."""
    if not traj.completed:
        raise FloatingPointError(
            f"{what}: the trajectory became non-finite ({traj.method.name}, dt = {traj.dt:g}); "
            "use a smaller `dt`"
        )


def unit_direction(dim: int, seed) -> np.ndarray:
    """A reproducible random unit vector of length ``dim``."""
    u = np.random.default_rng(seed).standard_normal(dim)
    return u / np.linalg.norm(u)


def phase_distance(theta_a, p_a, theta_b, p_b, wrap: bool = False) -> np.ndarray:
    """Euclidean distance in ``(theta, p)``; with ``wrap`` angle differences are wrapped."""
    dtheta = np.asarray(theta_a) - np.asarray(theta_b)
    if wrap:
        dtheta = wrap_angle(dtheta)
    dp = np.asarray(p_a) - np.asarray(p_b)
    return np.sqrt(np.sum(dtheta**2, axis=-1) + np.sum(dp**2, axis=-1))


def scalar_or_array(x):
    """A float for a 0-d result, the array otherwise."""
    x = np.asarray(x)
    return float(x) if x.ndim == 0 else x
