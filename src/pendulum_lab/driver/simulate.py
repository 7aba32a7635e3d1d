"""The driver: a model, a method and a time grid make a :class:`Trajectory`.

Every function of the package that runs a simulation follows one calling
convention, the one of :func:`simulate`::

    f(model, theta0, omega0=None, *, t_end, dt, method=..., save_every=..., p0=None)

the initial state first (angles, then angular velocities or, with ``p0``,
canonical momenta), everything else by keyword. :func:`step_count` is the one
rule that turns ``t_end`` and ``dt`` into a number of steps.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
import warnings
from dataclasses import dataclass

import numpy as np

from .. import validation as check
from ..codegen import kernels as codegen
from ..codegen.compile_status import compile_seconds
from ..integrators import (
    MAX_SWEEPS,
    ConvergenceError,
    HamiltonianField,
    Method,
    get_method,
    suitable_methods,
    unsuitability,
)
from ..model import PendulumModel, SystemModel, reduce_turns, require_model
from .loops import (
    CALLS,
    NOT_CONVERGED,
    NOT_FINITE,
    RUNNING,
    STATUS,
    STEPS,
    SWEEPS,
    CompiledMethod,
    compile_method,
)

__all__ = [
    "AngleReduction",
    "Trajectory",
    "canonical_state",
    "check_clock",
    "check_memory",
    "check_method_fits",
    "check_run_length",
    "hamiltonian_field",
    "initial_state",
    "integrate",
    "memory_needed",
    "progress_bar",
    "run_arguments",
    "simulate",
    "step",
    "step_count",
    "time_grid",
    "to_method_variables",
    "velocity_state",
    "warn_not_finite",
]

# Show a progress bar by default once a run does this many state updates
# (steps times ensemble size): a few seconds of work or more.
PROGRESS_THRESHOLD = 2_000_000
# State updates per call of the compiled loop (a fraction of a second).
CHUNK_WORK = 200_000
# The compiled loop counts steps in int64; stay well clear of its end.
MAX_STEPS = 2**62
#: State updates (steps times trajectories) a run may take without ``allow_long_run=True``:
#: hours of computing at about a microsecond per update (RK4 on the double pendulum takes
#: 0.45 us, Gauss-Legendre methods and long chains more), 25 times the largest run of the
#: course (a basin map of 40,000 releases over 10,000 steps).
WORK_BUDGET = 10**10
# Floats a run holds at its peak, found with tracemalloc for chains of 1 to 12 links and
# explicit, implicit and symplectic methods (tests/driver/test_run_limits.py checks it): per
# kept state of a member, 9 per link plus 3 (the states saved while stepping, theta, omega, p
# and the energies afterwards, and the temporaries that convert them); per member, the
# method's memory (``method.kernel.memory(n)``) plus 3 per link plus 4 (the state being
# stepped in both variables, the conversions of the initial state, the counters).
FLOATS_PER_STATE = (9, 3)
FLOATS_PER_MEMBER = (3, 4)
#: Bytes a run may need without asking the system how much memory it has available.
SMALL_RUN = 2**26
#: Initial angles larger than this [rad] are reduced by whole turns before a run
#: (:class:`AngleReduction`): there floats are 2e-12 rad apart, 4000 times coarser than near pi.
REDUCE_ANGLES_BEYOND = 2.0**13
#: Saved angles spaced more coarsely than this [rad] by the floats warn.
ANGLE_SPACING_WARNING = 1e-8
#: A driven model's step times rounded by more than this fraction of ``dt`` warn.
CLOCK_ROUNDING_WARNING = 1e-6


@dataclass(frozen=True)
class Trajectory:
    """A computed trajectory. Arrays have the time axis first.

    Attributes
    ----------
    t : ndarray, shape (N+1,)
        Times [s], from the run's start time ``t0`` (0 by default).
    theta, omega, p : ndarray, shape (N+1, ..., n)
        Angles, angular velocities and canonical momenta (``...`` is the
        ensemble shape of the initial state, empty for one trajectory).
    kinetic, potential : ndarray, shape (N+1, ...)
        ``T`` and ``V`` [J] (for a moving pivot, ``T`` in the fixed frame).
    energy : ndarray, shape (N+1, ...)
        The mechanical energy ``T + V`` [J]. Where the pivot moves (the Kapitza
        pendulum) this is not the Hamiltonian, and neither is conserved.
    hamiltonian : ndarray, shape (N+1, ...)
        ``H(q, p, t) = p q' - L`` [J], the function whose Hamilton equations the run
        integrates: ``dH/dt = dH/dt|_(q, p)`` along the motion (constant if nothing depends
        on ``t``, and without damping). The same array as ``energy`` where ``H = T + V``
        (``model.hamiltonian_is_energy``: every chain, a system whose points the time does
        not move); for a moving pivot ``H = T + V - b q' - 2 T_0``.
    method : Method
    dt : float
    mean_iterations : float
        Mean implicit-solver iterations per step (0 for explicit methods).
    evaluations : int
        Vector-field evaluations (Hamilton's equations or the acceleration at
        one state), summed over the ensemble.
    wall_time : float
        Seconds spent stepping.
    completed : bool
        False if some trajectory reached a non-finite state or energy, a system's
        coordinate too large for a step to move it, or a place where a system's mass matrix
        is not positive definite (it then stops there, with a ``RuntimeWarning`` saying
        why; in an ensemble its later entries are NaN).
    compile_time : float
        Seconds the run spent before stepping on compiling its kernels and its time loop, or
        loading them from the disk cache (:mod:`pendulum_lab.codegen.compile_status`); 0 when
        this process had them ready. Not part of ``wall_time``.
    compiled : bool
        True when some of that time was spent compiling (a kernel was in no disk cache);
        False when it was spent loading machine code from the disk cache only.
    model : PendulumModel or None
        The model the run integrated (the drawings refuse another system's), None for a
        trajectory made by hand.
    """

    t: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    p: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray
    energy: np.ndarray
    hamiltonian: np.ndarray
    method: Method
    dt: float
    mean_iterations: float
    evaluations: int
    wall_time: float
    completed: bool
    compile_time: float = 0.0
    compiled: bool = False
    model: object = dataclasses.field(default=None, repr=False, compare=False)

    @property
    def energy_error(self) -> np.ndarray:
        """``E(t) - E(0)`` of the mechanical energy ``E = T + V`` (:attr:`energy`)."""
        return self.energy - self.energy[0]

    @property
    def relative_energy_error(self) -> np.ndarray:
        """``(E(t) - E(0)) / |E(0)|`` (absolute error where ``E(0) = 0``)."""
        scale = np.where(self.energy[0] == 0, 1.0, np.abs(self.energy[0]))
        return self.energy_error / scale


@functools.lru_cache(maxsize=64)
def _field(n: int, forced: bool, params: tuple, separable: bool,
           damping_rate: float) -> HamiltonianField:
    kernels = codegen.load_kernels(n, forced)
    # An unforced chain also has a discrete Lagrangian (variational methods).
    discrete = None if forced else functools.partial(codegen.load_discrete_kernels, n)
    return HamiltonianField(kernels.hamilton, kernels.acceleration,
                            np.array(params, dtype=float), separable, damping_rate, discrete,
                            kernels.stages, kernels.description)


def hamiltonian_field(model: PendulumModel) -> HamiltonianField:
    """The model's compiled vector field (Hamiltonian, plus its forces), as integrators see it.

    For a :class:`~pendulum_lab.model.ModelFamily` or a
    :class:`~pendulum_lab.model.SystemFamily` the parameters come as one row per member (its
    shape flattened), and so do the damping rates.
    """
    rate = model.conformal_damping_rate
    system = isinstance(model, SystemModel)
    if system and not model.shape:  # the kernels of its own equations, same generator
        kernels = model.kernels()
        # A discrete Lagrangian, as for an unforced chain, if L = T - V is all there is.
        discrete = (functools.partial(codegen.load_discrete_kernels, model.system)
                    if model.is_conservative and model.is_autonomous else None)
        return HamiltonianField(kernels.hamilton, kernels.acceleration,
                                np.array(tuple(model.parameter_values.values()), dtype=float),
                                model.separable, np.nan if rate is None else rate, discrete,
                                kernels.stages, kernels.description)
    if not model.shape:
        return _field(model.n, model.forced, tuple(model.parameter_values.values()),
                      model.separable, np.nan if rate is None else rate)
    kernels = model.kernels() if system else codegen.load_kernels(model.n, model.forced)
    rows = np.stack(np.broadcast_arrays(*model.parameter_values.values()), axis=-1)
    rates = np.broadcast_to(np.nan if rate is None else rate, model.shape)
    return HamiltonianField(kernels.hamilton, kernels.acceleration,
                            np.ascontiguousarray(rows.reshape(-1, rows.shape[-1])),
                            model.separable, np.array(rates, dtype=float).reshape(-1),
                            stages=kernels.stages, name=kernels.description)


def check_method_fits(model: PendulumModel, method: Method, field: HamiltonianField) -> None:
    """A ``ValueError`` naming the method and the reason if it cannot integrate ``model``."""
    reason = unsuitability(method, field)
    if reason is None:
        return
    if model.conformal_damping_rate is None:
        reason += (f"; joint damping on a chain of {model.n} links gives dp/dt = -H_q - "
                   "C M(theta)^-1 p, whose contraction rate depends on theta, so it is not "
                   "conformal (conformal methods take one link)")
    raise ValueError(f"`method` {method.name!r} cannot integrate this model (damping "
                     f"{model.damping}): {reason}. Methods that can: "
                     f"{suitable_methods(field)}")


def step_count(t_end: float, dt: float) -> int:
    """The number of steps of size ``dt`` in ``[0, t_end]``: ``floor(t_end / dt)``.

    A relative slack of ``1e-12`` forgives the rounding of a quotient that
    should be whole (``0.3 / 0.1`` is ``2.9999999999999996``). This is the
    one rule every run of the package uses.

    Parameters
    ----------
    t_end : float
        Length of the interval [s], ``>= 0``.
    dt : float
        Step size [s], ``> 0``.

    Raises
    ------
    ValueError
        If ``t_end < 0``, ``dt <= 0``, either is not finite, or ``t_end / dt`` overflows.

    Examples
    --------
    >>> step_count(0.3, 0.1), step_count(1.0, 0.3)
    (3, 3)
    """
    t_end = check.non_negative_number("t_end", t_end)
    dt = check.positive_number("dt", dt)
    steps = t_end / dt * (1 + 1e-12)
    if not math.isfinite(steps):
        raise ValueError(f"`t_end` / `dt` = {t_end:g} / {dt:g} overflows: more steps than "
                         "can be counted; choose a larger `dt`")
    return int(steps)


def time_grid(t_end, dt, *, members: int = 1, allow_long_run: bool = False
              ) -> tuple[float, float, int]:
    """Validated ``(t_end, dt, number of steps)`` of a run; ``t_end >= dt > 0``.

    A run of more than :data:`WORK_BUDGET` state updates (steps times ``members``) is refused
    unless ``allow_long_run`` (:func:`check_run_length`).
    """
    dt = check.positive_number("dt", dt)
    t_end = check.positive_number("t_end", t_end)
    if t_end < dt:
        raise ValueError(f"`t_end` must be at least `dt` ({dt}), got {t_end}")
    n_steps = step_count(t_end, dt)
    if n_steps > MAX_STEPS:
        raise ValueError(
            f"`t_end` / `dt` = {t_end:g} / {dt:g} = {n_steps:.3g} steps, more than a run can "
            f"count ({MAX_STEPS:.3g}); choose a larger `dt` or a shorter `t_end`"
        )
    check_run_length(n_steps, members, what=f"`t_end` / `dt` = {t_end:g} s / {dt:g} s",
                     advice="Choose a larger `dt` or a shorter `t_end`",
                     allow_long_run=allow_long_run)
    return t_end, dt, n_steps


def check_run_length(n_steps: int, members: int, *, what: str, advice: str,
                     allow_long_run: bool = False, opt_in: bool = True) -> None:
    """Refuse a run of more than :data:`WORK_BUDGET` state updates unless ``allow_long_run``.

    The message gives the count and the budget: a mistyped ``dt`` (``1e-12`` for ``1e-2``)
    or ``t_end`` would otherwise start a run of days behind a progress bar. ``what`` names
    the arguments that make the ``n_steps`` steps, ``advice`` what to change; ``opt_in`` says
    whether the caller offers ``allow_long_run``.
    """
    if not isinstance(allow_long_run, bool):
        raise TypeError(f"`allow_long_run` must be True or False, got {allow_long_run!r}")
    work = n_steps * members
    if allow_long_run or work <= WORK_BUDGET:
        return
    runs = "" if members == 1 else f" x {members} trajectories = {work:.3g} state updates"
    raise ValueError(
        f"{what} = {n_steps:.3g} steps{runs}, more than the budget of {WORK_BUDGET:.0e} state "
        f"updates for one run (at about a microsecond each, {work * 1e-6 / 3600:.3g} hours). "
        f"{advice}"
        + ("; to run it anyway, pass allow_long_run=True (to simulate or simulate_segments)."
           if opt_in else ".")
    )


def check_clock(model: PendulumModel, t0: float, span: float, dt: float,
                stacklevel: int = 3) -> None:
    """Refuse times so large that ``t + dt == t``; warn where a driven model's times round.

    Floats near ``t`` are ``np.spacing(t)`` apart. Once that exceeds twice ``|dt|`` the clock
    of the run stands still (every step starts at the same time), which would leave a driven
    model's drive frozen and every model's saved times equal. Short of that, a driven model's
    drive is evaluated at rounded times: a ``RuntimeWarning`` says by how much when the
    rounding exceeds :data:`CLOCK_ROUNDING_WARNING` of a step.
    """
    last = max(abs(t0), abs(t0 + span))
    spacing = math.ulp(last)
    if last + abs(dt) != last and spacing <= CLOCK_ROUNDING_WARNING * abs(dt):
        return  # the usual case, decided without asking the model
    driven = not model.is_autonomous
    if last + abs(dt) == last or (driven and spacing > CLOCK_ROUNDING_WARNING * abs(dt)):
        period = model.drive_period
        if not driven:
            remedy = ("This model does not depend on the time, so t0 only labels the saved "
                      "times: start at t0 = 0 for the same motion.")
        elif np.ndim(period) == 0:
            remedy = (f"The drive repeats every {period:.6g} s: start at t0 % {period:.6g} = "
                      f"{math.fmod(t0, period):.6g} s for about the same drive phase.")
        else:  # a family's periods
            remedy = ("The drive repeats with its period 2 pi / drive_frequency: start at t0 "
                      "modulo it for about the same drive phase.")
    # the argument that makes the times large
    where = f"`t0` = {t0:g} s" if abs(t0) >= abs(span) else f"`t0` + `t_end` = {t0 + span:g} s"
    if last + abs(dt) == last:
        raise ValueError(
            f"{where}: floats near t = {last:.3g} s are {spacing:.3g} s apart, more "
            f"than twice `dt` = {abs(dt):g} s, so t + dt == t and the clock of the run would "
            f"stand still. {remedy}"
        )
    if driven and spacing > CLOCK_ROUNDING_WARNING * abs(dt):
        warnings.warn(
            f"{where}: floats near t = {last:.3g} s are {spacing:.3g} s apart, "
            f"{spacing / abs(dt):.2g} of `dt`, so the drive is evaluated at times rounded by "
            f"up to that much. {remedy}",
            RuntimeWarning,
            stacklevel=stacklevel,
        )


@dataclass(frozen=True)
class AngleReduction:
    """Initial angles reduced by whole turns, and the way back to the angles given.

    Every model of the package is 2 pi-periodic in each absolute angle: its Hamiltonian
    depends on them through ``cos theta_i`` (gravity) and ``cos(theta_i - theta_j)`` (the rods'
    coupling), the damping torques on the angular velocities, the drive on the time. So the run
    from ``theta0 + 2 pi k`` is the run from ``theta0`` with every angle shifted by ``2 pi k``,
    in canonical variables and in the velocity variables of ``*_velocity`` methods alike (a
    whole turn changes neither ``omega`` nor ``p = M(theta) omega``). What is not periodic in the
    angles is what a caller computes from them as numbers (an angle plotted against time, a
    crossing of ``theta = 0`` rather than of ``0 mod 2 pi``): hence the angles given back. The
    drive is periodic in ``t``, but that is no reason to reduce the time, whose saved values
    must stay the caller's: a huge ``t0`` is refused or warned about instead (:func:`check_clock`).

    Far from zero, floats are spaced too widely for the small changes of a step (1e15 rad: 0.125
    rad apart, and a run there made relative energy errors of 1e3). So angles beyond
    :data:`REDUCE_ANGLES_BEYOND` are reduced exactly (:func:`~pendulum_lab.model.reduce_turns`)
    and the run steps from there; the saved angles are given back as ``theta0 + (theta -
    reduced)``: they start at the ``theta0`` given and are continuous (never wrapped), and the
    energies, velocities and momenta are computed from the reduced angles, where they are
    accurate.

    Attributes
    ----------
    given, reduced : ndarray, shape (K, n)
        The initial angles as given (flattened) and reduced; equal where not reduced.
    mask : ndarray of bool, shape (K, n)
        The entries reduced.
    """

    given: np.ndarray
    reduced: np.ndarray
    mask: np.ndarray

    @classmethod
    def of(cls, theta: np.ndarray, stacklevel: int = 3) -> AngleReduction | None:
        """The reduction of the angles ``theta`` (shape ``(K, n)``), or None if none is needed.

        Warns where the angles given are so large that floats there are spaced more than
        :data:`ANGLE_SPACING_WARNING` apart: the saved angles are rounded to that spacing.
        """
        mask = np.abs(theta) > REDUCE_ANGLES_BEYOND
        if not mask.any():
            return None
        largest = float(np.max(np.abs(theta)))
        spacing = float(np.spacing(largest))
        if spacing > ANGLE_SPACING_WARNING:
            warnings.warn(
                f"`theta0` holds angles up to {largest:.3g} rad, where floats are {spacing:.3g}"
                " rad apart: the saved angles (theta0 plus the motion) are rounded to that. The "
                "run itself, and its energies, velocities and momenta, use the angles reduced "
                "by whole turns (the model is 2 pi-periodic in each angle); start from "
                "pendulum_lab.model.reduce_turns(theta0) to see the motion in the angles.",
                RuntimeWarning,
                stacklevel=stacklevel,
            )
        reduced = np.where(mask, reduce_turns(np.where(mask, theta, 0.0)), theta)
        return cls(theta.copy(), reduced, mask)

    def restore(self, theta: np.ndarray) -> np.ndarray:
        """Angles ``theta`` of the reduced run (shape ``(..., K, n)``) as continued from those
        given."""
        return np.where(self.mask, self.given + (theta - self.reduced), theta)

    def select(self, rows) -> AngleReduction:
        """The reduction of some members (rows) only."""
        return AngleReduction(self.given[rows], self.reduced[rows], self.mask[rows])

    def restored(self, traj: Trajectory, batch_shape: tuple) -> Trajectory:
        """``traj`` (of the reduced run, ensemble ``batch_shape``) with the angles restored."""
        n = traj.theta.shape[-1]
        flat = traj.theta.reshape(len(traj.t), -1, n)
        return dataclasses.replace(traj, theta=self.restore(flat).reshape(traj.theta.shape))


def initial_state(model: PendulumModel, theta0, omega0, p0) -> tuple[np.ndarray, np.ndarray]:
    """Validated ``theta0`` and the one of ``omega0`` and ``p0`` that was given."""
    theta0 = check.state_array("theta0", theta0, model.n)
    if (omega0 is None) == (p0 is None):
        raise TypeError("give exactly one of `omega0` (angular velocities) and `p0` (momenta)")
    name, start = ("omega0", omega0) if p0 is None else ("p0", p0)
    start = check.state_array(name, start, model.n)
    check.same_shape("theta0", theta0, name, start)
    if theta0.size == 0:
        raise ValueError(f"`theta0` must hold at least one state, got shape {theta0.shape} "
                         "(an empty ensemble)")
    return theta0, start


def run_arguments(model, theta0, omega0, p0, t_end, dt, method, save_every, t0,
                  allow_long_run: bool = False):
    """The arguments of a run, validated in the order :func:`simulate` names them.

    Also refuses, before any work: a run beyond :data:`WORK_BUDGET` unless ``allow_long_run``
    (:func:`check_run_length`), a ``save_every`` longer than the run, and a clock that would
    stand still (:func:`check_clock`).

    Returns
    -------
    method : Method
    theta0, start : ndarray
        The initial angles and the one of ``omega0``, ``p0`` that was given.
    (t_end, dt, n_steps) : tuple
    save_every : int
    t0 : float
    """
    require_model(model)
    method = get_method(method)
    theta0, start = initial_state(model, theta0, omega0, p0)
    grid = time_grid(t_end, dt, members=theta0.size // model.n, allow_long_run=allow_long_run)
    save_every = check.integer_at_least("save_every", save_every, 1)
    if save_every > grid[2]:
        raise ValueError(
            f"`save_every` = {save_every} is more than the run's {grid[2]} steps (`t_end` / "
            f"`dt` = {grid[0]:g} / {grid[1]:g}), so only the initial state would be kept; "
            f"choose `save_every` <= {grid[2]} or a longer `t_end`"
        )
    t0 = check.real_number("t0", t0)
    check_clock(model, t0, grid[0], grid[1], stacklevel=4)
    return method, theta0, start, grid, save_every, t0


def canonical_state(model: PendulumModel, theta0, omega0=None, p0=None, *, t0: float = 0.0):
    """The initial state ``(theta0, p0)`` in canonical variables, validated.

    Give exactly one of ``omega0`` (converted by ``p = M(theta) omega``, or
    ``M(theta, t0) omega + b(theta, t0)`` where the equations depend on the
    time) and ``p0`` (taken as it is).

    Returns
    -------
    theta0, p0 : ndarray, shape (..., n)
    """
    require_model(model)
    t0 = check.real_number("t0", t0)
    theta0, start = initial_state(model, theta0, omega0, p0)
    return theta0, (start if p0 is not None else model.momenta(theta0, start, t=t0))


def velocity_state(model: PendulumModel, theta0, omega0=None, p0=None, *,
                   single: bool = False, t0: float = 0.0):
    """The initial state ``(theta0, omega0)`` in velocity variables, validated.

    Give exactly one of ``omega0`` (taken as it is) and ``p0`` (converted by
    ``omega = M(theta)^-1 p``, at the time ``t0`` where the equations depend
    on it). With ``single``, it must be one state of shape ``(n,)``.

    Returns
    -------
    theta0, omega0 : ndarray, shape (..., n)
    """
    require_model(model)
    t0 = check.real_number("t0", t0)
    theta0, start = initial_state(model, theta0, omega0, p0)
    if single and theta0.ndim != 1:
        raise ValueError("`theta0` and `omega0` must have shape (n,) (one trajectory)")
    return theta0, (start if p0 is None else model.velocities(theta0, start, t=t0))


def step(model: PendulumModel, theta0, omega0=None, *, dt: float, method="glrk4", p0=None,
         t0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """One step of ``method`` from ``(theta0, omega0)`` or ``(theta0, p0)``.

    The result is always in canonical variables ``(theta1, p1)``, whatever
    the method steps internally: the velocity-variable methods are converted
    ``p -> omega`` before and back after their step, so all methods can be
    compared as maps of ``(theta, p)``. A negative ``dt`` steps backwards.

    Parameters
    ----------
    model : PendulumModel
    theta0 : array_like, shape (n,) or (..., n)
        Angles [rad].
    omega0 : array_like, shape like ``theta0``, optional
        Angular velocities [rad/s]; or give ``p0``.
    dt : float
        Step size [s], non-zero.
    method : str or Method
        A key of :data:`pendulum_lab.METHODS`, ``CONFORMAL_METHODS`` or
        ``VARIATIONAL_METHODS``.
    p0 : array_like, shape like ``theta0``, optional
        Canonical momenta instead of ``omega0`` (give exactly one).
    t0 : float
        Time at the start of the step [s] (the drive of a driven model
        depends on it).

    Returns
    -------
    theta1, p1 : ndarray, shape like ``theta0``
        Angles and canonical momenta after the step.

    Raises
    ------
    ConvergenceError
        If an implicit method's equations do not converge.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> theta1, p1 = pl.step(pl.simple_pendulum(), [0.1], p0=[0.0], dt=0.01, method="leapfrog")
    >>> theta1.shape
    (1,)
    """
    require_model(model)
    method = get_method(method)
    theta0, start = initial_state(model, theta0, omega0, p0)
    dt = check.real_number("dt", dt)
    if dt == 0:
        raise ValueError("`dt` must be non-zero (a negative dt steps backwards in time)")
    t0 = check.real_number("t0", t0)
    check_clock(model, t0, dt, dt)
    shape = theta0.shape
    members = theta0.size // model.n
    check_memory(memory_needed(model.n, method, members, 1), "one step of "
                 + ("1 state" if members == 1 else f"{members} states"),
                 "Step fewer states at a time.")
    row_models = model.for_ensemble(shape[:-1])
    field = hamiltonian_field(row_models)
    check_method_fits(model, method, field)
    # Copies: the compiled loop updates its arguments in place.
    q = theta0.reshape(-1, model.n).copy()
    reduction = AngleReduction.of(q) if model.periodic_coordinates else None
    if reduction is not None:
        q = reduction.reduced.copy()
    y = start.reshape(-1, model.n)
    y = to_method_variables(row_models, method, q, y, given_momenta=p0 is not None, t=t0)
    compile_method(method, field, model.n).step_rows(q, y, dt, f"dt = {dt:g}", t0=t0)
    if method.variables == "velocity":
        with np.errstate(over="ignore", invalid="ignore"):  # a non-finite step, warned below
            y = row_models.momenta(q, y, t=t0 + dt)
    if not (np.isfinite(q).all() and np.isfinite(y).all()):
        bad = ~(np.isfinite(q).all(axis=-1) & np.isfinite(y).all(axis=-1))
        warn_not_finite(method, 1, t0 + dt, int(bad.sum()), members,
                        "the step returns it as computed.")
    if reduction is not None:
        q = reduction.restore(q)
    return q.reshape(shape), y.reshape(shape)


def to_method_variables(model, method, q, y, given_momenta: bool, t=None) -> np.ndarray:
    """``y`` (momenta or velocities, rows like ``q``) as a new C array in the method's variables.

    ``t``: the time of the states (where a moving pivot makes ``p`` depend on it).
    """
    canonical = method.variables == "canonical"
    if canonical and not given_momenta:
        y = model.momenta(q, y, t=t)
    elif not canonical and given_momenta:
        y = model.velocities(q, y, t=t)
    return np.array(y, order="C")


def progress_bar(total: int, work: int, enabled: bool | None, label: str, unit: str = "step"):
    """A tqdm bar over ``total`` steps (or other ``unit``), or None.

    ``enabled=None`` shows one only for work of a few seconds or more
    (``work`` = state updates, steps times ensemble members).
    """
    if enabled is None:
        enabled = work >= PROGRESS_THRESHOLD
    if not enabled:
        return None
    from tqdm.auto import tqdm

    return tqdm(total=total, desc=label, unit=unit, mininterval=0.5)


def memory_needed(n: int, method: Method, members: int, n_saved: int) -> float:
    """Bytes a run of ``members`` trajectories of ``n`` links keeping ``n_saved`` states each
    holds at its peak: the kept states and their conversions, the method's working memory
    (``method.kernel.memory(n)`` floats per trajectory) and the state being stepped.

    Measured peaks (tracemalloc) stay below it; see :data:`FLOATS_PER_STATE`.
    """
    per_member = (max(1, method.kernel.memory(n)) + FLOATS_PER_MEMBER[0] * n
                  + FLOATS_PER_MEMBER[1])
    per_state = FLOATS_PER_STATE[0] * n + FLOATS_PER_STATE[1]
    return 8.0 * members * (n_saved * per_state + per_member)


def check_memory(needed: float, what: str, advice: str) -> None:
    """Refuse, before any work, ``what`` (a run) needing ``needed`` bytes if this machine does
    not have them available now; ``advice`` says which arguments to change.

    Runs below :data:`SMALL_RUN` bytes pass unasked: asking the system costs 0.1 ms, as much
    as a short run.
    """
    if needed < SMALL_RUN:
        return
    available = check.available_memory()
    if available is None or needed <= available:
        return
    raise ValueError(
        f"{what} needs about {check.bytes_text(needed)} of memory, more than the "
        f"{check.bytes_text(available)} this machine has available. {advice}"
    )


def warn_not_finite(method: Method, first_bad: int, t: float, count: int, members: int,
                    what_follows: str, stacklevel: int = 3) -> None:
    """The one warning of a state that became non-finite (:func:`simulate` and :func:`step`).

    Neither raises: the states computed are returned, and the warning says where the first
    non-finite one appeared and what the result holds from there.
    """
    warnings.warn(
        f"{method.name}: the state became non-finite at step {first_bad} (t = {t:.6g}) in "
        f"{count} of {members} trajectories; {what_follows} Try a smaller dt.",
        RuntimeWarning,
        stacklevel=stacklevel,
    )


def simulate(
    model: PendulumModel,
    theta0,
    omega0=None,
    *,
    t_end: float = 20.0,
    dt: float = 0.01,
    method="glrk4",
    save_every: int = 1,
    p0=None,
    t0: float = 0.0,
    keep: str = "all",
    progress: bool | None = None,
    allow_long_run: bool = False,
) -> Trajectory:
    """Integrate the pendulum from ``(theta0, omega0)`` over ``[t0, t0 + t_end]``.

    Parameters
    ----------
    model : PendulumModel
        Or a :class:`~pendulum_lab.model.ModelFamily` (``model.family(...)``)
        whose shape broadcasts to the ensemble shape ``...``: each member then
        runs with its own parameters.
    theta0, omega0 : array_like, shape (n,) or (..., n)
        Initial angles [rad] and angular velocities [rad/s]. Leading axes
        make an ensemble, integrated together.
    t_end : float
        Length of the run [s], ``t_end >= dt``; the run takes
        :func:`step_count` ``(t_end, dt) = floor(t_end / dt)`` steps.
    dt : float
        Step size [s], ``> 0``.
    method : str or Method
        A key of :data:`pendulum_lab.METHODS`, ``CONFORMAL_METHODS`` or
        ``VARIATIONAL_METHODS``. On a damped model the methods that assume a
        Hamiltonian (``semi_implicit_euler``, ``leapfrog``, the variational
        ones) raise a ``ValueError``; so do the variational methods on a driven
        model or one whose Lagrangian depends on the time (a shaken pivot).
    save_every : int
        Keep every ``save_every``-th state (memory for long runs and ensembles).
    p0 : array_like, shape like ``theta0``, optional
        Initial canonical momenta, instead of ``omega0`` (give exactly one):
        restarting from a saved ``(theta, p)`` then involves no conversion.
    t0 : float
        Time of the initial state [s]; ``Trajectory.t`` starts there (the
        drive of a driven model depends on it).
    keep : {"all", "final"}
        ``"all"``: every ``save_every``-th state; ``"final"``: the initial and
        the final state only (an ensemble's end points, in little memory).
    progress : bool, optional
        Show a progress bar; by default only for long runs.
    allow_long_run : bool
        Run even beyond :data:`WORK_BUDGET` state updates (steps times
        trajectories, hours of computing), which is otherwise refused before it
        starts.

    Returns
    -------
    Trajectory

    Raises
    ------
    ConvergenceError
        If an implicit method's equations do not converge; the message names
        the step and the time.
    ValueError
        For invalid arguments, and before any work for a run that would not fit
        in the memory available (the message names ``t_end``, ``dt``,
        ``save_every`` and the memory needed), one beyond the work budget
        without ``allow_long_run``, a ``save_every`` longer than the run, or a
        ``t0`` so large that ``t0 + dt == t0``.

    Warns
    -----
    RuntimeWarning
        If the state becomes non-finite (see Notes); if a driven model's step
        times round by more than a millionth of ``dt`` (a huge ``t0``); if
        ``theta0`` is so large that the saved angles round by more than 1e-8 rad.

    Notes
    -----
    Explicit methods can blow up (explicit Euler with a large ``dt``): a single
    trajectory then stops at the first non-finite state with a
    ``RuntimeWarning`` and returns what it computed, with ``completed=False``;
    in an ensemble the other members go on and the blown-up one holds NaN.
    :func:`step` warns in the same words and returns the non-finite state.

    Initial angles beyond :data:`REDUCE_ANGLES_BEYOND` rad are reduced by whole
    turns before stepping (:class:`AngleReduction`); the saved angles start at
    ``theta0`` and are continuous, and the energies are computed accurately.
    Ensemble members are integrated in parallel threads. For runs processed
    piece by piece (every step needed, too many to keep), see
    :func:`pendulum_lab.simulate_segments`.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> traj = pl.simulate(pl.simple_pendulum(), [0.5], [0.0], t_end=1.0, dt=0.1, method="rk4")
    >>> traj.theta.shape
    (11, 1)
    """
    method, theta0, start, (t_end, dt, n_steps), save_every, t0 = run_arguments(
        model, theta0, omega0, p0, t_end, dt, method, save_every, t0, allow_long_run
    )
    compiled_before = compile_seconds(), compile_seconds(compiled_only=True)
    if check.choice("keep", keep, ("all", "final")) == "final":
        if save_every != 1:
            raise ValueError("give `save_every` only with keep='all' (keep='final' keeps the "
                             "initial and the final state)")
        save_every = n_steps
    progress = check_progress(progress)
    batch_shape = theta0.shape[:-1]
    members = theta0.size // model.n
    n_saved = n_steps // save_every + 1
    runs = "1 trajectory" if members == 1 else f"{members} trajectories"
    check_memory(memory_needed(model.n, method, members, n_saved),
                 f"`t_end` = {t_end:g} s with `dt` = {dt:g} s is {n_steps:.3g} steps; with "
                 f"`save_every` = {save_every}, keeping {n_saved:.3g} states of {runs}",
                 "Raise `save_every`, pass keep='final' (the final state only), or choose a "
                 "shorter `t_end` or a larger `dt`" + (" or fewer initial states." if members > 1
                                                       else "."))
    # One model per row of the run (a family's members get their own parameters).
    row_models = model.for_ensemble(batch_shape)
    field = hamiltonian_field(row_models)
    check_method_fits(model, method, field)
    # Copies: the compiled loop updates its arguments in place.
    q = theta0.reshape(-1, model.n).copy()
    reduction = AngleReduction.of(q) if model.periodic_coordinates else None
    if reduction is not None:
        q = reduction.reduced.copy()
    y = to_method_variables(row_models, method, q, start.reshape(-1, model.n),
                             given_momenta=p0 is not None, t=t0)
    compiled = compile_method(method, field, model.n)
    compile_time = compile_seconds() - compiled_before[0]
    compiled_anything = compile_seconds(compiled_only=True) > compiled_before[1]
    traj = integrate(model, compiled, q, y, batch_shape, t_end=t_end, dt=dt, n_steps=n_steps,
                     save_every=save_every, t0=t0, progress=progress)
    traj = dataclasses.replace(traj, compile_time=compile_time, compiled=compiled_anything)
    return traj if reduction is None else reduction.restored(traj, batch_shape)


def unphysical_stop(model, theta, energy, at, batch_shape: tuple):
    """Where each trajectory of a run must stop although its state is finite, and why; None
    if none must.

    ``theta`` (shape ``(N, *batch_shape, n)``) and ``energy`` (``(N, *batch_shape)``) are the
    saved states and energies, ``at`` their times (broadcasting). A trajectory stops at the
    first saved state that has a non-finite energy (an overflow: the state is finite, its
    energy is not a number), or where the mass matrix of a system whose positivity is not
    proved (:attr:`~pendulum_lab.symbolic.systems.MechanicalSystem.positivity_proved`) is not
    positive definite; and after its start if a coordinate a step cannot move starts there
    (a system's coordinates are not reduced by whole turns: at 1e17 floats are 16 apart).
    Returns ``(first, reason)``: ``first`` of shape ``(K,)``, the number of states to keep
    per member (at least the start; ``N`` for one that goes on), and the reason of the
    earliest stop.
    """
    count = theta.shape[0]
    flat = theta.reshape(count, -1, theta.shape[-1])
    energies = np.asarray(energy).reshape(count, -1)
    finite_state = np.all(np.isfinite(flat), axis=-1)
    checks = [(~np.isfinite(energies) & finite_state,
               "its energy is not a finite number (it overflowed: the state is too large for "
               "floats)")]
    if not model.periodic_coordinates:
        largest = np.max(np.abs(flat[0]), axis=-1)
        coarse = np.spacing(largest) > ANGLE_SPACING_WARNING
        bad = np.zeros_like(finite_state)
        bad[1:] = coarse
        checks.append((bad, f"a coordinate starts at {float(largest.max()):.3g}, where floats "
                            f"are {float(np.spacing(largest.max())):.3g} apart, so the steps "
                            "cannot move it (a system's coordinates are not reduced by whole "
                            "turns); start nearer 0"))
    if getattr(model, "positivity_proved", True) is False:
        with np.errstate(all="ignore"):
            mass = np.asarray(model.mass_matrix_at(theta, t=at)).reshape(count, -1, *(
                theta.shape[-1],) * 2)
            usable = np.all(np.isfinite(mass), axis=(-2, -1))
            lowest = np.full(usable.shape, np.inf)
            lowest[usable] = np.linalg.eigvalsh(mass[usable])[:, 0]
            scale = np.where(usable, np.abs(np.where(usable[..., None, None], mass, 0)).max(
                axis=(-2, -1)), 1.0)
        checks.append((lowest <= 1e-12 * np.maximum(scale, 1e-300),
                       "its mass matrix is not positive definite there (the kinetic energy "
                       "can be negative or zero: not a motion of masses); the Lagrangian's "
                       "q'^T M q' must stay positive wherever the system goes"))
    first = np.full(flat.shape[1], count)
    reason, earliest = None, count
    for bad, why in checks:
        bad[0] = False  # the start is kept: a trajectory holds at least one state
        hit = np.where(bad.any(axis=0), np.argmax(bad, axis=0), count)
        first = np.minimum(first, hit)
        if hit.min() < earliest:
            reason, earliest = why, int(hit.min())
    return None if reason is None else (first, reason)


def check_progress(progress) -> bool | None:
    """``progress`` if it is True, False or None (decide by the length of the run)."""
    if progress is not None and not isinstance(progress, (bool, np.bool_)):
        raise TypeError(f"`progress` must be True, False or None (by the run's length), got "
                        f"{progress!r}")
    return None if progress is None else bool(progress)


def integrate(model: PendulumModel, compiled: CompiledMethod, q, y, batch_shape: tuple, *,
              t_end: float, dt: float, n_steps: int, save_every: int, t0: float, progress,
              memory=None, first_step: int = 0) -> Trajectory:
    """The run of :func:`simulate` from validated arguments; ``q``, ``y`` are updated in place.

    ``compiled`` is the method compiled for the run's field
    (:func:`~pendulum_lab.driver.loops.compile_method`). ``q`` and ``y`` (shape ``(K, n)``,
    ``y`` in the method's variables) are the flattened ensemble of shape ``batch_shape``;
    ``memory`` (shape ``(K, S)``, :meth:`~pendulum_lab.driver.loops.CompiledMethod.new_memory`,
    updated in place) is what the method carries from step to step; a fresh one by default.
    Passing the memory of the previous call, with ``first_step`` the steps it has taken since
    ``t0`` (a multiple of ``save_every``), continues that run exactly: the same step times
    and saved times, computed from the step's number since ``t0``
    (:func:`pendulum_lab.simulate_segments` does). The callers have checked the memory needed
    (:func:`check_memory`), before any work.
    """
    method = compiled.method
    n_saved = n_steps // save_every + 1
    members = q.shape[0]
    try:
        if memory is None:
            memory = compiled.new_memory(members)
        saved_q = np.full((members, n_saved, model.n), np.nan)
        saved_y = np.full((members, n_saved, model.n), np.nan)
    except MemoryError:  # the callers check first; memory may still run out in the meantime
        raise MemoryError(
            f"keeping {n_saved:.3g} states of {members} trajectories ({model.n} links, "
            f"{method.name}) needs about "
            f"{check.bytes_text(memory_needed(model.n, method, members, n_saved))} of memory, "
            "which this machine no longer has available; raise `save_every` or run fewer "
            "trajectories"
        ) from None
    saved_q[:, 0], saved_y[:, 0] = q, y
    stats = np.zeros((members, 4), dtype=np.int64)

    # The compiled loop runs in chunks only so that a progress bar can move.
    chunk = max(1, min(n_steps, CHUNK_WORK // members))
    bar = progress_bar(n_steps, n_steps * members, progress, method.name)
    start = time.perf_counter()
    try:
        for first in range(0, n_steps, chunk):
            todo = min(chunk, n_steps - first)
            compiled.advance(q, y, dt, todo, first_step + first, save_every, saved_q, saved_y,
                             stats, memory, t0=t0, origin=first_step)
            if bar is not None:
                bar.update(todo)
            if np.all(stats[:, STATUS] != RUNNING):
                break
    finally:
        if bar is not None:
            bar.close()
    wall = time.perf_counter() - start

    failed = np.flatnonzero(stats[:, STATUS] == NOT_CONVERGED)
    if failed.size:
        k = failed[np.argmin(stats[failed, STEPS])]
        at = first_step + int(stats[k, STEPS]) + 1
        member = f", ensemble member {np.unravel_index(k, batch_shape)}" if batch_shape else ""
        raise ConvergenceError(
            f"{method.name}: the implicit equations did not converge within {MAX_SWEEPS} "
            f"iterations at step {at} (t = {t0 + at * dt:.6g}, dt = {dt:g}{member}); "
            "use a smaller dt"
        )
    blown = stats[:, STATUS] == NOT_FINITE
    completed = not np.any(blown)
    kept = n_saved
    if not completed:
        first_bad = int(np.min(stats[blown, STEPS])) + 1
        at = first_step + first_bad
        warn_not_finite(method, at, t0 + at * dt, int(blown.sum()), members,
                        "the trajectory stops there." if not batch_shape
                        else "those trajectories hold NaN from there on.", stacklevel=4)
        if not batch_shape:
            kept = int(stats[0, STEPS]) // save_every + 1

    out_shape = (kept, *batch_shape, model.n)
    theta = np.ascontiguousarray(saved_q[:, :kept].swapaxes(0, 1)).reshape(out_shape)
    saved = np.ascontiguousarray(saved_y[:, :kept].swapaxes(0, 1)).reshape(out_shape)
    # From the saved state's number since t0, as one long run computes them.
    times = t0 + (first_step // save_every + np.arange(kept)) * (save_every * dt)
    at = times.reshape(-1, *(1,) * len(batch_shape))  # the time of each saved state
    if method.variables == "canonical":
        p, omega = saved, model.velocities(theta, saved, t=at)
    else:
        omega, p = saved, model.momenta(theta, saved, t=at)
    with np.errstate(over="ignore", invalid="ignore"):  # states just before a blow-up
        kinetic = model.kinetic_energy(theta, omega, t=at)
        potential = model.potential_energy(theta, t=at)
    stop = unphysical_stop(model, theta, kinetic + potential, at, batch_shape)
    if stop is not None:
        first, reason = stop
        completed = False
        members_stopped = int(np.count_nonzero(first < kept))
        warnings.warn(
            f"{method.name}: the run stops at t = "
            f"{float(times[min(int(first.min()), kept - 1)]):.6g} in {members_stopped} of "
            f"{members} trajectories: {reason}; "
            + ("the trajectory stops there." if not batch_shape
               else "those trajectories hold NaN from there on."),
            RuntimeWarning, stacklevel=3)
        if not batch_shape:
            kept = int(first[0])
            theta, omega, p = theta[:kept], omega[:kept], p[:kept]
            kinetic, potential, times = kinetic[:kept], potential[:kept], times[:kept]
            at = at[:kept]
        else:
            after = (np.arange(kept).reshape(-1, 1) >= first.reshape(1, -1)).reshape(
                kept, *batch_shape)
            theta, omega, p = (np.where(after[..., None], np.nan, a) for a in (theta, omega, p))
            kinetic, potential = (np.where(after, np.nan, a) for a in (kinetic, potential))
    with np.errstate(over="ignore", invalid="ignore"):
        energy = kinetic + potential
        hamiltonian = (energy if model.hamiltonian_is_energy
                       else model.hamiltonian_value(theta, p, t=at))
    return Trajectory(
        t=times,
        theta=theta,
        omega=omega,
        p=p,
        kinetic=kinetic,
        potential=potential,
        energy=energy,
        hamiltonian=hamiltonian,
        method=method,
        dt=dt,
        mean_iterations=float(stats[:, SWEEPS].sum() / max(stats[:, STEPS].sum(), 1)),
        evaluations=int(stats[:, CALLS].sum()),
        wall_time=wall,
        completed=completed,
        model=model,
    )
