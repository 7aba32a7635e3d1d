"""One-step integrators for Hamiltonian systems.

This module knows vector fields, not pendulums. A :class:`HamiltonianField`
bundles ``dH/dq(q, p)`` and ``dH/dp(q, p)`` (and, for the course report's
velocity-variable methods, the acceleration ``a(q, v)``). Every method maps a
state ``(x, y)`` to the next one; ``y`` is the canonical momentum ``p`` for
all methods except the two ``*_velocity`` ones, where it is the velocity.

Methods are data where they can be: explicit Euler and RK4 are Butcher
tableaus run by :func:`explicit_rk_step`; Gauss-Legendre is a tableau plus the
implicit stage solver :func:`solve_fixed_point`. The symplectic partitioned
methods are short functions whose lines follow the textbook formulas.

References
----------
.. [HLW] E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*,
   2nd ed., Springer 2006: symplectic Euler (Thm VI.3.3), Stormer-Verlet for
   general H (eq. VI.3.4), Gauss collocation (Sect. II.1.3, VI.4).
.. [HMR] E. Hairer, R. I. McLachlan, A. Razakarivony, "Achieving Brouwer's
   law with implicit Runge-Kutta methods", BIT 48 (2008) 231-243: iterate the
   stage equations to round-off, or energy drifts.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "METHODS",
    "ButcherTableau",
    "ConvergenceError",
    "HamiltonianField",
    "Method",
    "explicit_rk_step",
    "get_method",
    "solve_fixed_point",
]

Array = np.ndarray


class ConvergenceError(RuntimeError):
    """An implicit step's equations did not converge."""


@dataclass(frozen=True)
class HamiltonianField:
    """The vector field of ``H(q, p)``, as the integrators see it.

    Attributes
    ----------
    dH_dq, dH_dp : callable ``(q, p) -> array (..., n)``
    acceleration : callable ``(q, v) -> array (..., n)``, optional
        Only used by the velocity-variable methods.
    separable : bool
        True when ``dH/dq`` does not depend on ``p`` and ``dH/dp`` not on ``q``;
        the symplectic methods are then explicit.
    """

    dH_dq: Callable[[Array, Array], Array]
    dH_dp: Callable[[Array, Array], Array]
    acceleration: Callable[[Array, Array], Array] | None = None
    separable: bool = False

    def rhs(self, y: Array) -> Array:
        """``(dH/dp, -dH/dq)`` on the stacked state ``y = (q, p)``, shape ``(..., 2n)``."""
        q, p = np.split(y, 2, axis=-1)
        return np.concatenate([self.dH_dp(q, p), -self.dH_dq(q, p)], axis=-1)


# --------------------------------------------------------------------------- tableaus
@dataclass(frozen=True)
class ButcherTableau:
    """A Runge-Kutta method as data; it checks itself on creation.

    Checks: ``sum(b) == 1`` and row sums of ``A`` equal ``c`` (to 1e-14).
    """

    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    order: int
    explicit: bool = field(init=False)

    def __post_init__(self):
        a, b, c = (np.asarray(x, dtype=float) for x in (self.a, self.b, self.c))
        s = b.size
        if a.shape != (s, s) or c.shape != (s,):
            raise ValueError(f"tableau shapes do not match: A {a.shape}, b {b.shape}, c {c.shape}")
        if abs(b.sum() - 1.0) > 1e-14:
            raise ValueError(f"tableau weights must sum to 1, got {b.sum()!r}")
        if np.max(np.abs(a.sum(axis=1) - c)) > 1e-14:
            raise ValueError("tableau row sums of A must equal c")
        object.__setattr__(self, "a", a)
        object.__setattr__(self, "b", b)
        object.__setattr__(self, "c", c)
        object.__setattr__(self, "explicit", bool(np.all(np.triu(a) == 0)))

    @property
    def stages(self) -> int:
        return self.b.size


EULER_TABLEAU = ButcherTableau(a=[[0.0]], b=[1.0], c=[0.0], order=1)
RK4_TABLEAU = ButcherTableau(
    a=[[0, 0, 0, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 1, 0]],
    b=[1 / 6, 1 / 3, 1 / 3, 1 / 6],
    c=[0, 0.5, 0.5, 1],
    order=4,
)
_R3 = np.sqrt(3.0)
# Two-stage Gauss-Legendre collocation (the course report, section 2.4.5).
GAUSS4_TABLEAU = ButcherTableau(
    a=[[1 / 4, 1 / 4 - _R3 / 6], [1 / 4 + _R3 / 6, 1 / 4]],
    b=[1 / 2, 1 / 2],
    c=[1 / 2 - _R3 / 6, 1 / 2 + _R3 / 6],
    order=4,
)


