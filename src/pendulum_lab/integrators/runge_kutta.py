"""Runge-Kutta methods stepped from their Butcher tableaus: explicit ones and implicit ones.

:func:`tableau_step` makes a method's step from its tableau: an explicit tableau is stepped by
:func:`explicit_rk`, an implicit one by :func:`implicit_rk`, which solves the stage equations by
fixed-point iteration to round-off
(:func:`~pendulum_lab.integrators.stopping.fixed_point_status`) and evaluates all the stages of
a sweep in one call of the field's ``stages`` kernel.

References
----------
.. [HLW] E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
   Springer 2006: Gauss collocation (Sect. II.1.3, VI.4), starting values for the stage
   iteration (Sect. VIII.6.1), compensated summation (Sect. VIII.5).
"""

from __future__ import annotations

import functools

import numba
import numpy as np

from ..codegen.lowlevel import LANE_GROUP, block, span, stack_floats, vector
from .step import Step, jit_step, kernel_function
from .stopping import MAX_SWEEPS, fixed_point_status
from .tableau import ButcherTableau

__all__ = [
    "MAX_STAGE_LANES",
    "compensated_sum",
    "explicit_rk",
    "explicit_rk_memory",
    "implicit_rk",
    "implicit_rk_memory",
    "stage_lanes",
    "tableau_step",
]


def explicit_rk_memory(stages: int, n: int) -> int:
    """Floats of workspace :func:`explicit_rk` needs: the stage slopes and two states."""
    return (2 * stages + 4) * n


@kernel_function
def explicit_rk(hamilton, t, q, p, h, params, a, b, c, work):
    """One step of the explicit Runge-Kutta method ``(a, b, c)``.

    Stage ``i`` evaluates the field at time ``t + c_i h`` and state
    ``y + h sum_{j<i} a_ij k_j``; the step is ``y + h sum_i b_i k_i``. Written
    with element loops in the workspace ``work`` (:func:`explicit_rk_memory`
    floats: vectors ``2 i`` and ``2 i + 1`` hold stage ``i``'s ``dq``, ``dp``,
    then come the stage state and the new state): allocating small arrays
    would cost more than the arithmetic. The new state is returned as views
    into ``work``.
    """
    stages, n = b.size, q.size
    qi, pi = vector(work, 2 * stages, n), vector(work, 2 * stages + 1, n)
    q1, p1 = vector(work, 2 * stages + 2, n), vector(work, 2 * stages + 3, n)
    for i in range(stages):
        for m in range(n):
            qi[m], pi[m] = q[m], p[m]
            for j in range(i):
                qi[m] += h * a[i, j] * work[2 * j * n + m]
                pi[m] += h * a[i, j] * work[(2 * j + 1) * n + m]
        hamilton(t + c[i] * h, qi, pi, params, vector(work, 2 * i, n),
                 vector(work, 2 * i + 1, n))
    for m in range(n):
        q1[m], p1[m] = q[m], p[m]
    for i in range(stages):
        for m in range(n):
            q1[m] += h * b[i] * work[2 * i * n + m]
            p1[m] += h * b[i] * work[(2 * i + 1) * n + m]
    return q1, p1


