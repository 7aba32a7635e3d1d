"""Numeric pendulum models: the symbolic equations with their parameters bound.

Every numeric function here is lambdified from :mod:`pendulum_lab.mechanics`
once per number of links (with ``cse=True`` and the parameters as arguments),
so models that differ only in masses, lengths, ``g`` or forces share the
compiled code and building one is cheap. All functions accept a batch of
states: arrays of shape ``(..., n)``, so one code path serves one trajectory
and an ensemble.

A model with damping or a drive (``driven_pendulum``, or the ``damping``,
``drive_amplitude``, ``drive_frequency`` arguments of the other factories)
uses the forced chain of :mod:`pendulum_lab.mechanics`; without them it is the
conservative chain, unchanged. Functions of a driven model's equations take
the time ``t``.
"""

from __future__ import annotations

import functools

import numpy as np
import sympy as sp

from . import _validation as check
from .mechanics import Chain, derive_chain

__all__ = ["PendulumModel", "double_pendulum", "driven_pendulum", "n_pendulum", "simple_pendulum"]

#: Chains up to this many links are evaluated from their SymPy expressions,
#: unrolled (lambdified here, printed as kernels by :mod:`pendulum_lab.codegen`);
#: longer ones link by link, from the closed form (:mod:`pendulum_lab.long_chains`),
#: which is the faster from three links on and needs no code generated per chain.
UNROLLED_MAX_LINKS = 2
#: The longest chain a numeric model accepts, and why (measured on unit chains).
MAX_LINKS = 1000
MAX_LINKS_REASON = (
    "longer chains are untested: the mass matrix's condition number grows like n^2 (1.6e6 at "
    "1000 links, where the linear-time solve already loses 5e-12 against a dense one) and its "
    "fastest normal mode like sqrt(n) (about 200 rad/s at 1000 unit links), so the steps an "
    "integrator needs shrink with n")


def _lambdify(args, exprs, shape):
    """Lambdify a list of expressions into one function returning shape ``(..., *shape)``.

    Entries that are constant (no state symbol in them) come back from
    lambdify as Python floats; broadcasting them against the state keeps
    every output the same batch shape.
    """
    fn = sp.lambdify(args, list(exprs), modules="numpy", cse=True)

    def evaluate(*values):
        parts = np.broadcast_arrays(*fn(*values), values[0])[:-1]
        return np.stack(parts, axis=-1).reshape(parts[0].shape + shape)

    evaluate.__doc__ = f"Arguments: {', '.join(map(str, args))}."
    return evaluate


def _state(theta, other, params) -> tuple:
    """Arguments of a lambdified state function: each angle, each velocity, each parameter."""
    return (*np.moveaxis(np.asarray(theta, float), -1, 0),
            *np.moveaxis(np.asarray(other, float), -1, 0), *params)


def _config(theta, params) -> tuple:
    return (*np.moveaxis(np.asarray(theta, float), -1, 0), *params)


