"""One-step integrators for vector fields, compiled with Numba.

This module knows vector fields, not pendulums. A vector field is a pair of
compiled kernels (see :mod:`pendulum_lab._signatures`):
``hamilton(t, q, p, params, dq, dp)`` writes ``dq = dH/dp`` and
``dp = -dH/dq + Q`` (``Q``: forces no Hamiltonian describes, such as
damping); ``acceleration(t, q, v, params, out)`` writes the acceleration for
the course report's velocity-variable methods. ``t`` is the time, for fields
that depend on it (a driven pendulum).

Every method is a step function ``(hamilton, acceleration, t, q, p, h,
params, separable, damping_rate) -> (q1, p1, sweeps, calls)`` advancing from
time ``t`` to ``t + h``: ``p`` is the canonical momentum for all methods
except the two ``*_velocity`` ones, where it is the velocity; ``sweeps``
counts implicit-solver iterations (``-1``: did not converge) and ``calls``
the vector-field evaluations. ``separable`` and ``damping_rate`` describe the
field (see :class:`HamiltonianField`). :func:`run` drives any of them over
many steps and many initial states; it is the only time loop.

Methods are data where they can be: a Runge-Kutta method (explicit Euler,
RK4, Gauss-Legendre) is one registry entry made from its Butcher tableau by
:meth:`Method.from_tableau`, which derives its order, implicitness,
symplecticity and evaluation count (:mod:`pendulum_lab.tableau`); explicit
tableaus are stepped by :func:`explicit_rk`, implicit ones by
:func:`implicit_rk` (fixed-point iteration). Stage ``i`` is evaluated at
time ``t + c_i h``. The symplectic partitioned methods follow the textbook
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
   general H (eq. VI.3.4), Gauss collocation (Sect. II.1.3, VI.4); a
   time-dependent H is made autonomous by taking t as one more coordinate.
.. [HMR] E. Hairer, R. I. McLachlan, A. Razakarivony, "Achieving Brouwer's
   law with implicit Runge-Kutta methods", BIT 48 (2008) 231-243: iterate the
   stage equations to round-off, or energy drifts.
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
import math
from dataclasses import dataclass, field

import numba
import numpy as np
from numba import types

from . import _validation as check
from ._signatures import ACCELERATION, HAMILTON, VECTOR
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
    "explicit_rk",
    "fixed_point_status",
    "gauss_legendre_tableau",
    "get_method",
    "implicit_kick",
    "implicit_rk",
    "remove_damping",
    "run",
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
    """

    hamilton: object
    acceleration: object
    params: np.ndarray
    separable: bool
    damping_rate: float | np.ndarray = 0.0
    discrete: object = field(default=None, repr=False)


# --------------------------------------------------------------------------- kernel types
HamiltonFn = types.FunctionType(HAMILTON)
AccelerationFn = types.FunctionType(ACCELERATION)
STEP = types.Tuple((VECTOR, VECTOR, types.int64, types.int64))(
    HamiltonFn, AccelerationFn, types.float64, VECTOR, VECTOR, types.float64, VECTOR,
    types.boolean, types.float64,
)


class LazyKernel:
    """A Numba kernel with a fixed signature, compiled on first use.

    Numba compiles a function with an explicit signature as soon as it is
    decorated; on a machine that has never run the package that would put
    half a minute into ``import pendulum_lab``. Wrapped like this, only the
    methods actually used get compiled, once: ``cache=True`` keeps the machine
    code on disk for later processes. ``py_func`` is the Python source.
    """

    def __init__(self, signature, py_func, **options):
        functools.update_wrapper(self, py_func)
        self.py_func = py_func
        self.signature = signature
        self.options = options

    @functools.cached_property
    def compiled(self):
        """The Numba dispatcher (compiled, or loaded from the cache, now)."""
        return numba.njit(self.signature, **self.options)(self.py_func)

    def __call__(self, *args):
        return self.compiled(*args)


def jit_step(py_func) -> LazyKernel:
    """Declare a step function: a kernel with the :data:`STEP` signature."""
    return LazyKernel(STEP, py_func, cache=True)


# --------------------------------------------------------------------------- implicit solver
MAX_SWEEPS = 100
# A stalled iteration counts as converged only if its last increment is this
# small relative to the unknowns: stalling far from round-off means divergence.
ROUNDOFF_TOLERANCE = 1e-11
EPSILON = np.finfo(np.float64).eps


