"""Numeric pendulum models: the symbolic equations with their parameters bound.

Every numeric function here comes from :mod:`pendulum_lab.model.numeric`, made once per
number of links from the equations of :mod:`pendulum_lab.symbolic.mechanics` with the
parameters as arguments, so models that differ only in masses, lengths, ``g`` or forces share
the compiled code and building one is cheap. All functions accept a batch of
states: arrays of shape ``(..., n)``, so one code path serves one trajectory
and an ensemble.

A model with damping or a drive (``driven_pendulum``, or the ``damping``,
``drive_amplitude``, ``drive_frequency`` arguments of the other factories)
uses the forced chain of :mod:`pendulum_lab.symbolic.mechanics`; without them it is the
conservative chain, unchanged. Functions of a driven model's equations take
the time ``t``.

A bifurcation diagram needs the same pendulum at hundreds of drive amplitudes.
Running them one by one would pay the run's fixed costs hundreds of times;
the compiled time loop instead accepts one row of parameters per ensemble
member (:class:`~pendulum_lab.integrators.HamiltonianField`). A
:class:`ModelFamily` is the model side of that: a
:class:`~pendulum_lab.PendulumModel` whose numbers are arrays, one entry per
member. Its NumPy functions broadcast those arrays against the states (the
lambdified functions take the parameters as arguments), so energies,
momenta and Jacobians of the whole family come out of one call, and
:func:`~pendulum_lab.simulate` and :func:`~pendulum_lab.simulate_segments`
run it like any model.

Examples
--------
>>> import numpy as np, pendulum_lab as pl
>>> family = pl.driven_pendulum().family(drive_amplitude=[1.0, 1.5])
>>> run = pl.simulate(family, [[0.2], [0.2]], [[0.0], [0.0]], t_end=1.0, dt=0.1, method="rk4")
>>> one = pl.simulate(family.member(1), [0.2], [0.0], t_end=1.0, dt=0.1, method="rk4")
>>> bool(np.array_equal(run.theta[:, 1], one.theta))
True
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
import sympy as sp

from .. import validation as check
from ..symbolic.mechanics import derive_chain
from .numeric import compiled_chain, solve_small

__all__ = [
    "FAMILY_PARAMETERS",
    "Drawing",
    "ModelFamily",
    "PendulumModel",
    "double_pendulum",
    "driven_pendulum",
    "n_pendulum",
    "family_parameter",
    "require_chain",
    "require_double_pendulum",
    "require_model",
    "simple_pendulum",
]

#: The longest chain a numeric model accepts, and why (measured on unit chains).
MAX_LINKS = 1000
MAX_LINKS_REASON = (
    "longer chains are untested: the mass matrix's condition number grows like n^2 (1.6e6 at "
    "1000 links, where the linear-time solve already loses 5e-12 against a dense one) and its "
    "fastest normal mode like sqrt(n) (about 200 rad/s at 1000 unit links), so the steps an "
    "integrator needs shrink with n")
#: The range of every number of a model (masses, lengths, and the size of g, the damping and
#: the drive), and why.
PARAMETER_RANGE = (1e-9, 1e9)
PARAMETER_RANGE_REASON = (
    "the compiled kernels divide by products such as m l^2 and l1 l2 m2, which must stay far "
    "inside the range of double precision (length = 1e-300 gives m l^2 = 0, a division by "
    "zero); choose units in which the numbers lie in [1e-9, 1e9]")


def _links(n) -> int:
    """The number of links ``n``, checked before anything is built for it."""
    n = check.integer_at_least("n", n, 1)
    if n > MAX_LINKS:
        shown = n if n < 10**6 else format(n, ".3g")
        raise ValueError(f"`n` must be at most {MAX_LINKS} links, got {shown}: "
                         f"{MAX_LINKS_REASON}")
    return n


def _in_range(name: str, values, positive: bool) -> np.ndarray:
    """``values`` (a number or an array, validated finite) checked against PARAMETER_RANGE:
    ``low <= value <= high`` if ``positive``, else ``|value| <= high``."""
    low, high = PARAMETER_RANGE
    array = np.asarray(values, dtype=float)
    bad = (array < low) | (array > high) if positive else np.abs(array) > high
    if np.any(bad):
        first = float(array[bad].flat[0]) if array.ndim else float(array)
        accepted = f"in [{low:g}, {high:g}]" if positive else f"of size at most {high:g}"
        raise ValueError(f"`{name}` must be {accepted}, got {first:g}: {PARAMETER_RANGE_REASON}")
    return array


def _size(name: str, value, positive: bool = True) -> float:
    """A model's number, finite and (positive and) within PARAMETER_RANGE."""
    value = check.positive_number(name, value) if positive else check.real_number(name, value)
    _in_range(name, value, positive)
    return value


