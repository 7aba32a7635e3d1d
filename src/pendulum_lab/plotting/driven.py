"""Figures of the driven pendulum: stroboscopic sections, bifurcation diagrams, basins.

Each result of :mod:`pendulum_lab.chaos` (``StroboscopicSection``,
``BifurcationDiagram``, ``Basins``) has a ``plot`` method that calls the
function here.
"""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure

from .figures import get_axes, new_figure, subscript

__all__ = ["plot_basins", "plot_bifurcation", "plot_orbit_branches", "plot_stroboscopic"]

# Colours of basins (attractor 0, 1, ...); "none settled" is light grey.
BASIN_COLOURS = ("#9ecae1", "#fdae6b", "#a1d99b", "#bcbddc", "#fdd0a2", "#c7e9c0")
UNSETTLED = "0.92"


def plot_stroboscopic(section, ax: Axes | None = None, link: int = 0, member=None,
                      s: float = 0.6, **kwargs) -> Figure:
    """Samples of a :class:`~pendulum_lab.chaos.StroboscopicSection` in ``(theta, omega)``.

    ``member`` picks one member of an ensemble (all are drawn by default).
    """
    ax = get_axes(ax, width=5.4, height=4.2)
    theta, omega = section.theta[..., link], section.omega[..., link]
    if member is not None:
        member = (member,) if np.ndim(member) == 0 else tuple(member)
        theta, omega = theta[(slice(None), *member)], omega[(slice(None), *member)]
    ax.scatter(theta.ravel(), omega.ravel(), s=s, c=kwargs.pop("c", "k"), linewidths=0,
               **kwargs)
    label = subscript(link + 1) if section.theta.shape[-1] > 1 else ""
    ax.set(xlabel=f"theta{label} (rad)", ylabel=f"omega{label} (rad/s)", xlim=(-np.pi, np.pi))
    ax.set_title(f"once per drive period ({len(section.t)} periods)", fontsize="medium")
    return ax.figure


def plot_bifurcation(diagram, ax: Axes | None = None, lyapunov=None,
                     mark_doublings: bool = True, s: float = 0.3) -> Figure:
    """A :class:`~pendulum_lab.chaos.BifurcationDiagram`; returns the Figure.

    Every stroboscopic sample is a dot above its parameter value. With
    ``mark_doublings``, a dashed line marks each period doubling found in
    the data (at the first value with the doubled period). With
    ``lyapunov`` (a ``LyapunovSpectrum`` or ``LyapunovEstimate`` whose
    ensemble shape starts with the diagram's values), a second panel below
    shows the largest exponent on the same axis.
    """
    if lyapunov is not None and ax is not None:
        raise ValueError("give `ax` or `lyapunov`, not both (with `lyapunov` the figure has "
                         "two panels)")
    if lyapunov is None:
        ax = get_axes(ax, width=7.5, height=4.2)
        axes = [ax]
    else:
        fig, axes = new_figure(2, 1, width=7.5, height=3.0, sharex=True,
                               gridspec_kw={"height_ratios": (3, 2)})
        ax = axes[0]
    points = diagram.points
    values = np.broadcast_to(diagram.values[None, :, None], points.shape)
    ax.scatter(values.ravel(), points.ravel(), s=s, c="k", linewidths=0, rasterized=True)
    link = subscript(diagram.link + 1) if diagram.theta.shape[-1] > 1 else ""
    unit = "rad/s" if diagram.variable == "omega" else "rad"
    ax.set(ylabel=f"{diagram.variable}{link} once per period ({unit})")
    if mark_doublings:
        for k, doubling in enumerate(diagram.doublings()):
            for each in axes:
                each.axvline(doubling.value, color="tab:red", lw=0.8, ls="--")
            # staggered, so that labels of close doublings do not overlap
            ax.annotate(f"{doubling.period}\u2192{2 * doubling.period}", (doubling.value, 1.0),
                        xycoords=("data", "axes fraction"), xytext=(2, -10 - 9 * (k % 3)),
                        textcoords="offset points", fontsize="x-small", color="tab:red")
        if diagram.doublings():
            ax.set_title("dashed: period doublings found in the data", fontsize="small",
                         color="tab:red")
    if lyapunov is not None:
        # a LyapunovSpectrum's first exponent, or a LyapunovEstimate's exponent
        largest = getattr(lyapunov, "largest", None)
        largest = np.asarray(lyapunov.exponent if largest is None else largest)
        if largest.ndim == 0 or largest.shape[0] != len(diagram.values):
            raise ValueError(f"`lyapunov` must have one estimate per value of the diagram "
                             f"({len(diagram.values)}), got ensemble shape {largest.shape}")
        largest = largest.reshape(len(diagram.values), -1)
        axes[1].plot(diagram.values, largest, ".", ms=2, color="tab:blue")
        axes[1].axhline(0.0, color="0.4", lw=0.8)
        axes[1].set(ylabel="lambda\u2081 (1/s)")
    axes[-1].set(xlabel=diagram.parameter.replace("_", " "))
    return ax.figure


