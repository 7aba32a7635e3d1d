"""Basins of attraction of a driven pendulum: which attractor each initial state ends on.

A damped, driven pendulum can have several attractors at the same
parameters (Baker and Gollub show two periodic ones side by side, with
interleaved, fractal basin boundaries [BG]_). Here a grid of initial states
``(theta0, omega0)`` is integrated as one ensemble, past a transient; each
member's stroboscopic orbit is given its period
(:func:`~pendulum_lab.chaos.orbit_periods`), and members whose orbits share
their points are put on the same attractor.

References
----------
.. [BG] G. L. Baker, J. P. Gollub, *Chaotic Dynamics: An Introduction*, 2nd
   ed., Cambridge University Press 1996, ch. 5 (basins of attraction).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .. import validation as check
from ..driver.cluster import check_client, map_members, members_of, portable_method
from ..driver.segments import default_segment_steps
from ..integrators import get_method
from ..model import require_model
from ..model.angles import wrap_angle
from ..model.pendulum import PendulumModel
from ..plot_dispatch import plot_with
from .stroboscopic import PERIOD_TOLERANCE, drive_period, orbit_periods, stroboscopic_section

__all__ = ["Basins", "basin_samples", "basins_of_attraction"]


@dataclass(frozen=True)
class Basins:
    """Which attractor each initial state of a grid ends on.

    Attributes
    ----------
    theta0, omega0 : ndarray, shapes (A,) and (W,)
        The grid's initial angles [rad] and angular velocities [rad/s].
    label : ndarray of int, shape (W, A)
        ``label[j, i]`` is the index of the attractor the start
        ``(theta0[i], omega0[j])`` ends on, or -1 if its orbit has no period
        up to ``max_period`` (chaotic, longer, or not settled).
    attractors : tuple of ndarray, each shape (p, 2)
        Each attractor's stroboscopic points ``(theta, omega)``, ``p`` its period.
    turns : tuple of float
        Each attractor's mean full turns per drive period (0: it oscillates;
        +-1: it goes over the top once per period, one way or the other).
    tolerance : float
        Two samples closer than this (max-norm) are the same point.
    transient_periods, max_period : int
    method : str
    wall_time : float
    """

    theta0: np.ndarray
    omega0: np.ndarray
    label: np.ndarray
    attractors: tuple
    turns: tuple
    tolerance: float
    transient_periods: int
    max_period: int
    method: str
    wall_time: float

    @property
    def periods(self) -> tuple[int, ...]:
        """The period of each attractor."""
        return tuple(len(points) for points in self.attractors)

    @property
    def fractions(self) -> np.ndarray:
        """Share of the grid in each basin, shape ``(len(attractors),)``."""
        return np.array([np.mean(self.label == k) for k in range(len(self.attractors))])

    def plot(self, ax=None, **kwargs):
        """The basins in the ``(theta0, omega0)`` plane with the attractors' points."""
        return plot_with("plot_basins", self, ax=ax, **kwargs)


