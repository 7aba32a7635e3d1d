"""Figures that compare integrators: observed order, energy error growth, work-precision.

Also the contraction of an implicit method's stage iteration against the step and the
decay of energy under damping.
"""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from .. import validation as check
from ..analysis import AdaptiveRun, EnergyComparison, OrderResult
from .figures import axis_label, get_axes, pendulum_name

__all__ = [
    "plot_amplification",
    "plot_energy_comparison",
    "plot_energy_decay",
    "plot_energy_error_growth",
    "plot_order",
    "plot_stage_contraction",
    "plot_work_precision",
]


def _run_label(run) -> str:
    return run.label if isinstance(run, AdaptiveRun) else run.method.name


def plot_energy_error_growth(runs, ax: Axes | None = None, labels=None) -> Figure:
    """The largest energy error so far, ``max_{s <= t} |E(s) - E(0)|``, on a log scale.

    The running maximum is flat once a bounded error has reached its bound
    and keeps rising for a drifting one; the raw error oscillates too fast to
    read over a long run. The course report's velocity-variable methods are
    dashed, adaptive runs (SciPy's DOP853) dotted.

    Parameters
    ----------
    runs : sequence of Trajectory or AdaptiveRun
        Single trajectories.
    ax : Axes, optional
    labels : sequence of str, optional
        Legend entries; by default the method names.

    Returns
    -------
    matplotlib.figure.Figure
    """
    ax = get_axes(ax, width=8.0, height=4.2)
    labels = [_run_label(run) for run in runs] if labels is None else list(labels)
    if len(labels) != len(runs):
        raise ValueError(f"`labels` must have one entry per run ({len(runs)}), got {len(labels)}")
    for run, label in zip(runs, labels):
        if np.ndim(run.energy_error) != 1:
            raise ValueError("`runs` must be single trajectories, got an ensemble")
        worst = np.maximum.accumulate(np.abs(run.energy_error[1:]))
        if isinstance(run, AdaptiveRun):
            style = ":"
        else:
            style = "--" if run.method.variables == "velocity" else "-"
        ax.plot(run.t[1:], np.where(worst > 0, worst, np.nan), style, lw=1.4, label=label)
    ax.set_yscale("log")
    ax.set(xlabel=axis_label("t"), ylabel="largest |E(s) − E(0)| for s ≤ t (J)")
    ax.legend(fontsize="small", ncols=2)
    return ax.figure


def plot_amplification(h_omega, factors: dict, limits: dict | None = None,
                       ax: Axes | None = None) -> Figure:
    """Growth factor per step of a small swing against ``h omega``, one line per method.

    Parameters
    ----------
    h_omega : array_like, shape (N,)
        Step times the oscillation's angular frequency.
    factors : dict
        ``{method name: amplification at each h_omega}``, shape (N,) each
        (:func:`pendulum_lab.analysis.amplification`); NaN where not computed.
    limits : dict, optional
        ``{method name: largest stable h omega}``; finite ones are marked by a
        dotted vertical line in the method's colour.
    ax : Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
        Above the line at 1 small swings grow step after step; on it they
        stay bounded.
    """
    ax = get_axes(ax, width=7.0, height=4.2)
    h_omega = np.asarray(h_omega, dtype=float)
    limits = {} if limits is None else limits
    # Methods can coincide on the oscillator (symplectic Euler and the leapfrog
    # do): each gets its own dash pattern, so none hides another.
    dashes = ["-", "--", "-.", (0, (7, 2)), (0, (3, 1, 1, 1, 1, 1))]
    for k, (name, values) in enumerate(factors.items()):
        values = np.asarray(values, dtype=float)
        if values.shape != h_omega.shape:
            raise ValueError(f"`factors[{name!r}]` must have the shape of `h_omega`, "
                             f"{h_omega.shape}, got {values.shape}")
        line = ax.plot(h_omega, values, ls=dashes[k % len(dashes)], lw=1.8, label=name)[0]
        limit = limits.get(name)
        if limit is not None and 0.0 < limit < np.inf:
            ax.axvline(limit, color=line.get_color(), ls=":", lw=1.0)
    ax.axhline(1.0, color="black", lw=0.8)
    ax.set(xlabel="h ω", ylabel="growth factor per step", ylim=(0.4, 1.6),
           xlim=(0.0, float(h_omega.max())),
           title="Small swings: growth per step (dotted: each method's stability limit)")
    ax.legend(fontsize="small", loc="upper left")
    return ax.figure


def plot_order(results, ax: Axes | None = None) -> Figure:
    """Global error against step size (log-log) with each fitted slope.

    Parameters
    ----------
    results : OrderResult or sequence of OrderResult
        From :func:`pendulum_lab.analysis.observed_order`.
    ax : Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
        Markers are the measured errors, dashed lines the least-squares fits
        ``log(error) = slope log(dt) + c``; the legend gives each method, the
        pendulum it was measured on and its slope.
    """
    if isinstance(results, OrderResult):
        results = [results]
    ax = get_axes(ax, width=6.0, height=4.2)
    for result in results:
        slope, intercept = np.polyfit(np.log(result.dts), np.log(result.errors), 1)
        where = "" if result.model is None else f", {pendulum_name(result.model)}"
        line = ax.loglog(
            result.dts, result.errors, "o", label=f"{result.method}{where}: slope {slope:.2f}"
        )[0]
        ax.loglog(
            result.dts, np.exp(intercept) * result.dts**slope, "--", lw=1, color=line.get_color()
        )
    ax.set(
        xlabel="step Δt (s)",
        ylabel="error at t_end, max over θ (rad), ω (rad/s)",
        title="Observed order of accuracy",
    )
    ax.legend(fontsize="small")
    return ax.figure


