"""One-step integrators for vector fields, compiled with Numba.

This module knows vector fields, not pendulums. A vector field is a set of
compiled kernels (see :mod:`pendulum_lab._signatures`):
``hamilton(t, q, p, params, dq, dp)`` writes ``dq = dH/dp`` and
``dp = -dH/dq + Q`` (``Q``: forces no Hamiltonian describes, such as
damping); ``acceleration(t, q, v, params, out)`` writes the acceleration for
the course report's velocity-variable methods; ``stages`` evaluates
``hamilton`` at the several stage states of an implicit step in one call.
``t`` is the time, for fields that depend on it (a driven pendulum).

Every method is a step function ``(hamilton, acceleration, t, q, p, h,
params, separable, damping_rate[, memory]) -> (q1, p1, sweeps, calls)``
advancing from time ``t`` to ``t + h``: ``p`` is the canonical momentum for
all methods except the two ``*_velocity`` ones, where it is the velocity;
``sweeps`` counts implicit-solver iterations (``-1``: did not converge) and
``calls`` the vector-field evaluations. ``separable`` and ``damping_rate``
describe the field (see :class:`HamiltonianField`). A step declared with a
memory size (``jit_step(memory=...)``) takes one more argument, ``memory``:
floats that the time loop keeps for each trajectory from one step to the
next. Steps use it as workspace (no memory is allocated inside a run) and
the implicit Runge-Kutta methods for what they carry between steps: the
last stage slopes, from which the next step's iteration starts, and the
rounding error of the state (compensated summation). A fresh ``memory``
(zeros) is a first step: nothing carried over. The time loop that drives the
steps is :mod:`pendulum_lab.loops`; it compiles each method together with
each field, so the field's kernels are called directly (and inlined), not
through function pointers.

Methods are data where they can be: a Runge-Kutta method (explicit Euler,
RK4, Gauss-Legendre) is one registry entry made from its Butcher tableau by
:meth:`Method.from_tableau`, which derives its order, implicitness,
symplecticity and evaluation count (:mod:`pendulum_lab.tableau`); explicit
tableaus are stepped by :func:`explicit_rk`, implicit ones by
:func:`implicit_rk` (fixed-point iteration), which evaluates all stages in
one call of the field's third kernel, ``stages``, received in place of
``acceleration`` (:func:`step_kernels`). Stage ``i`` is evaluated at time
``t + c_i h``. The symplectic partitioned methods follow the textbook
formulas line by line, with the time attached to the positions (extended
phase space: the first kick at ``t``, the last at ``t + h``); the conformal
methods compose them with the exact flow of linear damping. All implicit
equations are iterated to round-off with one stopping rule,
:func:`fixed_point_status`.

The variational integrators (:data:`VARIATIONAL_METHODS`) are made from a
discrete Lagrangian instead of the vector field: their step solves the
discrete Legendre transform with kernels generated per chain
(:func:`pendulum_lab.codegen.load_discrete_kernels`), which it receives in
place of ``hamilton`` and ``acceleration`` (same Numba types; see
:func:`step_kernels`).

Which fields a method accepts (:attr:`Method.applies_to`): Runge-Kutta and
the velocity methods integrate any field; symplectic Euler and the leapfrog
assume a Hamiltonian one (a drive is fine: ``H`` then depends on ``t``); the
conformal methods need damping of the form ``-gamma p`` (constant
``gamma``); the variational methods need the discrete Lagrangian of an
unforced chain. :func:`unsuitability` says why a method does not fit a field.

References
----------
.. [HLW] E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*,
   2nd ed., Springer 2006: symplectic Euler (Thm VI.3.3), Stormer-Verlet for
   general H (eq. VI.3.4), Gauss collocation (Sect. II.1.3, VI.4), starting
   values for the stage iteration (Sect. VIII.6.1), compensated summation
   (Sect. VIII.5); a time-dependent H is made autonomous by taking t as one
   more coordinate.
.. [HMR] E. Hairer, R. I. McLachlan, A. Razakarivony, "Achieving Brouwer's
   law with implicit Runge-Kutta methods", BIT 48 (2008) 231-243: iterate the
   stage equations to round-off, or energy drifts; compensated summation.
.. [MP] R. I. McLachlan, M. Perlmutter, "Conformal Hamiltonian systems",
   J. Geom. Phys. 39 (2001) 276-300: splitting a conformal Hamiltonian field
   into its Hamiltonian part and the linear damping keeps the exact
   contraction of the symplectic form.
.. [MW] J. E. Marsden, M. West, "Discrete mechanics and variational
   integrators", Acta Numerica 10 (2001) 357-514, Sect. 1.3 and 2.1: the
   discrete Legendre transforms define a symplectic one-step map.
"""

from __future__ import annotations

import functools
import hashlib
import inspect
import math
from dataclasses import dataclass, field

import llvmlite.ir as llvm_ir
import numba
import numpy as np
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from . import _validation as check
from ._lane_math import LANE_GROUP
from ._llvm_attributes import inline_into_callers
from .discrete_mechanics import RULES
from .tableau import ButcherTableau, gauss_legendre_tableau