def explicit_rk_step(tableau: ButcherTableau, f: Callable[[Array], Array], y: Array, h: float):
    """One step of an explicit Runge-Kutta method for the autonomous ``y' = f(y)``."""
    k = []
    for i in range(tableau.stages):
        yi = y
        for j in range(i):
            if tableau.a[i, j] != 0.0:
                yi = yi + (h * tableau.a[i, j]) * k[j]
        k.append(f(yi))
    return y + h * sum(bi * ki for bi, ki in zip(tableau.b, k))


# --------------------------------------------------------------------------- implicit solver
MAX_ITERATIONS = 100
# A stalled iteration counts as converged only if its last increment is this
# small relative to the unknowns: stalling far from round-off means divergence.
ROUNDOFF_TOLERANCE = 1e-11


def solve_fixed_point(g: Callable[[Array], Array], x0: Array, max_iterations: int = MAX_ITERATIONS):
    """Iterate ``x <- g(x)`` to round-off for a batch of unknowns.

    ``x0`` has shape ``(..., k)``: the leading axes index independent problems
    (trajectories of an ensemble), the last axis the unknowns of one problem.
    A problem is finished when no component of its increment ``|x_new - x|``
    fell below that component's smallest earlier increment (the iteration has
    reached round-off, where increments only fluctuate) and the increment is
    tiny. This per-component rule avoids stopping early on a small max-norm
    that is not yet the fixed point, and avoids a fixed tolerance.

    Returns
    -------
    x : array, shape like ``x0``
    iterations : int
        Evaluations of ``g`` made.
    converged : bool
    """
    x = x0
    smallest = np.full(x0.shape, np.inf)
    done = np.zeros(x0.shape[:-1], dtype=bool)
    for iteration in range(1, max_iterations + 1):
        x_new = g(x)
        delta = np.abs(x_new - x)
        x = x_new
        if not np.all(np.isfinite(x)):
            return x, iteration, False
        stalled = ~np.any(delta < smallest, axis=-1)
        small = np.all(delta <= ROUNDOFF_TOLERANCE * (1.0 + np.abs(x)), axis=-1)
        done |= stalled & small
        if np.all(done):
            return x, iteration, True
        smallest = np.minimum(smallest, delta)
    return x, max_iterations, False


# --------------------------------------------------------------------------- methods
@dataclass(frozen=True)
class Method:
    """An integrator: its properties and its one-step map.

    Attributes
    ----------
    name : str
    order : int
        Classical order of accuracy.
    symplectic : bool
        Symplectic for every Hamiltonian (in the variables it works in).
    implicit : bool
        Solves equations at each step (for non-separable ``H``).
    variables : {"canonical", "velocity"}
        ``(q, p)`` or, for the course report's versions, ``(q, v)``.
    summary : str
        One line for tables and dropdowns.
    step : callable ``(field, x, y, h) -> (x1, y1, iterations)``
        ``iterations`` counts the implicit solver's sweeps (0 if explicit).
    """

    name: str
    order: int
    symplectic: bool
    implicit: bool
    variables: str
    summary: str
    step: Callable = field(repr=False)

    def __str__(self) -> str:
        return self.name


def _explicit_euler(fld: HamiltonianField, q, p, h):
    y = explicit_rk_step(EULER_TABLEAU, fld.rhs, np.concatenate([q, p], -1), h)
    return (*np.split(y, 2, axis=-1), 0)


def _rk4(fld: HamiltonianField, q, p, h):
    y = explicit_rk_step(RK4_TABLEAU, fld.rhs, np.concatenate([q, p], -1), h)
    return (*np.split(y, 2, axis=-1), 0)


def _implicit(g, x0, what):
    x, iterations, converged = solve_fixed_point(g, x0)
    if not converged:
        raise ConvergenceError(
            f"the implicit equations for {what} did not converge in {iterations} "
            "fixed-point iterations; use a smaller dt"
        )
    return x, iterations


def _gauss_legendre(fld: HamiltonianField, q, p, h):
    """Two-stage Gauss collocation: ``K = f(y + h A K)``, ``y1 = y + h b.K``."""
    tab = GAUSS4_TABLEAU
    y = np.concatenate([q, p], -1)
    f0 = fld.rhs(y)
    dim = y.shape[-1]

    def stages(k_flat):
        k = k_flat.reshape(*y.shape[:-1], tab.stages, dim)
        stage_states = y[..., None, :] + h * np.einsum("ij,...jk->...ik", tab.a, k)
        return fld.rhs(stage_states).reshape(k_flat.shape)

    k0 = np.repeat(f0[..., None, :], tab.stages, axis=-2).reshape(*y.shape[:-1], -1)
    k_flat, iterations = _implicit(stages, k0, "the Gauss-Legendre stages")
    k = k_flat.reshape(*y.shape[:-1], tab.stages, dim)
    y1 = y + h * np.einsum("i,...ik->...k", tab.b, k)
    return (*np.split(y1, 2, axis=-1), iterations)


