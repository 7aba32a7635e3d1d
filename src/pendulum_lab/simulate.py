"""The driver: a model, a method and a time grid make a :class:`Trajectory`."""

from __future__ import annotations

import functools
import os
import time
import warnings
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from . import _validation as check
from . import codegen
from .integrators import (
    CALLS,
    CONFORMAL_METHODS,
    MAX_SWEEPS,
    METHODS,
    NOT_CONVERGED,
    NOT_FINITE,
    RUNNING,
    STATUS,
    STEPS,
    SWEEPS,
    ConvergenceError,
    HamiltonianField,
    Method,
    get_method,
    run,
    suitable_methods,
    unsuitability,
)
from .model import PendulumModel, check_model, driven_pendulum, n_pendulum

__all__ = ["Trajectory", "hamiltonian_field", "simulate", "step", "warm_up"]

# Show a progress bar by default once a run does this many state updates
# (steps times ensemble size): a few seconds of work or more.
PROGRESS_THRESHOLD = 2_000_000
# State updates per call of the compiled loop (a fraction of a second).
CHUNK_WORK = 200_000
# Ensembles at least this large are split across threads.
PARALLEL_MIN_MEMBERS = 64


@dataclass(frozen=True)
class Trajectory:
    """A computed trajectory. Arrays have the time axis first.

    Attributes
    ----------
    t : ndarray, shape (N+1,)
        Times, from the start time ``t0``.
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
    return HamiltonianField(kernels.hamilton, kernels.acceleration,
                            np.array(params, dtype=float), separable, damping_rate)


def hamiltonian_field(model: PendulumModel) -> HamiltonianField:
    """The model's compiled vector field (Hamiltonian, plus its forces), as integrators see it."""
    rate = model.conformal_damping_rate
    return _field(model.n, model.forced, tuple(model.parameter_values.values()), model.separable,
                  np.nan if rate is None else rate)


def _check_method_fits(model: PendulumModel, method: Method, field: HamiltonianField):
    """A ``ValueError`` naming the method and the reason if it cannot integrate ``model``."""
    reason = unsuitability(method, field.damping_rate)
    if reason is None:
        return
    if model.conformal_damping_rate is None:
        reason += (f"; joint damping on a chain of {model.n} links gives dp/dt = -H_q - "
                   "C M(theta)^-1 p, whose contraction rate depends on theta, so it is not "
                   "conformal (conformal methods take one link)")
    raise ValueError(f"`method` {method.name!r} cannot integrate this model (damping "
                     f"{model.damping}): {reason}. Methods that can: "
                     f"{suitable_methods(field.damping_rate)}")


def _advance(method: Method, field: HamiltonianField, q, p, h, n_steps, first_step,
             save_every, saved_q, saved_p, stats, t0: float = 0.0):
    """Run the compiled time loop on rows ``q, p`` of shape ``(K, n)``, in place.

    Step ``s`` (counted from 1 over the whole run, ``first_step`` before this
    call) starts at time ``t0 + (s - 1) h``. ``field.params`` and
    ``field.damping_rate`` may hold one row per member (shapes ``(K, P)``,
    ``(K,)``). Large ensembles are split into one slice per core; the compiled
    loop releases the GIL, so the slices run in parallel threads.
    """
    loop, step_kernel = run.compiled, method.kernel.compiled  # compile before any threads
    params = np.atleast_2d(np.asarray(field.params, dtype=float))
    rates = np.atleast_1d(np.asarray(field.damping_rate, dtype=float))
    per_member = params.shape[0] > 1

    def advance(rows):
        loop(step_kernel, field.hamilton, field.acceleration, field.separable,
             rates[rows] if per_member else rates, q[rows], p[rows], float(t0), float(h),
             n_steps, first_step, save_every, params[rows] if per_member else params,
             saved_q[rows], saved_p[rows], stats[rows])

    members, workers = q.shape[0], os.cpu_count() or 1
    if members < PARALLEL_MIN_MEMBERS or workers == 1:
        advance(slice(None))
        return
    bounds = np.linspace(0, members, workers + 1).astype(int)
    list(_pool(workers).map(advance, [slice(a, b) for a, b in zip(bounds[:-1], bounds[1:])]))


@functools.cache
def _pool(workers: int) -> ThreadPoolExecutor:
    """One thread pool for the whole session (starting threads per call costs milliseconds)."""
    return ThreadPoolExecutor(workers, thread_name_prefix="pendulum_lab")