__all__ = [
    "CONFORMAL_METHODS",
    "METHODS",
    "VARIATIONAL_METHODS",
    "ButcherTableau",
    "ConvergenceError",
    "HamiltonianField",
    "Method",
    "Step",
    "explicit_rk",
    "fixed_point_status",
    "gauss_legendre_tableau",
    "get_method",
    "implicit_kick",
    "implicit_rk",
    "jit_step",
    "kernel_function",
    "remove_damping",
    "step_kernels",
    "suitable_methods",
    "tableau_step",
    "unsuitability",
    "variational_method",
    "variational_step",
]


class ConvergenceError(RuntimeError):
    """An implicit step's equations did not converge."""


@dataclass(frozen=True)
class HamiltonianField:
    """A vector field as the integrators see it: Hamiltonian, possibly with damping.

    Attributes
    ----------
    hamilton, acceleration : compiled kernels (see :mod:`pendulum_lab._signatures`)
    params : ndarray, shape (P,) or (K, P)
        Parameters passed through to the kernels; with ``K`` rows, row ``k``
        belongs to ensemble member ``k`` (one run over many parameter values).
    separable : bool
        True when ``dH/dq`` does not depend on ``p`` nor ``dH/dp`` on ``q``
        (damping aside); the symplectic methods are then explicit.
    damping_rate : float or ndarray, shape (K,)
        ``gamma`` when the non-Hamiltonian part of ``dp/dt`` is exactly
        ``-gamma p`` (a conformal Hamiltonian field [MP]); ``0`` for a
        Hamiltonian field; NaN for damping of any other form.
    discrete : callable or None
        ``discrete(rule)`` returns the compiled discrete Legendre transforms
        of the field's discrete Lagrangian by ``rule`` (a namespace with
        ``fixed_point_update``, ``newton_update``, ``impulse``); None
        when the field has no Lagrangian of its own (damping or a drive).
    stages : compiled kernel or None
        ``hamilton`` at several states at once (see
        :mod:`pendulum_lab._signatures`), for the implicit Runge-Kutta
        methods; without it they cannot integrate the field.
    """

    hamilton: object
    acceleration: object
    params: np.ndarray
    separable: bool
    damping_rate: float | np.ndarray = 0.0
    discrete: object = field(default=None, repr=False)
    stages: object = field(default=None, repr=False)


# --------------------------------------------------------------------------- declaring steps
#: Decorator of every function that receives a kernel (``hamilton``,
#: ``acceleration``, a step) as an argument. Such a function is compiled into
#: each field's time loop (:mod:`pendulum_lab.loops`), where the kernels are
#: known: inlined there, its kernel calls are direct calls. (A Numba function
#: compiled on its own with a kernel argument would hold a pointer to a Python
#: object, which Numba cannot keep in its disk cache.) Helpers that take no
#: kernel are plain ``numba.njit``: LLVM inlines them when the loop is linked,
#: while Numba's own inlining copies the callee's IR at every call site (it
#: made compiling the eight methods' loops 1.8 times slower, measured).
kernel_function = numba.njit(inline="always")


class Step:
    """A method's step function, compiled into the time loop of each field it integrates.

    Make one with :func:`jit_step`. ``py_func`` is the Python source;
    ``memory(n)`` the floats the step keeps per trajectory for a state of
    ``n`` coordinates (0: the step takes no ``memory`` argument);
    ``compiled`` the Numba function the time loop calls, always with a
    ``memory`` argument; ``digest`` identifies the code and constants the
    step compiles to (the generated loops are cached under it).
    """

    def __init__(self, py_func, memory=None):
        functools.update_wrapper(self, py_func)
        self.py_func = py_func
        self.memory = memory if memory is not None else (lambda n: 0)
        inner = kernel_function(py_func)
        if memory is None:  # the loop passes memory to every step; this one ignores it

            def ignores_memory(hamilton, acceleration, t, q, p, h, params, separable,
                               damping_rate, memory):
                return inner(hamilton, acceleration, t, q, p, h, params, separable,
                             damping_rate)

            self.compiled = kernel_function(ignores_memory)
        else:
            self.compiled = inner

    @functools.cached_property
    def digest(self) -> str:
        """A hash of the step's source, of its module's source and of its constants."""
        module = inspect.getmodule(self.py_func)
        parts = [inspect.getsource(self.py_func), inspect.getsource(module)]
        for cell in self.py_func.__closure__ or ():
            value = cell.cell_contents
            parts.append(value.tobytes().hex() if isinstance(value, np.ndarray) else repr(value))
        return hashlib.sha256("\n".join(parts).encode()).hexdigest()[:16]

    def __call__(self, *args):
        return self.py_func(*args)


def jit_step(py_func=None, *, memory=None):
    """Declare a step function (see the module docstring): ``@jit_step`` or ``@jit_step(memory=f)``.

    ``memory(n)`` is the number of floats the step keeps per trajectory for a
    state of ``n`` coordinates; a step declared with it takes the ``memory``
    argument last.
    """
    if py_func is None:
        return lambda fn: Step(fn, memory)
    return Step(py_func, memory)


# --------------------------------------------------------------------------- implicit solver
MAX_SWEEPS = 100
# A stalled iteration counts as converged only if its last increment is this
# small relative to the unknowns (or to the floor the caller gives, see
# fixed_point_status): stalling far from round-off means divergence.
ROUNDOFF_TOLERANCE = 1e-11
EPSILON = np.finfo(np.float64).eps


