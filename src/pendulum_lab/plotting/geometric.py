"""Figures of geometric integration, notebooks 13-16: areas, modified energies, maps, steps.

Each function draws into ``ax`` (or ``axes``) when given and otherwise makes
a new figure (:func:`~pendulum_lab.plotting.get_axes`,
:func:`~pendulum_lab.plotting.get_axes_grid`); it returns the Figure. The
numbers drawn come from the result objects of :mod:`pendulum_lab.geometric`
and :mod:`pendulum_lab.analysis`; nothing is computed here beyond grids of
level sets.
"""

from __future__ import annotations

import numpy as np
from matplotlib.ticker import NullFormatter

from ..geometric.standard_map import GREENE_K
from .figures import axis_label, get_axes, get_axes_grid, subscript, superscript

__all__ = [
    "plot_adaptive_energy",
    "plot_area_ratio",
    "plot_carried_loops",
    "plot_energy_drift",
    "plot_error_growth",
    "plot_level_sets",
    "plot_modified_energy_orders",
    "plot_orbit_on_level_sets",
    "plot_projected_areas",
    "plot_standard_map",
    "plot_step_sizes",
    "plot_transport_threshold",
]


def plot_level_sets(energy, theta_range, p_range, ax=None, levels=15, **contour_kw):
    """Contours of ``energy(theta, p)`` (a NumPy function) over a rectangle.

    ``energy`` takes arrays of shape ``(..., 1)`` for ``theta`` and ``p``.
    """
    ax = get_axes(ax)
    theta = np.linspace(*theta_range, 241)
    p = np.linspace(*p_range, 241)
    grid_theta, grid_p = np.meshgrid(theta, p)
    values = energy(grid_theta[..., None], grid_p[..., None])
    kw = {"colors": "0.75", "linewidths": 0.6} | contour_kw
    ax.contour(grid_theta, grid_p, values, levels=levels, **kw)
    ax.set(xlabel=axis_label("theta"), ylabel=axis_label("p"))
    return ax.figure


def plot_orbit_on_level_sets(run, functions, axes=None, margin=0.15):
    """A computed orbit on the level sets of several functions, one panel each.

    Parameters
    ----------
    run : Trajectory
        A simple-pendulum run.
    functions : dict
        ``{label: f}`` with ``f(theta, p)`` NumPy functions (``H``, a truncated ``H~``).
        The level through the orbit's first state is drawn in black.
    """
    fig, grid = get_axes_grid(axes, len(functions), len(functions), height=4.0)
    theta, p = run.theta[:, 0], run.p[:, 0]
    span = np.array([np.ptp(theta), np.ptp(p)])
    lo = np.array([theta.min(), p.min()]) - margin * span
    hi = np.array([theta.max(), p.max()]) + margin * span
    for ax, (label, f) in zip(grid, functions.items()):
        plot_level_sets(f, (lo[0], hi[0]), (lo[1], hi[1]), ax=ax, levels=12)
        start = float(f(run.theta[:1], run.p[:1])[0])
        plot_level_sets(f, (lo[0], hi[0]), (lo[1], hi[1]), ax=ax, levels=[start],
                        colors="black", linewidths=1.2)
        ax.plot(theta, p, ".", color="tab:red", ms=3, label=f"{run.method.name}, h = {run.dt:g}")
        ax.set_title(f"level sets of {label}", fontsize=10)
    grid[0].legend(fontsize=8, loc="upper right")
    return fig