@dataclass(frozen=True)
class Drawing:
    """What a picture of a model shows: its points, and which of them are joined.

    The drawings, the animations and the live simulator read this, and the points'
    positions from ``model.positions(theta, t)``; a chain and a system given by its points
    are drawn by the same code.

    Attributes
    ----------
    masses : tuple of float
        One per point [kg]; a point of mass 0 (a moving pivot) is drawn as a small mark.
    rods, springs : tuple of (int, int)
        Pairs of points joined by a rod or by a spring; ``-1`` is the fixed origin.
    movable : tuple of (str or None)
        One per point: None where dragging the point places the coordinates
        (:meth:`PendulumModel.place_point`), else the sentence that says why it cannot.
    reach : float or None
        Half the width of a square view that holds every configuration [m] (a chain's
        length); None where only the motion tells (the view is fitted to it).
    """

    masses: tuple
    rods: tuple
    springs: tuple = ()
    movable: tuple = ()
    reach: float | None = None

    @property
    def uses_origin(self) -> bool:
        """Whether a rod or a spring hangs from the fixed origin (drawn as the pivot)."""
        return any(-1 in pair for pair in (*self.rods, *self.springs))


class PendulumModel:
    """A planar chain of ``n`` pendulums with numeric masses, lengths, ``g`` and forces.

    Build one with :func:`simple_pendulum`, :func:`driven_pendulum`,
    :func:`double_pendulum` or :func:`n_pendulum`. Angles are absolute,
    measured from the downward vertical; ``theta``, ``omega`` (angular
    velocities) and ``p`` (canonical momenta) are arrays of shape ``(n,)`` or
    ``(..., n)``.

    Parameters
    ----------
    n : int
    masses, lengths : sequence of n positive floats
    g : float
    damping : float or sequence of n floats >= 0
        Viscous damping coefficient of each joint [N m s/rad]: joint ``i``
        exerts the torque ``-damping_i (omega_i - omega_(i-1))`` (joint 1 ties
        link 1 to the pivot). One number applies to every joint.
    drive_amplitude : float
        Amplitude ``A`` of the drive torque ``A cos(drive_frequency t)`` on
        the first link, at the pivot [N m].
    drive_frequency : float > 0, optional
        Angular frequency of the drive [rad/s]; needed when
        ``drive_amplitude != 0``.

    Attributes
    ----------
    n : int
        Number of links.
    masses, lengths, damping : tuple of float
    g, drive_amplitude : float
    drive_frequency : float or None
    chain : pendulum_lab.symbolic.mechanics.Chain
        The symbolic equations (parameters symbolic); the forced chain when
        there is damping or a drive.
    """

    def __init__(self, n: int, masses, lengths, g: float, *, damping=0.0,
                 drive_amplitude: float = 0.0, drive_frequency: float | None = None):
        self.n = _links(n)
        self.masses = check.positive_vector("masses", masses, self.n)
        self.lengths = check.positive_vector("lengths", lengths, self.n)
        for name, values in (("masses", self.masses), ("lengths", self.lengths)):
            for i, value in enumerate(values):
                _in_range(f"{name}[{i}]", value, positive=True)
        self.g = _size("g", g, positive=False)
        self.damping = check.nonnegative_vector("damping", damping, self.n)
        for i, value in enumerate(self.damping):
            _in_range("damping" if self.n == 1 else f"damping[{i}]", value, positive=False)
        self.drive_amplitude = _size("drive_amplitude", drive_amplitude, positive=False)
        self.drive_frequency = (None if drive_frequency is None
                                else _size("drive_frequency", drive_frequency))
        if self.drive_amplitude != 0 and self.drive_frequency is None:
            raise ValueError("`drive_frequency` must be given (> 0) when `drive_amplitude` != 0")
        self.forced = not (self.is_conservative and self.is_autonomous)
        self.chain = derive_chain(self.n, self.forced)
        self._fn = compiled_chain(self.n, self.forced)
        self._params = self._parameters(self.forced)

    #: Every coordinate is an angle the equations are 2 pi-periodic in (so the driver may
    #: reduce large initial angles by whole turns); False for a ``SystemModel``.
    periodic_coordinates: bool = True
    #: A planar chain of rods (a ``SystemModel``, given by its points or Lagrangian, is not).
    is_chain: bool = True
    #: The Hamiltonian equals ``T + V`` (a chain's pivot is fixed; a ``SystemModel`` whose
    #: points move with the time, such as the Kapitza pendulum's, answers False).
    hamiltonian_is_energy: bool = True

    #: Shape of the parameters: ``()`` for one model; a
    #: :class:`~pendulum_lab.model.ModelFamily` has one model per entry.
    shape: tuple = ()
    #: Parameters that set the period of the time dependence and so cannot vary along a family
    #: (a chain has none: its drive period follows ``drive_frequency``).
    clock_parameters: tuple = ()

    @property
    def family_parameters(self) -> tuple[str, ...]:
        """The parameters a family or an orbit's continuation can vary
        (:data:`FAMILY_PARAMETERS` for a chain)."""
        return FAMILY_PARAMETERS

    def _parameters(self, forced: bool) -> tuple:
        """The numbers of ``Chain.parameters`` (of the forced chain if ``forced``)."""
        params = (*self.masses, *self.lengths, self.g)
        if forced:
            params += (*self.damping, self.drive_amplitude, self.drive_frequency or 0.0)
        return params

    # ---- forces ------------------------------------------------------------
    @property
    def is_conservative(self) -> bool:
        """No damping: the mechanical energy changes only by the drive's work."""
        return not any(np.any(np.asarray(c) != 0) for c in self.damping)

    @property
    def is_autonomous(self) -> bool:
        """No drive: the equations do not depend on time."""
        return not np.any(np.asarray(self.drive_amplitude) != 0)

    @property
    def drive_period(self) -> float | None:
        """``2 pi / drive_frequency`` [s], or None without a drive frequency."""
        return None if self.drive_frequency is None else 2 * np.pi / self.drive_frequency

    @property
    def conformal_damping_rate(self):
        """``gamma`` when damping makes ``dp/dt = -H_q - gamma p`` (a conformal field), else None.

        Zero without damping. For one link the damping torque ``-c omega``
        is ``-(c / (m l^2)) p``: conformal, with ``gamma = c / (m l^2)``. For
        ``n >= 2`` joint damping gives ``dp/dt = -H_q - C M(theta)^-1 p``,
        whose rate depends on ``theta``: not conformal, so None. (For a
        :class:`~pendulum_lab.model.ModelFamily`, an array of its shape.)
        """
        if self.is_conservative:
            return 0.0
        if self.n > 1:
            return None
        # one link: M = m l^2 is constant
        rate = self.damping[0] / self.mass_matrix_at(np.zeros(1))[..., 0, 0]
        return float(rate) if np.ndim(rate) == 0 else rate

    def replace(self, **changes) -> PendulumModel:
        """A copy with some constructor arguments changed (``masses``, ``lengths``, ``g``,
        ``damping``, ``drive_amplitude``, ``drive_frequency``).

        Examples
        --------
        >>> import pendulum_lab as pl
        >>> pl.driven_pendulum().replace(drive_amplitude=1.5).drive_amplitude
        1.5
        """
        arguments = self._arguments()
        unknown = set(changes) - set(arguments)
        if unknown:
            raise ValueError(f"cannot replace {sorted(unknown)}: the arguments are "
                             f"{list(arguments)}")
        return PendulumModel(self.n, **(arguments | changes))

    def _arguments(self) -> dict:
        """The constructor's arguments after ``n``."""
        return dict(masses=self.masses, lengths=self.lengths, g=self.g, damping=self.damping,
                    drive_amplitude=self.drive_amplitude, drive_frequency=self.drive_frequency)

    def __reduce__(self):
        # Pickled as its constructor call (for Dask workers, see pendulum_lab.driver.cluster): the
        # compiled functions it holds cannot be pickled, and a worker builds its own.
        return functools.partial(PendulumModel, self.n, **self._arguments()), ()

    def family(self, **values):
        """Copies of this model, one per entry of an array of parameter values.

        Parameters
        ----------
        **values : array_like
            Values of ``damping``, ``drive_amplitude``, ``drive_frequency``
            or ``g`` (one number per member; several arrays broadcast
            against each other).

        Returns
        -------
        pendulum_lab.model.ModelFamily
            Give it to :func:`~pendulum_lab.simulate` with an ensemble of
            initial states whose shape its shape broadcasts to: member ``k``
            runs with its own parameters, all in one run.

        Examples
        --------
        >>> import pendulum_lab as pl
        >>> family = pl.driven_pendulum().family(drive_amplitude=[1.0, 1.2, 1.5])
        >>> family.shape, family.drive_amplitude.tolist()
        ((3,), [1.0, 1.2, 1.5])
        """
        return ModelFamily(self, values)

    def for_ensemble(self, batch_shape: tuple) -> PendulumModel:
        """The model of each member of a flattened ensemble of ``batch_shape``: this one.

        A :class:`~pendulum_lab.model.ModelFamily` answers with its members
        broadcast to ``batch_shape`` and flattened, one per row of the run.
        """
        return self

    # ---- symbolic views (parameters symbolic) -----------------------------
    @property
    def lagrangian(self) -> sp.Expr:
        return self.chain.lagrangian

    @property
    def hamiltonian(self) -> sp.Expr:
        """``H(q, p)``; built on first access (it needs ``M^-1``)."""
        return self.chain.hamiltonian

    @property
    def mass_matrix(self) -> sp.Matrix:
        return self.chain.mass_matrix

    @property
    def forcing(self) -> sp.Matrix:
        return self.chain.forcing

    @property
    def parameter_values(self) -> dict:
        """``{symbol: value}`` for substituting this model's numbers into the symbolic forms."""
        return dict(zip(self.chain.parameters, self._params))

    @property
    def separable(self) -> bool:
        """True when ``H = T(p) + V(q)`` (constant mass matrix: the simple pendulum)."""
        return self._fn.separable

    @property
    def equilibria(self) -> list:
        """The chain's equilibria, ``model.chain.equilibria`` (all links down first)."""
        return self.chain.equilibria

    # ---- numeric functions -------------------------------------------------
    def _described(self) -> tuple[str, str]:
        """How error messages name the model (its coordinates) and why it needs ``t``."""
        return (f"a model with {self.n} link(s)",
                "the model is driven, so its equations depend on the time")

    def _time(self, t):
        """``t`` as floats; it may be left out only when the equations do not depend on it."""
        if t is None:
            if not self.is_autonomous:
                raise ValueError(f"`t` is required: {self._described()[1]}")
            return 0.0
        t = np.asarray(t, dtype=float)
        if not np.all(np.isfinite(t)):
            raise ValueError("`t` must be finite")
        return t

    def _states(self, name: str, value) -> np.ndarray:
        """``value`` as floats of shape ``(..., n)``, or an error naming ``name``."""
        try:
            array = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise TypeError(f"`{name}` must be an array of real numbers of shape (..., "
                            f"{self.n})") from None
        if array.ndim == 0 or array.shape[-1] != self.n:
            raise ValueError(f"`{name}` must have shape (..., {self.n}) for "
                             f"{self._described()[0]}, got shape {array.shape}")
        return array

    def mass_matrix_at(self, theta) -> np.ndarray:
        """``M(theta)``, shape ``(..., n, n)``."""
        return self._fn.mass_matrix(self._states("theta", theta), self._params)

    def accelerations(self, theta, omega, t=None) -> np.ndarray:
        """``omega' = M(theta)^-1 (F(theta, omega) + Q(omega, t))``, shape ``(..., n)``.

        ``t`` (a float, or an array of the batch shape ``...``) is needed for a
        driven model only.
        """
        return self._fn.accelerations(self._states("theta", theta),
                                      self._states("omega", omega), self._params, self._time(t))

    def generalized_forces(self, theta, omega, t=None) -> np.ndarray:
        """``Q(omega, t)``: joint damping and drive torques, shape ``(..., n)``; 0 if unforced."""
        return self._fn.generalized_forces(self._states("theta", theta),
                                           self._states("omega", omega), self._params,
                                           self._time(t))

    def vector_field(self, theta, p, t=None) -> tuple[np.ndarray, np.ndarray]:
        """``(dtheta/dt, dp/dt) = (dH/dp, -dH/dq + Q)`` in canonical variables, each ``(..., n)``.

        The right-hand side every integrator integrates (the compiled kernels
        compute the same). ``t`` is needed for a driven model only.
        """
        theta = self._states("theta", theta)
        omega = self.velocities(theta, p)
        return omega, (self._fn.dlagrangian_dq(theta, omega, self._params)
                       + self._fn.generalized_forces(theta, omega, self._params, self._time(t)))

    def momenta(self, theta, omega, t=None) -> np.ndarray:
        """``p = M(theta) omega`` (``t``, accepted as by every model, does not enter)."""
        return self._fn.momenta(self._states("theta", theta), self._states("omega", omega),
                                self._params)

    def velocities(self, theta, p, t=None) -> np.ndarray:
        """``omega = M(theta)^-1 p`` (this is ``dH/dp``; ``t`` does not enter)."""
        return self._fn.velocities(self._states("theta", theta), self._states("p", p),
                                   self._params)

    def kinetic_energy(self, theta, omega, t=None) -> np.ndarray:
        """Kinetic energy (``t`` is accepted for the calling convention of every model; a chain's
        energies do not depend on it)."""
        return self._fn.kinetic(self._states("theta", theta), self._states("omega", omega),
                                self._params)

    def potential_energy(self, theta, t=None) -> np.ndarray:
        """Potential energy, zero at the pivot's height."""
        return self._fn.potential(self._states("theta", theta), self._params)

    def energy(self, theta, omega, t=None) -> np.ndarray:
        return self.kinetic_energy(theta, omega, t) + self.potential_energy(theta, t)

    # Hamilton's equations in canonical variables. dH/dq at fixed p equals
    # -dL/dq at omega = M^-1 p (a property of the Legendre transform), which
    # avoids differentiating a symbolic inverse. H is the mechanical energy:
    # the forces Q of a forced model are not in it (see vector_field).
    def dH_dp(self, theta, p, t=None) -> np.ndarray:
        return self.velocities(theta, p, t)

    def dH_dq(self, theta, p) -> np.ndarray:
        theta = self._states("theta", theta)
        return -self._fn.dlagrangian_dq(theta, self.velocities(theta, p), self._params)

    def hamiltonian_value(self, theta, p) -> np.ndarray:
        """``H(theta, p)`` evaluated numerically."""
        return self.energy(theta, self.velocities(theta, p))

    def jacobian(self, theta, p, t=None) -> np.ndarray:
        """Jacobian of :meth:`vector_field` with respect to ``(theta, p)``, shape ``(..., 2n, 2n)``.

        With ``omega = M^-1 p``: ``d omega/dp = M^-1``,
        ``d omega/dq = -M^-1 d(M omega)/dq``, and ``-dH/dq = dL/dq(q, omega)``
        differentiates by the chain rule. The damping force ``-C omega`` adds
        ``-C`` to ``d(dp/dt)/d omega``; the drive depends on ``t`` only.
        """
        self._time(t)  # a driven model's field depends on t (its Jacobian does not)
        theta = self._states("theta", theta)
        mass = self.mass_matrix_at(theta)
        omega = solve_small(mass, self._states("p", p))
        args = (theta, omega, self._params)
        inv_mass = np.linalg.inv(mass)
        dw_dq = -inv_mass @ self._fn.dmomenta_dq(*args)
        rate_w = self._fn.lag_qw(*args)  # d(dp/dt)/d omega
        if not self.is_conservative:
            rate_w = rate_w - self._fn.damping_matrix(self._params)
        top = np.concatenate([dw_dq, inv_mass], axis=-1)
        bottom = np.concatenate([self._fn.lag_qq(*args) + rate_w @ dw_dq, rate_w @ inv_mass], -1)
        return np.concatenate([top, bottom], axis=-2)

    #: A chain swings in a plane: its positions are ``(x, y)``.
    dimensions = 2

    def positions(self, theta, t=None) -> tuple[np.ndarray, np.ndarray]:
        """Cartesian bob positions ``(x, y)``, each shape ``(..., n)``, pivot at the origin
        (``t`` is accepted for the protocol a :class:`~pendulum_lab.model.SystemModel`
        shares; a chain's pivot does not move)."""
        theta = self._states("theta", theta)
        lengths = np.stack(np.broadcast_arrays(*self.lengths), axis=-1)
        return (np.cumsum(lengths * np.sin(theta), axis=-1),
                -np.cumsum(lengths * np.cos(theta), axis=-1))

    @property
    def angle_coordinates(self) -> tuple[bool, ...]:
        """For each coordinate, whether it is an angle (every one of a chain's)."""
        return (True,) * self.n

    @property
    def drawing(self) -> Drawing:
        """The chain's picture: the bobs joined by rods, the first to the pivot."""
        n = self.n
        return Drawing(masses=tuple(float(m) for m in self.masses),
                       rods=tuple((i - 1, i) for i in range(n)), movable=(None,) * n,
                       reach=float(sum(self.lengths)))

    def place_point(self, point: int, x: float, y: float, theta, t: float = 0.0) -> np.ndarray:
        """The angles after bob ``point`` (0-based) is dragged to ``(x, y)`` [m].

        The bob moves on its circle around the joint before it, to the point of the circle
        in the direction of ``(x, y)`` (a rod does not stretch: a point beyond reach is
        clamped onto the circle); the other arms keep their angles ``theta``.

        Raises
        ------
        ValueError
            If ``(x, y)`` is the joint itself (it gives the arm no direction).
        """
        theta = self._states("theta", theta)
        point = check.index_below("point", point, self.n)
        x, y = check.real_number("x", x), check.real_number("y", y)
        joint_x, joint_y = 0.0, 0.0
        if point > 0:
            xs, ys = self.positions(theta)
            joint_x, joint_y = float(xs[point - 1]), float(ys[point - 1])
        dx, dy = x - joint_x, y - joint_y
        if math.hypot(dx, dy) <= 1e-9 * sum(self.lengths):
            raise ValueError(f"the release point ({x:.3g}, {y:.3g}) m is the joint of arm "
                             f"{point + 1}: it gives the arm no direction")
        angles = np.array(theta, dtype=float)
        # theta is measured from the downward vertical: (x, y) = l (sin theta, -cos theta).
        angles[point] = math.atan2(dx, -dy)
        return angles

    def __repr__(self) -> str:
        forces = ""
        if self.forced:
            forces = (f", damping={self.damping}, drive_amplitude={self.drive_amplitude}, "
                      f"drive_frequency={self.drive_frequency}")
        return (f"PendulumModel(n={self.n}, masses={self.masses}, lengths={self.lengths}, "
                f"g={self.g}{forces})")