@numba.njit
def fixed_point_status(new, old, smallest, floor=0.0):
    """The stopping rule of every implicit solve here, applied per component.

    ``new`` and ``old`` are successive iterates (1-d arrays) and ``smallest``
    holds each component's smallest increment so far (updated in place).
    ``floor`` is added to every component's size where "tiny" is judged
    (below): unknowns whose round-off is set by larger numbers they are
    combined with, as the slopes of :func:`implicit_rk`, need it. A
    component is done when its increment did not fall below its smallest
    earlier one (it only jitters at round-off now), or when the iteration's
    observed contraction predicts that all its further corrections together
    stay below half a unit in its last place. Returns ``1`` when every component is done
    and all increments are tiny, ``0`` to continue, and ``-1`` if an iterate is
    not finite. Unlike a tolerance, this cannot stop on a small but still
    shrinking increment and needs no tuning to the problem; the prediction
    saves the sweeps a plain stall test would spend at round-off.
    """
    # Most sweeps are far from round-off: a first pass finds that out (and
    # whether all is finite) and records the smallest increments; the full
    # test runs only on the last few sweeps. The loops are written without
    # branches (`&`, `|`, conditional expressions): this rule runs once per
    # sweep and, with data-dependent branches, cost as much as a stage.
    inline_into_callers()
    small, finite = True, True
    for i in range(new.size):
        x = new[i]
        finite &= math.isfinite(x)
        small &= abs(x - old[i]) <= ROUNDOFF_TOLERANCE * (1.0 + floor + abs(x))
    if not finite:
        return -1
    if not small:
        for i in range(new.size):
            smallest[i] = min(smallest[i], abs(new[i] - old[i]))
        return 0
    return _roundoff_status(new, old, smallest)


@intrinsic
def _float_bits(typingctx, x):
    """The bits of a float64 as an int64: for ``x >= 0`` they order as ``x`` does."""
    def codegen(context, builder, sig, args):
        return builder.bitcast(args[0], context.get_value_type(types.int64))

    return types.int64(types.float64), codegen


@intrinsic
def _bits_float(typingctx, bits):
    """The float64 whose bits are ``bits`` (the inverse of :func:`_float_bits`)."""
    def codegen(context, builder, sig, args):
        return builder.bitcast(args[0], context.get_value_type(types.float64))

    return types.float64(types.int64), codegen


@numba.njit(error_model="numpy")  # x / 0 is inf, as intended below, not ZeroDivisionError
def _roundoff_status(new, old, smallest):
    """:func:`fixed_point_status` once every increment is tiny: stalled, or predicted done?"""
    # rate: the largest ratio of an increment to the one before it, over the
    # components whose previous increment was well above round-off (below
    # that, ratios are noise); unknown on the first sweep or if none qualifies.
    # worst: the largest relative increment among components still improving.
    # Every quantity is computed for every component and then selected, with
    # no branch and no running comparison between components, so that the
    # loop vectorizes (an earlier version compared fractions by cross
    # products, and its chain of selects cost 2.6 times as much). Both
    # maxima are taken over the quantities' bits as integers: they are never
    # negative, so their bits order as they do, and LLVM vectorizes an
    # integer maximum but not a floating-point one, whose NaN rules forbid
    # reordering it (3 times as fast on 32 components, measured).
    inline_into_callers()
    rate_bits, worst_bits = 0, 0
    measured, first = False, False
    for i in range(new.size):
        x = new[i]
        delta, previous, size = abs(x - old[i]), smallest[i], abs(x)
        unknown = math.isinf(previous)
        counts = (not unknown) & (previous > 256.0 * EPSILON * size)
        first |= unknown
        measured |= counts
        # the divisors are replaced where the quotient is not used (no 0 / 0)
        ratio = delta / (previous if counts else 1.0)
        rate_bits = max(rate_bits, _float_bits(ratio if counts else 0.0))
        improving = delta < previous
        smallest[i] = delta if improving else previous
        grows = improving & (delta > 0.0)  # size 0: an infinite relative increment
        relative = delta / (size if grows else 1.0)
        worst_bits = max(worst_bits, _float_bits(relative if grows else 0.0))
    rate, worst = _bits_float(rate_bits), _bits_float(worst_bits)
    if worst == 0.0:  # every component stalled or exactly unchanged
        return 1
    # the improving ones are done if rate / (1 - rate) * worst < half an ulp
    done = (measured and not first and rate < 1.0
            and rate * worst <= 0.5 * EPSILON * (1.0 - rate))
    return 1 if done else 0


# --------------------------------------------------------------------------- Runge-Kutta methods
@intrinsic
def _element_address(typingctx, array, index):
    """The address of ``array[index]`` (a 1-d contiguous array) as a typed pointer."""
    signature = types.CPointer(array.dtype)(array, index)

    def codegen(context, builder, sig, args):
        data = context.make_array(sig.args[0])(context, builder, args[0]).data
        return builder.gep(data, [args[1]])

    return signature, codegen


