"""Modified equations by matching Taylor expansions in the step size (SymPy only).

A one-step method with step ``h`` maps ``y = (q, p)`` to

    Phi_h(y) = y + h d_1(y) + h^2 d_2(y) + h^3 d_3(y) + ...

Backward error analysis looks for the modified vector field
``f~ = f_1 + h f_2 + h^2 f_3 + ...`` whose *exact* flow has the same
expansion. The exact flow of ``f~`` is the Lie series
``sum_k h^k / k! L^k(y)`` with ``L g = g' f~``, so the coefficient of ``h^N``
is ``f_N`` plus terms built from ``f_1, ..., f_{N-1}`` only:

    f_N = d_N - sum over compositions N = j_1 + ... + j_k, k >= 2, of
          (1 / k!) L_{j_1} L_{j_2} ... L_{j_{k-1}} f_{j_k},

with ``L_j g = g' f_j`` [HLW, Sect. IX.1]. That recursion is :func:`modified_fields`.

The expansion ``d_N`` of a method comes from its defining equations, solved as
power series in ``h``: every implicit equation ``x = x0 + h G(x)`` is iterated
once per power of ``h`` (each sweep fixes one more coefficient), and a function
evaluated at a shifted point ``E(y + Delta)`` is expanded by Taylor's formula
(:func:`step_series`).

For a symplectic method each ``f_{j+1}`` is a Hamiltonian vector field
``(dH_j/dp, -dH_j/dq)``. :func:`hamiltonian_of_field` finds ``H_j`` as a
combination of *elementary Hamiltonians*, products of partial derivatives of
``H`` contracted along a tree (one node per factor, each edge pairing a
``q``-derivative at one end with a ``p``-derivative at the other; HLW,
Sect. IX.10), by matching coefficients exactly. When no combination fits, the
field is not Hamiltonian and it says so.

Everything here works on any Hamiltonian expression: an undefined SymPy
function ``H(q, p)`` gives the general formulas (such as HLW's
``H~ = H - h/2 H_p H_q + ...`` for symplectic Euler), a concrete one the
pendulum's.

References
----------
.. [HLW] E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*,
   2nd ed., Springer 2006: Chapter IX (backward error analysis), Sect. IX.3
   (modified Hamiltonians of symplectic Euler and Stormer-Verlet), IX.9-IX.10
   (P-series, elementary Hamiltonians).
"""

from __future__ import annotations

import functools
import itertools
import math

import sympy as sp

from .. import validation as check

__all__ = [
    "SERIES_METHODS",
    "STEP_SIZE",
    "elementary_hamiltonians",
    "hamiltonian_of_field",
    "modified_fields",
    "step_series",
]

#: The step-size symbol ``h`` of every expansion here.
STEP_SIZE = sp.Symbol("h", positive=True)

_ZERO = sp.Integer(0)


# --------------------------------------------------------------------------- truncated series
# A series is a list [c_0, c_1, ..., c_N] of h-free expressions, meaning sum_k c_k h^k.
def _constant(value, order: int) -> list:
    return [sp.sympify(value)] + [_ZERO] * order


def _add(*series) -> list:
    return [sp.Add(*terms) for terms in zip(*series)]


def _times_h(series, factor) -> list:
    """``factor * h * series``, truncated."""
    return [_ZERO] + [sp.expand(factor * c) for c in series[:-1]]


def _product(a, b) -> list:
    order = len(a) - 1
    out = [[] for _ in range(order + 1)]
    for i, ai in enumerate(a):
        if ai == 0:
            continue
        for j in range(order + 1 - i):
            if b[j] != 0:
                out[i + j].append(ai * b[j])
    return [sp.expand(sp.Add(*terms)) for terms in out]