def _symplectic_euler(fld: HamiltonianField, q, p, h):
    """``p1 = p - h H_q(q, p1)``; ``q1 = q + h H_p(q, p1)`` (implicit in ``p1`` only)."""
    if fld.separable:
        p1, iterations = p - h * fld.dH_dq(q, p), 0
    else:
        p1, iterations = _implicit(lambda x: p - h * fld.dH_dq(q, x), p, "p_{n+1}")
    return q + h * fld.dH_dp(q, p1), p1, iterations


def _stormer_verlet(fld: HamiltonianField, q, p, h):
    """Generalized Stormer-Verlet (Lobatto IIIA-IIIB pair) for a general ``H(q, p)``.

    ``p_half = p - h/2 H_q(q, p_half)``                 (implicit)
    ``q1 = q + h/2 [H_p(q, p_half) + H_p(q1, p_half)]``  (implicit)
    ``p1 = p_half - h/2 H_q(q1, p_half)``                (explicit)
    """
    if fld.separable:
        p_half = p - 0.5 * h * fld.dH_dq(q, p)
        q1 = q + h * fld.dH_dp(q, p_half)
        return q1, p_half - 0.5 * h * fld.dH_dq(q1, p_half), 0
    p_half, it1 = _implicit(lambda x: p - 0.5 * h * fld.dH_dq(q, x), p, "p_{n+1/2}")
    drift = q + 0.5 * h * fld.dH_dp(q, p_half)
    q1, it2 = _implicit(lambda x: drift + 0.5 * h * fld.dH_dp(x, p_half), q, "q_{n+1}")
    return q1, p_half - 0.5 * h * fld.dH_dq(q1, p_half), it1 + it2


def _symplectic_euler_velocity(fld: HamiltonianField, q, v, h):
    """The course report's version on ``(q, v)``: ``v1 = v + h a(q, v)``; ``q1 = q + h v1``."""
    v1 = v + h * fld.acceleration(q, v)
    return q + h * v1, v1, 0


def _leapfrog_velocity(fld: HamiltonianField, q, v, h):
    """The course report's leapfrog on ``(q, v)``, written as kick-drift-kick.

    ``v_half = v + h/2 a(q, v)``; ``q1 = q + h v_half``; ``v1 = v_half + h/2 a(q1, v_half)``.
    Second order only when ``a`` does not depend on ``v``.
    """
    v_half = v + 0.5 * h * fld.acceleration(q, v)
    q1 = q + h * v_half
    return q1, v_half + 0.5 * h * fld.acceleration(q1, v_half), 0


METHODS: dict[str, Method] = {
    m.name: m
    for m in [
        Method("explicit_euler", 1, False, False, "canonical",
               "explicit Euler: y1 = y + h f(y)", _explicit_euler),
        Method("semi_implicit_euler", 1, True, True, "canonical",
               "symplectic Euler in (theta, p): implicit in p1 unless H is separable",
               _symplectic_euler),
        Method("leapfrog", 2, True, True, "canonical",
               "Stormer-Verlet in (theta, p): the generalized, implicit form",
               _stormer_verlet),
        Method("rk4", 4, False, False, "canonical",
               "classical fourth-order Runge-Kutta", _rk4),
        Method("glrk4", 4, True, True, "canonical",
               "two-stage Gauss-Legendre collocation (implicit Runge-Kutta)",
               _gauss_legendre),
        Method("semi_implicit_euler_velocity", 1, False, False, "velocity",
               "the report's semi-implicit Euler on (theta, omega): not symplectic for n >= 2",
               _symplectic_euler_velocity),
        Method("leapfrog_velocity", 2, False, False, "velocity",
               "the report's leapfrog on (theta, omega): not symplectic for n >= 2",
               _leapfrog_velocity),
    ]
}

MAIN_METHODS = ("explicit_euler", "semi_implicit_euler", "leapfrog", "rk4", "glrk4")


def get_method(method) -> Method:
    """Look up a method by name (or pass a :class:`Method` through)."""
    if isinstance(method, Method):
        return method
    if not isinstance(method, str):
        raise TypeError(f"`method` must be a method name (str), got {type(method).__name__}")
    try:
        return METHODS[method]
    except KeyError:
        raise ValueError(f"`method` must be one of {list(METHODS)}, got {method!r}") from None
