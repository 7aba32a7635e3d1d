"""What every benchmark item shares: configurations, result rows, timing, the machine.

Machines are noisy (and shared), so every figure that carries a target is a
ratio of two contenders timed in the same run, interleaved round by round
(the order rotates each round), each summarised by the median of its rounds.
Each item (``item_*.py``, one file per item) takes a :class:`Config` and
returns a :class:`Section`: table rows (with target and PASS/MISS), detail
lines and the raw numbers.
"""

from __future__ import annotations

import datetime
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

import c_yardstick
import numpy as np

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

    ``FULL`` is the configuration the targets are stated for; ``QUICK`` a short
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
    long_methods: tuple = ("glrk12", "glrk8", "glrk4", "leapfrog")
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
    variational_t_end: float = 20.0  # item 7
    variational_rounds: int = 7
    bif_values: int = 600  # item 8: amplitudes of the bifurcation diagram
    bif_periods: int = 300  # sampled drive periods
    bif_transient: int = 300  # drive periods before the samples
    bif_steps_per_period: int = 100
    bif_rounds: int = 2
    bif_c_members: int = 20  # members the C loop runs for its time per step
    live_rounds: int = 15  # item 9: interleaved update/recompute rounds in the kernel
    live_browser_seconds: float = 5.0  # item 9: play time counted in Chromium (0: not run)
    per_eval_steps: int = 50000  # item 10: steps of the long run (the short one: a tenth)
    per_eval_repeats: int = 3
    per_eval_rounds: int = 3
    per_eval_before: bool = True  # also measure the package at item_per_eval.BEFORE (git archive)
    floor_dt: float = 0.002  # item 10: energy floor of glrk8 (truncation far below round-off)
    floor_t_end: float = 1000.0
    peer_t_end: float = 1000.0  # item 11 (heyoka)
    peer_long_t_end: float = 1e4
    peer_grid: float = 0.01
    peer_requirements: tuple = (1e-8, 1e-11)
    peer_targets: dict = field(default_factory=lambda: {1e-8: 1.0, 1e-11: 1.5})
    peer_pilot_dt: float = 0.02
    heyoka_tol_steps: int = 12  # tolerances tried in half-decades from the requirement down
    peer_rounds: int = 3
    stage_study_t_end: float = 100.0  # item 11: the stage-solver count (stage_solvers.py)
    pyhamsys_t_end: float = 100.0  # item 12
    pyhamsys_step: float = 0.01
    chain_rounds: int = 3  # item 13: long chains
    chain_first_use: tuple = (10, 20, 50)
    chain_printed: tuple = (3, 4, 5)
    chain_evaluations: int = 200_000
    chain_sizes: tuple = (3, 5, 10, 20, 50, 100, 200)
    chain_step_budget: int = 20_000  # steps x links per timed run
    cluster_size: int = 1000  # item 14: flip-time map on a Dask LocalCluster
    cluster_t_end: float = 10.0
    cluster_workers: int = 2
    # item 15: systems given by their points; runs of 50 ms, since a few ms are noise-dominated
    systems_steps: int = 400_000
    systems_rounds: int = 7
    systems_processes: int = 5  # fresh processes; the median of their ratios
    systems_first_use: bool = True  # fresh processes with empty kernel caches


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
    variational_rounds=3,
    bif_values=120,
    bif_periods=60,
    bif_transient=60,
    bif_rounds=1,
    bif_c_members=10,
    live_rounds=4,
    live_browser_seconds=2.0,
    per_eval_steps=20000,
    per_eval_repeats=1,
    per_eval_rounds=1,
    per_eval_before=False,
    systems_steps=20000,
    systems_rounds=1,
    systems_processes=1,
    floor_t_end=100.0,
    peer_t_end=100.0,
    peer_long_t_end=300.0,
    peer_rounds=1,
    stage_study_t_end=10.0,
    pyhamsys_t_end=10.0,
    chain_rounds=1,
    chain_first_use=(20,),
    chain_printed=(3,),
    chain_evaluations=20_000,
    chain_sizes=(3, 10, 50),
    chain_step_budget=5_000,
    cluster_size=150,
    cluster_t_end=5.0,
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
    variational_t_end=0.2,
    variational_rounds=1,
    bif_values=4,
    bif_periods=2,
    bif_transient=2,
    bif_steps_per_period=10,
    bif_rounds=1,
    bif_c_members=2,
    live_rounds=1,
    live_browser_seconds=0.0,
    per_eval_steps=200,
    per_eval_repeats=1,
    per_eval_rounds=1,
    per_eval_before=False,
    systems_steps=500,
    systems_rounds=1,
    systems_processes=1,
    systems_first_use=False,
    floor_dt=0.01,
    floor_t_end=1.0,
    peer_t_end=2.0,
    peer_long_t_end=4.0,
    peer_requirements=(1e-6,),
    peer_pilot_dt=0.05,
    heyoka_tol_steps=4,
    peer_rounds=1,
    stage_study_t_end=0.5,
    pyhamsys_t_end=0.5,
    pyhamsys_step=0.05,
    chain_rounds=1,
    chain_first_use=(10,),
    chain_printed=(3,),
    chain_evaluations=100,
    chain_sizes=(3, 10, 20),
    chain_step_budget=200,
    cluster_size=8,
    cluster_t_end=0.5,
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



