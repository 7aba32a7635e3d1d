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
from ..model import PendulumModel, require_model
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
    "Trajectory",
    "canonical_state",
    "check_method_fits",
    "hamiltonian_field",
    "initial_state",
    "integrate",
    "progress_bar",
    "run_arguments",
    "simulate",
    "step",
    "step_count",
    "time_grid",
    "to_method_variables",
    "velocity_state",
]

# Show a progress bar by default once a run does this many state updates
# (steps times ensemble size): a few seconds of work or more.
PROGRESS_THRESHOLD = 2_000_000
# State updates per call of the compiled loop (a fraction of a second).
CHUNK_WORK = 200_000
# The compiled loop counts steps in int64; stay well clear of its end.
MAX_STEPS = 2**62
# Floats a run holds per kept state: per member and link (theta and the saved
# momenta while stepping; theta, omega, p afterwards), and per member (the
# three energies). A lower bound of what a run needs.
FLOATS_PER_STATE = (5, 3)


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
    kinetic, potential, energy : ndarray, shape (N+1, ...)
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
        False if some trajectory reached a non-finite state (it then stops
        there; in an ensemble its later entries are NaN).
    compile_time : float
        Seconds the run spent before stepping on compiling its kernels and its time loop, or
        loading them from the disk cache (:mod:`pendulum_lab.codegen.compile_status`); 0 when
        this process had them ready. Not part of ``wall_time``.
    """

    t: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    p: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray
    energy: np.ndarray
    method: Method
    dt: float
    mean_iterations: float
    evaluations: int
    wall_time: float
    completed: bool
    compile_time: float = 0.0

    @property
    def energy_error(self) -> np.ndarray:
        """``E(t) - E(0)``."""
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

    For a :class:`~pendulum_lab.model.ModelFamily` the parameters come as one
    row per member (its shape flattened), and so do the damping rates.
    """
    rate = model.conformal_damping_rate
    if not model.shape:
        return _field(model.n, model.forced, tuple(model.parameter_values.values()),
                      model.separable, np.nan if rate is None else rate)
    kernels = codegen.load_kernels(model.n, model.forced)
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

    Examples
    --------
    >>> step_count(0.3, 0.1), step_count(1.0, 0.3)
    (3, 3)
    """
    return int(np.floor(t_end / dt * (1 + 1e-12)))


def time_grid(t_end, dt) -> tuple[float, float, int]:
    """Validated ``(t_end, dt, number of steps)`` of a run; ``t_end >= dt > 0``."""
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
    return t_end, dt, n_steps


def initial_state(model: PendulumModel, theta0, omega0, p0) -> tuple[np.ndarray, np.ndarray]:
    """Validated ``theta0`` and the one of ``omega0`` and ``p0`` that was given."""
    theta0 = check.state_array("theta0", theta0, model.n)
    if (omega0 is None) == (p0 is None):
        raise TypeError("give exactly one of `omega0` (angular velocities) and `p0` (momenta)")
    name, start = ("omega0", omega0) if p0 is None else ("p0", p0)
    start = check.state_array(name, start, model.n)
    check.same_shape("theta0", theta0, name, start)
    return theta0, start


def run_arguments(model, theta0, omega0, p0, t_end, dt, method, save_every, t0):
    """The arguments of a run, validated in the order :func:`simulate` names them.

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
    grid = time_grid(t_end, dt)
    save_every = check.integer_at_least("save_every", save_every, 1)
    return method, theta0, start, grid, save_every, check.real_number("t0", t0)


def canonical_state(model: PendulumModel, theta0, omega0=None, p0=None):
    """The initial state ``(theta0, p0)`` in canonical variables, validated.

    Give exactly one of ``omega0`` (converted by ``p = M(theta) omega``) and
    ``p0`` (taken as it is).

    Returns
    -------
    theta0, p0 : ndarray, shape (..., n)
    """
    require_model(model)
    theta0, start = initial_state(model, theta0, omega0, p0)
    return theta0, (start if p0 is not None else model.momenta(theta0, start))