@numba.njit
def span(memory, start, length):
    """``memory[start : start + length]`` as a view without a reference count.

    The step functions carve their workspace out of ``memory`` with this.
    An ordinary slice is reference counted: each view and each argument
    passed on costs an atomic increment and decrement, several times the
    arithmetic of a small step; a reshape calls into Numba's runtime. This
    view points into ``memory``'s data and owns nothing, so it must not
    outlive ``memory`` (it never leaves the time loop), and ``memory`` must be
    named again after the view's last use if nothing else holds it: Numba
    frees an array after the last line that names it (see ``loops.time_loop``).
    """
    return numba.carray(_element_address(memory, start), length)


@numba.njit
def vector(memory, index, n):
    """The ``index``-th vector of ``n`` floats in ``memory`` (a :func:`span`)."""
    return span(memory, index * n, n)


@numba.njit
def unmanaged(array):
    """``array`` (1-d, contiguous) as a view without a reference count (see :func:`vector`)."""
    return numba.carray(_element_address(array, 0), array.size)


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


@numba.njit
def block(memory, start, rows, columns):
    """``memory[start:]`` as a C-ordered ``(rows, columns)`` array, a :func:`span` in 2-d."""
    return numba.carray(_element_address(memory, start), (rows, columns))


#: The most columns an implicit step's stages take (:func:`stage_lanes`): its
#: stage sums are accumulated in a stack buffer of this size.
MAX_STAGE_LANES = 64


@intrinsic
def _stack_floats(typingctx, count):
    """A float64 array of ``count`` (a literal) elements on the calling function's stack."""
    if not isinstance(count, types.IntegerLiteral):
        return None
    size = count.literal_value
    array_type = types.Array(types.float64, 1, "C")

    def codegen(context, builder, sig, args):
        buffer = cgutils.alloca_once(builder, llvm_ir.ArrayType(llvm_ir.DoubleType(), size))
        buffer.align = 64
        array = context.make_array(array_type)(context, builder)
        intp = context.get_value_type(types.intp)
        context.populate_array(array, data=builder.bitcast(buffer, array.data.type),
                               shape=[intp(size)], strides=[intp(8)], itemsize=intp(8),
                               meminfo=None)
        return array._getvalue()

    return array_type(count), codegen