def plot_carried_loops(model, results, frames, axes=None, ncols=3, margin=0.3):
    """The loop of initial states and its images at saved times, one panel per method.

    Each panel is scaled to its own loops, with the energy's level sets behind.

    Parameters
    ----------
    model : PendulumModel
        A simple pendulum (its energy gives the background level sets).
    results : sequence of LoopAreas
    frames : sequence of int
        Indices of saved times to draw.
    """
    fig, grid = get_axes_grid(axes, len(results), ncols, height=3.4)
    for ax, result in zip(grid, results):
        loops = result.loops[list(frames)]
        lo, hi = loops.min(axis=(0, 1)), loops.max(axis=(0, 1))
        pad = margin * (hi - lo)
        plot_level_sets(model.hamiltonian_value, (lo[0] - pad[0], hi[0] + pad[0]),
                        (lo[1] - pad[1], hi[1] + pad[1]), ax=ax)
        for k, frame in enumerate(frames):
            closed = np.vstack([result.loops[frame], result.loops[frame][:1]])
            ax.fill(closed[:, 0], closed[:, 1], alpha=0.35, color=f"C{k}",
                    label=f"t = {result.t[frame]:g} s")
            ax.plot(closed[:, 0], closed[:, 1], color=f"C{k}", lw=0.8)
        ax.set_title(f"{result.method}, h = {result.dt:g}", fontsize=10)
    for ax in grid[len(results):]:
        ax.set_visible(False)
    grid[0].legend(fontsize=8, loc="best")
    return fig


def plot_area_ratio(results, ax=None, labels=None):
    """``area(t) / area(0)`` (Poincare's invariant for chains) against time, one line per run."""
    ax = get_axes(ax)
    labels = labels or [f"{r.method}, h = {r.dt:g}" for r in results]
    for result, label in zip(results, labels):
        ax.plot(result.t, result.ratio, marker=".", label=label)
    ax.set_xlabel(axis_label("t"))
    ax.set_ylabel("area(t) / area(0)")
    ax.legend(fontsize=8)
    return ax.figure


def plot_projected_areas(result, ax=None):
    """The areas of a loop's projections on each ``(theta_i, p_i)`` plane, their sum, and the
    sum of the ``(theta_i, omega_i)`` areas, against time."""
    ax = get_axes(ax)
    n = result.canonical.shape[1]
    for i in range(n):
        sub = subscript(i + 1)
        ax.plot(result.t, result.canonical[:, i], ls="--", label=f"(θ{sub}, p{sub}) plane")
    ax.plot(result.t, result.invariant, color="black", lw=2, label="sum over the planes")
    ax.plot(result.t, result.velocity.sum(axis=1), color="tab:red", label="sum in (θᵢ, ωᵢ)")
    ax.set_xlabel(axis_label("t"))
    ax.set_ylabel("oriented area (rad kg m²/s)")
    ax.set_title(f"{result.method}, h = {result.dt:g}", fontsize=10)
    ax.legend(fontsize=8)
    return ax.figure


def plot_modified_energy_orders(result, ax=None):
    """Errors of ``H~`` truncated after ``h^k`` against the step, log-log, slopes in the legend."""
    ax = get_axes(ax)
    for k, errors, slope, expected in zip(result.orders, result.errors, result.slopes,
                                          result.expected):
        name = "H" if k == 0 else f"modified H to h{superscript(k)}"
        ax.loglog(result.dts, errors, marker="o",
                  label=f"{name}: slope {slope:.2f} (theory {expected})")
    ax.xaxis.set_minor_formatter(NullFormatter())  # minor labels collide on short decades
    ax.set_xlabel(axis_label("step"))
    ax.set_ylabel("max |error| along the orbit (J)")
    ax.set_title(result.method, fontsize=10)
    ax.legend(fontsize=8)
    return ax.figure


def plot_energy_drift(result, ax=None):
    """Measured energy drift rate against the modified equation's prediction, log-log."""
    ax = get_axes(ax)
    ax.loglog(result.dts, np.abs(result.measured), "o", label="measured (fit over the run)")
    ax.loglog(result.dts, np.abs(result.predicted), "-",
              label=f"predicted, ∝ h{superscript(result.power)}")
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel(axis_label("step"))
    ax.set_ylabel("|dE/dt| (J/s)")
    ax.set_title(f"{result.method}: energy drift from {result.amplitude:g} rad", fontsize=10)
    ax.legend(fontsize=8)
    return ax.figure


