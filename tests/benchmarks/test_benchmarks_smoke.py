"""Smoke test of the benchmark suite in benchmarks/.

Every benchmark item runs in the tiny ``SMOKE`` configuration and must return
well-formed table rows. Nothing here asserts a timing: timings belong to
``make bench``. What is asserted is behaviour that cannot depend on the
machine: the C yardstick does the same arithmetic as ``pl.simulate``, the
search for the loosest setting finds the threshold, verdicts compare the right
way round, and a failing item is reported, not swallowed.
"""

import math
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

import pendulum_lab as pl

BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"
RESULTS = {"PASS", "info", "not available"}


@pytest.fixture(scope="module")
def suite():
    with pytest.MonkeyPatch.context() as mp:
        mp.syspath_prepend(str(BENCHMARKS))
        import suite as module
    return module


@pytest.fixture(scope="module")
def long_run(suite):
    with pytest.MonkeyPatch.context() as mp:
        mp.syspath_prepend(str(BENCHMARKS))
        import item_long_run as module
    return module


@pytest.fixture(scope="module")
def run(suite):
    with pytest.MonkeyPatch.context() as mp:
        mp.syspath_prepend(str(BENCHMARKS))
        import run as module
    return module


def well_formed(suite, section, number):
    assert isinstance(section, suite.Section)
    assert section.rows, f"{section.key} returned no rows"
    for row in section.rows:
        cells = row.cells()
        assert len(cells) == len(suite.COLUMNS)
        assert all(isinstance(c, str) and c for c in cells)
        assert row.item == str(number)
        assert row.result in RESULTS or row.result.startswith("MISS"), (row, section.details)
    assert all(isinstance(line, str) for line in section.details)


@pytest.mark.parametrize(
    "key",
    ["slider", "first_use", "long_run", "report_glrk4", "ensemble", "c_limit", "variational",
     "bifurcation", "per_eval", "heyoka", "pyhamsys", "long_chains", "distributed", "systems",
     "browser"],
)
def test_each_item_runs_and_returns_rows(suite, key):
    if suite.ITEMS[key][2] and shutil.which(suite.c_yardstick.COMPILER) is None:
        pytest.skip("no C compiler: the C yardstick cannot be built")
    (section,) = suite.run_items(suite.SMOKE, [key], log=lambda _: None)
    well_formed(suite, section, suite.ITEMS[key][0])


def test_live_item_counts_the_bytes_of_one_run(suite):
    """Item 9 in the smoke configuration: the kernel rows only (no browser), and the byte
    count is exactly the run's float32 arrays."""
    (section,) = suite.run_items(suite.SMOKE, ["live"], log=lambda _: None)
    well_formed(suite, section, suite.ITEMS["live"][0])
    assert [row.result for row in section.rows][-1] == "not available"  # no browser in smoke
    kernel = section.data["kernel"]
    assert kernel["steps"] == 2000 and kernel["messages"] == 1
    # 2001 states of (2 angles, 3 energies, 1 energy error) as float32.
    assert kernel["buffer_bytes"] == 2001 * 6 * 4
    # The matplotlib simulator's frames: 20 s at 20 frames per second, and many more bytes.
    assert kernel["frames"] == 401 and kernel["image_bytes"] > 10 * kernel["buffer_bytes"]


def test_a_failing_item_becomes_an_error_row(suite, monkeypatch):
    def broken(cfg):
        raise RuntimeError("boom")

    monkeypatch.setitem(suite.ITEMS, "first_use", (2, broken, False))
    (section,) = suite.run_items(suite.SMOKE, ["first_use"], log=lambda _: None)
    assert [row.result for row in section.rows] == ["ERROR"]
    assert "boom" in section.details[0]
    with pytest.raises(AssertionError):  # the well-formedness check rejects it
        well_formed(suite, section, 2)


