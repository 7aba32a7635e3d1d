"""The time loop, compiled once for each pair of a vector field and a method.

:func:`time_loop` advances every trajectory of an ensemble by many steps of
one method; it is the package's only time loop. It is never compiled on its
own: for each field (the kernels of :mod:`pendulum_lab.codegen`) and each
method (a :class:`~pendulum_lab.integrators.Step`), :func:`compiled_loop`
writes a small module into the kernel cache that compiles the loop, the
step and the field's kernels into one machine-code function, ``run``. Inside
it every kernel call is a direct call that the compiler can inline, where a
loop compiled once for all fields would call the kernels through function
pointers (about 30 ns more per evaluation, measured). Numba keeps ``run`` on
disk: it is compiled once per machine, and a change in the field, the
method or this code gets a new file name, so a stale one is never loaded.

Each trajectory has a row of ``memory`` (:func:`new_memory`) that the loop
hands to every step and keeps between steps and between calls (a long run
is several calls): the step's workspace and what it carries from one step to
the next (see :mod:`pendulum_lab.integrators`).
"""

from __future__ import annotations

import functools
import math
import re

import numba
import numpy as np

from . import codegen
from .integrators import (
    HamiltonianField,
    Method,
    Step,
    kernel_function,
    span,
    step_kernels,
    unmanaged,
)

__all__ = [
    "CALLS",
    "NOT_CONVERGED",
    "NOT_FINITE",
    "RUNNING",
    "STATUS",
    "STEPS",
    "SWEEPS",
    "compiled_loop",
    "loop_source",
    "new_memory",
    "time_loop",
]

#: Codes in ``stats[:, STATUS]`` after :func:`time_loop`.
RUNNING, NOT_FINITE, NOT_CONVERGED = 0, 1, 2
#: Columns of ``stats``.
STEPS, SWEEPS, CALLS, STATUS = 0, 1, 2, 3


@numba.njit
def _all_finite(x):
    """``np.all(np.isfinite(x))`` without allocating a temporary array."""
    for value in x:
        if not math.isfinite(value):
            return False
    return True


@numba.njit
def _keep(array):
    """Nothing: a use of ``array`` that keeps it alive up to this point (see :func:`time_loop`)."""


@numba.njit
def _copy(out, x):
    """``out[:] = x`` for 1-d arrays, as a plain loop (Numba's slice assignment checks for
    overlapping memory and may copy: several times slower for a few elements)."""
    for i in range(out.size):
        out[i] = x[i]


