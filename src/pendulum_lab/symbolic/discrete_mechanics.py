"""Discrete mechanics of a chain of pendulums or any conservative, autonomous system (SymPy
only; uses :mod:`mechanics` and :mod:`systems`).

Variational integrators discretise the *action* instead of the equations of
motion [MW]. A discrete Lagrangian ``L_d(q_k, q_{k+1}; h)`` approximates the
action of the exact motion between two configurations a step ``h`` apart:

* midpoint rule:   ``L_d = h L((q_k + q_{k+1}) / 2, (q_{k+1} - q_k) / h)``
* trapezoidal rule: ``L_d = h/2 [L(q_k, v) + L(q_{k+1}, v)]``, ``v = (q_{k+1} - q_k) / h``

Making the discrete action ``sum_k L_d(q_k, q_{k+1})`` stationary gives the
discrete Euler-Lagrange equations

    D_2 L_d(q_{k-1}, q_k) + D_1 L_d(q_k, q_{k+1}) = 0,

and the discrete Legendre transforms

    p_k = -D_1 L_d(q_k, q_{k+1}),      p_{k+1} = D_2 L_d(q_k, q_{k+1}),

which turn them into a one-step map ``(q_k, p_k) -> (q_{k+1}, p_{k+1})``. That
map is symplectic for any ``L_d`` (its generating function is ``L_d``), and
``p`` is the *canonical* momentum: as ``h -> 0`` it tends to
``dL/domega = M(q) omega``, not to the velocity.

This module derives these equations; :func:`reference_step` solves them for
one step numerically, to check them against the course's integrators (it is
slow, pure Python; compiled kernels come with the integrator registry).

References
----------
.. [MW] J. E. Marsden, M. West, "Discrete mechanics and variational
   integrators", Acta Numerica 10 (2001) 357-514, Sect. 1.2-1.3 and 2.
.. [HLW] E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*,
   2nd ed., Springer 2006, Sect. VI.6 (variational integrators).
"""

from __future__ import annotations

import functools

import numpy as np
import sympy as sp

from .mechanics import Chain, derive_chain
from .systems import MechanicalSystem

__all__ = ["RULES", "DiscreteLagrangian", "discrete_lagrangian", "discrete_momenta",
           "reference_step"]

RULES = ("midpoint", "trapezoid")


def _configuration(system, base: str, label: str) -> sp.Matrix:
    """Symbols for the coordinates at step ``label``, shown with LaTeX subscripts.

    A chain's are ``theta_{k}`` (one link) or ``theta_{i,k}``; a system's carry its
    coordinates' names, ``r_{k}``, ``theta_{k}``. ``base`` names a chain's (``theta``, or
    ``v`` for the velocities); a system's velocities are ``v_{r,k}``.
    """
    n = system.n
    if isinstance(system, MechanicalSystem):
        names = ([f"{qi.name}_{{{label}}}" for qi in system.q] if base == "theta"
                 else [f"{base}_{{{qi.name},{label}}}" for qi in system.q])
    else:
        names = ([f"{base}_{{{label}}}"] if n == 1
                 else [f"{base}_{{{i},{label}}}" for i in range(1, n + 1)])
    return sp.Matrix([sp.Symbol(name, real=True) for name in names])


def _require_lagrangian_only(system) -> None:
    """A ``ValueError`` unless ``L = T - V`` is all of ``system``'s dynamics and has no ``t``.

    The generated kernels take no time and no forces: a drive, damping or a shaken pivot
    would be left out of the steps without a word.
    """
    if getattr(system, "forced", False):
        raise ValueError(f"{_described(system)} has generalized forces (a drive or damping), "
                         "which are not part of its Lagrangian: a discrete Lagrangian would "
                         "leave them out")
    if isinstance(system, MechanicalSystem) and not system.autonomous:
        raise ValueError(f"{_described(system)} has a Lagrangian that depends on the time t; "
                         "the discrete Lagrangians here are of autonomous systems only")


def _described(system) -> str:
    return system.name if isinstance(system, MechanicalSystem) else f"a chain of {system.n} links"


