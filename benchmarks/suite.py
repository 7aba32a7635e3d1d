"""The benchmark suite of issue 7: six items, each a ratio measured side by side.

Machines are noisy (and shared), so every figure that carries a target is a
ratio of two contenders timed in the same run, interleaved round by round
(the order rotates each round), each summarised by the median of its rounds.
Each ``bench_*`` function takes a :class:`Config` and returns a
:class:`Section`: table rows (with target and PASS/MISS), detail lines and
the raw numbers. ``benchmarks/run.py`` is the command-line front end; see
``benchmarks/README.md`` for what each item measures and against which peer.

This directory is a folder of scripts, not a package: ``run.py`` (or a test)
puts it on ``sys.path`` before importing this module.
"""

from __future__ import annotations

import datetime
import json
import math
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

import c_yardstick
import numpy as np
import report_glrk4

import pendulum_lab as pl

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
SEARCH_CACHE = RESULTS / "long_run_search.json"

#: Item 3 settings used by a run that neither searches nor finds a search cache.
FALLBACK_DT, FALLBACK_RTOL = 0.0015, 1e-11

#: Item 4: two runs still follow the same motion while their angles differ by less [rad].
SAME_MOTION = 1e-2

#: The default explorer's start: the double pendulum from (2.0, 2.5) rad at rest.
THETA0 = (2.0, 2.5)


# --------------------------------------------------------------------------- configuration
@dataclass(frozen=True)
class Config:
    """Sizes and repetitions of one benchmark run.

    ``FULL`` is the configuration of the issue's targets; ``QUICK`` a short
    run of the same code (minutes -> seconds; figures indicative only);
    ``SMOKE`` the tiny one the test suite uses to check the machinery.
    """

    name: str
    rounds: int = 15  # interleaved rounds, items 1 and 6 (cheap: milliseconds each)
    dt: float = 0.01
    slider_t_end: float = 20.0  # item 1: the default explorer run
    c_inner_reps: int = 20  # C repeats inside one call (median taken)
    update_rounds: int = 6  # item 1: slider changes timed per method
    first_use_runs: int = 5  # item 2: alternating fresh processes, each
    cold_runs: int = 2  # item 2: runs with empty kernel caches
    long_t_end: float = 1000.0  # item 3
    long_tol: float = 1e-8
    long_search: bool = True  # False: reuse results/long_run_search.json
    long_pilot_t_end: float = 100.0
    long_pilot_dt: float = 0.01
    long_max_trial_s: float = 60.0  # skip a method whose predicted run is longer
    long_rounds: int = 3
    long_methods: tuple = ("glrk8", "glrk4", "leapfrog")
    long_rtol_start: float = 1e-11  # DOP853 search start (measured earlier: near the answer)
    atol_factor: float = 1e-3  # item 3: solve_ivp atol = rtol * atol_factor
    report_t_end: float = 20.0  # item 4
    report_rounds: int = 3
    ensemble_side: int = 200  # item 5: side x side initial conditions
    ensemble_steps: dict = field(default_factory=lambda: {"rk4": 200, "glrk4": 100})
    ensemble_rounds: int = 3
    flip_size: int = 200
    flip_t_end: float = 10.0
    limit_members: int = 4000  # item 6: ensemble verified against the C loop
    limit_steps: int = 200


FULL = Config("full")
QUICK = replace(
    FULL,
    name="quick",
    rounds=5,
    c_inner_reps=10,
    update_rounds=3,
    first_use_runs=3,
    cold_runs=0,
    long_search=False,
    long_rounds=1,
    report_t_end=2.0,
    report_rounds=1,
    ensemble_side=60,
    ensemble_steps={"rk4": 100, "glrk4": 50},
    ensemble_rounds=1,
    flip_size=40,
    flip_t_end=5.0,
    limit_members=400,
)
SMOKE = replace(
    FULL,
    name="smoke",
    rounds=1,
    slider_t_end=0.5,
    c_inner_reps=2,
    update_rounds=1,
    first_use_runs=1,
    cold_runs=0,
    long_t_end=5.0,
    long_tol=1e-5,
    long_pilot_t_end=2.0,
    long_pilot_dt=0.02,
    long_max_trial_s=5.0,
    long_rounds=1,
    long_rtol_start=1e-7,
    report_t_end=0.2,
    report_rounds=1,
    ensemble_side=8,
    ensemble_steps={"rk4": 5, "glrk4": 5},
    ensemble_rounds=1,
    flip_size=6,
    flip_t_end=1.0,
    limit_members=16,
    limit_steps=10,
)
CONFIGS = {"full": FULL, "quick": QUICK, "smoke": SMOKE}


# --------------------------------------------------------------------------- results
@dataclass
class Row:
    """One line of the results table (all fields are display strings)."""

    item: str
    name: str
    ours: str
    peer: str
    ratio: str
    target: str
    result: str  # PASS, MISS, info, not available, ERROR

    def cells(self) -> list[str]:
        return [self.item, self.name, self.ours, self.peer, self.ratio, self.target, self.result]


COLUMNS = ["#", "benchmark", "ours", "peer", "ratio", "target", "result"]


@dataclass
class Section:
    """What one benchmark item returns."""

    key: str
    title: str
    rows: list[Row]
    details: list[str]
    data: dict
    seconds: float = 0.0


def verdict(ratio: float, limit: float, at_most: bool = True) -> str:
    """PASS when ``ratio <= limit`` (``at_most``) or ``ratio >= limit``."""
    if not math.isfinite(ratio):
        return "MISS"
    ok = ratio <= limit if at_most else ratio >= limit
    if ok:
        return "PASS"
    factor = ratio / limit if at_most else limit / ratio
    return f"MISS ({factor:.2f}x off)"


def fmt_time(seconds: float) -> str:
    """``850 us``, ``12.3 ms``, ``1.23 s``."""
    if not math.isfinite(seconds):
        return "n/a"
    if seconds < 1e-3:
        return f"{seconds * 1e6:.3g} us"
    if seconds < 1.0:
        return f"{seconds * 1e3:.3g} ms"
    return f"{seconds:.3g} s"


def fmt_rate(per_second: float) -> str:
    return f"{per_second / 1e6:.3g} M/s"


def median(values) -> float:
    values = list(values)
    return float(statistics.median(values)) if values else float("nan")


@dataclass(frozen=True)
class Sample:
    """One measurement: wall-clock seconds and CPU seconds of the measured process.

    On a shared machine a job can wait for a core while its wall clock runs;
    CPU time counts only the time it computed, so ratios of CPU times stay
    fair between a short and a long job (a short one is rarely preempted).
    """

    wall: float
    cpu: float


def interleave(contenders: dict[str, Callable[[], Sample]], rounds: int) -> dict[str, list]:
    """Run each contender once per round, rotating the order; collect the samples returned.

    A contender returns its own :class:`Sample` (the C program reports what it
    measured itself; a Python contender times its call with :func:`timed`).
    """
    names = list(contenders)
    samples: dict[str, list] = {name: [] for name in names}
    for r in range(rounds):
        for name in names[r % len(names) :] + names[: r % len(names)]:
            samples[name].append(contenders[name]())
    return samples