@numba.njit(inline="always")  # with Numba's inlining the loop bounds stay constants
def _combine_row(memory, row, columns, stages, lanes, out):
    """``out[i] = sum_j columns[j, i] memory[row + j]`` for ``i < lanes``, summed over j in order.

    The innermost loop runs over ``i``, so it vectorizes, and ``out`` is a
    stack buffer (:func:`_stack_floats`), which LLVM knows the loads from
    ``memory`` cannot see: written into ``memory`` directly, the sums must be
    stored and loaded again for every ``j`` (glrk16's 4 x 8 x 8 took 66 ns a
    sweep as dot products per stage, 32 ns this way, in a micro-benchmark; a
    glrk16 run over 1000 s took 43.0 instead of 50.4 ms).
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
    (:mod:`pendulum_lab.codegen`). ``c_lanes`` is ``c`` padded with zeros to
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
    sums = _stack_floats(MAX_STAGE_LANES)
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
        q1[m] = _compensated_sum(q[m], h * increment_q, compensation, m)
        p1[m] = _compensated_sum(p[m], h * increment_p, compensation, n + m)
    return q1, p1, sweeps, calls


@numba.njit
def _compensated_sum(y, increment, compensation, i):
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


# --------------------------------------------------------------------------- symplectic methods
@numba.njit
def add_scaled(out, x, factor, y):
    """``out = x + factor * y``, element by element (no temporary arrays)."""
    for i in range(out.size):
        out[i] = x[i] + factor * y[i]


@numba.njit(cache=True)
def remove_damping(p, damping_rate, dp):
    """``dp += damping_rate p``: from a conformal field's ``dp/dt`` to its Hamiltonian part's.

    A conformal Hamiltonian field has ``dp/dt = -H_q - gamma p`` [MP]; the
    symplectic steps below integrate ``-H_q`` and leave the damping to the
    conformal methods' exact flow. They call this only when ``gamma != 0``
    (a function call per evaluation would cost Hamiltonian fields 10 %).
    """
    for i in range(p.size):
        dp[i] += damping_rate * p[i]


@kernel_function
def implicit_kick(hamilton, t, q, p, k, params, separable, damping_rate, dq, dp, p_k, p_new,
                  smallest):
    """Solve ``p_k = p - k H_q(t, q, p_k)`` for ``p_k`` (written into ``p_k``): the momentum update.

    Starts from ``p + k dp``, so ``dp`` must hold ``-H_q(t, q, p)`` on entry
    (see :func:`remove_damping` for ``damping_rate``);
    the guess is exact when ``H`` is separable. Otherwise iterates
    ``p_k <- p + k dp(t, q, p_k)`` until :func:`fixed_point_status` finds
    round-off. ``dq``, ``dp``, ``p_new`` and ``smallest`` are workspace.
    Returns the sweeps, ``-1`` if the iteration did not converge (after
    ``MAX_SWEEPS``).
    """
    add_scaled(p_k, p, k, dp)  # p_k = p + k dp
    if separable:
        return 0
    smallest[:] = np.inf
    status, sweeps = 0, 0
    while status == 0 and sweeps < MAX_SWEEPS:
        sweeps += 1
        hamilton(t, q, p_k, params, dq, dp)
        if damping_rate != 0.0:
            remove_damping(p_k, damping_rate, dp)
        add_scaled(p_new, p, k, dp)  # p_new = p + k dp(t, q, p_k)
        status = fixed_point_status(p_new, p_k, smallest)
        p_k[:] = p_new
    return sweeps if status == 1 else -1


@kernel_function
def symplectic_euler(hamilton, t, q, p, h, params, separable, damping_rate, work):
    """Symplectic Euler for a general ``H(t, q, p)``:

    ``p1 = p - h H_q(t, q, p1)``   (implicit in ``p1`` only)
    ``q1 = q + h H_p(t, q, p1)``

    ``work`` holds ``6 n`` floats; ``q1, p1`` are returned as views into it.
    """
    n = q.size
    dq, dp, q1 = vector(work, 0, n), vector(work, 1, n), vector(work, 2, n)
    p1, p_new, smallest = vector(work, 3, n), vector(work, 4, n), vector(work, 5, n)
    hamilton(t, q, p, params, dq, dp)
    if damping_rate != 0.0:
        remove_damping(p, damping_rate, dp)
    sweeps = implicit_kick(hamilton, t, q, p, h, params, separable, damping_rate, dq, dp, p1,
                           p_new, smallest)
    if sweeps < 0:
        return q, p, -1, 1 + MAX_SWEEPS
    hamilton(t, q, p1, params, dq, dp)  # only dq = H_p is used
    add_scaled(q1, q, h, dq)  # q1 = q + h dq
    return q1, p1, sweeps, sweeps + 2


@kernel_function
def stormer_verlet(hamilton, t, q, p, h, params, separable, damping_rate, work):
    """Stormer-Verlet for a general ``H(t, q, p)`` (the Lobatto IIIA-IIIB pair):

    ``p_half = p - h/2 H_q(t, q, p_half)``                          (implicit)
    ``q1 = q + h/2 [H_p(t, q, p_half) + H_p(t + h, q1, p_half)]``   (implicit)
    ``p1 = p_half - h/2 H_q(t + h, q1, p_half)``                    (explicit)

    ``work`` holds ``8 n`` floats; ``q1, p1`` are returned as views into it.
    """
    n = q.size
    dq, dp = vector(work, 0, n), vector(work, 1, n)
    p_half, q1 = vector(work, 2, n), vector(work, 3, n)
    p1, drift = vector(work, 4, n), vector(work, 5, n)
    new, smallest = vector(work, 6, n), vector(work, 7, n)
    hamilton(t, q, p, params, dq, dp)
    if damping_rate != 0.0:
        remove_damping(p, damping_rate, dp)
    sweeps = implicit_kick(hamilton, t, q, p, 0.5 * h, params, separable, damping_rate, dq, dp,
                           p_half, new, smallest)
    if sweeps < 0:
        return q, p, -1, 1 + MAX_SWEEPS
    calls = 1 + sweeps
    hamilton(t, q, p_half, params, dq, dp)  # only dq = H_p is used
    add_scaled(drift, q, 0.5 * h, dq)  # drift = q + h/2 dq
    add_scaled(q1, q, h, dq)  # q1 = q + h dq: exact when H is separable, else the first guess
    calls += 1
    if not separable:
        smallest[:] = np.inf
        status, first_sweeps = 0, sweeps
        while status == 0 and sweeps - first_sweeps < MAX_SWEEPS:
            sweeps += 1
            hamilton(t + h, q1, p_half, params, dq, dp)
            add_scaled(new, drift, 0.5 * h, dq)  # q1 <- drift + h/2 dq(t + h, q1, p_half)
            status = fixed_point_status(new, q1, smallest)
            q1[:] = new
        calls += sweeps - first_sweeps
        if status != 1:
            return q, p, -1, calls
    hamilton(t + h, q1, p_half, params, dq, dp)
    if damping_rate != 0.0:
        remove_damping(p_half, damping_rate, dp)
    add_scaled(p1, p_half, 0.5 * h, dp)  # p1 = p_half + h/2 dp
    return q1, p1, sweeps, calls + 1


@jit_step(memory=lambda n: 6 * n)
def semi_implicit_euler_step(hamilton, acceleration, t, q, p, h, params, separable,
                             damping_rate, memory):
    """Symplectic Euler in ``(q, p)``: :func:`symplectic_euler` of the Hamiltonian."""
    return symplectic_euler(hamilton, t, q, p, h, params, separable, damping_rate, memory)


@jit_step(memory=lambda n: 8 * n)
def leapfrog_step(hamilton, acceleration, t, q, p, h, params, separable, damping_rate, memory):
    """Stormer-Verlet in ``(q, p)``: :func:`stormer_verlet` of the Hamiltonian."""
    return stormer_verlet(hamilton, t, q, p, h, params, separable, damping_rate, memory)


@jit_step(memory=lambda n: 6 * n)
def conformal_euler_step(hamilton, acceleration, t, q, p, h, params, separable, damping_rate,
                         memory):
    """Conformal symplectic Euler [MP]: symplectic Euler, then the exact damping flow.

    ``(q, p) <- symplectic Euler of H``;  ``p <- exp(-gamma h) p``.
    """
    q1, p1, sweeps, calls = symplectic_euler(hamilton, t, q, p, h, params, separable,
                                             damping_rate, memory)
    contraction = math.exp(-damping_rate * h)
    for i in range(p1.size):
        p1[i] = contraction * p1[i]
    return q1, p1, sweeps, calls


@jit_step(memory=lambda n: 9 * n)
def conformal_leapfrog_step(hamilton, acceleration, t, q, p, h, params, separable,
                            damping_rate, memory):
    """Conformal Stormer-Verlet [MP]: half the damping, a leapfrog step of ``H``, half again.

    ``p <- exp(-gamma h/2) p``;  ``(q, p) <- Stormer-Verlet of H``;
    ``p <- exp(-gamma h/2) p``. The damping flow is exact and the middle step
    symplectic, so each step contracts phase-space volume by exactly
    ``exp(-n gamma h)``, as the true flow does; symmetric, second order.
    """
    contraction, n = math.exp(-0.5 * damping_rate * h), q.size
    contracted = vector(memory, 0, n)
    for i in range(n):
        contracted[i] = contraction * p[i]
    q1, p1, sweeps, calls = stormer_verlet(hamilton, t, q, contracted, h, params, separable,
                                           damping_rate, span(memory, n, 8 * n))
    for i in range(n):
        p1[i] = contraction * p1[i]
    return q1, p1, sweeps, calls


# --------------------------------------------------------------------------- the report's methods
@jit_step(memory=lambda n: 3 * n)
def semi_implicit_euler_velocity_step(hamilton, acceleration, t, q, v, h, params, separable,
                                      damping_rate, memory):
    """The course report's version on ``(q, v)``: ``v1 = v + h a(t, q, v)``; ``q1 = q + h v1``."""
    n = q.size
    a, v1, q1 = vector(memory, 0, n), vector(memory, 1, n), vector(memory, 2, n)
    acceleration(t, q, v, params, a)
    add_scaled(v1, v, h, a)  # v1 = v + h a
    add_scaled(q1, q, h, v1)  # q1 = q + h v1
    return q1, v1, 0, 1


