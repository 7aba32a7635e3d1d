"""The picture of a model's configuration: its points, rods and springs, in metres.

Every drawing of the package (:func:`~pendulum_lab.plotting.draw_pendulum`, the scene of the
animations and of the simulators) draws from a model's
:class:`~pendulum_lab.model.Drawing` and ``model.positions(theta, t)``: a chain is points
joined by rods, the first to the fixed pivot; the elastic pendulum is a point on a spring;
the Kapitza pendulum a rod from a shaking, massless pivot. The functions here turn one
configuration into the line data of matplotlib's ``Line2D`` (paths broken by NaN), so that an
animation moves each kind of part with one ``set_data``.
"""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes

from ..model.pendulum import Drawing, PendulumModel

__all__ = ["VIEWS", "drawing_frame", "joined_paths", "rod_chains", "spring_path", "view_reach"]

#: The views of a model's drawing, by its number of dimensions: for each, the two axes drawn
#: (indices into ``model.positions``), their labels and the view's name. A system in space is
#: drawn from above (x, y) and from the side (x, z), z up.
VIEWS = {
    2: (((0, 1), ("x (m)", "y (m)"), None),),
    3: (((0, 1), ("x (m)", "y (m)"), "from above"),
        ((0, 2), ("x (m)", "z (m)"), "from the side")),
}


#: Zigzags of a drawn spring, and its half-width as a share of the view's reach.
SPRING_TURNS = 9
SPRING_WIDTH = 0.035


def rod_chains(pairs) -> list[list[int]]:
    """The pairs ``(i, j)`` joined end to end into as few index paths as greedy joining
    gives: a chain's rods ``(-1, 0), (0, 1)`` become the one path ``[-1, 0, 1]``.

    >>> rod_chains([(-1, 0), (0, 1), (3, 2)])
    [[-1, 0, 1], [3, 2]]
    """
    paths: list[list[int]] = []
    for i, j in pairs:
        for path in paths:
            if path[-1] == i:
                path.append(j)
                break
        else:
            paths.append([i, j])
    return paths


def _point(x, y, k: int) -> tuple[float, float]:
    return (0.0, 0.0) if k == -1 else (float(x[k]), float(y[k]))


def spring_path(start, end, width: float, turns: int = SPRING_TURNS) -> np.ndarray:
    """A zigzag from ``start`` to ``end`` (points ``(x, y)``) of half-width ``width``, with a
    straight tenth at each end; shape ``(2 turns + 4, 2)``."""
    start, end = np.asarray(start, float), np.asarray(end, float)
    along = end - start
    length = float(np.hypot(*along))
    if length == 0.0:
        return np.array([start, end])
    across = np.array([-along[1], along[0]]) / length
    s = np.linspace(0.1, 0.9, 2 * turns + 1)
    side = np.zeros_like(s)
    side[1:-1:2], side[2:-1:2] = width, -width
    coil = start + s[:, None] * along + side[:, None] * across
    return np.vstack([start, coil, end])


def joined_paths(drawing: Drawing, x, y, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """The rods and the springs of one configuration as line data, paths broken by NaN.

    Parameters
    ----------
    drawing : Drawing
    x, y : array_like, shape (points,)
        The points' positions [m].
    reach : float
        The view's reach [m] (sets the springs' width).

    Returns
    -------
    rods, springs : ndarray, shape (k, 2)
        ``(x, y)`` rows; a row of NaN separates two paths.
    """
    gap = np.array([[np.nan, np.nan]])

    def joined(paths):
        if not paths:
            return np.empty((0, 2))
        return np.vstack([part for path in paths for part in (gap, path)][1:])

    rods = [np.array([_point(x, y, k) for k in path]) for path in rod_chains(drawing.rods)]
    springs = [spring_path(_point(x, y, i), _point(x, y, j), SPRING_WIDTH * reach)
               for i, j in drawing.springs]
    return joined(rods), joined(springs)


def view_reach(model: PendulumModel, x=None, y=None) -> float:
    """Half the width of a square view holding the model's configurations [m]: a chain's
    length, else the farthest point of the positions ``x, y`` given (any shape) from the
    origin."""
    reach = model.drawing.reach
    if reach is not None:
        return reach
    if x is None:
        raise ValueError("`x` and `y` are needed: a system's reach comes from its motion")
    farthest = float(np.nanmax(np.abs(np.concatenate([np.ravel(x), np.ravel(y), [0.0]]))))
    return farthest if farthest > 0 else 1.0


def drawing_frame(ax: Axes, model: PendulumModel, x=None, y=None, margin: float = 1.1,
                  labels=("x (m)", "y (m)")) -> float:
    """Square axes in metres reaching ``margin`` times :func:`view_reach`, and the fixed pivot
    where a rod or spring hangs from it; returns the reach drawn. ``labels``: those of the
    two axes (a view of a system in space draws ``x, z``)."""
    reach = margin * view_reach(model, x, y)
    ax.set(
        xlim=(-reach, reach), ylim=(-reach, reach), aspect="equal", xlabel=labels[0],
        ylabel=labels[1],
    )
    if model.drawing.uses_origin:
        ax.plot([0], [0], "s", color="black", ms=6, zorder=4)
    return reach
