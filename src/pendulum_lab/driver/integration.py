"""The run itself: from validated arguments and a compiled method to a :class:`Trajectory`.

:func:`integrate` steps the flattened ensemble with the compiled loop, in chunks so that a
progress bar can move, then converts the saved states (velocities, momenta, energies) and
stops a trajectory that left the finite numbers or the physical states, with the warning
that says where and why (:func:`warn_not_finite`, :func:`unphysical_stop`).
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from .. import validation as check
from ..integrators import MAX_SWEEPS, ConvergenceError, Method
from ..model import PendulumModel
from .arguments import memory_needed, progress_bar
from .loops import (
    CALLS,
    NOT_CONVERGED,
    NOT_FINITE,
    RUNNING,
    STATUS,
    STEPS,
    SWEEPS,
    CompiledMethod,
)
from .trajectory import ANGLE_SPACING_WARNING, Trajectory

__all__ = ["integrate", "unphysical_stop", "warn_not_finite"]

# State updates per call of the compiled loop (a fraction of a second).
CHUNK_WORK = 200_000


def warn_not_finite(method: Method, first_bad: int, t: float, count: int, members: int,
                    what_follows: str, stacklevel: int = 3) -> None:
    """The one warning of a state that became non-finite (:func:`~pendulum_lab.simulate` and
    :func:`~pendulum_lab.step`).

    Neither raises: the states computed are returned, and the warning says where the first
    non-finite one appeared and what the result holds from there.
    """
    warnings.warn(
        f"{method.name}: the state became non-finite at step {first_bad} (t = {t:.6g}) in "
        f"{count} of {members} trajectories; {what_follows} Try a smaller dt.",
        RuntimeWarning,
        stacklevel=stacklevel,
    )


def integrate(model: PendulumModel, compiled: CompiledMethod, q, y, batch_shape: tuple, *,
              t_end: float, dt: float, n_steps: int, save_every: int, t0: float, progress,
              memory=None, first_step: int = 0) -> Trajectory:
    """The run of :func:`~pendulum_lab.simulate` from validated arguments; ``q``, ``y`` are
    updated in place.

    ``compiled`` is the method compiled for the run's field
    (:func:`~pendulum_lab.driver.loops.compile_method`). ``q`` and ``y`` (shape ``(K, n)``,
    ``y`` in the method's variables) are the flattened ensemble of shape ``batch_shape``;
    ``memory`` (shape ``(K, S)``, :meth:`~pendulum_lab.driver.loops.CompiledMethod.new_memory`,
    updated in place) is what the method carries from step to step; a fresh one by default.
    Passing the memory of the previous call, with ``first_step`` the steps it has taken since
    ``t0`` (a multiple of ``save_every``), continues that run exactly: the same step times
    and saved times, computed from the step's number since ``t0``
    (:func:`pendulum_lab.simulate_segments` does). The callers have checked the memory needed
    (:func:`~pendulum_lab.driver.arguments.check_memory`), before any work.
    """
    method = compiled.method
    n_saved = n_steps // save_every + 1
    members = q.shape[0]
    memory, saved_q, saved_y = _run_storage(model, compiled, memory, members, n_saved)
    saved_q[:, 0], saved_y[:, 0] = q, y
    stats = np.zeros((members, 4), dtype=np.int64)
    wall = _advance_in_chunks(compiled, q, y, dt, n_steps, first_step, save_every, saved_q,
                              saved_y, stats, memory, t0, progress)
    _check_converged(method, stats, first_step, t0, dt, batch_shape)
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
    stopped = _stopped_unphysical(model, method, (theta, omega, p, kinetic, potential, times),
                                  at, batch_shape)
    if stopped is not None:
        completed = False
        theta, omega, p, kinetic, potential, times = stopped
        at = at[:len(times)]
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


def _run_storage(model: PendulumModel, compiled: CompiledMethod, memory, members: int,
                 n_saved: int):
    """The method's memory (``memory``, or a fresh one) and the arrays of the saved states."""
    try:
        if memory is None:
            memory = compiled.new_memory(members)
        saved_q = np.full((members, n_saved, model.n), np.nan)
        saved_y = np.full((members, n_saved, model.n), np.nan)
    except MemoryError:  # the callers check first; memory may still run out in the meantime
        method = compiled.method
        raise MemoryError(
            f"keeping {n_saved:.3g} states of {members} trajectories ({model.n} links, "
            f"{method.name}) needs about "
            f"{check.bytes_text(memory_needed(model.n, method, members, n_saved))} of memory, "
            "which this machine no longer has available; raise `save_every` or run fewer "
            "trajectories"
        ) from None
    return memory, saved_q, saved_y


def _advance_in_chunks(compiled: CompiledMethod, q, y, dt, n_steps, first_step, save_every,
                       saved_q, saved_y, stats, memory, t0, progress) -> float:
    """Run the compiled loop over ``n_steps`` steps; the seconds it took.

    It runs in chunks only so that a progress bar can move, and stops early once no
    trajectory is still running.
    """
    members = q.shape[0]
    chunk = max(1, min(n_steps, CHUNK_WORK // members))
    bar = progress_bar(n_steps, n_steps * members, progress, compiled.method.name)
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
    return time.perf_counter() - start


def _check_converged(method: Method, stats, first_step: int, t0: float, dt: float,
                     batch_shape: tuple) -> None:
    """A :class:`ConvergenceError` naming the earliest step whose implicit equations failed."""
    failed = np.flatnonzero(stats[:, STATUS] == NOT_CONVERGED)
    if not failed.size:
        return
    k = failed[np.argmin(stats[failed, STEPS])]
    at = first_step + int(stats[k, STEPS]) + 1
    member = f", ensemble member {np.unravel_index(k, batch_shape)}" if batch_shape else ""
    raise ConvergenceError(
        f"{method.name}: the implicit equations did not converge within {MAX_SWEEPS} "
        f"iterations at step {at} (t = {t0 + at * dt:.6g}, dt = {dt:g}{member}); "
        "use a smaller dt"
    )


def _stopped_unphysical(model, method: Method, saved: tuple, at, batch_shape: tuple):
    """The saved ``(theta, omega, p, kinetic, potential, times)`` cut where
    :func:`unphysical_stop` says (a single trajectory) or NaN from there (an ensemble), with a
    ``RuntimeWarning`` saying why; None if no trajectory must stop."""
    theta, omega, p, kinetic, potential, times = saved
    stop = unphysical_stop(model, theta, kinetic + potential, at, batch_shape)
    if stop is None:
        return None
    first, reason = stop
    kept = len(times)
    members_stopped = int(np.count_nonzero(first < kept))
    warnings.warn(
        f"{method.name}: the run stops at t = "
        f"{float(times[min(int(first.min()), kept - 1)]):.6g} in {members_stopped} of "
        f"{first.size} trajectories: {reason}; "
        + ("the trajectory stops there." if not batch_shape
           else "those trajectories hold NaN from there on."),
        RuntimeWarning, stacklevel=4)
    if not batch_shape:
        kept = int(first[0])
        return tuple(a[:kept] for a in saved)
    after = (np.arange(kept).reshape(-1, 1) >= first.reshape(1, -1)).reshape(kept, *batch_shape)
    theta, omega, p = (np.where(after[..., None], np.nan, a) for a in (theta, omega, p))
    kinetic, potential = (np.where(after, np.nan, a) for a in (kinetic, potential))
    return theta, omega, p, kinetic, potential, times


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