def _shifted(expr, variables, displacement, order: int) -> list:
    """Series of ``expr(y + displacement)`` by Taylor's formula.

    ``displacement`` holds one series per variable, each without constant
    term (it is ``O(h)``), so derivatives beyond ``order`` do not contribute.
    """
    active = [i for i, d in enumerate(displacement) if any(c != 0 for c in d)]
    powers = {}
    for i in active:
        table = [_constant(1, order)]
        for _ in range(order):
            table.append(_product(table[-1], displacement[i]))
        powers[i] = table
    out = [[] for _ in range(order + 1)]
    for alpha in itertools.product(range(order + 1), repeat=len(active)):
        if sum(alpha) > order:
            continue
        derivative = expr
        for i, a in zip(active, alpha):
            if a:
                derivative = sp.diff(derivative, variables[i], a)
        if derivative == 0:
            continue
        weight = derivative / math.prod(math.factorial(a) for a in alpha)
        monomial = _constant(1, order)
        for i, a in zip(active, alpha):
            if a:
                monomial = _product(monomial, powers[i][a])
        for k, c in enumerate(monomial):
            if c != 0:
                out[k].append(weight * c)
    return [sp.expand(sp.Add(*terms)) for terms in out]


def _difference(series, value) -> list:
    """``series - value`` for ``value`` its constant term: the displacement, ``O(h)``."""
    return [_ZERO, *series[1:]]


# --------------------------------------------------------------------------- the methods
def _cut(series, order: int) -> list:
    """``series`` truncated (or padded with zeros) to powers ``h^0 .. h^order``."""
    return list(series[: order + 1]) + [_ZERO] * (order + 1 - len(series))


class _Problem:
    """A Hamiltonian ``H(q, p)`` and its partial derivatives, for one expansion.

    The implicit equations are solved by sweeps that each fix one more power
    of ``h``; sweep ``k`` works with series truncated after ``h^k``, which
    keeps the early sweeps cheap.
    """

    def __init__(self, hamiltonian, q, p, order):
        self.q, self.p, self.n, self.order = list(q), list(p), len(q), order
        self.variables = self.q + self.p
        self.h_q = [sp.diff(hamiltonian, x) for x in self.q]
        self.h_p = [sp.diff(hamiltonian, x) for x in self.p]
        self.field = self.h_p + [-e for e in self.h_q]

    def at(self, exprs, q_series, p_series) -> list:
        """``exprs`` at the point given as series ``(q_series, p_series)``, to their order."""
        order = len(q_series[0]) - 1
        displacement = [_difference(s, y) for s, y in zip(q_series + p_series, self.variables)]
        return [_shifted(e, self.variables, displacement, order) for e in exprs]

    def constants(self, values, order: int | None = None) -> list:
        return [_constant(v, self.order if order is None else order) for v in values]


def _semi_implicit_euler(problem: _Problem):
    """``p1 = p - h H_q(q, p1)``;  ``q1 = q + h H_p(q, p1)`` [HLW, Thm VI.3.3]."""
    p1 = [[x] for x in problem.p]
    for k in range(1, problem.order + 1):
        q, p = problem.constants(problem.q, k), problem.constants(problem.p, k)
        force = problem.at(problem.h_q, q, [_cut(s, k) for s in p1])
        p1 = [_add(pi, _times_h(g, -1)) for pi, g in zip(p, force)]
    q = problem.constants(problem.q)
    return [_add(qi, _times_h(g, 1)) for qi, g in zip(q, problem.at(problem.h_p, q, p1))], p1


def _leapfrog(problem: _Problem):
    """Generalized Stormer-Verlet [HLW, eq. VI.3.4], kick-drift-kick."""
    half = sp.Rational(1, 2)
    p_half = [[x] for x in problem.p]
    for k in range(1, problem.order + 1):
        q, p = problem.constants(problem.q, k), problem.constants(problem.p, k)
        force = problem.at(problem.h_q, q, [_cut(s, k) for s in p_half])
        p_half = [_add(pi, _times_h(g, -half)) for pi, g in zip(p, force)]
    q = problem.constants(problem.q)
    drift = [_add(qi, _times_h(g, half)) for qi, g in zip(q, problem.at(problem.h_p, q, p_half))]
    q1 = [[x] for x in problem.q]
    for k in range(1, problem.order + 1):
        velocity = problem.at(problem.h_p, [_cut(s, k) for s in q1],
                              [_cut(s, k) for s in p_half])
        q1 = [_add(_cut(d, k), _times_h(g, half)) for d, g in zip(drift, velocity)]
    force = problem.at(problem.h_q, q1, p_half)
    return q1, [_add(pi, _times_h(g, -half)) for pi, g in zip(p_half, force)]


