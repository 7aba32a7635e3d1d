"""Compile every Numba kernel of the course ahead of time (``pendulum-lab warmup``).

Numba compiles each kernel the first time it runs on a machine (a few seconds
each) and keeps the machine code on disk. This module sits on top of the
layers so that it can reach every kernel: the vector fields and the step
functions of every registered method compiled into the time loop of each
field (:mod:`pendulum_lab.driver.loops`), the discrete Legendre transforms of the
variational methods, and the standard map's loop.
"""

from __future__ import annotations

import time

import numpy as np

from .. import validation as check
from ..driver.simulate import hamiltonian_field, simulate
from ..geometric.standard_map import first_crossings
from ..integrators import (
    CONFORMAL_METHODS,
    METHODS,
    VARIATIONAL_METHODS,
    get_method,
    unsuitability,
)
from ..model.pendulum import driven_pendulum, n_pendulum

__all__ = ["warm_up"]


def warm_up(ns=(1, 2), methods=None, progress: bool = True) -> float:
    """Compile now, or load from the disk cache, the kernels the course uses.

    Calling this ahead of time (``pendulum-lab warmup``; the Binder image does
    it while it is built) spares students the wait.

    Parameters
    ----------
    ns : sequence of int
        Chain lengths (numbers of links) to prepare: 1 the simple pendulum
        (and the driven pendulum's kernels), 2 the double pendulum, ...
    methods : sequence of str, optional
        Method names; all of :data:`pendulum_lab.METHODS`,
        ``CONFORMAL_METHODS`` and ``VARIATIONAL_METHODS`` by default. The
        standard map's kernel (notebook 15) is compiled too when all methods
        are.
    progress : bool
        Show a progress bar.

    Returns
    -------
    float
        Seconds spent.
    """
    everything = [*METHODS, *CONFORMAL_METHODS, *VARIATIONAL_METHODS]
    if isinstance(methods, str):
        methods = [methods]
    names = [get_method(m).name for m in (everything if methods is None else methods)]
    if isinstance(ns, (int, np.integer)) or not hasattr(ns, "__iter__"):
        raise TypeError(f"`ns` must be a sequence of chain lengths (numbers of links), such as "
                        f"[1, 2], got {ns!r}")
    ns = [check.integer_at_least("ns", n, 1) for n in ns]
    start = time.perf_counter()
    jobs = [(n, name) for n in ns for name in names]
    if progress:
        from tqdm.auto import tqdm

        jobs = tqdm(jobs, desc="compiling kernels", unit="kernel")
    for n, name in jobs:
        simulate(n_pendulum(n), np.full(n, 0.1), np.zeros(n), t_end=0.01, dt=0.01, method=name)
    if 1 in ns:  # each (field, method) pair has its own compiled loop: the forced field too
        driven = driven_pendulum()
        field = hamiltonian_field(driven)
        for name in names:
            if unsuitability(get_method(name), field) is None:
                simulate(driven, [0.1], [0.0], t_end=0.01, dt=0.01, method=name)
    if methods is None:
        first_crossings([1.0], [0.1], [0.0], 1)
    return time.perf_counter() - start
