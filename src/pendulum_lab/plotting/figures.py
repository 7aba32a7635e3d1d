"""What every figure of the package shares: new figures, the axes helper, labels, colours.

Figures are created without :mod:`matplotlib.pyplot`, so nothing accumulates
in a global figure list; every ``plot_*`` function draws into ``ax`` when
given one and otherwise makes a new figure (:func:`get_axes`).

One notation for every label: Unicode symbols and subscripts (``θ₂``,
``λ₁``, ``E − E(0)``), never TeX, each quantity with its unit in
parentheses (:func:`axis_label`). Unicode costs nothing to draw, where
mathtext costs milliseconds per label on every redraw of a live explorer.
"""

from __future__ import annotations

import numpy as np
from matplotlib import colormaps
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure

from .. import validation as check
from ..driver.simulate import Trajectory
from ..model.angles import wrap_angle
from ..model.pendulum import PendulumModel

__all__ = [
    "KINETIC",
    "LIBRATION",
    "POTENTIAL",
    "QUANTITIES",
    "ROTATION",
    "SEPARATRIX",
    "TOTAL",
    "axis_label",
    "broken_at_wraps",
    "get_axes",
    "get_axes_grid",
    "link_label",
    "new_figure",
    "pendulum_name",
    "plot_by_time",
    "single_trajectory",
    "subscript",
    "superscript",
    "wrap_angle",
]

# Colours used for the same quantity everywhere.
KINETIC, POTENTIAL, TOTAL = "tab:blue", "tab:orange", "black"
LIBRATION, ROTATION, SEPARATRIX = "tab:blue", "tab:green", "tab:red"

_SUBSCRIPTS = str.maketrans("0123456789", "₀₁₂₃₄₅₆₇₈₉")
_SUPERSCRIPTS = str.maketrans("0123456789-", "⁰¹²³⁴⁵⁶⁷⁸⁹⁻")
#: Colours of :func:`plot_by_time`, from the start of a run (dark) to its end (light): the
#: "plasma" colour map without its palest yellow, which vanishes on white.
TIME_COLOURS = colormaps["plasma"].resampled(256)
TIME_RANGE = (0.0, 0.85)

#: Symbol and unit of the quantities the figures share, for :func:`axis_label`.
QUANTITIES = {
    "t": ("t", "s"),
    "theta": ("θ", "rad"),
    "omega": ("ω", "rad/s"),
    "p": ("p", "kg m²/s"),
    "energy": ("E", "J"),
    "step": ("step h", "s"),
    "lambda": ("λ", "1/s"),
}


def new_figure(
    nrows: int = 1, ncols: int = 1, *, width: float = 6.4, height: float = 3.6, **subplot_kw
):
    """A new Figure and its axes (as ``Figure.subplots`` returns them).

    ``width`` is the whole figure's width and ``height`` that of one row, in
    inches. The figure uses the constrained layout.
    """
    fig = Figure(figsize=(width, height * nrows), layout="constrained")
    return fig, fig.subplots(nrows, ncols, squeeze=True, **subplot_kw)


def get_axes(ax: Axes | None, **figure_kw) -> Axes:
    """``ax`` (checked), or the axes of a :func:`new_figure` with ``figure_kw``."""
    if ax is None:
        return new_figure(**figure_kw)[1]
    if not isinstance(ax, Axes):
        raise TypeError(f"`ax` must be a matplotlib Axes or None, got {type(ax).__name__}")
    return ax


