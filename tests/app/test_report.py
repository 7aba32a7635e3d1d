"""The headless report: files, the summary table, its numbers, and argument errors."""

import re
from pathlib import Path

import matplotlib.image
import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab import analysis, plotting, report, source, tables

pytestmark = pytest.mark.plumbing  # the report's wiring: not again at the floors

T_END, DT = 2.0, 0.01
METHODS = tuple(pl.METHODS)
# from the declarations: the methods symplectic in the variables the report runs them in
SYMPLECTIC_IN_P = tuple(name for name, method in pl.METHODS.items()
                        if method.symplectic and method.variables == "canonical")


def parse_table(text):
    """The rows of the first Markdown table in ``text`` as dicts of header -> cell."""
    lines = [line for line in text.splitlines() if line.startswith("|")]
    header = [cell.strip() for cell in lines[0].strip("|").split("|")]
    assert set(lines[1].replace("|", "")) == {"-"}
    return [
        dict(zip(header, (c.strip() for c in line.strip("|").split("|")))) for line in lines[2:]
    ]


@pytest.fixture(scope="module")
def short_report(tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    status = report.main(
        ["--out", str(out), "--t-end", str(T_END), "--dt", str(DT), "--no-progress"]
    )
    return status, out, parse_table((out / "summary.md").read_text())


def test_short_run_writes_every_figure_and_the_summary(short_report):
    status, out, _ = short_report
    assert status == 0
    expected = {f"energy_{p}_{m}.png" for p in report.PENDULUMS for m in METHODS}
    expected |= {f"energy_error_{p}.png" for p in report.PENDULUMS}
    assert {path.name for path in out.glob("*.png")} == expected
    for name in expected:
        image = matplotlib.image.imread(out / name)
        assert image.ndim == 3 and image.shape[0] > 300 and image.shape[1] > 500
        assert np.ptp(image[..., :3]) > 0.5  # something is drawn, not a blank canvas
    summary = (out / "summary.md").read_text()
    for name in expected:
        assert f"]({name})" in summary


def test_summary_has_one_row_per_pendulum_and_method(short_report):
    _, _, rows = short_report
    assert [(r["pendulum"], r["method"]) for r in rows] == [
        (p, m) for p in report.PENDULUMS for m in METHODS
    ]


def row(rows, pendulum, method):
    (found,) = [r for r in rows if r["pendulum"] == pendulum and r["method"] == method]
    return found


def test_order_column_matches_the_analysis_function(short_report):
    _, _, rows = short_report
    dp = pl.double_pendulum()
    theta0 = report.PENDULUMS["double"][1]
    for name, nominal in (("rk4", 4), ("leapfrog", 2), ("leapfrog_velocity", 2)):
        fit = analysis.observed_order(dp, theta0, [0.0, 0.0], t_end=1.0,
                                      dts=analysis.ORDER_DTS, method=name)
        assert row(rows, "double", name)["observed order"] == f"{fit.slope:.2f}"
        if name == "leapfrog_velocity":
            # negative control: the report's leapfrog loses an order on the double pendulum
            assert abs(fit.slope - 1.0) < 0.15
        else:
            assert abs(fit.slope - nominal) < 0.15


def test_energy_columns_match_a_fresh_run(short_report):
    _, _, rows = short_report
    for pendulum, (factory, theta0) in report.PENDULUMS.items():
        model = factory()
        for name in ("rk4", "leapfrog_velocity"):
            traj = pl.simulate(model, theta0, [0.0] * model.n, t_end=T_END, dt=DT, method=name)
            first, last = analysis.energy_growth(traj)
            found = row(rows, pendulum, name)
            assert found["max abs(dE), first tenth"] == f"{first:.2e}"
            assert found["max abs(dE), last tenth"] == f"{last:.2e}"


def test_symplecticity_column_separates_the_methods(short_report):
    _, _, rows = short_report
    defects = {
        r["method"]: float(r["symplecticity defect"]) for r in rows if r["pendulum"] == "double"
    }
    worst_symplectic = max(defects[name] for name in SYMPLECTIC_IN_P)
    assert worst_symplectic < 1e-8
    for name in set(METHODS) - set(SYMPLECTIC_IN_P):  # negative control
        assert defects[name] > 100 * max(worst_symplectic, 1e-9)


def test_implicit_failure_is_reported_not_fatal(tmp_path):
    with pytest.warns(RuntimeWarning, match="non-finite"):  # rk4 blows up at this dt
        result = report.run_report(
            tmp_path,
            t_end=6.0,
            dt=0.6,
            methods=["glrk4", "rk4"],
            pendulums=["double"],
            progress=False,
        )
    assert [(p, m) for p, m, _ in result.failures] == [("double", "glrk4")]
    assert [(r.method, r.completed) for r in result.rows] == [("rk4", False)]
    summary = result.summary.read_text()
    assert "## Runs that failed" in summary and re.search(r"glrk4: .*step \d+", summary)
    assert "Stopped early at a non-finite state: double/rk4." in summary
    assert not (tmp_path / "energy_double_glrk4.png").exists()


def test_progress_bar_goes_to_stderr(tmp_path, capsys):
    report.run_report(tmp_path, t_end=0.5, methods=["rk4"], pendulums=["simple"], progress=True)
    assert "1/1" in capsys.readouterr().err
    report.run_report(tmp_path, t_end=0.5, methods=["rk4"], pendulums=["simple"], progress=False)
    assert "1/1" not in capsys.readouterr().err


def test_defaults_and_quick():
    parser = report.build_parser()
    settings = report.settings_from_args(parser.parse_args(["--out", "x"]))
    assert settings["t_end"] == report.DEFAULT_T_END and settings["dt"] == report.DEFAULT_DT
    assert settings["methods"] == list(pl.METHODS)
    assert settings["pendulums"] == list(report.PENDULUMS)
    quick = report.settings_from_args(parser.parse_args(["--out", "x", "--quick"]))
    assert quick["t_end"] == report.QUICK_T_END < report.DEFAULT_T_END


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--dt", "-0.1"], "argument --dt: must be a positive number"),
        (["--t-end", "abc"], "argument --t-end: must be a positive number"),
        (["--methods", "euler"], "argument --methods: invalid choice: 'euler'"),
        (["--pendulums", "triple"], "argument --pendulums: invalid choice: 'triple'"),
        (["--quick", "--t-end", "5"], "not allowed with argument"),
        (["--t-end", "0.05"], "`t_end` must be at least 10 steps of dt = 0.01"),
    ],
)
def test_bad_arguments_exit_with_a_clear_message(tmp_path, capsys, argv, message):
    with pytest.raises(SystemExit) as exit_info:
        report.main(["--out", str(tmp_path / "out"), "--no-progress", *argv])
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "out" / "summary.md").exists()