#: The parameters a family can vary (one number per member).
FAMILY_PARAMETERS = ("damping", "drive_amplitude", "drive_frequency", "g")


class FamilyMembers:
    """The members of a family (:class:`ModelFamily`, :class:`~pendulum_lab.model.SystemFamily`):
    counted, picked, selected and broadcast to a run's ensemble. A family has ``base`` (the
    model varied), ``values`` (``{name: array}``) and ``_mapped(transform)``, the same family
    with ``transform`` applied to every array."""

    def __len__(self) -> int:
        return int(np.prod(self.shape))

    def member(self, index) -> PendulumModel:
        """The member at ``index`` (an index into ``shape``) as a model of its own."""
        return self.base.replace(**{k: float(a[index]) for k, a in self.values.items()})

    def select(self, index):
        """The members ``self.values[...][index]`` (NumPy indexing: a mask, a slice)."""
        return self._mapped(lambda a: a[index])

    def for_ensemble(self, batch_shape: tuple):
        """The members broadcast to an ensemble of ``batch_shape`` and flattened.

        Raises
        ------
        ValueError
            If the family's shape does not broadcast to ``batch_shape``.
        """
        batch_shape = require_ensemble_fit(self.shape, batch_shape)
        return self._mapped(lambda a: np.broadcast_to(a, batch_shape).reshape(-1))


