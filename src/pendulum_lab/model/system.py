"""Numeric models of any mechanical system: a :class:`SystemModel` is a
:class:`~pendulum_lab.PendulumModel` whose equations come from a
:class:`~pendulum_lab.symbolic.systems.MechanicalSystem` instead of a chain.

It has the methods of a chain's model, so :func:`~pendulum_lab.simulate`,
:func:`~pendulum_lab.step` and the methods accept it; each numeric method also takes the
time ``t`` (a moving pivot makes the momenta and the energies depend on it; ``t`` may be
left out where nothing depends on it). ``theta`` names the generalized coordinates, as for
a chain, whatever they are (a length, a cart's position). The kernels come from the one
generator of :mod:`pendulum_lab.codegen.kernels`.

:func:`mechanical_system` builds one from a description; the systems the course names (the
elastic, Kapitza, cart, spherical and Foucault pendulums) are built in
:mod:`~pendulum_lab.model.named_systems`.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import numbers

import numpy as np
import sympy as sp

from .. import validation as check
from ..codegen.kernels import load_system_kernels
from ..symbolic.systems import MechanicalSystem, parameter_values
from .drawing import Drawing
from .family import FamilyMembers, broadcast_values
from .numeric import compiled_system
from .pendulum import PendulumModel, family_parameter

__all__ = ["SystemFamily", "SystemModel", "mechanical_system", "positive_finite", "readable_number"]


class SystemModel(PendulumModel):
    """A :class:`~pendulum_lab.symbolic.systems.MechanicalSystem` with its parameters bound.

    Parameters
    ----------
    system : MechanicalSystem
    values : dict, optional
        Values replacing some of the system's defaults, ``{symbol or name: number}``.
    period : float or sympy expression, optional
        The period of the time dependence [s] (a shaken pivot's): a number, or an
        expression of the parameters (``2*pi/w``). By default the system's own
        (:attr:`MechanicalSystem.period <pendulum_lab.symbolic.systems.MechanicalSystem.period>`),
        if its time dependence is periodic. A number is taken as that many of the system's
        own periods, so that :meth:`replace` of a parameter the time dependence reads (the
        Kapitza pendulum's ``w``) moves it with them.
    start : sequence of float, optional
        The coordinates the simulators and explorers start from by default (zeros if not
        given); the velocities start at zero.
    factory : str, optional
        The call that builds the system (``"pl.elastic_pendulum()"``), for the code an
        instrument copies; None for a system built by :func:`mechanical_system`.

    Attributes
    ----------
    system : MechanicalSystem
        Its symbolic equations (also ``chain``, the attribute the code generator reads).
    n : int
        Number of generalized coordinates.
    factory_units : dict of str -> (callable, callable)
        The parameters its factory takes in another unit than the model holds them (the
        Foucault pendulum's ``lat``: degrees given, radians held), each with two functions:
        one checks a value in the factory's unit and turns it into the model's, the other
        turns a held value back (:meth:`in_factory_units`). :meth:`replace` and
        :meth:`family` take values in the factory's unit. Empty for most systems.
    """

    def __init__(self, system: MechanicalSystem, values: dict | None = None, *,
                 period: float | None = None, start=None, factory: str | None = None):
        if not isinstance(system, MechanicalSystem):
            raise TypeError(f"`system` must be a MechanicalSystem, got {type(system).__name__}")
        given = parameter_values({} if values is None else values)
        by_name = {str(s): s for s in system.parameters}
        unknown = [str(s) for s in given if str(s) not in by_name]
        if unknown:
            raise ValueError(f"`values` names {unknown}, which are not parameters of "
                             f"{system.name}; its parameters are {list(by_name)}")
        values = dict(system.defaults) | {by_name[str(s)]: v for s, v in given.items()}
        if values != system.defaults:  # the constructor checked the defaults
            system.check_values(values)
        if period is not None and not isinstance(period, sp.Basic):
            period = positive_finite("period", period)
        self.system = self.chain = system
        self.n = system.n
        self.forced = system.forced
        self._fn = compiled_system(system)
        self._params = tuple(values[s] for s in system.parameters)
        self._period = _period_rule(system, period, values)
        self._period_value = (None if self._period is None
                              else float(self._period.xreplace(values)))
        if self._period_value is not None and not (math.isfinite(self._period_value)
                                                   and self._period_value > 0):
            raise ValueError(f"the period of {system.name} is {self._period} = "
                             f"{self._period_value} s at these parameter values; it must be "
                             "positive and finite")
        self.start = (np.zeros(self.n) if start is None
                      else check.state_vector("start", start, self.n))
        self.factory = factory
        self.factory_units = {}

    #: Its coordinates may be lengths or positions: never reduced by whole turns.
    periodic_coordinates = False
    is_chain = False

    # ---- what only a chain has: a clear refusal where a chain's tool asks for it -----------
    def _chain_only(self, attribute: str):
        raise TypeError(
            f"{self.system.name} is a system given by its points or its Lagrangian, not a chain "
            f"of rods, so it has no `{attribute}`: pl.simulate, pl.step, every method that "
            "applies, explore, explore_equilibrium, the simulators and the drawings accept it "
            "(they read `model.drawing` and `model.positions`); the tools written for a "
            "chain's rods (explore_energy among them) refuse it")

    lengths = property(lambda self: self._chain_only("lengths"))
    masses = property(lambda self: self._chain_only("masses"))
    g = property(lambda self: self._chain_only("g"))
    drive_amplitude = property(lambda self: self._chain_only("drive_amplitude"))
    drive_frequency = property(lambda self: self._chain_only("drive_frequency"))

    # ---- what the driver asks ------------------------------------------------------
    @property
    def name(self) -> str:
        return self.system.name

    @property
    def is_conservative(self) -> bool:
        """No forces besides the Lagrangian's (no dissipation)."""
        return not self.system.forced

    @property
    def is_autonomous(self) -> bool:
        return self.system.autonomous

    @property
    def positivity_proved(self) -> bool:
        """Whether the mass matrix is proved positive definite wherever the system goes;
        if not, the simulators check it along each run
        (:attr:`~pendulum_lab.symbolic.systems.MechanicalSystem.positivity_proved`)."""
        return self.system.positivity_proved

    @property
    def drive_period(self) -> float | None:
        """The period of the time dependence [s] at these parameter values (it follows
        :meth:`replace`), or None."""
        return self._period_value

    @property
    def conformal_damping_rate(self):
        """0 without forces; None with (the integrators' conformal methods do not apply)."""
        return 0.0 if self.is_conservative else None

    @property
    def separable(self) -> bool:
        return self.system.separable

    @functools.cached_property
    def hamiltonian_is_energy(self) -> bool:
        """Whether ``H = T + V``: the kinetic energy is quadratic in the velocities and the
        Lagrangian at rest is ``-V``. True without a moving pivot, and for points written in a
        turning frame (the Foucault pendulum: ``T`` and ``V`` as seen in that frame, the
        centrifugal potential in ``V``; ``H`` is Jacobi's integral). Otherwise (a moving
        pivot) ``H - (T + V) = -b q' - 2 T_0``, with ``b`` the momentum offset and ``T_0`` the
        kinetic energy at rest, the points' motion the time imposes."""
        system = self.system
        rest = {w: 0 for w in system.omega}
        # A velocity-linear part of L (b q', the Coriolis terms) drops out of p q' - L.
        kinetic = sp.Poly(system.kinetic, *system.omega)
        return bool(all(sum(powers) == 2 for powers in kinetic.monoms())
                    and sp.expand(system.lagrangian.xreplace(rest) + system.potential) == 0)

    @property
    def damping(self) -> str:
        """The system's forces, in words (for the messages that name a model's damping)."""
        return "none" if self.is_conservative else "Q = " + str(list(
            self.system.generalized_forces))

    @property
    def parameter_values(self) -> dict:
        return dict(zip(self.system.parameters, self._params))

    def kernels(self):
        """The compiled kernels of the system's Hamilton equations (generated on first use)."""
        return load_system_kernels(self.system)

    @property
    def coordinate_names(self) -> tuple[str, ...]:
        """The coordinates' names as people read them (``θ``, ``r``, ``x``, ``l₀``)."""
        return tuple(sp.pretty(qi, use_unicode=True) for qi in self.system.q)

    @property
    def angle_coordinates(self) -> tuple[bool, ...]:
        """For each coordinate, whether it is an angle (the description depends on it only
        through its sine and cosine): the sliders offer angles in ``[-pi, pi]`` rad."""
        return self.system.angle_coordinates

    def _in_model_units(self, changes: dict, *, arrays: bool = False) -> dict:
        """``changes`` with the values of :attr:`factory_units` turned into the model's unit
        (checked as the factory checks them, entry by entry for arrays)."""
        converted = dict(changes)
        for name, (convert, _) in self.factory_units.items():
            if name in changes:
                value = changes[name]
                entries = np.ravel(np.asarray(value)).tolist() if arrays else None
                converted[name] = (np.array([convert(v) for v in entries], dtype=float)
                                   .reshape(np.shape(value))
                                   if arrays and np.ndim(value) else convert(value))
        return converted

    def in_factory_units(self, values: dict) -> dict:
        """``values`` (``{name: number}`` in the units the model holds, as
        :attr:`parameter_values` has them) in the units :meth:`replace` takes."""
        return {name: (self.factory_units[name][1](value) if name in self.factory_units
                       else value) for name, value in values.items()}

    def replace(self, **changes) -> SystemModel:
        """A copy with some parameter values changed (by name), in the units the factory takes
        (:attr:`factory_units`: ``pl.foucault_pendulum().replace(lat=45)`` is at 45 degrees);
        the period follows them (``pl.kapitza_pendulum().replace(w=50).drive_period`` is
        ``2 pi / 50``)."""
        changes = self._in_model_units(changes)
        clock = set(self.clock_parameters) & set(changes)
        if clock and self._period is not None and not self._period.free_symbols:
            raise ValueError(
                f"{sorted(clock)} set{'s' if len(clock) == 1 else ''} how {self.name} depends "
                f"on the time, but its period was given as the number {self._period_value:g} "
                "s and no period could be derived from its equations: build it with `period` "
                "as an expression of the parameters (such as 2*sp.pi/w)")
        copy = SystemModel(self.system, dict(zip(map(str, self.system.parameters),
                                                 self._params)) | changes, period=self._period,
                           start=self.start, factory=self.factory)
        copy.factory_units = dict(self.factory_units)
        return copy

    @property
    def clock_parameters(self) -> tuple[str, ...]:
        """The parameters the time dependence reads (the Kapitza pendulum's ``w``): they set
        the period, which every member of a family and every orbit of a continuation shares,
        so families and continuations keep them (:meth:`replace` changes them)."""
        return self.system.clock_parameters

    @property
    def family_parameters(self) -> tuple[str, ...]:
        """The parameters a family or an orbit's continuation can vary: all but the
        :attr:`clock_parameters`."""
        clock = self.clock_parameters
        return tuple(name for name in map(str, self.system.parameters) if name not in clock)

    def family(self, **values) -> SystemFamily:
        """Copies of this system, one per entry of arrays of parameter values (by name).

        Examples
        --------
        >>> import pendulum_lab as pl
        >>> springs = pl.elastic_pendulum().family(k=[20.0, 39.24, 60.0])
        >>> springs.shape, [round(float(w), 4) for w in springs.member(1).parameter_values.values()]
        ((3,), [1.0, 39.24, 0.75, 9.81])
        """
        return SystemFamily(self, self._in_model_units(values, arrays=True))

    def __reduce__(self):
        return SystemModel, (self.system, dict(zip(map(str, self.system.parameters),
                                                   self._params))), {
            "_period": self._period, "_period_value": self._period_value, "start": self.start,
            "factory": self.factory, "factory_units": self.factory_units}

    @functools.cached_property
    def equilibria(self) -> tuple:
        """The equilibria SymPy finds at these parameter values, least potential energy first.

        A coordinate an equilibrium leaves free (the cart's position ``x``) is set to 0, so
        each point is a number; each name reads ``"r = 0.5, theta = pi"`` (a multiple of pi
        with a small denominator by name, other numbers to 6 digits). An empty tuple if
        SymPy finds none; a ``ValueError`` if the equations depend on the time.
        """
        free = {qi: 0 for qi in self.system.q}
        found = []
        for equilibrium in self.system.equilibria(self.parameter_values):
            point = tuple(float(sp.sympify(c).xreplace(free)) for c in equilibrium.angles)
            name = ", ".join(f"{qi} = {readable_number(v)}"
                             for qi, v in zip(self.system.q, point))
            found.append(dataclasses.replace(
                equilibrium, name=name, angles=point,
                jacobian=equilibrium.jacobian.xreplace(free),
                stiffness_ratio=equilibrium.stiffness_ratio.xreplace(free)))
        return tuple(sorted(found, key=lambda eq: float(self.potential_energy(
            np.array(eq.angles, dtype=float), 0.0))))

    # ---- numeric functions: those of every model (ModelFunctions), with the time ---------
    def _described(self) -> tuple[str, str]:
        coordinates = ", ".join(map(str, self.system.q))
        return (f"{self.system.name} ({self.n} coordinates: {coordinates})",
                f"the equations of {self.system.name} depend on the time")

    def _configuration_time(self, t):
        return self._time(t)  # the points may move with the time (a moving pivot)

    def jacobian(self, theta, p, t=None) -> np.ndarray:
        """Jacobian of :meth:`vector_field` with respect to ``(q, p)``, shape ``(..., 2n, 2n)``."""
        theta, t = self._states("theta", theta), self._time(t)
        mass = self._fn.mass_matrix(theta, self._params, t)
        omega = self.velocities(theta, p, t)
        args = (theta, omega, self._params, t)
        inv_mass = np.linalg.inv(mass)
        dw_dq = -inv_mass @ self._fn.dmomenta_dq(*args)
        rate_w = self._fn.rate_w(*args)
        top = np.concatenate([dw_dq, inv_mass], axis=-1)
        bottom = np.concatenate([self._fn.rate_q(*args) + rate_w @ dw_dq, rate_w @ inv_mass],
                                -1)
        return np.concatenate([top, bottom], axis=-2)

    @property
    def dimensions(self) -> int:
        """3 for points given as ``(x, y, z)`` (in space, ``z`` up by default), else 2."""
        return self.system.dimensions

    def positions(self, theta, t=None) -> tuple[np.ndarray, ...]:
        """Cartesian positions ``(x, y)`` of the points (``(x, y, z)`` for points in space),
        each shape ``(..., points)``."""
        self._require_points()
        xyz = self._fn.positions(self._states("theta", theta), self._params, self._time(t))
        return tuple(xyz[..., k] for k in range(self.dimensions))

    def _require_points(self) -> None:
        if not self._fn.points:
            raise TypeError(f"{self.system.name} was given by its Lagrangian, so it has no "
                            "points to draw: pl.simulate, pl.step and the methods accept it; "
                            "give `points` and `masses` to mechanical_system to draw it")

    @property
    def drawing(self) -> Drawing:
        """The points (discs of area proportional to mass, a massless point as a small mark),
        the rods and springs between them, and which points a drag can place."""
        self._require_points()
        values = self.parameter_values
        masses = tuple(float(sp.sympify(m).xreplace(values)) for m in self.system.masses)
        moved = set(self.system.q)
        movable = tuple(
            None if set().union(*(sp.sympify(c).free_symbols for c in point)) & moved else
            f"point {k} of {self.system.name} does not move with the coordinates (its motion "
            "is prescribed), so dragging it cannot set them; drag a point the coordinates place"
            for k, point in enumerate(self.system.points))
        return Drawing(masses=masses, rods=tuple(self.system.joints),
                       springs=tuple(self.system.springs), movable=movable)

    def place_point(self, point: int, x: float, y: float, theta, t: float = 0.0) -> np.ndarray:
        """The coordinates nearest ``theta`` that put point ``point`` at ``(x, y)`` [m] at
        time ``t``; for points in space, its horizontal position ``(x, y)`` (where a view from
        above shows it: the height follows from the coordinates).

        Damped Gauss-Newton (Levenberg-Marquardt) on the point's position from ``theta``:
        where the point's position fixes the coordinates (the elastic pendulum's bob), it
        lands on ``(x, y)``; where it fixes fewer (the cart pendulum's cart sets ``x``, not
        ``theta``), the others keep their values; a point that cannot reach ``(x, y)`` (a
        rod does not stretch) stops at the nearest place it can.

        Raises
        ------
        ValueError
            For a point whose position does not depend on the coordinates
            (``drawing.movable`` says why), or a place where the coordinates fail (a
            singular mass matrix, such as ``r = 0`` of polar coordinates).
        """
        drawing = self.drawing
        point = check.index_below("point", point, len(drawing.masses))
        if drawing.movable[point] is not None:
            raise ValueError(drawing.movable[point])
        target = np.array([check.real_number("x", x), check.real_number("y", y)])
        q = np.array(self._states("theta", theta), dtype=float)
        t = check.real_number("t", t)

        def place(coordinates):
            with np.errstate(invalid="ignore"):  # a height beyond reach: refused below
                xs, ys = self.positions(coordinates, t)[:2]
            return np.array([xs[point], ys[point]])

        def jacobian(coordinates):
            steps = 1e-7 * (1.0 + np.abs(coordinates))
            return np.column_stack([(place(coordinates + e) - place(coordinates - e)) / (2 * h)
                                    for e, h in zip(np.diag(steps), steps)])

        # A step is kept only if it brings the point nearer; the damping grows until one does
        # (far out of reach, plain Gauss-Newton overshoots round the circle).
        miss = place(q) - target
        damping = 1e-3
        for _ in range(200):
            jac = jacobian(q)
            normal = jac.T @ jac
            scale = max(np.trace(normal), 1e-12)
            step = np.linalg.solve(normal + damping * scale * np.eye(self.n), -jac.T @ miss)
            trial_miss = place(q + step) - target
            if trial_miss @ trial_miss < miss @ miss:
                q, miss, damping = q + step, trial_miss, max(damping / 10, 1e-12)
                if np.max(np.abs(step)) < 1e-12 * (1.0 + np.max(np.abs(q))):
                    break
            else:
                damping *= 10
                if damping > 1e12:
                    break  # no step helps: the nearest place it can reach
        matrix = self.mass_matrix_at(q, t)
        if not np.all(np.isfinite(matrix)) or abs(np.linalg.det(matrix)) < 1e-12 * max(
                1.0, np.max(np.abs(matrix)) ** self.n):
            raise ValueError(f"at ({x:.3g}, {y:.3g}) m the coordinates of {self.system.name} "
                             "fail (its mass matrix is singular there): release it elsewhere")
        # Beyond a rod's reach a point in space has no height (a square root of a negative
        # number): refused, not run with NaN positions and an indefinite mass matrix.
        with np.errstate(invalid="ignore"):
            placed = np.concatenate(self.positions(q, t))
        if not np.all(np.isfinite(placed)) or np.min(
                np.linalg.eigvalsh(matrix)) <= 0:
            raise ValueError(f"point {point} of {self.system.name} cannot be at ({x:.3g}, "
                             f"{y:.3g}) m: its rods do not reach there; release it nearer the "
                             "pivot")
        return q

    def __repr__(self) -> str:
        values = ", ".join(f"{s}={v:g}" for s, v in self.parameter_values.items())
        return f"SystemModel({self.system.name!r}, {values})"


class SystemFamily(FamilyMembers, SystemModel):
    """Copies of a :class:`SystemModel` that differ in some parameter values, one per entry
    of ``shape``: what :class:`~pendulum_lab.model.ModelFamily` is for a chain.

    The numeric functions broadcast the parameter arrays against the state, whose batch shape
    must end in one that ``shape`` broadcasts to; :func:`~pendulum_lab.simulate` runs every
    member in one ensemble, with the kernels of the one system (its parameters are a row of
    ``params`` per member). The parameters its time dependence reads cannot vary
    (:attr:`~SystemModel.clock_parameters`: the period was given with them).

    Attributes
    ----------
    base : SystemModel
    values : dict
        ``{name: ndarray of shape}``, the varied parameters.
    shape : tuple
    """

    def __init__(self, base: SystemModel, values: dict):
        if isinstance(base, SystemFamily):
            raise TypeError("`model` is already a family; vary its `base` instead")
        if not values:
            raise ValueError("name at least one parameter to vary, among "
                             f"{list(base.family_parameters)}")
        arrays = {family_parameter(base, name, "values"): check.real_array(name, value)
                  for name, value in values.items()}
        shape, self.values = broadcast_values(arrays)
        self.base = base
        self.system = self.chain = base.system
        self.n, self.forced, self._fn = base.n, base.forced, base._fn
        self._period, self._period_value = base._period, base._period_value
        self.start, self.factory = base.start, base.factory
        self.factory_units = base.factory_units
        defaults = dict(zip(map(str, base.system.parameters), base._params))
        self._params = tuple(np.array(np.broadcast_to(self.values.get(name, value), shape),
                                      dtype=float) for name, value in defaults.items())
        for symbol, values in zip(base.system.parameters, self._params):
            base.system.check_assumptions(symbol, values)

    @property
    def shape(self) -> tuple:
        return self._params[0].shape

    def member(self, index) -> SystemModel:
        """The member at ``index`` (an index into ``shape``) as a model of its own."""
        held = {k: float(a[index]) for k, a in self.values.items()}
        return self.base.replace(**self.base.in_factory_units(held))

    def _mapped(self, transform) -> SystemFamily:
        return SystemFamily(self.base, {k: transform(a) for k, a in self.values.items()})

    def replace(self, **changes) -> SystemFamily:
        """The same family of the base system with some of its fixed parameters changed."""
        return SystemFamily(self.base.replace(**changes), self.values)

    def family(self, **values):
        raise TypeError("`model` is already a family; vary its `base` instead")

    def _per_member(self, what: str):
        raise TypeError(f"a family has one {what} per member: ask a member "
                        "(`family.member(index)`)")

    equilibria = property(lambda self: self._per_member("set of equilibria"))
    drawing = property(lambda self: self._per_member("drawing"))

    def __reduce__(self):
        return SystemFamily, (self.base, dict(self.values))

    def __repr__(self) -> str:
        return (f"SystemFamily({self.system.name!r}, varying {list(self.values)} over shape "
                f"{self.shape})")


def mechanical_system(coordinates, parameters, *, points=None, masses=None, gravity=None,
                      potential=0, lagrangian=None, velocities=None, dissipation=0,
                      forces=None, joints=None, springs=None,
                      name: str = "a mechanical system", period: float | None = None,
                      start=None, gravity_direction=None,
                      frame_rotation=None) -> SystemModel:
    """A model of any holonomic system: from its points (or its Lagrangian) to ``simulate``.

    The arguments are those of :class:`~pendulum_lab.symbolic.systems.MechanicalSystem`
    (``coordinates``, ``parameters`` with default values, ``points`` with ``masses``,
    ``gravity``, ``potential``, or a ``lagrangian``; ``dissipation``, ``forces``; the
    ``joints`` drawn as rods and the ``springs``; for points in space, ``(x, y, z)``,
    ``gravity_direction`` (default ``-z``) and ``frame_rotation``, the angular velocity of a
    rotating frame the points are written in), plus ``period``, the period of a time
    dependence (a number or an expression of the parameters; by default derived from the
    equations when they are periodic in ``t``), and ``start``, the coordinates the
    simulators start from.

    Examples
    --------
    >>> import sympy as sp, pendulum_lab as pl
    >>> x, th = sp.symbols("x theta", real=True)
    >>> m, l, g = sp.symbols("m l g", positive=True)
    >>> model = pl.mechanical_system([th], {m: 1.0, l: 2.0, g: 9.81},
    ...                              points=[(l * sp.sin(th), -l * sp.cos(th))], masses=[m],
    ...                              gravity=g, name="a pendulum")
    >>> float(model.accelerations([np.pi / 2], [0.0])[0])
    -4.905
    """
    system = MechanicalSystem(coordinates, parameters, points=points, masses=masses,
                              gravity=gravity, potential=potential, lagrangian=lagrangian,
                              velocities=velocities, dissipation=dissipation, forces=forces,
                              joints=joints, springs=springs, name=name,
                              gravity_direction=gravity_direction,
                              frame_rotation=frame_rotation)
    return SystemModel(system, period=period, start=start)


def readable_number(value: float, digits: int = 6) -> str:
    """``value`` as people read it: a fraction or a multiple of pi with a denominator up to
    12 by name (``"1/2"``, ``"pi"``, ``"-pi/2"``), any other number to ``digits``
    significant digits (an equilibrium found at float parameter values is a float, not
    ``2176782336/(282475249*pi**113)``).

    Examples
    --------
    >>> readable_number(np.pi), readable_number(-np.pi / 2), readable_number(0.5)
    ('pi', '-pi/2', '1/2')
    >>> readable_number(0.9499999999999998), readable_number(1.0270642201834863)
    ('0.95', '1.02706')
    """
    value = float(value)
    if value == 0:
        return "0"
    for unit, scale in ((sp.Integer(1), 1.0), (sp.pi, math.pi)):
        multiple = value / scale
        for denominator in range(1, 13):
            numerator = round(multiple * denominator)
            if numerator and abs(multiple * denominator - numerator) <= 1e-12 * abs(numerator):
                return str(sp.Rational(numerator, denominator) * unit)
    return f"{value:.{digits}g}"


def _period_rule(system: MechanicalSystem, period, values: dict) -> sp.Expr | None:
    """The period as an expression of the parameters (a constant if nothing better is
    known), from ``period`` as :class:`SystemModel` takes it."""
    if period is None:
        return system.period
    if isinstance(period, sp.Basic):  # given as an expression: no need to derive one
        unknown = period.free_symbols - set(system.parameters)
        if unknown:
            raise ValueError(f"`period` uses {sorted(map(str, unknown))}, which are not "
                             f"parameters of {system.name} ({list(map(str, system.parameters))})")
        return period
    value = check.positive_number("period", period)
    own = system.period
    if own is None:
        return sp.Float(value)
    # The same multiple of the system's own period at any parameter values.
    return value * own / own.xreplace(values)


def positive_finite(name: str, value) -> float:
    """``value`` as a float if it is a positive finite real number (NumPy's included)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise TypeError(f"`{name}` must be a positive finite number, got {value!r} "
                        f"({type(value).__name__})")
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"`{name}` must be a positive finite number, got {value!r}")
    return float(value)
