"""Where the linearised motion about the hanging equilibrium and the full motion part."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import validation as check
from ..analysis.linearization import linearized_solution
from ..driver.simulate import simulate, velocity_state
from ..model.pendulum import PendulumModel
from ..plot_dispatch import plot_with
from .common import scalar_or_array

__all__ = ["SmallAngleComparison", "small_angle_comparison"]


@dataclass(frozen=True)
class SmallAngleComparison:
    """The linearised motion about the hanging equilibrium against the full motion.

    Attributes
    ----------
    t : ndarray, shape (S,)
    theta_full, theta_linear : ndarray, shape (S, ..., n)
    difference : ndarray, shape (S, ...)
        ``max_i |theta_full_i - theta_linear_i|`` [rad].
    parting_time : float or ndarray, shape (...)
        First time the difference exceeds the threshold (``inf`` if never).
    threshold : float
    relative : bool
        Whether ``threshold`` is a fraction of the largest linear angle.
    """

    t: np.ndarray
    theta_full: np.ndarray
    theta_linear: np.ndarray
    difference: np.ndarray
    parting_time: float | np.ndarray
    threshold: float
    relative: bool

    def plot(self, ax=None, member=()):
        """Both motions of one ensemble member (index ``member``); returns the Figure."""
        return plot_with("plot_small_angle", self, ax=ax, member=member)

    def plot_parting(self, amplitudes, ax=None):
        """Parting time against release amplitude (log-log) with a fitted power law.

        Parameters
        ----------
        amplitudes : array_like, shape like ``parting_time``
            The size of each member's release (for example its largest angle).

        Returns
        -------
        matplotlib.figure.Figure
        """
        return plot_with("plot_parting", self, amplitudes, ax=ax)


def small_angle_comparison(
    model: PendulumModel,
    theta0,
    omega0=None,
    *,
    t_end: float,
    dt: float = 0.01,
    method="glrk4",
    save_every: int = 1,
    p0=None,
    threshold: float = 0.05,
    relative: bool = False,
    progress: bool | None = None,
) -> SmallAngleComparison:
    """Where the linearised motion and the full nonlinear motion part.

    The linear motion about the all-down equilibrium is exact:
    :func:`pendulum_lab.analysis.linearized_solution` evaluates
    ``exp(A t) x0`` with the equilibrium's Jacobian ``A`` from
    ``model.chain.equilibria[0]``. The full motion comes from
    :func:`~pendulum_lab.simulate`. They "part" when the largest angle difference first
    exceeds ``threshold`` (in radians, or with ``relative=True`` as a
    fraction of the largest angle of the linear motion). The nonlinearity
    enters through terms of third order in the amplitude ``a``: it shifts the
    frequencies by an amount of order ``a^2``, so the difference grows like
    ``a^3 t`` and a relative threshold is crossed after a time of order
    ``a^-2``.

    Parameters
    ----------
    model : PendulumModel
        Meant for one or two links (the equilibria of longer chains are slow
        to derive).
    theta0, omega0, p0 : array_like, shape (..., n)
    t_end, dt, method, save_every, progress
        As for :func:`~pendulum_lab.simulate`.
    threshold : float
        Angle difference that counts as parting, ``> 0``.
    relative : bool
        Measure ``threshold`` as a fraction of ``max |theta_linear|`` (per
        ensemble member) instead of in radians.

    Returns
    -------
    SmallAngleComparison
    """
    theta0, omega0 = velocity_state(model, theta0, omega0, p0)
    threshold = check.positive_number("threshold", threshold)
    traj = simulate(model, theta0, omega0, t_end=t_end, dt=dt, method=method,
                    save_every=save_every, progress=progress)
    n, batch = model.n, theta0.shape[:-1]
    flat0, flatw = theta0.reshape(-1, n), omega0.reshape(-1, n)
    linear = np.stack(
        [linearized_solution(model, th, om, t=traj.t)[0] for th, om in zip(flat0, flatw)],
        axis=1,
    )
    linear = linear.reshape(len(traj.t), *batch, n)
    difference = np.max(np.abs(traj.theta - linear), axis=-1)
    limit = threshold * np.max(np.abs(linear), axis=(0, -1)) if relative else threshold
    apart = difference > limit
    parting = np.where(np.any(apart, axis=0), traj.t[np.argmax(apart, axis=0)], np.inf)
    return SmallAngleComparison(
        traj.t, traj.theta, linear, difference, scalar_or_array(parting), threshold, bool(relative)
    )