class _CompiledChain:
    """The lambdified functions of one :class:`~pendulum_lab.mechanics.Chain` (a short one).

    Each method takes states of shape ``(..., n)`` and ``params`` in the order
    of ``Chain.parameters``; :class:`~pendulum_lab.long_chains.LoopedChain`
    has the same methods for long chains.
    """

    def __init__(self, chain: Chain):
        n, q, w = chain.n, list(chain.q), list(chain.omega)
        state_args = (*q, *w, *chain.parameters)
        config_args = (*q, *chain.parameters)
        lag_dq = chain.dlagrangian_dq
        lag_dw = sp.Matrix([chain.lagrangian.diff(wi) for wi in w])
        self._mass_matrix = _lambdify(config_args, chain.mass_matrix, (n, n))
        # The time comes last; the conservative forcing does not use it.
        self._forcing = _lambdify((*state_args, chain.t), chain.forcing, (n,))
        self._generalized_forces = _lambdify((*state_args, chain.t), chain.generalized_forces,
                                             (n,))
        self._damping_matrix = _lambdify(chain.parameters, chain.damping_matrix, (n, n))
        self._dlagrangian_dq = _lambdify(state_args, lag_dq, (n,))
        self._kinetic = _lambdify(state_args, [chain.kinetic], ())
        self._potential = _lambdify(config_args, [chain.potential], ())
        # Pieces of the Jacobian of Hamilton's equations, all written in (q, omega):
        # d2L/dq2, d2L/dq domega and d(M omega)/dq; no symbolic inverse of M needed.
        self._lag_qq = _lambdify(state_args, lag_dq.jacobian(q), (n, n))
        self._lag_qw = _lambdify(state_args, lag_dq.jacobian(w), (n, n))
        self._dmomenta_dq = _lambdify(state_args, lag_dw.jacobian(q), (n, n))
        self.separable = not (chain.mass_matrix.free_symbols & set(q))

    def mass_matrix(self, theta, params):
        return self._mass_matrix(*_config(theta, params))

    def velocities(self, theta, p, params):
        return solve_small(self.mass_matrix(theta, params), np.asarray(p, float))

    def momenta(self, theta, omega, params):
        return np.einsum("...ij,...j->...i", self.mass_matrix(theta, params), omega)

    def dlagrangian_dq(self, theta, omega, params):
        return self._dlagrangian_dq(*_state(theta, omega, params))

    def forcing(self, theta, omega, params, t):
        return self._forcing(*_state(theta, omega, params), t)

    def accelerations(self, theta, omega, params, t):
        return solve_small(self.mass_matrix(theta, params), self.forcing(theta, omega, params, t))

    def generalized_forces(self, theta, omega, params, t):
        return self._generalized_forces(*_state(theta, omega, params), t)

    def kinetic(self, theta, omega, params):
        return self._kinetic(*_state(theta, omega, params))

    def potential(self, theta, params):
        return self._potential(*_config(theta, params))

    def damping_matrix(self, params):
        return self._damping_matrix(*params)

    def lag_qq(self, theta, omega, params):
        return self._lag_qq(*_state(theta, omega, params))

    def lag_qw(self, theta, omega, params):
        return self._lag_qw(*_state(theta, omega, params))

    def dmomenta_dq(self, theta, omega, params):
        return self._dmomenta_dq(*_state(theta, omega, params))


@functools.cache
def _compiled(n: int, forced: bool):
    """The numeric functions of ``n`` links: lambdified for short chains, looped for long ones."""
    if n > UNROLLED_MAX_LINKS:
        from .long_chains import LoopedChain  # compiles (once per machine) on first use

        return LoopedChain(n, forced)
    return _CompiledChain(derive_chain(n, forced))