@kernel_function
def time_loop(step, first_kernel, second_kernel, n, separable, damping_rates, q, p, t0, h,
              n_steps, first_step, save_every, params, saved_q, saved_p, stats, memory):
    """Advance every row of ``(q, p)`` (shape ``(K, n)``) by ``n_steps`` steps, in place.

    ``step`` receives ``first_kernel`` and ``second_kernel``: the field's
    ``hamilton`` and ``acceleration``, or a variational method's update and
    impulse (:func:`~pendulum_lab.integrators.step_kernels`).

    ``n`` is the number of coordinates, a constant where the loop is compiled
    (the field's ``COORDINATES``): the steps' loops over coordinates then
    have a known length, which the compiler unrolls.

    Steps are numbered globally from ``first_step + 1`` so that a long run can
    be made of several calls (for a progress bar); step ``s`` goes from time
    ``t0 + (s - 1) h`` to ``t0 + s h`` (computed from ``s``, not summed), and
    row ``k``'s state after it is stored in ``saved_q[k, s // save_every]``
    when ``save_every`` divides ``s``. ``params`` (shape ``(1, P)`` or
    ``(K, P)``) and ``damping_rates`` (shape ``(1,)`` or ``(K,)``) are shared
    or per row; ``memory[k]`` is row ``k``'s memory, handed to every step.
    ``stats[k]`` accumulates (steps done, solver sweeps, vector-field calls,
    status); a row stops at a non-finite state or a solver failure, keeping
    its status. Rows are independent; the caller may run slices of them in
    parallel threads (the compiled loop releases the GIL).
    """
    shared = params.shape[0] == 1
    # The arrays handed to the steps are views without reference counts (see
    # integrators.vector): counting the references of arrays passed through the
    # inlined step functions would cost more than a small step's arithmetic.
    state = np.empty(2 * n)
    qk, pk = span(state, 0, n), span(state, n, n)
    for k in range(q.shape[0]):
        if stats[k, STATUS] != RUNNING:
            continue
        row = 0 if shared else k
        row_params, damping_rate = unmanaged(params[row]), damping_rates[row]
        row_memory = unmanaged(memory[k])
        _copy(qk, q[k])
        _copy(pk, p[k])
        done, sweeps_done, calls_done, status = stats[k, STEPS], 0, 0, RUNNING
        until_save = save_every - first_step % save_every
        for s in range(first_step + 1, first_step + n_steps + 1):
            q1, p1, sweeps, calls = step(first_kernel, second_kernel, t0 + (s - 1) * h, qk, pk, h,
                                         row_params, separable, damping_rate, row_memory)
            calls_done += calls
            if sweeps < 0:
                status = NOT_CONVERGED
                break
            _copy(qk, q1)  # a step may return views into its memory: copy
            _copy(pk, p1)
            if not (_all_finite(qk) and _all_finite(pk)):
                status = NOT_FINITE
                break
            done = s
            sweeps_done += sweeps
            until_save -= 1
            if until_save == 0:
                saved_q[k, s // save_every] = qk
                saved_p[k, s // save_every] = pk
                until_save = save_every
        q[k], p[k] = qk, pk
        stats[k, STEPS] = done
        stats[k, SWEEPS] += sweeps_done
        stats[k, CALLS] += calls_done
        stats[k, STATUS] = status
    # qk and pk point into `state` without holding a reference to it, and Numba
    # frees an array after the last line that names it: without this use, the
    # kernels' own allocations (a long chain's workspace) could be given the
    # state's memory and overwrite it mid-step.
    _keep(state)


def new_memory(method: Method, members: int, n: int) -> np.ndarray:
    """Zeroed loop memory for ``members`` trajectories of ``n`` coordinates: a fresh start.

    Shape ``(members, S)`` with ``S = max(1, method.kernel.memory(n))``.
    """
    return np.zeros((members, max(1, method.kernel.memory(n))))


_TEMPLATE = '''"""Generated by pendulum_lab.loops: the time loop of the method {method!r}
with the kernels {first} and {second}; do not edit.

The step ({step}, digest {digest}) is set by pendulum_lab.loops before this runs.
"""
import numba

from pendulum_lab._llvm_attributes import align_stack
from pendulum_lab.loops import time_loop
from {first_module} import {first_name} as first_kernel
from {second_module} import {second_name} as second_kernel

#: Coordinates of the state: the loops over them have a known length.
COORDINATES = {n}


@numba.njit(cache=True, nogil=True)
def run(separable, damping_rates, q, p, t0, h, n_steps, first_step, save_every, params, saved_q,
        saved_p, stats, memory):
    """time_loop(step, first_kernel, second_kernel, ...) with this module's step and kernels."""
    align_stack()  # the steps' vectorized loops spill 64-byte registers to the stack
    if q.shape[1] != COORDINATES or p.shape[1] != COORDINATES:
        raise ValueError("the states do not have this loop's number of coordinates")
    time_loop(step, first_kernel, second_kernel, COORDINATES, separable, damping_rates, q, p, t0,
              h, n_steps, first_step, save_every, params, saved_q, saved_p, stats, memory)
'''


def loop_source(method: Method, first, second, n: int) -> str:
    """The generated module that compiles ``method``'s step with the kernels ``first``, ``second``.

    ``first`` and ``second`` are what the step receives as its two kernels
    (:func:`~pendulum_lab.integrators.step_kernels`); ``n`` the number of coordinates.
    """
    step = method.kernel
    (first_module, first_name), (second_module, second_name) = map(codegen.import_name,
                                                                    (first, second))
    return _TEMPLATE.format(method=method.name, step=step.__qualname__, digest=step.digest,
                            first=f"{first_module}.{first_name}",
                            second=f"{second_module}.{second_name}", first_module=first_module,
                            first_name=first_name, second_module=second_module,
                            second_name=second_name, n=n)


@functools.cache
def _load(method: Method, step: Step, first, second, n: int):
    stem = first.py_func.__module__.removeprefix("pendulum_lab_kernels_")
    stem = f"{stem}_{re.sub(r'[^A-Za-z0-9_]', '_', method.name)}"
    module, _ = codegen.load_generated(stem, loop_source(method, first, second, n),
                                       derived_from=("loops.py", *codegen.package_files(first,
                                                                                        second)),
                                       inject={"step": step.compiled})
    return module.run


def compiled_loop(field: HamiltonianField, method: Method, n: int):
    """The compiled time loop of ``method`` on ``field`` for ``n`` coordinates (made on first use).

    Returns ``run(separable, damping_rates, q, p, t0, h, n_steps, first_step,
    save_every, params, saved_q, saved_p, stats, memory)``: :func:`time_loop`
    with the method's step and the kernels it takes on this field
    (:func:`~pendulum_lab.integrators.step_kernels`).
    """
    first, second = step_kernels(method, field)
    return _load(method, method.kernel, first, second, n)