def _runge_kutta(a, b):
    """The Runge-Kutta method with exact tableau ``(a, b)``, explicit or implicit."""

    def method(problem: _Problem):
        stages, dim, n = len(b), 2 * problem.n, problem.n
        slopes = [[[f] for f in problem.field] for _ in range(stages)]
        # Sweep k fixes the coefficient of h^k in every stage (explicit or not).
        for k in range(1, problem.order + 1):
            y = problem.constants(problem.variables, k)
            old = [[_cut(s, k) for s in stage] for stage in slopes]
            slopes = []
            for i in range(stages):
                point = [_add(y[m], *[_times_h(old[j][m], a[i][j])
                                      for j in range(stages) if a[i][j] != 0])
                         for m in range(dim)]
                slopes.append(problem.at(problem.field, point[:n], point[n:]))
        y = problem.constants(problem.variables)
        slopes = [[_cut(s, problem.order) for s in stage] for stage in slopes]
        y1 = [_add(y[m], *[_times_h(slopes[i][m], b[i]) for i in range(stages)])
              for m in range(dim)]
        return y1[:n], y1[n:]

    return method


def _gauss_tableau(stages: int):
    """Exact Gauss-Legendre collocation tableau (nodes: zeros of the shifted Legendre
    polynomial; ``a_ij`` and ``b_j`` integrate the Lagrange polynomials) [HLW, II.1.3]."""
    t = sp.Symbol("t")
    nodes = sorted(sp.solve(sp.legendre(stages, 2 * t - 1), t), key=lambda c: float(c))
    a, b = [[None] * stages for _ in range(stages)], [None] * stages
    for j in range(stages):
        basis = sp.Mul(*[(t - c) / (nodes[j] - c) for k, c in enumerate(nodes) if k != j])
        for i in range(stages):
            a[i][j] = sp.nsimplify(sp.simplify(sp.integrate(basis, (t, 0, nodes[i]))))
        b[j] = sp.nsimplify(sp.simplify(sp.integrate(basis, (t, 0, 1))))
    return a, b


_R = sp.Rational
#: Methods whose one-step map :func:`step_series` can expand, by registry name.
#: Each is a function of a ``_Problem`` returning the series of ``(q1, p1)``.
SERIES_METHODS = {
    "explicit_euler": _runge_kutta([[0]], [1]),
    "semi_implicit_euler": _semi_implicit_euler,
    "leapfrog": _leapfrog,
    "rk4": _runge_kutta(
        [[0, 0, 0, 0], [_R(1, 2), 0, 0, 0], [0, _R(1, 2), 0, 0], [0, 0, 1, 0]],
        [_R(1, 6), _R(1, 3), _R(1, 3), _R(1, 6)],
    ),
    "glrk4": _runge_kutta(*_gauss_tableau(2)),
}


def _check_method_name(method: str) -> str:
    if method not in SERIES_METHODS:
        raise ValueError(f"`method` must be one of {list(SERIES_METHODS)}, got {method!r}")
    return method


def step_series(method: str, hamiltonian, q, p, order: int) -> list[list]:
    """Taylor coefficients in ``h`` of one step of ``method`` for Hamilton's equations of ``H``.

    Parameters
    ----------
    method : str
        A key of :data:`SERIES_METHODS`.
    hamiltonian : sympy.Expr
        ``H(q, p)``, concrete or built from undefined functions.
    q, p : sequence of sympy.Symbol, length n
    order : int
        Highest power of ``h`` kept, ``>= 1``.

    Returns
    -------
    list of 2n lists of ``order + 1`` expressions
        ``series[m][k]`` is the coefficient of ``h^k`` in component ``m`` of
        ``Phi_h(q, p)`` (``q`` components first).

    Examples
    --------
    >>> x, v = sp.symbols("x v")
    >>> step_series("leapfrog", (x**2 + v**2) / 2, [x], [v], 2)[0]
    [x, v, -x/2]
    """
    method = _check_method_name(method)
    order = check.integer_at_least("order", order, 1)
    if len(q) != len(p) or not q:
        raise ValueError(f"`q` and `p` must be sequences of the same length >= 1, got "
                         f"{len(q)} and {len(p)}")
    problem = _Problem(hamiltonian, q, p, order)
    q1, p1 = SERIES_METHODS[method](problem)
    return [[sp.expand(c) for c in s] for s in q1 + p1]