class ModelFamily(FamilyMembers, PendulumModel):
    """Models differing only in the values of some parameters, one per entry of ``shape``.

    Build one with :meth:`PendulumModel.family`. Its parameter attributes
    (``damping``, ``drive_amplitude``, ``g``, ...) are arrays of ``shape``;
    the numeric functions of :class:`~pendulum_lab.PendulumModel` broadcast
    them against the state, whose batch shape must end in a shape that
    ``shape`` broadcasts to.

    Every member is validated as a model of its own (a negative damping is a
    ``ValueError`` naming ``damping``). If any member has damping or a drive,
    all members use the forced equations (where the forces vanish they add
    exactly zero).

    Attributes
    ----------
    base : PendulumModel
        The model whose parameters are varied.
    values : dict
        ``{name: ndarray of shape}``, the varied parameters.
    shape : tuple
    """

    def __init__(self, base: PendulumModel, values: dict):
        require_model(base)
        if isinstance(base, ModelFamily):
            raise TypeError("`model` is already a ModelFamily; vary its `base` instead")
        if not values:
            raise ValueError(f"name at least one parameter to vary, among {FAMILY_PARAMETERS}")
        arrays = {}
        for name, value in values.items():
            if name not in FAMILY_PARAMETERS:
                raise ValueError(f"a family cannot vary {name!r}: the parameters it can vary "
                                 f"are {list(FAMILY_PARAMETERS)}")
            arrays[name] = check.real_array(name, value)
        shape, arrays = broadcast_values(arrays)
        # Each member is a model of its own: the constructor's checks, on whole arrays (a
        # million members are checked at once, not built one by one).
        value = {name: arrays.get(name, getattr(base, name)) for name in FAMILY_PARAMETERS}
        for name, array in arrays.items():
            if name == "damping" and np.any(array < 0):
                raise ValueError(f"`damping` must be non-negative (>= 0), got "
                                 f"{array[array < 0].flat[0]}")
            if name == "drive_frequency" and np.any(array <= 0):
                raise ValueError(f"`drive_frequency` must be a positive number (> 0), got "
                                 f"{array[array <= 0].flat[0]}")
            _in_range(name, array, positive=name == "drive_frequency")
        has_frequency = value["drive_frequency"] is not None
        if not has_frequency and np.any(np.asarray(value["drive_amplitude"]) != 0):
            raise ValueError("`drive_frequency` must be given (> 0) when `drive_amplitude` != 0")
        # A varied damping is the same for every joint of a member (as `replace` sets it).
        damping = ((arrays["damping"],) * base.n if "damping" in arrays
                   else base.damping)
        forced = (any(np.any(np.asarray(c) != 0) for c in damping)
                  or bool(np.any(np.asarray(value["drive_amplitude"]) != 0)))
        params = (*base.masses, *base.lengths, value["g"])
        if forced:
            params += (*damping, value["drive_amplitude"],
                       0.0 if value["drive_frequency"] is None else value["drive_frequency"])
        self._setup(base, arrays, forced,
                    tuple(np.array(np.broadcast_to(p, shape), dtype=float) for p in params),
                    has_frequency=has_frequency)

    def _setup(self, base, values, forced, params, has_frequency):
        self.base, self.n, self.forced = base, base.n, forced
        self.values = values
        self.chain = derive_chain(self.n, forced)
        self._fn = compiled_chain(self.n, forced)
        self._params = params
        self._has_frequency = has_frequency

    def __reduce__(self):
        # Pickled as the base model and the values (for Dask workers, as PendulumModel is).
        return ModelFamily, (self.base, dict(self.values))

    def _mapped(self, transform) -> ModelFamily:
        """A family with ``transform`` (an array -> array function) applied to every array."""
        family = object.__new__(ModelFamily)
        family._setup(self.base, {k: transform(a) for k, a in self.values.items()}, self.forced,
                      tuple(transform(a) for a in self._params), self._has_frequency)
        return family

    # ---- parameters as arrays ------------------------------------------------
    @property
    def shape(self) -> tuple:
        return self._params[0].shape

    @property
    def masses(self) -> tuple:
        return self._params[: self.n]

    @property
    def lengths(self) -> tuple:
        return self._params[self.n : 2 * self.n]

    @property
    def g(self) -> np.ndarray:
        return self._params[2 * self.n]

    @property
    def damping(self) -> tuple:
        if not self.forced:
            return (np.zeros(self.shape),) * self.n
        return self._params[2 * self.n + 1 : 3 * self.n + 1]

    @property
    def drive_amplitude(self) -> np.ndarray:
        return self._params[3 * self.n + 1] if self.forced else np.zeros(self.shape)

    @property
    def drive_frequency(self) -> np.ndarray | None:
        if not self._has_frequency:
            return None
        if not self.forced:  # the frequencies are not among the parameters of the equations
            if "drive_frequency" in self.values:
                return self.values["drive_frequency"]
            return np.broadcast_to(float(self.base.drive_frequency), self.shape)
        return self._params[3 * self.n + 2]

    def replace(self, **changes) -> ModelFamily:
        """The same family of a base model with some constructor arguments changed."""
        return ModelFamily(self.base.replace(**changes), self.values)

    def family(self, **values):
        raise TypeError("`model` is already a ModelFamily; vary its `base` instead")

    def __repr__(self) -> str:
        return f"ModelFamily({self.base!r}, varying {list(self.values)} over shape {self.shape})"