def basins_of_attraction(
    model: PendulumModel,
    theta0,
    omega0,
    *,
    transient_periods: int = 100,
    steps_per_period: int = 100,
    method="rk4",
    tolerance: float = PERIOD_TOLERANCE,
    max_period: int = 8,
    progress: bool | None = None,
    client=None,
    chunk_size: int | None = None,
) -> Basins:
    """Label every initial state of a grid by the attractor it ends on.

    Parameters
    ----------
    model : PendulumModel
        A driven model with one link.
    theta0, omega0 : array_like, shapes (A,) and (W,)
        The grid's axes: initial angles [rad] and angular velocities [rad/s].
    transient_periods, steps_per_period, method, progress
        As for :func:`~pendulum_lab.chaos.stroboscopic_section`; after the
        transient, ``2 max_period`` periods are sampled.
    tolerance, max_period
        Of the period detection (:func:`~pendulum_lab.chaos.orbit_periods`);
        a member joins an attractor when its last sample lies within
        ``tolerance`` of one of the attractor's points.
    client : dask.distributed.Client, optional
        Integrate the grid's starts on this Dask cluster, in chunks
        (:func:`pendulum_lab.driver.cluster.map_members`); the basins are the same,
        bit for bit, as without it.
    chunk_size : int, optional
        Starts per chunk on a cluster (by default a few chunks per worker).

    Returns
    -------
    Basins

    Examples
    --------
    >>> import numpy as np, pendulum_lab as pl
    >>> basins = basins_of_attraction(pl.driven_pendulum(drive_amplitude=0.9),
    ...                               np.linspace(-1, 1, 3), [0.0], transient_periods=100,
    ...                               steps_per_period=50)
    >>> basins.periods, basins.label.tolist()  # one period-1 attractor takes them all
    ((1,), [[0, 0, 0]])
    """
    require_model(model)
    if model.n != 1:
        raise ValueError(f"`model` must have one link (basins are drawn in its (theta, omega) "
                         f"plane), got n = {model.n}")
    axes = [check.real_sequence("theta0", theta0), check.real_sequence("omega0", omega0)]
    tolerance = check.positive_number("tolerance", tolerance)
    max_period = check.integer_at_least("max_period", max_period, 1)
    transient_periods = check.integer_at_least("transient_periods", transient_periods, 0)
    steps_per_period = check.integer_at_least("steps_per_period", steps_per_period, 1)
    drive_period(model)  # refuse an undriven model here, not on a worker
    theta_grid, omega_grid = np.meshgrid(*axes)  # shape (W, A)
    method = get_method(method)
    client = check_client(client)
    # The segments of the whole grid, for every chunk of it (see default_segment_steps).
    segment_steps = default_segment_steps(1, theta_grid.size,
                                          (transient_periods + 2 * max_period) * steps_per_period,
                                          steps_per_period)
    start = time.perf_counter()
    samples = map_members(
        basin_samples, (theta_grid.reshape(-1, 1), omega_grid.reshape(-1, 1),
                        np.arange(theta_grid.size)),
        client=client, chunk_size=chunk_size, label="basins", progress=progress,
        args=(model.for_ensemble(theta_grid.shape), 2 * max_period, transient_periods,
              steps_per_period, portable_method(method, client), segment_steps,
              progress if client is None else False))
    # Back to the section's layout: samples first, then the grid, shape (S, W, A, 1).
    section_theta, section_omega = (np.moveaxis(a, 0, 1).reshape(-1, *theta_grid.shape, 1)
                                    for a in samples[:2])
    section_turns = samples[2].reshape(*theta_grid.shape, 1)
    theta, omega = section_theta[..., 0], section_omega[..., 0]
    periods = orbit_periods(section_theta, section_omega, tolerance, max_period)
    label = np.full(periods.shape, -1)
    attractors, turns = [], []
    pending = periods > 0
    while np.any(pending):
        first = tuple(np.argwhere(pending)[0])
        p = periods[first]
        points = np.stack([theta[-p:][(slice(None), *first)], omega[-p:][(slice(None), *first)]],
                          axis=-1)
        gap = np.maximum(np.abs(wrap_angle(theta[-1][..., None] - points[:, 0])),
                         np.abs(omega[-1][..., None] - points[:, 1])).min(axis=-1)
        joins = pending & (periods == p) & (gap < tolerance)
        label[joins] = len(attractors)
        pending &= ~joins
        attractors.append(points)
        turns.append(float(np.round(section_turns[(*first, 0)], 6)) + 0.0)
    return Basins(axes[0], axes[1], label, tuple(attractors), tuple(turns), tolerance,
                  transient_periods, max_period, method.name, time.perf_counter() - start)


def basin_samples(theta0, omega0, rows, model: PendulumModel, n_periods: int,
                  transient_periods: int, steps_per_period: int, method, segment_steps: int,
                  progress: bool | None = None) -> tuple:
    """The stroboscopic samples of the starts ``rows`` of a basins grid.

    The work of :func:`basins_of_attraction` (arguments validated there) on
    starts ``theta0, omega0`` of shape ``(K, 1)``, rows ``rows`` of the
    flattened grid (a family's members are taken there), here or on a Dask
    worker (:func:`pendulum_lab.driver.cluster.map_members`).

    Returns
    -------
    theta, omega : ndarray, shape (K, S, 1)
        Wrapped angles and velocities, the starts first.
    turns : ndarray, shape (K, 1)
    """
    section = stroboscopic_section(
        members_of(model, rows), theta0, omega0, n_periods=n_periods,
        transient_periods=transient_periods, steps_per_period=steps_per_period, method=method,
        progress=progress, segment_steps=segment_steps,
    )
    return np.moveaxis(section.theta, 1, 0), np.moveaxis(section.omega, 1, 0), section.turns
