"""The driver: a model, a method and a time grid make a :class:`Trajectory`."""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass

import numpy as np

from . import _validation as check
from .integrators import ConvergenceError, HamiltonianField, Method, get_method
from .model import PendulumModel

__all__ = ["Trajectory", "hamiltonian_field", "simulate", "step"]

# Show a progress bar by default once a run does this many state updates
# (steps times ensemble size): about two seconds of work or more.
PROGRESS_THRESHOLD = 200_000


@dataclass(frozen=True)
class Trajectory:
    """A computed trajectory. Arrays have the time axis first.

    Attributes
    ----------
    t : ndarray, shape (N+1,)
    theta, omega, p : ndarray, shape (N+1, ..., n)
        Angles, angular velocities and canonical momenta (``...`` is the
        ensemble shape of the initial state, empty for one trajectory).
    kinetic, potential, energy : ndarray, shape (N+1, ...)
    method : Method
    dt : float
    mean_iterations : float
        Mean implicit-solver sweeps per step (0 for explicit methods).
    evaluations : int
        Calls of the vector-field functions (``dH/dq``, ``dH/dp`` or the
        acceleration), each on the whole ensemble.
    wall_time : float
        Seconds spent stepping.
    completed : bool
        False if the run stopped early at a non-finite state.
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


class _Counter:
    """Wraps a function and counts its calls (for work-precision diagrams)."""

    def __init__(self, fn):
        self.fn, self.calls = fn, 0

    def __call__(self, *args):
        self.calls += 1
        return self.fn(*args)


def hamiltonian_field(model: PendulumModel) -> HamiltonianField:
    """The model's Hamiltonian vector field, as the integrators expect it."""
    return HamiltonianField(model.dH_dq, model.dH_dp, model.accelerations, model.separable)


def _check_model(model):
    if not isinstance(model, PendulumModel):
        raise TypeError(
            "`model` must be a PendulumModel (from simple_pendulum, double_pendulum or "
            f"n_pendulum), got {type(model).__name__}"
        )


def step(model: PendulumModel, method, q0, p0, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """One step of ``method`` in canonical variables ``(theta, p)``.

    The velocity-variable methods are converted ``p -> omega`` before and back
    after their step, so all methods can be compared as maps of ``(theta, p)``.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> q1, p1 = pl.step(pl.simple_pendulum(), "leapfrog", [0.1], [0.0], 0.01)
    >>> q1.shape
    (1,)
    """
    _check_model(model)
    method = get_method(method)
    q0 = check.state_array("q0", q0, model.n)
    p0 = check.state_array("p0", p0, model.n)
    dt = check.real_number("dt", dt)
    if dt == 0:
        raise ValueError("`dt` must be non-zero (negative dt steps backwards in time)")
    field = hamiltonian_field(model)
    if method.variables == "velocity":
        q1, v1, _ = method.step(field, q0, model.velocities(q0, p0), dt)
        return q1, model.momenta(q1, v1)
    q1, p1, _ = method.step(field, q0, p0, dt)
    return q1, p1


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
    omega0,
    t_end: float = 20.0,
    dt: float = 0.01,
    method="glrk4",
    *,
    save_every: int = 1,
    progress: bool | None = None,
) -> Trajectory:
    """Integrate the pendulum from ``(theta0, omega0)`` over ``[0, t_end]``.

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0 : array_like, shape (n,) or (..., n)
        Initial angles [rad] and angular velocities [rad/s]. Leading axes
        make an ensemble, integrated together.
    t_end : float
        Final time, ``t_end >= dt``; the run takes ``floor(t_end / dt)`` steps.
    dt : float
        Step size, ``> 0``.
    method : str or Method
        A key of :data:`pendulum_lab.METHODS`.
    save_every : int
        Keep every ``save_every``-th state (memory for long runs and ensembles).
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

    Notes
    -----
    Explicit methods can blow up (explicit Euler with a large ``dt``): the run
    then stops at the first non-finite state with a ``RuntimeWarning`` and
    returns what it computed, with ``completed=False``.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> traj = pl.simulate(pl.simple_pendulum(), [0.5], [0.0], t_end=1.0, dt=0.1, method="rk4")
    >>> traj.theta.shape
    (11, 1)
    """
    _check_model(model)
    method = get_method(method)
    theta0 = check.state_array("theta0", theta0, model.n)
    omega0 = check.state_array("omega0", omega0, model.n)
    if theta0.shape != omega0.shape:
        raise ValueError(
            f"`theta0` and `omega0` must have the same shape, got {theta0.shape} and {omega0.shape}"
        )
    dt = check.positive_number("dt", dt)
    t_end = check.positive_number("t_end", t_end)
    if t_end < dt:
        raise ValueError(f"`t_end` must be at least `dt` ({dt}), got {t_end}")
    save_every = check.integer_at_least("save_every", save_every, 1)

    n_steps = int(np.floor(t_end / dt * (1 + 1e-12)))
    n_saved = n_steps // save_every + 1
    canonical = method.variables == "canonical"
    x = theta0.copy()
    y = model.momenta(theta0, omega0) if canonical else omega0.copy()
    xs = np.empty((n_saved, *x.shape))
    ys = np.empty((n_saved, *x.shape))
    xs[0], ys[0] = x, y

    counters = [_Counter(f) for f in (model.dH_dq, model.dH_dp, model.accelerations)]
    field = HamiltonianField(*counters, separable=model.separable)
    bar = _progress_bar(n_steps, progress, n_steps * max(1, x.size // model.n), method.name)
    iterations, taken, completed = 0, 0, True
    start = time.perf_counter()
    try:
        for k in range(1, n_steps + 1):
            try:
                x_new, y_new, sweeps = method.step(field, x, y, dt)
            except ConvergenceError as err:
                raise ConvergenceError(
                    f"{method.name}: {err} (step {k}, t = {k * dt:.6g}, dt = {dt:g})"
                ) from None
            if not (np.all(np.isfinite(x_new)) and np.all(np.isfinite(y_new))):
                completed = False
                warnings.warn(
                    f"{method.name}: the state became non-finite at step {k} "
                    f"(t = {k * dt:.6g}); the trajectory stops there. Try a smaller dt.",
                    RuntimeWarning,
                    stacklevel=2,
                )
                break
            x, y, taken = x_new, y_new, k
            iterations += sweeps
            if k % save_every == 0:
                xs[k // save_every], ys[k // save_every] = x, y
            if bar is not None:
                bar.update(1)
    finally:
        if bar is not None:
            bar.close()
    wall = time.perf_counter() - start

    kept = taken // save_every + 1
    theta = xs[:kept]
    if canonical:
        p, omega = ys[:kept], model.velocities(theta, ys[:kept])
    else:
        omega, p = ys[:kept], model.momenta(theta, ys[:kept])
    kinetic = model.kinetic_energy(theta, omega)
    potential = model.potential_energy(theta)
    return Trajectory(
        t=np.arange(kept) * (save_every * dt),
        theta=theta,
        omega=omega,
        p=p,
        kinetic=kinetic,
        potential=potential,
        energy=kinetic + potential,
        method=method,
        dt=dt,
        mean_iterations=iterations / max(taken, 1),
        evaluations=sum(c.calls for c in counters),
        wall_time=wall,
        completed=completed,
    )
