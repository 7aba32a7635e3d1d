"""The time loop, compiled once for each pair of a vector field and a method.

:func:`time_loop` advances every trajectory of an ensemble by many steps of
one method; it is the package's only time loop. It is never compiled on its
own: for each field (the kernels of :mod:`pendulum_lab.codegen.kernels`) and each
method (a :class:`~pendulum_lab.integrators.Step`), :func:`compile_method`
writes a small module into the kernel cache that compiles the loop, the
step and the field's kernels into one machine-code function, ``run``. Inside
it every kernel call is a direct call that the compiler can inline, where a
loop compiled once for all fields would call the kernels through function
pointers, slower per evaluation (docs/design/compiled-loop.md). Numba keeps ``run`` on
disk: it is compiled once per machine, and a change in the field, the
method or this code gets a new file name, so a stale one is never loaded
(:mod:`pendulum_lab.codegen.cache`). A run holds the result, a
:class:`CompiledMethod`, and steps with it; nothing is looked up again.

Each trajectory has a row of ``memory`` (:meth:`CompiledMethod.new_memory`) that the loop
hands to every step and keeps between steps and between calls (a long run
is several calls): the step's workspace and what it carries from one step to
the next (see :mod:`pendulum_lab.integrators`).
"""

from __future__ import annotations

import functools
import math
import os
import re
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numba
import numpy as np
from numba import types

from ..codegen.cache import load_generated
from ..codegen.kernels import import_name
from ..codegen.lowlevel import keep_alive, span, unmanaged
from ..integrators import (
    MAX_SWEEPS,
    ConvergenceError,
    HamiltonianField,
    Method,
    Step,
    kernel_function,
    step_kernels,
)

__all__ = [
    "CALLS",
    "RUN",
    "NOT_CONVERGED",
    "NOT_FINITE",
    "RUNNING",
    "STATUS",
    "STEPS",
    "SWEEPS",
    "CompiledMethod",
    "compile_method",
    "loop_source",
    "time_loop",
]

#: Codes in ``stats[:, STATUS]`` after :func:`time_loop`.
RUNNING, NOT_FINITE, NOT_CONVERGED = 0, 1, 2
#: Columns of ``stats``.
STEPS, SWEEPS, CALLS, STATUS = 0, 1, 2, 3
#: Ensembles at least this large are split across threads.
PARALLEL_MIN_MEMBERS = 64
_ROWS, _ROW = types.float64[:, ::1], types.float64[::1]
#: The Numba type of every compiled loop ``run`` (the generated module's): ``(separable,
#: damping_rates, q, p, t0, h, n_steps, first_step, origin, save_every, params, saved_q,
#: saved_p, stats, memory)``, C arrays. Given, so that the loop is compiled (or loaded) when its
#: module is made, in :func:`compile_method`, and never on a run's first call.
RUN = types.void(types.boolean, _ROW, _ROWS, _ROWS, types.float64, types.float64, types.int64,
                 types.int64, types.int64, types.int64, _ROWS, types.float64[:, :, ::1],
                 types.float64[:, :, ::1], types.int64[:, ::1], _ROWS)


@numba.njit
def _all_finite(x):
    """``np.all(np.isfinite(x))`` without allocating a temporary array."""
    for value in x:
        if not math.isfinite(value):
            return False
    return True


@numba.njit
def _copy(out, x):
    """``out[:] = x`` for 1-d arrays, as a plain loop (Numba's slice assignment checks for
    overlapping memory and may copy, which is slower for a few elements)."""
    for i in range(out.size):
        out[i] = x[i]