def velocity_state(model: PendulumModel, theta0, omega0=None, p0=None, *,
                   single: bool = False):
    """The initial state ``(theta0, omega0)`` in velocity variables, validated.

    Give exactly one of ``omega0`` (taken as it is) and ``p0`` (converted by
    ``omega = M(theta)^-1 p``). With ``single``, it must be one state of shape
    ``(n,)``.

    Returns
    -------
    theta0, omega0 : ndarray, shape (..., n)
    """
    require_model(model)
    theta0, start = initial_state(model, theta0, omega0, p0)
    if single and theta0.ndim != 1:
        raise ValueError("`theta0` and `omega0` must have shape (n,) (one trajectory)")
    return theta0, (start if p0 is None else model.velocities(theta0, start))


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
    shape = theta0.shape
    row_models = model.for_ensemble(shape[:-1])
    field = hamiltonian_field(row_models)
    check_method_fits(model, method, field)
    # Copies: the compiled loop updates its arguments in place.
    q = theta0.reshape(-1, model.n).copy()
    y = start.reshape(-1, model.n)
    y = to_method_variables(row_models, method, q, y, given_momenta=p0 is not None)
    compile_method(method, field, model.n).step_rows(q, y, dt, f"dt = {dt:g}", t0=t0)
    if method.variables == "velocity":
        y = row_models.momenta(q, y)
    return q.reshape(shape), y.reshape(shape)


def to_method_variables(model, method, q, y, given_momenta: bool) -> np.ndarray:
    """``y`` (momenta or velocities, rows like ``q``) as a new C array in the method's variables."""
    canonical = method.variables == "canonical"
    if canonical and not given_momenta:
        y = model.momenta(q, y)
    elif not canonical and given_momenta:
        y = model.velocities(q, y)
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


def _check_memory(n_saved: int, members: int, n: int, t_end: float, dt: float, n_steps: int,
                  save_every: int) -> None:
    """Refuse a run whose kept states cannot fit in this machine's memory."""
    per_state = FLOATS_PER_STATE[0] * n + FLOATS_PER_STATE[1]
    needed = 8.0 * n_saved * members * per_state
    available = check.physical_memory()
    if available is None or needed <= available:
        return
    runs = "1 trajectory" if members == 1 else f"{members} trajectories"
    raise ValueError(
        f"`t_end` = {t_end:g} s with `dt` = {dt:g} s is {n_steps:.3g} steps; with "
        f"`save_every` = {save_every}, keeping {n_saved:.3g} states of {runs} needs at least "
        f"{check.bytes_text(needed)} of memory, more than this machine's "
        f"{check.bytes_text(available)}. Raise `save_every`, pass keep='final' (the final "
        "state only), or choose a shorter `t_end` or a larger `dt`."
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
        model.
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

    Returns
    -------
    Trajectory

    Raises
    ------
    ConvergenceError
        If an implicit method's equations do not converge; the message names
        the step and the time.
    ValueError
        For invalid arguments, including a run whose kept states would not fit
        in memory (the message names ``t_end``, ``dt``, ``save_every`` and the
        memory needed).

    Notes
    -----
    Explicit methods can blow up (explicit Euler with a large ``dt``): a single
    trajectory then stops at the first non-finite state with a
    ``RuntimeWarning`` and returns what it computed, with ``completed=False``;
    in an ensemble the other members go on and the blown-up one holds NaN.
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
        model, theta0, omega0, p0, t_end, dt, method, save_every, t0
    )
    compiled_before = compile_seconds()
    if check.choice("keep", keep, ("all", "final")) == "final":
        if save_every != 1:
            raise ValueError("give `save_every` only with keep='all' (keep='final' keeps the "
                             "initial and the final state)")
        save_every = n_steps
    batch_shape = theta0.shape[:-1]
    # One model per row of the run (a family's members get their own parameters).
    row_models = model.for_ensemble(batch_shape)
    field = hamiltonian_field(row_models)
    check_method_fits(model, method, field)
    # Copies: the compiled loop updates its arguments in place.
    q = theta0.reshape(-1, model.n).copy()
    y = to_method_variables(row_models, method, q, start.reshape(-1, model.n),
                             given_momenta=p0 is not None)
    compiled = compile_method(method, field, model.n)
    compile_time = compile_seconds() - compiled_before
    trajectory = integrate(model, compiled, q, y, theta0.shape[:-1], t_end=t_end, dt=dt,
                           n_steps=n_steps, save_every=save_every, t0=t0, progress=progress)
    return dataclasses.replace(trajectory, compile_time=compile_time)


