"""Slips in the course report's arguments, each checked symbolically (SymPy only).

The course report (Kanoun, Cowley, Ivachtchenko, *Periodic Pendulums*, MAT332,
University of Toronto, 2024) prints the double pendulum's equations, and
notebook ``01a_auditing_the_report`` types those in and compares them with
:mod:`pendulum_lab.symbolic.mechanics`. The slips checked here are in the steps
*between* equations: an expansion, an order-of-magnitude argument, a
chain-rule line, a step size called small. Each function types in what the
report prints (its section and equation numbers are in the docstring),
derives the correct statement, and returns the verdicts as
:class:`Comparison` rows a notebook prints in one line each.

Symbols are those of :func:`pendulum_lab.symbolic.mechanics.derive_chain` (the report
writes ``L_1, L_2`` for the lengths ``l_1, l_2``).
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from .mechanics import derive_chain, is_identically_zero

__all__ = [
    "Comparison",
    "LeapfrogLimit",
    "energy_rate_checks",
    "leapfrog_stability_limit",
    "simple_pendulum_eigenvalue_checks",
    "small_angle_argument_checks",
    "small_angle_lagrangian_checks",
    "small_angle_order",
]

#: Bookkeeping parameter of the small-angle expansion: angles and angular
#: velocities are scaled by it, so a term of degree ``k`` in them is ``O(epsilon^k)``.
EPSILON = sp.Symbol("epsilon", positive=True)


@dataclass(frozen=True)
class Comparison:
    """One statement of the report against the derivation.

    Attributes
    ----------
    label : str
        What is compared, in words.
    agrees : bool
        Whether the two sides are identically equal (decided by
        :func:`~pendulum_lab.symbolic.mechanics.is_identically_zero`).
    difference : sympy.Expr
        Derived side minus the side being checked (or the expression itself
        when it is checked against 0), factored; ``0`` when they agree.
    """

    label: str
    agrees: bool
    difference: sp.Expr

    def __str__(self) -> str:
        if self.agrees:
            return f"{self.label}: agrees"
        return f"{self.label}: differs by {self.difference}"


def _compare(label: str, derived, claimed) -> Comparison:
    """Compare two expressions, or two column matrices entry by entry."""
    difference = sp.expand(derived - claimed)
    entries = list(difference) if isinstance(difference, sp.MatrixBase) else [difference]
    agrees = all(is_identically_zero(entry) for entry in entries)
    if agrees:
        return Comparison(label, True, sp.Integer(0))
    factored = difference.applyfunc(sp.factor) if len(entries) > 1 else sp.factor(entries[0])
    return Comparison(label, False, factored)


def small_angle_order(expr) -> int:
    """Lowest power of the angles and angular velocities in ``expr`` (double pendulum symbols).

    Scales ``theta_i`` and ``omega_i`` by :data:`EPSILON` and returns the
    lowest power of ``EPSILON`` in the Maclaurin series: ``2`` for
    ``theta_1**2 + theta_2**2``, ``4`` for ``(cos(theta_1 - theta_2) - 1) omega_1 omega_2``.

    Examples
    --------
    >>> chain = derive_chain(2)
    >>> t1, t2 = chain.q
    >>> small_angle_order((t1 - t2) ** 2), small_angle_order(sp.cos(t1) - 1)
    (2, 2)
    """
    chain = derive_chain(2)
    scale = {s: EPSILON * s for s in (*chain.q, *chain.omega)}
    scaled = sp.sympify(expr).xreplace(scale)
    for power in range(0, 12):
        if not is_identically_zero(sp.series(scaled, EPSILON, 0, power + 1).removeO()):
            return power
    raise ValueError("`expr` vanishes to order 11 in the angles; nothing to count")


def _quadratic_lagrangian() -> sp.Expr:
    """The double pendulum's Lagrangian to second order in the angles and velocities.

    The constant (zeroth-order) term is dropped, as the report's (35) drops it;
    the odd orders vanish (``L`` is even in ``(theta, omega)``).
    """
    chain = derive_chain(2)
    scale = {s: EPSILON * s for s in (*chain.q, *chain.omega)}
    series = sp.series(chain.lagrangian.xreplace(scale), EPSILON, 0, 3).removeO()
    return sp.expand(series.coeff(EPSILON, 2))


def _report_35(potential_sign: int) -> sp.Expr:
    """The report's small-angle Lagrangian (35), with its potential terms' sign as given."""
    chain = derive_chain(2)
    (t1, t2), (w1, w2) = chain.q, chain.omega
    (m1, m2), (l1, l2), g = chain.masses, chain.lengths, chain.g
    kinetic = (m1 + m2) / 2 * l1**2 * w1**2 + m2 / 2 * l2**2 * w2**2 + m2 * l1 * l2 * w1 * w2
    potential_terms = (m1 + m2) / 2 * g * l1 * t1**2 + m2 / 2 * g * l2 * t2**2
    return kinetic + potential_sign * potential_terms


def _euler_lagrange(lagrangian: sp.Expr) -> list[sp.Expr]:
    """``d/dt dL/d omega_i - dL/d theta_i`` for a Lagrangian quadratic in ``omega``.

    For such a Lagrangian with a constant mass matrix (the small-angle case)
    ``d/dt dL/domega_i = sum_j d2L/domega_i domega_j alpha_j``.
    """
    chain = derive_chain(2)
    rows = []
    for qi, wi in zip(chain.q, chain.omega):
        momentum = lagrangian.diff(wi)
        rate = sum(momentum.diff(wj) * aj for wj, aj in zip(chain.omega, chain.omega_dot))
        rate += sum(momentum.diff(qj) * wj for qj, wj in zip(chain.q, chain.omega))
        rows.append(sp.expand(rate - lagrangian.diff(qi)))
    return rows


def simple_pendulum_eigenvalue_checks() -> list[Comparison]:
    """Section 3.2: the simple pendulum's Jacobians and their characteristic equations.

    The report's Jacobians at the bottom and at the top, ``[[0, 1], [-+g/l, 0]]``,
    are right, but the characteristic equations that follow,
    ``lambda^2 + 1 = 0`` and ``lambda^2 - 1 = 0``, silently set ``g/l = 1``; the
    right ones are ``lambda^2 + g/l = 0`` and ``lambda^2 - g/l = 0``.

    Returns
    -------
    list of Comparison
        For each equilibrium: the printed Jacobian against the derived one, and
        the printed characteristic polynomial against the derived one.

    Examples
    --------
    >>> [c.agrees for c in simple_pendulum_eigenvalue_checks()]
    [True, False, True, False]
    """
    chain = derive_chain(1)
    lam = sp.Symbol("lambda")
    ratio = chain.g / chain.lengths[0]
    printed = {
        "down": (sp.Matrix([[0, 1], [-ratio, 0]]), lam**2 + 1),
        "up": (sp.Matrix([[0, 1], [ratio, 0]]), lam**2 - 1),
    }
    rows = []
    for name, (jacobian, polynomial) in printed.items():
        derived = chain.equilibrium(name).jacobian
        rows.append(_compare(f"Jacobian at {name}", derived, jacobian))
        rows.append(_compare(f"characteristic polynomial at {name}",
                             derived.charpoly(lam).as_expr(), polynomial))
    return rows


def small_angle_lagrangian_checks() -> list[Comparison]:
    """Section 4.4, equations (35) to (37): the small-angle Lagrangian and its equations.

    Expanding the Lagrangian (11) to second order gives the potential terms
    ``-(m1 + m2) g L1 theta1^2 / 2 - m2 g L2 theta2^2 / 2`` (``cos x ~ 1 - x^2/2``
    multiplies ``+(m1 + m2) g L1`` and ``+m2 g L2`` in ``L``). The report's (35)
    prints them with a plus sign. Its equations (36), ``(1 + m1/m2) L1 alpha1 +
    L2 alpha2 + (1 + m1/m2) g theta1 = 0``, and (37), ``L1 alpha1 + L2 alpha2 +
    g theta2 = 0``, have the right sign nonetheless: they follow from the
    corrected (35), not from the printed one.

    Returns
    -------
    list of Comparison
        (35) as printed and with the sign reversed against the expansion of
        the derived Lagrangian; (36) and (37) against the Euler-Lagrange
        equations of the corrected and of the printed (35).

    Examples
    --------
    >>> [c.agrees for c in small_angle_lagrangian_checks()]
    [False, True, True, True, False]
    """
    chain = derive_chain(2)
    (t1, t2), (a1, a2) = chain.q, chain.omega_dot
    (m1, m2), (l1, l2), g = chain.masses, chain.lengths, chain.g
    quadratic = _quadratic_lagrangian()
    eq36 = (1 + m1 / m2) * l1 * a1 + l2 * a2 + (1 + m1 / m2) * g * t1
    eq37 = l1 * a1 + l2 * a2 + g * t2
    # (36) is the first Euler-Lagrange equation divided by m2 L1, (37) the second by m2 L2.
    corrected = _euler_lagrange(_report_35(-1))
    printed = _euler_lagrange(_report_35(+1))
    return [
        _compare("(35) as printed against the expansion of L to second order", quadratic,
                 _report_35(+1)),
        _compare("(35) with the potential terms' sign reversed", quadratic, _report_35(-1)),
        _compare("(36) from the corrected (35)", corrected[0] / (m2 * l1), eq36),
        _compare("(37) from the corrected (35)", corrected[1] / (m2 * l2), eq37),
        _compare("(36) from (35) as printed", printed[0] / (m2 * l1), eq36),
    ]


def small_angle_argument_checks() -> dict[str, int]:
    """Section 4.4: why ``cos(theta1 - theta2)`` may be replaced by 1 for small angles.

    The report argues that ``theta1^2 + theta2^2 ~ 2 theta1 theta2`` for small
    angles, so ``(theta1 - theta2)^2 ~ 0``. That is false: the difference of
    the two sides is ``(theta1 - theta2)^2`` itself, of the same (second)
    order as each side, and not small compared with them (at ``theta = (0.1,
    -0.1)`` the sides are ``0.02`` and ``-0.02``). The right argument is order
    counting: ``cos(theta1 - theta2)`` multiplies ``omega1 omega2``, already of
    second order, so replacing it by 1 changes ``L`` only at fourth order, and
    the linear equations (second-order ``L``) not at all, whatever the angle
    between the arms.

    Returns
    -------
    dict
        Orders in the angles and velocities (see :func:`small_angle_order`) of
        the report's two sides, of their difference, of the term the report
        drops from ``L`` when it sets the cosine to 1, and of the Lagrangian
        that gives linear equations.

    Examples
    --------
    >>> sorted(set(small_angle_argument_checks().values()))  # orders 2, and 4 for the term dropped
    [2, 4]
    """
    chain = derive_chain(2)
    (t1, t2), (w1, w2) = chain.q, chain.omega
    dropped = (sp.cos(t1 - t2) - 1) * w1 * w2
    return {
        "theta1^2 + theta2^2": small_angle_order(t1**2 + t2**2),
        "2 theta1 theta2": small_angle_order(2 * t1 * t2),
        "their difference (theta1 - theta2)^2": small_angle_order((t1 - t2) ** 2),
        "term dropped from L: (cos(theta1 - theta2) - 1) omega1 omega2": small_angle_order(dropped),
        "L for linear equations of motion": small_angle_order(_quadratic_lagrangian()),
    }


def energy_rate_checks() -> list[Comparison]:
    """Section 3.3: the report's proof that the simple pendulum conserves energy.

    In this section the report follows Hairer, Lubich and Wanner's notation:
    ``p`` is the angle, ``q`` the angular velocity, ``p' = q``,
    ``q' = -sin p`` and ``H(p, q) = q^2/2 + 1 - cos p`` (with ``g/l = 1``).
    Its chain-rule line reads ``dH/dt = p p' + q' sin p``; the chain rule gives
    ``H_p p' + H_q q' = sin(p) p' + q q'``. The printed line does not vanish
    along the flow (it equals ``p q - sin(p)^2``); the report's next line,
    ``-q sin p + sin(p) q``, follows from the correct one. The energy line
    before it, ``E = p^2/2 + u(x)``, likewise puts the angle where the velocity
    belongs: along the flow ``d/dt (p^2/2 + 1 - cos p) = (p + sin p) q``.

    Returns
    -------
    list of Comparison
        ``H`` against the system it should generate; the printed and the
        chain-rule lines against ``dH/dt``; each line along the flow against 0;
        the printed energy's rate against 0.

    Examples
    --------
    >>> [c.agrees for c in energy_rate_checks()]
    [True, False, True, False, True, False]
    """
    p, q = sp.symbols("p q", real=True)  # the report's names: p the angle, q its velocity
    p_dot, q_dot = sp.symbols(r"\dot{p} \dot{q}", real=True)
    hamiltonian = q**2 / 2 + 1 - sp.cos(p)
    flow = {p_dot: q, q_dot: -sp.sin(p)}
    # The report's sign convention here: p' = dH/dq, q' = -dH/dp.
    generated = sp.Matrix([hamiltonian.diff(q), -hamiltonian.diff(p)])
    chain_rule = hamiltonian.diff(p) * p_dot + hamiltonian.diff(q) * q_dot
    printed_line = p * p_dot + q_dot * sp.sin(p)
    printed_energy = p**2 / 2 + 1 - sp.cos(p)
    printed_energy_rate = printed_energy.diff(p) * q + printed_energy.diff(q) * (-sp.sin(p))
    return [
        _compare("H = q^2/2 + 1 - cos p generates (p', q') = (q, -sin p)", generated,
                 sp.Matrix([flow[p_dot], flow[q_dot]])),
        _compare("printed line p p' + q' sin p against the chain rule", chain_rule, printed_line),
        _compare("chain rule sin(p) p' + q q' along the flow, against 0",
                 chain_rule.xreplace(flow), sp.Integer(0)),
        _compare("printed line along the flow, against 0", printed_line.xreplace(flow),
                 sp.Integer(0)),
        _compare("the report's next line -q sin p + sin(p) q, against 0",
                 -q * sp.sin(p) + sp.sin(p) * q, sp.Integer(0)),
        _compare("rate of the printed energy p^2/2 + 1 - cos p along the flow, against 0",
                 printed_energy_rate, sp.Integer(0)),
    ]


@dataclass(frozen=True)
class LeapfrogLimit:
    """Leapfrog's linear stability limit and the double pendulum's fastest mode.

    Attributes
    ----------
    step_matrix : sympy.Matrix, shape (2, 2)
        One leapfrog step on ``q' = p``, ``p' = -omega^2 q`` in the variable
        ``y = h omega``, acting on ``(omega q, p)``.
    trace, determinant : sympy.Expr
        ``2 - y^2`` and ``1``: the eigenvalues are ``exp(+-i phi)`` with
        ``cos phi = 1 - y^2/2`` while ``|trace| <= 2``, i.e. ``y <= 2``.
    omega_fast : sympy.Expr
        The fast normal-mode frequency of the double pendulum with equal masses
        ``m`` and lengths ``l``: ``sqrt((2 + sqrt 2) g / l)``.
    limit : sympy.Expr
        ``2 / omega_fast`` [s], the largest stable step for small swings.
    """

    step_matrix: sp.Matrix
    trace: sp.Expr
    determinant: sp.Expr
    omega_fast: sp.Expr
    limit: sp.Expr

    def limit_value(self, length: float = 1.0, g: float = 9.81) -> float:
        """``2 / omega_fast`` [s] for arms of ``length`` [m] under gravity ``g`` [m/s^2]."""
        values = {sp.Symbol("l", positive=True): length, derive_chain(2).g: g}
        return float(self.limit.subs(values))


def leapfrog_stability_limit() -> LeapfrogLimit:
    """Section 4.6.3: the report's "small" step 0.3 s against leapfrog's stability limit.

    Leapfrog (half kick, drift, half kick) applied to the harmonic oscillator
    ``q'' = -omega^2 q`` is a linear map with determinant 1 and trace
    ``2 - (h omega)^2``; its powers stay bounded exactly when
    ``h omega < 2`` (at ``h omega = 2`` the map is a Jordan block whose powers grow
    linearly). Near the bottom, the double pendulum is two such oscillators,
    its normal modes; the fast one limits the step to ``2 / omega_fast``.

    References
    ----------
    E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
    Springer 2006, section I.5 (linear stability of the Stormer-Verlet method).

    Examples
    --------
    >>> limit = leapfrog_stability_limit()
    >>> limit.trace, limit.determinant
    (2 - y**2, 1)
    >>> round(limit.limit_value(length=1.0, g=9.81), 4)
    0.3456
    """
    y = sp.Symbol("y", positive=True)
    # State (x, v) = (omega q, p): then x' = omega v, v' = -omega x and a step of
    # size h depends on y = h omega only.
    x, v = sp.symbols("x v")
    v_half = v - y / 2 * x
    x1 = x + y * v_half
    v1 = v_half - y / 2 * x1
    matrix = sp.Matrix([x1, v1]).jacobian([x, v]).applyfunc(sp.expand)
    chain = derive_chain(2)
    mass, length = sp.symbols("m l", positive=True)
    equal = {chain.masses[0]: mass, chain.masses[1]: mass,
             chain.lengths[0]: length, chain.lengths[1]: length}
    # Eigenvalues +-i omega of the bottom equilibrium's Jacobian: the fastest mode.
    omegas = [sp.simplify(sp.im(e)) for e in chain.equilibria[0].eigenvalues(equal)]
    omega_fast = max(omegas, key=lambda w: float(w.subs({chain.g: 1, length: 1})))
    return LeapfrogLimit(
        step_matrix=matrix,
        trace=sp.expand(matrix.trace()),
        determinant=sp.expand(matrix.det()),
        omega_fast=omega_fast,
        limit=sp.simplify(2 / omega_fast),
    )
