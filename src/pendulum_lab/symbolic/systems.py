"""Symbolic mechanics of any holonomic system a student writes down (SymPy only).

A :class:`MechanicalSystem` is described either by the Cartesian positions of point
masses, as SymPy expressions of the generalized coordinates ``q`` and the time ``t``
(a moving pivot is a position that depends on ``t``), in a plane ``(x, y)`` or in space
``(x, y, z)`` (with the direction of gravity, and optionally a turning frame the points are
written in: :class:`MechanicalSystem`'s ``frame_rotation``), with extra potential terms
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
neither coordinates, velocities, ``t`` nor declared parameters (named), names that collide
(a coordinate named ``t``, or like a parameter, or like a generated velocity ``x_dot`` or
momentum ``p_x``: SymPy would merge them), parameter values that are not real finite
numbers (or break a parameter's declared assumption, such as ``positive``), masses that are
not real, finite and non-negative, functions the equations cannot be generated from (named,
with those accepted: :data:`ACCEPTED_FUNCTIONS`), planar points mixed with points in space,
a gravity direction that is zero or not a vector of numbers, a turning frame for planar points
or one that depends on the motion, and descriptions of more than
:data:`MAX_COORDINATES` coordinates (the derivation would take minutes). A symbol given with
other assumptions than the declared one of the same name (``Symbol("l")`` beside a
``positive`` ``l``), or a name in a string, is the declared symbol. Strings are parsed
without running Python: only numbers, names, arithmetic and the accepted functions.

The mass matrix of points with non-negative masses, ``sum m_k J_k^T J_k``, is positive
semidefinite by construction. A Lagrangian given directly is proved positive where SymPy
decides that the leading minors of its mass matrix are positive under the declared
assumptions; otherwise it is searched for a place where it is not (refused, with the place)
and, if none is found, :attr:`MechanicalSystem.positivity_proved` is False and the
simulators check it along each run (a run that reaches such a place stops there, not
completed, with the reason).

References
----------
.. [G] H. Goldstein, C. Poole, J. Safko, *Classical Mechanics*, 3rd ed., Addison-Wesley
   2002, Sects. 1.4-1.5 and 8.1 (the Legendre transform with velocity-linear terms).
"""

from __future__ import annotations

import ast
import functools
import itertools
import math
import numbers
from dataclasses import dataclass

import sympy as sp
from sympy.parsing.sympy_parser import parse_expr, standard_transformations
from sympy.simplify.fu import TR10i

from .mechanics import Equilibrium, derive_chain, hamilton_equations_of, legendre_transform_of

__all__ = [
    "ACCEPTED_FUNCTIONS",
    "MAX_COORDINATES",
    "MechanicalSystem",
    "SystemEquilibrium",
    "chain_system",
    "parameter_values",
]

#: Random configurations the mass matrix is checked at (numeric rank and definiteness).
_CHECK_POINTS = 3
#: Descriptions with more coordinates are refused: the derivation (expanding and folding the
#: points' squared velocities, then the Euler-Lagrange equations) grows 1.3 to 1.5 times per
#: coordinate. Measured for a chain written as its points (``chain_system(n)``, the worst
#: common case: each point moves with all the coordinates before it) on a 2-core machine
#: shared with other work (load about 11): CPU time 2.1 s for 6 coordinates, 3.9 s for 8,
#: 8.8 s for 10, 12.8 s for 11, 16.3 s for 12 (91 s of wall time). An idle core would pass a
#: minute at about 16, a shared hub already at 12; the kernels generated from the equations
#: grow with them. ``pl.n_pendulum`` builds long chains from their closed form.
MAX_COORDINATES = 12
#: Derivations expected to take longer than this [s] show a progress bar.
PROGRESS_AFTER = 1.0
#: The functions the equations can hold: smooth where defined (the equations need second
#: derivatives of L), each printed by the code generator. By name, for strings and messages.
ACCEPTED_FUNCTIONS = {f.__name__: f for f in (
    sp.sin, sp.cos, sp.tan, sp.sinh, sp.cosh, sp.tanh, sp.exp, sp.log, sp.asin, sp.acos,
    sp.atan, sp.atan2, sp.sqrt)}
_ACCEPTED_CLASSES = frozenset(ACCEPTED_FUNCTIONS.values())
_ACCEPTED_TEXT = (", ".join(ACCEPTED_FUNCTIONS) + ", powers (**) and the constants pi and E")
#: The nodes a string may hold (checked before SymPy reads it; no attribute, index, call of
#: anything but an accepted function by name, or literal other than a number).
_STRING_NODES = (ast.Expression, ast.BinOp, ast.UnaryOp, ast.Call, ast.Name, ast.Load,
                 ast.Constant, ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow, ast.USub,
                 ast.UAdd)
