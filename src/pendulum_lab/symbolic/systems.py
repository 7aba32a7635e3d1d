"""Symbolic mechanics of any holonomic system a student writes down (SymPy only).

A :class:`MechanicalSystem` is described either by the Cartesian positions of point
masses, as SymPy expressions of the generalized coordinates ``q`` and the time ``t``
(a moving pivot is a position that depends on ``t``), with extra potential terms
(springs), or directly by a Lagrangian ``L(q, q', t)``. Optional: Rayleigh's
dissipation function ``R(q, q', t)`` and generalized forces ``Q(q, q', t)``. It derives,
as :class:`~pendulum_lab.symbolic.mechanics.Chain` does for a chain::

    L = 1/2 q'^T M(q, t) q' + b(q, t)^T q' + L_0(q, t)
    p = dL/dq' = M q' + b                        (a moving pivot gives b)
    H = p q' - L = 1/2 (p - b)^T M^-1 (p - b) - L_0
    dq/dt = M^-1 (p - b),   dp/dt = dL/dq + Q    (at q' = M^-1 (p - b))
    M q'' = dL/dq - (d/dq dL/dq') q' - d/dt dL/dq' + Q   (the forcing)

with ``Q = -dR/dq' + forces``. The attributes the code generator reads
(:mod:`pendulum_lab.codegen.kernels`) are those of ``Chain``: ``n, q, omega, t,
parameters, mass_matrix, dlagrangian_dq, generalized_forces, forcing, forced``, plus
``momentum_offset`` (``b``, zero for a chain). A chain is one case
(:func:`chain_system`); the tests assert that its general derivation equals ``Chain(n)``.

Refused, with a message naming the argument: a Lagrangian that is not a polynomial of
degree two in the velocities, a mass matrix that is singular (the coordinates of its null
direction are named: they are redundant) or not positive definite, symbols that are
neither coordinates, velocities, ``t`` nor declared parameters (named), and parameter
values that are not real finite numbers.

References
----------
.. [G] H. Goldstein, C. Poole, J. Safko, *Classical Mechanics*, 3rd ed., Addison-Wesley
   2002, Sects. 1.4-1.5 and 8.1 (the Legendre transform with velocity-linear terms).
"""

from __future__ import annotations

import functools
import math
import numbers
from dataclasses import dataclass

import sympy as sp
from sympy.simplify.fu import TR10i

from .mechanics import Equilibrium, derive_chain, hamilton_equations_of, legendre_transform_of

__all__ = [
    "MechanicalSystem",
    "SystemEquilibrium",
    "chain_system",
    "parameter_values",
]

#: Random configurations the mass matrix is checked at (numeric rank and definiteness).
_CHECK_POINTS = 3


def _symbol_list(name: str, values) -> list:
    if isinstance(values, sp.Symbol):
        values = [values]
    try:
        values = list(values)
    except TypeError:
        raise TypeError(f"`{name}` must be a sequence of SymPy symbols, got {values!r}") from None
    if not values:
        raise ValueError(f"`{name}` must hold at least one SymPy symbol")
    for value in values:
        if not isinstance(value, sp.Symbol):
            raise TypeError(f"`{name}` must hold SymPy symbols, got {value!r} "
                            f"({type(value).__name__})")
    if len(set(values)) != len(values):
        raise ValueError(f"`{name}` must not repeat a symbol, got {values}")
    return values


def parameter_values(parameters) -> dict:
    """``{Symbol: float}`` from a dict of symbols (or names) to real finite numbers."""
    if not isinstance(parameters, dict):
        raise TypeError("`parameters` must be a dict {symbol: default value}, got "
                        f"{type(parameters).__name__}")
    values = {}
    for key, value in parameters.items():
        symbol = sp.Symbol(key) if isinstance(key, str) else key
        if not isinstance(symbol, sp.Symbol):
            raise TypeError(f"`parameters` keys must be SymPy symbols or names, got {key!r}")
        if isinstance(value, bool) or not isinstance(value, (numbers.Number, sp.Number)):
            raise TypeError(f"`parameters[{symbol}]` must be a real number, got {value!r}")
        if isinstance(value, complex) or (isinstance(value, sp.Number) and not value.is_real):
            raise ValueError(f"`parameters[{symbol}]` must be a real number, got {value!r}")
        value = float(value)
        if not math.isfinite(value):
            raise ValueError(f"`parameters[{symbol}]` must be finite, got {value}")
        values[symbol] = value
    return values


