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

from ..geometric.standard_map import FLUX_EXPONENT, GREENE_K
from .figures import axis_label, get_axes, get_axes_grid, subscript

__all__ = [
    "plot_adaptive_energy",
    "plot_area_ratio",
    "plot_carried_loops",
    "plot_crossing_times",
    "plot_energy_drift",
    "plot_error_growth",
    "plot_level_sets",
    "plot_modified_energy_orders",
    "plot_orbit_on_level_sets",
    "plot_projected_areas",
    "plot_root_branch",
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


def plot_carried_loops(model, results, frames, axes=None, ncols=3, margin=0.3, shared=True):
    """The loop of initial states and its images at saved times, one panel per method.

    Every panel has equal scales on its two axes (a blob's shape and area
    are seen as they are) and the area ratio at the last frame drawn in its
    title; the energy's level sets are drawn behind.

    Parameters
    ----------
    model : PendulumModel
        A simple pendulum (its energy gives the background level sets).
    results : sequence of LoopAreas
    frames : sequence of int
        Indices of saved times to draw.
    shared : bool or "row"
        Give every panel the same limits (the union of all loops drawn), so
        that areas can be compared across panels; ``"row"``: the same limits
        within each row of ``ncols`` panels; ``False``: each panel fitted to
        its own loops.
    """
    if shared not in (True, False, "row"):
        raise ValueError(f"`shared` must be True, False or 'row', got {shared!r}")
    fig, grid = get_axes_grid(axes, len(results), ncols, height=3.4)
    frames = list(frames)
    bounds = [(r.loops[frames].min(axis=(0, 1)), r.loops[frames].max(axis=(0, 1)))
              for r in results]
    if shared:
        size = ncols if shared == "row" else len(results)
        for first in range(0, len(results), size):
            group = bounds[first:first + size]
            union = (np.min([lo for lo, _ in group], axis=0),
                     np.max([hi for _, hi in group], axis=0))
            bounds[first:first + size] = [union] * len(group)
    for ax, result, (lo, hi) in zip(grid, results, bounds):
        pad = margin * (hi - lo)
        lo, hi = lo - pad, hi + pad
        plot_level_sets(model.hamiltonian_value, (lo[0], hi[0]), (lo[1], hi[1]), ax=ax)
        for k, frame in enumerate(frames):
            closed = np.vstack([result.loops[frame], result.loops[frame][:1]])
            ax.fill(closed[:, 0], closed[:, 1], alpha=0.35, color=f"C{k}",
                    label=f"t = {result.t[frame]:g} s")
            ax.plot(closed[:, 0], closed[:, 1], color=f"C{k}", lw=0.8)
        ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), aspect="equal")
        ax.set_title(f"{result.method}, h = {result.dt:g}: area ratio "
                     f"{result.ratio[frames[-1]]:.6f} at t = {result.t[frames[-1]]:g} s",
                     fontsize=9)
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


def plot_projected_areas(result, axes=None, legend=True):
    """A loop's projected areas against time, in two panels of different units.

    The upper panel has the oriented areas of the loop's projections on each
    ``(theta_i, p_i)`` plane and their sum, Poincare's invariant (units J s,
    as rad kg m^2/s); the lower one the sum of the areas in the
    ``(theta_i, omega_i)`` planes (rad^2/s), which the exact flow does not keep
    for two links.

    Parameters
    ----------
    result : LoopAreas
    axes : pair of Axes, optional
        Upper and lower panel; a new two-row figure by default.
    legend : bool
        Draw the legends, outside the panels on the right (so that they hide
        no part of the curves).
    """
    fig, (upper, lower) = get_axes_grid(axes, 2, 1, width=7.0, height=2.6, sharex=True)
    n = result.canonical.shape[1]
    for i in range(n):
        sub = subscript(i + 1)
        upper.plot(result.t, result.canonical[:, i], ls="--", label=f"(θ{sub}, p{sub}) plane")
    upper.plot(result.t, result.invariant, color="black", lw=2, label="sum over the planes")
    upper.set_ylabel("area in (θᵢ, pᵢ) (J s)")
    upper.set_title(f"{result.method}, h = {result.dt:g}", fontsize=10)
    lower.plot(result.t, result.velocity.sum(axis=1), color="tab:red",
               label="sum over the (θᵢ, ωᵢ) planes")
    lower.set_ylabel("area in (θᵢ, ωᵢ) (rad²/s)")
    lower.set_xlabel(axis_label("t"))
    if legend:
        for ax in (upper, lower):
            ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0)
    return fig