#: The largest number a string may raise to a power (a larger one could take SymPy forever).
_LARGEST_EXPONENT = 100
#: Search grid of a mass matrix not proved positive: each coordinate (and t) at these
#: values (positive ones only for a coordinate declared positive).
_SEARCH_VALUES = (-30.0, -10.0, -3.0, -1.0, -0.3, 0.3, 1.0, 3.0, 10.0, 30.0)
_SEARCH_POINTS = 4000
#: Random places in [-1, 1] per coordinate that Newton's method also starts from (each with
#: its mirror image), for the equilibria of points in a turning frame (besides the origin).
_NEWTON_STARTS = 8


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


def _sequence(name: str, values, what: str) -> list:
    """``values`` as a list, refusing a single expression, number or string where a sequence
    of ``what`` is expected."""
    if isinstance(values, (str, bytes, sp.Basic, numbers.Number)) or not hasattr(
            values, "__iter__"):
        raise TypeError(f"`{name}` must be a sequence of {what}, got {values!r} "
                        f"({type(values).__name__})")
    return list(values)


def _parse(name: str, text: str, names: dict) -> sp.Expr:
    """The expression a string writes, read without running Python: numbers, the names in
    ``names`` (and any other, refused later as undeclared), arithmetic, and calls of the
    accepted functions by name."""
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError:
        raise ValueError(f"`{name}` = {text!r} is not an expression (write products with *, "
                         "powers with **)") from None
    for node in ast.walk(tree):
        allowed = isinstance(node, _STRING_NODES) and not (
            isinstance(node, ast.Constant) and not isinstance(node.value, (int, float)))
        if isinstance(node, ast.Call):
            allowed = (isinstance(node.func, ast.Name) and node.func.id in ACCEPTED_FUNCTIONS
                       and not node.keywords)
        if isinstance(node, ast.Name) and node.id.startswith("_"):
            allowed = False
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Pow) and not any(
                isinstance(inner, ast.Name) for inner in ast.walk(node.right)):
            # SymPy computes a power of whole numbers exactly: 9**9**9 would not end
            exponent = node.right.operand if isinstance(node.right, ast.UnaryOp) else node.right
            allowed = (isinstance(exponent, ast.Constant)
                       and isinstance(exponent.value, (int, float))
                       and abs(exponent.value) <= _LARGEST_EXPONENT)
        if not allowed:
            raise ValueError(
                f"`{name}` = {text!r} holds {ast.unparse(node) if node is not tree else text!r}"
                ", which a description cannot: a string may hold numbers, names of coordinates,"
                f" velocities, t and parameters, + - * / ** and the functions {_ACCEPTED_TEXT}")
    local = dict(names) | dict(ACCEPTED_FUNCTIONS) | {"pi": sp.pi, "E": sp.E}
    return parse_expr(text, local_dict=local, global_dict={"__builtins__": {}, **{
        k: getattr(sp, k) for k in ("Symbol", "Integer", "Float", "Rational")}},
        transformations=standard_transformations)


def _require_smooth(name: str, expr: sp.Expr) -> None:
    """Refuse what the equations cannot be generated from: other functions than the accepted
    ones (named), and numbers that are not real and finite."""
    for node in sp.preorder_traversal(expr):
        if isinstance(node, (sp.Symbol, sp.Add, sp.Mul, sp.Pow)):
            continue
        if node in (sp.pi, sp.E):
            continue
        if isinstance(node, sp.Number):
            if not (node.is_real and node.is_finite):
                raise ValueError(f"`{name}` holds {node}: numbers must be real and finite")
            continue
        if node is sp.I:
            raise ValueError(f"`{name}` holds {node}: numbers must be real and finite")
        if isinstance(node, sp.NumberSymbol):
            raise ValueError(f"`{name}` holds the constant {node}: the constants accepted are "
                             "pi and E (give another as a number)")
        if isinstance(node, sp.Function) and node.func in _ACCEPTED_CLASSES:
            continue
        what = type(node).__name__ if isinstance(node, sp.Function) else sp.sstr(node)
        why = ("an undefined function" if isinstance(node, sp.core.function.AppliedUndef)
               else "not smooth everywhere, or not a function the code generator prints")
        raise ValueError(
            f"`{name}` holds {what} ({why}): the equations need the second derivatives of the "
            f"description, so it may use only {_ACCEPTED_TEXT}")