def integrate(model: PendulumModel, compiled: CompiledMethod, q, y, batch_shape: tuple, *,
              t_end: float, dt: float, n_steps: int, save_every: int, t0: float, progress,
              memory=None) -> Trajectory:
    """The run of :func:`simulate` from validated arguments; ``q``, ``y`` are updated in place.

    ``compiled`` is the method compiled for the run's field
    (:func:`~pendulum_lab.driver.loops.compile_method`). ``q`` and ``y`` (shape ``(K, n)``,
    ``y`` in the method's variables) are the flattened ensemble of shape ``batch_shape``;
    ``memory`` (shape ``(K, S)``, :meth:`~pendulum_lab.driver.loops.CompiledMethod.new_memory`,
    updated in place) is what the method carries from step to step; a fresh one by default.
    Passing the memory of the previous call continues that run exactly
    (:func:`pendulum_lab.simulate_segments` does).
    """
    method = compiled.method
    n_saved = n_steps // save_every + 1
    members = q.shape[0]
    _check_memory(n_saved, members, model.n, t_end, dt, n_steps, save_every)
    if memory is None:
        memory = compiled.new_memory(members)
    saved_q = np.full((members, n_saved, model.n), np.nan)
    saved_y = np.full((members, n_saved, model.n), np.nan)
    saved_q[:, 0], saved_y[:, 0] = q, y
    stats = np.zeros((members, 4), dtype=np.int64)

    # The compiled loop runs in chunks only so that a progress bar can move.
    chunk = max(1, min(n_steps, CHUNK_WORK // members))
    bar = progress_bar(n_steps, n_steps * members, progress, method.name)
    start = time.perf_counter()
    try:
        for first in range(0, n_steps, chunk):
            todo = min(chunk, n_steps - first)
            compiled.advance(q, y, dt, todo, first, save_every, saved_q, saved_y, stats, memory,
                             t0=t0)
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
        at = int(stats[k, STEPS]) + 1
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
        warnings.warn(
            f"{method.name}: the state became non-finite at step {first_bad} "
            f"(t = {t0 + first_bad * dt:.6g}) in {int(blown.sum())} of {members} trajectories; "
            + ("the trajectory stops there. " if not batch_shape
               else "those trajectories hold NaN from there on. ")
            + "Try a smaller dt.",
            RuntimeWarning,
            stacklevel=2,
        )
        if not batch_shape:
            kept = int(stats[0, STEPS]) // save_every + 1

    out_shape = (kept, *batch_shape, model.n)
    theta = np.ascontiguousarray(saved_q[:, :kept].swapaxes(0, 1)).reshape(out_shape)
    saved = np.ascontiguousarray(saved_y[:, :kept].swapaxes(0, 1)).reshape(out_shape)
    if method.variables == "canonical":
        p, omega = saved, model.velocities(theta, saved)
    else:
        omega, p = saved, model.momenta(theta, saved)
    with np.errstate(over="ignore", invalid="ignore"):  # states just before a blow-up
        kinetic = model.kinetic_energy(theta, omega)
        potential = model.potential_energy(theta)
    return Trajectory(
        t=t0 + np.arange(kept) * (save_every * dt),
        theta=theta,
        omega=omega,
        p=p,
        kinetic=kinetic,
        potential=potential,
        energy=kinetic + potential,
        method=method,
        dt=dt,
        mean_iterations=float(stats[:, SWEEPS].sum() / max(stats[:, STEPS].sum(), 1)),
        evaluations=int(stats[:, CALLS].sum()),
        wall_time=wall,
        completed=completed,
    )
