"""Runge-Kutta methods as data: the Butcher tableau and the conditions it satisfies.

A tableau ``(A, b, c)`` defines the method; everything else about it is
derived here from the coefficients, never typed by hand: whether it is
explicit, its number of stages, its order (from the order conditions over
rooted trees), whether it is symplectic, and which of the simplifying
conditions ``B(p)``, ``C(q)``, ``D(r)`` it satisfies (collocation methods are
those with ``C(s)``).

References
----------
.. [HLW] E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*,
   2nd ed., Springer 2006: collocation and the conditions B, C, D
   (Sect. II.1.3), order conditions and rooted trees (Sect. III.1), the
   symplecticity condition (Thm VI.4.3), starting values for the stage
   iteration (Sect. VIII.6.1).
.. [B64] J. C. Butcher, "Implicit Runge-Kutta processes", Math. Comp. 18
   (1964) 50-64: ``B(p)``, ``C(q)``, ``D(r)`` with ``p <= q + r + 1`` and
   ``p <= 2q + 2`` give order ``p``.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import NamedTuple

import mpmath
import numpy as np

__all__ = ["ButcherTableau", "Condition", "gauss_legendre_tableau", "rooted_trees"]

#: Decimal digits of the exact arithmetic that builds the Gauss-Legendre tableaus.
DIGITS = 40

#: Coefficient identities are accepted up to this (the coefficients are
#: rounded to double precision; a violated condition misses by far more).
TOLERANCE = 1e-13


class Condition(NamedTuple):
    """The defect of an algebraic condition on a tableau, and whether it holds.

    Attributes
    ----------
    defect : ndarray
        Left minus right side of every equation of the condition (zero when
        it holds exactly).
    holds : bool
        ``max |defect| <= tolerance``.
    """

    defect: np.ndarray
    holds: bool

    @property
    def largest(self) -> float:
        """``max |defect|``."""
        return float(np.max(np.abs(self.defect))) if self.defect.size else 0.0


def _condition(defect, tolerance: float) -> Condition:
    defect = np.asarray(defect, dtype=float)
    return Condition(defect, bool(np.all(np.abs(defect) <= tolerance)))


@functools.cache
def rooted_trees(order: int) -> tuple:
    """All rooted trees with ``order`` vertices, each written as the sorted tuple of its subtrees.

    The single vertex is ``()``; a tree whose root has children ``t1, t2`` is
    ``(t1, t2)``. Trees of order ``k + 1`` are those of order ``k`` with one
    leaf grafted onto any vertex; sorting the children makes equal trees equal
    tuples. There are 1, 1, 2, 4, 9, 20, 48, 115, 286 trees of orders 1 to 9.

    Examples
    --------
    >>> rooted_trees(3)  # the root with two leaves; a chain of three vertices
    (((), ()), (((),),))
    """
    if order < 1:
        raise ValueError(f"`order` must be an integer >= 1, got {order}")
    if order == 1:
        return ((),)

    def grafted(tree):
        yield tuple(sorted((*tree, ())))
        for i, child in enumerate(tree):
            for bigger in grafted(child):
                yield tuple(sorted((*tree[:i], bigger, *tree[i + 1:])))

    return tuple(sorted({bigger for tree in rooted_trees(order - 1) for bigger in grafted(tree)}))


@dataclass(frozen=True, eq=False)  # compared by identity: arrays do not hash
class ButcherTableau:
    """A Runge-Kutta method as data; it checks itself on creation.

    Parameters
    ----------
    a : array_like, shape (s, s)
    b : array_like, shape (s,)
    c : array_like, shape (s,), optional
        The nodes; by default the row sums of ``a``.

    Checks: ``sum(b) == 1`` and the row sums of ``a`` equal ``c`` (to 1e-14).

    Attributes
    ----------
    stages : int
    explicit : bool
        ``a`` strictly lower triangular: each stage uses only earlier ones.
    order : int
        The largest ``p`` such that every order condition of the rooted trees
        with at most ``p`` vertices holds [HLW, Sect. III.1].

    Examples
    --------
    >>> midpoint = ButcherTableau(a=[[0.5]], b=[1.0])
    >>> midpoint.order, midpoint.explicit, midpoint.symplectic_condition().holds
    (2, False, True)
    """

    a: np.ndarray
    b: np.ndarray
    c: np.ndarray | None = None
    explicit: bool = field(init=False)
    order: int = field(init=False)

    def __post_init__(self):
        a, b = np.asarray(self.a, dtype=float), np.asarray(self.b, dtype=float)
        c = a.sum(axis=1) if self.c is None else np.asarray(self.c, dtype=float)
        s = b.size
        if b.shape != (s,) or a.shape != (s, s) or c.shape != (s,):
            raise ValueError(f"tableau shapes do not match: A {a.shape}, b {b.shape}, c {c.shape}")
        if abs(b.sum() - 1.0) > 1e-14:
            raise ValueError(f"tableau weights must sum to 1, got {b.sum()!r}")
        if np.max(np.abs(a.sum(axis=1) - c)) > 1e-14:
            raise ValueError("tableau row sums of A must equal c")
        for name, value in (("a", a), ("b", b), ("c", c)):
            value.flags.writeable = False
            object.__setattr__(self, name, value)
        object.__setattr__(self, "explicit", bool(np.all(np.triu(a) == 0)))
        object.__setattr__(self, "order", self._derived_order())

    @property
    def stages(self) -> int:
        return self.b.size

    # ---- order conditions --------------------------------------------------------
    def _stage_weights(self, tree, known: dict | None = None) -> np.ndarray:
        """The vector whose ``b``-weighted sum is the elementary weight of ``tree``.

        ``known`` remembers the subtrees already done (trees of order 12 share
        most of their subtrees; without it order 12 takes seconds).
        """
        if known is not None and tree in known:
            return known[tree]
        weights = np.ones(self.stages)
        for child in tree:
            weights = weights * (self.a @ self._stage_weights(child, known))
        if known is not None:
            known[tree] = weights
        return weights

    @functools.cached_property
    def _known_weights(self) -> dict:
        return {}

    @staticmethod
    @functools.cache
    def _density(tree) -> int:
        product = 1
        for child in tree:
            product *= ButcherTableau._density(child)
        return _size(tree) * product

    def order_condition(self, order: int, tolerance: float = TOLERANCE) -> Condition:
        """The order conditions of the trees with exactly ``order`` vertices.

        For each rooted tree ``t``: ``b . Phi(t) = 1 / gamma(t)``, with the
        elementary weight ``Phi`` and the density ``gamma`` [HLW, Sect. III.1].
        The method has order ``p`` when these hold for every order up to ``p``.
        """
        trees, known = rooted_trees(order), self._known_weights
        return _condition(
            [self.b @ self._stage_weights(t, known) - 1.0 / self._density(t) for t in trees],
            tolerance,
        )

    def _derived_order(self) -> int:
        # An s-stage method has order <= 2 s, an explicit one order <= s.
        bound = self.stages if self.explicit else 2 * self.stages
        order = self.simplified_order()
        while order < bound and self.order_condition(order + 1).holds:
            order += 1
        return order

    def simplified_order(self) -> int:
        """The order that the simplifying conditions alone guarantee [B64].

        With ``p``, ``q``, ``r`` the largest integers (at most ``2 s``) for
        which ``B(p)``, ``C(q)`` and ``D(r)`` hold, the method has order at least
        ``min(p, q + r + 1, 2 q + 2)``. The order conditions of the rooted trees
        are checked only above that: for the six-stage Gauss method they
        would be 7,813 trees up to order 12.

        Examples
        --------
        >>> gauss_legendre_tableau(2).simplified_order()  # B(4), C(2), D(2)
        4
        """
        def largest(condition) -> int:
            k = 0
            while k < 2 * self.stages and condition(k + 1).holds:
                k += 1
            return k

        p, q = largest(self.quadrature_condition), largest(self.stage_condition)
        return min(p, q + largest(self.adjoint_stage_condition) + 1, 2 * q + 2)

    # ---- structure ---------------------------------------------------------------
    def symplectic_condition(self, tolerance: float = TOLERANCE) -> Condition:
        """``m_ij = b_i a_ij + b_j a_ji - b_i b_j``, shape (s, s), and whether all vanish.

        A Runge-Kutta method whose ``m_ij`` all vanish conserves every
        quadratic invariant and is symplectic for every Hamiltonian
        [HLW, Thm VI.4.3]. The Gauss-Legendre methods satisfy it, explicit
        methods never do.

        Examples
        --------
        >>> trapezoidal = ButcherTableau(a=[[0, 0], [0.5, 0.5]], b=[0.5, 0.5])
        >>> trapezoidal.symplectic_condition().holds
        False
        """
        weighted = self.b[:, None] * self.a
        return _condition(weighted + weighted.T - np.outer(self.b, self.b), tolerance)

    def quadrature_condition(self, p: int, tolerance: float = TOLERANCE) -> Condition:
        """``B(p)``: ``sum_i b_i c_i^(k-1) = 1/k`` for ``k = 1..p``; defect shape (p,).

        The weights and nodes integrate polynomials of degree ``< p`` exactly
        [HLW, Sect. II.1.3].
        """
        k = np.arange(1, _positive("p", p) + 1)
        return _condition(self.b @ self.c[:, None] ** (k - 1) - 1.0 / k, tolerance)

    def stage_condition(self, q: int, tolerance: float = TOLERANCE) -> Condition:
        """``C(q)``: ``sum_j a_ij c_j^(k-1) = c_i^k / k`` for ``k = 1..q``; defect shape (s, q).

        Every stage integrates polynomials of degree ``< q`` exactly. An
        ``s``-stage method with distinct nodes is a collocation method exactly
        when ``C(s)`` holds, and it then has order ``p`` when ``B(p)`` holds
        [HLW, Sect. II.1.3].
        """
        k = np.arange(1, _positive("q", q) + 1)
        return _condition(self.a @ self.c[:, None] ** (k - 1) - self.c[:, None] ** k / k,
                          tolerance)

    def adjoint_stage_condition(self, r: int, tolerance: float = TOLERANCE) -> Condition:
        """``D(r)``: ``sum_i b_i c_i^(k-1) a_ij = b_j (1 - c_j^k) / k``, ``k = 1..r``; shape (s, r).

        With ``B(p)``, ``C(q)`` and ``D(r)``, ``p <= q + r + 1`` and
        ``p <= 2 q + 2``, the method has order ``p`` [B64], [HLW, Sect. II.1.3].
        The ``s``-stage Gauss methods satisfy ``B(2s)``, ``C(s)``, ``D(s)``.
        """
        k = np.arange(1, _positive("r", r) + 1)
        powers = self.c[:, None] ** (k - 1)  # (s, r): c_i^(k-1)
        left = self.a.T @ (self.b[:, None] * powers)  # (s, r): sum_i b_i c_i^(k-1) a_ij
        return _condition(left - self.b[:, None] * (1.0 - self.c[:, None] ** k) / k, tolerance)

    @functools.cached_property
    def extrapolation(self) -> np.ndarray | None:
        """``E_ij = l_j(1 + c_i)``, shape (s, s): the next step's stage slopes from this step's.

        ``l_j`` is the Lagrange polynomial of node ``j``. The polynomial of
        degree ``s - 1`` through this step's stage slopes ``K_j`` (for a
        collocation method: the derivative of the collocation polynomial),
        continued into the next step of the same size, gives the guess
        ``K_i^0 = sum_j E_ij K_j`` for its stage equations, whose error is
        ``O(h^s)`` instead of the ``O(h)`` of ``K_i^0 = f(y_n)``
        [HLW, Sect. VIII.6.1]. None when nodes coincide (no such polynomial).

        Examples
        --------
        >>> midpoint = ButcherTableau(a=[[0.5]], b=[1.0])
        >>> midpoint.extrapolation  # one stage: the constant continues
        array([[1.]])
        """
        c = self.c
        if np.unique(c).size != self.stages:
            return None
        extrapolation = np.ones((self.stages, self.stages))
        for j in range(self.stages):
            for k in range(self.stages):
                if k != j:
                    extrapolation[:, j] *= (1.0 + c - c[k]) / (c[j] - c[k])
        extrapolation.flags.writeable = False
        return extrapolation

    @property
    def symmetric(self) -> bool:
        """``b_(s+1-j) = b_j`` and ``a_(s+1-i, s+1-j) + a_ij = b_j``: the method is its own adjoint.

        Then it is time-reversible and of even order [HLW, Thm V.2.3]. The Gauss methods are,
        explicit methods are not.
        """
        flipped = self.a[::-1, ::-1]
        return bool(np.all(np.abs(self.b[::-1] - self.b) <= TOLERANCE)
                    and np.all(np.abs(flipped + self.a - self.b[None, :]) <= TOLERANCE))

    @property
    def is_collocation(self) -> bool:
        """Distinct nodes and ``C(s)``: the method is collocation at the nodes ``c``."""
        distinct = np.unique(self.c).size == self.stages
        return distinct and self.stage_condition(self.stages).holds


def _size(tree) -> int:
    return 1 + sum(_size(child) for child in tree)


def _positive(name: str, value) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"`{name}` must be an integer >= 1, got {value!r}")
    return int(value)


def gauss_legendre_tableau(stages: int) -> ButcherTableau:
    """The ``stages``-stage Gauss-Legendre collocation method (order ``2 stages``).

    The nodes ``c`` are the zeros of the Legendre polynomial of degree
    ``stages`` moved to [0, 1]; ``a_ij`` integrates the Lagrange polynomial
    of node ``j`` from 0 to ``c_i`` and ``b_j`` from 0 to 1 [HLW, Sect. II.1.3].
    Everything is computed with :data:`DIGITS` decimal digits (``mpmath``) and
    rounded once at the end: in double precision the Lagrange polynomials of
    six nodes already lose the row sums ``sum_j a_ij = c_i`` at 1e-14.

    Examples
    --------
    >>> gauss = gauss_legendre_tableau(3)
    >>> gauss.order, gauss.is_collocation, gauss.symplectic_condition().holds
    (6, True, True)
    """
    stages = _positive("stages", stages)
    with mpmath.workdps(DIGITS):
        c = [(x + 1) / 2 for x in _legendre_zeros(stages)]
        a, b = [[None] * stages for _ in range(stages)], [None] * stages
        for j in range(stages):
            # the Lagrange polynomial of node j, as coefficients of t^0, t^1, ...
            lagrange = [mpmath.mpf(1)]
            for k in range(stages):
                if k != j:
                    lagrange = _times_linear(lagrange, c[k], c[j] - c[k])
            # its integral from 0, evaluated at x
            def integral(x, coefficients=lagrange):
                return mpmath.fsum(q * x ** (m + 1) / (m + 1) for m, q in enumerate(coefficients))

            b[j] = integral(mpmath.mpf(1))
            for i in range(stages):
                a[i][j] = integral(c[i])
        return ButcherTableau(a=[[float(x) for x in row] for row in a],
                              b=[float(x) for x in b], c=[float(x) for x in c])


def _legendre_zeros(degree: int) -> list:
    """The zeros of the Legendre polynomial ``P_degree`` on [-1, 1], ascending, to full precision.

    Newton's method from Tricomi's approximation ``cos(pi (k - 1/4) / (degree + 1/2))``,
    with ``(x^2 - 1) P'_n(x) = n (x P_n(x) - P_(n-1)(x))``.
    """
    zeros = []
    for k in range(1, degree + 1):
        x = mpmath.cos(mpmath.pi * (k - mpmath.mpf(1) / 4) / (degree + mpmath.mpf(1) / 2))
        for _ in range(100):
            value = mpmath.legendre(degree, x)
            slope = degree * (x * value - mpmath.legendre(degree - 1, x)) / (x * x - 1)
            step = value / slope
            x -= step
            if abs(step) < mpmath.mpf(10) ** (-DIGITS):
                break
        zeros.append(x)
    return sorted(zeros)


def _times_linear(coefficients: list, root, scale) -> list:
    """The coefficients of ``p(t) (t - root) / scale`` from those of ``p`` (lowest first)."""
    out = [mpmath.mpf(0)] * (len(coefficients) + 1)
    for m, q in enumerate(coefficients):
        out[m + 1] += q / scale
        out[m] -= q * root / scale
    return out