@numba.njit(cache=True)
def fixed_point_status(new, old, smallest):
    """The stopping rule of every implicit solve here, applied per component.

    ``new`` and ``old`` are successive iterates (1-d arrays) and ``smallest``
    holds each component's smallest increment so far (updated in place). A
    component is done when its increment did not fall below its smallest
    earlier one (it only jitters at round-off now), or when the iteration's
    observed contraction predicts that all its further corrections together
    stay below half a unit in its last place. Returns ``1`` when every component is done
    and all increments are tiny, ``0`` to continue, and ``-1`` if an iterate is
    not finite. Unlike a tolerance, this cannot stop on a small but still
    shrinking increment and needs no tuning to the problem; the prediction
    saves the sweeps a plain stall test would spend at round-off.
    """
    # rate: the largest ratio of an increment to the one before it, over the
    # components whose previous increment was well above round-off (below
    # that, ratios are noise); unknown on the first sweep or if none qualifies
    rate, measured, first, small = 0.0, False, False, True
    worst = 0.0  # the largest relative increment among components still improving
    for i in range(new.size):
        x = new[i]
        if not math.isfinite(x):
            return -1
        delta, previous = abs(x - old[i]), smallest[i]
        if delta > ROUNDOFF_TOLERANCE * (1.0 + abs(x)):
            small = False
        if not math.isfinite(previous):
            first = True
        elif previous > 256.0 * EPSILON * abs(x):
            rate, measured = max(rate, delta / previous), True
        if delta < previous:
            smallest[i] = delta
            if delta > 0.0:
                worst = max(worst, delta / abs(x) if x != 0.0 else math.inf)
    if not small:
        return 0
    if worst == 0.0:  # every component stalled or exactly unchanged
        return 1
    # the improving ones are done if rate / (1 - rate) * increment < half an ulp
    done = measured and not first and rate < 1.0 and rate * worst <= 0.5 * EPSILON * (1.0 - rate)
    return 1 if done else 0


# --------------------------------------------------------------------------- Runge-Kutta methods
@numba.njit(cache=True)
def explicit_rk(hamilton, t, q, p, h, params, a, b, c):
    """One step of the explicit Runge-Kutta method ``(a, b, c)``.

    Stage ``i`` evaluates the field at time ``t + c_i h`` and state
    ``y + h sum_{j<i} a_ij k_j``; the step is ``y + h sum_i b_i k_i``. Written
    with element loops and one block of memory for all the vectors:
    allocating each small array separately would cost more than the
    arithmetic.
    """
    stages, n = b.size, q.size
    work = np.empty((2 * stages + 4, n))
    kq, kp = work[:stages], work[stages : 2 * stages]
    qi, pi, q1, p1 = work[2 * stages], work[2 * stages + 1], work[-2], work[-1]
    for i in range(stages):
        for m in range(n):
            qi[m], pi[m] = q[m], p[m]
            for j in range(i):
                qi[m] += h * a[i, j] * kq[j, m]
                pi[m] += h * a[i, j] * kp[j, m]
        hamilton(t + c[i] * h, qi, pi, params, kq[i], kp[i])
    q1[:], p1[:] = q, p
    for i in range(stages):
        for m in range(n):
            q1[m] += h * b[i] * kq[i, m]
            p1[m] += h * b[i] * kp[i, m]
    return q1, p1


@numba.njit(cache=True)
def implicit_rk(hamilton, t, q, p, h, params, a, b, c):
    """One step of the implicit Runge-Kutta method ``(a, b, c)``.

    The stage slopes solve ``K_i = f(t + c_i h, y + h sum_j a_ij K_j)``; they
    are found by fixed-point iteration from the guess ``K_i = f(t, y)``, each
    sweep re-evaluating every stage at the latest slopes, until
    :func:`fixed_point_status` finds round-off. The step is
    ``y1 = y + h sum_i b_i K_i``. Returns ``(q1, p1, sweeps, calls)``, with
    ``sweeps = -1`` if the iteration did not converge.
    """
    stages, n = b.size, q.size
    # Two iterates in one block of memory: slopes[k, 0, i] and slopes[k, 1, i]
    # are dq and dp of stage i in iterate k, and flat[k] is iterate k as one
    # vector for the stopping rule (views made once: reshaping costs more
    # than a sweep's arithmetic).
    block = np.empty(2 * 2 * stages * n)
    slopes, flat = block.reshape((2, 2, stages, n)), block.reshape((2, 2 * stages * n))
    current = 0
    hamilton(t, q, p, params, slopes[current, 0, 0], slopes[current, 1, 0])
    for i in range(1, stages):
        slopes[current, :, i] = slopes[current, :, 0]
    smallest = np.full(2 * stages * n, np.inf)
    stage_q, stage_p = np.empty(n), np.empty(n)
    sweeps, status = 0, 0
    while status == 0 and sweeps < MAX_SWEEPS:
        sweeps += 1
        new = 1 - current
        for i in range(stages):
            for m in range(n):
                sum_q, sum_p = 0.0, 0.0
                for j in range(stages):
                    sum_q += a[i, j] * slopes[current, 0, j, m]
                    sum_p += a[i, j] * slopes[current, 1, j, m]
                stage_q[m], stage_p[m] = q[m] + h * sum_q, p[m] + h * sum_p
            hamilton(t + c[i] * h, stage_q, stage_p, params, slopes[new, 0, i], slopes[new, 1, i])
        status = fixed_point_status(flat[new], flat[current], smallest)
        current = new
    calls = 1 + stages * sweeps
    if status != 1:
        return q, p, -1, calls
    q1, p1 = q.copy(), p.copy()
    for i in range(stages):
        for m in range(n):
            q1[m] += h * b[i] * slopes[current, 0, i, m]
            p1[m] += h * b[i] * slopes[current, 1, i, m]
    return q1, p1, sweeps, calls