def med(samples, attr: str = "cpu") -> float:
    """Median wall or CPU seconds of a list of samples."""
    return median(getattr(s, attr) for s in samples)


def timed(fn, *args, **kwargs):
    """``(Sample, result)`` of one call (CPU: the whole process, all threads)."""
    cpu = time.process_time()
    start = time.perf_counter()
    result = fn(*args, **kwargs)
    return Sample(time.perf_counter() - start, time.process_time() - cpu), result


# --------------------------------------------------------------------------- helpers
def double_pendulum():
    return pl.double_pendulum()


def explorer_start():
    """The default explorer's initial state: theta, omega, p (each shape (2,))."""
    dp = double_pendulum()
    theta0 = np.array(THETA0)
    omega0 = np.zeros(2)
    return dp, theta0, omega0, dp.momenta(theta0, omega0)


def steps_for(t_end: float, dt: float) -> int:
    """The number of steps ``pl.simulate`` takes (its own rule)."""
    return int(np.floor(t_end / dt * (1 + 1e-12)))


def max_relative_energy_error(energy) -> float:
    energy = np.asarray(energy)
    return float(np.max(np.abs(energy - energy[0])) / abs(energy[0]))


# --------------------------------------------------------------------------- machine
def machine_description() -> dict:
    """CPU, cores, load, versions and the environment variables that steer threads."""
    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        affinity = len(os.sched_getaffinity(0))
    except AttributeError:
        affinity = None
    versions = {}
    for module in ("numpy", "scipy", "sympy", "numba", "matplotlib", "ipywidgets"):
        try:
            versions[module] = __import__(module).__version__
        except ImportError:
            versions[module] = "not installed"
    import numba

    threads = {
        k: v
        for k, v in sorted(os.environ.items())
        if k.startswith(("OPENBLAS", "OMP_", "MKL_", "NUMBA_", "PENDULUM_LAB"))
    }
    commit = _git("rev-parse", "--short", "HEAD")
    dirty = _git("status", "--porcelain", "--untracked-files=no")
    return {
        "date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
        "cpu": cpu,
        "cores": os.cpu_count(),
        "cores_available": affinity,
        "platform": platform.platform(),
        "python": platform.python_version(),
        "pendulum_lab": getattr(pl, "__version__", "?"),
        "git": f"{commit}{' (with uncommitted changes)' if dirty else ''}" if commit else "unknown",
        "versions": versions,
        "numba_threads": numba.config.NUMBA_NUM_THREADS,
        "compiler": c_yardstick.compiler_version(),
        "env": threads,
        "load_start": os.getloadavg(),
    }


def _git(*args) -> str:
    try:
        out = subprocess.run(
            ["git", "-C", str(HERE), *args], capture_output=True, text=True, check=False, timeout=10
        )
    except (OSError, subprocess.TimeoutExpired):
        return ""
    return out.stdout.strip() if out.returncode == 0 else ""


# =========================================================================== item 1
def bench_slider(cfg: Config, cloop: c_yardstick.CLoop | None) -> Section:
    """Recompute of the default explorer run for every method vs the C RK4 loop; full update."""
    dp, theta0, omega0, p0 = explorer_start()
    n_steps = steps_for(cfg.slider_t_end, cfg.dt)
    rows, details, data = [], [], {"n_steps": n_steps, "methods": {}}
    trajectories = {}

    def ours(method):
        def call():
            sample, traj = timed(
                pl.simulate,
                dp,
                theta0,
                omega0,
                t_end=cfg.slider_t_end,
                dt=cfg.dt,
                method=method,
                progress=False,
            )
            trajectories.setdefault(method, []).append(traj)
            return sample

        return call

    contenders = {m: ours(m) for m in pl.METHODS}
    for call in contenders.values():  # load the compiled kernels before timing
        call()
    trajectories.clear()
    if cloop is not None:

        def c_loop():
            run = cloop.single(theta0, p0, n_steps, cfg.dt, cfg.c_inner_reps)
            return Sample(median(run.seconds), median(run.cpu))

        contenders = {"C rk4": c_loop, **contenders}
    samples = interleave(contenders, cfg.rounds)
    nan = float("nan")
    c_cpu = med(samples["C rk4"]) if cloop is not None else nan
    c_wall = med(samples["C rk4"], "wall") if cloop is not None else nan
    data["c_seconds"] = {"cpu": c_cpu, "wall": c_wall}
    details.append(
        f"{n_steps} steps (t_end = {cfg.slider_t_end:g} s, dt = {cfg.dt:g} s) from theta = "
        f"{THETA0} at rest; {cfg.rounds} interleaved rounds, medians; the C figure is the median "
        f"of {cfg.c_inner_reps} repetitions inside each C call: {fmt_time(c_cpu)} CPU, "
        f"{fmt_time(c_wall)} wall. Ratios use CPU time (see the README: a 20 ms job on a "
        "shared machine is preempted far more often than a 0.4 ms one, which would bias a "
        "wall-clock ratio); wall times are in the table below."
    )
    details.append("")
    details.append(
        "| method | CPU | wall | stepping (`traj.wall_time`) | wall outside the loop "
        f"| sweeps/step | field evals/step | ns/eval (C RK4: {c_cpu / (4 * n_steps) * 1e9:.0f}) |"
    )
    details.append("|---|---|---|---|---|---|---|---|")
    for method in pl.METHODS:
        cpu, wall = med(samples[method]), med(samples[method], "wall")
        trajs = trajectories[method]
        stepping = median(t.wall_time for t in trajs)
        evals = trajs[-1].evaluations / n_steps
        per_eval = stepping / trajs[-1].evaluations if trajs[-1].evaluations else nan
        ratio = cpu / c_cpu
        data["methods"][method] = {
            "cpu": cpu,
            "wall": wall,
            "stepping": stepping,
            "sweeps": trajs[-1].mean_iterations,
            "evals_per_step": evals,
            "ratio": ratio,
        }
        rows.append(
            Row(
                "1",
                f"recompute {cfg.slider_t_end:g} s, {method}",
                f"{fmt_time(cpu)} ({fmt_time(wall)} wall)",
                f"C RK4 {fmt_time(c_cpu)} ({fmt_time(c_wall)} wall)",
                f"{ratio:.1f}x",
                "ours/C <= 20 (CPU)",
                verdict(ratio, 20.0) if cloop is not None else "not available",
            )
        )
        details.append(
            f"| {method} | {fmt_time(cpu)} | {fmt_time(wall)} | {fmt_time(stepping)} | "
            f"{fmt_time(wall - stepping)} | {trajs[-1].mean_iterations:.2f} | {evals:.1f} | "
            f"{per_eval * 1e9:.0f} |"
        )
    details.append("")
    details.append(
        "'outside the loop' = validation, momenta, result arrays and the energies computed by "
        "`pl.simulate` after the compiled loop; ns/eval = stepping time per field evaluation."
    )
    one_step = [
        timed(
            pl.simulate, dp, theta0, omega0, t_end=cfg.dt, dt=cfg.dt, method="rk4", progress=False
        )
        for _ in range(21)
    ]
    call, loop = med([s for s, _ in one_step], "wall"), median(t.wall_time for _, t in one_step)
    data["one_step"] = {"call": call, "loop": loop}
    details.append(
        f"Fixed cost per call (a one-step rk4 `pl.simulate`, median of 21, wall): whole call "
        f"{fmt_time(call)}, of which the compiled loop's call {fmt_time(loop)}."
    )
    rows += _full_update(cfg, dp, data, details)
    return Section("slider", "1. Slider latency", rows, details, data)


