"""The headless study: every method on the simple and the double pendulum.

``pendulum-lab report --out DIR`` (or ``python -m pendulum_lab.app.report --out
DIR``) integrates each pendulum with each method, writes one energy-versus-time
figure per (pendulum, method) - the figure set of the course report
(Kanoun, Cowley, Ivachtchenko, MAT332, 2024), made with the corrected canonical
methods and, labelled as such, with the report's velocity-variable versions -
one overview of the energy errors per pendulum, and ``summary.md`` with a table
of energy drift, observed order, symplecticity defect and wall time.

The same study is available from Python as :func:`run_report`. Its runs and
table rows come from :func:`pendulum_lab.analysis.compare_methods` (which
notebook 09 calls too), its figures from :mod:`pendulum_lab.plotting` and its
table from :mod:`pendulum_lab.app.tables`; this module holds only the study's
output and its command.

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

from matplotlib.figure import Figure

from .. import analysis, plotting
from .. import validation as check
from ..driver.simulate import Trajectory
from ..integrators import METHODS, get_method
from ..model import double_pendulum, simple_pendulum
from ..version import __version__
from .tables import markdown_table

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


def _error_overview(trajectories: list[Trajectory], pendulum: str) -> Figure:
    """:func:`~pendulum_lab.plotting.plot_energy_error_growth` of every method on one pendulum."""
    fig = plotting.plot_energy_error_growth(trajectories)
    fig.axes[0].set_title(
        f"{pendulum.capitalize()} pendulum: energy error of each method\n"
        "(dashed: the course report's velocity-variable versions)"
    )
    return fig


def _save(fig: Figure, path: Path) -> Path:
    fig.savefig(path)
    return path


def _check_times(t_end, dt) -> tuple[float, float]:
    dt = check.positive_number("dt", dt)
    t_end = check.positive_number("t_end", t_end)
    if t_end < 10 * dt:
        raise ValueError(
            f"`t_end` must be at least 10 steps of dt = {dt:g} "
            f"(the energy drift compares tenths of the run), got {t_end:g}"
        )
    return t_end, dt


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
    methods = check.choices("methods", methods, METHODS)
    pendulums = check.choices("pendulums", pendulums, PENDULUMS)
    out = check.output_folder("out", out)

    start = time.perf_counter()
    problems = []
    for pendulum in pendulums:
        factory, theta0 = PENDULUMS[pendulum]
        model = factory()
        problems.append((model, theta0, (0.0,) * model.n))
    study = analysis.compare_methods(problems, methods, t_end=t_end, dt=dt, progress=progress)
    figures = []
    for pendulum, done in study.trajectories.items():
        for traj in done:
            name = traj.method.name
            figures.append(
                _save(_energy_figure(traj, pendulum), out / f"energy_{pendulum}_{name}.png")
            )
        if done:
            figures.append(
                _save(_error_overview(done, pendulum), out / f"energy_error_{pendulum}.png")
            )
    rows, failures = study.rows, study.failures
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
        markdown_table(rows).rstrip(),
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
        return check.positive_number("value", float(text))
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a positive number, got {text!r}") from None


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
    """The stand-alone parser of ``python -m pendulum_lab.app.report``."""
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
    except OSError as err:  # the folder was writable, a file in it was not
        args.report_parser.error(f"could not write the report into {str(args.out)!r}: {err}")
    print(f"wrote {len(result.figures)} figures and {result.summary} in {result.elapsed:.1f} s")
    for pendulum, method, message in result.failures:
        print(f"warning: {pendulum} / {method} failed: {message}", file=sys.stderr)
    return 0


def main(argv=None) -> int:
    """Entry point of ``python -m pendulum_lab.app.report``."""
    args = build_parser().parse_args(argv)
    return args.handler(args)


if __name__ == "__main__":
    sys.exit(main())