def _compositions(total: int):
    """Ordered tuples of positive integers summing to ``total``."""
    if total == 0:
        yield ()
        return
    for first in range(1, total + 1):
        for rest in _compositions(total - first):
            yield (first, *rest)


def modified_fields(series, variables) -> list[list]:
    """The modified vector field ``f_1, f_2, ...`` of a method from its step's Taylor series.

    Parameters
    ----------
    series : list of lists
        As returned by :func:`step_series` (``series[m][k]``).
    variables : sequence of sympy.Symbol
        ``(q_1, ..., q_n, p_1, ..., p_n)``, in the order of ``series``.

    Returns
    -------
    list
        ``fields[j - 1]`` is ``f_j`` (a list of ``2n`` expressions), for
        ``j = 1 .. order``: the modified equation is
        ``y' = f_1 + h f_2 + h^2 f_3 + ...``.

    Examples
    --------
    >>> x, v = sp.symbols("x v")
    >>> s = step_series("explicit_euler", (x**2 + v**2) / 2, [x], [v], 2)
    >>> modified_fields(s, [x, v])[1]      # explicit Euler: f_2 = -f'f/2
    [x/2, v/2]
    """
    variables = list(variables)
    order = len(series[0]) - 1
    fields = [[component[1] for component in series]]

    def lie(g, f):
        return [sp.expand(sp.Add(*[sp.diff(gi, y) * fy for y, fy in zip(variables, f)]))
                for gi in g]

    def word(w, memo):
        """``L_{w_0} L_{w_1} ... f_{w_last}``, memoised on suffixes."""
        if w not in memo:
            memo[w] = (fields[w[0] - 1] if len(w) == 1
                       else lie(word(w[1:], memo), fields[w[0] - 1]))
        return memo[w]

    for total in range(2, order + 1):
        memo, flow = {}, [[] for _ in variables]
        for composition in _compositions(total):
            if len(composition) < 2:
                continue
            weight = sp.Rational(1, math.factorial(len(composition)))
            for m, value in enumerate(word(composition, memo)):
                flow[m].append(weight * value)
        fields.append([sp.expand(component[total] - sp.Add(*terms))
                       for component, terms in zip(series, flow)])
    return fields


# ------------------------------------------------------------------------- elementary Hamiltonians
def _labelled_trees(nodes: int):
    """Edge lists of all labelled trees on ``nodes`` vertices (Pruefer sequences)."""
    if nodes == 1:
        yield []
        return
    for code in itertools.product(range(nodes), repeat=nodes - 2):
        degree = [1] * nodes
        for x in code:
            degree[x] += 1
        edges = []
        for x in code:
            leaf = min(i for i in range(nodes) if degree[i] == 1)
            edges.append((leaf, x))
            degree[leaf] -= 1
            degree[x] -= 1
        edges.append(tuple(i for i in range(nodes) if degree[i] == 1))
        yield edges


def elementary_hamiltonians(hamiltonian, q, p, nodes: int) -> list:
    """All distinct elementary Hamiltonians with ``nodes`` factors of ``H``.

    A tree on ``nodes`` vertices with an orientation of each edge gives the
    product over vertices of partial derivatives of ``H``: each edge
    differentiates one end by ``q_i`` and the other by ``p_i``, summed over
    ``i = 1..n``. With one node this is ``H``, with two ``sum_i H_{p_i} H_{q_i}``,
    with three ``H_pp(H_q, H_q)``, ``H_qq(H_p, H_p)`` and ``H_qp(H_p, H_q)``.
    Modified Hamiltonians of symplectic (partitioned) Runge-Kutta methods are
    combinations of them [HLW, Sect. IX.10].

    Returns
    -------
    list of sympy.Expr
        Expanded, without zeros or repeats.
    """
    nodes = check.integer_at_least("nodes", nodes, 1)
    n = len(q)
    found, seen = {}, set()
    for edges in _labelled_trees(nodes):
        for orientation in itertools.product((False, True), repeat=len(edges)):
            if n == 1:
                # With one degree of freedom the product depends only on how many q- and
                # p-derivatives each node carries: skip trees that repeat such a multiset.
                signature = [[0, 0] for _ in range(nodes)]
                for (a, b), flip in zip(edges, orientation):
                    signature[b if flip else a][0] += 1
                    signature[a if flip else b][1] += 1
                key = tuple(sorted(map(tuple, signature)))
                if key in seen:
                    continue
                seen.add(key)
            total = []
            for index in itertools.product(range(n), repeat=len(edges)):
                factors = [hamiltonian] * nodes
                for (a, b), flip, i in zip(edges, orientation, index):
                    q_end, p_end = (b, a) if flip else (a, b)
                    factors[q_end] = sp.diff(factors[q_end], q[i])
                    factors[p_end] = sp.diff(factors[p_end], p[i])
                total.append(sp.Mul(*factors))
            expr = sp.expand(sp.Add(*total))
            if expr != 0:
                found.setdefault(expr, None)
    return list(found)