def tableau_step(tableau: ButcherTableau, name: str) -> LazyKernel:
    """The step function of the Runge-Kutta method ``name``, made from its tableau.

    An explicit tableau is stepped by :func:`explicit_rk`, an implicit one by
    :func:`implicit_rk`. The coefficients are closed over, so Numba compiles
    them in as constants; the evaluation count comes from the number of
    stages. Each method's step is named ``<name>_step``: Numba names its
    machine code and its disk cache after the function, and closures sharing
    one name could be mixed up when some are loaded from the cache and others
    compiled in the same process (numba/numba#5128).
    """
    a, b, c, stages = tableau.a, tableau.b, tableau.c, tableau.stages
    if tableau.explicit:

        def explicit_tableau_step(hamilton, acceleration, t, q, p, h, params, separable,
                                  damping_rate):
            """One step of an explicit Runge-Kutta method: ``stages`` evaluations."""
            q1, p1 = explicit_rk(hamilton, t, q, p, h, params, a, b, c)
            return q1, p1, 0, stages

        step = explicit_tableau_step
    else:

        def implicit_tableau_step(hamilton, acceleration, t, q, p, h, params, separable,
                                  damping_rate):
            """One step of an implicit Runge-Kutta method (stages by fixed-point iteration)."""
            return implicit_rk(hamilton, t, q, p, h, params, a, b, c)

        step = implicit_tableau_step
    step.__name__ = step.__qualname__ = f"{name}_step"
    return jit_step(step)


# --------------------------------------------------------------------------- symplectic methods
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


@numba.njit(cache=True)
def implicit_kick(hamilton, t, q, p, k, params, separable, damping_rate, dq, dp):
    """Solve ``p_k = p - k H_q(t, q, p_k)`` for ``p_k``: the implicit momentum update.

    Starts from ``p + k dp``, so ``dp`` must hold ``-H_q(t, q, p)`` on entry
    (see :func:`remove_damping` for ``damping_rate``);
    the guess is exact when ``H`` is separable. Otherwise iterates
    ``p_k <- p + k dp(t, q, p_k)`` until :func:`fixed_point_status` finds
    round-off. ``dq``, ``dp`` are workspace. Returns ``(p_k, sweeps)``, with
    ``sweeps = -1`` if the iteration did not converge (after ``MAX_SWEEPS``).
    """
    p_k = p + k * dp
    if separable:
        return p_k, 0
    smallest, status, sweeps = np.full(p.size, np.inf), 0, 0
    while status == 0 and sweeps < MAX_SWEEPS:
        sweeps += 1
        hamilton(t, q, p_k, params, dq, dp)
        if damping_rate != 0.0:
            remove_damping(p_k, damping_rate, dp)
        p_new = p + k * dp
        status = fixed_point_status(p_new, p_k, smallest)
        p_k = p_new
    return p_k, (sweeps if status == 1 else -1)


@numba.njit(cache=True)
def symplectic_euler(hamilton, t, q, p, h, params, separable, damping_rate):
    """Symplectic Euler for a general ``H(t, q, p)``:

    ``p1 = p - h H_q(t, q, p1)``   (implicit in ``p1`` only)
    ``q1 = q + h H_p(t, q, p1)``
    """
    dq, dp = np.empty_like(q), np.empty_like(p)
    hamilton(t, q, p, params, dq, dp)
    if damping_rate != 0.0:
        remove_damping(p, damping_rate, dp)
    p1, sweeps = implicit_kick(hamilton, t, q, p, h, params, separable, damping_rate, dq, dp)
    if sweeps < 0:
        return q, p, -1, 1 + MAX_SWEEPS
    hamilton(t, q, p1, params, dq, dp)  # only dq = H_p is used
    return q + h * dq, p1, sweeps, sweeps + 2