@kernel_function
def time_loop(step, first_kernel, second_kernel, n, separable, damping_rates, q, p, t0, h,
              n_steps, first_step, origin, save_every, params, saved_q, saved_p, stats, memory):
    """Advance every row of ``(q, p)`` (shape ``(K, n)``) by ``n_steps`` steps, in place.

    ``step`` receives ``first_kernel`` and ``second_kernel``: the field's
    ``hamilton`` and ``acceleration``, or a variational method's update and
    impulse (:func:`~pendulum_lab.integrators.step_kernels`).

    ``n`` is the number of coordinates, a constant where the loop is compiled
    (the field's ``COORDINATES``): the steps' loops over coordinates then
    have a known length, which the compiler unrolls.

    Steps are numbered globally from ``first_step + 1`` so that a long run can
    be made of several calls (for a progress bar, for segments); step ``s`` goes from time
    ``t0 + (s - 1) h`` to ``t0 + s h`` (computed from ``s``, not summed: a run cut into
    segments evaluates a drive at the same times as one long call, to the bit), and row
    ``k``'s state after it is stored in ``saved_q[k, (s - origin) // save_every]`` when
    ``save_every`` divides ``s - origin`` (``origin``: the step of the state saved first,
    where this segment starts; ``stats`` counts steps from it). ``params`` (shape ``(1, P)`` or
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
        until_save = save_every - (first_step - origin) % save_every
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
            done = s - origin
            sweeps_done += sweeps
            until_save -= 1
            if until_save == 0:
                saved_q[k, done // save_every] = qk
                saved_p[k, done // save_every] = pk
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
    keep_alive(state)


_TEMPLATE = '''"""Generated by pendulum_lab.driver.loops: the time loop of the method {method!r}
with the kernels {first} and {second}; do not edit.

The step ({step}) is set by pendulum_lab.driver.loops before this runs.
"""
from pendulum_lab.codegen.cache import cached_njit
from pendulum_lab.codegen.lowlevel import align_stack
from pendulum_lab.driver.loops import RUN, time_loop
from {first_module} import {first_name} as first_kernel
from {second_module} import {second_name} as second_kernel

#: Coordinates of the state: the loops over them have a known length.
COORDINATES = {n}


@cached_njit(RUN, nogil=True)
def run(separable, damping_rates, q, p, t0, h, n_steps, first_step, origin, save_every, params,
        saved_q, saved_p, stats, memory):
    """time_loop(step, first_kernel, second_kernel, ...) with this module's step and kernels."""
    align_stack()  # the steps' vectorized loops spill 64-byte registers to the stack
    if q.shape[1] != COORDINATES or p.shape[1] != COORDINATES:
        raise ValueError("the states do not have this loop's number of coordinates")
    time_loop(step, first_kernel, second_kernel, COORDINATES, separable, damping_rates, q, p, t0,
              h, n_steps, first_step, origin, save_every, params, saved_q, saved_p, stats,
              memory)