def _matrix(name: str, values, n: int) -> sp.Matrix:
    values = sp.Matrix([sp.sympify(v) for v in values])
    if values.shape != (n, 1):
        raise ValueError(f"`{name}` must hold {n} expressions (one per coordinate), got "
                         f"{values.shape[0]}")
    return values


def _tidy(expr) -> sp.Expr:
    """``expr`` expanded, with ``cos a cos b + sin a sin b`` folded into ``cos(a - b)`` and
    ``sin^2 + cos^2`` into 1 (as :func:`~pendulum_lab.symbolic.mechanics.lagrangian_derivation`
    does for a chain)."""
    expr = TR10i(sp.factor_terms(sp.expand(expr)))
    squares = {s.args[0] for s in expr.atoms(sp.sin)}
    expr = sp.expand(expr.subs({sp.sin(a) ** 2: 1 - sp.cos(a) ** 2 for a in squares}))
    return sp.expand(TR10i(sp.factor_terms(expr)))


def _vanishes(expr) -> bool:
    """Zero, exactly or (for a number computed from floats) to round-off."""
    if expr == 0:
        return True
    return not expr.free_symbols and abs(complex(expr)) < 1e-9


@dataclass(frozen=True)
class SystemEquilibrium(Equilibrium):
    """An equilibrium ``(q*, q'* = 0)`` of an autonomous system.

    ``jacobian`` is that of ``(q', q'')`` with respect to ``(q, q')`` there, velocity-linear
    (gyroscopic, damping) terms included; ``stiffness_ratio`` is ``M^-1 dF/dq``.
    """