def test_out_must_be_given_and_be_a_folder(tmp_path, capsys):
    with pytest.raises(SystemExit):
        report.main([])
    assert "--out" in capsys.readouterr().err
    a_file = tmp_path / "file.txt"
    a_file.write_text("not a folder")
    with pytest.raises(SystemExit):
        report.main(["--out", str(a_file), "--t-end", "0.5", "--no-progress"])
    assert "is a file" in capsys.readouterr().err


@pytest.mark.parametrize("where", ["proc", "inside_a_file"])
def test_an_out_folder_that_cannot_be_made_gives_a_message_not_a_traceback(
    tmp_path, capsys, where
):
    if where == "proc":
        if not Path("/proc").is_dir():
            pytest.skip("no /proc on this system")
        out = "/proc/nope"
    else:
        (tmp_path / "file.txt").write_text("not a folder")
        out = str(tmp_path / "file.txt" / "figures")
    with pytest.raises(SystemExit) as exit_info:
        report.main(["--out", out, "--quick", "--no-progress"])
    err = capsys.readouterr().err
    assert exit_info.value.code == 2
    assert f"`out` must be a folder that can be created, but '{out}' cannot be" in err
    assert "Traceback" not in err
    with pytest.raises(ValueError, match="`out` must be a folder that can be created"):
        report.run_report(out, t_end=0.5, methods=["rk4"], pendulums=["simple"], progress=False)
    # negative control: a folder that can be made is made, and nothing is refused
    assert report.main(["--out", str(tmp_path / "fine"), "--t-end", "0.5", "--methods", "rk4",
                        "--pendulums", "simple", "--no-progress"]) == 0
    assert (tmp_path / "fine" / "summary.md").is_file()


