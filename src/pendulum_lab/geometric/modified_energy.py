"""The modified Hamiltonian as numbers: evaluated on states (:func:`modified_energy`,
:func:`hamiltonian_function`), and checked along computed orbits, where the error of ``H~``
truncated after ``h^k`` shrinks like the first omitted power of ``h``
(:func:`modified_energy_orders`)."""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import sympy as sp

from .. import validation as check
from ..driver.simulate import simulate
from ..integrators import get_method
from ..model.pendulum import PendulumModel
from .model_checks import conservative_model
from .modified_hamiltonians import (
    MAX_ORDER,
    STEP_SIZE,
    SYMMETRIC,
    checked_order,
    hamiltonian_method,
    modified_hamiltonian,
)

__all__ = [
    "ModifiedEnergy",
    "ModifiedEnergyOrders",
    "hamiltonian_function",
    "modified_energy",
    "modified_energy_orders",
]


@dataclass(frozen=True)
class ModifiedEnergy:
    """A truncated modified Hamiltonian of one method and model, symbolic and numeric.

    Attributes
    ----------
    expression : sympy.Expr
        ``H~ = H + h H_1 + ... + h^order H_order`` (from :func:`modified_hamiltonian`).
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

    @functools.cached_property
    def _function(self):
        return hamiltonian_function(self.model, self.expression)

    def __call__(self, theta, p, dt: float) -> np.ndarray:
        """``H~`` at step ``dt`` for states of shape ``(..., n)``; returns shape ``(...)``."""
        return self._function(theta, p, float(dt))


def modified_energy(model: PendulumModel, method, order: int) -> ModifiedEnergy:
    """:func:`modified_hamiltonian` with its terms split out, and evaluable on states.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> energy = modified_energy(pl.simple_pendulum(), "semi_implicit_euler", 1)
    >>> energy.terms[1]
    -g*p*sin(theta)/(2*l)
    >>> round(float(energy([[0.5]], [[1.0]], dt=0.1)[0]), 4)  # H - h/2 H_q H_p there
    -8.3442
    """
    expression = sp.expand(modified_hamiltonian(model, method, order))
    terms = (model.hamiltonian,) + tuple(
        expression.coeff(STEP_SIZE, j) for j in range(1, order + 1))
    return ModifiedEnergy(expression, terms, get_method(method).name, model)


def hamiltonian_function(model: PendulumModel, expr):
    """``expr`` (in the model's symbols and ``h``) as a NumPy function ``f(theta, p, h)``.

    ``theta`` and ``p`` have shape ``(..., n)``; the model's parameter values
    are put in. Lambdified once with common subexpressions shared.
    """
    chain = conservative_model(model).chain
    args = (*chain.q, *chain.p, STEP_SIZE)
    expr = sp.sympify(expr).xreplace(model.parameter_values)
    fn = sp.lambdify(args, expr, modules="numpy", cse=True)

    def evaluate(theta, p, h):
        theta, p = np.asarray(theta, float), np.asarray(p, float)
        value = fn(*np.moveaxis(theta, -1, 0), *np.moveaxis(p, -1, 0), h)
        return np.broadcast_to(value, theta.shape[:-1]).astype(float)

    return evaluate


@dataclass(frozen=True)
class ModifiedEnergyOrders:
    """Errors of truncated modified Hamiltonians along computed orbits.

    Attributes
    ----------
    method : str
    dts : ndarray, shape (m,)
    orders : tuple of int
        Truncation orders ``k`` (``0`` is ``H`` itself, the negative control).
    errors : ndarray, shape (len(orders), m)
        ``max |H~_k(y_n) - H~_k(y_0)|`` over the run.
    slopes : ndarray, shape (len(orders),)
        Least-squares slopes of ``log error`` against ``log dt``.
    expected : ndarray, shape (len(orders),)
        The first omitted power of ``h``: the method's order for ``k = 0``;
        otherwise ``k + 1``, or ``k + 2`` for a symmetric method.
    """

    method: str
    dts: np.ndarray
    orders: tuple
    errors: np.ndarray
    slopes: np.ndarray
    expected: np.ndarray


def _first_omitted_power(method_order: int, symmetric: bool, k: int) -> int:
    power = max(k + 1, method_order)
    if symmetric and power % 2:
        power += 1
    return power


def modified_energy_orders(model: PendulumModel, method, theta0, omega0, *, dts, orders,
                           t_end: float) -> ModifiedEnergyOrders:
    """Measure how the error of ``H~`` truncated after ``h^k`` shrinks with ``h``.

    Parameters
    ----------
    model : PendulumModel
    method : str or Method
        A method with a modified Hamiltonian (see :func:`modified_hamiltonian`).
    theta0, omega0 : array_like, shape (n,)
    dts : sequence of float
        Step sizes; ``t_end`` should be a multiple of each.
    orders : sequence of int
        Truncation orders ``k``, each within :func:`modified_hamiltonian`'s range.
    t_end : float

    Returns
    -------
    ModifiedEnergyOrders
    """
    model = conservative_model(model, MAX_ORDER)
    name = hamiltonian_method(model, method)
    orders = tuple(checked_order(k, MAX_ORDER[model.n], f"for n = {model.n}") for k in orders)
    if not orders:
        raise ValueError("`orders` must name at least one truncation order")
    dts = np.asarray([check.positive_number("dts", dt) for dt in dts])
    if dts.size < 2:
        raise ValueError(f"`dts` must hold at least two step sizes, got {dts.size}")
    top = modified_hamiltonian(model, name, max(orders))
    terms = [hamiltonian_function(model, top.coeff(STEP_SIZE, j) if j else model.hamiltonian)
             for j in range(max(orders) + 1)]
    errors = np.empty((len(orders), dts.size))
    for i, dt in enumerate(dts):
        run = simulate(model, theta0, omega0, t_end=t_end, dt=dt, method=get_method(method))
        values = np.cumsum([dt**j * term(run.theta, run.p, dt) for j, term in enumerate(terms)],
                           axis=0)
        for row, k in enumerate(orders):
            errors[row, i] = np.max(np.abs(values[k] - values[k][0]))
    slopes = np.array([np.polyfit(np.log(dts), np.log(e), 1)[0] for e in errors])
    order = get_method(name).order
    expected = np.array([_first_omitted_power(order, name in SYMMETRIC, k) for k in orders])
    return ModifiedEnergyOrders(name, dts, orders, errors, slopes, expected)
