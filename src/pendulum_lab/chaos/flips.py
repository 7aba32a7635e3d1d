"""Heyl's flip-time fractal: how long until an arm of a double pendulum passes the top.

References
----------
.. [Heyl] J. S. Heyl, "The double pendulum fractal", 2008.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .. import validation as check
from ..driver.cluster import check_client, map_members, portable_method
from ..driver.events import find_crossings
from ..driver.segments import simulate_segments
from ..driver.simulate import progress_bar, step_count, time_grid
from ..integrators import get_method
from ..model import require_double_pendulum, require_model
from ..model.pendulum import PendulumModel
from ..plot_dispatch import plot_with
from .common import require_finite

__all__ = ["FlipMap", "can_flip", "flip_time_map", "flip_times"]

# Cells integrated as one ensemble. A segment holds at most
# segments.SEGMENT_FLOATS (2**21) floats, about 8 per cell and step here, so the
# more cells, the shorter the segments: the ~665,000 cells of a 1000 x 1000 map
# ran in segments of one step. Each segment costs NumPy work per cell besides
# its steps (its first state repeats the previous segment's last, the velocities
# and energies of its states, the copy of the cells still running), and arrays
# of tens of MB are mapped and page-faulted afresh by every segment. In blocks
# of 10,000 cells the segments have 26 steps, the work per cell is a small part
# of the map (docs/design/dask-ensembles.md), and the times are the same to the
# last bit.
BLOCK_CELLS = 10_000


def can_flip(model: PendulumModel, theta, omega=None) -> np.ndarray:
    """Whether energy allows any arm to pass over the top (``|theta_i| = pi``).

    With ``w_j = g l_j (m_j + ... + m_n)`` the potential energy is
    ``V = -sum_j w_j cos(theta_j)``. Arm ``i`` upside down (``theta_i = pi``)
    costs at least ``V_i = w_i - sum_{j != i} |w_j|`` (every other arm as low
    as it can be). Energy is conserved and kinetic energy is not negative, so
    if ``E < min_i V_i`` no arm can ever flip. For the double pendulum
    ``min_i V_i = -g |(m_1 + m_2) l_1 - m_2 l_2|``; released at rest with
    ``m = l = 1`` that reads ``2 cos(theta_1) + cos(theta_2) > 1`` for "cannot
    flip". (The often-quoted ``3 cos(theta_1) + cos(theta_2) > 2`` is the same
    bound for two uniform rods, whose centres of mass sit at mid-length.)

    Parameters
    ----------
    model : PendulumModel
    theta : array_like, shape (..., n)
    omega : array_like, shape (..., n), optional
        Angular velocities; at rest by default.

    Returns
    -------
    ndarray of bool, shape (...)
        True where the energy is at least the flipping threshold.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> dp = pl.double_pendulum()
    >>> can_flip(dp, [[0.5, 0.5], [2.0, 2.5]]).tolist()
    [False, True]
    """
    require_model(model)
    theta = check.state_array("theta", theta, model.n)
    omega = np.zeros_like(theta) if omega is None else check.state_array("omega", omega, model.n)
    energy = model.energy(theta, omega)
    return energy >= _flip_threshold(model)


def _flip_threshold(model) -> float:
    tail_mass = np.cumsum(np.asarray(model.masses)[::-1])[::-1]
    w = model.g * np.asarray(model.lengths) * tail_mass
    return float(np.min(w - (np.sum(np.abs(w)) - np.abs(w))))


@dataclass(frozen=True)
class FlipMap:
    """Time until either arm of a double pendulum released at rest flips over.

    Attributes
    ----------
    theta1 : ndarray, shape (N1,)
    theta2 : ndarray, shape (N2,)
        Grid of initial angles [rad]; exactly symmetric about 0.
    time : ndarray, shape (N2, N1)
        Flip time [s] (row = ``theta2``, column = ``theta1``); ``inf`` where no
        arm flipped before ``t_end`` or where energy forbids it.
    forbidden : ndarray of bool, shape (N2, N1)
        Cells that cannot flip on energy grounds (not simulated).
    t_end, dt : float
    method : str
    wall_time : float
    """

    theta1: np.ndarray
    theta2: np.ndarray
    time: np.ndarray
    forbidden: np.ndarray
    t_end: float
    dt: float
    method: str
    wall_time: float

    def plot(self, ax=None, colorbar: bool = True):
        """The map with a logarithmic colour scale; returns the Figure.

        Energy-forbidden cells are grey, cells that did not flip before
        ``t_end`` white.
        """
        return plot_with("plot_flip_map", self, ax=ax, colorbar=colorbar)


def _symmetric_grid(size: int, half_width: float) -> np.ndarray:
    """``size`` points on ``[-half_width, half_width]``, exactly symmetric about 0."""
    if size == 1:
        return np.zeros(1)
    return (2.0 * np.arange(size) - (size - 1)) * (half_width / (size - 1))


def flip_time_map(
    model: PendulumModel,
    size=20,
    *,
    t_end: float = 10.0,
    dt: float = 0.01,
    method="rk4",
    half_width: float = 3.0,
    progress: bool | None = None,
    client=None,
    chunk_size: int | None = None,
) -> FlipMap:
    """Heyl's flip-time map: time until either arm passes over the top.

    Every cell of a grid of initial angles ``(theta_1, theta_2)``, released at
    rest, is integrated until an arm flips (the unwrapped ``|theta_i|``
    reaches ``pi``; the time is interpolated linearly between steps) or until
    ``t_end``. Cells that cannot flip on energy grounds (:func:`can_flip`)
    are not simulated. The cells are integrated in blocks (``BLOCK_CELLS``),
    each block one ensemble run in segments; cells that have flipped leave
    the ensemble at the end of their segment.

    Parameters
    ----------
    model : PendulumModel
        A double pendulum.
    size : int or (int, int)
        Grid points along ``theta_1`` and ``theta_2``.
    t_end : float
        Time limit [s].
    dt : float
        Step size [s].
    method : str or Method
        Integrator; RK4 by default: over a few seconds its error is far below
        what the map can show, and it is the cheapest fourth-order method.
    half_width : float
        The grid covers ``[-half_width, half_width]^2``, ``0 < half_width < pi``.
    progress : bool, optional
    client : dask.distributed.Client, optional
        Integrate the cells on this Dask cluster, in chunks
        (:func:`pendulum_lab.driver.cluster.map_members`); the map is the same, bit
        for bit, as without it.
    chunk_size : int, optional
        Cells per chunk on a cluster (by default a few chunks per worker).

    Returns
    -------
    FlipMap

    Notes
    -----
    The equations are odd in ``(theta, p)``, so ``theta -> -theta`` maps a
    trajectory to its mirror image and the map is symmetric under a half
    turn of the grid; the grid is built to be exactly symmetric so this holds
    to round-off.

    References
    ----------
    J. S. Heyl, "The double pendulum fractal", 2008.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> fm = flip_time_map(pl.double_pendulum(), size=6, t_end=2.0)
    >>> fm.time.shape, bool(fm.forbidden[2:4, 2:4].all())
    ((6, 6), True)
    """
    require_double_pendulum(model)
    n1, n2 = (size, size) if np.ndim(size) == 0 else tuple(size)
    n1 = check.integer_at_least("size", n1, 1)
    n2 = check.integer_at_least("size", n2, 1)
    half_width = check.positive_number("half_width", half_width)
    if half_width >= np.pi:
        raise ValueError(
            f"`half_width` must be below pi (the grid starts below the top), got {half_width}"
        )
    t_end, dt, _ = time_grid(t_end, dt)
    theta1 = _symmetric_grid(n1, half_width)
    theta2 = _symmetric_grid(n2, half_width)
    grid = np.stack(np.meshgrid(theta1, theta2), axis=-1)
    forbidden = ~can_flip(model, grid)
    flip = np.full(forbidden.shape, np.inf)
    cells = np.flatnonzero(~forbidden)
    theta = grid.reshape(-1, 2)[cells]
    method = get_method(method)
    client = check_client(client)
    start = time.perf_counter()
    flip.flat[cells] = map_members(
        flip_times, (theta,), client=client, chunk_size=chunk_size, label="flip-time map",
        progress=progress,
        args=(model, t_end, dt, portable_method(method, client),
              progress if client is None else False))
    return FlipMap(
        theta1, theta2, flip, forbidden, t_end, dt, method.name, time.perf_counter() - start
    )


def flip_times(theta, model: PendulumModel, t_end: float, dt: float, method,
               progress: bool | None = None) -> np.ndarray:
    """Flip time of each state released at rest, ``inf`` if none before ``t_end``.

    The work of :func:`flip_time_map` on a batch of cells, here or on a Dask
    worker (:func:`pendulum_lab.driver.cluster.map_members`). The cells are
    integrated in blocks of at most ``BLOCK_CELLS``; each cell's time is the
    same in any block.

    Parameters
    ----------
    theta : ndarray, shape (K, 2)
    model, t_end, dt, method, progress
        As for :func:`flip_time_map` (validated there).

    Returns
    -------
    ndarray, shape (K,)
    """
    if len(theta) <= BLOCK_CELLS:
        return _block_flip_times(theta, model, t_end, dt, method, progress)
    flip = np.full(len(theta), np.inf)
    # One bar over the cells instead of one per block.
    bar = progress_bar(len(theta), len(theta) * step_count(t_end, dt), progress,
                       "flip-time map", unit="cell")
    try:
        for first in range(0, len(theta), BLOCK_CELLS):
            block = slice(first, first + BLOCK_CELLS)
            flip[block] = _block_flip_times(theta[block], model, t_end, dt, method, False)
            if bar is not None:
                bar.update(len(flip[block]))
    finally:
        if bar is not None:
            bar.close()
    return flip


def _block_flip_times(theta, model, t_end, dt, method, progress) -> np.ndarray:
    """:func:`flip_times` of one block of cells, integrated as one ensemble."""
    flip = np.full(len(theta), np.inf)
    if not len(theta):
        return flip
    run = simulate_segments(model, theta, np.zeros_like(theta), t_end=t_end, dt=dt,
                            method=method, progress=progress, label="flip-time map")
    first_step = 0
    for segment in run:
        require_finite(segment, "flip_time_map")
        # An arm flips when the larger |theta_i| passes pi (upwards).
        height = np.max(np.abs(segment.theta), axis=-1)
        flips = find_crossings(height, direction=1, level=np.pi).first()
        # Counted in steps from the start: segments end where the batch's size puts them,
        # and the time must not depend on that (a chunk of the batch gives the same).
        flip[run.members[flips.member]] = (first_step + flips.step + flips.fraction()) * dt
        first_step += len(segment.t) - 1
        # Cells that have flipped leave the ensemble.
        stay = np.ones(len(run.members), dtype=bool)
        stay[flips.member] = False
        run.keep(stay)
    return flip