def plot_basins(basins, ax: Axes | None = None, s: float = 30.0) -> Figure:
    """A :class:`~pendulum_lab.chaos.Basins` map: one colour per attractor, its points on top."""
    ax = get_axes(ax, width=5.8, height=4.4)
    count = len(basins.attractors)
    colours = ListedColormap([UNSETTLED, *BASIN_COLOURS[:max(count, 1)]])
    dtheta = np.diff(basins.theta0).mean() / 2 if basins.theta0.size > 1 else 0.5
    domega = np.diff(basins.omega0).mean() / 2 if basins.omega0.size > 1 else 0.5
    extent = (basins.theta0[0] - dtheta, basins.theta0[-1] + dtheta,
              basins.omega0[0] - domega, basins.omega0[-1] + domega)
    ax.imshow(basins.label + 1, origin="lower", extent=extent, aspect="auto",
              interpolation="nearest", cmap=colours, vmin=0, vmax=max(count, 1))
    markers = ("o", "s", "^", "D", "v", "P")
    for k, points in enumerate(basins.attractors):
        ax.scatter(points[:, 0], points[:, 1], s=s, marker=markers[k % len(markers)],
                   color=BASIN_COLOURS[k % len(BASIN_COLOURS)], edgecolors="k", zorder=3,
                   label=f"attractor {k}: period {len(points)}, {basins.turns[k]:+g} turns "
                         f"per period, {basins.fractions[k]:.0%} of starts")
    ax.set(xlabel="theta(0) (rad)", ylabel="omega(0) (rad/s)")
    ax.legend(fontsize="small", loc="upper right")
    return ax.figure


def plot_orbit_branches(branches: dict, bifurcations=(), axes=None, parameter: str = "A",
                        link: int = 0) -> Figure:
    """Periodic orbits followed through a parameter: their mean angle and leading multiplier.

    Parameters
    ----------
    branches : dict
        ``{label: (values, orbits)}``: the parameter's values and the
        :class:`~pendulum_lab.chaos.PeriodicOrbit` at each (as from
        :func:`~pendulum_lab.chaos.continue_orbit`).
    bifurcations : sequence of Bifurcation
        Marked by a dotted vertical line in both panels, labelled by the multiplier.
    axes : pair of Axes, optional
    parameter : str
        The parameter's symbol on the horizontal axes.
    link : int
        Whose mean angle.

    Left: the time average of the angle over each orbit (0 on a symmetric
    orbit), solid where the orbit is stable and dashed where it is not.
    Right: the real part of the multiplier of largest modulus, with the
    lines +1 and -1 where an orbit loses its stability.
    """
    if axes is None:
        fig, axes = new_figure(1, 2, width=11.0, height=3.8)
    for k, (label, (values, orbits)) in enumerate(branches.items()):
        values = np.asarray(values, dtype=float)
        if len(values) != len(orbits):
            raise ValueError(f"branch {label!r}: {len(values)} values but {len(orbits)} orbits")
        order = np.argsort(values, kind="stable")  # a branch may be followed both ways
        values, orbits = values[order], [orbits[i] for i in order]
        stable = np.array([orbit.stable for orbit in orbits])
        # each piece runs to the neighbouring point of the other kind, so the line is unbroken
        solid = stable | np.r_[stable[1:], False]
        dashed = ~stable | np.r_[~stable[1:], False]
        mean = np.array([orbit.mean_theta[link] for orbit in orbits])
        leading = np.array([orbit.multipliers[0].real for orbit in orbits])
        colour = f"C{k}"
        for y, ax in ((mean, axes[0]), (leading, axes[1])):
            ax.plot(values, np.where(solid, y, np.nan), "-", color=colour, label=label)
            ax.plot(values, np.where(dashed, y, np.nan), "--", color=colour)
    for bifurcation in bifurcations:
        for ax in axes:
            ax.axvline(bifurcation.value, color="0.3", lw=0.8, ls=":")
        axes[1].annotate(f"μ = {bifurcation.multiplier:+d}", (bifurcation.value, 1.0),
                         xycoords=("data", "axes fraction"), xytext=(3, -12),
                         textcoords="offset points", fontsize="x-small")
    for level in (1.0, -1.0):
        axes[1].axhline(level, color="0.6", lw=0.8)
    axes[0].set(xlabel=parameter, ylabel="mean angle over the orbit (rad)")
    axes[1].set(xlabel=parameter, ylabel="leading Floquet multiplier (real part)")
    axes[0].legend(fontsize="small")
    axes[0].set_title("solid: stable, dashed: unstable", fontsize="small")
    return axes[0].figure