def _full_update(cfg: Config, dp, data: dict, details: list[str]) -> list[Row]:
    """Time a slider change in the explorer (recompute + redraw + PNG), Agg backend."""
    try:
        from pendulum_lab import widgets
    except ImportError:
        widgets = None
    if widgets is None or not hasattr(widgets, "explore"):
        details.append("Full update: `pendulum_lab.widgets.explore` is not available.")
        return [Row("1", "full update incl. redraw", "-", "-", "-", "<= 50 ms", "not available")]
    import matplotlib

    matplotlib.use("Agg")
    ex = widgets.explore(dp, method="glrk4", t_end=cfg.slider_t_end, dt=cfg.dt)
    rows, data["full_update"] = [], {}
    details.append("")
    details.append(
        f"Full update: `ex = pl.widgets.explore(dp, t_end={cfg.slider_t_end:g}, dt={cfg.dt:g})`, "
        f"then `ex.controls['theta1'].value = x` with alternating x (recompute + redraw + PNG "
        f"encoding), {cfg.update_rounds} changes per method, medians. The verdict uses CPU time "
        "(what an idle machine would show); the wall time on this shared machine is given too. "
        "'redraw' = full update minus the method's recompute above (CPU)."
    )
    slider = ex.controls["theta1"]
    for method in pl.METHODS:
        ex.controls["method"].value = method  # this update also warms the method up
        times, ok = [], True
        for _ in range(cfg.update_rounds):
            # a new value every time, or the slider would not fire
            x = round(THETA0[0] + (0.02 if slider.value == THETA0[0] + 0.01 else 0.01), 2)
            before = ex.trajectory
            sample, _ = timed(setattr, slider, "value", x)
            ok = ok and ex.trajectory is not before and float(ex.trajectory.theta[0, 0]) == x
            times.append(sample)
        cpu, wall = med(times), med(times, "wall")
        redraw = cpu - data["methods"][method]["cpu"]
        data["full_update"][method] = {"cpu": cpu, "wall": wall, "redraw": redraw, "updated": ok}
        status = verdict(cpu, 0.050) if ok else "ERROR (no update)"
        rows.append(
            Row(
                "1",
                f"full update incl. redraw, {method}",
                f"{fmt_time(cpu)} ({fmt_time(wall)} wall)",
                f"redraw {fmt_time(redraw)}",
                f"{cpu / 0.1:.2f} of 100 ms",
                "well under 100 ms (<= 50 ms CPU)",
                status,
            )
        )
    return rows