def solve_small(matrix: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Solve ``matrix @ x = rhs`` for a batch of small systems.

    ``matrix`` has shape ``(..., n, n)`` and ``rhs`` shape ``(..., n)``. For
    ``n <= 2`` the closed form is several times faster than
    ``numpy.linalg.solve`` on tiny matrices; beyond that LAPACK does the work.
    """
    n = matrix.shape[-1]
    if n == 1:
        return rhs / matrix[..., 0, :]
    if n == 2:
        a, b = matrix[..., 0, 0], matrix[..., 0, 1]
        c, d = matrix[..., 1, 0], matrix[..., 1, 1]
        det = a * d - b * c
        x0 = (d * rhs[..., 0] - b * rhs[..., 1]) / det
        x1 = (a * rhs[..., 1] - c * rhs[..., 0]) / det
        return np.stack((x0, x1), axis=-1)
    return np.linalg.solve(matrix, rhs[..., None])[..., 0]


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
    chain : pendulum_lab.mechanics.Chain
        The symbolic equations (parameters symbolic); the forced chain when
        there is damping or a drive.
    """

    def __init__(self, n: int, masses, lengths, g: float, *, damping=0.0,
                 drive_amplitude: float = 0.0, drive_frequency: float | None = None):
        self.n = check.integer_at_least("n", n, 1)
        if self.n > MAX_LINKS:
            raise ValueError(f"`n` must be at most {MAX_LINKS} links, got {self.n}: "
                             f"{MAX_LINKS_REASON}")
        self.masses = check.positive_vector("masses", masses, self.n)
        self.lengths = check.positive_vector("lengths", lengths, self.n)
        self.g = check.real_number("g", g)
        self.damping = check.nonnegative_vector("damping", damping, self.n)
        self.drive_amplitude = check.real_number("drive_amplitude", drive_amplitude)
        self.drive_frequency = (None if drive_frequency is None
                                else check.positive_number("drive_frequency", drive_frequency))
        if self.drive_amplitude != 0 and self.drive_frequency is None:
            raise ValueError("`drive_frequency` must be given (> 0) when `drive_amplitude` != 0")
        self.forced = not (self.is_conservative and self.is_autonomous)
        self.chain = derive_chain(self.n, self.forced)
        self._fn = _compiled(self.n, self.forced)
        self._params = self._parameters(self.forced)

    #: Shape of the parameters: ``()`` for one model; a
    #: :class:`~pendulum_lab.family.ModelFamily` has one model per entry.
    shape: tuple = ()

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
        :class:`~pendulum_lab.family.ModelFamily`, an array of its shape.)
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
        # Pickled as its constructor call (for Dask workers, see pendulum_lab.cluster): the
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
        pendulum_lab.family.ModelFamily
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
        from .family import ModelFamily

        return ModelFamily(self, values)

    def for_ensemble(self, batch_shape: tuple) -> PendulumModel:
        """The model of each member of a flattened ensemble of ``batch_shape``: this one.

        A :class:`~pendulum_lab.family.ModelFamily` answers with its members
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

    # ---- numeric functions -------------------------------------------------
    def _time(self, t):
        """``t`` as floats; it may be left out only when the equations do not depend on it."""
        if t is None:
            if not self.is_autonomous:
                raise ValueError("`t` is required: the model is driven, so its equations "
                                 "depend on the time")
            return 0.0
        t = np.asarray(t, dtype=float)
        if not np.all(np.isfinite(t)):
            raise ValueError("`t` must be finite")
        return t

    def mass_matrix_at(self, theta) -> np.ndarray:
        """``M(theta)``, shape ``(..., n, n)``."""
        return self._fn.mass_matrix(theta, self._params)

    def accelerations(self, theta, omega, t=None) -> np.ndarray:
        """``omega' = M(theta)^-1 (F(theta, omega) + Q(omega, t))``, shape ``(..., n)``.

        ``t`` (a float, or an array of the batch shape ``...``) is needed for a
        driven model only.
        """
        return self._fn.accelerations(theta, omega, self._params, self._time(t))

    def generalized_forces(self, theta, omega, t=None) -> np.ndarray:
        """``Q(omega, t)``: joint damping and drive torques, shape ``(..., n)``; 0 if unforced."""
        return self._fn.generalized_forces(theta, omega, self._params, self._time(t))

    def vector_field(self, theta, p, t=None) -> tuple[np.ndarray, np.ndarray]:
        """``(dtheta/dt, dp/dt) = (dH/dp, -dH/dq + Q)`` in canonical variables, each ``(..., n)``.

        The right-hand side every integrator integrates (the compiled kernels
        compute the same). ``t`` is needed for a driven model only.
        """
        omega = self.velocities(theta, p)
        return omega, (self._fn.dlagrangian_dq(theta, omega, self._params)
                       + self._fn.generalized_forces(theta, omega, self._params, self._time(t)))

    def momenta(self, theta, omega) -> np.ndarray:
        """``p = M(theta) omega``."""
        return self._fn.momenta(theta, omega, self._params)

    def velocities(self, theta, p) -> np.ndarray:
        """``omega = M(theta)^-1 p`` (this is ``dH/dp``)."""
        return self._fn.velocities(theta, p, self._params)

    def kinetic_energy(self, theta, omega) -> np.ndarray:
        return self._fn.kinetic(theta, omega, self._params)

    def potential_energy(self, theta) -> np.ndarray:
        """Potential energy, zero at the pivot's height."""
        return self._fn.potential(theta, self._params)

    def energy(self, theta, omega) -> np.ndarray:
        return self.kinetic_energy(theta, omega) + self.potential_energy(theta)

    # Hamilton's equations in canonical variables. dH/dq at fixed p equals
    # -dL/dq at omega = M^-1 p (a property of the Legendre transform), which
    # avoids differentiating a symbolic inverse. H is the mechanical energy:
    # the forces Q of a forced model are not in it (see vector_field).
    def dH_dp(self, theta, p) -> np.ndarray:
        return self.velocities(theta, p)

    def dH_dq(self, theta, p) -> np.ndarray:
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
        theta = np.asarray(theta, float)
        mass = self.mass_matrix_at(theta)
        omega = solve_small(mass, np.asarray(p, float))
        args = (theta, omega, self._params)
        inv_mass = np.linalg.inv(mass)
        dw_dq = -inv_mass @ self._fn.dmomenta_dq(*args)
        rate_w = self._fn.lag_qw(*args)  # d(dp/dt)/d omega
        if not self.is_conservative:
            rate_w = rate_w - self._fn.damping_matrix(self._params)
        top = np.concatenate([dw_dq, inv_mass], axis=-1)
        bottom = np.concatenate([self._fn.lag_qq(*args) + rate_w @ dw_dq, rate_w @ inv_mass], -1)
        return np.concatenate([top, bottom], axis=-2)

    def positions(self, theta) -> tuple[np.ndarray, np.ndarray]:
        """Cartesian bob positions ``(x, y)``, each shape ``(..., n)``, pivot at the origin."""
        theta = np.asarray(theta, float)
        lengths = np.stack(np.broadcast_arrays(*self.lengths), axis=-1)
        return (np.cumsum(lengths * np.sin(theta), axis=-1),
                -np.cumsum(lengths * np.cos(theta), axis=-1))

    def __repr__(self) -> str:
        forces = ""
        if self.forced:
            forces = (f", damping={self.damping}, drive_amplitude={self.drive_amplitude}, "
                      f"drive_frequency={self.drive_frequency}")
        return (f"PendulumModel(n={self.n}, masses={self.masses}, lengths={self.lengths}, "
                f"g={self.g}{forces})")