def plot_error_growth(results, ax=None, labels=None):
    """Global error against time, log-log, with lines of slope 1 and 2 for reference."""
    ax = get_axes(ax, width=9.0, height=5.0)
    labels = labels or [f"{r.method}, h = {r.dt:g}, from {r.amplitude:g} rad" for r in results]
    for result, label in zip(results, labels):
        ax.loglog(result.t, result.error, marker=".", label=label)
    t = np.geomspace(results[0].t[0], results[0].t[-1], 2)
    low = min(r.error.min() for r in results)
    ax.loglog(t, low * t / t[0], color="0.6", ls=":", label="slope 1")
    ax.loglog(t, low * (t / t[0]) ** 2, color="0.3", ls=":", label="slope 2")
    ax.set_xlabel(axis_label("t"))
    ax.set_ylabel("global error (rad)")
    ax.legend(fontsize=8)
    return ax.figure


def plot_standard_map(portraits, axes=None, ncols=3):
    """Phase portraits of the standard map.

    Parameters
    ----------
    portraits : dict
        ``{K: (phi, action)}`` with arrays of shape ``(iterations + 1, orbits)``
        (from :func:`pendulum_lab.geometric.standard_map.iterate`).
    """
    fig, grid = get_axes_grid(axes, len(portraits), ncols, height=3.8)
    for ax, (k, (phi, action)) in zip(grid, portraits.items()):
        wrapped = np.mod(action + np.pi, 2 * np.pi) - np.pi
        for j in range(phi.shape[1]):
            ax.plot(phi[:, j], wrapped[:, j], ",", color=f"C{j % 10}")
        ax.set_xlim(0, 2 * np.pi)
        ax.set_ylim(-np.pi, np.pi)
        ax.set_title(f"K = {k:g}" + (" (> K_c)" if k > GREENE_K else ""), fontsize=10)
        ax.set(xlabel="φ", ylabel="I (mod 2π)")
    for ax in grid[len(portraits):]:
        ax.set_visible(False)
    return fig


def plot_transport_threshold(result, ax=None):
    """Finite-time transport threshold against the number of iterations, with Greene's K_c."""
    ax = get_axes(ax)
    ax.semilogx(result.iterations, result.thresholds, "o-", label="smallest K with crossings")
    ax.axhline(GREENE_K, color="black", ls="--", label=f"Greene's K_c = {GREENE_K:.4f}")
    ax.set_xlabel("iterations N")
    ax.set_ylabel("K")
    ax.legend(fontsize=8)
    return ax.figure


def plot_adaptive_energy(runs, ax=None, envelope=False):
    """Energy error against time for several runs (fixed or adaptive steps).

    With ``envelope=True`` the largest ``|E - E0|`` so far is drawn on a
    logarithmic axis: drifts of very different sizes then share one picture.
    """
    ax = get_axes(ax)
    for run in runs:
        label = getattr(run, "label", None) or f"{run.method.name}, dt = {run.dt:g}"
        if envelope:
            ax.semilogy(run.t[1:], np.maximum.accumulate(np.abs(run.energy_error))[1:], lw=1.0,
                        label=label)
        else:
            ax.plot(run.t, run.energy_error, lw=0.8, label=label)
    ax.set_xlabel(axis_label("t"))
    ax.set_ylabel("largest |H − H(0)| so far (J)" if envelope else "H − H(0) (J)")
    ax.legend(fontsize=8)
    return ax.figure


def plot_step_sizes(run, ax=None, speed=None):
    """Step sizes of an adaptive run against time, with the angular speed for comparison."""
    ax = get_axes(ax)
    ax.plot(run.t[:-1], run.step_sizes, color="tab:blue", lw=0.8)
    ax.set_xlabel(axis_label("t"))
    ax.set_ylabel(axis_label("step"), color="tab:blue")
    if speed is not None:
        twin = ax.twinx()
        twin.plot(run.t, speed, color="tab:orange", lw=0.8)
        twin.set_ylabel("|ω| (rad/s)", color="tab:orange")
    ax.set_title(run.label, fontsize=10)
    return ax.figure