def broadcast_values(arrays: dict) -> tuple[tuple, dict]:
    """The common shape of a family's arrays of values and the arrays broadcast to it; a
    ``ValueError`` naming their shapes if they do not broadcast together."""
    try:
        shape = np.broadcast_shapes(*(a.shape for a in arrays.values()))
    except ValueError:
        shapes = {k: a.shape for k, a in arrays.items()}
        raise ValueError(f"the arrays of values must broadcast together, got {shapes}") from None
    return shape, {k: np.broadcast_to(a, shape) for k, a in arrays.items()}


def require_ensemble_fit(shape: tuple, batch_shape) -> tuple:
    """``batch_shape`` as a tuple if a family of ``shape`` broadcasts to it, else a
    ``ValueError`` (the members of a run are its initial states' batch)."""
    batch_shape = tuple(batch_shape)
    try:
        fits = np.broadcast_shapes(shape, batch_shape) == batch_shape
    except ValueError:
        fits = False
    if not fits:
        raise ValueError(
            f"the model family has shape {shape}, which must broadcast to the ensemble shape "
            f"of the initial state, {batch_shape} (`theta0` of shape (..., n))")
    return batch_shape


def simple_pendulum(mass: float = 1.0, length: float = 1.0, g: float = 9.81) -> PendulumModel:
    """A simple pendulum: one point mass on a massless rod.

    Examples
    --------
    >>> sp_ = simple_pendulum(length=2.0)
    >>> float(sp_.accelerations([np.pi / 2], [0.0])[0])
    -4.905
    """
    return PendulumModel(1, (_size("mass", mass),), (_size("length", length),), g)