def plot_root_branch(branch, ax=None, steps=()):
    """The roots ``q_{k+1}(h)`` of a variational step along their branch, with its fold.

    Parameters
    ----------
    branch : RootBranch
        From :func:`pendulum_lab.geometric.continuation.variational_root_branch`.
    steps : sequence of float
        Steps at which to mark the branch's roots (one before the fold, one
        beyond it when the branch comes back).
    """
    ax = get_axes(ax)
    n = branch.q_next.shape[1]
    for i in range(n):
        sub = subscript(i + 1) if n > 1 else ""
        ax.plot(branch.h, branch.q_next[:, i], color=f"C{i}", label=f"θ{sub} at step k + 1")
    if branch.folded:
        ax.axvline(branch.fold_h, color="black", ls="--", lw=0.8,
                   label=f"fold, h = {branch.fold_h:.4f} s")
    for h in steps:
        roots = branch.roots_at(h)
        for i in range(n):
            ax.plot(np.full(len(roots), h), roots[:, i], "o", color=f"C{i}", ms=5)
    ax.set_xlabel(axis_label("step"))
    ax.set_ylabel("root θ at step k + 1 (rad)")
    ax.set_title(f"{branch.rule} rule: the root that continues the small-step one", fontsize=10)
    ax.legend(fontsize=8)
    return ax.figure


def plot_modified_energy_orders(result, ax=None):
    """Errors of ``H~`` truncated after ``h^k`` against the step, log-log, slopes in the legend."""
    ax = get_axes(ax)
    for k, errors, slope, expected in zip(result.orders, result.errors, result.slopes,
                                          result.expected):
        name = "H" if k == 0 else rf"$\tilde H$ to $h^{k}$"
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
              label=rf"predicted, $\propto h^{result.power}$")
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


def plot_crossing_times(result, ax=None):
    """Median first-crossing time of the standard map against ``K - K_c``, log-log.

    The medians of the whole ensemble (dots) and of its two halves (small
    marks), the fastest orbit of each half (grey), and a line of
    MacKay-Meiss-Percival's slope ``-FLUX_EXPONENT`` through the medians.
    """
    ax = get_axes(ax)
    known = np.isfinite(result.median)
    ax.loglog(result.excess, result.median, "o", color="tab:blue",
              label=f"median of {result.orbits} orbits (fitted slope {result.slope:.2f})")
    for half in range(2):  # one legend entry for both halves
        ax.loglog(result.excess, result.half_medians[:, half], "_", color="tab:blue", ms=10,
                  label=None if half else "medians of the two halves")
    for half in range(2):
        ax.loglog(result.excess, result.half_fastest[:, half], "x", color="0.5",
                  label=None if half else "fastest orbit of each half")
    if known.any():
        x = result.excess[known]
        centre = np.exp(np.mean(np.log(result.median[known])))
        anchor = np.exp(np.mean(np.log(x)))
        ax.loglog(x, centre * (x / anchor) ** -FLUX_EXPONENT, color="black", ls="--",
                  label=f"slope -{FLUX_EXPONENT:g} (MacKay, Meiss, Percival)")
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xticks(result.excess, [f"{x:.2g}" for x in result.excess])
    ax.set_xlabel("K - K_c")
    ax.set_ylabel("iterations to cross 2π in I")
    ax.legend(fontsize=8)
    return ax.figure


def plot_transport_threshold(result, ax=None):
    """Finite-time transport threshold (the fastest orbit's) against the number of iterations.

    With Greene's K_c for reference. The threshold depends on the number of
    orbits started; :func:`plot_crossing_times` draws the median instead.
    """
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
    ax.set_ylabel("largest |H - H(0)| so far (J)" if envelope else "H - H(0) (J)")
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