class MechanicalSystem:
    """Symbolic equations of a holonomic mechanical system (see the module docstring).

    Parameters
    ----------
    coordinates : sequence of sympy.Symbol
        The generalized coordinates ``q``.
    parameters : dict
        ``{symbol: default value}`` of every other symbol the description uses (``t``
        aside); the values must be real and finite.
    points : sequence of (x, y) pairs of expressions, optional
        Cartesian positions of point masses, functions of ``q`` and ``t``.
    masses : sequence of expressions, optional
        One mass per point (numbers or parameter symbols).
    gravity : expression, optional
        ``g``: the potential ``sum m_i g y_i`` of the points (``y`` up). None: no gravity.
    potential : expression, optional
        Further potential energy ``V(q, t)`` (springs).
    lagrangian : expression, optional
        ``L(q, q', t)`` directly, instead of points (give ``velocities`` to write it).
    velocities : sequence of sympy.Symbol, optional
        The symbols of ``q'``; by default ``<q>_dot`` for each coordinate.
    dissipation : expression, optional
        Rayleigh's function ``R(q, q', t)``: forces ``-dR/dq'``.
    forces : sequence of expressions, optional
        Further generalized forces ``Q(q, q', t)``, one per coordinate.
    joints : sequence of (i, j) pairs, optional
        Points drawn joined by a rod (point indices; ``-1`` is the origin); for drawings only.
        When neither ``joints`` nor ``springs`` is given, they are read from the points: a
        point at a fixed distance from an earlier point or the origin hangs from it; one at a
        fixed distance from a place that only the time moves (a shaken pivot) hangs from
        that place, added to ``points`` as a massless point. Give ``joints=[]`` to draw no
        rod.
    springs : sequence of (i, j) pairs, optional
        Points drawn joined by a spring (as ``joints``); for drawings only.
    name : str
        What the system is, for people ("the elastic pendulum").

    Attributes
    ----------
    n, q, omega, p, t, parameters, defaults
    mass_matrix : sympy.Matrix, shape (n, n)
        ``M = d^2 L / dq'^2``.
    momentum_offset : sympy.Matrix, shape (n, 1)
        ``b = dL/dq'`` at ``q' = 0``.
    kinetic, potential, lagrangian : sympy.Expr
    dlagrangian_dq, generalized_forces, forcing, momenta : sympy.Matrix, shape (n, 1)
    forced : bool
        Whether there are generalized forces ``Q`` besides the Lagrangian's.
    autonomous : bool
        Whether nothing depends on ``t``.

    Examples
    --------
    >>> th, m, l, g = sp.symbols("theta m l g")
    >>> s = MechanicalSystem([th], {m: 1.0, l: 1.0, g: 9.81},
    ...                      points=[(l * sp.sin(th), -l * sp.cos(th))], masses=[m], gravity=g)
    >>> s.mass_matrix, s.forcing
    (Matrix([[l**2*m]]), Matrix([[-g*l*m*sin(theta)]]))
    """

    def __init__(self, coordinates, parameters, *, points=None, masses=None, gravity=None,
                 potential=0, lagrangian=None, velocities=None, dissipation=0, forces=None,
                 joints=None, springs=None, name: str = "a mechanical system"):
        self.q = sp.Matrix(_symbol_list("coordinates", coordinates))
        self.n = n = len(self.q)
        if velocities is None:
            velocities = [sp.Symbol(f"{qi.name}_dot", real=True) for qi in self.q]
        self.omega = sp.Matrix(_symbol_list("velocities", velocities))
        if len(self.omega) != n:
            raise ValueError(f"`velocities` must hold {n} symbols (one per coordinate), got "
                             f"{len(self.omega)}")
        self.p = sp.Matrix([sp.Symbol(f"p_{qi.name}", real=True) for qi in self.q])
        self.t = sp.Symbol("t", real=True)
        self.defaults = parameter_values(parameters)
        self.parameters = tuple(self.defaults)
        self.name = name
        overlap = set(self.parameters) & (set(self.q) | set(self.omega) | {self.t})
        if overlap:
            raise ValueError(f"`parameters` must not name coordinates, velocities or t, got "
                             f"{sorted(map(str, overlap))}")
        self._time_alias = {sp.Symbol("t"): self.t}

        if (lagrangian is None) == (points is None):
            raise TypeError("give exactly one of `points` (with `masses`) and `lagrangian`")
        if points is not None:
            points = [tuple(self._expr(f"points[{i}]", c) for c in point)
                      for i, point in enumerate(points)]
            if any(len(point) != 2 for point in points):
                raise ValueError("`points` must hold (x, y) pairs")
            if masses is None or len(masses) != len(points):
                raise ValueError(f"`masses` must hold one mass per point ({len(points)})")
            self.points = points
            self.masses = [self._expr(f"masses[{i}]", m) for i, m in enumerate(masses)]
            kinetic = sp.Add(*(m * _tidy(self._rate(x) ** 2 + self._rate(y) ** 2) / 2
                               for m, (x, y) in zip(self.masses, points)))
            weight = 0 if gravity is None else self._expr("gravity", gravity)
            potential = self._expr("potential", potential)
            potential += sp.Add(*(m * weight * y for m, (_, y) in zip(self.masses, points)))
            self.potential = sp.expand(potential)
            self.kinetic = sp.expand(kinetic)
            self.lagrangian = self.kinetic - self.potential
        else:
            if potential != 0 or gravity is not None or masses is not None:
                raise TypeError("`potential`, `gravity` and `masses` go with `points`; a "
                                "`lagrangian` contains its potential")
            self.points, self.masses = [], []
            self.lagrangian = sp.expand(self._expr("lagrangian", lagrangian))
            self._require_quadratic()
            rest = self.lagrangian.xreplace({w: 0 for w in self.omega})
            self.kinetic = sp.expand(self.lagrangian - rest)
            self.potential = -rest
        self.joints = self._pairs("joints", joints)
        self.springs = self._pairs("springs", springs)
        if joints is None and springs is None and self.points:
            self._infer_suspension()
        self.dissipation = self._expr("dissipation", dissipation)
        extra = sp.zeros(n, 1) if forces is None else _matrix("forces", forces, n)
        extra = extra.applyfunc(lambda e: self._expr("forces", e))
        self.generalized_forces = (extra - sp.Matrix([self.dissipation.diff(w)
                                                      for w in self.omega])).applyfunc(sp.expand)
        self.forced = any(f != 0 for f in self.generalized_forces)
        self._require_quadratic()
        self._check_mass_matrix()

    # ---- input -------------------------------------------------------------------
    def _expr(self, name: str, value) -> sp.Expr:
        """``value`` as a SymPy expression of declared symbols only."""
        try:
            expr = sp.sympify(value)
        except (sp.SympifyError, TypeError):
            raise TypeError(f"`{name}` must be a SymPy expression, got {value!r}") from None
        expr = expr.xreplace(self._time_alias)
        known = set(self.q) | set(self.omega) | set(self.parameters) | {self.t}
        unknown = expr.free_symbols - known
        if unknown:
            raise ValueError(
                f"`{name}` uses {', '.join(sorted(map(str, unknown)))}, which "
                f"{'is' if len(unknown) == 1 else 'are'} neither a coordinate "
                f"({', '.join(map(str, self.q))}), a velocity, t, nor a declared parameter "
                f"({', '.join(map(str, self.parameters)) or 'none'}): declare "
                f"{'it' if len(unknown) == 1 else 'them'} in `parameters` with a default value")
        return expr

    def _pairs(self, name: str, pairs) -> list[tuple[int, int]]:
        """Pairs of point indices (``-1``: the origin) that a drawing joins."""
        found = []
        for pair in pairs or []:
            try:
                i, j = (int(k) for k in pair)
            except (TypeError, ValueError):
                raise TypeError(f"`{name}` must hold pairs of point indices, got {pair!r}") \
                    from None
            if not (-1 <= i < len(self.points) and -1 <= j < len(self.points)) or i == j:
                raise ValueError(
                    f"`{name}` pair {tuple(pair)} must join two different points among 0 to "
                    f"{len(self.points) - 1} (or -1, the origin)")
            found.append((i, j))
        return found

    def _infer_suspension(self) -> None:
        """Rods for the drawing, when neither ``joints`` nor ``springs`` were given: a point
        kept at a fixed distance from an earlier point, or else from the origin, hangs from
        it on a rod; one kept at a fixed distance from the place its position gives at
        ``q = 0`` terms only (the part of it the coordinates do not move, such as a shaken
        pivot's ``a cos(w t)``) hangs from that place, added as a massless point after the
        given ones (so that a pendulum whose pivot moves is drawn with its rod and pivot)."""
        moved = set(self.q)

        def fixed_distance(dx, dy) -> bool:
            if not (sp.sympify(dx).free_symbols | sp.sympify(dy).free_symbols) & moved:
                return False  # nothing between them moves: not an arm
            square = sp.trigsimp(sp.expand(dx ** 2 + dy ** 2))
            return square != 0 and not square.free_symbols & moved

        given = list(self.points)
        for k, (x, y) in enumerate(given):
            anchors = [(j, given[j]) for j in range(k)] + [(-1, (0, 0))]
            hung = next((j for j, (ax, ay) in anchors if fixed_distance(x - ax, y - ay)), None)
            if hung is not None:
                self.joints.append((hung, k))
                continue
            pivot = tuple(sp.Add(*(term for term in sp.Add.make_args(sp.expand(c))
                                   if not term.free_symbols & moved)) for c in (x, y))
            if any(c != 0 for c in pivot) and fixed_distance(x - pivot[0], y - pivot[1]):
                self.points.append(pivot)
                self.masses.append(sp.Integer(0))
                self.joints.append((len(self.points) - 1, k))

    def _rate(self, expr) -> sp.Expr:
        """``d expr / dt`` along a motion: ``sum dexpr/dq_i q'_i + dexpr/dt``."""
        return sp.Add(*(expr.diff(qi) * wi for qi, wi in zip(self.q, self.omega))) + expr.diff(
            self.t)

    def _require_quadratic(self) -> None:
        lagrangian = self.lagrangian
        try:
            poly = sp.Poly(lagrangian, *self.omega)
        except sp.PolynomialError:
            poly = None
        if poly is None or any(not c.free_symbols.isdisjoint(self.omega) for c in poly.coeffs()):
            raise ValueError(
                "`lagrangian` must be a polynomial in the velocities "
                f"({', '.join(map(str, self.omega))}) of degree at most two "
                "(L = 1/2 q'^T M q' + b^T q' + L_0); got one that is not a polynomial in them")
        if poly.total_degree() > 2:
            raise ValueError(
                "`lagrangian` must be of degree at most two in the velocities "
                f"({', '.join(map(str, self.omega))}), got degree {poly.total_degree()}: the "
                "Legendre transform p = dL/dq' must be solvable for q' as a linear system")

    def _check_mass_matrix(self) -> None:
        """Refuse a mass matrix that is singular or not positive definite (at random points)."""
        import random

        import numpy as np

        mass = self.mass_matrix
        if all(e == 0 for e in mass):
            raise ValueError("the mass matrix is zero: the description has no kinetic energy "
                             f"in the velocities ({', '.join(map(str, self.omega))})")
        numbers_ = dict(self.defaults)
        rng = random.Random(20261202)
        for _ in range(_CHECK_POINTS):
            point = numbers_ | {s: rng.uniform(0.3, 1.3) for s in (*self.q, self.t)}
            matrix = np.array(mass.xreplace(point).evalf(), dtype=float)
            values, vectors = np.linalg.eigh(matrix)
            scale = max(abs(values).max(), 1e-300)
            if values[0] <= 1e-10 * scale:
                null = vectors[:, 0]
                if abs(values[0]) <= 1e-10 * scale:
                    named = [str(qi) for qi, c in zip(self.q, null) if abs(c) > 1e-6]
                    raise ValueError(
                        f"the mass matrix is singular: the coordinates "
                        f"{', '.join(named)} are redundant (a motion combining them, with "
                        f"weights {np.round(null[np.abs(null) > 1e-6], 3).tolist()}, has no "
                        "kinetic energy); describe the system with fewer coordinates")
                raise ValueError("the mass matrix is not positive definite (a kinetic energy "
                                 "that can be negative): check the masses' signs")

    # ---- the equations -------------------------------------------------------------
    @functools.cached_property
    def _dl_dw(self) -> sp.Matrix:
        return sp.Matrix([self.lagrangian.diff(w) for w in self.omega])

    @functools.cached_property
    def mass_matrix(self) -> sp.Matrix:
        """``M = d^2 L / dq'^2``, shape (n, n)."""
        return self._dl_dw.jacobian(self.omega).applyfunc(sp.expand)

    @functools.cached_property
    def momentum_offset(self) -> sp.Matrix:
        """``b = dL/dq'`` at ``q' = 0``: the momenta at rest (a moving pivot's part)."""
        return self._dl_dw.xreplace({w: 0 for w in self.omega}).applyfunc(sp.expand)

    @property
    def momenta(self) -> sp.Matrix:
        """``p = M q' + b``."""
        return self.mass_matrix * self.omega + self.momentum_offset

    @functools.cached_property
    def dlagrangian_dq(self) -> sp.Matrix:
        """``dL/dq``: the rate of change of the momenta without ``Q`` (``-dH/dq``)."""
        return sp.Matrix([sp.expand(self.lagrangian.diff(qi)) for qi in self.q])

    @functools.cached_property
    def forcing(self) -> sp.Matrix:
        """The right-hand side of ``M q'' = forcing``: ``dL/dq - (d/dq dL/dq') q' - d/dt dL/dq'
        + Q``."""
        dl_dw = self._dl_dw
        rate = dl_dw.jacobian(self.q) * self.omega + dl_dw.diff(self.t)
        return (self.dlagrangian_dq - rate + self.generalized_forces).applyfunc(sp.expand)

    @property
    def _dynamics(self) -> list[sp.Expr]:
        """The expressions the motion follows from: ``L`` and the generalized forces ``Q``
        (damping included)."""
        return [self.lagrangian, *self.generalized_forces]

    @property
    def autonomous(self) -> bool:
        """Nothing depends on the time ``t``."""
        return all(self.t not in e.free_symbols for e in self._dynamics)

    @functools.cached_property
    def clock_parameters(self) -> tuple[str, ...]:
        """Names of the parameters that the time dependence reads: those inside a function of
        ``t`` in the Lagrangian or in a generalized force (the Kapitza pendulum's ``w`` in
        ``cos(w t)``, a drive's frequency)."""
        clock = set()
        for term in (f for e in self._dynamics for f in e.atoms(sp.Function)):
            if self.t in term.free_symbols:
                clock |= {str(s) for s in term.free_symbols - {self.t}}
        return tuple(str(s) for s in self.parameters if str(s) in clock)

    @functools.cached_property
    def period(self) -> sp.Expr | None:
        """The period of the time dependence as an expression of the parameters
        (``2*pi/w`` for the Kapitza pendulum), or None: autonomous, or not periodic in ``t``
        in a way found here (each function of ``t`` periodic, their periods in rational
        ratios, ``t`` nowhere else).

        Examples
        --------
        >>> th, t = sp.symbols("theta t", real=True)
        >>> w, l = sp.symbols("w l", positive=True)
        >>> s = MechanicalSystem([th], {w: 10.0, l: 1.0}, masses=[1], gravity=9.81,
        ...                      points=[(l * sp.sin(th), sp.cos(w * t) + sp.sin(3 * w * t / 2)
        ...                               - l * sp.cos(th))])
        >>> s.period
        4*pi/w
        """
        from sympy.calculus.util import periodicity

        if self.autonomous:
            return None
        timed = {f for e in self._dynamics for f in e.atoms(sp.Function)
                 if self.t in f.free_symbols}
        stand_ins = {f: sp.Dummy() for f in timed}
        if any(self.t in e.xreplace(stand_ins).free_symbols for e in self._dynamics):
            return None  # t outside a function (a ramp, a polynomial in t)
        periods = [periodicity(f, self.t) for f in timed]
        if not periods or any(p is None or p == 0 for p in periods):
            return None
        base = periods[0]
        multiples = [sp.nsimplify(sp.simplify(p / base)) for p in periods]
        if any(not (m.is_Rational and m > 0) for m in multiples):
            return None  # incommensurate periods: no common period
        return sp.simplify(base * math.lcm(*(int(m.p) for m in multiples))
                           / math.gcd(*(int(m.q) for m in multiples)))

    @property
    def separable(self) -> bool:
        """``H = T(p) + V(q)``: ``M`` constant, ``b = 0``, no time in the kinetic energy."""
        return bool(not (self.mass_matrix.free_symbols & (set(self.q) | {self.t}))
                    and all(b == 0 for b in self.momentum_offset)
                    and self.kinetic.xreplace({w: 0 for w in self.omega}) == 0)

    @functools.cached_property
    def angle_coordinates(self) -> tuple[bool, ...]:
        """For each coordinate, whether it is an angle: whether the description depends on it
        only through its sine and cosine (``theta``, not ``r`` or a cart's ``x``)."""
        exprs = [self.lagrangian, self.dissipation, *self.generalized_forces,
                 *(c for point in self.points for c in point)]
        angles = []
        for qi in self.q:
            stand_in = {sp.sin(qi): sp.Dummy(), sp.cos(qi): sp.Dummy()}
            angles.append(all(qi not in sp.expand_trig(e).subs(stand_in).free_symbols
                              for e in exprs))
        return tuple(angles)

    @property
    def euler_lagrange(self) -> sp.Eq:
        """``M(q, t) q'' = forcing``, with ``q''`` written ``<q>_ddot``."""
        acc = sp.Matrix([sp.Symbol(f"{qi.name}_ddot", real=True) for qi in self.q])
        return sp.Eq(self.mass_matrix * acc, self.forcing)

    @functools.cached_property
    def inverse_mass_matrix(self) -> sp.Matrix:
        """``M^-1`` (symbolic; for display and small systems)."""
        if self.n > 3:
            raise ValueError(f"the symbolic inverse mass matrix of {self.n} coordinates is "
                             "refused beyond 3 (its determinant grows like n!); the numeric "
                             "layer solves M x = b instead")
        return self.mass_matrix.inv().applyfunc(sp.simplify)

    @functools.cached_property
    def hamiltonian(self) -> sp.Expr:
        """``H(q, p, t) = 1/2 (p - b)^T M^-1 (p - b) - L_0`` (Legendre transform of ``L``)."""
        shifted = self.p - self.momentum_offset
        rest = self.lagrangian.xreplace({w: 0 for w in self.omega})
        return sp.expand((shifted.T * self.inverse_mass_matrix * shifted)[0, 0] / 2 - rest)

    @functools.cached_property
    def hamilton_equations(self) -> tuple[sp.Matrix, sp.Matrix]:
        """``(dq/dt, dp/dt) = (dH/dp, -dH/dq + Q)``, ``Q`` at ``q' = dH/dp``."""
        return hamilton_equations_of(self)

    def legendre_transform(self) -> sp.Expr:
        """``q' . p - L`` in ``(q, q')``: ``1/2 q'^T M q' - L_0``."""
        return legendre_transform_of(self)

    # ---- equilibria ----------------------------------------------------------------
    def _require_autonomous(self, what: str) -> None:
        if not self.autonomous:
            raise ValueError(f"{what} of {self.name}: refused, because its equations depend on "
                             "the time t (a moving pivot or a drive), so a state at rest does "
                             "not stay at rest; for a periodic drive, look at the stroboscopic "
                             "map instead")

    def equilibrium_equations(self) -> sp.Matrix:
        """``forcing`` at ``q' = 0``: zero exactly at the equilibria."""
        self._require_autonomous("The equilibria")
        return self.forcing.xreplace({w: 0 for w in self.omega}).applyfunc(sp.simplify)

    def equilibria(self, subs: dict | None = None) -> list[SystemEquilibrium]:
        """The equilibria SymPy's ``solve`` finds, each with its Jacobian.

        ``subs`` gives values to some parameters first (solving is then easier).
        """
        equations = self.equilibrium_equations()
        if subs:
            equations = equations.xreplace(dict(subs))
        solutions = sp.solve(list(equations), list(self.q), dict=True)
        found = []
        for solution in solutions:
            point = tuple(sp.simplify(solution.get(qi, qi)) for qi in self.q)
            if any(c.is_real is False for c in point):
                continue
            at = dict(zip(self.q, point)) | dict(subs or {})
            if sp.simplify(self.mass_matrix.xreplace(at).det()) == 0:
                continue  # where the coordinates fail (r = 0 of polar coordinates)
            found.append(self.equilibrium_at(point, subs))
        return found

    def equilibrium_at(self, point, subs: dict | None = None) -> SystemEquilibrium:
        """The equilibrium at ``q* = point``, checked (``forcing(q*, 0) = 0``), with its
        Jacobian ``[[0, I], [M^-1 dF/dq, M^-1 dF/dq']]``."""
        self._require_autonomous("An equilibrium")
        at = dict(zip(self.q, point)) | {w: 0 for w in self.omega} | dict(subs or {})
        residual = self.forcing.xreplace(at).applyfunc(sp.simplify)
        if any(not _vanishes(e) for e in residual):
            raise ValueError(f"`point` {tuple(point)} is not an equilibrium: the forcing there "
                             f"is {list(residual)}")
        inverse = self.mass_matrix.xreplace(at).inv()
        stiffness = (inverse * self.forcing.jacobian(self.q).xreplace(at)).applyfunc(sp.simplify)
        friction = (inverse * self.forcing.jacobian(self.omega).xreplace(at)).applyfunc(
            sp.simplify)
        n = self.n
        jacobian = sp.Matrix(sp.BlockMatrix([[sp.zeros(n), sp.eye(n)], [stiffness, friction]]))
        name = ", ".join(f"{qi} = {sp.sstr(v)}" for qi, v in zip(self.q, point))
        return SystemEquilibrium(name, tuple(point), jacobian, stiffness)

    def __repr__(self) -> str:
        return (f"MechanicalSystem({self.name!r}, coordinates={list(self.q)}, "
                f"parameters={list(self.parameters)})")


def chain_system(n: int) -> MechanicalSystem:
    """The chain of ``n`` links described by its bob positions, derived the general way.

    Same symbols as :func:`~pendulum_lab.symbolic.mechanics.derive_chain` (``n``), so the
    two derivations can be compared entry by entry; default parameters all 1, ``g = 9.81``.
    """
    chain = derive_chain(n)
    defaults = {s: 1.0 for s in (*chain.masses, *chain.lengths)} | {chain.g: 9.81}
    return MechanicalSystem(list(chain.q), defaults, points=chain.positions,
                            masses=list(chain.masses), gravity=chain.g,
                            velocities=list(chain.omega),
                            joints=[(i - 1, i) for i in range(n)],
                            name=f"a chain of {n} links")