def stage_lanes(stages: int) -> int:
    """Columns of the states an implicit step hands the ``stages`` kernel.

    A multiple of 8 from 3 stages on; one or two stages (``glrk4``) cost less
    evaluated one by one than as 8 columns of which 6 are padding (measured).
    """
    if stages <= 2:
        return stages
    return -(-stages // LANE_GROUP) * LANE_GROUP


def implicit_rk_memory(stages: int, n: int) -> int:
    """Floats of memory :func:`implicit_rk` keeps per trajectory.

    With ``L = stage_lanes(stages)`` columns: the compensation of the state's
    rounding (``2 n``), two iterates of the stage slopes and the stopping
    rule's record (``3 x 2 n L``), the stage states (``2 n L``), their times
    (``L``), the stage kernel's scratch (``4 n``) and the new state (``2 n``);
    then two numbers saying which slopes are stored: the step size they
    belong to (0: none) and the iterate that holds them.
    """
    lanes = stage_lanes(stages)
    return 8 * n * lanes + lanes + 8 * n + 2


#: The most columns an implicit step's stages take (:func:`stage_lanes`): its
#: stage sums are accumulated in a stack buffer of this size.
MAX_STAGE_LANES = 64


@numba.njit(inline="always")  # with Numba's inlining the loop bounds stay constants
def _combine_row(memory, row, columns, stages, lanes, out):
    """``out[i] = sum_j columns[j, i] memory[row + j]`` for ``i < lanes``, summed over j in order.

    The innermost loop runs over ``i``, so it vectorizes, and ``out`` is a stack buffer
    (:func:`~pendulum_lab.codegen.lowlevel.stack_floats`), which LLVM knows the loads from
    ``memory`` cannot see: written into ``memory`` directly, the sums must be stored and loaded
    again for every ``j`` (glrk16's 4 x 8 x 8 took 66 ns a sweep as dot products per stage, 32
    ns this way, in a micro-benchmark; a glrk16 run over 1000 s took 43.0 instead of 50.4 ms).
    """
    slope = memory[row]
    for i in range(lanes):
        out[i] = columns[0, i] * slope
    for j in range(1, stages):
        slope = memory[row + j]
        for i in range(lanes):
            out[i] += columns[j, i] * slope


@kernel_function
def implicit_rk(hamilton, stage_field, t, q, p, h, params, a_columns, b, c_lanes,
                extrapolation_columns, memory):
    """One step of the implicit Runge-Kutta method ``(a, b, c)``.

    The stage slopes solve ``K_i = f(t + c_i h, y + h sum_j a_ij K_j)``; they
    are found by fixed-point iteration, each sweep re-evaluating every stage
    at the latest slopes, until :func:`fixed_point_status` finds round-off.
    A sweep hands all stage states to ``stage_field`` (the field's ``stages``
    kernel) at once, as the columns of a ``(2 n, lanes)`` array: the
    generated fields evaluate them with SIMD instructions
    (:mod:`pendulum_lab.codegen.kernels`). ``c_lanes`` is ``c`` padded with zeros to
    the number of columns (:func:`stage_lanes`) and ``a_columns`` is ``a``
    transposed and padded with zero columns (``a_columns[j, i] = a_ij``), so
    that the columns beyond the stages hold the step's start.

    A slope's round-off is not set by its own size: it enters the stage
    states as ``y + h sum_j a_ij K_j``, rounded to the state's last place, so
    a slope stalls at about ``L ulp(y)`` (``L`` the field's Lipschitz
    constant). The stopping rule's "tiny" is therefore judged against
    ``max |y| / h`` too; without it a long run whose angles had grown to a
    few hundred radians stalled just above the tolerance and was refused.

    The first guess: if ``memory`` holds the slopes of a previous step of the
    same size, they are continued with ``K_i^0 = sum_j E_ij K_j^prev``
    (``E``, :attr:`ButcherTableau.extrapolation`, given as
    ``extrapolation_columns`` like ``a``, or empty: the
    derivative of the previous step's collocation polynomial, one step on),
    which is ``O(h^s)`` close [HLW, Sect. VIII.6.1] and saves sweeps;
    otherwise (a first step, or no ``E``) the guess is
    ``K_i^0 = hamilton(t, y)``, one evaluation. The step is
    ``y1 = y + h sum_i b_i K_i``, added with compensated summation: the part
    of the increment that rounding to ``y1`` loses is kept in ``memory`` and
    added at the next step, so that round-off does not accumulate over a long
    run [HLW, Sect. VIII.5]. ``memory`` holds :func:`implicit_rk_memory`
    floats. Returns ``(q1, p1, sweeps, calls)`` (``q1, p1`` views into
    ``memory``), with ``sweeps = -1`` if the iteration did not converge.
    """
    stages, n, lanes = b.size, q.size, c_lanes.size
    size = 2 * n * lanes  # one iterate of the slopes, in floats
    # Float r lanes + i of an iterate is row r (dq of coordinate r, then dp of
    # coordinate r - n) of stage i; the stage states have the same layout.
    slopes = 2 * n
    compensation, smallest = span(memory, 0, slopes), span(memory, slopes + 2 * size, size)
    states = slopes + 3 * size
    stage_states = block(memory, states, 2 * n, lanes)
    ts, work = span(memory, states + size, lanes), span(memory, states + size + lanes, 4 * n)
    at = states + size + lanes + 4 * n
    q1, p1 = span(memory, at, n), span(memory, at + n, n)
    stored_step, stored_iterate = at + 2 * n, at + 2 * n + 1
    calls = 0
    sums = stack_floats(MAX_STAGE_LANES)
    if memory[stored_step] == h and extrapolation_columns.shape[0] == stages:
        previous = int(memory[stored_iterate])
        current = 1 - previous
        for r in range(2 * n):
            _combine_row(memory, slopes + previous * size + r * lanes, extrapolation_columns,
                         stages, lanes, sums)
            new_row = slopes + current * size + r * lanes
            for i in range(lanes):
                memory[new_row + i] = sums[i]
    else:
        current = 0
        hamilton(t, q, p, params, span(work, 0, n), span(work, n, n))
        calls = 1
        for r in range(2 * n):
            for i in range(stages):
                memory[slopes + r * lanes + i] = work[r]
    for i in range(lanes):
        ts[i] = t + c_lanes[i] * h
    smallest[:] = np.inf
    floor = 0.0
    for m in range(n):
        floor = max(floor, abs(q[m]), abs(p[m]))
    floor /= abs(h)
    sweeps, status = 0, 0
    while status == 0 and sweeps < MAX_SWEEPS:
        sweeps += 1
        new = 1 - current
        old_at, new_at = slopes + current * size, slopes + new * size
        for r in range(2 * n):
            _combine_row(memory, old_at + r * lanes, a_columns, stages, lanes, sums)
            start, row = q[r] if r < n else p[r - n], states + r * lanes
            for i in range(lanes):
                memory[row + i] = start + h * sums[i]
        stage_field(ts, stage_states, params, block(memory, new_at, 2 * n, lanes), work)
        status = fixed_point_status(span(memory, new_at, size), span(memory, old_at, size),
                                    smallest, floor)
        current = new
    calls += stages * sweeps
    if status != 1:
        memory[stored_step] = 0.0
        return q, p, -1, calls
    memory[stored_step], memory[stored_iterate] = h, current
    at = slopes + current * size
    for m in range(n):
        increment_q, increment_p = 0.0, 0.0
        for i in range(stages):
            increment_q += b[i] * memory[at + m * lanes + i]
            increment_p += b[i] * memory[at + (n + m) * lanes + i]
        q1[m] = compensated_sum(q[m], h * increment_q, compensation, m)
        p1[m] = compensated_sum(p[m], h * increment_p, compensation, n + m)
    return q1, p1, sweeps, calls


@numba.njit
def compensated_sum(y, increment, compensation, i):
    """``y + increment``, with the rounding error carried in ``compensation[i]`` [HLW, VIII.5]."""
    carried = compensation[i] + increment
    total = y + carried
    compensation[i] = carried + (y - total)
    return total


def _lane_columns(matrix: np.ndarray, lanes: int) -> np.ndarray:
    """``matrix`` (stages x stages) transposed and padded with zero columns to ``lanes``.

    C-ordered, as :func:`_combine_row`'s vectorized loop reads its rows
    (``np.pad`` of a transpose would give a Fortran-ordered array).
    """
    stages = matrix.shape[0]
    columns = np.zeros((stages, lanes))
    columns[:, :stages] = matrix.T
    return columns


def tableau_step(tableau: ButcherTableau, name: str) -> Step:
    """The step function of the Runge-Kutta method ``name``, made from its tableau.

    An explicit tableau is stepped by :func:`explicit_rk`, an implicit one by
    :func:`implicit_rk` (which starts each step from the previous one through
    the tableau's :attr:`~ButcherTableau.extrapolation`). The coefficients are
    closed over, so Numba compiles them in as constants; the evaluation count
    comes from the number of stages. Each method's step is named
    ``<name>_step``.
    """
    a, b, c, stages = tableau.a, tableau.b, tableau.c, tableau.stages
    if tableau.explicit:

        def explicit_tableau_step(hamilton, acceleration, t, q, p, h, params, separable,
                                  damping_rate, memory):
            """One step of an explicit Runge-Kutta method: ``stages`` evaluations."""
            q1, p1 = explicit_rk(hamilton, t, q, p, h, params, a, b, c, memory)
            return q1, p1, 0, stages

        step, size = explicit_tableau_step, functools.partial(explicit_rk_memory, stages)
    else:
        lanes = stage_lanes(stages)
        if lanes > MAX_STAGE_LANES:
            raise ValueError(f"`tableau` has {stages} stages; an implicit method may have at "
                             f"most {MAX_STAGE_LANES}")
        c_lanes = np.zeros(lanes)
        c_lanes[:stages] = c
        a_columns = _lane_columns(a, lanes)
        extrapolation_columns = np.zeros((0, 0))
        if tableau.extrapolation is not None:  # None: coinciding nodes, no polynomial to continue
            extrapolation_columns = _lane_columns(tableau.extrapolation, lanes)

        def implicit_tableau_step(hamilton, stage_field, t, q, p, h, params, separable,
                                  damping_rate, memory):
            """One step of an implicit Runge-Kutta method (stages by fixed-point iteration).

            It receives the field's ``stages`` kernel in place of
            ``acceleration`` (:func:`step_kernels`).
            """
            return implicit_rk(hamilton, stage_field, t, q, p, h, params, a_columns, b, c_lanes,
                               extrapolation_columns, memory)

        step, size = implicit_tableau_step, functools.partial(implicit_rk_memory, stages)
    step.__name__ = step.__qualname__ = f"{name}_step"
    return jit_step(step, memory=size)
