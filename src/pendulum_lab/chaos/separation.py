"""Sensitivity to initial conditions: two trajectories that start close."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import validation as check
from ..driver.simulate import Trajectory, canonical_state, simulate
from ..model.pendulum import PendulumModel
from ..plot_dispatch import plot_with
from .common import phase_distance, unit_direction

__all__ = ["Separation", "perturbed", "separation", "separation_between"]


@dataclass(frozen=True)
class Separation:
    """Phase-space distance between a trajectory and a slightly perturbed copy.

    Attributes
    ----------
    t : ndarray, shape (S,)
    distance : ndarray, shape (S, ...)
        Euclidean distance in ``(theta, p)``, angle differences wrapped to
        ``(-pi, pi]`` (so it saturates at the size of the accessible region).
    delta : float
        Initial distance.
    trajectory : Trajectory or None
        Both runs, the reference first: ``theta`` of shape ``(S, 2, ..., n)``
        (None when built by :func:`separation_between` from two runs).
    """

    t: np.ndarray
    distance: np.ndarray
    delta: float
    trajectory: Trajectory | None

    def plot(self, ax=None, label=None, **kwargs):
        """Distance against time on a log scale; returns the Figure."""
        return plot_with("plot_separation", self, ax=ax, label=label, **kwargs)


def perturbed(theta, p, delta: float, seed) -> tuple[np.ndarray, np.ndarray]:
    """``(theta, p)`` moved by ``delta`` along a random unit direction fixed by ``seed``.

    The direction is one vector of length ``2n`` in ``(theta, p)``, the same
    for every state of a batch.
    """
    n = np.shape(theta)[-1]
    u = unit_direction(2 * n, seed)
    return theta + delta * u[:n], p + delta * u[n:]


def separation(
    model: PendulumModel,
    theta0,
    omega0=None,
    *,
    t_end: float,
    dt: float = 0.01,
    method="glrk4",
    save_every: int = 1,
    p0=None,
    delta: float = 1e-9,
    seed=0,
    progress: bool | None = None,
    t0: float = 0.0,
) -> Separation:
    """Distance versus time between two trajectories that start ``delta`` apart.

    The perturbation has length ``delta`` in ``(theta, p)`` along a random
    direction fixed by ``seed``. Both runs are one ensemble of two members.
    On a chaotic orbit the distance grows like ``delta exp(lambda t)`` (a
    straight line on a log scale, slope the largest Lyapunov exponent) until
    it saturates; on a regular orbit it grows at most linearly.

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0, p0 : array_like, shape (..., n)
        The initial state, as for :func:`~pendulum_lab.simulate`.
    t_end, dt, method, save_every, progress, t0
        As for :func:`~pendulum_lab.simulate`.
    delta : float
        Initial distance, ``> 0``.
    seed : int or None
        Seed of the perturbation direction.

    Returns
    -------
    Separation

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> sep = separation(pl.double_pendulum(), [2.0, 2.5], [0.0, 0.0], t_end=5.0,
    ...                  method="rk4")
    >>> bool(sep.distance[-1] > 100 * sep.delta)
    True
    """
    theta0, p0 = canonical_state(model, theta0, omega0, p0, t0=t0)
    delta = check.positive_number("delta", delta)
    theta1, p1 = perturbed(theta0, p0, delta, check.seed("seed", seed))
    traj = simulate(model, np.stack([theta0, theta1]), p0=np.stack([p0, p1]), t_end=t_end,
                    dt=dt, method=method, save_every=save_every, progress=progress, t0=t0)
    distance = phase_distance(
        traj.theta[:, 0], traj.p[:, 0], traj.theta[:, 1], traj.p[:, 1], wrap=True
    )
    return Separation(traj.t, distance, delta, traj)


def separation_between(a: Trajectory, b: Trajectory) -> Separation:
    """The distance between two computed runs, saved at the same times.

    The runs may differ in anything: the initial state (a perturbation of one
    unit in the last place), the step (``dt`` against ``dt / 2`` with
    ``save_every=2``), the method. Their distance shows what each difference
    does to the trajectory. On a chaotic orbit a difference made once (the
    start) grows at the orbit's exponential rate; a difference made every step
    (the step size, the method) is fed a new local error each step, so at first
    it grows faster, then at the same rate. The larger gap separates the runs
    first.

    Parameters
    ----------
    a, b : Trajectory
        Single trajectories of the same model with equal saved times.

    Returns
    -------
    Separation
        Distance in ``(theta, p)`` with angle differences wrapped, ``delta`` the
        distance at the first saved time.

    Examples
    --------
    >>> import numpy as np, pendulum_lab as pl
    >>> dp = pl.double_pendulum()
    >>> coarse = pl.simulate(dp, [2.0, 2.5], [0.0, 0.0], t_end=1.0, dt=0.01, method="rk4")
    >>> fine = pl.simulate(dp, [2.0, 2.5], [0.0, 0.0], t_end=1.0, dt=0.005, method="rk4",
    ...                    save_every=2)
    >>> sep = separation_between(coarse, fine)
    >>> sep.delta, bool(1e-7 < sep.distance[-1] < 1e-4)
    (0.0, True)
    """
    for name, traj in (("a", a), ("b", b)):
        if not isinstance(traj, Trajectory):
            raise TypeError(f"`{name}` must be a Trajectory, got {type(traj).__name__}")
        if traj.theta.ndim != 2:
            raise ValueError(f"`{name}` must be a single trajectory (angles of shape (N+1, n)), "
                             f"got angles of shape {traj.theta.shape}")
    if a.theta.shape != b.theta.shape or not np.allclose(a.t, b.t, rtol=0, atol=1e-9):
        raise ValueError(
            f"`a` and `b` must be saved at the same times, got {len(a.t)} times up to "
            f"{a.t[-1]:g} s and {len(b.t)} up to {b.t[-1]:g} s (thin the finer run with "
            "`save_every`)"
        )
    distance = phase_distance(a.theta, a.p, b.theta, b.p, wrap=True)
    return Separation(a.t, distance, float(distance[0]), None)
