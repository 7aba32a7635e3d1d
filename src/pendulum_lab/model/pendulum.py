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

This module holds :class:`PendulumModel` and :class:`ModelFamily`, and the checks of a model
argument. The numeric methods every model shares are in :mod:`~pendulum_lab.model.functions`,
a chain's picture in :mod:`~pendulum_lab.model.drawing`, what every family shares in
:mod:`~pendulum_lab.model.family`, the factories of chains in :mod:`~pendulum_lab.model.chains`,
the numbers a chain accepts in :mod:`~pendulum_lab.model.parameters`.

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

import numpy as np
import sympy as sp

from .. import validation as check
from ..symbolic.mechanics import derive_chain
from .drawing import ChainDrawing, Drawing
from .family import FamilyMembers, broadcast_values, require_ensemble_fit
from .functions import ModelFunctions
from .numeric import compiled_chain
from .parameters import (
    FAMILY_PARAMETERS,
    MAX_LINKS,
    MAX_LINKS_REASON,
    PARAMETER_RANGE,
    PARAMETER_RANGE_REASON,
    check_range,
    link_count,
    model_number,
)

__all__ = [
    "FAMILY_PARAMETERS",
    "MAX_LINKS",
    "MAX_LINKS_REASON",
    "PARAMETER_RANGE",
    "PARAMETER_RANGE_REASON",
    "Drawing",
    "FamilyMembers",
    "ModelFamily",
    "PendulumModel",
    "broadcast_values",
    "family_parameter",
    "require_chain",
    "require_double_pendulum",
    "require_model",
    "require_ensemble_fit",
]


class PendulumModel(ModelFunctions, ChainDrawing):
    """A planar chain of ``n`` pendulums with numeric masses, lengths, ``g`` and forces.

    Build one with :func:`~pendulum_lab.simple_pendulum`, :func:`~pendulum_lab.driven_pendulum`,
    :func:`~pendulum_lab.double_pendulum` or :func:`~pendulum_lab.n_pendulum`. Angles are absolute,
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
        self.n = link_count(n)
        self.masses = check.positive_vector("masses", masses, self.n)
        self.lengths = check.positive_vector("lengths", lengths, self.n)
        for name, values in (("masses", self.masses), ("lengths", self.lengths)):
            for i, value in enumerate(values):
                check_range(f"{name}[{i}]", value, positive=True)
        self.g = model_number("g", g, positive=False)
        self.damping = check.nonnegative_vector("damping", damping, self.n)
        for i, value in enumerate(self.damping):
            check_range("damping" if self.n == 1 else f"damping[{i}]", value, positive=False)
        self.drive_amplitude = model_number("drive_amplitude", drive_amplitude, positive=False)
        self.drive_frequency = (None if drive_frequency is None
                                else model_number("drive_frequency", drive_frequency))
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

    def __repr__(self) -> str:
        forces = ""
        if self.forced:
            forces = (f", damping={self.damping}, drive_amplitude={self.drive_amplitude}, "
                      f"drive_frequency={self.drive_frequency}")
        return (f"PendulumModel(n={self.n}, masses={self.masses}, lengths={self.lengths}, "
                f"g={self.g}{forces})")


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
            check_range(name, array, positive=name == "drive_frequency")
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