def driven_pendulum(damping: float = 0.5, drive_amplitude: float = 1.2,
                    drive_frequency: float = 2 / 3, mass: float = 1.0, length: float = 1.0,
                    g: float = 1.0) -> PendulumModel:
    """The damped, driven simple pendulum.

    ``m l^2 theta'' + damping theta' + m g l sin(theta) = drive_amplitude cos(drive_frequency t)``.
    With ``m = l = g = 1`` (the defaults) this is the dimensionless form of
    Baker and Gollub, with quality factor ``q = 1 / damping``; the defaults
    (``q = 2``, amplitude 1.2, frequency 2/3) lie in its chaotic range.
    ``damping = drive_amplitude = 0`` gives the conservative simple pendulum.

    Parameters
    ----------
    damping : float >= 0
        Viscous damping coefficient [N m s/rad].
    drive_amplitude : float
        Amplitude of the drive torque [N m].
    drive_frequency : float > 0
        Angular frequency of the drive [rad/s].
    mass, length : float > 0
    g : float

    References
    ----------
    G. L. Baker, J. P. Gollub, *Chaotic Dynamics: An Introduction*, 2nd ed.,
    Cambridge University Press 1996, ch. 3.

    Examples
    --------
    >>> model = driven_pendulum()
    >>> model.conformal_damping_rate, round(model.drive_period, 6)
    (0.5, 9.424778)
    >>> float(model.accelerations([0.0], [0.0], t=0.0)[0])  # the drive alone at t = 0
    1.2
    """
    return PendulumModel(1, (_size("mass", mass),), (_size("length", length),), g,
                         damping=damping, drive_amplitude=drive_amplitude,
                         drive_frequency=drive_frequency)