class DiscreteLagrangian:
    """A discrete Lagrangian of a chain or a system and the equations it generates.

    Parameters
    ----------
    chain : Chain or MechanicalSystem
        Unforced, with a Lagrangian that does not depend on the time (a ``ValueError``
        otherwise). Only ``n``, ``q``, ``omega``, ``lagrangian``, ``parameters`` and
        ``mass_matrix`` are read.
    rule : {"midpoint", "trapezoid"}

    Attributes
    ----------
    h : sympy.Symbol
        The step, ``h`` (positive): the same symbol as
        ``pendulum_lab.geometric.STEP_SIZE``.
    q_prev, q, q_next : sympy.Matrix, shape (n, 1)
        Configurations at steps ``k - 1``, ``k``, ``k + 1``.
    expression : sympy.Expr
        ``L_d(q, q_next)``.
    momentum_minus : sympy.Matrix, shape (n, 1)
        ``p_k = -D_1 L_d(q, q_next)``.
    momentum_plus : sympy.Matrix, shape (n, 1)
        ``p_{k+1} = D_2 L_d(q, q_next)``.
    euler_lagrange : sympy.Matrix, shape (n, 1)
        ``D_2 L_d(q_prev, q) + D_1 L_d(q, q_next)``; zero along a discrete motion.
    v : sympy.Matrix, shape (n, 1)
        Symbols for the step's velocity ``(q_next - q) / h``, used by the
        *velocity forms* below, in which ``q``, ``q_next`` and ``v`` are
        independent (so no ``1/h`` appears; :meth:`with_velocity` substitutes).
    mean_mass : sympy.Matrix, shape (n, n)
        ``(1/h) d^2 L_d / dv^2``: ``M`` at the midpoint, or the mean of ``M`` at
        the two ends (trapezoid). Symmetric positive definite.
    momentum_minus_form, momentum_plus_form : sympy.Matrix, shape (n, 1)
        The transforms in velocity form: ``mean_mass v - dL_d/dq`` and
        ``mean_mass v + dL_d/dq_next``, derivatives at fixed ``v``.
    impulse_form : sympy.Matrix, shape (n, 1)
        ``p_{k+1} - p_k = D_2 L_d + D_1 L_d`` in velocity form: ``h`` times
        forces, without the ``mean_mass v`` that both transforms contain, so
        a momentum update ``p_{k+1} = p_k + impulse`` carries no ``1/h``
        amplification of round-off.
    momentum_minus_jacobian_form : sympy.Matrix, shape (n, n)
        ``d p_k / d q_next`` (the total derivative, ``v`` moving with
        ``q_next``) in velocity form: the Jacobian of Newton's method for
        ``q_next``.

    Examples
    --------
    >>> dl = discrete_lagrangian(1, "trapezoid")
    >>> dl.momentum_minus[0]
    g*h*l*m*sin(theta_{k})/2 + l**2*m*theta_{k+1}/h - l**2*m*theta_{k}/h
    """

    def __init__(self, chain: Chain | MechanicalSystem, rule: str):
        if rule not in RULES:
            raise ValueError(f"`rule` must be one of {list(RULES)}, got {rule!r}")
        _require_lagrangian_only(chain)
        self.chain, self.rule, self.n = chain, rule, chain.n
        self.h = sp.Symbol("h", positive=True)
        self.q_prev = _configuration(chain, "theta", "k-1")
        self.q = _configuration(chain, "theta", "k")
        self.q_next = _configuration(chain, "theta", "k+1")
        self.expression = self(self.q, self.q_next)
        self.momentum_minus = sp.expand(-self._gradient(self.expression, self.q))
        self.momentum_plus = sp.expand(self._gradient(self.expression, self.q_next))
        self.euler_lagrange = (self._gradient(self(self.q_prev, self.q), self.q)
                               + self._gradient(self.expression, self.q))
        self._velocity_forms()

    def _velocity_forms(self) -> None:
        """The transforms with the velocity ``v`` as independent symbols (see the attributes).

        With ``L_d(a, b) = A(a, b, (b - a)/h)``: ``D_1 L_d = A_a - A_v / h`` and
        ``D_2 L_d = A_b + A_v / h``, and ``A_v / h = mean_mass v`` because ``L``
        is quadratic in the velocity (plus the rule's mean of ``b`` where ``L`` has terms
        linear in it, ``b(q)^T omega``; the transforms keep them, as they keep everything
        ``A_v`` holds).
        """
        self.v = _configuration(self.chain, "v", "k")
        action = self._action(self.q, self.q_next, self.v)
        velocity_momentum = self._gradient(action, self.v) / self.h
        self.mean_mass = sp.expand(velocity_momentum.jacobian(self.v))
        self.momentum_minus_form = sp.expand(velocity_momentum - self._gradient(action, self.q))
        self.momentum_plus_form = sp.expand(velocity_momentum
                                            + self._gradient(action, self.q_next))
        self.impulse_form = sp.expand(self._gradient(action, self.q)
                                      + self._gradient(action, self.q_next))
        self.momentum_minus_jacobian_form = sp.expand(
            self.momentum_minus_form.jacobian(self.q_next)
            + self.momentum_minus_form.jacobian(self.v) / self.h)

    def with_velocity(self, expr):
        """``expr`` in velocity form with ``v = (q_next - q) / h`` put back."""
        return expr.xreplace(dict(zip(self.v, (self.q_next - self.q) / self.h)))

    @staticmethod
    def _gradient(expr, variables) -> sp.Matrix:
        return sp.Matrix([sp.diff(expr, x) for x in variables])

    def lagrangian_at(self, configuration, velocity) -> sp.Expr:
        """The continuous ``L(q, omega)`` at the given configuration and velocity."""
        chain = self.chain
        subs = dict(zip(chain.q, configuration)) | dict(zip(chain.omega, velocity))
        return chain.lagrangian.xreplace(subs)

    def __call__(self, a, b) -> sp.Expr:
        """``L_d(a, b)`` for configurations ``a``, ``b`` (sequences of length n)."""
        a, b = sp.Matrix(a), sp.Matrix(b)
        return self._action(a, b, (b - a) / self.h)

    def _action(self, a, b, velocity) -> sp.Expr:
        """The rule's quadrature of the action from ``a`` to ``b`` at the given velocity."""
        if self.rule == "midpoint":
            return self.h * self.lagrangian_at((a + b) / 2, velocity)
        return self.h / 2 * (self.lagrangian_at(a, velocity) + self.lagrangian_at(b, velocity))

    def __repr__(self) -> str:
        if isinstance(self.chain, MechanicalSystem):
            return f"DiscreteLagrangian({self.chain.name!r}, rule={self.rule!r})"
        return f"DiscreteLagrangian(n={self.n}, rule={self.rule!r})"