@pytest.mark.skipif(shutil.which("gcc") is None, reason="no C compiler")
def test_c_loop_does_the_same_arithmetic_as_simulate(suite, tmp_path):
    dp = pl.double_pendulum()
    loop = suite.c_yardstick.build(dp, tmp_path)
    theta0, omega0 = np.array([2.0, 2.5]), np.zeros(2)
    run = loop.single(theta0, dp.momenta(theta0, omega0), 300, 0.01)
    q, p = run.theta, run.p
    traj = pl.simulate(dp, theta0, omega0, t_end=3.0, dt=0.01, method="rk4")
    assert np.max(np.abs(q - traj.theta[-1])) <= 1e-9
    assert np.max(np.abs(p - traj.p[-1])) <= 1e-9
    # Negative control: one step fewer is a different end state.
    q_short = loop.single(theta0, dp.momenta(theta0, omega0), 299, 0.01).theta
    assert np.max(np.abs(q_short - traj.theta[-1])) > 1e-6


@pytest.mark.skipif(shutil.which("gcc") is None, reason="no C compiler")
def test_c_loop_of_the_driven_pendulum_does_the_same_arithmetic(suite, tmp_path):
    model = pl.driven_pendulum()  # forced: the drive depends on the time of each stage
    loop = suite.c_yardstick.build(model, tmp_path)
    theta0 = np.array([[0.2], [1.0]])
    p0 = model.momenta(theta0, np.zeros_like(theta0))
    run = loop.ensemble(theta0, p0, 500, 0.05)
    traj = pl.simulate(model, theta0, p0=p0, t_end=25.0, dt=0.05, method="rk4", keep="final")
    assert np.max(np.abs(run.theta - traj.theta[-1])) <= 1e-9
    assert np.max(np.abs(run.p - traj.p[-1])) <= 1e-9
    # Negative control: the conservative pendulum's C loop is a different motion.
    free = suite.c_yardstick.build(pl.simple_pendulum(g=1.0), tmp_path)
    assert np.max(np.abs(free.ensemble(theta0, p0, 500, 0.05).theta - traj.theta[-1])) > 1e-3


def test_search_finds_the_largest_passing_value(long_run):
    calls = []

    def error(x):
        calls.append(x)
        return x**4, {}

    best, trials = long_run._largest_passing(error, 0.02, 4, 1e-8, precision=1.05, max_trials=12)
    assert best[0] <= 0.01 * (1 + 1e-12)
    assert best[0] > 0.01 / 1.05
    assert len(trials) == len(calls)
    # Negative control: an error that never meets the tolerance gives no answer.
    best, _ = long_run._largest_passing(lambda x: (1.0, {}), 0.02, 4, 1e-8, 1.05, max_trials=5)
    assert best is None


def test_search_takes_a_step_without_convergence_as_too_long(long_run):
    def error(x):
        if x > 0.05:  # like an implicit step whose iteration diverges
            raise pl.ConvergenceError(f"did not converge at dt = {x}")
        return x**4, {"seconds": 1 / x}

    best, trials = long_run._largest_passing(error, 0.4, 4, 1e-8, precision=1.05, max_trials=12)
    assert 0.01 / 1.05 < best[0] <= 0.01 * (1 + 1e-12)
    diverged = [t for t in trials if t[0] > 0.05]
    assert diverged and all(t[1] == math.inf for t in diverged)
    # Each diverging try is halved, not cut by the error model (which would give 0.05x).
    assert [t[0] for t in trials[:3]] == pytest.approx([0.4, 0.2, 0.1], rel=1e-12)
    # Negative control: other errors are not taken for a step that is too long.
    with pytest.raises(ZeroDivisionError):
        long_run._largest_passing(lambda x: (1 / 0, {}), 0.02, 4, 1e-8, 1.05, max_trials=3)


def test_verdict_direction(suite):
    assert suite.verdict(2.0, 3.0) == "PASS"
    assert suite.verdict(4.5, 3.0).startswith("MISS (1.50x")
    assert suite.verdict(60.0, 50.0, at_most=False) == "PASS"
    assert suite.verdict(25.0, 50.0, at_most=False).startswith("MISS (2.00x")
    assert suite.verdict(math.nan, 3.0).startswith("MISS")


def test_resolve_names_and_numbers(suite):
    assert suite.resolve(None) == list(suite.ITEMS)
    assert suite.resolve(["5", "slider"]) == ["slider", "ensemble"]
    with pytest.raises(ValueError, match="unknown benchmark"):
        suite.resolve(["nonsense"])