def _coefficients(expr) -> list:
    """Coefficients of ``expr`` as a polynomial in the derivatives of the undefined functions.

    Each derivative (and each undefined function) is replaced by a plain
    symbol first; whatever else is left (the unknown weights) ends up in the
    coefficients.
    """
    atoms = sorted(expr.atoms(sp.Derivative), key=sp.default_sort_key)
    atoms += sorted(expr.atoms(sp.core.function.AppliedUndef), key=sp.default_sort_key)
    if not atoms:
        return [expr]
    stand_ins = [sp.Dummy() for _ in atoms]
    return sp.Poly(expr.xreplace(dict(zip(atoms, stand_ins))), *stand_ins).coeffs()


def hamiltonian_of_field(field, hamiltonian, q, p, nodes: int):
    """``K`` with ``(dK/dp, -dK/dq) = field``, as a combination of elementary Hamiltonians.

    Parameters
    ----------
    field : sequence of 2n sympy.Expr
        A term ``f_j`` of a modified vector field, ``q`` components first.
    hamiltonian : sympy.Expr
        ``H(q, p)``; best an undefined function (or ``T(p) + U(q)``), so that
        matching coefficients is exact polynomial algebra.
    q, p : sequence of sympy.Symbol
    nodes : int
        Factors of ``H`` in each term: ``j`` for ``f_j``.

    Returns
    -------
    sympy.Expr
        ``K``, expanded (zero if the field is zero).

    Raises
    ------
    ValueError
        If no combination reproduces ``field``: it is not a Hamiltonian
        vector field (the method is not symplectic at this order).
    """
    nodes = check.integer_at_least("nodes", nodes, 1)
    if len(field) != len(q) + len(p):
        raise ValueError(f"`field` must have 2n = {len(q) + len(p)} components, got {len(field)}")
    if all(sp.expand(c) == 0 for c in field):
        return _ZERO
    candidates = elementary_hamiltonians(hamiltonian, q, p, nodes)
    unknowns = sp.symbols(f"c0:{len(candidates)}")
    ansatz = sp.Add(*[c * e for c, e in zip(unknowns, candidates)])
    hamilton = [sp.diff(ansatz, x) for x in p] + [-sp.diff(ansatz, x) for x in q]
    equations = []
    for lhs, rhs in zip(hamilton, field):
        equations += _coefficients(sp.expand(lhs - rhs))
    solutions = sp.linsolve(equations, unknowns)
    if solutions == sp.EmptySet:
        raise ValueError(
            f"the modified vector field at order h^{nodes - 1} is not Hamiltonian: no "
            f"combination of the {len(candidates)} elementary Hamiltonians with {nodes} "
            "factors reproduces it (the method is not symplectic)"
        )
    (solution,) = solutions
    free = {u: 0 for u in unknowns}  # any member of the family: they give the same K
    return sp.expand(ansatz.xreplace({u: s.xreplace(free) for u, s in zip(unknowns, solution)}))


@functools.cache
def abstract_problem(n: int, separable: bool):
    """Symbols and an undefined Hamiltonian for ``n`` degrees of freedom.

    Returns ``(q, p, H)`` with ``H = H(q, p)``, or ``T(p) + U(q)`` when
    ``separable``.
    """
    n = check.integer_at_least("n", n, 1)
    q = sp.symbols(f"q1:{n + 1}") if n > 1 else (sp.Symbol("q"),)
    p = sp.symbols(f"p1:{n + 1}") if n > 1 else (sp.Symbol("p"),)
    if separable:
        return q, p, sp.Function("T")(*p) + sp.Function("U")(*q)
    return q, p, sp.Function("H")(*q, *p)