@jit_step(memory=lambda n: 4 * n)
def leapfrog_velocity_step(hamilton, acceleration, t, q, v, h, params, separable, damping_rate,
                           memory):
    """The course report's leapfrog on ``(q, v)``, written as kick-drift-kick:

    ``v_half = v + h/2 a(t, q, v)``; ``q1 = q + h v_half``;
    ``v1 = v_half + h/2 a(t + h, q1, v_half)``.
    Second order only when ``a`` does not depend on ``v``.
    """
    n = q.size
    a, v_half = vector(memory, 0, n), vector(memory, 1, n)
    q1, v1 = vector(memory, 2, n), vector(memory, 3, n)
    acceleration(t, q, v, params, a)
    add_scaled(v_half, v, 0.5 * h, a)  # v_half = v + h/2 a
    add_scaled(q1, q, h, v_half)  # q1 = q + h v_half
    acceleration(t + h, q1, v_half, params, a)
    add_scaled(v1, v_half, 0.5 * h, a)  # v1 = v_half + h/2 a
    return q1, v1, 0, 2


# ----------------------------------------------------------------------- variational integrators
@jit_step
def variational_step(update, impulse, t, q, p, h, params, separable, damping_rate):
    """A variational integrator [MW]: the discrete Legendre transforms, solved.

    ``p = -D_1 L_d(q, q1)``   (implicit in ``q1``)
    ``p1 = D_2 L_d(q, q1)``   (explicit; computed as ``p + D_2 L_d + D_1 L_d``)

    ``update(h, q, q1, params, p, out)`` writes the next iterate for ``q1``
    (a fixed-point or a Newton step, generated from the discrete Lagrangian);
    it is iterated from ``q1 = q`` until :func:`fixed_point_status` finds
    round-off (the first iterate is already a symplectic-Euler-like guess).
    ``impulse(h, q, q1, params, out)`` writes ``p1 - p``. ``t``,
    ``separable`` and ``damping_rate`` are not used: the discrete Lagrangian
    is autonomous and conservative. ``calls`` counts kernel evaluations.
    """
    q1, new = q.copy(), np.empty_like(q)
    smallest, status, sweeps = np.full(q.size, np.inf), 0, 0
    while status == 0 and sweeps < MAX_SWEEPS:
        sweeps += 1
        update(h, q, q1, params, p, new)
        status = fixed_point_status(new, q1, smallest)
        q1, new = new, q1
    if status != 1:
        return q, p, -1, sweeps
    kick = np.empty_like(p)
    impulse(h, q, q1, params, kick)
    return q1, p + kick, sweeps, sweeps + 1


#: How a variational step solves for ``q1``: the generated kernel it iterates.
VARIATIONAL_SOLVERS = {"fixed_point": "fixed_point_update", "newton": "newton_update"}


def variational_method(rule: str, solver: str, name: str | None = None) -> Method:
    """The variational integrator of the discrete Lagrangian ``rule``, solved by ``solver``.

    Parameters
    ----------
    rule : {"midpoint", "trapezoid"}
        The quadrature of the action (see :mod:`pendulum_lab.discrete_mechanics`).
    solver : {"fixed_point", "newton"}
        How the step solves ``p = -D_1 L_d(q, q1)`` for ``q1``.
    name : str, optional
        By default ``"variational_<rule>"``.
    """
    rule = check.choice("rule", rule, RULES)
    solver = check.choice("solver", solver, VARIATIONAL_SOLVERS)
    quadrature = "M and L at the midpoint" if rule == "midpoint" else "L averaged over both ends"
    return Method(name or f"variational_{rule}", 2, True, True, "canonical",
                  f"variational integrator of the {rule} rule ({quadrature}): symmetric, "
                  "symplectic in (theta, p)", variational_step, applies_to=LAGRANGIAN_FIELD,
                  rule=rule, solver=solver)