@functools.cache
def _discrete(n_or_system, rule: str) -> DiscreteLagrangian:
    system = n_or_system if isinstance(n_or_system, MechanicalSystem) else derive_chain(n_or_system)
    return DiscreteLagrangian(system, rule)


def discrete_lagrangian(n, rule: str) -> DiscreteLagrangian:
    """The discrete Lagrangian of a chain of ``n`` links, or of a system, by ``rule``
    (derived once, cached).

    Parameters
    ----------
    n : int or MechanicalSystem
        Number of links, ``>= 1``; or a conservative system whose Lagrangian does not depend
        on the time (the elastic pendulum's, the cart pendulum's).
    rule : {"midpoint", "trapezoid"}

    Examples
    --------
    >>> import sympy as sp
    >>> r, th, m, k, g = sp.symbols("r theta m k g", positive=True)
    >>> spring = MechanicalSystem([r, th], {m: 1.0, k: 40.0, g: 9.81}, masses=[m],
    ...                           points=[(r * sp.sin(th), -r * sp.cos(th))], gravity=g,
    ...                           potential=k * (r - 1) ** 2 / 2)
    >>> list(discrete_lagrangian(spring, "midpoint").q_next)
    [r_{k+1}, theta_{k+1}]
    """
    if rule not in RULES:
        raise ValueError(f"`rule` must be one of {list(RULES)}, got {rule!r}")
    if isinstance(n, MechanicalSystem):
        return _discrete(n, rule)  # DiscreteLagrangian refuses forces or a time-dependent L
    if isinstance(n, bool) or not isinstance(n, int):
        raise TypeError(f"`n` must be an integer >= 1 or a MechanicalSystem, got {n!r}")
    if n < 1:
        raise ValueError(f"`n` must be an integer >= 1, got {n}")
    return _discrete(n, rule)


@functools.cache
def _step_functions(n, rule: str):
    dl = _discrete(n, rule)
    args = (*dl.q, *dl.q_next, dl.h, *dl.chain.parameters)
    minus = sp.lambdify(args, list(dl.momentum_minus), cse=True, dummify=True)
    jac = sp.lambdify(args, dl.momentum_minus.jacobian(dl.q_next).tolist(), cse=True, dummify=True)
    plus = sp.lambdify(args, list(dl.momentum_plus), cse=True, dummify=True)
    return minus, jac, plus


