"""Figures of the chaos measurements: separation, Lyapunov exponents, sections, flip map.

Each result of :mod:`pendulum_lab.chaos` has a ``plot`` method that calls the
function here.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib import colormaps
from matplotlib.axes import Axes
from matplotlib.colors import ListedColormap, LogNorm
from matplotlib.figure import Figure
from matplotlib.ticker import NullFormatter

from .. import validation as check
from .figures import axis_label, get_axes, new_figure, subscript

__all__ = [
    "plot_flip_map",
    "plot_landing_errors",
    "plot_lyapunov",
    "plot_lyapunov_energy",
    "plot_lyapunov_spectrum",
    "plot_parting",
    "plot_section",
    "plot_sections",
    "plot_separation",
    "plot_small_angle",
]


def plot_separation(sep, ax: Axes | None = None, label=None, **kwargs) -> Figure:
    """Distance against time on a log scale, for a :class:`~pendulum_lab.chaos.Separation`."""
    ax = get_axes(ax)
    ax.semilogy(sep.t, sep.distance, label=label, **kwargs)
    ax.set(xlabel=axis_label("t"), ylabel="distance in (θ, p)")
    if label is not None:
        ax.legend(fontsize="small")
    return ax.figure


def plot_lyapunov(estimate, ax: Axes | None = None, label=None, **kwargs) -> Figure:
    """Running estimate of a :class:`~pendulum_lab.chaos.LyapunovEstimate` (log time axis).

    For an ensemble, one line per member.
    """
    ax = get_axes(ax)
    if label is None:
        label = f"{estimate.approach}, {estimate.method}"
    lines = ax.semilogx(estimate.t, estimate.running.reshape(len(estimate.t), -1), **kwargs)
    lines[0].set_label(label)
    ax.axhline(0.0, color="0.6", lw=0.8)
    ax.set(xlabel=axis_label("t"), ylabel="running estimate of lambda_1 (1/s)")
    ax.legend(fontsize="small")
    return ax.figure


def plot_lyapunov_energy(scan, ax: Axes | None = None) -> Figure:
    """Exponent against energy for a :class:`~pendulum_lab.chaos.EnergyLyapunov`.

    Every orbit is a dot (hollow if it counts as regular); the line joins the
    means over the chaotic orbits of each energy, with their standard errors.
    """
    ax = get_axes(ax, width=6.4, height=4.0)
    regular = scan.regular
    ax.scatter(scan.energy[~regular], scan.exponent[~regular], s=12, color="0.55",
               linewidths=0, label="one orbit (chaotic)")
    ax.scatter(scan.energy[regular], scan.exponent[regular], s=14, facecolors="none",
               edgecolors="0.35", linewidths=0.8, label="one orbit (regular)")
    rows = scan.per_energy()
    energy = np.array([row.energy for row in rows])
    mean = np.array([row.mean for row in rows])
    error = np.array([row.standard_error for row in rows])
    ax.errorbar(energy, mean, yerr=error, color="C3", marker="o", ms=4, capsize=3,
                label="mean over the chaotic orbits")
    ax.axhline(scan.threshold, color="0.6", lw=0.8, ls="--")
    ax.set(xlabel="energy E (J)", ylabel=f"lambda_1 after {scan.t_end:g} s (1/s)",
           title=f"{scan.method}, dt = {scan.dt:g} s; dashed: regular below "
                 f"{scan.threshold:g} 1/s")
    ax.legend(fontsize="small")
    return ax.figure


def plot_landing_errors(errors, ax: Axes | None = None, **kwargs) -> Figure:
    """A :class:`~pendulum_lab.chaos.LandingErrors`: error against crossing speed, log-log."""
    ax = get_axes(ax, width=6.0, height=4.0)
    order = np.argsort(errors.speed)
    kwargs.setdefault("label", f"{errors.landing}, {errors.method}, dt = {errors.dt:g} s")
    ax.loglog(errors.speed[order], errors.state_error[order], "o-", ms=4, **kwargs)
    ax.xaxis.set_minor_formatter(NullFormatter())  # a short range labels its minor ticks
    ax.set(xlabel="speed of the crossing |theta' of the surface's link| (rad/s)",
           ylabel="distance from the exact crossing")
    ax.legend(fontsize="small")
    return ax.figure


def plot_section(section, ax: Axes | None = None, link: int | None = None, s: float = 2.0,
                 **kwargs) -> Figure:
    """A :class:`~pendulum_lab.chaos.PoincareSection` in ``(theta_j, p_j)``, one colour per orbit.

    ``link`` is ``j``, by default the first link off the surface.
    """
    ax = get_axes(ax, width=4.8, height=4.2)
    x, y = section.coordinates(link)
    link = section.shown_link(link)
    ax.scatter(
        x, y, c=section.orbit % 20, s=s, cmap="tab20", vmin=0, vmax=19, linewidths=0, **kwargs
    )
    sub = subscript(link + 1)
    ax.set(xlabel=axis_label("theta", sub), ylabel=axis_label("p", sub))
    return ax.figure


def plot_sections(sections: dict, ncols: int = 2) -> Figure:
    """Poincare sections side by side, one panel per energy; returns the Figure.

    Parameters
    ----------
    sections : dict
        ``{energy: PoincareSection}``, as from :func:`pendulum_lab.chaos.energy_sections`.
    ncols : int
        Panels per row.
    """
    ncols = check.integer_at_least("ncols", ncols, 1)
    count = len(sections)
    if count == 0:
        raise ValueError("`sections` must hold at least one section")
    ncols = min(ncols, count)
    nrows = math.ceil(count / ncols)
    fig, axes = new_figure(nrows, ncols, width=4.0 * ncols, height=3.6)
    axes = np.asarray(axes).reshape(-1)
    for ax, (energy, sec) in zip(axes, sections.items()):
        sec.plot(ax=ax)
        ax.set_title(f"E = {energy:g} J, {len(sec.t)} crossings", fontsize="medium")
    for ax in axes[count:]:
        ax.set_visible(False)
    return fig


def plot_flip_map(flip_map, ax: Axes | None = None, colorbar: bool = True) -> Figure:
    """A :class:`~pendulum_lab.chaos.FlipMap` with a logarithmic colour scale.

    Energy-forbidden cells are grey, cells that did not flip before
    ``t_end`` white.
    """
    ax = get_axes(ax, width=5.4, height=4.4)
    half1 = (flip_map.theta1[1] - flip_map.theta1[0]) / 2 if flip_map.theta1.size > 1 else 0.5
    half2 = (flip_map.theta2[1] - flip_map.theta2[0]) / 2 if flip_map.theta2.size > 1 else 0.5
    extent = (
        flip_map.theta1[0] - half1,
        flip_map.theta1[-1] + half1,
        flip_map.theta2[0] - half2,
        flip_map.theta2[-1] + half2,
    )
    flipped = np.ma.masked_invalid(np.where(np.isfinite(flip_map.time), flip_map.time, np.nan))
    lowest = float(flipped.min()) if flipped.count() else flip_map.dt
    lowest = min(max(lowest, flip_map.dt), flip_map.t_end / 10)
    image = ax.imshow(
        flipped,
        origin="lower",
        extent=extent,
        interpolation="nearest",
        cmap=colormaps["viridis"].with_extremes(bad="white"),
        norm=LogNorm(vmin=lowest, vmax=flip_map.t_end),
    )
    ax.imshow(
        np.ma.masked_where(~flip_map.forbidden, flip_map.forbidden.astype(float)),
        origin="lower",
        extent=extent,
        interpolation="nearest",
        cmap=ListedColormap(["0.75"]),
        vmin=0,
        vmax=1,
    )
    ax.set(xlabel="theta1(0) (rad)", ylabel="theta2(0) (rad)")
    if colorbar:
        ax.figure.colorbar(image, ax=ax, label="flip time (s)")
    return ax.figure


def plot_small_angle(comparison, ax: Axes | None = None, member=()) -> Figure:
    """Both motions of one member of a :class:`~pendulum_lab.chaos.SmallAngleComparison`."""
    ax = get_axes(ax, width=7.0, height=3.6)
    member = tuple(member) if isinstance(member, tuple | list) else (int(member),)
    full = comparison.theta_full[(slice(None), *member)]
    linear = comparison.theta_linear[(slice(None), *member)]
    for i in range(full.shape[-1]):
        line = ax.plot(comparison.t, full[:, i], label=f"theta{i + 1} full")[0]
        ax.plot(comparison.t, linear[:, i], "--", color=line.get_color(),
                label=f"theta{i + 1} linearised")
    parting = np.asarray(comparison.parting_time)[member]
    if np.isfinite(parting):
        ax.axvline(parting, color="k", lw=0.8, ls=":", label="they part")
    ax.set(xlabel=axis_label("t"), ylabel="angle (rad)")
    ax.legend(fontsize="small", ncol=2)
    return ax.figure


def plot_parting(comparison, amplitudes, ax: Axes | None = None) -> Figure:
    """Parting time against release amplitude (log-log) with a fitted power law.

    Parameters
    ----------
    comparison : SmallAngleComparison
    amplitudes : array_like, shape like ``comparison.parting_time``
        The size of each member's release (for example its largest angle).
    """
    amplitudes = np.asarray(amplitudes, dtype=float)
    times = np.asarray(comparison.parting_time, dtype=float)
    if amplitudes.shape != times.shape:
        raise ValueError(
            f"`amplitudes` must have the shape of `parting_time` {times.shape}, "
            f"got {amplitudes.shape}"
        )
    ax = get_axes(ax)
    ax.loglog(amplitudes, times, "o", label="measured")
    parted = np.isfinite(times) & (amplitudes > 0)
    if parted.sum() >= 2:
        slope, offset = np.polyfit(np.log(amplitudes[parted]), np.log(times[parted]), 1)
        ax.loglog(
            amplitudes[parted],
            np.exp(offset) * amplitudes[parted] ** slope,
            "--",
            color="0.4",
            label=f"fit: time ~ amplitude^{slope:.2f}",
        )
    ax.set(xlabel="release amplitude (rad)", ylabel="parting time (s)")
    ax.legend(fontsize="small")
    return ax.figure


def plot_lyapunov_spectrum(spectrum, ax: Axes | None = None, member=(), **kwargs) -> Figure:
    """Running estimates of every exponent of a :class:`~pendulum_lab.chaos.LyapunovSpectrum`.

    ``member`` picks one member of an ensemble; the dotted line is the sum
    of the exponents (the mean contraction rate of phase-space volume).
    """
    ax = get_axes(ax)
    member = tuple(member) if isinstance(member, tuple | list) else (int(member),)
    running = spectrum.running[(slice(None), *member)]
    if running.ndim != 2:
        raise ValueError(f"`member` must pick one member of the ensemble shape "
                         f"{spectrum.running.shape[1:-1]}, got {member}")
    for i in range(running.shape[-1]):
        ax.semilogx(spectrum.t, running[:, i], label=f"lambda{subscript(i + 1)}", **kwargs)
    ax.semilogx(spectrum.t, running.sum(axis=-1), ":", color="k", label="sum")
    ax.axhline(0.0, color="0.6", lw=0.8)
    ax.set(xlabel="t (s)", ylabel="running estimate (1/s)")
    ax.legend(fontsize="small", ncol=2)
    return ax.figure
