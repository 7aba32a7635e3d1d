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
from ..symbolic.mechanics import derive_chain, is_identically_zero
from .long_time import exact_libration
from .model_checks import conservative_model
from .modified_equations import (
    SERIES_METHODS,
    STEP_SIZE,
    abstract_problem,
    hamiltonian_of_field,
    modified_fields,
    step_series,
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

#: Methods with a modified Hamiltonian here, and the largest ``order`` derived per ``n``.
HAMILTONIAN_METHODS = ("semi_implicit_euler", "leapfrog", "glrk4")
MAX_ORDER = {1: 4, 2: 2}
#: The report's velocity-variable methods equal these canonical ones when ``n = 1``.
VELOCITY_TWINS = {"semi_implicit_euler_velocity": "semi_implicit_euler",
                  "leapfrog_velocity": "leapfrog"}
# Symmetric (time-reversible) methods: their modified equations hold even powers of h only.
SYMMETRIC = ("leapfrog", "glrk4", "glrk8")
MAX_FIELD_ORDER = 7


def _order(order, maximum: int, what: str) -> int:
    order = check.integer_at_least("order", order, 0)
    if order > maximum:
        raise ValueError(f"`order` must be in [0, {maximum}] {what}, got {order}")
    return order


def _hamiltonian_method(model: PendulumModel, method) -> str:
    """The canonical method whose modified Hamiltonian ``method`` has, or a clear error.

    The verdicts come from theory, not from a fit attempted here: explicit
    Euler and RK4 fail the symplecticity condition of their tableaus
    (``Method.symplectic``, HLW Thm VI.4.3), and :func:`hamiltonian_fit` shows
    the first term of their modified equations that no Hamiltonian
    reproduces. The velocity versions step ``(theta, omega)``; for ``n >= 2``
    their Jacobian misses ``Psi^T J Psi = J`` in ``(theta, p)`` (notebook 13) and
    their energy error grows on regular motion, which a map conjugate to a
    symplectic one would not show (notebook 14).
    """
    name = get_method(method).name
    if name in VELOCITY_TWINS:
        if model.n == 1 and model.is_chain:
            return VELOCITY_TWINS[name]
        raise ValueError(
            f"`method` {name!r} has no modified Hamiltonian for n = {model.n}: it steps "
            "(theta, omega), and for n >= 2 that map is not symplectic in (theta, p) and its "
            "energy error grows on regular motion, so it is not conjugate to a symplectic map "
            f"either (for n = 1 it equals {VELOCITY_TWINS[name]!r})"
        )
    if name in ("explicit_euler", "rk4"):
        raise ValueError(
            f"`method` {name!r} is not symplectic (its tableau fails the symplecticity "
            "condition), so it has no modified Hamiltonian: hamiltonian_fit shows the first "
            "term of its modified equation that is not a Hamiltonian vector field"
        )
    if name not in HAMILTONIAN_METHODS:
        raise ValueError(
            f"`method` must be one of {list(HAMILTONIAN_METHODS) + list(VELOCITY_TWINS)} "
            f"for a modified Hamiltonian, got {name!r}"
        )
    return name


@functools.cache
def _abstract_fields(method: str, n: int, separable: bool, order: int) -> tuple:
    """``f_1, ..., f_{order+1}`` of ``method`` for an undefined ``H`` (or ``T + U``)."""
    q, p, hamiltonian = abstract_problem(n, separable)
    series = step_series(method, hamiltonian, q, p, order + 1)
    return tuple(tuple(f) for f in modified_fields(series, (*q, *p)))


@functools.cache
def _abstract_terms(method: str, n: int, separable: bool, order: int) -> tuple:
    """``(H_0, H_1, ..., H_order)`` for an undefined ``H`` (or ``T + U``)."""
    q, p, hamiltonian = abstract_problem(n, separable)
    fields = _abstract_fields(method, n, separable, order)
    return (hamiltonian, *(hamiltonian_of_field(fields[j], hamiltonian, q, p, j + 1)
                           for j in range(1, order + 1)))


@dataclass(frozen=True)
class HamiltonianFit:
    """The attempt to write each term of a modified equation as a Hamiltonian vector field.

    Attributes
    ----------
    method : str
    separable : bool
        Whether the general Hamiltonian was ``T(p) + U(q)`` rather than ``H(q, p)``.
    powers : tuple of int
        The powers ``j`` of ``h`` tried, in order (the attempt stops at the
        first term that no Hamiltonian fits).
    outcomes : tuple of str
        Per power: ``"zero"`` (no term), ``"fitted"`` (a combination of
        elementary Hamiltonians reproduces it) or ``"no fit"``.
    hamiltonians : tuple
        Per power: the fitted ``H_j`` (sympy), ``0`` for a zero term, ``None``
        where no fit exists.
    message : str
        The reason the last attempt failed (empty when every term fitted).
    """

    method: str
    separable: bool
    powers: tuple
    outcomes: tuple
    hamiltonians: tuple
    message: str

    @property
    def first_failure(self) -> int | None:
        """The first power of ``h`` whose term no Hamiltonian reproduces (None: all fitted)."""
        return self.powers[-1] if self.outcomes and self.outcomes[-1] == "no fit" else None


def hamiltonian_fit(method: str, max_power: int, *, separable: bool = False) -> HamiltonianFit:
    """Try to fit a Hamiltonian to each term of ``method``'s modified equation, for a general H.

    One degree of freedom, ``H(q, p)`` an undefined function (or ``T(p) + U(q)``
    with ``separable``). For each power ``j = 1 .. max_power`` of ``h`` the term
    ``f_{j+1}`` is matched, coefficient by coefficient, with the Hamiltonian
    vector fields of all combinations of elementary Hamiltonians with
    ``j + 1`` factors
    (:func:`~pendulum_lab.geometric.modified_equations.hamiltonian_of_field`).
    A symplectic method passes at every power [HLW, Thm IX.3.1]; for any other
    method some term fails, and the attempt stops there.

    Parameters
    ----------
    method : str
        A method :func:`~pendulum_lab.geometric.modified_equations.step_series`
        expands: ``explicit_euler``, ``semi_implicit_euler``, ``leapfrog``,
        ``rk4``, ``glrk4``.
    max_power : int
        The highest power of ``h`` tried, ``1 <= max_power <= 4``.
    separable : bool

    Returns
    -------
    HamiltonianFit

    References
    ----------
    HLW, Sect. IX.3 (modified equations of symplectic methods are Hamiltonian)
    and IX.10 (elementary Hamiltonians).

    Examples
    --------
    >>> hamiltonian_fit("explicit_euler", 2).first_failure
    1
    >>> hamiltonian_fit("semi_implicit_euler", 2).outcomes
    ('fitted', 'fitted')
    """
    if method not in SERIES_METHODS:
        raise ValueError(f"`method` must be one of {list(SERIES_METHODS)}, got {method!r}")
    max_power = check.integer_at_least("max_power", max_power, 1)
    if max_power > 4:
        raise ValueError(f"`max_power` must be in [1, 4] (the fit at h^5 is costly), "
                         f"got {max_power}")
    separable = bool(separable)
    q, p, hamiltonian = abstract_problem(1, separable)
    fields = _abstract_fields(method, 1, separable, max_power)
    powers, outcomes, hamiltonians, message = [], [], [], ""
    for j in range(1, max_power + 1):
        powers.append(j)
        if all(sp.expand(c) == 0 for c in fields[j]):
            outcomes.append("zero")
            hamiltonians.append(sp.Integer(0))
            continue
        try:
            hamiltonians.append(hamiltonian_of_field(fields[j], hamiltonian, q, p, j + 1))
            outcomes.append("fitted")
        except ValueError as error:
            outcomes.append("no fit")
            hamiltonians.append(None)
            message = str(error)
            break
    return HamiltonianFit(method, separable, tuple(powers), tuple(outcomes),
                          tuple(hamiltonians), message)


@functools.cache
def _simple_pendulum_fields(method: str, order: int) -> tuple:
    """Modified-equation terms for the simple pendulum's own ``H`` (parameters symbolic).

    Cheaper than the general form at high order: the kinetic energy is
    quadratic and the derivatives of ``cos`` are known, so far fewer terms arise.
    """
    chain = derive_chain(1)
    (theta,), (p,) = chain.q, chain.p
    series = step_series(method, chain.hamiltonian, [theta], [p], order + 1)
    return tuple(tuple(sp.expand(c) for c in f) for f in modified_fields(series, (theta, p)))


def generic_modified_hamiltonian(method: str, order: int, n: int = 1,
                                 separable: bool = False) -> sp.Expr:
    """The modified Hamiltonian for an undefined ``H(q, p)`` (or ``T(p) + U(q)``).

    This is the general formula, before any pendulum is put in: for symplectic
    Euler it reproduces ``H - h/2 H_p H_q + h^2/12 (H_pp H_q^2 + H_qq H_p^2 +
    4 H_pq H_p H_q)`` [HLW, Sect. IX.3]. Symbols: ``q``, ``p`` for ``n = 1``,
    ``q1, q2, p1, p2`` for ``n = 2``, and :data:`STEP_SIZE`.

    Examples
    --------
    >>> generic_modified_hamiltonian("semi_implicit_euler", 1)
    -h*Derivative(H(q, p), p)*Derivative(H(q, p), q)/2 + H(q, p)
    """
    if method not in HAMILTONIAN_METHODS:
        raise ValueError(f"`method` must be one of {list(HAMILTONIAN_METHODS)}, got {method!r}")
    n = check.integer_at_least("n", n, 1)
    if n not in MAX_ORDER:
        raise ValueError(f"`n` must be 1 or 2, got {n}")
    order = _order(order, MAX_ORDER[n], f"for n = {n}")
    terms = _abstract_terms(method, n, bool(separable), order)
    return sp.Add(*[STEP_SIZE**j * term for j, term in enumerate(terms)])


def _concrete(expr, model: PendulumModel):
    """Put the model's Hamiltonian (parameters symbolic) in place of the undefined one."""
    chain = model.chain
    q, p, abstract = abstract_problem(model.n, model.separable)
    hamiltonian = model.hamiltonian
    if model.separable:
        potential = hamiltonian.subs({x: 0 for x in chain.p})
        parts = {sp.Function("T"): hamiltonian - potential, sp.Function("U"): potential}
    else:
        parts = {sp.Function("H"): hamiltonian}
    rename = dict(zip((*q, *p), (*chain.q, *chain.p)))
    parts = {f: e.xreplace({v: k for k, v in rename.items()}) for f, e in parts.items()}
    mapping = {}
    for d in expr.atoms(sp.Derivative):
        mapping[d] = sp.diff(parts[d.expr.func], *d.variable_count)
    for f in expr.atoms(sp.core.function.AppliedUndef):
        mapping.setdefault(f, parts[f.func])
    return expr.xreplace(mapping).xreplace(rename)


def _tidy(expr, model: PendulumModel):
    """Simplify for display where that is cheap (one link); leave larger forms as they are."""
    return sp.simplify(expr) if model.n == 1 else expr


def modified_hamiltonian(model: PendulumModel, method, order: int) -> sp.Expr:
    """The modified Hamiltonian ``H~ = H + h H_1 + ... + h^order H_order`` of ``method``.

    Derived by matching the Taylor expansion of one step with the exact flow
    of ``H~`` (see :mod:`pendulum_lab.geometric.modified_equations`), first
    for an undefined ``H``, then with the model's Hamiltonian put in.

    Parameters
    ----------
    model : PendulumModel
        A simple (``n = 1``) or double (``n = 2``) pendulum.
    method : str or Method
        ``"semi_implicit_euler"``, ``"leapfrog"`` or ``"glrk4"`` (and, for
        ``n = 1`` only, the report's velocity versions, which then are the
        same maps).
    order : int
        The highest power of ``h`` kept: at most 4 for ``n = 1``, 2 for ``n = 2``.

    Returns
    -------
    sympy.Expr
        In the symbols of ``model.hamiltonian`` (angles, momenta, masses,
        lengths, ``g``) and the step size :data:`STEP_SIZE` (``h``; use this
        symbol, do not create another).

    Raises
    ------
    ValueError
        For a method without a modified Hamiltonian (explicit Euler, RK4, the
        velocity versions when ``n >= 2``), an unsupported method, an
        ``order`` out of range or a chain of more than two links.

    References
    ----------
    HLW, Sect. IX.3 (symplectic Euler, Stormer-Verlet), IX.10 (symplectic
    P-series).

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> h_tilde = pl.modified_hamiltonian(pl.simple_pendulum(), "semi_implicit_euler", 1)
    >>> sp.expand(h_tilde - pl.simple_pendulum().hamiltonian)
    -g*h*p*sin(theta)/(2*l)
    """
    model = conservative_model(model, MAX_ORDER)
    name = _hamiltonian_method(model, method)
    order = _order(order, MAX_ORDER[model.n], f"for n = {model.n}")
    terms = _abstract_terms(name, model.n, model.separable, order)
    total = model.hamiltonian
    for j, term in enumerate(terms[1:], start=1):
        total += STEP_SIZE**j * _tidy(_concrete(term, model), model)
    return total


def modified_equation(model: PendulumModel, method, order: int) -> list[sp.Matrix]:
    """The terms ``f_1, f_2, ..., f_{order+1}`` of the modified equation of any method.

    ``y' = f_1(y) + h f_2(y) + h^2 f_3(y) + ...`` in ``y = (theta, p)``; ``f_1``
    is Hamilton's vector field. Every method has one, symplectic or not.

    Parameters
    ----------
    model : PendulumModel
        A simple pendulum (``n = 1``).
    method : str or Method
        ``explicit_euler``, ``semi_implicit_euler``, ``leapfrog``, ``rk4``,
        ``glrk4`` (or a velocity version, the same map for ``n = 1``).
    order : int
        Highest power of ``h``, ``0 <= order <= 6``.

    Returns
    -------
    list of sympy.Matrix, each shape (2, 1)
        ``fields[j]`` multiplies ``h^j``; parameters symbolic.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> modified_equation(pl.simple_pendulum(), "explicit_euler", 1)[1].T
    Matrix([[g*sin(theta)/(2*l), g*p*cos(theta)/(2*l)]])
    """
    model = conservative_model(model, (1,), chain=True)
    name = get_method(method).name
    name = VELOCITY_TWINS.get(name, name)
    if name == "glrk8":
        raise ValueError("`method` 'glrk8' is not expanded here (its first correction is h^8)")
    order = _order(order, MAX_FIELD_ORDER - 1, "for the modified equation")
    return [sp.Matrix(f) for f in _simple_pendulum_fields(name, order)]


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
    name = _hamiltonian_method(model, method)
    orders = tuple(_order(k, MAX_ORDER[model.n], f"for n = {model.n}") for k in orders)
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
    max_power = _order(max_power, MAX_FIELD_ORDER - 1, "for the modified equation")
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
    power = _order(power, MAX_FIELD_ORDER - 1, "for the modified equation")
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