def step(model: PendulumModel, method, q0, p0, dt: float, *, t0: float = 0.0
         ) -> tuple[np.ndarray, np.ndarray]:
    """One step of ``method`` in canonical variables ``(theta, p)``, from time ``t0``.

    ``q0`` and ``p0`` have shape ``(n,)`` or ``(..., n)``. The velocity-variable
    methods are converted ``p -> omega`` before and back after their step, so
    all methods can be compared as maps of ``(theta, p)``. A negative ``dt``
    steps backwards. ``t0`` matters for a driven model only.

    Raises
    ------
    ConvergenceError
        If an implicit method's equations do not converge.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> q1, p1 = pl.step(pl.simple_pendulum(), "leapfrog", [0.1], [0.0], 0.01)
    >>> q1.shape
    (1,)
    """
    check_model(model)
    method = get_method(method)
    q0 = check.state_array("q0", q0, model.n)
    p0 = check.state_array("p0", p0, model.n)
    if q0.shape != p0.shape:
        raise ValueError(f"`q0` and `p0` must have the same shape, got {q0.shape} and {p0.shape}")
    dt = check.real_number("dt", dt)
    if dt == 0:
        raise ValueError("`dt` must be non-zero (a negative dt steps backwards in time)")
    t0 = check.real_number("t0", t0)
    field = hamiltonian_field(model)
    _check_method_fits(model, method, field)
    shape = q0.shape
    # Copies: the compiled loop updates its arguments in place.
    q = q0.reshape(-1, model.n).copy()
    y = p0.reshape(-1, model.n).copy()
    if method.variables == "velocity":
        y = np.ascontiguousarray(model.velocities(q, y))
    unused = np.empty((q.shape[0], 1, model.n))
    stats = np.zeros((q.shape[0], 4), dtype=np.int64)
    _advance(method, field, q, y, dt, 1, 0, 2, unused, unused, stats, t0=t0)
    if np.any(stats[:, STATUS] == NOT_CONVERGED):
        raise ConvergenceError(f"{method.name}: the implicit equations did not converge "
                               f"within {MAX_SWEEPS} iterations (dt = {dt:g})")
    if method.variables == "velocity":
        y = model.momenta(q, y)
    return q.reshape(shape), y.reshape(shape)


def _progress_bar(total: int, enabled: bool | None, work: int, label: str):
    if enabled is None:
        enabled = work >= PROGRESS_THRESHOLD
    if not enabled:
        return None
    from tqdm.auto import tqdm

    return tqdm(total=total, desc=label, unit="step", mininterval=0.5)


