"""The headless study: every method on the simple and the double pendulum.

``pendulum-lab report --out DIR`` (or ``python -m pendulum_lab.report --out
DIR``) integrates each pendulum with each method, writes one energy-versus-time
figure per (pendulum, method) - the figure set of the course report
(Kanoun, Cowley, Ivachtchenko, MAT332, 2024), made with the corrected canonical
methods and, labelled as such, with the report's velocity-variable versions -
one overview of the energy errors per pendulum, and ``summary.md`` with a table
of energy drift, observed order, symplecticity defect and wall time.

The same study is available from Python as :func:`run_report`, and its figures
as functions the course notebooks use: :func:`plot_order` (error against step,
with the fitted slopes), :func:`plot_energy_error_growth` (the running maximum
of the energy error over a long run) and :func:`plot_work_precision` (energy
error against evaluations or wall time).

Examples
--------
>>> import tempfile
>>> from pendulum_lab import report
>>> with tempfile.TemporaryDirectory() as out:
...     result = report.run_report(out, t_end=0.5, methods=["rk4"], pendulums=["simple"],
...                                progress=False)
...     sorted(p.name for p in result.figures)
['energy_error_simple.png', 'energy_simple_rk4.png']
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from . import __version__, analysis, plotting
from .integrators import METHODS, ConvergenceError, get_method
from .model import double_pendulum, simple_pendulum
from .simulate import Trajectory, simulate

__all__ = [
    "DEFAULT_DT",
    "DEFAULT_T_END",
    "PENDULUMS",
    "QUICK_T_END",
    "ReportResult",
    "add_arguments",
    "add_report_command",
    "build_parser",
    "main",
    "plot_energy_error_growth",
    "plot_order",
    "plot_work_precision",
    "run_from_args",
    "run_report",
    "settings_from_args",
]

#: Length of the runs [s]: long enough that a drifting energy error visibly
#: grows from the first to the last tenth of the run, and the whole study
#: (14 runs of 20,000 steps, order fits, figures) takes seconds.
DEFAULT_T_END = 200.0
#: ``--quick``: a smoke run.
QUICK_T_END = 20.0
DEFAULT_DT = 0.01
#: name -> (model factory, initial angles [rad]); the runs start at rest.
PENDULUMS = {
    "simple": (simple_pendulum, (2.0,)),
    "double": (double_pendulum, (2.0, 2.5)),
}
DPI = 100


@dataclass(frozen=True)
class ReportResult:
    """What :func:`run_report` wrote.

    Attributes
    ----------
    out : Path
        The output folder.
    rows : list of ComparisonRow
        One per (pendulum, method) that ran, in run order.
    failures : list of (str, str, str)
        ``(pendulum, method, message)`` for runs whose implicit equations did
        not converge.
    figures : list of Path
        The PNG files.
    summary : Path
        ``summary.md``.
    elapsed : float
        Seconds for the whole study.
    """

    out: Path
    rows: list
    failures: list
    figures: list
    summary: Path
    elapsed: float


def _label(method) -> str:
    method = get_method(method)
    if method.variables == "velocity":
        return f"{method.name} (the course report's version, in (theta, omega))"
    return f"{method.name} (canonical, in (theta, p))"


def _energy_figure(traj: Trajectory, pendulum: str) -> Figure:
    """Kinetic, potential and total energy over time, and the total's error."""
    fig = Figure(figsize=(8, 5.5), dpi=DPI, layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True, height_ratios=(3, 2))
    plotting.plot_energy(traj, ax=top)
    top.set(title="", xlabel="")
    bottom.plot(traj.t, traj.energy_error, lw=0.8, color=plotting.TOTAL)
    bottom.axhline(0.0, color="grey", lw=0.5)
    bottom.set(xlabel="t (s)", ylabel="E(t) - E(0) (J)")
    stopped = "" if traj.completed else ", stopped early: state not finite"
    fig.suptitle(
        f"{pendulum.capitalize()} pendulum: {_label(traj.method)}\n"
        f"dt = {traj.dt:g} s, E(0) = {traj.energy[0]:.4g} J{stopped}"
    )
    return fig


# --------------------------------------------------------------------------- figures of the study
def _axes(ax, **figure_kw):
    if ax is None:
        return plotting.new_figure(**figure_kw)[1]
    if not isinstance(ax, Axes):
        raise TypeError(f"`ax` must be a matplotlib Axes or None, got {type(ax).__name__}")
    return ax


def _run_label(run) -> str:
    if isinstance(run, analysis.ReferenceRun):
        return f"DOP853, rtol = {run.rtol:g}"
    return run.method.name


