"""The registry of methods: every integrator the course compares, by name.

A Runge-Kutta method is one entry made from its Butcher tableau by
:meth:`~pendulum_lab.integrators.method.Method.from_tableau`; the other families declare
their properties next to their step, and every entry its reference step
(:mod:`~pendulum_lab.integrators.reference`). :func:`get_method` looks a method up,
:func:`unsuitability` says why a method cannot integrate a field, and :func:`step_kernels`
picks the two kernels a method's step receives from a field.
"""

from __future__ import annotations

import numpy as np

from . import reference
from .composition import Composition
from .field import HamiltonianField
from .method import ANY_FIELD, CONFORMAL_FIELD, HAMILTONIAN_FIELD, LAGRANGIAN_FIELD, Method
from .symplectic import (
    conformal_euler_step,
    conformal_leapfrog_step,
    leapfrog_step,
    semi_implicit_euler_step,
)
from .tableau import ButcherTableau, gauss_legendre_tableau
from .variational import VARIATIONAL_SOLVERS, variational_method
from .velocity import leapfrog_velocity_step, semi_implicit_euler_velocity_step

__all__ = [
    "CONFORMAL_METHODS",
    "MAIN_METHODS",
    "METHODS",
    "VARIATIONAL_METHODS",
    "get_method",
    "step_kernels",
    "suitable_methods",
    "unsuitability",
]


# Weights of the composition methods below, from their closed forms where they have one.
_TRIPLE_JUMP = 1 / (2 - 2 ** (1 / 3))
#: Yoshida's w0 (from the sum), w1, w2, w3: the sequence is w3 w2 w1 w0 w1 w2 w3.
_YOSHIDA6_PUBLISHED = (-1.17767998417887, 0.235573213359357, 0.784513610477560)
_YOSHIDA6 = (1 - 2 * sum(_YOSHIDA6_PUBLISHED), *_YOSHIDA6_PUBLISHED)
_SUZUKI = 1 / (4 - 4 ** (1 / 3))
_MCLACHLAN4 = ((14 - 19 ** 0.5) / 108, (146 + 5 * 19 ** 0.5) / 540, (-23 - 20 * 19 ** 0.5) / 270,
               (-2 + 10 * 19 ** 0.5) / 135, 1 / 5)
# Omelyan, Mryglod, Folk's PEFRL: drift xi, kick (1 - 2 lambda)/2, drift chi, kick lambda,
# drift 1 - 2 (chi + xi), then the same backwards; as adjoint, Euler, adjoint, ... substeps
# (each drift and kick is the sum of the two substeps that meet there).
_XI, _LAMBDA, _CHI = 0.1786178958448091, -0.2123418310626054, -0.06626458266981849
_OMELYAN4 = (_XI, 0.5 - _LAMBDA - _XI, _LAMBDA + _XI + _CHI - 0.5, 0.5 - _CHI - _XI)


def _substeps_meeting_at(flows):
    """Substep weights ``w`` with ``w_1 = flows[0]`` and ``w_k + w_(k-1) = flows[k-1]``.

    A splitting method's drifts and kicks are sums of neighbouring substeps of symplectic
    Euler and its adjoint, so this turns the first half of a splitting into substeps.
    """
    weights = [flows[0]]
    for flow in flows[1:]:
        weights.append(flow - weights[-1])
    return tuple(weights)


# Blanes and Moan's six-stage splitting of order 4 (their Table 2, S6, as published):
# drifts a1 a2 a3 a4 a3 a2 a1 between kicks b1 b2 b3 b3 b2 b1, a4 = 1 - 2 (a1 + a2 + a3),
# b3 = 1/2 - (b1 + b2). It begins with a drift: adjoint, Euler, adjoint, ... substeps.
_BM_A1, _BM_A2, _BM_A3 = 0.0792036964311957, 0.353172906049774, -0.0420650803577195
_BM_B1, _BM_B2 = 0.209515106613362, -0.143851773179818
_BLANES_MOAN4 = _substeps_meeting_at(
    (_BM_A1, _BM_B1, _BM_A2, _BM_B2, _BM_A3, 0.5 - _BM_B1 - _BM_B2))