@numba.njit(cache=True)
def stormer_verlet(hamilton, t, q, p, h, params, separable, damping_rate):
    """Stormer-Verlet for a general ``H(t, q, p)`` (the Lobatto IIIA-IIIB pair):

    ``p_half = p - h/2 H_q(t, q, p_half)``                          (implicit)
    ``q1 = q + h/2 [H_p(t, q, p_half) + H_p(t + h, q1, p_half)]``   (implicit)
    ``p1 = p_half - h/2 H_q(t + h, q1, p_half)``                    (explicit)
    """
    dq, dp = np.empty_like(q), np.empty_like(p)
    hamilton(t, q, p, params, dq, dp)
    if damping_rate != 0.0:
        remove_damping(p, damping_rate, dp)
    p_half, sweeps = implicit_kick(hamilton, t, q, p, 0.5 * h, params, separable, damping_rate,
                                   dq, dp)
    if sweeps < 0:
        return q, p, -1, 1 + MAX_SWEEPS
    calls = 1 + sweeps
    hamilton(t, q, p_half, params, dq, dp)  # only dq = H_p is used
    drift = q + 0.5 * h * dq
    q1 = q + h * dq  # exact when H is separable, else the first guess
    calls += 1
    if not separable:
        smallest, status, first_sweeps = np.full(q.size, np.inf), 0, sweeps
        while status == 0 and sweeps - first_sweeps < MAX_SWEEPS:
            sweeps += 1
            hamilton(t + h, q1, p_half, params, dq, dp)
            q_new = drift + 0.5 * h * dq
            status = fixed_point_status(q_new, q1, smallest)
            q1 = q_new
        calls += sweeps - first_sweeps
        if status != 1:
            return q, p, -1, calls
    hamilton(t + h, q1, p_half, params, dq, dp)
    if damping_rate != 0.0:
        remove_damping(p_half, damping_rate, dp)
    return q1, p_half + 0.5 * h * dp, sweeps, calls + 1


@jit_step
def semi_implicit_euler_step(hamilton, acceleration, t, q, p, h, params, separable,
                             damping_rate):
    """Symplectic Euler in ``(q, p)``: :func:`symplectic_euler` of the Hamiltonian."""
    return symplectic_euler(hamilton, t, q, p, h, params, separable, damping_rate)


@jit_step
def leapfrog_step(hamilton, acceleration, t, q, p, h, params, separable, damping_rate):
    """Stormer-Verlet in ``(q, p)``: :func:`stormer_verlet` of the Hamiltonian."""
    return stormer_verlet(hamilton, t, q, p, h, params, separable, damping_rate)


@jit_step
def conformal_euler_step(hamilton, acceleration, t, q, p, h, params, separable, damping_rate):
    """Conformal symplectic Euler [MP]: symplectic Euler, then the exact damping flow.

    ``(q, p) <- symplectic Euler of H``;  ``p <- exp(-gamma h) p``.
    """
    q1, p1, sweeps, calls = symplectic_euler(hamilton, t, q, p, h, params, separable,
                                             damping_rate)
    return q1, math.exp(-damping_rate * h) * p1, sweeps, calls


@jit_step
def conformal_leapfrog_step(hamilton, acceleration, t, q, p, h, params, separable,
                            damping_rate):
    """Conformal Stormer-Verlet [MP]: half the damping, a leapfrog step of ``H``, half again.

    ``p <- exp(-gamma h/2) p``;  ``(q, p) <- Stormer-Verlet of H``;
    ``p <- exp(-gamma h/2) p``. The damping flow is exact and the middle step
    symplectic, so each step contracts phase-space volume by exactly
    ``exp(-n gamma h)``, as the true flow does; symmetric, second order.
    """
    contraction = math.exp(-0.5 * damping_rate * h)
    q1, p1, sweeps, calls = stormer_verlet(hamilton, t, q, contraction * p, h, params,
                                           separable, damping_rate)
    return q1, contraction * p1, sweeps, calls


# --------------------------------------------------------------------------- the report's methods
@jit_step
def semi_implicit_euler_velocity_step(hamilton, acceleration, t, q, v, h, params, separable,
                                      damping_rate):
    """The course report's version on ``(q, v)``: ``v1 = v + h a(t, q, v)``; ``q1 = q + h v1``."""
    a = np.empty_like(v)
    acceleration(t, q, v, params, a)
    v1 = v + h * a
    return q + h * v1, v1, 0, 1