def test_python_api_names_the_bad_argument(tmp_path):
    with pytest.raises(ValueError, match="`methods` must be among"):
        report.run_report(tmp_path, methods=["rk5"])
    with pytest.raises(ValueError, match="`pendulums` must be among"):
        report.run_report(tmp_path, pendulums=["triple"])
    with pytest.raises(ValueError, match="`dt` must be a positive number"):
        report.run_report(tmp_path, dt=0.0)
    with pytest.raises(TypeError, match="`t_end` must be a real number"):
        report.run_report(tmp_path, t_end="long")


# ---------------------------------------------------------------- the analysis helpers it uses
#: The longest text method_source may show for one method, helpers included ("about 40").
MAX_SOURCE_LINES = 45
#: A composition shows its base method's step and, on top, its own loop over the substeps
#: and their list.
COMPOSITION_LINES = 15


@pytest.mark.parametrize("name", [*pl.METHODS, *pl.CONFORMAL_METHODS, *pl.VARIATIONAL_METHODS])
def test_method_source_is_the_reference_step_with_its_helpers(name):
    """What a notebook shows is the method's reference step, the one its kernel is tested on.

    ``Method.reference`` is the step that tests/integrators/test_reference_steps.py compares
    the compiled kernel with; method_source shows its source (after a comment naming the
    tableau or rule it is bound to), then the reference functions it calls.
    """
    import functools
    import inspect
    import itertools

    method = pl.get_method(name)
    step = method.reference
    function = step.func if isinstance(step, functools.partial) else step
    text = source.method_source(name, helpers=True)
    own = inspect.getsource(function).rstrip()
    header = list(itertools.takewhile(lambda line: line.startswith("#"), text.splitlines()))
    code = "\n".join(text.splitlines()[len(header):])
    assert code.startswith(own)
    if isinstance(step, functools.partial):
        assert text.startswith(f"# {name}: {function.__name__}(")
    extra = 0 if method.composition is None else len(header) + COMPOSITION_LINES
    assert len(text.splitlines()) <= MAX_SOURCE_LINES + extra
    # the helpers: the fixed-point solver (with the stopping rule) of every implicit method
    solver = "def fixed_point("
    assert (solver in text) is method.implicit  # negative control: explicit ones have none
    # By default the step alone, then a line naming what it calls (the solver is not the
    # lesson); the same start as with the helpers.
    alone = source.method_source(name)
    assert solver not in alone and text.startswith(alone.rsplit("\n# It calls", 1)[0])
    assert ("fixed_point, shown by" in alone or "and fixed_point, shown by" in alone) is \
        method.implicit
    # negative control: not the compiled kernel (that is tested against this, not shown)
    compiled = inspect.getsource(method.kernel.py_func).strip().splitlines()[0]
    assert compiled not in text


def test_method_source_shows_the_formula():
    assert "y1 = y + h * field.f(t, y)" in source.method_source("explicit_euler")
    assert "p_half - h / 2 * field.H_q(t + h, q1, p_half)" in source.method_source("leapfrog")
    assert "<the Butcher tableau of glrk4, 2 stages>" in source.method_source("glrk4")
    with pytest.raises(ValueError, match="`method` must be one of"):
        source.method_source("midpoint")


def test_velocity_method_source_uses_the_acceleration():
    text = source.method_source("leapfrog_velocity")
    assert "field.acceleration(t + h, q1, v_half)" in text and "hamilton" not in text
    assert "field.acceleration" not in source.method_source("leapfrog")  # negative control


def test_windowed_energy_error_takes_the_maximum_in_each_window():
    traj = pl.simulate(
        pl.double_pendulum(), [2.0, 2.5], [0.0, 0.0], t_end=4.0, dt=0.01, method="leapfrog_velocity"
    )
    windows = analysis.windowed_energy_error(traj, [0.0, 1.0, 4.0])
    err = np.abs(traj.energy_error)
    assert windows[0] == err[traj.t <= 1.0].max()
    assert windows[1] == err[traj.t >= 1.0].max()
    with pytest.raises(ValueError, match="increasing"):
        analysis.windowed_energy_error(traj, [1.0, 0.5])
    with pytest.raises(ValueError, match=r"must lie in \[0, 4\]"):
        analysis.windowed_energy_error(traj, [0.0, 10.0])