def simulate(
    model: PendulumModel,
    theta0,
    omega0=None,
    t_end: float = 20.0,
    dt: float = 0.01,
    method="glrk4",
    *,
    p0=None,
    save_every: int = 1,
    progress: bool | None = None,
    t0: float = 0.0,
) -> Trajectory:
    """Integrate the pendulum from ``(theta0, omega0)`` at time ``t0`` to ``t_end``.

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0 : array_like, shape (n,) or (..., n)
        Initial angles [rad] and angular velocities [rad/s]. Leading axes
        make an ensemble, integrated together.
    t_end : float
        Final time, ``t_end >= t0 + dt``; the run takes ``floor((t_end - t0) / dt)``
        steps.
    dt : float
        Step size, ``> 0``.
    method : str or Method
        A key of :data:`pendulum_lab.METHODS` (or of ``CONFORMAL_METHODS``).
        On a damped model the methods that assume a Hamiltonian
        (``semi_implicit_euler``, ``leapfrog``) raise a ``ValueError``.
    p0 : array_like, shape like ``theta0``, optional
        Initial canonical momenta, instead of ``omega0`` (give exactly one):
        restarting from a saved ``(theta, p)`` then involves no conversion.
    save_every : int
        Keep every ``save_every``-th state (memory for long runs and ensembles).
    progress : bool, optional
        Show a progress bar; by default only for long runs.
    t0 : float
        Start time: the time of ``theta0``, ``omega0`` (the drive of a driven
        model depends on it).

    Returns
    -------
    Trajectory

    Raises
    ------
    ConvergenceError
        If an implicit method's equations do not converge; the message names
        the step and the time.

    Notes
    -----
    Explicit methods can blow up (explicit Euler with a large ``dt``): a single
    trajectory then stops at the first non-finite state with a
    ``RuntimeWarning`` and returns what it computed, with ``completed=False``;
    in an ensemble the other members go on and the blown-up one holds NaN.
    Ensemble members are integrated in parallel threads.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> traj = pl.simulate(pl.simple_pendulum(), [0.5], [0.0], t_end=1.0, dt=0.1, method="rk4")
    >>> traj.theta.shape
    (11, 1)
    """
    check_model(model)
    method = get_method(method)
    theta0 = check.state_array("theta0", theta0, model.n)
    if (omega0 is None) == (p0 is None):
        raise TypeError("give exactly one of `omega0` (angular velocities) and `p0` (momenta)")
    name, start = ("omega0", omega0) if p0 is None else ("p0", p0)
    start = check.state_array(name, start, model.n)
    if theta0.shape != start.shape:
        raise ValueError(
            f"`theta0` and `{name}` must have the same shape, got {theta0.shape} and {start.shape}"
        )
    dt = check.positive_number("dt", dt)
    t0 = check.real_number("t0", t0)
    t_end = check.real_number("t_end", t_end)
    if t_end - t0 < dt:
        after = f" after `t0` ({t0:g})" if t0 else ""
        raise ValueError(f"`t_end` must be at least `dt` ({dt}){after}, got {t_end}")
    save_every = check.integer_at_least("save_every", save_every, 1)
    field = hamiltonian_field(model)
    _check_method_fits(model, method, field)

    n_steps = int(np.floor((t_end - t0) / dt * (1 + 1e-12)))
    n_saved = n_steps // save_every + 1
    canonical = method.variables == "canonical"
    batch_shape = theta0.shape[:-1]
    # Copies: the compiled loop updates its arguments in place.
    q = theta0.reshape(-1, model.n).copy()
    y = start.reshape(-1, model.n)
    if canonical and p0 is None:
        y = model.momenta(q, y)
    elif not canonical and p0 is not None:
        y = model.velocities(q, y)
    y = np.array(y, order="C")
    members = q.shape[0]
    saved_q = np.full((members, n_saved, model.n), np.nan)
    saved_y = np.full((members, n_saved, model.n), np.nan)
    saved_q[:, 0], saved_y[:, 0] = q, y
    stats = np.zeros((members, 4), dtype=np.int64)

    # The compiled loop runs in chunks only so that a progress bar can move.
    chunk = max(1, min(n_steps, CHUNK_WORK // members))
    bar = _progress_bar(n_steps, progress, n_steps * members, method.name)
    start = time.perf_counter()
    try:
        for first in range(0, n_steps, chunk):
            todo = min(chunk, n_steps - first)
            _advance(method, field, q, y, dt, todo, first, save_every, saved_q, saved_y, stats,
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
            f"iterations at step {at} (t = {t0 + at * dt:.6g}, dt = {dt:g}{member}); use a "
            "smaller dt"
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
    if canonical:
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


def warm_up(links=(1, 2), methods=None, progress: bool = True) -> float:
    """Compile now, or load from the disk cache, the kernels a course session uses.

    Numba compiles each kernel the first time it runs on a machine (a few
    seconds each) and keeps the machine code on disk. Calling this ahead of
    time (``pendulum-lab warmup``; the Binder image does it while it is
    built) spares students the wait.

    Parameters
    ----------
    links : sequence of int
        Chain lengths to prepare (1: simple pendulum, 2: double pendulum, ...);
        with 1, the driven pendulum's kernels too.
    methods : sequence of str, optional
        Method names; all of :data:`pendulum_lab.METHODS` and
        ``CONFORMAL_METHODS`` by default.
    progress : bool
        Show a progress bar.

    Returns
    -------
    float
        Seconds spent.
    """
    everything = [*METHODS, *CONFORMAL_METHODS]
    names = [get_method(m).name for m in (everything if methods is None else methods)]
    links = [check.integer_at_least("links", n, 1) for n in links]
    start = time.perf_counter()
    jobs = [(n, name) for n in links for name in names]
    if progress:
        from tqdm.auto import tqdm

        jobs = tqdm(jobs, desc="compiling kernels", unit="kernel")
    for n, name in jobs:
        simulate(n_pendulum(n), np.full(n, 0.1), np.zeros(n), t_end=0.01, dt=0.01, method=name)
    if 1 in links:  # the step kernels take any field: one run compiles the forced field
        simulate(driven_pendulum(), [0.1], [0.0], t_end=0.01, dt=0.01, method=names[0])
    return time.perf_counter() - start