def double_pendulum(m1: float = 1.0, m2: float = 1.0, l1: float = 1.0, l2: float = 1.0,
                    g: float = 9.81, *, damping=0.0, drive_amplitude: float = 0.0,
                    drive_frequency: float | None = None) -> PendulumModel:
    """A double pendulum with absolute angles ``theta_1``, ``theta_2`` from the vertical.

    ``damping`` (one number for both joints, or one per joint),
    ``drive_amplitude`` and ``drive_frequency`` add joint damping and a drive
    torque at the pivot; see :class:`PendulumModel`.
    """
    masses = (_size("m1", m1), _size("m2", m2))
    lengths = (_size("l1", l1), _size("l2", l2))
    return PendulumModel(2, masses, lengths, g, damping=damping, drive_amplitude=drive_amplitude,
                         drive_frequency=drive_frequency)


def n_pendulum(n: int, masses=None, lengths=None, g: float = 9.81, *, damping=0.0,
               drive_amplitude: float = 0.0, drive_frequency: float | None = None
               ) -> PendulumModel:
    """A chain of ``n`` pendulums; masses and lengths default to 1.

    ``damping``, ``drive_amplitude`` and ``drive_frequency`` as for
    :class:`PendulumModel`.
    """
    n = _links(n)  # before the default masses and lengths are made for it
    return PendulumModel(n, (1.0,) * n if masses is None else masses,
                         (1.0,) * n if lengths is None else lengths, g, damping=damping,
                         drive_amplitude=drive_amplitude, drive_frequency=drive_frequency)