def simple_pendulum(mass: float = 1.0, length: float = 1.0, g: float = 9.81) -> PendulumModel:
    """A simple pendulum: one point mass on a massless rod.

    Examples
    --------
    >>> sp_ = simple_pendulum(length=2.0)
    >>> float(sp_.accelerations([np.pi / 2], [0.0])[0])
    -4.905
    """
    return PendulumModel(1, (check.positive_number("mass", mass),),
                         (check.positive_number("length", length),), g)


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
    return PendulumModel(1, (check.positive_number("mass", mass),),
                         (check.positive_number("length", length),), g, damping=damping,
                         drive_amplitude=drive_amplitude, drive_frequency=drive_frequency)


def double_pendulum(m1: float = 1.0, m2: float = 1.0, l1: float = 1.0, l2: float = 1.0,
                    g: float = 9.81, *, damping=0.0, drive_amplitude: float = 0.0,
                    drive_frequency: float | None = None) -> PendulumModel:
    """A double pendulum with absolute angles ``theta_1``, ``theta_2`` from the vertical.

    ``damping`` (one number for both joints, or one per joint),
    ``drive_amplitude`` and ``drive_frequency`` add joint damping and a drive
    torque at the pivot; see :class:`PendulumModel`.
    """
    masses = (check.positive_number("m1", m1), check.positive_number("m2", m2))
    lengths = (check.positive_number("l1", l1), check.positive_number("l2", l2))
    return PendulumModel(2, masses, lengths, g, damping=damping, drive_amplitude=drive_amplitude,
                         drive_frequency=drive_frequency)


def n_pendulum(n: int, masses=None, lengths=None, g: float = 9.81, *, damping=0.0,
               drive_amplitude: float = 0.0, drive_frequency: float | None = None
               ) -> PendulumModel:
    """A chain of ``n`` pendulums; masses and lengths default to 1.

    ``damping``, ``drive_amplitude`` and ``drive_frequency`` as for
    :class:`PendulumModel`.
    """
    n = check.integer_at_least("n", n, 1)
    return PendulumModel(n, (1.0,) * n if masses is None else masses,
                         (1.0,) * n if lengths is None else lengths, g, damping=damping,
                         drive_amplitude=drive_amplitude, drive_frequency=drive_frequency)