def child_json(args: list[str], what: str, *, env: dict | None = None,
               timeout: float = 900) -> dict:
    """The JSON object that ``python *args`` prints on its last line; a RuntimeError naming
    ``what``, with the end of the child's stderr, if it fails."""
    done = subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env,
                          encoding="utf-8", errors="replace",
                          timeout=timeout, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"{what} failed: {done.stderr.strip()[-500:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])

# --------------------------------------------------------------------------- helpers
def double_pendulum():
    return pl.double_pendulum()


def explorer_start():
    """The default explorer's initial state: theta, omega, p (each shape (2,))."""
    dp = double_pendulum()
    theta0 = np.array(THETA0)
    omega0 = np.zeros(2)
    return dp, theta0, omega0, dp.momenta(theta0, omega0)


def max_relative_energy_error(energy) -> float:
    energy = np.asarray(energy)
    return float(np.max(np.abs(energy - energy[0])) / abs(energy[0]))


# --------------------------------------------------------------------------- machine
def machine_description() -> dict:
    """CPU, cores, load, versions and the environment variables that steer threads."""
    cpu = cpu_name()
    try:
        affinity = len(os.sched_getaffinity(0))
    except AttributeError:  # macOS and Windows have no affinity call
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
        "load_start": load_average(),
    }


#: Linux's description of the processors (absent on macOS and Windows, and in some sandboxes).
CPUINFO = Path("/proc/cpuinfo")


def cpu_name() -> str:
    """The processor's model name: Linux's ``/proc/cpuinfo``, else what ``platform`` says
    (Windows: family and vendor; macOS: ``arm`` or ``i386``), else ``"unknown"``."""
    try:
        for line in CPUINFO.read_text(encoding="utf-8", errors="replace").splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def load_average() -> tuple[float, float, float] | None:
    """The 1, 5 and 15 minute load averages, or None where there are none (Windows)."""
    try:
        return os.getloadavg()
    except (AttributeError, OSError):
        return None


def load_text(load, separator: str = ", ") -> str:
    """A :func:`load_average` for a report: ``"0.52, 0.61, 0.70"``, or ``"unknown"``."""
    return "unknown" if load is None else separator.join(f"{x:.2f}" for x in load)


def _git(*args) -> str:
    try:
        out = subprocess.run(
            ["git", "-C", str(HERE), *args], capture_output=True, text=True, encoding="utf-8",
            errors="replace", check=False, timeout=10,
        )
    except (OSError, subprocess.TimeoutExpired):
        return ""
    return out.stdout.strip() if out.returncode == 0 else ""
