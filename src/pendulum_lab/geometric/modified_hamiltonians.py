"""The modified Hamiltonian and the modified equation of the course's integrators on the
pendulums, derived symbolically, and the term-by-term attempt to write a method's modified
equation as a Hamiltonian vector field (:func:`hamiltonian_fit`).

The engine (Taylor expansions of one step, modified vector fields, elementary Hamiltonians)
is :mod:`pendulum_lab.geometric.modified_equations`; the overview of the theory and its
numerical checks is :mod:`pendulum_lab.geometric.backward_error`.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import sympy as sp

from .. import validation as check
from ..integrators import get_method
from ..model.pendulum import PendulumModel
from ..symbolic.mechanics import derive_chain
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
    "HAMILTONIAN_METHODS",
    "MAX_FIELD_ORDER",
    "MAX_ORDER",
    "STEP_SIZE",
    "SYMMETRIC",
    "VELOCITY_TWINS",
    "HamiltonianFit",
    "checked_order",
    "generic_modified_hamiltonian",
    "hamiltonian_fit",
    "hamiltonian_method",
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


def checked_order(order, maximum: int, what: str) -> int:
    """``order``, an integer in ``[0, maximum]``, or an error naming it and what limits it."""
    order = check.integer_at_least("order", order, 0)
    if order > maximum:
        raise ValueError(f"`order` must be in [0, {maximum}] {what}, got {order}")
    return order


def hamiltonian_method(model: PendulumModel, method) -> str:
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
    order = checked_order(order, MAX_ORDER[n], f"for n = {n}")
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
    name = hamiltonian_method(model, method)
    order = checked_order(order, MAX_ORDER[model.n], f"for n = {model.n}")
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
    order = checked_order(order, MAX_FIELD_ORDER - 1, "for the modified equation")
    return [sp.Matrix(f) for f in _simple_pendulum_fields(name, order)]
