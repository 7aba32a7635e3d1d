"""The integrators layer: one-step maps of vector fields, compiled with Numba.

Modules, in the order they build on each other: ``tableau`` (Butcher tableaus and their
conditions), ``composition`` (composition methods' weights and their conditions), ``field``
(what a method sees of a system), ``step`` (how a step is declared),
``stopping`` (the stopping rule of every implicit solve), one module per family of methods
(``runge_kutta``, ``symplectic``, ``velocity``, ``variational``), ``reference`` (every method
again as a plain NumPy reference step that reads like its formula), ``method`` and ``registry``
(the methods by name, each with its compiled step and its reference step), ``source`` (a
method's reference step as the notebooks show it).

This layer knows vector fields, not pendulums. A vector field is a set of
compiled kernels (see :mod:`pendulum_lab.codegen.signatures`):
``hamilton(t, q, p, params, dq, dp)`` writes ``dq = dH/dp`` and
``dp = -dH/dq + Q`` (``Q``: forces no Hamiltonian describes, such as
damping); ``acceleration(t, q, v, params, out)`` writes the acceleration for
the course report's velocity-variable methods; ``stages`` evaluates
``hamilton`` at the several stage states of an implicit step in one call.
``t`` is the time, for fields that depend on it (a driven pendulum).

Every method is a step function ``(hamilton, acceleration, t, q, p, h, params, separable,
damping_rate[, memory]) -> (q1, p1, sweeps, calls)`` advancing from time ``t`` to ``t + h``:
``p`` is the canonical momentum for all methods except the two ``*_velocity`` ones, where it is
the velocity; ``sweeps`` counts implicit-solver iterations (``-1``: did not converge) and
``calls`` the vector-field evaluations. ``separable`` and ``damping_rate`` describe the field
(see :class:`~pendulum_lab.integrators.field.HamiltonianField`). A step declared with a memory
size (``jit_step(memory=...)``) takes one more argument, ``memory``: floats that the time loop
keeps for each trajectory from one step to the next. Steps use it as workspace (no memory is
allocated inside a run) and the implicit Runge-Kutta methods for what they carry between steps:
the last stage slopes, from which the next step's iteration starts, and the rounding error of
the state (compensated summation). A fresh ``memory`` (zeros) is a first step: nothing carried
over. The time loop that drives the steps is :mod:`pendulum_lab.driver.loops`; it compiles each
method together with each field, so the field's kernels are called directly (and inlined), not
through function pointers.

Methods are data where they can be: a Runge-Kutta method (explicit Euler, RK4, Gauss-Legendre)
is one registry entry made from its Butcher tableau by
:meth:`~pendulum_lab.integrators.method.Method.from_tableau`, which derives its order,
implicitness, symplecticity and evaluation count (:mod:`pendulum_lab.integrators.tableau`);
explicit tableaus are stepped by :func:`~pendulum_lab.integrators.runge_kutta.explicit_rk`,
implicit ones by :func:`~pendulum_lab.integrators.runge_kutta.implicit_rk` (fixed-point
iteration), which evaluates all stages in one call of the field's third kernel, ``stages``,
received in place of ``acceleration`` (:func:`~pendulum_lab.integrators.registry.step_kernels`).
Stage ``i`` is evaluated at time ``t + c_i h``. A composition method (Yoshida, Suzuki,
McLachlan, Omelyan) is one entry made from its weights and base method by
:meth:`~pendulum_lab.integrators.method.Method.from_composition`
(:mod:`~pendulum_lab.integrators.composition` checks them), stepped by
:func:`~pendulum_lab.integrators.symplectic.composition_step`: leapfrog steps, or symplectic
Euler and its adjoint in turn, each from the time where the last ended. The symplectic
partitioned methods follow the
textbook formulas line by line, with the time attached to the positions (extended phase space:
the first kick at ``t``, the last at ``t + h``); the conformal methods compose them with the
exact flow of linear damping. All implicit equations are iterated to round-off with one stopping
rule, :func:`~pendulum_lab.integrators.stopping.fixed_point_status`.

The compiled steps are written for speed (workspaces, views, stage sums padded to vector lanes).
Each method also carries a reference step (:attr:`Method.reference
<pendulum_lab.integrators.method.Method.reference>`, :mod:`~pendulum_lab.integrators.reference`):
the same step in NumPy, with the same starting values and the same stopping rule, never used in a
run; the tests compare the two step by step, and the notebooks show the reference.

The variational integrators (:data:`VARIATIONAL_METHODS`) are made from a
discrete Lagrangian instead of the vector field: their step solves the
discrete Legendre transform with kernels generated per chain or system
(:func:`pendulum_lab.codegen.kernels.load_discrete_kernels`), which it receives in
place of ``hamilton`` and ``acceleration`` (same Numba types; see
:func:`~pendulum_lab.integrators.registry.step_kernels`).

Which fields a method accepts (:attr:`~pendulum_lab.integrators.method.Method.applies_to`):
Runge-Kutta and the velocity methods integrate any field; symplectic Euler and the leapfrog
assume a Hamiltonian one (a drive is fine: ``H`` then depends on ``t``); the conformal methods
need damping of the form ``-gamma p`` (constant ``gamma``); the variational methods need a
discrete Lagrangian: an unforced chain's, or a system's whose L = T - V is all of its dynamics and
does not depend on the time.
:func:`~pendulum_lab.integrators.registry.unsuitability` says why a method does not fit a field.

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

from .field import ConvergenceError, HamiltonianField
from .method import Method
from .registry import (
    CONFORMAL_METHODS,
    EULER_TABLEAU,
    GAUSS4_TABLEAU,
    GAUSS8_TABLEAU,
    GAUSS12_TABLEAU,
    GAUSS16_TABLEAU,
    MAIN_METHODS,
    METHODS,
    RK4_TABLEAU,
    VARIATIONAL_METHODS,
    get_method,
    step_kernels,
    suitable_methods,
    unsuitability,
)
from .runge_kutta import explicit_rk, implicit_rk, tableau_step
from .step import Step, jit_step, kernel_function
from .stopping import MAX_SWEEPS, fixed_point_status
from .symplectic import implicit_kick, remove_damping
from .tableau import ButcherTableau, gauss_legendre_tableau
from .variational import variational_method, variational_step

__all__ = [
    "CONFORMAL_METHODS",
    "EULER_TABLEAU",
    "GAUSS12_TABLEAU",
    "GAUSS16_TABLEAU",
    "GAUSS4_TABLEAU",
    "GAUSS8_TABLEAU",
    "MAIN_METHODS",
    "MAX_SWEEPS",
    "METHODS",
    "RK4_TABLEAU",
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