# =========================================================================== item 2
FIRST_USE = (
    "import pendulum_lab as pl; dp = pl.double_pendulum(); "
    "pl.simulate(dp, [2.0, 2.5], [0, 0], t_end=1.0, dt=0.01)"
)
BARE_IMPORTS = "import scipy.integrate; import sympy"
PHASES = r"""
import json, time
t0 = time.perf_counter()
import pendulum_lab as pl
t1 = time.perf_counter()
dp = pl.double_pendulum()
t2 = time.perf_counter()
pl.simulate(dp, [2.0, 2.5], [0, 0], t_end=1.0, dt=0.01)
t3 = time.perf_counter()
pl.simulate(dp, [2.0, 2.5], [0, 0], t_end=1.0, dt=0.01)
t4 = time.perf_counter()
print(json.dumps({"import pendulum_lab": t1 - t0, "pl.double_pendulum()": t2 - t1,
                  "first pl.simulate (kernels loaded)": t3 - t2,
                  "second pl.simulate": t4 - t3}))
"""


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _fresh_process(code: str, env: dict | None = None) -> Sample:
    """Wall time of a fresh ``python -c code`` seen from outside, and the child's CPU time."""
    cpu = _children_cpu()
    sample, out = timed(
        subprocess.run,
        [sys.executable, "-c", code],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    if out.returncode != 0:
        raise RuntimeError(f"fresh process failed: {out.stderr.strip()[-500:]}")
    return Sample(sample.wall, _children_cpu() - cpu)


def _cold_process(code: str) -> Sample:
    """A fresh process whose kernel cache and Numba cache are empty temporary folders."""
    with tempfile.TemporaryDirectory() as kernels, tempfile.TemporaryDirectory() as numba_dir:
        env = os.environ | {"PENDULUM_LAB_CACHE": kernels, "NUMBA_CACHE_DIR": numba_dir}
        return _fresh_process(code, env)


def bench_first_use(cfg: Config) -> Section:
    """Fresh process: import, model, 1 s simulation vs ``import scipy.integrate; import sympy``."""
    _fresh_process(FIRST_USE)  # fills the kernel cache (as any earlier use would have)
    _fresh_process(BARE_IMPORTS)
    samples = interleave(
        {
            "ours": lambda: _fresh_process(FIRST_USE),
            "peer": lambda: _fresh_process(BARE_IMPORTS),
            "python": lambda: _fresh_process("pass"),
        },
        cfg.first_use_runs,
    )
    ours, peer, bare = (med(samples[k], "wall") for k in ("ours", "peer", "python"))
    ours_cpu, peer_cpu = med(samples["ours"]), med(samples["peer"])
    ratio = ours / peer
    rows = [
        Row(
            "2",
            "first use (warm kernel cache)",
            fmt_time(ours),
            fmt_time(peer),
            f"{ratio:.2f}x",
            "ours/peer <= 3 (wall)",
            verdict(ratio, 3.0),
        )
    ]
    details = [
        f"Fresh `{sys.executable} -c ...` processes, wall time from outside (interpreter start "
        f"included for both), {cfg.first_use_runs} alternating runs each, medians. Ours: "
        f"`{FIRST_USE}` (default method glrk4). Peer: `{BARE_IMPORTS}`. A bare `python -c pass` "
        f"takes {fmt_time(bare)}. The verdict uses wall time (both jobs last seconds and include "
        f"file reads); by the children's CPU time: ours {fmt_time(ours_cpu)}, peer "
        f"{fmt_time(peer_cpu)}, ratio {ours_cpu / peer_cpu:.2f}.",
        "Samples, wall (s): "
        + "; ".join(f"{k} " + ", ".join(f"{x.wall:.2f}" for x in v) for k, v in samples.items()),
    ]
    data = {
        "ours": ours,
        "peer": peer,
        "python": bare,
        "ratio": ratio,
        "ours_cpu": ours_cpu,
        "peer_cpu": peer_cpu,
    }
    if cfg.cold_runs:
        cold_samples = interleave(
            {
                "cold": lambda: _cold_process(FIRST_USE),
                "peer": lambda: _fresh_process(BARE_IMPORTS),
            },
            cfg.cold_runs,
        )
        cold, cold_peer = med(cold_samples["cold"], "wall"), med(cold_samples["peer"], "wall")
        rows.append(
            Row(
                "2",
                "first use, COLD (empty kernel + Numba caches)",
                fmt_time(cold),
                fmt_time(cold_peer),
                f"{cold / cold_peer:.1f}x",
                "none (information)",
                "info",
            )
        )
        details.append(
            "Cold: `PENDULUM_LAB_CACHE` and `NUMBA_CACHE_DIR` set to new empty temporary "
            "folders, so kernels are generated from SymPy and everything is compiled by Numba: "
            f"what the very first use on a machine costs (once). {cfg.cold_runs} run(s), "
            f"median; CPU {fmt_time(med(cold_samples['cold']))}."
        )
        data["cold"] = cold
    else:
        rows.append(
            Row(
                "2",
                "first use, COLD (empty kernel + Numba caches)",
                "not measured",
                "-",
                "-",
                "none (information)",
                "info",
            )
        )
        details.append(
            "Cold first use (empty caches) is not measured in this configuration; "
            "the full run measures it."
        )
    phases = json.loads(
        subprocess.run(
            [sys.executable, "-c", PHASES], capture_output=True, text=True, check=True
        ).stdout
    )
    data["phases"] = phases
    details.append(
        "Where a warm first use spends its time (one fresh process): "
        + "; ".join(f"{k} {fmt_time(v)}" for k, v in phases.items())
        + "."
    )
    details.append(
        "Largest imports (`python -X importtime`, cumulative): "
        + "; ".join(f"{k} {fmt_time(v)}" for k, v in _import_times()[:6])
        + "."
    )
    return Section("first_use", "2. First use", rows, details, data)


def _import_times() -> list[tuple[str, float]]:
    """Cumulative import times of the heavy dependencies and of pendulum_lab's modules.

    From ``python -X importtime -c "import pendulum_lab"``; nested entries
    overlap (sympy is imported inside ``pendulum_lab.mechanics``).
    """
    out = subprocess.run(
        [sys.executable, "-X", "importtime", "-c", "import pendulum_lab"],
        capture_output=True,
        text=True,
        check=False,
    )
    heavy = {"numpy", "scipy", "sympy", "numba", "matplotlib", "ipywidgets", "tqdm", "llvmlite"}
    found = {}
    for line in out.stderr.splitlines():
        parts = line.removeprefix("import time:").split("|")
        if len(parts) != 3 or not parts[1].strip().isdigit():
            continue
        name = parts[2].strip()
        if name in heavy or name.startswith("pendulum_lab"):
            found[name] = int(parts[1]) * 1e-6
    return sorted(found.items(), key=lambda kv: -kv[1])


# =========================================================================== item 3
def _largest_passing(
    evaluate,
    x0: float,
    exponent: float,
    tol: float,
    precision: float,
    max_trials: int,
    safety: float = 0.9,
    max_factor: float = 4.0,
):
    """Largest ``x`` with ``evaluate(x)[0] <= tol``, for an error growing like ``x**exponent``.

    Model-guided bracketing, then geometric bisection until the passing and
    the next failing ``x`` are within the factor ``precision``. Returns
    ``(best trial or None, all trials)``; a trial is ``(x, error, extra)``.
    """
    trials, x = [], x0
    best = None
    for _ in range(max_trials):
        err, extra = evaluate(x)
        trials.append((x, err, extra))
        passing = [t for t in trials if t[1] <= tol]
        best = max(passing, key=lambda t: t[0]) if passing else None
        failing = [t for t in trials if t[1] > tol and (best is None or t[0] > best[0])]
        above = min(failing, key=lambda t: t[0]) if failing else None
        if best and above:
            if above[0] / best[0] <= precision:
                break
            x = math.sqrt(best[0] * above[0])
        elif above:
            factor = (tol / above[1]) ** (1 / exponent) * safety if above[1] > 0 else 0.5
            x = above[0] * min(max(factor, 0.05), 0.95)
        else:
            factor = (tol / best[1]) ** (1 / exponent) / safety if best[1] > 0 else max_factor
            x = best[0] * min(max(factor, 1.05), max_factor)
    return best, trials


def _scipy_rhs(dp):
    """The fastest right-hand side we can give ``solve_ivp``: compiled kernel or NumPy model."""
    from pendulum_lab import codegen

    kernels = codegen.load_kernels(2)
    params = codegen.parameters_array(dp.masses, dp.lengths, dp.g)
    acceleration = kernels.acceleration

    def compiled(t, y):
        out = np.empty(2)
        acceleration(t, y[:2], y[2:], params, out)
        return np.concatenate((y[2:], out))

    def numpy_model(t, y):
        return np.concatenate((y[2:], dp.accelerations(y[:2], y[2:])))

    y = np.array([2.0, 2.5, 0.3, -0.2])
    cost = {}
    for name, fn in (
        ("compiled kernel `codegen.load_kernels(2).acceleration`", compiled),
        ("NumPy `model.accelerations`", numpy_model),
    ):
        fn(0.0, y)
        cost[name] = min(
            timed(lambda f=fn: [f(0.0, y) for _ in range(300)])[0].cpu / 300 for _ in range(3)
        )
    name = min(cost, key=cost.get)
    return (compiled if name.startswith("compiled") else numpy_model), name, cost


def bench_long_run(cfg: Config) -> Section:
    """T = 1000 with max relative energy error <= 1e-8: our best method vs tuned DOP853."""
    from scipy.integrate import solve_ivp

    dp, theta0, omega0, _ = explorer_start()
    energy0 = float(dp.energy(theta0, omega0))
    T, tol = cfg.long_t_end, cfg.long_tol
    rhs, rhs_name, rhs_cost = _scipy_rhs(dp)
    details = [
        f"Double pendulum from theta = {THETA0} at rest (E0 = {energy0:.6f} J), "
        f"T = {T:g} s; requirement: max over every step of |E - E0|/|E0| <= {tol:g}.",
        "solve_ivp right-hand side: "
        + "; ".join(f"{k} {v * 1e6:.1f} us/call" for k, v in rhs_cost.items())
        + f"; used: {rhs_name} (the faster), in (theta, omega).",
    ]

    def run_ours(method, dt, t_end=T):
        sample, traj = timed(
            pl.simulate, dp, theta0, omega0, t_end=t_end, dt=dt, method=method, progress=False
        )
        return max_relative_energy_error(traj.energy), {
            "seconds": sample.cpu,
            "wall": sample.wall,
            "stepping": traj.wall_time,
            "sweeps": traj.mean_iterations,
        }

    def run_dop(rtol, t_end=T):
        sample, sol = timed(
            solve_ivp,
            rhs,
            (0.0, t_end),
            [*theta0, *omega0],
            method="DOP853",
            rtol=rtol,
            atol=rtol * cfg.atol_factor,
        )
        extra = {
            "seconds": sample.cpu,
            "wall": sample.wall,
            "steps": sol.t.size - 1,
            "nfev": sol.nfev,
        }
        if sol.status != 0:
            return float("inf"), extra
        return max_relative_energy_error(dp.energy(sol.y[:2].T, sol.y[2:].T)), extra

    for method in cfg.long_methods:
        run_ours(method, 0.1, t_end=1.0)  # load kernels
    cached = _load_search(cfg) if not cfg.long_search else None
    found: dict = {
        "T": T,
        "tol": tol,
        "atol_factor": cfg.atol_factor,
        "rhs": rhs_name,
        "ours": {},
        "dop853": {},
    }
    if cached is not None:
        found = cached
        details.append(
            f"dt and rtol reused from `{SEARCH_CACHE.relative_to(HERE.parent)}` "
            f"(searched {cached.get('date', '?')}); no search in this run."
        )
    elif not cfg.long_search:
        found["ours"] = {"glrk4": {"dt": FALLBACK_DT, "seconds": 0.0}}
        found["dop853"] = {"rtol": FALLBACK_RTOL}
        details.append(
            f"No search cache for T = {T:g}, tol = {tol:g}: using fallback values "
            f"dt = {FALLBACK_DT:g} (glrk4) and rtol = {FALLBACK_RTOL:g}; run the full "
            f"benchmark once to search."
        )
    else:
        for method in cfg.long_methods:
            found["ours"][method] = _search_ours(cfg, method, run_ours, details)
        found["dop853"] = _search_dop(cfg, run_dop, details)
        found["date"] = datetime.date.today().isoformat()
        if cfg.name == "full":
            RESULTS.mkdir(parents=True, exist_ok=True)
            SEARCH_CACHE.write_text(json.dumps(found, indent=2) + "\n")
    candidates = {m: v for m, v in found["ours"].items() if v.get("dt")}
    rtol = found["dop853"].get("rtol")
    data = {"search": found}
    if not candidates or rtol is None:
        return Section(
            "long_run",
            "3. Long-run accuracy per cost",
            [
                Row(
                    "3",
                    f"T={T:g}, energy <= {tol:g}",
                    "-",
                    "-",
                    "-",
                    "peer/ours >= 10",
                    "MISS (no passing setting found)",
                )
            ],
            details,
            data,
        )
    best = min(candidates, key=lambda m: candidates[m]["seconds"])
    dt = candidates[best]["dt"]
    last = {}

    def ours():
        err, extra = run_ours(best, dt)
        last["ours"] = (err, extra)
        return Sample(extra["wall"], extra["seconds"])

    def peer():
        err, extra = run_dop(rtol)
        last["dop"] = (err, extra)
        return Sample(extra["wall"], extra["seconds"])

    samples = interleave({"ours": ours, "dop853": peer}, cfg.long_rounds)
    t_ours, t_dop = med(samples["ours"]), med(samples["dop853"])
    w_ours, w_dop = med(samples["ours"], "wall"), med(samples["dop853"], "wall")
    err_ours, err_dop = last["ours"][0], last["dop"][0]
    ratio = t_dop / t_ours
    met = err_ours <= tol and err_dop <= tol
    rows = [
        Row(
            "3",
            f"T={T:g}, max rel. energy error <= {tol:g}",
            f"{best} dt={dt:.4g}: {fmt_time(t_ours)} CPU (err {err_ours:.2g})",
            f"DOP853 rtol={rtol:.2g}: {fmt_time(t_dop)} CPU (err {err_dop:.2g})",
            f"{ratio:.1f}x faster",
            "peer/ours >= 10 (CPU)",
            verdict(ratio, 10.0, at_most=False) if met else "MISS (requirement not met)",
        )
    ]
    for method, v in found["ours"].items():
        if method != best:
            shown = (
                f"dt={v['dt']:.4g}: {fmt_time(v['seconds'])} (search run)"
                if v.get("dt")
                else v.get("skipped", "no passing dt")
            )
            rows.append(Row("3", f"T={T:g}, other method: {method}", shown, "-", "-", "-", "info"))
    details.append(
        f"Timed: {cfg.long_rounds} interleaved round(s), medians of CPU time (wall: ours "
        f"{fmt_time(w_ours)}, DOP853 {fmt_time(w_dop)}, ratio {w_dop / w_ours:.1f}). "
        f"Search runs report CPU seconds. Ours = the whole "
        f"`pl.simulate` call (stepping {fmt_time(last['ours'][1]['stepping'])}, "
        f"{last['ours'][1]['sweeps']:.2f} sweeps/step, energies at all "
        f"{steps_for(T, dt) + 1} states included); DOP853 = the `solve_ivp` call "
        f"({last['dop'][1]['steps']} steps, {last['dop'][1].get('nfev', '?')} "
        f"evaluations; energies computed afterwards, not timed), "
        f"atol = rtol * {cfg.atol_factor:g}, dense output off, t_eval None."
    )
    data.update(
        {
            "best": best,
            "dt": dt,
            "rtol": rtol,
            "ours_cpu": t_ours,
            "dop853_cpu": t_dop,
            "ours_wall": w_ours,
            "dop853_wall": w_dop,
            "ours_error": err_ours,
            "dop853_error": err_dop,
            "ratio": ratio,
        }
    )
    return Section("long_run", "3. Long-run accuracy per cost", rows, details, data)


def _search_ours(cfg, method, run_ours, details) -> dict:
    order = pl.METHODS[method].order
    pilot_err, pilot = run_ours(method, cfg.long_pilot_dt, t_end=cfg.long_pilot_t_end)
    predicted = cfg.long_pilot_dt * (cfg.long_tol / max(pilot_err, 1e-300)) ** (1 / order)
    per_step = pilot["seconds"] / steps_for(cfg.long_pilot_t_end, cfg.long_pilot_dt)
    predicted_seconds = per_step * cfg.long_t_end / predicted
    details.append(
        f"{method}: pilot T = {cfg.long_pilot_t_end:g}, dt = {cfg.long_pilot_dt:g}: "
        f"error {pilot_err:.3g}; order {order} predicts dt ~ {predicted:.3g}, "
        f"~{predicted_seconds:.3g} s at T = {cfg.long_t_end:g}."
    )
    if predicted_seconds > cfg.long_max_trial_s:
        reason = (
            f"not run: predicted dt ~ {predicted:.2g} and ~{predicted_seconds:.0f} s "
            f"(> {cfg.long_max_trial_s:g} s limit)"
        )
        details.append(f"{method}: {reason}.")
        return {
            "skipped": reason,
            "predicted_dt": predicted,
            "predicted_seconds": predicted_seconds,
        }
    best, trials = _largest_passing(
        lambda dt: run_ours(method, dt),
        predicted * 0.9,
        order,
        cfg.long_tol,
        precision=1.05,
        max_trials=8,
    )
    details.append(
        f"{method} search (dt: error, CPU seconds): "
        + "; ".join(f"{x:.4g}: {e:.3g}, {extra['seconds']:.2f}" for x, e, extra in trials)
    )
    if best is None:
        return {"skipped": "no passing dt in the search", "trials": len(trials)}
    return {"dt": best[0], "error": best[1], "seconds": best[2]["seconds"]}


def _search_dop(cfg, run_dop, details) -> dict:
    best, trials = _largest_passing(
        run_dop,
        cfg.long_rtol_start,
        1.0,
        cfg.long_tol,
        precision=1.5,
        max_trials=8,
        max_factor=100.0,
    )
    details.append(
        "DOP853 search (rtol: error, CPU seconds): "
        + "; ".join(f"{x:.3g}: {e:.3g}, {extra['seconds']:.2f}" for x, e, extra in trials)
    )
    if best is None:
        return {}
    return {"rtol": best[0], "error": best[1], "seconds": best[2]["seconds"]}


def _load_search(cfg: Config) -> dict | None:
    try:
        found = json.loads(SEARCH_CACHE.read_text())
    except (OSError, ValueError):
        found = None
    if found is None or found.get("T") != cfg.long_t_end or found.get("tol") != cfg.long_tol:
        return None
    return found


# =========================================================================== item 4
def bench_report_glrk4(cfg: Config) -> Section:
    """The course report's GLRK4 (fsolve per step, NumPy model) vs ours, same dt and T."""
    dp, theta0, omega0, _ = explorer_start()
    T, dt = cfg.report_t_end, cfg.dt
    last = {}

    def ours():
        seconds, traj = timed(
            pl.simulate, dp, theta0, omega0, t_end=T, dt=dt, method="glrk4", progress=False
        )
        last["ours"] = traj
        return seconds

    def report():
        seconds, result = timed(report_glrk4.integrate, dp, theta0, omega0, T, dt)
        last["report"] = result
        return seconds

    ours()
    samples = interleave({"ours": ours, "report": report}, cfg.report_rounds)
    t_ours, t_report = med(samples["ours"]), med(samples["report"])
    w_ours, w_report = med(samples["ours"], "wall"), med(samples["report"], "wall")
    traj, (t, theta_r, _, energy_r, stepping_r) = last["ours"], last["report"]
    ratio = t_report / t_ours
    # Energy errors compare like with like only while both follow the same motion: the start
    # is chaotic, so after a while the two runs are on different trajectories.
    gap = np.max(np.abs(traj.theta - theta_r), axis=-1)
    apart = np.flatnonzero(gap > SAME_MOTION)
    window = int(apart[0]) if apart.size else t.size
    err_o = np.abs(traj.energy - traj.energy[0]) / abs(traj.energy[0])
    err_r = np.abs(energy_r - energy_r[0]) / abs(energy_r[0])
    win_o, win_r = float(np.max(err_o[:window])), float(np.max(err_r[:window]))
    full_o, full_r = float(np.max(err_o)), float(np.max(err_r))
    horizon = t[window - 1]
    rows = [
        Row(
            "4",
            f"GLRK4 dt={dt:g}, T={T:g}: speed",
            f"{fmt_time(t_ours)} CPU",
            f"report's fsolve GLRK4 {fmt_time(t_report)} CPU",
            f"{ratio:.0f}x faster",
            "peer/ours >= 50 (CPU)",
            verdict(ratio, 50.0, at_most=False),
        ),
        Row(
            "4",
            f"max rel. energy error on the common motion (t <= {horizon:.2f} s)",
            f"{win_o:.3g}",
            f"{win_r:.3g}",
            f"{win_o / win_r:.3f}",
            "ours <= peer (+1%)",
            "PASS" if win_o <= 1.01 * win_r else "MISS",
        ),
        Row(
            "4",
            f"max rel. energy error over all of T={T:g}",
            f"{full_o:.3g}",
            f"{full_r:.3g}",
            f"{full_o / full_r:.2f}",
            "(info: different motions after t above)",
            "info",
        ),
    ]
    details = [
        f"Peer: `benchmarks/report_glrk4.py`, the course report's approach (Kanoun, Cowley, "
        f"Ivachtchenko, MAT332, 2024, sect. 4.6.5): GLRK4 on (theta, omega), stage equations "
        f"solved by `scipy.optimize.fsolve` (default xtol) every step, NumPy model "
        f"accelerations. Both from theta = {THETA0} at rest, {steps_for(T, dt)} steps; whole "
        f"calls timed (energies included for both), {cfg.report_rounds} interleaved round(s), "
        f"medians of CPU time (wall: ours {fmt_time(w_ours)}, peer {fmt_time(w_report)}, "
        f"ratio {w_report / w_ours:.0f}).",
        f"Ours: {traj.mean_iterations:.2f} fixed-point sweeps/step, stepping "
        f"{fmt_time(traj.wall_time)}; peer stepping {fmt_time(stepping_r)}.",
        f"Accuracy: the start is chaotic, so the two runs (different variables, different "
        f"solver tolerance) separate: their angles differ by more than {SAME_MOTION:g} rad "
        f"from t = {horizon + dt:.2f} s on"
        + (f" and by {float(gap[-1]):.2g} rad at t = {T:g}" if apart.size else " (never here)")
        + ". Until then both integrate the same motion and their energy errors compare like "
        "with like; that comparison carries the verdict. The maxima over the whole run are "
        "shown too, but after the separation they belong to different motions.",
    ]
    data = {
        "ours": t_ours,
        "report": t_report,
        "ratio": ratio,
        "err_window_ours": win_o,
        "err_window_report": win_r,
        "window_end": horizon,
        "err_full_ours": full_o,
        "err_full_report": full_r,
        "samples": samples,
    }
    return Section("report_glrk4", "4. Against the report's approach", rows, details, data)


# =========================================================================== item 5
def ensemble_grid(side: int) -> np.ndarray:
    """``side x side`` angles uniform on ``[-pi/2, pi/2]^2``, shape (side, side, 2)."""
    axis = np.linspace(-np.pi / 2, np.pi / 2, side)
    return np.stack(np.meshgrid(axis, axis, indexing="ij"), axis=-1)


def bench_ensemble(cfg: Config, cloop: c_yardstick.CLoop | None) -> Section:
    """RK4 and GLRK4 trajectory-steps per second on side^2 initial conditions vs C per core."""
    dp = double_pendulum()
    theta = ensemble_grid(cfg.ensemble_side)
    omega = np.zeros_like(theta)
    members = theta.shape[0] * theta.shape[1]
    cores = os.cpu_count() or 1
    last = {}

    def ours(method):
        steps = cfg.ensemble_steps[method]

        def call():
            sample, traj = timed(
                pl.simulate,
                dp,
                theta,
                omega,
                t_end=steps * cfg.dt,
                dt=cfg.dt,
                method=method,
                save_every=steps,
                progress=False,
            )
            last[method] = traj
            return sample

        return call

    for method in cfg.ensemble_steps:  # load kernels
        pl.simulate(dp, theta[:2, :2], omega[:2, :2], t_end=cfg.dt, dt=cfg.dt, method=method)
    contenders = {m: ours(m) for m in cfg.ensemble_steps}
    c_steps = cfg.ensemble_steps["rk4"]
    if cloop is not None:

        def c_loop():
            run = cloop.ensemble(theta.reshape(-1, 2), np.zeros((members, 2)), c_steps, cfg.dt)
            last["C"] = run
            return Sample(run.seconds[0], run.cpu[0])

        contenders = {"C rk4": c_loop, **contenders}
    samples = interleave(contenders, cfg.ensemble_rounds)
    nan = float("nan")
    c_wall = members * c_steps / med(samples["C rk4"], "wall") if cloop else nan
    c_cpu = members * c_steps / med(samples["C rk4"]) if cloop else nan
    rows = []
    data = {
        "members": members,
        "cores": cores,
        "c_rate_wall": c_wall,
        "c_rate_cpu": c_cpu,
        "methods": {},
    }
    details = [
        f"{members} initial conditions ({cfg.ensemble_side} x {cfg.ensemble_side} grid on "
        f"[-pi/2, pi/2]^2, at rest), dt = {cfg.dt:g}, save_every = steps; "
        f"{cfg.ensemble_rounds} interleaved round(s), medians. The C loop runs on ONE thread "
        f"({c_steps} steps): {fmt_rate(c_wall)} by the wall clock, {fmt_rate(c_cpu)} per "
        f"CPU-second. `pl.simulate` splits the ensemble over os.cpu_count() = {cores} threads.",
        "'Per core' is measured as trajectory-steps per CPU-second on both sides (process CPU "
        "time: all our threads, Python included; the C program's CLOCK_PROCESS_CPUTIME_ID), "
        "which stays fair when the shared machine gives our threads less than a core each. "
        f"The naive figure, our wall-clock rate divided by {cores} cores against C's wall-clock "
        "rate, is given below as well ('nominal').",
    ]
    for method, steps in cfg.ensemble_steps.items():
        seconds, cpu_seconds = med(samples[method], "wall"), med(samples[method])
        traj = last[method]
        rate, per_cpu = members * steps / seconds, members * steps / cpu_seconds
        evals = traj.evaluations / (members * steps)
        ratio, nominal = c_cpu / per_cpu, c_wall / (rate / cores)
        data["methods"][method] = {
            "seconds": seconds,
            "cpu_seconds": cpu_seconds,
            "rate_wall": rate,
            "rate_cpu": per_cpu,
            "steps": steps,
            "evals_per_step": evals,
            "ratio": ratio,
            "ratio_nominal": nominal,
        }
        name = f"ensemble {members} x {steps} steps, {method}"
        ours_text = f"{fmt_rate(rate)} wall, {fmt_rate(per_cpu)}/CPU-s"
        peer_text = f"C RK4 {fmt_rate(c_cpu)}/CPU-s"
        if method == "rk4":
            rows.append(
                Row(
                    "5",
                    name,
                    ours_text,
                    peer_text,
                    f"{ratio:.1f}x",
                    "C/ours per core <= 3",
                    verdict(ratio, 3.0) if cloop else "not available",
                )
            )
        else:
            eval_ratio = ratio * 4 / evals
            rows.append(
                Row(
                    "5",
                    name,
                    ours_text,
                    peer_text,
                    f"{ratio:.1f}x",
                    "(info: another method)",
                    "info",
                )
            )
            rows.append(
                Row(
                    "5",
                    f"ensemble, {method} per field evaluation",
                    f"{fmt_rate(per_cpu * evals)} evals/CPU-s",
                    f"C RK4 {fmt_rate(c_cpu * 4)} evals/CPU-s",
                    f"{eval_ratio:.1f}x",
                    "C/ours per core <= 3",
                    verdict(eval_ratio, 3.0) if cloop else "not available",
                )
            )
        details.append(
            f"{method}: {fmt_time(seconds)} wall and {fmt_time(cpu_seconds)} CPU per run "
            f"(cores effectively used {cpu_seconds / seconds:.2f} of {cores}); "
            f"{evals:.1f} field evaluations/step ({traj.mean_iterations:.2f} sweeps); "
            f"nominal ratio {nominal:.1f}x."
        )
    if cloop is not None:
        traj, run = last["rk4"], last["C"]
        gap = max(
            float(np.max(np.abs(run.theta - traj.theta[-1].reshape(-1, 2)))),
            float(np.max(np.abs(run.p - traj.p[-1].reshape(-1, 2)))),
        )
        data["c_gap"] = gap
        details.append(
            f"C vs `pl.simulate(..., 'rk4')` final states, max |difference| over "
            f"all members: {gap:.3g}."
        )
    rows += _flip_map(cfg, dp, c_cpu, data, details)
    return Section("ensemble", "5. Ensemble throughput", rows, details, data)


def _flip_map(cfg, dp, c_cpu, data, details) -> list[Row]:
    try:
        from pendulum_lab import chaos
    except ImportError:
        chaos = None
    if chaos is None or not hasattr(chaos, "flip_time_map"):
        return [Row("5", "flip-time map", "-", "-", "-", "-", "not available")]
    chaos.flip_time_map(dp, size=4, t_end=0.1, dt=cfg.dt, progress=False)
    sample, fm = timed(
        chaos.flip_time_map, dp, size=cfg.flip_size, t_end=cfg.flip_t_end, dt=cfg.dt, progress=False
    )
    seconds, cpu_seconds = sample.wall, sample.cpu
    simulated = ~fm.forbidden
    work = int(np.sum(np.ceil(np.minimum(fm.time[simulated], fm.t_end) / fm.dt)))
    c_equivalent = work / c_cpu
    ratio = cpu_seconds / c_equivalent
    data["flip_map"] = {
        "seconds": seconds,
        "cpu_seconds": cpu_seconds,
        "work": work,
        "cells": int(simulated.sum()),
        "c_equivalent_cpu": c_equivalent,
    }
    details.append(
        f"Flip-time map: `chaos.flip_time_map(dp, size={cfg.flip_size}, "
        f"t_end={cfg.flip_t_end:g}, dt={cfg.dt:g})` (method {fm.method}, default grid "
        f"half-width), one run: {fmt_time(seconds)} wall, {fmt_time(cpu_seconds)} CPU. "
        f"{int(simulated.sum())} of {fm.time.size} cells simulated (the rest cannot flip on "
        f"energy grounds), at least {work} trajectory-steps (each cell up to its flip time; "
        f"cells leave at the end of a segment, so the real count is a little higher). "
        f"'C-equivalent' = that work at the C loop's rate per CPU-second; the ratio compares "
        f"CPU time with it."
    )
    return [
        Row(
            "5",
            f"flip-time map {cfg.flip_size}x{cfg.flip_size} to t={cfg.flip_t_end:g}",
            f"{fmt_time(seconds)} wall, {fmt_time(cpu_seconds)} CPU",
            f"C-equivalent {fmt_time(c_equivalent)} CPU",
            f"{ratio:.1f}x",
            "(info)",
            "info",
        )
    ]


# =========================================================================== item 6
def bench_c_limit(cfg: Config, cloop: c_yardstick.CLoop | None) -> Section:
    """The C RK4 loop itself: its speed per step, and that it does the same work as ours."""
    if cloop is None:
        return Section(
            "c_limit",
            "6. Physical limit (C)",
            [Row("6", "C RK4 loop", "-", "-", "-", "-", "not available")],
            [f"No C compiler (`{c_yardstick.COMPILER}`) found."],
            {},
        )
    dp, theta0, omega0, p0 = explorer_start()
    n_steps = steps_for(cfg.slider_t_end, cfg.dt)
    last = {}

    def ours():
        traj = pl.simulate(
            dp, theta0, omega0, t_end=cfg.slider_t_end, dt=cfg.dt, method="rk4", progress=False
        )
        last["ours"] = traj
        return Sample(traj.wall_time, float("nan"))

    def c_loop():
        run = cloop.single(theta0, p0, n_steps, cfg.dt, reps=cfg.c_inner_reps)
        last["C"] = run
        return Sample(median(run.seconds), median(run.cpu))

    ours()
    samples = interleave({"C": c_loop, "ours": ours}, cfg.rounds)
    c_step = med(samples["C"], "wall") / n_steps
    our_step = med(samples["ours"], "wall") / n_steps
    q, p = last["C"].theta, last["C"].p
    gap = max(
        float(np.max(np.abs(q - last["ours"].theta[-1]))),
        float(np.max(np.abs(p - last["ours"].p[-1]))),
    )
    rows = [
        Row(
            "6",
            f"C RK4, one trajectory ({n_steps} steps)",
            f"rk4 loop {our_step * 1e6:.3g} us/step",
            f"C {c_step * 1e6:.3g} us/step",
            f"{our_step / c_step:.1f}x",
            "(yardstick)",
            "info",
        ),
        Row(
            "6",
            f"C vs pl.simulate rk4: end state at t={cfg.slider_t_end:g}",
            f"max |diff| = {gap:.2g}",
            "-",
            "-",
            "<= 1e-9",
            "PASS" if gap <= 1e-9 else "MISS",
        ),
    ]
    # A small ensemble, checked member by member.
    theta = ensemble_grid(max(2, int(math.sqrt(cfg.limit_members)))).reshape(-1, 2)
    members = theta.shape[0]
    t_end = cfg.limit_steps * cfg.dt
    traj = pl.simulate(
        dp,
        theta,
        np.zeros_like(theta),
        t_end=t_end,
        dt=cfg.dt,
        method="rk4",
        save_every=cfg.limit_steps,
        progress=False,
    )
    run = cloop.ensemble(theta, np.zeros_like(theta), cfg.limit_steps, cfg.dt)
    egap = max(
        float(np.max(np.abs(run.theta - traj.theta[-1]))), float(np.max(np.abs(run.p - traj.p[-1])))
    )
    rows.append(
        Row(
            "6",
            f"C vs pl.simulate rk4: {members}-member ensemble, end states",
            f"max |diff| = {egap:.2g}",
            "-",
            "-",
            "<= 1e-9",
            "PASS" if egap <= 1e-9 else "MISS",
        )
    )
    source = cloop.source.read_text()
    details = [
        f"Generated from `pl.derive_chain(2)`: the mass matrix and dL/dq printed with "
        f"`sympy.ccode` after `sympy.cse` (the Hamiltonian form our kernels use: "
        f"dq = M^-1 p by Cramer's rule, dp = dL/dq at omega = dq), RK4 on (theta, p) with "
        f"every sum associated as in `integrators.explicit_rk`; compiled as "
        f"`{cloop.command}` ({c_yardstick.compiler_version()}) in a temporary folder; "
        f"the program times itself with clock_gettime(CLOCK_MONOTONIC). "
        f"{len(source.splitlines())} lines of C.",
        f"Per step: C {c_step * 1e9:.0f} ns, ours (compiled loop only, "
        f"`traj.wall_time`) {our_step * 1e9:.0f} ns; {cfg.rounds} interleaved rounds, "
        f"medians. Ensemble check: {members} members x {cfg.limit_steps} steps, C "
        f"{fmt_time(run.seconds[0])} on one thread, ours {fmt_time(traj.wall_time)}.",
        "Identical arithmetic makes the end states agree to the last bit when the same "
        "libm is used; a nonzero difference would grow with the motion's chaos.",
    ]
    data = {"c_step": c_step, "our_step": our_step, "gap": gap, "ensemble_gap": egap}
    return Section("c_limit", "6. Physical limit (C)", rows, details, data)


# =========================================================================== running
ITEMS = {
    "slider": (1, bench_slider, True),
    "first_use": (2, bench_first_use, False),
    "long_run": (3, bench_long_run, False),
    "report_glrk4": (4, bench_report_glrk4, False),
    "ensemble": (5, bench_ensemble, True),
    "c_limit": (6, bench_c_limit, True),
}


def resolve(names) -> list[str]:
    """Item keys from names or numbers (``"slider"``, ``"1"``); all items for none."""
    if not names:
        return list(ITEMS)
    by_number = {str(number): key for key, (number, _, _) in ITEMS.items()}
    keys = []
    for name in names:
        key = by_number.get(str(name), str(name).replace("-", "_"))
        if key not in ITEMS:
            raise ValueError(f"unknown benchmark {name!r}; choose from {list(ITEMS)} or 1-6")
        keys.append(key)
    return sorted(set(keys), key=lambda k: ITEMS[k][0])


def run_items(cfg: Config, keys, log=print) -> list[Section]:
    """Build the C loop if needed, run the items in order, never let one failure stop the rest."""
    sections = []
    with tempfile.TemporaryDirectory(prefix="pendulum_bench_") as tmp:
        cloop, c_error = None, ""
        if any(ITEMS[k][2] for k in keys):
            try:
                cloop = c_yardstick.build(double_pendulum(), tmp)
            except RuntimeError as err:
                c_error = str(err)
        for key in keys:
            number, fn, needs_c = ITEMS[key]
            log(f"[{time.strftime('%H:%M:%S')}] item {number}: {key} ...")
            start = time.perf_counter()
            try:
                section = fn(cfg, cloop) if needs_c else fn(cfg)
            except Exception as err:  # noqa: BLE001 - report and go on to the next item
                section = Section(
                    key,
                    f"{number}. {key}",
                    [Row(str(number), key, "-", "-", "-", "-", "ERROR")],
                    [f"ERROR: {type(err).__name__}: {err}"],
                    {},
                )
            if needs_c and cloop is None and c_error:
                section.details.append(f"C loop unavailable: {c_error}")
            section.seconds = time.perf_counter() - start
            log(f"    done in {section.seconds:.1f} s")
            sections.append(section)
    return sections