_REGISTRY = [
    # Its reference step is the formula itself, not the one-stage stage loop.
    Method.from_tableau("explicit_euler", ButcherTableau(a=[[0.0]], b=[1.0]),
                        "explicit Euler: y1 = y + h f(y)", reference=reference.explicit_euler),
    Method("semi_implicit_euler", 1, True, True, "canonical",
           "symplectic Euler in (theta, p): implicit in p1 unless H is separable",
           semi_implicit_euler_step, applies_to=HAMILTONIAN_FIELD,
           reference=reference.symplectic_euler),
    Method("leapfrog", 2, True, True, "canonical",
           "Stormer-Verlet in (theta, p): the generalized, implicit form", leapfrog_step,
           applies_to=HAMILTONIAN_FIELD, symmetric=True, reference=reference.leapfrog),
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
           semi_implicit_euler_velocity_step, reference=reference.semi_implicit_euler_velocity),
    # Its kick takes the acceleration at the old velocity, and on a chain of two or more links
    # the acceleration depends on the velocity: first order there (observed 0.94-0.99 on the
    # double pendulum), second only on one link, where it is the canonical leapfrog.
    Method("leapfrog_velocity", 1, False, False, "velocity",
           "the report's leapfrog on (theta, omega): second order on one link, first order "
           "and not symplectic for n >= 2",
           leapfrog_velocity_step, reference=reference.leapfrog_velocity),
    Method("conformal_euler", 1, True, True, "canonical",
           "conformal symplectic Euler: symplectic Euler, then the exact linear damping",
           conformal_euler_step, applies_to=CONFORMAL_FIELD, reference=reference.conformal_euler),
    Method("conformal_leapfrog", 2, True, True, "canonical",
           "conformal Stormer-Verlet: exact damping for h/2, leapfrog, damping for h/2",
           conformal_leapfrog_step, applies_to=CONFORMAL_FIELD, symmetric=True,
           reference=reference.conformal_leapfrog),
    # Fixed-point iteration, as for Gauss-Legendre. Newton's method with the
    # generated Jacobian needs half the iterations and is faster per step
    # (benchmark item 7), but at large steps it can converge to another root
    # of the discrete equations, off the branch that continues the small-step
    # solution, where fixed-point iteration stops with an error
    # (tests/integrators/test_variational.py): no result is silently wrong.
    variational_method("midpoint", "fixed_point"),
    variational_method("trapezoid", "fixed_point"),
    # Composition methods: weights applied to the leapfrog, or to symplectic Euler and its
    # adjoint in turn; each checks its order and symmetry when it is made (composition.py).
    Method.from_composition("yoshida4", Composition(
        [_TRIPLE_JUMP, 1 - 2 * _TRIPLE_JUMP, _TRIPLE_JUMP], order=4,
        source="H. Yoshida, Phys. Lett. A 150 (1990) 262-268: the triple jump, "
               "w1 = 1 / (2 - 2^(1/3))"),
        "Yoshida's triple jump: three leapfrog steps, the middle one backwards (order 4)"),
    Method.from_composition("yoshida6", Composition(
        [*_YOSHIDA6[:0:-1], _YOSHIDA6[0], *_YOSHIDA6[1:]], order=6,
        source="H. Yoshida, Phys. Lett. A 150 (1990) 262-268, Table 1, solution A (15 digits; "
               "w0 = 1 - 2 (w1 + w2 + w3))"),
        "Yoshida's sixth-order composition: seven leapfrog steps (his solution A)"),
    Method.from_composition("suzuki4", Composition(
        [_SUZUKI, _SUZUKI, 1 - 4 * _SUZUKI, _SUZUKI, _SUZUKI], order=4,
        source="M. Suzuki, Phys. Lett. A 146 (1990) 319-323: the fractal decomposition, "
               "p = 1 / (4 - 4^(1/3))"),
        "Suzuki's fractal composition: five leapfrog steps, the middle one backwards "
        "(order 4)"),
    Method.from_composition("mclachlan4", Composition(
        [*_MCLACHLAN4, *_MCLACHLAN4[::-1]], order=4, base="symplectic_euler",
        source="R. I. McLachlan, SIAM J. Sci. Comput. 16 (1995) 151-168: the five-stage "
               "symmetric method of order 4 with the least error, in closed form"),
        "McLachlan's optimised order-4 composition of symplectic Euler and its adjoint "
        "(ten substeps)"),
    Method.from_composition("omelyan4", Composition(
        [*_OMELYAN4, *_OMELYAN4[::-1]], order=4, base="symplectic_euler", adjoint_first=True,
        source="I. P. Omelyan, I. M. Mryglod, R. Folk, Comput. Phys. Commun. 146 (2002) "
               "188-202: the position extended Forest-Ruth-like scheme (PEFRL), its xi, "
               "lambda, chi to the 16 digits published there"),
        "Omelyan-Mryglod-Folk's optimised order-4 splitting (PEFRL): drifts and kicks as "
        "symplectic Euler and its adjoint"),
    Method.from_composition("blanes_moan4", Composition(
        [*_BLANES_MOAN4, *_BLANES_MOAN4[::-1]], order=4, base="symplectic_euler",
        adjoint_first=True,
        source="S. Blanes, P. C. Moan, J. Comput. Appl. Math. 142 (2002) 313-330: the "
               "six-stage symmetric splitting of order 4 for separable problems (S6), its a1, "
               "a2, a3, b1, b2 to the 15 digits published there"),
        "Blanes-Moan's optimised order-4 splitting (six force evaluations): drifts and kicks "
        "as symplectic Euler and its adjoint"),
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
        return (f"{method.name} steps a discrete Lagrangian, which this field does not come "
                "with: one is generated where L = T - V is all of the dynamics and does not "
                "depend on the time (a drive, damping or a shaken pivot is not part of the "
                "generated L_d, whose kernels take no time)")
    if method.applies_to == CONFORMAL_FIELD and not np.all(np.isfinite(rates)):
        return (f"{method.name} needs damping of the conformal form dp/dt = -H_q - gamma p "
                "with a constant gamma")
    return None


def suitable_methods(field: HamiltonianField) -> list[str]:
    """Names of the registered methods that integrate ``field``."""
    return [m.name for m in _REGISTRY if unsuitability(m, field) is None]


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