def test_work_precision_of_rk4_and_dop853():
    dp = pl.double_pendulum()
    rk4 = analysis.work_precision(dp, [1.0, 1.5], [0.0, 0.0], t_end=2.0, dts=[0.02, 0.01],
                                  method="rk4")
    assert [p.evaluations for p in rk4] == [4 * 100, 4 * 200]
    # energy error of a fourth-order method: about 2^4 smaller at half the step
    assert 8 < rk4[0].energy_error / rk4[1].energy_error < 32
    dop = analysis.dop853_work_precision(dp, [1.0, 1.5], [0.0, 0.0], t_end=2.0,
                                          rtols=[1e-5, 1e-10])
    assert dop[1].energy_error < 1e-3 * dop[0].energy_error
    assert dop[1].evaluations > dop[0].evaluations
    with pytest.raises(ValueError, match="`rtol` must be in"):
        analysis.scipy_run(dp, [1.0, 1.5], [0.0, 0.0], t_end=1.0, rtol=1.0)


def test_markdown_table_rejects_a_column_the_rows_lack():
    rows = analysis.work_precision(pl.simple_pendulum(), [1.0], [0.0], t_end=0.2, dts=[0.1],
                                   method="rk4")
    text = tables.markdown_table(rows, [("dt", "setting", "{:g}")])
    assert text.splitlines()[2] == "| 0.1 |"
    with pytest.raises(ValueError, match="no attribute 'pendulum'"):
        tables.markdown_table(rows)


# ---------------------------------------------------------------- the study's figures
def test_plot_order_shows_the_points_and_each_fitted_slope():
    result = analysis.observed_order(
        pl.simple_pendulum(), [1.0], [0.0], t_end=1.0, dts=analysis.ORDER_DTS, method="rk4"
    )
    ax = plotting.plot_order(result).axes[0]
    assert [t.get_text() for t in ax.get_legend().get_texts()] == [
        f"rk4, simple pendulum: slope {result.slope:.2f}"
    ]
    points, fit = ax.lines
    assert np.array_equal(points.get_xdata(), result.dts)
    assert np.array_equal(points.get_ydata(), result.errors)
    # a clean fourth-order power law: the fitted line runs through the points
    assert np.allclose(np.log(fit.get_ydata()), np.log(result.errors), atol=0.1)


def test_plot_energy_error_growth_draws_the_running_maximum():
    dp = pl.double_pendulum()
    runs = [
        pl.simulate(dp, [2.0, 2.5], [0.0, 0.0], t_end=2.0, dt=0.01, method=name)
        for name in ("leapfrog", "leapfrog_velocity")
    ]
    runs.append(analysis.scipy_run(dp, [2.0, 2.5], [0.0, 0.0], t_end=2.0, rtol=1e-6))
    ax = plotting.plot_energy_error_growth(runs).axes[0]
    assert [line.get_linestyle() for line in ax.lines] == ["-", "--", ":"]
    for line, run in zip(ax.lines, runs):
        expected = np.maximum.accumulate(np.abs(run.energy_error[1:]))
        assert np.array_equal(line.get_ydata(), expected)
        assert np.all(np.diff(line.get_ydata()) >= 0)
    assert ax.get_yscale() == "log"
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == ["leapfrog", "leapfrog_velocity", "DOP853, rtol 1e-06"]
    with pytest.raises(ValueError, match="one entry per run"):
        plotting.plot_energy_error_growth(runs, labels=["only one"])


def test_plot_work_precision_one_line_per_method():
    sp = pl.simple_pendulum()
    points = analysis.work_precision(sp, [1.0], [0.0], t_end=1.0, dts=[0.1, 0.05], method="rk4",
                                     repeats=2)
    points += analysis.work_precision(sp, [1.0], [0.0], t_end=1.0, dts=[0.1, 0.05],
                                      method="leapfrog")
    ax = plotting.plot_work_precision(points, x="evaluations").axes[0]
    assert [line.get_label() for line in ax.lines] == ["rk4", "leapfrog"]
    assert list(ax.lines[0].get_xdata()) == [40, 80]
    assert list(ax.lines[1].get_ydata()) == [p.energy_error for p in points[2:]]
    with pytest.raises(ValueError, match="`x` must be 'wall_time' or 'evaluations'"):
        plotting.plot_work_precision(points, x="steps")
    with pytest.raises(ValueError, match="`repeats` must be an integer >= 1"):
        analysis.work_precision(sp, [1.0], [0.0], t_end=1.0, dts=[0.1], method="rk4", repeats=0)