def require_model(model, name: str = "model") -> PendulumModel:
    """``model`` itself if it is a :class:`PendulumModel`, else a ``TypeError`` naming ``name``."""
    if not isinstance(model, PendulumModel):
        raise TypeError(
            f"`{name}` must be a PendulumModel (from simple_pendulum, driven_pendulum, "
            f"double_pendulum or n_pendulum), got {type(model).__name__}"
        )
    return model


def require_chain(model, what: str) -> PendulumModel:
    """``model`` itself if it is a chain of rods; a ``TypeError`` saying why ``what`` needs one.

    ``what`` completes "... because ..." (``"it uses the chain's closed-form period"``).
    """
    require_model(model)
    if not model.is_chain:
        raise TypeError(f"`model` must be a chain of rods (simple_pendulum, double_pendulum, "
                        f"n_pendulum, driven_pendulum) here, because {what}; got {model!r}")
    return model


def family_parameter(model, parameter, argument: str = "parameter") -> str:
    """``parameter`` if families of ``model`` and the orbit tools can vary it; else a
    ``ValueError`` naming ``argument`` and the parameters that can vary.

    Those are ``model.family_parameters``; a system's ``clock_parameters`` (the Kapitza
    pendulum's ``w``) are refused with the reason: they set the period, which the members
    of a family and the orbits of a continuation share.
    """
    allowed = list(model.family_parameters)
    if parameter in model.clock_parameters:
        raise ValueError(f"`{argument}` {parameter!r} sets how {model.name} depends on the time "
                         "(its period, shared by a family's members and a continuation's "
                         "orbits), so it cannot vary along a family or an orbit: build one "
                         f"model per value instead (model.replace({parameter}=...)); the "
                         f"parameters that can vary are {allowed}")
    return check.choice(argument, parameter, allowed)


def require_double_pendulum(model) -> PendulumModel:
    """``model`` itself if it is a :class:`PendulumModel` with two links."""
    require_model(model)
    if not model.is_chain:
        raise TypeError(f"`model` must be a double pendulum (a chain of two links), got {model!r}")
    if model.n != 2:
        raise ValueError(f"`model` must be a double pendulum (n = 2), got n = {model.n}")
    return model