def plot_energy_error_growth(runs, ax: Axes | None = None, labels=None) -> Figure:
    """The largest energy error so far, ``max_{s <= t} |E(s) - E(0)|``, on a log scale.

    The running maximum is flat once a bounded error has reached its bound
    and keeps rising for a drifting one; the raw error oscillates too fast to
    read over a long run. The course report's velocity-variable methods are
    dashed, DOP853 dotted.

    Parameters
    ----------
    runs : sequence of Trajectory or analysis.ReferenceRun
        Single trajectories.
    ax : Axes, optional
    labels : sequence of str, optional
        Legend entries; by default the method names.

    Returns
    -------
    matplotlib.figure.Figure
    """
    ax = _axes(ax, width=8.0, height=4.2)
    labels = [_run_label(run) for run in runs] if labels is None else list(labels)
    if len(labels) != len(runs):
        raise ValueError(f"`labels` must have one entry per run ({len(runs)}), got {len(labels)}")
    for run, label in zip(runs, labels):
        if np.ndim(run.energy_error) != 1:
            raise ValueError("`runs` must be single trajectories, got an ensemble")
        worst = np.maximum.accumulate(np.abs(run.energy_error[1:]))
        if isinstance(run, analysis.ReferenceRun):
            style = ":"
        else:
            style = "--" if run.method.variables == "velocity" else "-"
        ax.plot(run.t[1:], np.where(worst > 0, worst, np.nan), style, lw=1.4, label=label)
    ax.set_yscale("log")
    ax.set(xlabel="t (s)", ylabel="largest |E(s) - E(0)| for s <= t (J)")
    ax.legend(fontsize="small", ncols=2)
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
        ``log(error) = slope log(dt) + c``; the legend gives each slope.
    """
    if isinstance(results, analysis.OrderResult):
        results = [results]
    ax = _axes(ax, width=6.0, height=4.2)
    for result in results:
        slope, intercept = np.polyfit(np.log(result.dts), np.log(result.errors), 1)
        line = ax.loglog(
            result.dts, result.errors, "o", label=f"{result.method}: slope {slope:.2f}"
        )[0]
        ax.loglog(
            result.dts, np.exp(intercept) * result.dts**slope, "--", lw=1, color=line.get_color()
        )
    ax.set(
        xlabel="step size dt (s)",
        ylabel="error at the final time",
        title="Observed order of accuracy",
    )
    ax.legend(fontsize="small")
    return ax.figure


def plot_work_precision(points, x: str = "wall_time", ax: Axes | None = None) -> Figure:
    """Energy error against cost, one line per method (a work-precision diagram).

    Parameters
    ----------
    points : sequence of analysis.WorkPrecision
    x : {"wall_time", "evaluations"}
        The cost axis.
    ax : Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
        Lower left is better: less error for less work.
    """
    if x not in ("wall_time", "evaluations"):
        raise ValueError(f"`x` must be 'wall_time' or 'evaluations', got {x!r}")
    ax = _axes(ax, width=6.0, height=4.2)
    for name in dict.fromkeys(point.method for point in points):
        mine = [point for point in points if point.method == name and point.completed]
        style = ":" if name == "DOP853" else "-"
        ax.loglog(
            [getattr(point, x) for point in mine],
            [point.energy_error for point in mine],
            "o" + style,
            label=name,
        )
    ax.set(
        xlabel="wall time (s)" if x == "wall_time" else "vector-field evaluations",
        ylabel="max |E - E(0)| (J)",
    )
    ax.legend(fontsize="small")
    return ax.figure


def _error_overview(trajectories: list[Trajectory], pendulum: str) -> Figure:
    """:func:`plot_energy_error_growth` of every method on one pendulum."""
    fig = plot_energy_error_growth(trajectories)
    fig.axes[0].set_title(
        f"{pendulum.capitalize()} pendulum: energy error of each method\n"
        "(dashed: the course report's velocity-variable versions)"
    )
    return fig


def _save(fig: Figure, path: Path) -> Path:
    fig.savefig(path)
    return path


def _check_choices(name: str, values, allowed) -> tuple[str, ...]:
    if isinstance(values, str):
        values = [values]
    values = tuple(dict.fromkeys(values))  # drop repeats, keep order
    if not values:
        raise ValueError(f"`{name}` must name at least one of {list(allowed)}")
    for value in values:
        if value not in allowed:
            raise ValueError(f"`{name}` must be among {list(allowed)}, got {value!r}")
    return values


def _check_times(t_end, dt) -> tuple[float, float]:
    for name, value in (("t_end", t_end), ("dt", dt)):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise TypeError(f"`{name}` must be a real number, got {type(value).__name__}")
        if not np.isfinite(value) or value <= 0:
            raise ValueError(f"`{name}` must be a positive number, got {value}")
    if t_end < 10 * dt:
        raise ValueError(
            f"`t_end` must be at least 10 steps of dt = {dt:g} "
            f"(the energy drift compares tenths of the run), got {t_end:g}"
        )
    return float(t_end), float(dt)


def run_report(
    out,
    *,
    t_end: float = DEFAULT_T_END,
    dt: float = DEFAULT_DT,
    methods=tuple(METHODS),
    pendulums=tuple(PENDULUMS),
    progress: bool = True,
) -> ReportResult:
    """Run the study and write figures and ``summary.md`` into ``out``.

    Parameters
    ----------
    out : str or Path
        Output folder; created if missing. Existing files of the same names
        are overwritten.
    t_end : float
        Length of each run [s], at least ``10 * dt``.
    dt : float
        Step size [s], ``> 0``.
    methods : sequence of str
        Keys of :data:`pendulum_lab.METHODS`; all of them by default.
    pendulums : sequence of str
        Keys of :data:`PENDULUMS`.
    progress : bool
        Show a console progress bar (on standard error).

    Returns
    -------
    ReportResult
    """
    t_end, dt = _check_times(t_end, dt)
    methods = _check_choices("methods", methods, METHODS)
    pendulums = _check_choices("pendulums", pendulums, PENDULUMS)
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise ValueError(f"`out` must be a folder, but {str(out)!r} is a file")
    out.mkdir(parents=True, exist_ok=True)

    from tqdm.auto import tqdm

    start = time.perf_counter()
    rows, failures, figures = [], [], []
    bar = tqdm(
        total=len(pendulums) * len(methods), disable=not progress, unit="run", file=sys.stderr
    )
    try:
        for pendulum in pendulums:
            factory, theta0 = PENDULUMS[pendulum]
            model = factory()
            omega0 = (0.0,) * model.n
            # one DOP853 reference for the order fits of all methods
            reference = analysis.reference_solution(model, theta0, omega0, 1.0)
            done = []
            for name in methods:
                bar.set_description(f"{pendulum} {name}")
                try:
                    traj = simulate(
                        model, theta0, omega0, t_end=t_end, dt=dt, method=name, progress=False
                    )
                except ConvergenceError as err:
                    failures.append((pendulum, name, str(err)))
                    bar.update(1)
                    continue
                rows.append(analysis.compare_trajectory(model, traj, reference=reference))
                figures.append(
                    _save(_energy_figure(traj, pendulum), out / f"energy_{pendulum}_{name}.png")
                )
                done.append(traj)
                bar.update(1)
            if done:
                figures.append(
                    _save(_error_overview(done, pendulum), out / f"energy_error_{pendulum}.png")
                )
    finally:
        bar.close()
    elapsed = time.perf_counter() - start
    summary = out / "summary.md"
    summary.write_text(
        _summary_text(rows, failures, figures, out, t_end, dt, elapsed), encoding="utf-8"
    )
    return ReportResult(out, rows, failures, figures, summary, elapsed)


def _summary_text(rows, failures, figures, out: Path, t_end, dt, elapsed) -> str:
    starts = ", ".join(
        f"{name} pendulum theta0 = {tuple(PENDULUMS[name][1])} rad"
        for name in dict.fromkeys(r.pendulum for r in rows)
    )
    lines = [
        "# Integrator study: energy, order, structure",
        "",
        f"pendulum_lab {__version__}. Each run: t_end = {t_end:g} s, dt = {dt:g} s, "
        f"starting at rest ({starts or 'no run completed'}); "
        "unit masses and lengths, g = 9.81 m/s^2.",
        "",
        "Methods in canonical variables (theta, p) are the corrected ones; the two "
        "`*_velocity` methods are the course report's versions, stepping (theta, omega) "
        "(Kanoun, Cowley, Ivachtchenko, MAT332, 2024).",
        "",
        "Columns: *observed order* is the fitted log-log slope of the error at t = 1 s "
        f"against dt in {analysis.ORDER_DTS} ({analysis.HIGH_ORDER_DTS} for order 8), versus "
        "a DOP853 reference; "
        "*max abs(dE)* in the first and last tenth of the run compares early and late "
        "energy errors (a ratio near 1 means bounded, a growing one drift); "
        "*symplecticity defect* is max |Psi^T J Psi - J| for the Jacobian Psi of one step "
        "of 0.1 s in (theta, p) from the initial state (about 1e-10 means symplectic to "
        "the accuracy of the finite differences); *reversibility error* is the distance "
        "after one step forward and one back; *wall time* is the stepping time of the run.",
        "",
        analysis.markdown_table(rows).rstrip(),
        "",
    ]
    if any(not r.completed for r in rows):
        stopped = ", ".join(f"{r.pendulum}/{r.method}" for r in rows if not r.completed)
        lines += [f"Stopped early at a non-finite state: {stopped}.", ""]
    if failures:
        lines += ["## Runs that failed", ""]
        lines += [f"- {p} / {m}: {msg}" for p, m, msg in failures]
        lines.append("")
    lines += ["## Figures", ""]
    lines += [f"![{path.stem}]({path.relative_to(out).as_posix()})" for path in figures]
    lines += ["", f"The study took {elapsed:.1f} s.", ""]
    return "\n".join(lines)


# --------------------------------------------------------------------------- command line
DESCRIPTION = (
    "Run the integrator study headless: for each pendulum and method an energy-versus-time "
    "figure (PNG), and summary.md with energy drift, observed order, symplecticity defect "
    "and wall time."
)


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a positive number, got {text!r}") from None
    if not np.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"must be a positive number, got {text!r}")
    return value


def add_arguments(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """Add the report's options to ``parser`` and make it run the report."""
    parser.add_argument(
        "--out",
        required=True,
        type=Path,
        metavar="DIR",
        help="folder for the figures and summary.md (created if missing)",
    )
    length = parser.add_mutually_exclusive_group()
    length.add_argument(
        "--t-end",
        type=_positive_float,
        default=None,
        metavar="T",
        help=f"length of each run in seconds (default {DEFAULT_T_END:g})",
    )
    length.add_argument(
        "--quick", action="store_true", help=f"a short smoke run: --t-end {QUICK_T_END:g}"
    )
    parser.add_argument(
        "--dt",
        type=_positive_float,
        default=DEFAULT_DT,
        metavar="DT",
        help=f"step size in seconds (default {DEFAULT_DT:g})",
    )
    parser.add_argument(
        "--methods",
        nargs="+",
        choices=list(METHODS),
        default=list(METHODS),
        metavar="METHOD",
        help="methods to run (default: all): " + ", ".join(METHODS),
    )
    parser.add_argument(
        "--pendulums",
        nargs="+",
        choices=list(PENDULUMS),
        default=list(PENDULUMS),
        metavar="NAME",
        help="pendulums to run (default: all): " + ", ".join(PENDULUMS),
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.set_defaults(handler=run_from_args, report_parser=parser)
    return parser


def add_report_command(subparsers) -> argparse.ArgumentParser:
    """Register ``report`` on the ``subparsers`` of a larger command line.

    The parsed namespace's ``handler`` attribute is :func:`run_from_args`.
    """
    parser = subparsers.add_parser(
        "report", help="run the integrator study headless", description=DESCRIPTION
    )
    return add_arguments(parser)


def build_parser(prog: str = "pendulum-lab report") -> argparse.ArgumentParser:
    """The stand-alone parser of ``python -m pendulum_lab.report``."""
    return add_arguments(argparse.ArgumentParser(prog=prog, description=DESCRIPTION))


def settings_from_args(args: argparse.Namespace) -> dict:
    """The keyword arguments of :func:`run_report` that parsed arguments ask for."""
    t_end = QUICK_T_END if args.quick else (args.t_end or DEFAULT_T_END)
    return {
        "out": args.out,
        "t_end": t_end,
        "dt": args.dt,
        "methods": args.methods,
        "pendulums": args.pendulums,
        "progress": not args.no_progress,
    }


def run_from_args(args: argparse.Namespace) -> int:
    """Run the report from parsed arguments; returns the exit status."""
    try:
        result = run_report(**settings_from_args(args))
    except ValueError as err:
        args.report_parser.error(str(err))  # exits with status 2
    print(f"wrote {len(result.figures)} figures and {result.summary} in {result.elapsed:.1f} s")
    for pendulum, method, message in result.failures:
        print(f"warning: {pendulum} / {method} failed: {message}", file=sys.stderr)
    return 0


def main(argv=None) -> int:
    """Entry point of ``python -m pendulum_lab.report``."""
    args = build_parser().parse_args(argv)
    return args.handler(args)


if __name__ == "__main__":
    sys.exit(main())