def reference_step(n, rule: str, parameters: dict, q0, p0, h: float,
                   tol: float = 1e-14, max_iterations: int = 50):
    """One step of the variational integrator of ``rule``, solved by Newton's method.

    Solves ``p0 = -D_1 L_d(q0, q1)`` for ``q1`` (from the guess
    ``q0 + h M(q0)^-1 p0``), then ``p1 = D_2 L_d(q0, q1)``. A slow reference
    for checking the derivation, not a production integrator.

    Parameters
    ----------
    n : int or MechanicalSystem
        As for :func:`discrete_lagrangian`.
    rule : {"midpoint", "trapezoid"}
    parameters : dict
        ``{symbol: value}`` for the masses, lengths and ``g``, or a system's parameters (a
        model's ``parameter_values``).
    q0, p0 : array_like, shape (n,)
    h : float
        Step; negative steps backwards.

    Returns
    -------
    q1, p1 : ndarray, shape (n,)

    Raises
    ------
    RuntimeError
        If Newton's method does not converge.
    """
    dl = discrete_lagrangian(n, rule)
    minus, jac, plus = _step_functions(n, rule)
    values = _parameter_values(dl, parameters)
    q0, p0 = np.asarray(q0, float), np.asarray(p0, float)
    n = dl.n
    if q0.shape != (n,) or p0.shape != (n,):
        raise ValueError(f"`q0` and `p0` must have shape ({n},), got {q0.shape} and {p0.shape}")
    if not (np.isfinite(h) and h != 0):
        raise ValueError(f"`h` must be a finite, non-zero step, got {h}")
    mass = sp.lambdify((*dl.chain.q, *dl.chain.parameters), dl.chain.mass_matrix, dummify=True)
    q1 = q0 + h * np.linalg.solve(np.asarray(mass(*q0, *values), float), p0)
    for _ in range(max_iterations):
        residual = np.asarray(minus(*q0, *q1, h, *values), float) - p0
        update = np.linalg.solve(np.asarray(jac(*q0, *q1, h, *values), float), residual)
        q1 = q1 - update
        if np.max(np.abs(update)) <= tol * (1 + np.max(np.abs(q1))):
            return q1, np.asarray(plus(*q0, *q1, h, *values), float)
    raise RuntimeError(f"the discrete Legendre transform did not converge in {max_iterations} "
                       f"Newton iterations (h = {h})")


def _parameter_values(dl: DiscreteLagrangian, parameters) -> list[float]:
    """The chain's parameter values in the order of its symbols, from ``{symbol: value}``."""
    if not isinstance(parameters, dict):
        raise TypeError("`parameters` must be a dict {symbol: value} (a model's "
                        f"parameter_values), got {type(parameters).__name__}")
    try:
        return [float(parameters[s]) for s in dl.chain.parameters]
    except KeyError as missing:
        raise ValueError(f"`parameters` lacks a value for {missing}") from None


def discrete_momenta(n, rule: str, parameters: dict, q0, q1, h: float):
    """The discrete Legendre transforms of steps ``q0 -> q1``: the momenta at both ends.

    Parameters
    ----------
    n : int or MechanicalSystem
        As for :func:`discrete_lagrangian`.
    rule : {"midpoint", "trapezoid"}
    parameters : dict
        A model's ``parameter_values``.
    q0, q1 : array_like, shape (..., n)
        Configurations at the start and the end of each step.
    h : float
        The step.

    Returns
    -------
    p_start, p_end : ndarray, shape (..., n)
        ``-D_1 L_d(q0, q1)`` and ``D_2 L_d(q0, q1)``. Along a discrete motion
        ``q_0, q_1, ...`` the end momentum of one step equals the start
        momentum of the next: that is the discrete Euler-Lagrange equation.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> pendulum = pl.simple_pendulum(mass=1.0, length=1.0)
    >>> start, end = discrete_momenta(1, "midpoint", pendulum.parameter_values, [0.0], [0.1], 0.1)
    >>> round(float(start[0] + end[0]), 12)   # twice m l^2 v, v = 1 rad/s
    2.0
    """
    dl = discrete_lagrangian(n, rule)
    minus, _, plus = _step_functions(n, rule)
    values = _parameter_values(dl, parameters)
    q0, q1 = np.asarray(q0, float), np.asarray(q1, float)
    n = dl.n
    if q0.shape != q1.shape or q0.ndim == 0 or q0.shape[-1] != n:
        raise ValueError(f"`q0` and `q1` must have the same shape (..., {n}), got {q0.shape} "
                         f"and {q1.shape}")
    if not (np.isfinite(h) and h != 0):
        raise ValueError(f"`h` must be a finite, non-zero step, got {h}")
    args = (*np.moveaxis(q0, -1, 0), *np.moveaxis(q1, -1, 0), h, *values)
    return tuple(np.stack(np.broadcast_arrays(*f(*args)), axis=-1) for f in (minus, plus))