@jit_step
def leapfrog_velocity_step(hamilton, acceleration, t, q, v, h, params, separable, damping_rate):
    """The course report's leapfrog on ``(q, v)``, written as kick-drift-kick:

    ``v_half = v + h/2 a(t, q, v)``; ``q1 = q + h v_half``;
    ``v1 = v_half + h/2 a(t + h, q1, v_half)``.
    Second order only when ``a`` does not depend on ``v``.
    """
    a = np.empty_like(v)
    acceleration(t, q, v, params, a)
    v_half = v + 0.5 * h * a
    q1 = q + h * v_half
    acceleration(t + h, q1, v_half, params, a)
    return q1, v_half + 0.5 * h * a, 0, 2


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

    ``(field.hamilton, field.acceleration)``, or for a variational method the
    update and the momentum of the field's discrete Legendre transforms
    (compiled on first use).
    """
    if method.rule is None:
        return field.hamilton, field.acceleration
    kernels = field.discrete(method.rule)
    return getattr(kernels, VARIATIONAL_SOLVERS[method.solver]), kernels.impulse


# --------------------------------------------------------------------------- the time loop
MATRIX = types.float64[:, ::1]
RUN = types.void(
    types.FunctionType(STEP), HamiltonFn, AccelerationFn, types.boolean, VECTOR, MATRIX, MATRIX,
    types.float64, types.float64, types.int64, types.int64, types.int64, MATRIX,
    types.float64[:, :, ::1], types.float64[:, :, ::1], types.int64[:, ::1],
)
#: Codes in ``stats[:, STATUS]`` after :func:`run`.
RUNNING, NOT_FINITE, NOT_CONVERGED = 0, 1, 2
STEPS, SWEEPS, CALLS, STATUS = 0, 1, 2, 3


@numba.njit(cache=True)
def _all_finite(x):
    """``np.all(np.isfinite(x))`` without allocating a temporary array."""
    for value in x:
        if not math.isfinite(value):
            return False
    return True


def _run(step, hamilton, acceleration, separable, damping_rates, q, p, t0, h, n_steps,
         first_step, save_every, params, saved_q, saved_p, stats):
    """Advance every row of ``(q, p)`` (shape ``(K, n)``) by ``n_steps`` steps, in place.

    Steps are numbered globally from ``first_step + 1`` so that a long run can
    be made of several calls (for a progress bar); step ``s`` goes from time
    ``t0 + (s - 1) h`` to ``t0 + s h`` (computed from ``s``, not summed), and
    row ``k``'s state after it is stored in ``saved_q[k, s // save_every]``
    when ``save_every`` divides ``s``. ``params`` (shape ``(1, P)`` or
    ``(K, P)``) and ``damping_rates`` (shape ``(1,)`` or ``(K,)``) are shared
    or per row. ``stats[k]`` accumulates (steps done, solver sweeps,
    vector-field calls, status); a row stops at a non-finite state or a solver
    failure, keeping its status. Rows are independent; the caller may run
    slices of them in parallel threads (the kernel releases the GIL).
    """
    shared = params.shape[0] == 1
    for k in range(q.shape[0]):
        if stats[k, STATUS] != RUNNING:
            continue
        row = 0 if shared else k
        row_params, damping_rate = params[row], damping_rates[row]
        qk, pk = q[k].copy(), p[k].copy()
        for s in range(first_step + 1, first_step + n_steps + 1):
            q1, p1, sweeps, calls = step(hamilton, acceleration, t0 + (s - 1) * h, qk, pk, h,
                                         row_params, separable, damping_rate)
            stats[k, CALLS] += calls
            if sweeps < 0:
                stats[k, STATUS] = NOT_CONVERGED
                break
            qk, pk = q1, p1
            if not (_all_finite(qk) and _all_finite(pk)):
                stats[k, STATUS] = NOT_FINITE
                break
            stats[k, STEPS] = s
            stats[k, SWEEPS] += sweeps
            if s % save_every == 0:
                saved_q[k, s // save_every] = qk
                saved_p[k, s // save_every] = pk
        q[k], p[k] = qk, pk


run = LazyKernel(RUN, _run, cache=True, nogil=True)


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
    kernel : LazyKernel
        The step function (see the module docstring); ``kernel.py_func`` is
        its Python source, ``kernel.compiled`` the machine code.
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


def unsuitability(method: Method, field: HamiltonianField) -> str | None:
    """Why ``method`` cannot integrate ``field``, or None if it can."""
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