def test_markdown_has_machine_table_and_details(suite, run):
    machine = {
        "date": "today",
        "cpu": "a CPU",
        "cores": 2,
        "cores_available": 2,
        "platform": "linux",
        "python": "3.x",
        "pendulum_lab": "0",
        "git": "abc",
        "versions": {"numpy": "2"},
        "numba_threads": 2,
        "compiler": "gcc",
        "env": {"OPENBLAS_NUM_THREADS": "1"},
        "load_start": (1.0, 1.0, 1.0),
        "load_end": None,  # Windows has no load average
    }
    row = suite.Row("3", "a | b", "1 s", "2 s", "2x", "peer/ours >= 10", "MISS (5.0x off)")
    section = suite.Section("long_run", "3. Long run", [row], ["a detail", "| x |"], {}, 1.0)
    text = run.markdown(suite.SMOKE, machine, [section], ["long_run"], 61.0)
    assert "| # | benchmark | ours | peer | ratio | target | result |" in text
    assert "| 3 | a / b | 1 s | 2 s | 2x | peer/ours >= 10 | MISS (5.0x off) |" in text
    assert "OPENBLAS_NUM_THREADS=1" in text and "a CPU" in text
    assert "1.00, 1.00, 1.00; at end: unknown" in text and "SMOKE run" in text
    assert "a detail" in text and "| x |" in text


def test_machine_description_without_proc_load_average_or_affinity(suite, monkeypatch):
    """macOS and Windows have no /proc/cpuinfo, Windows no load average, neither an affinity
    call: the description says what it can and "unknown" for the rest, and never fails."""
    import harness

    monkeypatch.setattr(harness, "CPUINFO", Path("/proc/no-such-cpuinfo"))
    monkeypatch.delattr(os, "getloadavg")
    monkeypatch.delattr(os, "sched_getaffinity", raising=False)
    monkeypatch.setattr(harness.platform, "processor", lambda: "Intel64 Family 6 Model 85")
    machine = harness.machine_description()
    assert machine["cpu"] == "Intel64 Family 6 Model 85"
    assert machine["load_start"] is None and machine["cores_available"] is None
    assert harness.load_text(machine["load_start"]) == "unknown"
    monkeypatch.setattr(harness.platform, "processor", lambda: "")  # Linux says nothing there
    assert harness.cpu_name() == "unknown"


def test_machine_description_reads_the_model_name_where_proc_has_it(suite, monkeypatch,
                                                                      tmp_path):
    import harness

    cpuinfo = tmp_path / "cpuinfo"
    cpuinfo.write_text("processor\t: 0\nmodel name\t: A Test CPU @ 2.0GHz\n", encoding="utf-8")
    monkeypatch.setattr(harness, "CPUINFO", cpuinfo)
    monkeypatch.setattr(harness.platform, "processor", lambda: "not this")
    assert harness.cpu_name() == "A Test CPU @ 2.0GHz"
    assert harness.load_text((0.5, 1.0, 1.25)) == "0.50, 1.00, 1.25"


@pytest.mark.skipif(shutil.which("gcc") is None, reason="no C compiler")
def test_c_loop_without_sincos_calls_sin_and_cos_as_the_kernels_do_there(suite, tmp_path,
                                                                         monkeypatch):
    """macOS and Windows (emulated): the C library has no sincos, the kernels call sin and cos
    without the shift near pi, and so does the C yardstick."""
    from pendulum_lab.codegen import lowlevel

    dp = pl.double_pendulum()
    with_sincos = suite.c_yardstick.c_source(dp.chain)
    monkeypatch.setattr(lowlevel, "HAVE_SINCOS", False)
    monkeypatch.setattr(lowlevel, "SHIFT_NEAR_PI", False)
    source = suite.c_yardstick.c_source(dp.chain)
    assert "sincos(" in with_sincos and "sincos(" not in source.replace("paired_sincos(", "")
    assert "*s = sin(x);" in source and "*c = cos(x);" in source
    loop = suite.c_yardstick.build(dp, tmp_path)  # it compiles, and it moves the same way
    theta0, omega0 = np.array([2.0, 2.5]), np.zeros(2)
    run = loop.single(theta0, dp.momenta(theta0, omega0), 100, 0.01)
    traj = pl.simulate(dp, theta0, omega0, t_end=1.0, dt=0.01, method="rk4")
    assert np.max(np.abs(run.theta - traj.theta[-1])) <= 1e-9