def step_kernels(method: Method, field: HamiltonianField) -> tuple:
    """The two kernels ``method``'s step receives for ``field``.

    ``(field.hamilton, field.acceleration)``; for an implicit Runge-Kutta
    method ``(field.hamilton, field.stages)``; for a variational method the
    update and the momentum of the field's discrete Legendre transforms
    (compiled on first use).
    """
    if method.rule is None:
        if _takes_stages(method):
            return field.hamilton, field.stages
        return field.hamilton, field.acceleration
    kernels = field.discrete(method.rule)
    return getattr(kernels, VARIATIONAL_SOLVERS[method.solver]), kernels.impulse



# --------------------------------------------------------------------------- registry
#: Values of :attr:`Method.applies_to`.
ANY_FIELD, HAMILTONIAN_FIELD, CONFORMAL_FIELD = "any", "hamiltonian", "conformal"
LAGRANGIAN_FIELD = "lagrangian"


@dataclass(frozen=True)
class Method:
    """An integrator: its properties and its compiled one-step map.

    Build a Runge-Kutta method with :meth:`from_tableau`, which derives every
    property from the tableau.

    Attributes
    ----------
    name : str
    order : int
        Classical order of accuracy.
    symplectic : bool
        Symplectic for every Hamiltonian (in the variables it works in); for
        the conformal methods: conformal symplectic on damped fields.
    implicit : bool
        Solves equations at each step (for non-separable ``H``).
    variables : {"canonical", "velocity"}
        ``(q, p)`` or, for the course report's versions, ``(q, v)``.
    summary : str
        One line for tables and dropdowns.
    kernel : Step
        The step function (see the module docstring); ``kernel.py_func`` is
        its Python source, ``kernel.memory(n)`` the floats it keeps per
        trajectory; :mod:`pendulum_lab.loops` compiles it with each field.
    applies_to : {"any", "hamiltonian", "conformal", "lagrangian"}
        The fields it integrates: any; Hamiltonian ones (``damping_rate``
        zero); conformal ones (``damping_rate`` finite, zero included);
        those with a discrete Lagrangian (an unforced chain: no damping, no
        drive).
    tableau : ButcherTableau or None
        The Butcher tableau of a Runge-Kutta method.
    rule, solver : str or None
        For a variational method (:func:`variational_method`): the discrete
        Lagrangian's quadrature rule and how its step solves for ``q1``.
    """

    name: str
    order: int
    symplectic: bool
    implicit: bool
    variables: str
    summary: str
    kernel: object = field(repr=False)
    applies_to: str = ANY_FIELD
    tableau: ButcherTableau | None = field(default=None, repr=False)
    rule: str | None = None
    solver: str | None = None

    @classmethod
    def from_tableau(cls, name: str, tableau: ButcherTableau, summary: str) -> Method:
        """The Runge-Kutta method of ``tableau`` on ``(q, p)``; nothing typed but the name.

        Order, implicitness and symplecticity come from the tableau
        (:class:`~pendulum_lab.tableau.ButcherTableau`), the step function from
        :func:`tableau_step`. A Runge-Kutta method integrates any field.
        """
        return cls(name, tableau.order, tableau.symplectic_condition().holds,
                   not tableau.explicit, "canonical", summary, tableau_step(tableau, name),
                   tableau=tableau)

    def __str__(self) -> str:
        return self.name


