"""What a chain of ``n`` links costs: symbolic derivation, first use, a step.

Timings are measurements of this machine and this session (what is already
compiled or cached), printed by notebook 12; the speed targets of the package
live in ``benchmarks/`` as ratios.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from sympy.core.cache import clear_cache

from . import _validation as check
from .integrators import get_method
from .mechanics import Chain
from .model import n_pendulum
from .simulate import simulate, time_grid

__all__ = ["ChainCost", "chain_costs"]


@dataclass(frozen=True)
class ChainCost:
    """What a chain of ``n`` links costs.

    Attributes
    ----------
    n : int
    derivation : float
        Seconds for a fresh symbolic derivation of the mass matrix and the
        forcing (:class:`~pendulum_lab.Chain`).
    build : float
        Seconds for :func:`~pendulum_lab.n_pendulum` (prepares the numeric
        functions the first time ``n`` is used in a session, then reuses them).
    first_simulation : float
        Seconds of the first :func:`~pendulum_lab.simulate` call after building.
    per_step : float
        Seconds per step of a repeated run (``Trajectory.wall_time / steps``,
        the best of three runs).
    method : str
    """

    n: int
    derivation: float
    build: float
    first_simulation: float
    per_step: float
    method: str


def chain_costs(
    ns=(3, 4, 5), *, t_end: float = 2.0, dt: float = 0.01, method="glrk4"
) -> list[ChainCost]:
    """Measure derivation time, first-use time and step cost of n-link chains.

    For each ``n``: a fresh :class:`~pendulum_lab.mechanics.Chain` is
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
        Timings depend on the machine and on what this session already
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
        start = time.perf_counter()
        model = n_pendulum(n)
        build = time.perf_counter() - start
        theta0, omega0 = np.full(n, 0.5), np.zeros(n)
        start = time.perf_counter()
        simulate(model, theta0, omega0, t_end=t_end, dt=dt, method=method, progress=False)
        first = time.perf_counter() - start
        repeats = [
            simulate(
                model, theta0, omega0, t_end=t_end, dt=dt, method=method, progress=False
            ).wall_time
            for _ in range(3)
        ]
        rows.append(ChainCost(n, derivation, build, first, min(repeats) / steps, method.name))
    return rows