def test_work_precision_measures_the_global_error_against_the_reference():
    dp = pl.double_pendulum()
    start = ([1.0, 1.5], [0.0, 0.0])
    reference = analysis.reference_solution(dp, *start, t_end=2.0)
    rk4 = analysis.work_precision(dp, *start, t_end=2.0, dts=[0.02, 0.01], method="rk4",
                                  reference=reference)
    # the global error at T of a fourth-order method: 2^4 smaller at half the step
    assert 10 < rk4[0].state_error / rk4[1].state_error < 24
    by_hand = pl.simulate(dp, *start, t_end=2.0, dt=0.01, method="rk4")
    assert rk4[1].state_error == analysis.global_error(by_hand.theta[-1], by_hand.omega[-1],
                                                       reference)
    # Negative control: a second-order method's error only falls 2^2 per halving.
    leapfrog = analysis.work_precision(dp, *start, t_end=2.0, dts=[0.02, 0.01],
                                       method="leapfrog", reference=reference)
    assert 2.5 < leapfrog[0].state_error / leapfrog[1].state_error < 6
    # The reference defaults to DOP853 at t_end; tight DOP853 runs agree with it.
    dop = analysis.dop853_work_precision(dp, *start, t_end=2.0, rtols=[1e-6, 1e-11])
    assert dop[1].state_error < 1e-7 < dop[0].state_error
    with pytest.raises(ValueError, match="whole number of steps"):
        analysis.work_precision(dp, *start, t_end=2.0, dts=[0.3], method="rk4",
                                reference=reference)


def test_plot_work_precision_draws_either_error():
    sp = pl.simple_pendulum()
    points = analysis.work_precision(sp, [1.0], [0.0], t_end=1.0, dts=[0.1, 0.05], method="rk4")
    ax = plotting.plot_work_precision(points, x="evaluations", y="state_error").axes[0]
    assert list(ax.lines[0].get_ydata()) == [p.state_error for p in points]
    assert "global error" in ax.get_ylabel()
    with pytest.raises(ValueError, match="`y` must be 'energy_error' or 'state_error'"):
        plotting.plot_work_precision(points, y="error")


def test_compare_methods_is_the_table_of_the_report(tmp_path):
    dp = pl.double_pendulum()
    # glrk4's stage iteration cannot converge at dt = 0.25 from this start: a failure, no row
    result = analysis.compare_methods([(dp, [2.0, 2.5], [0.0, 0.0])], ["rk4", "glrk4"],
                                      t_end=5.0, dt=0.25)
    assert [(row.pendulum, row.method) for row in result.rows] == [("double", "rk4")]
    assert [(p, m) for p, m, _ in result.failures] == [("double", "glrk4")]
    assert [traj.method.name for traj in result.trajectories["double"]] == ["rk4"]
    # the report's rows are exactly these
    report_rows = report.run_report(tmp_path, t_end=5.0, dt=0.25, methods=["rk4", "glrk4"],
                                    pendulums=["double"], progress=False).rows
    assert [(r.method, r.energy_last, r.observed_order) for r in report_rows] == [
        (r.method, r.energy_last, r.observed_order) for r in result.rows
    ]
    with pytest.raises(TypeError, match="`problems` must hold"):
        analysis.compare_methods([dp], ["rk4"], t_end=1.0)
    with pytest.raises(ValueError, match="`methods` must be among"):
        analysis.compare_methods([(dp, [0.1, 0.1], [0.0, 0.0])], ["rk5"], t_end=1.0)


def test_a_fit_at_round_off_gives_no_order_and_the_table_says_so():
    # glrk16 on the simple pendulum: at the fitting steps its global error (about 1e-13) no
    # longer shrinks, so a slope would be noise; rk4's errors shrink (negative control).
    sp = pl.simple_pendulum()
    rows = analysis.compare_methods([(sp, [2.0], [0.0])], ["rk4", "glrk16"], t_end=2.0).rows
    by_method = {row.method: row for row in rows}
    assert 3.5 < by_method["rk4"].observed_order < 4.5
    assert np.isnan(by_method["glrk16"].observed_order)
    table = tables.markdown_table(rows)
    assert table.count("round-off") == 1 and "nan" not in table
