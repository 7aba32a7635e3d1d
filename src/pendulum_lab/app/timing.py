"""What things cost on this machine: a chain of ``n`` links, a method's first use.

Timings are measurements of this machine and this process (what is already
compiled or cached), printed by notebooks 00 and 12; the speed targets of the package
live in ``benchmarks/`` as ratios.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from sympy import count_ops
from sympy.core.cache import clear_cache

from .. import validation as check
from ..driver.simulate import simulate, time_grid
from ..integrators import get_method
from ..model import n_pendulum
from ..symbolic.mechanics import Chain

__all__ = ["ChainCost", "FirstUseCost", "chain_costs", "first_use_cost"]


@dataclass(frozen=True)
class ChainCost:
    """What a chain of ``n`` links costs.

    Attributes
    ----------
    n : int
    operations : int
        Arithmetic and function operations in the mass matrix and the forcing
        (``sympy.count_ops``): the size of the equations, the same on every
        computer, unlike the times.
    derivation : float
        Seconds for a fresh symbolic derivation of the mass matrix and the
        forcing (:class:`~pendulum_lab.Chain`).
    build : float
        Seconds for :func:`~pendulum_lab.n_pendulum` (prepares the numeric
        functions the first time ``n`` is used in a process, then reuses them).
    first_simulation : float
        Seconds of the first :func:`~pendulum_lab.simulate` call after building.
    per_step : float
        Seconds per step of a repeated run (``Trajectory.wall_time / steps``,
        the best of three runs).
    evaluations_per_step : float
        Vector-field evaluations per step in that run (implicit methods make
        one per stage and fixed-point sweep, so this depends on the motion).
    per_evaluation : float
        Seconds per evaluation in that run: the cost of Hamilton's equations
        for ``n`` links, apart from how many the method needs.
    method : str
    """

    n: int
    operations: int
    derivation: float
    build: float
    first_simulation: float
    per_step: float
    evaluations_per_step: float
    per_evaluation: float
    method: str


def chain_costs(
    ns=(3, 4, 5), *, t_end: float = 2.0, dt: float = 0.01, method="glrk4"
) -> list[ChainCost]:
    """Measure derivation time, first-use time, step and evaluation cost of n-link chains.

    For each ``n``: a fresh :class:`~pendulum_lab.symbolic.mechanics.Chain` is
    derived and timed (after clearing SymPy's cache); then the model is
    built, simulated once (first use) and three times more (steady state),
    all links starting at 0.5 rad at rest.

    Parameters
    ----------
    ns : sequence of int
        Numbers of links, each ``>= 1``.
    t_end, dt, method
        The test run.

    Returns
    -------
    list of ChainCost
        Timings depend on the machine and on what this process already
        compiled; they are measurements, not constants.
    """
    method = get_method(method)
    _, dt, steps = time_grid(t_end, dt)
    rows = []
    for n in ns:
        n = check.integer_at_least("ns", n, 1)
        clear_cache()  # SymPy's own cache would make a repeated derivation look cheap
        start = time.perf_counter()
        chain = Chain(n)
        _ = chain.mass_matrix, chain.forcing  # built on first access, entry by entry
        derivation = time.perf_counter() - start
        operations = int(count_ops([*chain.mass_matrix, *chain.forcing]))
        start = time.perf_counter()
        model = n_pendulum(n)
        build = time.perf_counter() - start
        theta0, omega0 = np.full(n, 0.5), np.zeros(n)
        start = time.perf_counter()
        simulate(model, theta0, omega0, t_end=t_end, dt=dt, method=method, progress=False)
        first = time.perf_counter() - start
        repeats = [
            simulate(model, theta0, omega0, t_end=t_end, dt=dt, method=method, progress=False)
            for _ in range(3)
        ]
        best = min(repeats, key=lambda run: run.wall_time)
        rows.append(ChainCost(n, operations, derivation, build, first, best.wall_time / steps,
                              best.evaluations / steps, best.wall_time / best.evaluations,
                              method.name))
    return rows


@dataclass(frozen=True)
class FirstUseCost:
    """What the first simulation costs on a new machine, and in later processes.

    Attributes
    ----------
    compile : float
        Seconds for the first :func:`~pendulum_lab.simulate` call of a fresh
        process whose kernel caches are empty: the kernels are generated and
        compiled by Numba (what every method costs once per machine).
    load : float
        The same call in a second fresh process, with the caches the first one
        filled: machine code loaded from disk.
    run : float
        The same call repeated within that process: the simulation itself.
    method : str
    n : int
    """

    compile: float
    load: float
    run: float
    method: str
    n: int


_FIRST_USE = """
import json, sys, time
import numpy as np
import pendulum_lab as pl
n, method = int(sys.argv[1]), sys.argv[2]
model = pl.n_pendulum(n)
times = []
for _ in range(2):
    start = time.perf_counter()
    pl.simulate(model, np.full(n, 0.5), np.zeros(n), t_end=1.0, dt=0.01, method=method,
                progress=False)
    times.append(time.perf_counter() - start)
print(json.dumps(times))
"""


def first_use_cost(n: int = 2, method="glrk4") -> FirstUseCost:
    """Measure the one-time compilation of a method's kernels, against loading and running.

    Two fresh Python processes share a new, empty temporary kernel cache
    (``PENDULUM_LAB_CACHE``: the generated source and Numba's machine code; no
    shared layer, ``PENDULUM_LAB_SHARED_CACHE``, is read): the first compiles, the
    second loads. Each runs a 1 s simulation of ``n`` links (100 steps) twice.
    The caches of the running process and of the user are not touched.

    Parameters
    ----------
    n : int
        Number of links.
    method : str or Method

    Returns
    -------
    FirstUseCost
        Timings of this machine (a measurement, not a constant).
    """
    import json
    import os
    import subprocess
    import sys
    import tempfile

    n = check.integer_at_least("n", n, 1)
    name = get_method(method).name
    firsts, seconds = [], []
    with tempfile.TemporaryDirectory() as kernels, tempfile.TemporaryDirectory() as machine_code:
        env = {k: v for k, v in os.environ.items() if k != "PENDULUM_LAB_SHARED_CACHE"}
        env |= {"PENDULUM_LAB_CACHE": kernels, "NUMBA_CACHE_DIR": machine_code,
                "PYTHONIOENCODING": "utf-8"}
        for _ in range(2):
            done = subprocess.run([sys.executable, "-c", _FIRST_USE, str(n), name], env=env,
                                  capture_output=True, text=True, encoding="utf-8",
                                  errors="replace", check=False)
            if done.returncode != 0:
                raise RuntimeError(f"the measuring process failed: {done.stderr.strip()[-500:]}")
            first, second = json.loads(done.stdout.strip().splitlines()[-1])
            firsts.append(first)
            seconds.append(second)
    return FirstUseCost(compile=firsts[0], load=firsts[1], run=seconds[1], method=name, n=n)
