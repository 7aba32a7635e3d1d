"""The driver: a model, a method and a time grid make a :class:`Trajectory`.

Every function of the package that runs a simulation follows one calling
convention, the one of :func:`simulate`::

    f(model, theta0, omega0=None, *, t_end, dt, method=..., save_every=..., p0=None)

the initial state first (angles, then angular velocities or, with ``p0``,
canonical momenta), everything else by keyword. :func:`step_count` is the one
rule that turns ``t_end`` and ``dt`` into a number of steps. The validation of
these arguments and the limits of a run live in :mod:`~pendulum_lab.driver.arguments`,
the loop of a run from validated arguments (:func:`integrate`) in
:mod:`~pendulum_lab.driver.integration`, the result (:class:`Trajectory`) in
:mod:`~pendulum_lab.driver.trajectory`; their names are importable from here too.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from .. import validation as check
from ..codegen import kernels as codegen
from ..codegen.compile_status import compile_seconds
from ..integrators import (
    HamiltonianField,
    Method,
    get_method,
    suitable_methods,
    unsuitability,
)
from ..model import PendulumModel, SystemModel, require_model
from .arguments import (
    canonical_state,
    check_clock,
    check_memory,
    check_progress,
    check_run_length,
    check_start_defined,
    initial_state,
    memory_needed,
    progress_bar,
    run_arguments,
    step_count,
    time_grid,
    velocity_state,
)
from .integration import integrate, unphysical_stop, warn_not_finite
from .loops import compile_method
from .trajectory import AngleReduction, Trajectory

__all__ = [
    "AngleReduction",
    "Trajectory",
    "canonical_state",
    "check_clock",
    "check_memory",
    "check_method_fits",
    "check_progress",
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
    "unphysical_stop",
    "velocity_state",
    "warn_not_finite",
]

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
    check_start_defined(model, theta0, t0)
    shape = theta0.shape
    members = theta0.size // model.n
    check_memory(memory_needed(model.n, method, members, 1), "one step of "
                 + ("1 state" if members == 1 else f"{members} states"),
                 "Step fewer states at a time.")
    row_models, field, q, y, reduction = prepared_rows(model, method, theta0, start,
                                                       given_momenta=p0 is not None, t0=t0)
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


def prepared_rows(model: PendulumModel, method: Method, theta0: np.ndarray, start: np.ndarray,
                  *, given_momenta: bool, t0: float):
    """What :func:`step` and :func:`simulate` step from, the initial state validated.

    Returns ``(row_models, field, q, y, reduction)``: one model per row of the run (a family's
    members get their own parameters), its compiled field (the method checked to fit it), the
    flattened initial state as new arrays (the compiled loop updates them in place; ``q``
    reduced by whole turns where :class:`AngleReduction` says so, ``y`` in the method's
    variables) and the reduction (None if none).
    """
    row_models = model.for_ensemble(theta0.shape[:-1])
    field = hamiltonian_field(row_models)
    check_method_fits(model, method, field)
    q = theta0.reshape(-1, model.n).copy()
    # the warning names the caller of step() or simulate()
    reduction = AngleReduction.of(q, stacklevel=4) if model.periodic_coordinates else None
    if reduction is not None:
        q = reduction.reduced.copy()
    y = to_method_variables(row_models, method, q, start.reshape(-1, model.n),
                            given_momenta=given_momenta, t=t0)
    return row_models, field, q, y, reduction


def saving_interval(keep, save_every: int, n_steps: int) -> int:
    """The steps between saved states: ``save_every``, or all ``n_steps`` for keep='final'."""
    if check.choice("keep", keep, ("all", "final")) == "all":
        return save_every
    if save_every != 1:
        raise ValueError("give `save_every` only with keep='all' (keep='final' keeps the "
                         "initial and the final state)")
    return n_steps


def check_run_memory(model: PendulumModel, method: Method, members: int, t_end: float,
                     dt: float, n_steps: int, save_every: int) -> None:
    """:func:`check_memory` for :func:`simulate`, naming the arguments that set the need."""
    n_saved = n_steps // save_every + 1
    runs = "1 trajectory" if members == 1 else f"{members} trajectories"
    check_memory(memory_needed(model.n, method, members, n_saved),
                 f"`t_end` = {t_end:g} s with `dt` = {dt:g} s is {n_steps:.3g} steps; with "
                 f"`save_every` = {save_every}, keeping {n_saved:.3g} states of {runs}",
                 "Raise `save_every`, pass keep='final' (the final state only), or choose a "
                 "shorter `t_end` or a larger `dt`" + (" or fewer initial states." if members > 1
                                                       else "."))


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
        Run even beyond :data:`~pendulum_lab.driver.arguments.WORK_BUDGET` state
        updates (steps times trajectories, hours of computing), which is otherwise
        refused before it
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

    Initial angles beyond :data:`~pendulum_lab.driver.trajectory.REDUCE_ANGLES_BEYOND`
    rad are reduced by whole turns before stepping (:class:`AngleReduction`); the saved
    angles start at ``theta0`` and are continuous, and the energies are computed accurately.
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
    save_every = saving_interval(keep, save_every, n_steps)
    progress = check_progress(progress)
    batch_shape = theta0.shape[:-1]
    check_run_memory(model, method, theta0.size // model.n, t_end, dt, n_steps, save_every)
    _, field, q, y, reduction = prepared_rows(model, method, theta0, start,
                                              given_momenta=p0 is not None, t0=t0)
    compiled = compile_method(method, field, model.n)
    compile_time = compile_seconds() - compiled_before[0]
    compiled_anything = compile_seconds(compiled_only=True) > compiled_before[1]
    traj = integrate(model, compiled, q, y, batch_shape, t_end=t_end, dt=dt, n_steps=n_steps,
                     save_every=save_every, t0=t0, progress=progress)
    traj = dataclasses.replace(traj, compile_time=compile_time, compiled=compiled_anything)
    return traj if reduction is None else reduction.restored(traj, batch_shape)
