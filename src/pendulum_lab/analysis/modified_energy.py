"""The modified Hamiltonian of symplectic Euler, by backward error analysis (one link).

A symplectic method's numerical solution is, up to terms beyond any chosen
order, the exact flow of a *modified* Hamiltonian
``H~ = H + h H_1 + h^2 H_2 + ...``, which it therefore conserves; ``H`` itself
only oscillates within ``O(h)`` of its start. :func:`symplectic_euler_modified_hamiltonian`
derives ``H~`` for the library's ``semi_implicit_euler`` (``p1 = p - h H_q(q, p1)``,
``q1 = q + h H_p(q, p1)``) on a one-link model:

1. expand one step of the method in powers of ``h`` (SymPy series);
2. find the modified vector field ``f~ = f + h f_2 + h^2 f_3 + ...`` whose exact
   flow, expanded the same way (Lie series), matches the step term by term;
3. integrate each correction ``f_k = (dH_k/dp, -dH_k/dq)`` back to ``H_k``, and
   check that the result generates ``f_k`` (it must: the method is symplectic).

The first correction is ``H_1 = -H_p H_q / 2`` for every ``H``.

This is a stop-gap with one method and one link, written for notebook 05; the
general ``modified_hamiltonian(model, method, order)`` of the geometric
integration notebooks is meant to replace it.

References
----------
E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
Springer 2006, sections IX.1 (modified equations) and IX.3 (Theorem IX.3.1:
symplectic methods have Hamiltonian modified equations; Example IX.3.4).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import sympy as sp

from .. import _validation as check
from ..mechanics import is_identically_zero
from ..model import PendulumModel

__all__ = ["STEP_SIZE", "ModifiedHamiltonian", "symplectic_euler_modified_hamiltonian"]

#: The step-size symbol ``h`` in every modified Hamiltonian of this module.
STEP_SIZE = sp.Symbol("h", positive=True)


@dataclass(frozen=True)
class ModifiedHamiltonian:
    """``H~ = H + h H_1 + ... + h^order H_order`` for one method and one model.

    Attributes
    ----------
    expression : sympy.Expr
        ``H~`` in the model's symbols (``theta``, ``p``, the parameters) and
        :data:`STEP_SIZE`.
    terms : tuple of sympy.Expr
        ``(H, H_1, ..., H_order)``.
    method : str
    model : PendulumModel
    """

    expression: sp.Expr
    terms: tuple
    method: str
    model: PendulumModel

    @property
    def order(self) -> int:
        """The highest power of ``h`` kept."""
        return len(self.terms) - 1

    def __call__(self, theta, p, dt: float) -> np.ndarray:
        """``H~`` at the step ``dt`` for ``theta`` and ``p``, each of shape ``(..., 1)``.

        Returns
        -------
        ndarray, shape (...)
        """
        chain = self.model.chain
        numeric = self.expression.subs(self.model.parameter_values)
        evaluate = sp.lambdify((chain.q[0], chain.p[0], STEP_SIZE), numeric, "numpy")
        theta, p = np.asarray(theta, dtype=float), np.asarray(p, dtype=float)
        return np.broadcast_to(evaluate(theta[..., 0], p[..., 0], float(dt)), theta.shape[:-1])


def _series(expr: sp.Expr, order: int) -> sp.Expr:
    """``expr`` expanded in ``h`` up to and including ``h^order``."""
    return sp.expand(sp.series(expr, STEP_SIZE, 0, order + 1).removeO())


def _flow_series(field: sp.Matrix, state: sp.Matrix, order: int) -> sp.Matrix:
    """The exact flow of ``field`` over time ``h`` as a Lie series, to ``h^order``."""
    term, total = state, state
    for k in range(1, order + 1):
        term = term.jacobian(state) * field
        total = total + STEP_SIZE**k / sp.factorial(k) * term
    return total.applyfunc(lambda e: _series(e, order))


def _symplectic_euler_series(hamiltonian: sp.Expr, q: sp.Symbol, p: sp.Symbol,
                             order: int) -> sp.Matrix:
    """One step of symplectic Euler expanded in ``h``: the implicit ``p1`` by iteration.

    Each substitution ``p1 <- p - h H_q(q, p1)`` fixes one more power of ``h``.
    """
    p1 = p
    for _ in range(order + 1):
        p1 = _series(p - STEP_SIZE * hamiltonian.diff(q).subs(p, p1), order)
    q1 = _series(q + STEP_SIZE * hamiltonian.diff(p).subs(p, p1), order)
    return sp.Matrix([q1, p1])


def _hamiltonian_of(field: sp.Matrix, q: sp.Symbol, p: sp.Symbol) -> sp.Expr:
    """``K`` with ``(dK/dp, -dK/dq) = field``, zero at ``q = p = 0``; ValueError if none exists."""
    candidate = sp.integrate(field[0], p)
    remainder = sp.simplify(-field[1] - candidate.diff(q))
    if remainder.has(p):
        raise ValueError("the correction field is not Hamiltonian: the method is not symplectic")
    candidate = sp.expand(candidate + sp.integrate(remainder, q))
    candidate -= candidate.subs({q: 0, p: 0})
    generated = sp.Matrix([candidate.diff(p), -candidate.diff(q)])
    if not all(is_identically_zero(a - b) for a, b in zip(generated, field)):
        raise ValueError("the correction field is not Hamiltonian: the method is not symplectic")
    return sp.simplify(candidate)


def symplectic_euler_modified_hamiltonian(model: PendulumModel,
                                          order: int = 1) -> ModifiedHamiltonian:
    """The modified Hamiltonian of ``semi_implicit_euler`` on a one-link model, to ``h^order``.

    Backward error analysis (see the module docstring): the step's Taylor
    expansion is matched, power by power of ``h``, with the Lie series of a
    modified vector field, and each correction is integrated to a Hamiltonian.

    Parameters
    ----------
    model : PendulumModel
        A simple pendulum (``model.n == 1``).
    order : {1, 2}
        Highest power of ``h`` kept.

    Returns
    -------
    ModifiedHamiltonian
        ``H_1 = -H_p H_q / 2`` and
        ``H_2 = (H_pp H_q^2 + H_qq H_p^2 + 4 H_pq H_p H_q) / 12`` (up to a constant).

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> sp_ = pl.simple_pendulum()
    >>> modified = symplectic_euler_modified_hamiltonian(sp_)
    >>> modified.terms[1]
    -g*p*sin(theta)/(2*l)
    >>> round(float(modified([[0.5]], [[1.0]], dt=0.1)[0]), 4)  # H - h/2 H_q H_p there
    -8.3442
    """
    check.pendulum_model(model)
    if model.n != 1:
        raise ValueError(
            f"`model` must have one link for this derivation, got n = {model.n}; "
            "the double pendulum needs the general modified_hamiltonian"
        )
    order = check.integer_at_least("order", order, 1)
    if order > 2:
        raise ValueError(f"`order` must be 1 or 2, got {order}")
    chain = model.chain
    q, p = chain.q[0], chain.p[0]
    hamiltonian = chain.hamiltonian
    state = sp.Matrix([q, p])
    step = _symplectic_euler_series(hamiltonian, q, p, order + 1)
    terms, modified = [hamiltonian], hamiltonian
    for k in range(1, order + 1):
        field = sp.Matrix([modified.diff(p), -modified.diff(q)])
        mismatch = (step - _flow_series(field, state, k + 1)).applyfunc(sp.expand)
        correction = mismatch.applyfunc(
            lambda e, power=k + 1: sp.simplify(e.coeff(STEP_SIZE, power)))
        terms.append(_hamiltonian_of(correction, q, p))
        modified = modified + STEP_SIZE**k * terms[-1]
    return ModifiedHamiltonian(modified, tuple(terms), "semi_implicit_euler", model)