def get_axes_grid(axes, count: int, ncols: int, *, width: float = 12.0, height: float = 3.6,
                  **subplot_kw):
    """``(figure, flat array of axes)`` for ``count`` panels in ``ncols`` columns.

    ``axes`` (several Axes, checked) when given, else a new :func:`new_figure`
    of ``ceil(count / ncols)`` rows (``height`` per row).
    """
    if axes is None:
        nrows = -(-count // ncols)
        fig, grid = new_figure(nrows, ncols, width=width, height=height, **subplot_kw)
        return fig, np.atleast_1d(grid).ravel()
    axes = np.atleast_1d(axes).ravel()
    if axes.size < count or not all(isinstance(ax, Axes) for ax in axes):
        raise ValueError(f"`axes` must hold at least {count} matplotlib Axes, got {axes.size} "
                         "objects")
    return axes[0].figure, axes


def axis_label(quantity: str, sub: str = "") -> str:
    """``"θ₂ (rad)"``: the label of a quantity of :data:`QUANTITIES`, with a subscript.

    Examples
    --------
    >>> axis_label("theta", link_label(1, 2)), axis_label("t")
    ('θ₂ (rad)', 't (s)')
    """
    symbol, unit = QUANTITIES[check.choice("quantity", quantity, QUANTITIES)]
    return f"{symbol}{sub} ({unit})"


def single_trajectory(traj: Trajectory) -> Trajectory:
    """``traj`` if it is one trajectory (not an ensemble), else a clear error."""
    if not isinstance(traj, Trajectory):
        raise TypeError(
            f"`traj` must be a Trajectory (from pl.simulate), got {type(traj).__name__}"
        )
    if traj.theta.ndim != 2:
        raise ValueError(
            "`traj` must be a single trajectory (angles of shape (N+1, n)); for an ensemble "
            f"plot one member, got angles of shape {traj.theta.shape}"
        )
    return traj


def link_label(i: int, n: int) -> str:
    """The subscript of link ``i`` (0-based) of ``n``: ``"₂"``, or nothing for one link.

    Unicode subscripts, not mathtext: mathtext costs milliseconds per label
    on every redraw of a live explorer.
    """
    return "" if n == 1 else subscript(i + 1)


def subscript(number: int) -> str:
    """``12`` as ``"₁₂"``."""
    return str(number).translate(_SUBSCRIPTS)


def superscript(number: int) -> str:
    """``-12`` as ``"⁻¹²"``."""
    return str(number).translate(_SUPERSCRIPTS)


def pendulum_name(model: PendulumModel) -> str:
    """What a legend calls ``model``: "simple pendulum", "damped, driven pendulum", ...; a
    system that is not a chain by its own name ("the elastic pendulum").

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> pendulum_name(pl.double_pendulum()), pendulum_name(pl.driven_pendulum())
    ('double pendulum', 'damped, driven pendulum')
    >>> pendulum_name(pl.n_pendulum(3, damping=0.1))
    'damped 3-link pendulum'
    """
    if not model.is_chain:
        return model.name
    kind = {1: "simple pendulum", 2: "double pendulum"}.get(model.n, f"{model.n}-link pendulum")
    forces = [word for word, present in (("damped", not model.is_conservative),
                                          ("driven", not model.is_autonomous)) if present]
    if model.n == 1 and forces:
        kind = "pendulum"
    return " ".join([", ".join(forces), kind]) if forces else kind


def plot_by_time(ax: Axes, t, theta, y, label: str | None = None,
                 lw: float = 1.2) -> LineCollection:
    """The curve ``(theta(t), y(t))`` coloured by time, dark at the start, light at the end.

    ``theta`` is an angle: it is wrapped into ``(-pi, pi]`` and the curve
    breaks where it jumps from one side to the other (and at non-finite
    values). A long curve that winds many times (an orbit spiralling out
    under explicit Euler) stays readable where one colour would fill the
    plane. The legend shows ``label`` in the colour of the start.
    """
    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    points = np.column_stack([wrap_angle(np.asarray(theta, dtype=float)), y])
    segments = np.stack([points[:-1], points[1:]], axis=1)
    keep = np.all(np.isfinite(segments), axis=(1, 2))
    keep &= np.abs(segments[:, 1, 0] - segments[:, 0, 0]) <= np.pi
    times = 0.5 * (t[:-1] + t[1:])
    low, high = TIME_RANGE
    span = max(float(np.nanmax(t) - np.nanmin(t)), 1e-300) if t.size else 1.0
    shade = low + (high - low) * (times - np.nanmin(t)) / span if t.size else times
    lines = LineCollection(segments[keep], colors=TIME_COLOURS(shade[keep]), linewidths=lw,
                           label=label)
    ax.add_collection(lines)
    ax.update_datalim(points[np.all(np.isfinite(points), axis=1)])
    ax.autoscale_view()
    return lines


def broken_at_wraps(theta: np.ndarray, other: np.ndarray):
    """Wrapped ``theta`` and ``other`` with NaN inserted where the angle jumps by 2 pi."""
    wrapped = wrap_angle(theta)
    jumps = np.nonzero(np.abs(np.diff(wrapped)) > np.pi)[0] + 1
    return (np.insert(wrapped, jumps, np.nan), np.insert(np.asarray(other, float), jumps, np.nan))
