"""Composition methods as data: weights applied to a base method, checked on creation.

A composition method takes the step ``h`` as several steps of a base method, of sizes
``w_1 h, w_2 h, ..., w_s h``, one after another [HLW, Sect. II.4]. The base is either

* the leapfrog (Stormer-Verlet, symmetric, order 2): ``w_i`` is the weight of the ``i``-th
  leapfrog step [Y90]; or
* symplectic Euler ``Phi`` and its adjoint ``Phi*`` (the drift first) taken in turn, ``w_i`` the
  weight of the ``i``-th of them [HLW, Sect. II.5, III.5]. For a separable ``H`` these are the
  splitting methods that alternate kicks and drifts; the leapfrog is ``Phi*`` after ``Phi``,
  each for ``h/2``.

Both bases are symplectic for any ``H`` (in ``(q, p)``), so every composition is. What else the
method is follows from its weights, and :class:`Composition` checks the declared values on
creation: the weights sum to one; a method declared symmetric reads the same backwards (with
``Phi`` and ``Phi*`` swapped); and the declared order is the order the weights give. The order
is found by composing generic maps ``exp(sum_k (w h)^k F_k)``: the base method's
modified vector field [HLW, Sect. IX.1] with random matrices ``F_k`` (``F_1`` the exact field;
odd ``k`` only for the symmetric leapfrog; ``(-1)^(k+1) F_k`` for the adjoint), as truncated
power series in ``h``. The method has order ``p`` when the product agrees with the exact flow
``exp(h F_1)`` in every power up to ``h^p``. These are the order conditions of compositions
[HLW, Sect. III.5]: random matrices of this size satisfy no polynomial identity of the degrees
involved, so a power that agrees for them agrees for every field.

The compiled step is :func:`~pendulum_lab.integrators.symplectic.composition_step`, the
reference step :func:`~pendulum_lab.integrators.reference.composition`.

References
----------
.. [HLW] E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
   Springer 2006: composition methods (Sect. II.4, V.3), splitting methods as compositions of
   symplectic Euler and its adjoint (Sect. II.5, III.5), modified equations (Sect. IX.1).
.. [Y90] H. Yoshida, "Construction of higher order symplectic integrators", Phys. Lett. A 150
   (1990) 262-268.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["ADJOINT", "BASES", "EULER", "LEAPFROG", "SUBSTEP_NAMES", "Composition"]

#: The kinds of substep, as the compiled step reads them.
LEAPFROG, EULER, ADJOINT = 0, 1, 2
SUBSTEP_NAMES = {LEAPFROG: "leapfrog", EULER: "symplectic_euler",
                 ADJOINT: "adjoint_symplectic_euler"}
#: The base methods a composition may be declared with.
BASES = ("leapfrog", "symplectic_euler")

#: The weights must sum to one to this, and a symmetric sequence read backwards match to this.
WEIGHT_TOLERANCE = 1e-14
#: A power of ``h`` agrees with the exact flow when its coefficients do to this, relative to
#: ``(sum |w_i|)^k``, the size of the coefficients of ``h^k`` (published weights of 15 digits
#: leave defects near 1e-15; the first unmet condition of a registered method misses by
#: 2.6e-6 or more, the least being ``yoshida6``'s).
ORDER_TOLERANCE = 1e-11
#: Size and seed of the random matrices that stand for the modified vector fields.
GENERIC_SIZE, GENERIC_SEED = 6, 20260


@dataclass(frozen=True, eq=False)  # compared by identity, as tableaus are
class Composition:
    """A composition method as data; it checks itself on creation.

    Parameters
    ----------
    weights : sequence of float
        The step sizes of the substeps, in units of ``h``, in the order they are taken.
    order : int
        The declared order; creation fails unless the weights give exactly this order.
    base : {"leapfrog", "symplectic_euler"}
        ``"symplectic_euler"``: the substeps alternate symplectic Euler and its adjoint.
    symmetric : bool
        Declared symmetric (then its order is even and it is time-reversible); checked.
    adjoint_first : bool
        With ``base="symplectic_euler"``: the first substep is the adjoint (the drift first).
    source : str
        Where the weights come from: authors, journal, year.

    Attributes
    ----------
    substeps : tuple of (int, float)
        ``(kind, weight)`` for each substep: :data:`LEAPFROG`, :data:`EULER` or :data:`ADJOINT`.

    Examples
    --------
    >>> jump = 2 ** (1 / 3)
    >>> triple = Composition([1 / (2 - jump), -jump / (2 - jump), 1 / (2 - jump)], order=4)
    >>> triple.stages, triple.conditions_order()
    (3, 4)
    """

    weights: tuple
    order: int
    base: str = "leapfrog"
    symmetric: bool = True
    adjoint_first: bool = False
    source: str = ""
    substeps: tuple = field(init=False, repr=False)

    def __post_init__(self):
        weights = tuple(float(w) for w in np.asarray(self.weights, dtype=float).ravel())
        object.__setattr__(self, "weights", weights)
        if self.base not in BASES:
            raise ValueError(f"`base` must be one of {BASES}, got {self.base!r}")
        if isinstance(self.order, bool) or not isinstance(self.order, (int, np.integer)) \
                or self.order < 1:
            raise ValueError(f"`order` must be an integer >= 1, got {self.order!r}")
        if not weights or not all(np.isfinite(weights)):
            raise ValueError(f"`weights` must be finite numbers, at least one, got {weights}")
        if abs(sum(weights) - 1.0) > WEIGHT_TOLERANCE:
            raise ValueError(f"`weights` must sum to 1, got {sum(weights)!r}")
        if self.base == "leapfrog":
            kinds = [LEAPFROG] * len(weights)
        else:
            pair = (ADJOINT, EULER) if self.adjoint_first else (EULER, ADJOINT)
            kinds = [pair[i % 2] for i in range(len(weights))]
        object.__setattr__(self, "substeps", tuple(zip(kinds, weights)))
        if self.symmetric and not self.reads_the_same_backwards():
            raise ValueError("the composition is declared symmetric, but its substeps read "
                             "backwards (adjoints swapped) are another sequence")
        found = self.conditions_order(self.order + 1)
        if found < self.order:
            raise ValueError(f"the composition is declared of order {self.order}, but its "
                             f"weights give order {found} (the order conditions of order "
                             f"{found + 1} fail)")
        if found > self.order:
            raise ValueError(f"the composition is declared of order {self.order}, but its "
                             f"weights give order at least {found} (the order conditions of "
                             f"order {found} hold too)")

    @property
    def stages(self) -> int:
        """The number of substeps."""
        return len(self.weights)

    def reads_the_same_backwards(self) -> bool:
        """The adjoint composition (substeps reversed, each replaced by its adjoint) is this one.

        Then the method is symmetric [HLW, Sect. II.4, V.3.1].
        """
        swapped = {LEAPFROG: LEAPFROG, EULER: ADJOINT, ADJOINT: EULER}
        backwards = [(swapped[kind], w) for kind, w in reversed(self.substeps)]
        return all(kind == other and abs(w - v) <= WEIGHT_TOLERANCE
                   for (kind, w), (other, v) in zip(self.substeps, backwards))

    def order_defects(self, highest: int) -> np.ndarray:
        """For ``k = 1..highest``: how far the coefficient of ``h^k`` misses the exact flow's.

        Each defect is the largest entry of the difference of the two ``h^k`` coefficients,
        divided by ``(sum |w_i|)^k`` (see the module docstring for the generic maps).
        """
        rng = np.random.default_rng(GENERIC_SEED)
        fields = [np.zeros((GENERIC_SIZE, GENERIC_SIZE))]  # F_0 = 0: the series start at h^1
        for _ in range(highest):
            matrix = rng.standard_normal((GENERIC_SIZE, GENERIC_SIZE))
            fields.append(matrix / np.linalg.norm(matrix, 2))
        fields = np.array(fields)
        powers = np.arange(highest + 1)
        exact = np.zeros_like(fields)
        exact[1] = fields[1]
        product = _series_exp(exact * 0.0)  # the identity
        for kind, w in self.substeps:
            signs = np.ones(highest + 1)
            if kind == LEAPFROG:
                signs[powers % 2 == 0] = 0.0  # a symmetric base: odd powers only
            elif kind == ADJOINT:
                signs = (-1.0) ** (powers + 1)  # the adjoint's modified field
            signs[1] = 1.0
            substep = _series_exp(fields * (signs * w ** powers)[:, None, None])
            product = _series_product(substep, product)  # applied after the ones before
        size = sum(abs(w) for w in self.weights)
        difference = np.abs(product - _series_exp(exact)).max(axis=(1, 2))
        return difference[1:] / size ** powers[1:]

    def conditions_order(self, highest: int | None = None) -> int:
        """The largest ``p <= highest`` whose order conditions all hold (default: declared + 1)."""
        highest = self.order + 1 if highest is None else highest
        defects = self.order_defects(highest)
        met = defects <= ORDER_TOLERANCE
        return highest if met.all() else int(np.argmin(met))

    def describe(self) -> list[str]:
        """One line per substep, as :func:`~pendulum_lab.integrators.source.method_source` shows."""
        return [f"{i}. {SUBSTEP_NAMES[kind]} with step {w!r} h"
                for i, (kind, w) in enumerate(self.substeps, start=1)]


def _series_product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The product of two power series in ``h`` with matrix coefficients, truncated."""
    out = np.zeros_like(a)
    for k in range(a.shape[0]):
        for i in range(k + 1):
            out[k] += a[i] @ b[k - i]
    return out


def _series_exp(x: np.ndarray) -> np.ndarray:
    """``exp`` of a power series in ``h`` without constant term, truncated at its length."""
    result = np.zeros_like(x)
    result[0] = np.eye(x.shape[1])
    term = result.copy()
    for m in range(1, x.shape[0]):
        term = _series_product(term, x) / m
        result = result + term
    return result