def plot_work_precision(points, x: str = "wall_time", ax: Axes | None = None,
                        y: str = "energy_error") -> Figure:
    """Error against cost, one line per method (a work-precision diagram).

    Parameters
    ----------
    points : sequence of WorkPrecision
    x : {"wall_time", "evaluations"}
        The cost axis.
    ax : Axes, optional
    y : {"energy_error", "state_error"}
        The error axis: the largest energy error of the run, or the global
        error of the state at the final time.

    Returns
    -------
    matplotlib.figure.Figure
        Lower left is better: less error for less work.
    """
    x = check.choice("x", x, ("wall_time", "evaluations"))
    y = check.choice("y", y, ("energy_error", "state_error"))
    ax = get_axes(ax, width=6.0, height=4.2)
    for name in dict.fromkeys(point.method for point in points):
        mine = [point for point in points if point.method == name and point.completed]
        style = ":" if name == "DOP853" else "-"
        ax.loglog(
            [getattr(point, x) for point in mine],
            [getattr(point, y) for point in mine],
            "o" + style,
            label=name,
        )
    ax.set(
        xlabel="wall time (s)" if x == "wall_time" else "vector-field evaluations",
        ylabel="max |E − E(0)| (J)" if y == "energy_error"
        else "global error at T, max |(θ, ω) − reference| (rad, rad/s)",
    )
    ax.legend(fontsize="small")
    return ax.figure


def plot_energy_comparison(comparison: EnergyComparison, ax: Axes | None = None) -> Figure:
    """``|E - E0| / |E0|`` against time, log scale, one line per method.

    Exact zeros are not drawn (a log axis cannot show them).

    Parameters
    ----------
    comparison : EnergyComparison
        From :func:`pendulum_lab.analysis.compare_energy`.
    ax : Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    ax = get_axes(ax, width=7.0, height=3.6)
    for name, traj in comparison.trajectories.items():
        err = np.abs(traj.relative_energy_error)
        ax.semilogy(traj.t, np.where(err > 0, err, np.nan), label=name, lw=1)
    ax.set(xlabel=axis_label("t"), ylabel="|E − E(0)| / |E(0)|")
    ax.legend(fontsize="small")
    return ax.figure


def plot_stage_contraction(iterations, ax: Axes | None = None, label: str = "") -> Figure:
    """Measured and predicted contraction per sweep against the step, log-log.

    Parameters
    ----------
    iterations : sequence of StageIteration
        From :func:`pendulum_lab.analysis.stage_contraction` at several steps.
    ax : Axes, optional
    label : str
        Names the state in the legend.
    """
    ax = get_axes(ax, width=6.0, height=4.2)
    if not iterations:
        raise ValueError("`iterations` must hold at least one StageIteration")
    dts = np.array([it.dt for it in iterations])
    measured = np.array([it.contraction for it in iterations])
    predicted = np.array([it.predicted for it in iterations])
    dots = ax.loglog(dts, measured, "o", label=f"measured{', ' + label if label else ''}")[0]
    ax.loglog(dts, predicted, "-", color=dots.get_color(), lw=1.0,
              label=f"h ρ(A) ρ(∂f/∂y){', ' + label if label else ''}")
    ax.set(xlabel="step h (s)", ylabel="contraction per sweep")
    ax.legend(fontsize="small")
    return ax.figure


def plot_energy_decay(decay, dt: float | None = None, ax: Axes | None = None) -> Figure:
    """Energy at the turning points over the reference's at the same times, from an ``EnergyDecay``.

    One line per method at step ``dt`` (the largest of ``decay.dt`` by
    default): the energy above rest at each highest point of the swing,
    divided by the reference's at that time (interpolated in its logarithm
    between the reference's own highest points). A method whose swings
    decay too slowly climbs above 1, too fast falls below; a wrong period
    alone moves the points sideways, not off 1.
    """
    from ..analysis.damping import turning_points

    ax = get_axes(ax, width=7.0, height=3.6)
    index = int(np.argmax(decay.dt)) if dt is None else int(np.argmin(np.abs(decay.dt - dt)))
    ref_times, ref_energies = turning_points(decay.model, decay.reference)
    for name in decay.methods:
        traj = decay.trajectories[name][index]
        times, energies = turning_points(decay.model, traj)
        inside = (times >= ref_times[0]) & (times <= ref_times[-1])
        envelope = np.exp(np.interp(times[inside], ref_times, np.log(ref_energies)))
        ax.plot(times[inside], energies[inside] / envelope, "o-", ms=3, lw=1.2,
                label=f"{name}, dt = {traj.dt:g} s")
    ax.axhline(1.0, color="k", lw=0.8, ls="--",
               label=f"reference ({decay.reference.method.name}, dt = {decay.reference.dt:g} s)")
    ax.set(xlabel="time of the turning point (s)", ylabel="energy above rest / reference's")
    ax.legend(fontsize="small")
    return ax.figure