_REGISTRY = [
    Method.from_tableau("explicit_euler", ButcherTableau(a=[[0.0]], b=[1.0]),
                        "explicit Euler: y1 = y + h f(y)"),
    Method("semi_implicit_euler", 1, True, True, "canonical",
           "symplectic Euler in (theta, p): implicit in p1 unless H is separable",
           semi_implicit_euler_step, applies_to=HAMILTONIAN_FIELD),
    Method("leapfrog", 2, True, True, "canonical",
           "Stormer-Verlet in (theta, p): the generalized, implicit form", leapfrog_step,
           applies_to=HAMILTONIAN_FIELD),
    Method.from_tableau("rk4", ButcherTableau(a=[[0, 0, 0, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0],
                                                 [0, 0, 1, 0]], b=[1 / 6, 1 / 3, 1 / 3, 1 / 6]),
                        "classical fourth-order Runge-Kutta"),
    # The course report's method (section 2.4.5): c = 1/2 -+ sqrt(3)/6, order 4.
    Method.from_tableau("glrk4", gauss_legendre_tableau(2),
                        "two-stage Gauss-Legendre collocation (implicit Runge-Kutta)"),
    # Four stages, order 8: far fewer steps where high accuracy is wanted.
    Method.from_tableau("glrk8", gauss_legendre_tableau(4),
                        "four-stage Gauss-Legendre collocation (order 8, implicit)"),
    # Six stages, order 12: for tight tolerances over long runs.
    Method.from_tableau("glrk12", gauss_legendre_tableau(6),
                        "six-stage Gauss-Legendre collocation (order 12, implicit)"),
    # Eight stages, order 16: they fill one pass of the vectorized stage kernel
    # (LANE_GROUP columns, where glrk12's six leave two for padding), so a sweep
    # costs about what glrk12's does and the steps are longer.
    Method.from_tableau("glrk16", gauss_legendre_tableau(8),
                        "eight-stage Gauss-Legendre collocation (order 16, implicit)"),
    Method("semi_implicit_euler_velocity", 1, False, False, "velocity",
           "the report's semi-implicit Euler on (theta, omega): not symplectic for n >= 2",
           semi_implicit_euler_velocity_step),
    Method("leapfrog_velocity", 2, False, False, "velocity",
           "the report's leapfrog on (theta, omega): not symplectic for n >= 2",
           leapfrog_velocity_step),
    Method("conformal_euler", 1, True, True, "canonical",
           "conformal symplectic Euler: symplectic Euler, then the exact linear damping",
           conformal_euler_step, applies_to=CONFORMAL_FIELD),
    Method("conformal_leapfrog", 2, True, True, "canonical",
           "conformal Stormer-Verlet: exact damping for h/2, leapfrog, damping for h/2",
           conformal_leapfrog_step, applies_to=CONFORMAL_FIELD),
    # Fixed-point iteration, as for Gauss-Legendre. Newton's method with the
    # generated Jacobian needs half the iterations and is faster per step
    # (benchmark item 7), but at large steps it can converge to another root
    # of the discrete equations, off the branch that continues the small-step
    # solution, where fixed-point iteration stops with an error
    # (tests/test_variational.py): no result is silently wrong.
    variational_method("midpoint", "fixed_point"),
    variational_method("trapezoid", "fixed_point"),
]
#: The methods for Hamiltonian systems, compared throughout the course.
METHODS: dict[str, Method] = {
    m.name: m for m in _REGISTRY if m.applies_to in (ANY_FIELD, HAMILTONIAN_FIELD)
}
#: The methods for damped (conformal Hamiltonian) systems; on a Hamiltonian
#: field they are symplectic Euler and the leapfrog.
CONFORMAL_METHODS: dict[str, Method] = {
    m.name: m for m in _REGISTRY if m.applies_to == CONFORMAL_FIELD
}
#: The variational integrators of notebook 15, made from discrete Lagrangians;
#: on the chains they coincide with, or stay within O(h^3) per step of, the
#: implicit midpoint rule and the leapfrog.
VARIATIONAL_METHODS: dict[str, Method] = {
    m.name: m for m in _REGISTRY if m.applies_to == LAGRANGIAN_FIELD
}
# The tableaus by name, for notebooks and tests (the registry holds them).
EULER_TABLEAU = METHODS["explicit_euler"].tableau
RK4_TABLEAU = METHODS["rk4"].tableau
GAUSS4_TABLEAU = METHODS["glrk4"].tableau
GAUSS8_TABLEAU = METHODS["glrk8"].tableau
GAUSS12_TABLEAU = METHODS["glrk12"].tableau
GAUSS16_TABLEAU = METHODS["glrk16"].tableau

MAIN_METHODS = ("explicit_euler", "semi_implicit_euler", "leapfrog", "rk4", "glrk4")


def get_method(method) -> Method:
    """Look up a method by name (or pass a :class:`Method` through)."""
    if isinstance(method, Method):
        return method
    if not isinstance(method, str):
        raise TypeError(f"`method` must be a method name (str), got {type(method).__name__}")
    for registry in (METHODS, CONFORMAL_METHODS, VARIATIONAL_METHODS):
        if method in registry:
            return registry[method]
    names = [*METHODS, *CONFORMAL_METHODS, *VARIATIONAL_METHODS]
    raise ValueError(f"`method` must be one of {names}, got {method!r}")


def _takes_stages(method: Method) -> bool:
    """Whether ``method``'s step evaluates its stages through the field's ``stages`` kernel."""
    return method.tableau is not None and method.implicit


def unsuitability(method: Method, field: HamiltonianField) -> str | None:
    """Why ``method`` cannot integrate ``field``, or None if it can."""
    if _takes_stages(method) and field.stages is None:
        return (f"{method.name} evaluates its stages together, through the field's `stages` "
                "kernel, and this field has none")
    rates = np.asarray(field.damping_rate, dtype=float)
    if method.applies_to in (HAMILTONIAN_FIELD, LAGRANGIAN_FIELD) and np.any(rates != 0):
        return (f"{method.name} assumes a Hamiltonian vector field, and damping is not "
                "Hamiltonian (its guesses and its symplecticity rely on dp/dt = -H_q)")
    if method.applies_to == LAGRANGIAN_FIELD and field.discrete is None:
        return (f"{method.name} steps the discrete Lagrangian of the unforced chain, "
                "L = T - V, and a drive torque is not part of L")
    if method.applies_to == CONFORMAL_FIELD and not np.all(np.isfinite(rates)):
        return (f"{method.name} needs damping of the conformal form dp/dt = -H_q - gamma p "
                "with a constant gamma")
    return None


def suitable_methods(field: HamiltonianField) -> list[str]:
    """Names of the registered methods that integrate ``field``."""
    return [m.name for m in _REGISTRY if unsuitability(m, field) is None]