def _progress(items, label: str, expected: float):
    """``items``, with a progress bar when the work is expected to take over
    :data:`PROGRESS_AFTER` seconds."""
    if expected < PROGRESS_AFTER:
        return items
    from tqdm.auto import tqdm

    return tqdm(items, desc=label, mininterval=0.5)


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
    points : sequence of (x, y) pairs or of (x, y, z) triples of expressions, optional
        Cartesian positions of point masses, functions of ``q`` and ``t``: all in a plane, or
        all in space (not a mixture).
    masses : sequence of expressions, optional
        One mass per point (numbers or parameter symbols).
    gravity : expression, optional
        ``g``: the potential ``sum m_i g y_i`` of planar points (``y`` up), ``sum m_i g z_i``
        of points in space (``z`` up). None: no gravity.
    gravity_direction : sequence of numbers, optional
        The direction gravity pulls, one entry per axis of the points (not zero; its length
        does not matter): the potential is ``-sum m_i g d . r_i`` with ``d`` made a unit
        vector. By default ``(0, -1)`` in a plane, ``(0, 0, -1)`` in space.
    frame_rotation : sequence of three expressions, optional
        For points in space written in a turning frame (a laboratory on the Earth): the
        frame's angular velocity ``w`` [rad/s] in its own axes, numbers or expressions of
        parameters, about an axis through the origin. The kinetic energy is built from the
        inertial velocities ``r' + w x r``, so the Coriolis and centrifugal forces follow
        from the derivation; ``kinetic`` is then ``1/2 m |r'|^2`` as seen in the frame, and
        ``potential`` holds the centrifugal potential ``-1/2 m |w x r|^2`` besides
        gravity's, so that ``T + V`` is the conserved Hamiltonian (Jacobi's integral).
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
    dimensions : int
        2 for planar points (and for a system given by its Lagrangian), 3 for points in
        space.
    frame_rotation : list of sympy.Expr or None
        The turning frame's angular velocity, as given.
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
                 joints=None, springs=None, name: str = "a mechanical system",
                 gravity_direction=None, frame_rotation=None):
        self.q = sp.Matrix(_symbol_list("coordinates", coordinates))
        self.n = n = len(self.q)
        if n > MAX_COORDINATES:
            raise ValueError(
                f"`coordinates` holds {n} coordinates: refused beyond {MAX_COORDINATES}, because "
                "the derivation grows about 1.4 times per coordinate (a chain written as its "
                "points took 16 s of CPU time for 12 coordinates, and over a minute on a "
                "shared machine); for a chain of pendulums use pl.n_pendulum(n), built from "
                "its closed form")
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
        self._require_distinct_names()
        self._declared = {s.name: s for s in (*self.q, *self.omega, *self.parameters, self.t)}

        if (lagrangian is None) == (points is None):
            raise TypeError("give exactly one of `points` (with `masses`) and `lagrangian`")
        if points is not None:
            self._energies_of_points(points, masses, gravity, potential, gravity_direction,
                                     frame_rotation)
        else:
            if potential != 0 or gravity is not None or masses is not None:
                raise TypeError("`potential`, `gravity` and `masses` go with `points`; a "
                                "`lagrangian` contains its potential")
            if gravity_direction is not None or frame_rotation is not None:
                raise TypeError("`gravity_direction` and `frame_rotation` go with `points`; a "
                                "`lagrangian` contains its potential and its frame")
            self._energies_of_lagrangian(lagrangian)
        self.joints = self._pairs("joints", joints)
        self.springs = self._pairs("springs", springs)
        if joints is None and springs is None and self.points:
            self._infer_suspension()
        self.dissipation = self._expr("dissipation", dissipation)
        self.generalized_forces = self._forces_with_dissipation(forces)
        self.forced = any(f != 0 for f in self.generalized_forces)
        self._require_quadratic()
        self.positivity_proved = self._prove_positive()
        self.check_values(self.defaults)

    def _energies_of_points(self, points, masses, gravity, potential, gravity_direction,
                            frame_rotation) -> None:
        """The points, masses, kinetic and potential energies and the Lagrangian of a system
        given by its points (``T`` of the points' velocities, ``V`` of gravity and
        ``potential``)."""
        name = self.name
        points = [self._point(i, point) for i, point in
                  enumerate(_sequence("points", points, "(x, y) or (x, y, z) tuples"))]
        if points and any(len(point) != len(points[0]) for point in points):
            odd = next(i for i, point in enumerate(points) if len(point) != len(points[0]))
            raise ValueError(
                f"`points[{odd}]` has {len(points[odd])} coordinates and `points[0]` "
                f"{len(points[0])}: give every point as (x, y) (a planar system) or every "
                "point as (x, y, z) (in space), not a mixture")
        masses = [] if masses is None else _sequence("masses", masses, "masses")
        if len(masses) != len(points):
            raise ValueError(f"`masses` must hold one mass per point ({len(points)})")
        self.points = points
        self.dimensions = len(points[0]) if points else 2
        self.masses = [self._mass(i, m) for i, m in enumerate(masses)]
        self.frame_rotation = self._frame_rotation(frame_rotation)
        expected = 0.05 * 1.5 ** max(0, max(
            len(c.free_symbols & set(self.q)) for point in points for c in point))
        kinetic = sp.Add(*(m * _tidy(sum(v ** 2 for v in self._inertial_velocity(point)))
                           / 2 for m, point in _progress(
                               list(zip(self.masses, points)),
                               f"kinetic energy of {name} (point by point)",
                               expected * len(points))))
        if self.frame_rotation is not None:
            # In the turning frame: T = 1/2 m |r'|^2 as seen there, and the rest of the
            # inertial kinetic energy (velocity-linear Coriolis part, centrifugal part at
            # rest) stays in L, the centrifugal part counted as potential energy below.
            inertial = kinetic
            kinetic = sp.Add(*(m * _tidy(sum(self._rate(c) ** 2 for c in point)) / 2
                               for m, point in zip(self.masses, points)))
        weight = 0 if gravity is None else self._expr("gravity", gravity)
        down = self._gravity_direction(gravity_direction, gravity)
        potential = self._expr("potential", potential)
        if down is None:  # straight down the last axis (y in a plane, z in space)
            potential += sp.Add(*(m * weight * point[-1]
                                  for m, point in zip(self.masses, points)))
        else:
            potential -= sp.Add(*(m * weight * sum(d * c for d, c in zip(down, point))
                                  for m, point in zip(self.masses, points)))
        self.potential = sp.expand(potential)
        self.kinetic = sp.expand(kinetic)
        self.lagrangian = self.kinetic - self.potential
        if self.frame_rotation is not None:
            self.lagrangian = sp.expand(inertial) - self.potential
            self.potential = -self.lagrangian.xreplace({w: 0 for w in self.omega})

    def _energies_of_lagrangian(self, lagrangian) -> None:
        """The kinetic and potential energies of a system given by its Lagrangian (``T`` its
        part quadratic in the velocities, ``V`` minus its part at rest)."""
        self.points, self.masses = [], []
        self.dimensions = 2
        self.frame_rotation = None
        self.lagrangian = sp.expand(self._expr("lagrangian", lagrangian))
        self._require_quadratic()
        rest = self.lagrangian.xreplace({w: 0 for w in self.omega})
        self.kinetic = sp.expand(self.lagrangian - rest)
        self.potential = -rest

    def _forces_with_dissipation(self, forces) -> sp.Matrix:
        """The generalized forces: ``forces`` (one expression per coordinate, or none) minus
        the derivatives of the dissipation function by the velocities."""
        n = self.n
        if forces is None:
            extra = sp.zeros(n, 1)
        else:
            forces = _sequence("forces", forces, "expressions, one per coordinate")
            if len(forces) != n:
                raise ValueError(f"`forces` must hold {n} expressions (one per coordinate), "
                                 f"got {len(forces)}")
            extra = sp.Matrix([self._expr(f"forces[{i}]", f) for i, f in enumerate(forces)])
        return (extra - sp.Matrix([self.dissipation.diff(w)
                                   for w in self.omega])).applyfunc(sp.expand)

    # ---- input -------------------------------------------------------------------
    def _require_distinct_names(self) -> None:
        """Refuse two roles under one name: SymPy and the generated code would merge them
        (a coordinate ``p_a`` beside ``a``, whose momentum is ``p_a``; a parameter ``t``)."""
        roles = [("t", "the time")]
        roles += [(qi.name, f"coordinate {qi.name}") for qi in self.q]
        roles += [(w.name, f"the velocity of {qi.name}") for qi, w in zip(self.q, self.omega)]
        roles += [(p.name, f"the momentum of {qi.name}") for qi, p in zip(self.q, self.p)]
        roles += [(s.name, f"parameter {s.name}") for s in self.parameters]
        for (first, role), (second, other) in itertools.combinations(roles, 2):
            if first == second:
                raise ValueError(
                    f"the name {first!r} is both {role} and {other}: SymPy would take them for "
                    "one symbol and the equations would be wrong; rename "
                    f"{'the coordinate or parameter' if role == 'the time' else 'one of them'}"
                    " (a coordinate x has the velocity x_dot and the momentum p_x)")

    def _expr(self, name: str, value) -> sp.Expr:
        """``value`` as a SymPy expression of declared symbols only.

        A symbol named like a declared one (with other assumptions, or from a string) is the
        declared one."""
        if isinstance(value, str):
            expr = _parse(name, value, self._declared)
        else:
            try:
                expr = sp.sympify(value, strict=True)
            except (sp.SympifyError, TypeError):
                raise TypeError(f"`{name}` must be a SymPy expression or a number, got "
                                f"{value!r} ({type(value).__name__})") from None
        if not isinstance(expr, sp.Expr):
            raise TypeError(f"`{name}` must be a SymPy expression or a number, got {value!r} "
                            f"({type(value).__name__})")
        expr = expr.xreplace({s: self._declared[s.name] for s in expr.free_symbols
                              if isinstance(s, sp.Symbol) and s.name in self._declared})
        known = set(self.q) | set(self.omega) | set(self.parameters) | {self.t}
        unknown = expr.free_symbols - known
        if unknown:
            raise ValueError(
                f"`{name}` uses {', '.join(sorted(map(str, unknown)))}, which "
                f"{'is' if len(unknown) == 1 else 'are'} neither a coordinate "
                f"({', '.join(map(str, self.q))}), a velocity, t, nor a declared parameter "
                f"({', '.join(map(str, self.parameters)) or 'none'}): declare "
                f"{'it' if len(unknown) == 1 else 'them'} in `parameters` with a default value")
        _require_smooth(name, expr)
        return expr

    def _point(self, index: int, point) -> tuple:
        """Point ``index`` as an ``(x, y)`` pair or an ``(x, y, z)`` triple of expressions."""
        name = f"points[{index}]"
        if isinstance(point, (str, sp.Basic, numbers.Number)) or not hasattr(point, "__len__"):
            raise TypeError(f"`{name}` must be an (x, y) pair or an (x, y, z) triple of "
                            f"expressions, got {point!r}: write points=[(x0, y0), (x1, y1), "
                            "...], one tuple per point")
        if len(point) not in (2, 3):
            raise ValueError(f"`{name}` must be an (x, y) pair (a point in a plane) or an "
                             f"(x, y, z) triple (in space), got {len(point)} entries")
        return tuple(self._expr(name, c) for c in point)

    def _constant_vector(self, name: str, value, what: str) -> list:
        """``value`` as a list of :attr:`dimensions` expressions of the parameters only."""
        size = self.dimensions
        if isinstance(value, (str, sp.Basic, numbers.Number)) or not hasattr(value, "__len__"):
            raise TypeError(f"`{name}` must be a sequence of {size} numbers ({what}), got "
                            f"{value!r} ({type(value).__name__})")
        if len(value) != size:
            raise ValueError(f"`{name}` must hold {size} entries, one per axis of the points "
                             f"({what}), got {len(value)}")
        entries = []
        for k, entry in enumerate(value):
            if isinstance(entry, bool):
                raise TypeError(f"`{name}[{k}]` must be a number, got {entry!r}")
            if isinstance(entry, numbers.Number) and not (
                    isinstance(entry, numbers.Real) and math.isfinite(float(entry))):
                raise ValueError(f"`{name}[{k}]` must be a real finite number, got {entry!r}")
            expr = self._expr(f"{name}[{k}]", entry)
            if expr.free_symbols & (set(self.q) | set(self.omega) | {self.t}):
                raise ValueError(f"`{name}[{k}]` = {expr} must be a number or an expression "
                                 "of parameters: it does not change with the motion")
            entries.append(expr)
        return entries

    def _gravity_direction(self, direction, gravity) -> list | None:
        """The unit vector gravity pulls along, or None for straight down the last axis."""
        if direction is None:
            return None
        if gravity is None:
            raise TypeError("`gravity_direction` goes with `gravity` (its strength g); give "
                            "both, or neither for a system without gravity")
        entries = self._constant_vector("gravity_direction", direction,
                                        "the direction gravity pulls the points")
        if any(e.free_symbols for e in entries):
            raise ValueError("`gravity_direction` must hold numbers (a fixed direction), got "
                             f"{entries}")
        length = sp.sqrt(sp.Add(*(e ** 2 for e in entries)))
        if _vanishes(length):
            raise ValueError(f"`gravity_direction` = {tuple(direction)} is zero: it has no "
                             "direction; give the way gravity pulls, such as (0, 0, -1)")
        return [e / length for e in entries]

    def _frame_rotation(self, rotation) -> list | None:
        """The angular velocity of the frame the points are written in, or None (inertial)."""
        if rotation is None:
            return None
        if self.dimensions != 3:
            raise ValueError("`frame_rotation` needs points in space, (x, y, z): a rotating "
                             "frame turns about an axis; write a planar system's points with "
                             "z = 0 to give one")
        return self._constant_vector("frame_rotation", rotation,
                                     "the angular velocity of the points' frame [rad/s]")

    def _inertial_velocity(self, point) -> list:
        """The velocity of ``point`` in an inertial frame: ``r' + w x r`` when the points are
        written in a frame turning at ``w`` (:attr:`frame_rotation`), else ``r'``."""
        rates = [self._rate(c) for c in point]
        if self.frame_rotation is None:
            return rates
        (wx, wy, wz), (x, y, z) = self.frame_rotation, point
        return [rates[0] + wy * z - wz * y, rates[1] + wz * x - wx * z,
                rates[2] + wx * y - wy * x]

    def _mass(self, index: int, mass) -> sp.Expr:
        """Mass ``index``: a real, finite, non-negative number or expression of parameters."""
        name = f"masses[{index}]"
        if isinstance(mass, numbers.Number) and not isinstance(mass, numbers.Real):
            raise ValueError(f"`{name}` must be a real mass, got {mass!r}")
        if isinstance(mass, numbers.Real) and not isinstance(mass, bool) and not math.isfinite(
                float(mass)):
            raise ValueError(f"`{name}` must be a finite mass, got {mass!r}")
        expr = self._expr(name, mass)
        if expr.free_symbols & (set(self.q) | set(self.omega) | {self.t}):
            raise ValueError(f"`{name}` = {expr} must be a number or an expression of "
                             "parameters: a mass does not change with the motion")
        if expr.is_negative:
            raise ValueError(f"`{name}` = {expr} must be non-negative")
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

        def fixed_distance(*differences) -> bool:
            if not set().union(*(sp.sympify(d).free_symbols for d in differences)) & moved:
                return False  # nothing between them moves: not an arm
            square = sp.trigsimp(sp.expand(sum(d ** 2 for d in differences)))
            return square != 0 and not square.free_symbols & moved

        given = list(self.points)
        origin = (0,) * self.dimensions
        for k, point in enumerate(given):
            anchors = [(j, given[j]) for j in range(k)] + [(-1, origin)]
            hung = next((j for j, anchor in anchors
                         if fixed_distance(*(c - a for c, a in zip(point, anchor)))), None)
            if hung is not None:
                self.joints.append((hung, k))
                continue
            pivot = tuple(sp.Add(*(term for term in sp.Add.make_args(sp.expand(c))
                                   if not term.free_symbols & moved)) for c in point)
            if any(c != 0 for c in pivot) and fixed_distance(
                    *(c - a for c, a in zip(point, pivot))):
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

    @functools.cached_property
    def _mass_function(self):
        """``M`` as a NumPy function of ``(q, t, parameters)``, each entry broadcast."""
        import numpy as np

        entries = sp.lambdify((*self.q, self.t, *self.parameters), list(self.mass_matrix),
                              modules="numpy", cse=True)
        n = self.n

        def mass(q, t, params):
            values = entries(*np.moveaxis(q, -1, 0), t, *params)
            shape = np.broadcast_shapes(*(np.shape(v) for v in values), np.shape(q)[:-1],
                                        np.shape(t))
            stacked = np.stack([np.broadcast_to(np.asarray(v, dtype=float), shape)
                                for v in values], axis=-1)
            return stacked.reshape(*shape, n, n)

        return mass

    @functools.cached_property
    def _position_function(self):
        """The points' coordinates, flat, as a NumPy function of ``(q, t, parameters)``."""
        return sp.lambdify((*self.q, self.t, *self.parameters),
                           [c for point in self.points for c in point], modules="numpy",
                           cse=True)

    def _placed(self, q, t, params) -> bool:
        """Whether the points have real, finite positions at ``(q, t)`` (True without points)."""
        import numpy as np

        if not self.points:
            return True
        with np.errstate(all="ignore"):
            values = self._position_function(*q, t, *params)
        return bool(all(np.all(np.isfinite(np.asarray(v, dtype=complex))) and
                        np.all(np.imag(np.asarray(v, dtype=complex)) == 0) for v in values))

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        for made in ("_mass_function", "_position_function"):
            state.pop(made, None)  # a lambdified function: made again when used
        return state

    def _prove_positive(self) -> bool:
        """Whether ``M`` is positive semidefinite everywhere, proved symbolically.

        Points: ``M = sum_k m_k J_k^T J_k`` with the masses non-negative (checked, here and at
        every model's values) is positive semidefinite by construction. A Lagrangian given
        directly: if SymPy decides that every leading minor is positive under the declared
        assumptions of the coordinates and parameters (Sylvester's criterion; tried up to
        three coordinates, the determinants grow like n!). Otherwise False: the numeric checks
        (:meth:`check_values`, and the simulators along each run) stand in.
        """
        if self.points:
            return True
        if self.n > 3:
            return False
        mass = self.mass_matrix
        return all(sp.factor(mass[:k, :k].det()).is_positive for k in range(1, self.n + 1))

    @staticmethod
    def check_assumptions(symbol: sp.Symbol, value) -> None:
        """Refuse a value (a number, or an array of them: every entry) that breaks what
        ``symbol`` is declared to be (``positive``, ``nonnegative``, ...)."""
        import numpy as np

        value = np.asarray(value, dtype=float)
        for assumption, holds in (("positive", value > 0), ("nonnegative", value >= 0),
                                  ("negative", value < 0), ("nonpositive", value <= 0),
                                  ("nonzero", value != 0)):
            if symbol.assumptions0.get(assumption) and not np.all(holds):
                wrong = value[~holds] if value.ndim else value
                raise ValueError(f"`{symbol}` must be {assumption.replace('non', 'non-')} "
                                 f"(it is declared {assumption}), got {np.ravel(wrong)[0]:g}")

    def check_values(self, values: dict) -> None:
        """Refuse parameter values (``{symbol: float}``, all parameters) that break a declared
        assumption (a ``positive`` symbol at 0), give a mass that is negative, or a mass matrix
        that is singular (redundant coordinates) or not positive definite where checked."""
        import numpy as np

        for symbol in self.parameters:
            self.check_assumptions(symbol, values[symbol])
        for k, mass in enumerate(self.masses):
            number = float(mass.xreplace(values))
            if not (math.isfinite(number) and number >= 0):
                raise ValueError(f"`masses[{k}]` = {mass} must be non-negative and finite, "
                                 f"got {number:g} at these parameter values")
        mass = self.mass_matrix
        if all(e == 0 for e in mass):
            raise ValueError("the mass matrix is zero: the description has no kinetic energy "
                             f"in the velocities ({', '.join(map(str, self.omega))})")
        params = tuple(values[s] for s in self.parameters)
        rng = np.random.default_rng(20261202)
        points = rng.uniform(0.3, 1.3, (_CHECK_POINTS, self.n + 1))
        for point in points:
            with np.errstate(all="ignore"):
                matrix = self._mass_function(point[:-1], point[-1], params)
                placed = self._placed(point[:-1], point[-1], params)
            if not (np.all(np.isfinite(matrix)) and placed):
                # outside the coordinates' domain (log r at r < 0; a height sqrt(l^2 - x^2 -
                # y^2) of x^2 + y^2 > l^2, which the squared velocities no longer show)
                continue
            values_, vectors = np.linalg.eigh(matrix)
            scale = max(abs(values_).max(), 1e-300)
            if values_[0] <= 1e-10 * scale:
                null = vectors[:, 0]
                if abs(values_[0]) <= 1e-10 * scale:
                    named = [str(qi) for qi, c in zip(self.q, null) if abs(c) > 1e-6]
                    raise ValueError(
                        f"the mass matrix is singular: the coordinates "
                        f"{', '.join(named)} are redundant (a motion combining them, with "
                        f"weights {np.round(null[np.abs(null) > 1e-6], 3).tolist()}, has no "
                        "kinetic energy); describe the system with fewer coordinates")
                raise ValueError("the mass matrix is not positive definite (a kinetic energy "
                                 "that can be negative): check the masses' signs")
        if not self.positivity_proved:
            self._search_indefinite(params)

    def _search_indefinite(self, params: tuple) -> None:
        """Refuse a mass matrix found not positive definite on a grid of states (each
        coordinate and t among :data:`_SEARCH_VALUES`, positive ones only where declared
        positive; a random selection of :data:`_SEARCH_POINTS` when the grid is larger)."""
        import numpy as np

        axes = [[v for v in _SEARCH_VALUES if v > 0] if s.is_positive else list(_SEARCH_VALUES)
                for s in (*self.q, self.t)]
        if self.t not in self.mass_matrix.free_symbols:
            axes[-1] = [0.0]
        size = math.prod(len(a) for a in axes)
        if size <= _SEARCH_POINTS:
            grid = np.array(list(itertools.product(*axes)), dtype=float)
        else:
            rng = np.random.default_rng(20261207)
            grid = np.column_stack([rng.choice(a, _SEARCH_POINTS) for a in axes])
        with np.errstate(all="ignore"):
            matrices = self._mass_function(grid[:, :-1], grid[:, -1], params)
        usable = np.all(np.isfinite(matrices), axis=(-2, -1))
        if not usable.any():
            return
        lowest = np.linalg.eigvalsh(matrices[usable])[:, 0]
        scale = np.maximum(np.abs(matrices[usable]).max(axis=(-2, -1)), 1e-300)
        bad = np.flatnonzero(lowest <= 1e-12 * scale)
        if bad.size:
            at = grid[usable][bad[0]]
            depends = self.mass_matrix.free_symbols
            place = ", ".join(f"{s} = {v:g}" for s, v in zip((*self.q, self.t), at)
                              if s in depends)
            raise ValueError(
                f"the mass matrix is not positive definite at {place} (its smallest "
                f"eigenvalue there is {lowest[bad[0]]:.3g}): the kinetic energy would be "
                "negative or zero for some motion. A Lagrangian must have L = 1/2 q'^T M q' + "
                "... with M positive definite wherever the system goes; declare a coordinate "
                "positive (sp.Symbol('x', positive=True)) if only positive values are meant")

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

        Points written in a turning frame (:attr:`frame_rotation`): SymPy's ``solve`` did not
        finish in five minutes on the Foucault pendulum's equations (a square root, and
        centrifugal terms some 1e-10 of gravity), so their equilibria are found numerically
        instead, by Newton's method from the origin and from :data:`_NEWTON_STARTS` other
        places and their mirror images, at the values ``subs`` gives every parameter; each is
        then checked and linearised as :meth:`equilibrium_at` does.
        """
        if self.frame_rotation is not None:
            return self._equilibria_by_newton(subs)
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

    def _equilibria_by_newton(self, subs) -> list[SystemEquilibrium]:
        """The equilibria Newton's method finds from the origin and from random places
        (see :meth:`equilibria`), every parameter given a value in ``subs``."""
        import numpy as np

        values = {s: v for s, v in dict(subs or {}).items() if s in self.parameters}
        missing = [str(s) for s in self.parameters if s not in values]
        if missing:
            raise ValueError(f"the equilibria of {self.name} (points in a turning frame) are "
                             f"found numerically: give every parameter a value in `subs`; "
                             f"missing {missing}")
        rest = {w: 0 for w in self.omega}
        forcing = self.forcing.xreplace(rest).xreplace(values)
        residual = sp.lambdify(list(self.q), list(forcing), modules="numpy", cse=True)
        slope = sp.lambdify(list(self.q), forcing.jacobian(self.q), modules="numpy", cse=True)
        rng = np.random.default_rng(20261207)
        places = rng.uniform(-1, 1, (_NEWTON_STARTS, self.n))
        starts = np.vstack([np.zeros(self.n), places, -places])  # mirrored: symmetric pairs
        points = []
        for q in starts:
            with np.errstate(all="ignore"):
                for _ in range(50):
                    try:
                        step = np.linalg.solve(np.array(slope(*q), dtype=float),
                                               -np.array(residual(*q), dtype=float))
                    except (np.linalg.LinAlgError, TypeError, ValueError):
                        break
                    q = q + step
                    if not np.all(np.isfinite(q)) or np.max(np.abs(step)) < 1e-15 * (
                            1 + np.max(np.abs(q))):
                        break
                value = np.array(residual(*q), dtype=complex)
            if not (np.all(np.isfinite(value)) and np.max(np.abs(value)) < 1e-10
                    and np.all(value.imag == 0)):
                continue
            if any(np.allclose(q, other, atol=1e-9) for other in points):
                continue
            points.append(q)
        found = []
        for q in points:
            at = dict(zip(self.q, q)) | values
            matrix = np.array(self.mass_matrix.xreplace(at).evalf(), dtype=complex)
            if not np.all(np.isfinite(matrix)) or abs(np.linalg.det(matrix)) < 1e-12:
                continue  # where the coordinates fail
            found.append(self.equilibrium_at(tuple(float(c) for c in q), values))
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