'''


def loop_source(method: Method, first, second, n: int) -> str:
    """The generated module that compiles ``method``'s step with the kernels ``first``, ``second``.

    ``first`` and ``second`` are what the step receives as its two kernels
    (:func:`~pendulum_lab.integrators.step_kernels`); ``n`` the number of coordinates.
    """
    step = method.kernel
    (first_module, first_name), (second_module, second_name) = map(import_name,
                                                                    (first, second))
    return _TEMPLATE.format(method=method.name, step=step.__qualname__,
                            first=f"{first_module}.{first_name}",
                            second=f"{second_module}.{second_name}", first_module=first_module,
                            first_name=first_name, second_module=second_module,
                            second_name=second_name, n=n)


@functools.cache
def _load(method: Method, step: Step, first, second, n: int, field_name: str):
    stem = first.py_func.__module__.removeprefix("pendulum_lab_kernels_")
    stem = f"{stem}_{re.sub(r'[^A-Za-z0-9_]', '_', method.name)}"
    module, _ = load_generated(stem, loop_source(method, first, second, n),
                               inject={"step": step.compiled},
                               what=f"{method.name} for {field_name}")
    return module.run


@dataclass(frozen=True)
class CompiledMethod:
    """A method compiled into the time loop of one field: what a run steps with.

    Made by :func:`compile_method`, once per run, after the driver has checked that the method
    fits the field. ``run`` is the compiled loop (:func:`time_loop` with the method's step and
    the field's kernels); the field's parameters and damping rates are passed to it on each
    call, so a compiled loop serves every model with the same kernels.
    """

    method: Method
    field: HamiltonianField
    n: int
    run: object = field(repr=False)

    def new_memory(self, members: int) -> np.ndarray:
        """Zeroed loop memory for ``members`` trajectories: a fresh start.

        Shape ``(members, S)`` with ``S = max(1, method.kernel.memory(n))``.
        """
        return np.zeros((members, max(1, self.method.kernel.memory(self.n))))

    def advance(self, q, p, h, n_steps, first_step, save_every, saved_q, saved_p, stats,
                memory, t0: float = 0.0, origin: int = 0) -> None:
        """Run the compiled loop on rows ``q, p`` of shape ``(K, n)``, in place.

        Step ``s`` (counted from 1 over the whole run, ``first_step`` before this call)
        starts at time ``t0 + (s - 1) h``; the states saved are those after steps
        ``origin + j save_every`` (``origin``: the steps of the earlier segments of a run
        handed out in segments, 0 otherwise), at ``saved_q[:, j]``. ``field.params`` and
        ``field.damping_rate`` may hold one row per member (shapes ``(K, P)``, ``(K,)``);
        ``memory`` (shape ``(K, S)``, :meth:`new_memory`) is what the method keeps per member
        between steps and calls.
        Large ensembles are split into one slice per core; the compiled loop releases the
        GIL, so the slices run in parallel threads.
        """
        params = np.atleast_2d(np.asarray(self.field.params, dtype=float))
        rates = np.atleast_1d(np.asarray(self.field.damping_rate, dtype=float))
        per_member = params.shape[0] > 1

        def advance(rows):
            try:
                self.run(self.field.separable, rates[rows] if per_member else rates, q[rows],
                         p[rows], float(t0), float(h), n_steps, first_step, origin, save_every,
                         params[rows] if per_member else params, saved_q[rows],
                         saved_p[rows], stats[rows], memory[rows])
            except ZeroDivisionError:  # compiled code raises it where NumPy would give inf
                raise ValueError(
                    f"{self.method.name}: a step of {self.field.name} divided by zero: the "
                    "state reached a place where its equations are not defined (a singular "
                    "mass matrix, such as r = 0 of polar coordinates, where the angle is not "
                    "defined); start elsewhere, or describe the system with coordinates that "
                    "stay regular along the motion") from None

        members, workers = q.shape[0], os.cpu_count() or 1
        if members < PARALLEL_MIN_MEMBERS or workers == 1:
            advance(slice(None))
            return
        bounds = np.linspace(0, members, workers + 1).astype(int)
        list(_pool(workers).map(advance, [slice(a, b) for a, b in zip(bounds[:-1], bounds[1:])]))

    def step_rows(self, q: np.ndarray, y: np.ndarray, h: float, what: str,
                  t0: float = 0.0) -> None:
        """One step from time ``t0`` for every row of ``q, y`` (C arrays), in place.

        Starts from a fresh memory (nothing carried over from an earlier step). ``what``
        names the step in the :class:`~pendulum_lab.integrators.ConvergenceError` raised if
        the implicit equations do not converge.
        """
        unused = np.empty((q.shape[0], 1, q.shape[1]))
        stats = np.zeros((q.shape[0], 4), dtype=np.int64)
        self.advance(q, y, h, 1, 0, 2, unused, unused, stats, self.new_memory(q.shape[0]), t0)
        if np.any(stats[:, STATUS] == NOT_CONVERGED):
            raise ConvergenceError(f"{self.method.name}: the implicit equations did not "
                                   f"converge within {MAX_SWEEPS} iterations ({what})")


def compile_method(method: Method, field: HamiltonianField, n: int) -> CompiledMethod:
    """``method`` compiled with the kernels it takes from ``field``, for ``n`` coordinates.

    The loop is made on first use (compiled once per machine, then loaded from disk) and
    kept for the life of the process; all of that happens here, announced as the compilation
    of "``method`` for ``field.name``" (:mod:`pendulum_lab.codegen.compile_status`: a note after
    :data:`~pendulum_lab.codegen.compile_status.NOTE_DELAY` seconds, or the listeners of the
    calling thread), so that running the result compiles nothing. The caller has checked that
    ``method`` can integrate ``field``
    (:func:`~pendulum_lab.integrators.unsuitability`).
    """
    first, second = step_kernels(method, field)
    run = _load(method, method.kernel, first, second, n, field.name)
    return CompiledMethod(method, field, n, run)


@functools.cache
def _pool(workers: int) -> ThreadPoolExecutor:
    """One thread pool for the whole process (starting threads per call costs milliseconds)."""
    return ThreadPoolExecutor(workers, thread_name_prefix="pendulum_lab")
