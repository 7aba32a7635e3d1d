"""Backward error analysis of the course's integrators on the pendulum.

A symplectic method is, up to terms smaller than any power of ``h``, the
exact flow of a *modified Hamiltonian* ``H~ = H + h H_1 + h^2 H_2 + ...``
[HLW, Chapter IX]. :func:`modified_hamiltonian` derives it symbolically (see
:mod:`pendulum_lab.geometric.modified_equations` for the method: matching
Taylor expansions, not the BCH formula, which applies only to splittings of a
separable ``H``). The rest of this module checks the theory with numbers:

* :func:`modified_energy_orders`: along a computed orbit the error of
  ``H~`` truncated after ``h^k`` shrinks like the first omitted power of ``h``;
* :func:`hamiltonian_fit`: the attempt, term by term, to write a method's
  modified vector field (for a general ``H``) as a Hamiltonian one; it fails
  for explicit Euler and RK4, and succeeds for the symplectic methods;
* :func:`first_dissipative_term`, :func:`mean_energy_rate` and
  :func:`energy_drift`: RK4 has a modified *equation* but no modified
  Hamiltonian; its first term with non-zero divergence predicts its energy
  drift rate;
* the growth of the global error over long times is measured in
  :mod:`pendulum_lab.geometric.long_time`.

The derivations (:func:`modified_hamiltonian`, :func:`modified_equation`,
:func:`hamiltonian_fit`) live in :mod:`pendulum_lab.geometric.modified_hamiltonians`; their
names are importable from here too, as the notebooks use them.

References
----------
.. [HLW] E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*,
   2nd ed., Springer 2006: Chapter IX (backward error analysis), Sect. X.3
   (linear error growth of symplectic methods on integrable systems).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import sympy as sp

from .. import validation as check
from ..analysis import exact_period
from ..driver.simulate import simulate
from ..integrators import get_method
from ..model.pendulum import PendulumModel
from ..symbolic.mechanics import is_identically_zero
from .long_time import exact_libration
from .model_checks import conservative_model
from .modified_hamiltonians import (
    MAX_FIELD_ORDER,
    MAX_ORDER,
    STEP_SIZE,
    SYMMETRIC,
    HamiltonianFit,
    checked_order,
    generic_modified_hamiltonian,
    hamiltonian_fit,
    hamiltonian_method,
    modified_equation,
    modified_hamiltonian,
)

__all__ = [
    "STEP_SIZE",
    "DissipativeTerm",
    "EnergyDrift",
    "HamiltonianFit",
    "ModifiedEnergy",
    "ModifiedEnergyOrders",
    "energy_drift",
    "first_dissipative_term",
    "generic_modified_hamiltonian",
    "hamiltonian_fit",
    "hamiltonian_function",
    "mean_energy_rate",
    "modified_energy",
    "modified_energy_orders",
    "modified_equation",
    "modified_hamiltonian",
]


# --------------------------------------------------------------------------- numbers
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


# --------------------------------------------------------------------------- RK4's energy drift
@dataclass(frozen=True)
class DissipativeTerm:
    """The first term of a modified equation whose divergence is not identically zero.

    Attributes
    ----------
    power : int
        It multiplies ``h^power``.
    field : sympy.Matrix, shape (2, 1)
        ``f_{power+1}``.
    divergence : sympy.Expr
        Its divergence, simplified (parameters symbolic).
    energy_rate : sympy.Expr
        ``grad H . f_{power+1}``: its contribution to ``dH/dt`` (times ``h^power``).
    divergence_free_powers : tuple of int
        The earlier non-zero terms, each shown divergence-free.
    """

    power: int
    field: sp.Matrix
    divergence: sp.Expr
    energy_rate: sp.Expr
    divergence_free_powers: tuple


def first_dissipative_term(model: PendulumModel, method, max_power: int = 6) -> DissipativeTerm:
    """Find the first term of ``method``'s modified equation with non-zero divergence.

    A divergence-free term changes no area, and over a closed orbit its
    ``grad H . f`` integrates to the flux through the orbit, which is zero;
    the first term with non-zero divergence sets the energy drift.

    Raises
    ------
    ValueError
        If every term up to ``h^max_power`` is divergence-free (a symplectic
        method, or too small ``max_power``).

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> first_dissipative_term(pl.simple_pendulum(), "explicit_euler").power
    1
    """
    model = conservative_model(model, (1,), chain=True)
    max_power = checked_order(max_power, MAX_FIELD_ORDER - 1, "for the modified equation")
    theta, p = model.chain.q[0], model.chain.p[0]
    fields = modified_equation(model, method, max_power)
    quiet = []
    for power, field in enumerate(fields[1:], start=1):
        if field == sp.zeros(2, 1):
            continue
        divergence = sp.diff(field[0], theta) + sp.diff(field[1], p)
        if is_identically_zero(divergence):
            quiet.append(power)
            continue
        h_theta, h_p = (sp.diff(model.hamiltonian, x) for x in (theta, p))
        # factor_terms, not factor: SymPy's multivariate factorization picks random
        # evaluation points and now and then takes many minutes here (seen in CI)
        return DissipativeTerm(power, field, sp.factor_terms(divergence),
                               sp.factor_terms(h_theta * field[0] + h_p * field[1]),
                               tuple(quiet))
    raise ValueError(f"every term of {get_method(method).name!r}'s modified equation up to "
                     f"h^{max_power} is divergence-free (a symplectic method has no such term)")


@dataclass(frozen=True)
class EnergyDrift:
    """Measured and predicted energy drift rates of a non-symplectic method.

    Attributes
    ----------
    method : str
    amplitude : float
    dts : ndarray, shape (m,)
    measured : ndarray, shape (m,)
        Slope of a least-squares line through ``H(t) - H(0)`` [J/s].
    predicted : ndarray, shape (m,)
        ``h^P <grad H . f_{P+1}>``, the orbit average over the exact libration.
    power : int
        ``P``, from :func:`first_dissipative_term`.
    measured_exponent : float
        Slope of ``log |measured|`` against ``log h``; theory: ``P``.
    t_end : float
    """

    method: str
    amplitude: float
    dts: np.ndarray
    measured: np.ndarray
    predicted: np.ndarray
    power: int
    measured_exponent: float
    t_end: float


def mean_energy_rate(model: PendulumModel, method, amplitude: float, power: int) -> float:
    """The orbit average of ``grad H . f_{power+1}``: what the ``h^power`` term does to the energy.

    Along the modified equation ``y' = f + h f_2 + ...`` the energy changes at
    the rate ``sum_j h^j grad H . f_{j+1}``; averaged over one period of the
    exact libration released at rest from ``amplitude`` (512 equally spaced
    times, the trapezoidal rule of a periodic function), the term ``h^power``
    contributes ``h^power`` times the number returned [J/s per s^power].

    Parameters
    ----------
    model : PendulumModel
        A simple pendulum.
    method : str or Method
        Any method :func:`modified_equation` expands.
    amplitude : float
        Release angle at rest, ``0 < |amplitude| < pi`` [rad].
    power : int
        ``1 <= power <= 6``.

    Returns
    -------
    float

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> rate = mean_energy_rate(pl.simple_pendulum(), "leapfrog", 1.0, 2)
    >>> bool(abs(rate) < 1e-12)      # a symplectic method's terms do not drain energy
    True
    """
    model = conservative_model(model, (1,), chain=True)
    power = checked_order(power, MAX_FIELD_ORDER - 1, "for the modified equation")
    if power < 1:
        raise ValueError("`power` must be >= 1 (power 0 is Hamilton's field, which keeps H)")
    field = modified_equation(model, method, power)[power]
    theta, p = model.chain.q[0], model.chain.p[0]
    rate = sp.diff(model.hamiltonian, theta) * field[0] + sp.diff(model.hamiltonian, p) * field[1]
    return _libration_mean(model, amplitude, rate)


def _libration_mean(model, amplitude, expr) -> float:
    """The mean of ``expr(theta, p)`` over one period of the exact libration from ``amplitude``."""
    period = exact_period(model, amplitude)
    theta, p = exact_libration(model, amplitude, np.arange(512) * period / 512)
    return float(np.mean(hamiltonian_function(model, expr)(theta, p, 0.0)))


def energy_drift(model: PendulumModel, method, amplitude: float, *, dts,
                 t_end: float) -> EnergyDrift:
    """Compare a method's measured energy drift rate with its modified equation's prediction.

    The prediction averages ``grad H . f_{P+1}`` over one period of the exact
    libration (512 equally spaced times: the trapezoidal rule of a periodic
    function, accurate to round-off) and multiplies by ``h^P``.

    Parameters
    ----------
    model : PendulumModel
        A simple pendulum.
    method : str or Method
        A method with a dissipative term (``rk4``, ``explicit_euler``).
    amplitude : float
        Release angle at rest [rad].
    dts : sequence of float
    t_end : float
        Length of each run; long enough for the drift to dominate the
        oscillation of ``H``.
    """
    term = first_dissipative_term(model, method)
    t_end = check.positive_number("t_end", t_end)
    dts = np.asarray([check.positive_number("dts", dt) for dt in dts])
    if dts.size < 2:
        raise ValueError(f"`dts` must hold at least two step sizes (for the exponent), got "
                         f"{dts.size}")
    coefficient = _libration_mean(model, amplitude, term.energy_rate)
    measured = []
    for dt in dts:
        run = simulate(model, [amplitude], [0.0], t_end=t_end, dt=dt, method=get_method(method),
                       save_every=max(1, int(round(0.05 / dt))))
        measured.append(np.polyfit(run.t, run.energy_error, 1)[0])
    measured = np.asarray(measured)
    exponent = float(np.polyfit(np.log(dts), np.log(np.abs(measured)), 1)[0])
    return EnergyDrift(get_method(method).name, float(amplitude), dts, measured,
                       coefficient * dts**term.power, term.power, exponent, t_end)
