"""Chaos in the double pendulum, and longer chains.

The course report (Kanoun, Cowley, Ivachtchenko, MAT332, 2024) observes that
small changes of the initial conditions of the double pendulum give radically
different motion, and names the n-pendulum as future work. This module turns
both into measurements:

* :func:`ensemble`: many initial conditions at once, keeping only what is asked
  for (final states or a thinned trajectory);
* :func:`separation`: phase-space distance of two nearby trajectories;
* :func:`lyapunov_benettin` and :func:`lyapunov_variational`: the largest
  Lyapunov exponent, by two independent methods;
* :func:`section_states`, :func:`poincare_section` and :func:`energy_sections`:
  Poincare sections on energy levels, with crossings located to round-off;
* :func:`can_flip` and :func:`flip_time_map`: Heyl's flip-time fractal;
* :func:`small_angle_comparison`: where the linearised motion and the full
  motion part;
* :func:`chain_costs` and :func:`compare_energy`: the n-pendulum.

Every trajectory comes from :func:`pendulum_lab.simulate` or
:func:`pendulum_lab.step`; nothing here steps the equations of motion itself.
Long runs are split into consecutive ``simulate`` calls ("chunks"), each
started from the previous one's last state, so memory grows with what is
kept, not with the number of steps.

Notes
-----
Phase-space distances are Euclidean in the canonical variables
``(theta, p)`` (radians and kg m^2/s). The largest Lyapunov exponent does not
depend on that choice of norm; finite-time estimates do, a little.

References
----------
.. [Benettin] G. Benettin, L. Galgani, A. Giorgilli, J.-M. Strelcyn,
   "Lyapunov characteristic exponents for smooth dynamical systems and for
   Hamiltonian systems; a method for computing all of them", Meccanica 15
   (1980) 9-20 and 21-30.
.. [Henon] M. Henon, "On the numerical computation of Poincare maps",
   Physica D 5 (1982) 412-414.
.. [Heyl] J. S. Heyl, "The double pendulum fractal", 2008.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from sympy.core.cache import clear_cache

from . import _validation as check
from .integrators import ConvergenceError, get_method
from .mechanics import Chain
from .model import PendulumModel, check_model, n_pendulum
from .simulate import PROGRESS_THRESHOLD, Trajectory, simulate, step

__all__ = [
    "ChainCost",
    "EnergyComparison",
    "FlipMap",
    "LyapunovEstimate",
    "PoincareSection",
    "Separation",
    "SmallAngleComparison",
    "can_flip",
    "chain_costs",
    "compare_energy",
    "energy_sections",
    "ensemble",
    "flip_time_map",
    "lyapunov_benettin",
    "lyapunov_variational",
    "plot_sections",
    "poincare_section",
    "section_states",
    "separation",
    "separation_panel",
    "small_angle_comparison",
]

# Largest number of saved floats (states x members x links) one chunk may hold
# when every step is kept for event detection: about 16 MB per array.
_CHUNK_FLOATS = 1 << 21
# Long runs are cut into at least this many chunks so a progress bar moves.
_PROGRESS_UPDATES = 50
# Fewer steps than this per chunk would make the per-call overhead dominate.
_MIN_CHUNK = 1000


# --------------------------------------------------------------------------- helpers
def _initial_state(model, theta0, omega0):
    theta0 = check.state_array("theta0", theta0, model.n)
    omega0 = check.state_array("omega0", omega0, model.n)
    if theta0.shape != omega0.shape:
        raise ValueError(
            f"`theta0` and `omega0` must have the same shape, got {theta0.shape} and {omega0.shape}"
        )
    return theta0, omega0


def _step_count(t_end, dt) -> tuple[float, float, int]:
    """Validated ``(t_end, dt, number of steps)``, counted as :func:`simulate` counts them."""
    dt = check.positive_number("dt", dt)
    t_end = check.positive_number("t_end", t_end)
    if t_end < dt:
        raise ValueError(f"`t_end` must be at least `dt` ({dt}), got {t_end}")
    return t_end, dt, int(np.floor(t_end / dt * (1 + 1e-12)))


def _chunk_length(n_steps: int, floats_per_step: int | None, stride: int = 1) -> int:
    """Steps per ``simulate`` call: few calls, bounded memory, a moving progress bar.

    ``floats_per_step`` is what one kept step costs in memory (``None`` when a
    call keeps only its last state). The length is a multiple of ``stride``.
    """
    length = max(math.ceil(n_steps / _PROGRESS_UPDATES), _MIN_CHUNK)
    if floats_per_step:
        length = min(length, max(stride, _CHUNK_FLOATS // floats_per_step))
    length = stride * max(1, math.ceil(length / stride))
    return min(length, n_steps)


class _Progress:
    """A tqdm bar over steps, shown by default once the work is a few seconds' worth."""

    def __init__(self, total: int, members: int, enabled, label: str):
        if enabled is None:
            enabled = total * max(1, members) >= PROGRESS_THRESHOLD
        self.bar = None
        if enabled:
            from tqdm.auto import tqdm

            self.bar = tqdm(total=total, desc=label, unit="step", mininterval=0.5)

    def update(self, steps: int):
        if self.bar is not None:
            self.bar.update(steps)

    def close(self):
        if self.bar is not None:
            self.bar.close()


def _advance(
    model, theta, omega, steps: int, dt: float, method, save_every: int, t_start: float
) -> Trajectory:
    """``steps`` steps from ``(theta, omega)`` by one :func:`simulate` call.

    ``simulate`` counts time from the segment's start; a
    :class:`ConvergenceError` is re-raised with the segment's absolute time.
    """
    try:
        return simulate(
            model,
            theta,
            omega,
            t_end=steps * dt,
            dt=dt,
            method=method,
            save_every=save_every,
            progress=False,
        )
    except ConvergenceError as err:
        raise ConvergenceError(
            f"{err} [in the run segment starting at t = {t_start:.6g}]"
        ) from None


def _require_finite(traj: Trajectory, what: str):
    if not traj.completed:
        raise FloatingPointError(
            f"{what}: the trajectory became non-finite ({traj.method.name}, dt = {traj.dt:g}); "
            "use a smaller `dt`"
        )


def _wrap(angle):
    """Angles wrapped to ``[-pi, pi)``."""
    return (np.asarray(angle) + np.pi) % (2 * np.pi) - np.pi


def _unit_direction(dim: int, seed) -> np.ndarray:
    """A reproducible random unit vector of length ``dim``."""
    u = np.random.default_rng(seed).standard_normal(dim)
    return u / np.linalg.norm(u)


def _phase_distance(theta_a, p_a, theta_b, p_b, wrap: bool = False) -> np.ndarray:
    """Euclidean distance in ``(theta, p)``; with ``wrap`` angle differences are wrapped."""
    dtheta = np.asarray(theta_a) - np.asarray(theta_b)
    if wrap:
        dtheta = _wrap(dtheta)
    dp = np.asarray(p_a) - np.asarray(p_b)
    return np.sqrt(np.sum(dtheta**2, axis=-1) + np.sum(dp**2, axis=-1))


def _axes(ax, width: float = 6.4, height: float = 3.6):
    """``ax``, or the axes of a new Figure made by :func:`pendulum_lab.plotting.new_figure`."""
    if ax is not None:
        return ax
    from .plotting import new_figure

    return new_figure(width=width, height=height)[1]


def _scalar_or_array(x):
    x = np.asarray(x)
    return float(x) if x.ndim == 0 else x


# --------------------------------------------------------------------------- ensembles
def ensemble(
    model: PendulumModel,
    theta0,
    omega0,
    t_end: float,
    dt: float = 0.01,
    method="glrk4",
    *,
    keep: str = "final",
    every: int = 1,
    progress: bool | None = None,
) -> Trajectory:
    """Integrate many initial conditions together, keeping only what is asked for.

    The run is split into consecutive :func:`~pendulum_lab.simulate` calls,
    each started from the previous one's last state, so memory is
    proportional to the states kept, not to the number of steps.

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0 : array_like, shape (..., n)
        Initial angles [rad] and angular velocities [rad/s]; the leading axes
        index the members of the ensemble.
    t_end : float
        Final time [s]; the run takes ``floor(t_end / dt)`` steps, as
        :func:`~pendulum_lab.simulate` does.
    dt : float
        Step size [s], ``> 0``.
    method : str or Method
        A key of :data:`pendulum_lab.METHODS`.
    keep : {"final", "thinned"}
        ``"final"``: the initial and the final state (two time points).
        ``"thinned"``: every ``every``-th state.
    every : int
        Thinning stride for ``keep="thinned"``, ``>= 1``.
    progress : bool, optional
        Show a progress bar (console or notebook); by default only for runs
        of a few seconds or more.

    Returns
    -------
    Trajectory
        As from :func:`~pendulum_lab.simulate`, holding the kept states:
        ``t`` of shape ``(S,)``, ``theta``, ``omega``, ``p`` of shape
        ``(S, ..., n)``, energies of shape ``(S, ...)``.

    Notes
    -----
    Each segment restarts from angular velocities, which ``simulate`` turns
    back into momenta: for the canonical methods this adds a rounding error of
    about 1e-16 at each segment boundary. Over a chaotic run that rounding is
    amplified like any other, so a chunked run and a single ``simulate`` run
    agree to round-off only for a few Lyapunov times.

    If some member's state becomes non-finite (an explicit method with too
    large a ``dt``), ``simulate`` warns, and the run stops at the end of that
    segment with ``completed=False``.

    Examples
    --------
    >>> import numpy as np, pendulum_lab as pl
    >>> theta0 = np.array([[0.1, 0.2], [1.0, 1.5], [2.0, 2.5]])
    >>> traj = ensemble(pl.double_pendulum(), theta0, np.zeros_like(theta0), t_end=1.0,
    ...                 dt=0.01, method="rk4")
    >>> traj.t.tolist(), traj.theta.shape
    ([0.0, 1.0], (2, 3, 2))
    """
    check_model(model)
    method = get_method(method)
    theta0, omega0 = _initial_state(model, theta0, omega0)
    t_end, dt, n_steps = _step_count(t_end, dt)
    if keep not in ("final", "thinned"):
        raise ValueError(f"`keep` must be one of ['final', 'thinned'], got {keep!r}")
    every = check.integer_at_least("every", every, 1)
    thinned = keep == "thinned"
    members = theta0.size // model.n
    # Memory per kept state: theta, omega, p and the three energies, per member.
    length = (
        _chunk_length(n_steps, max(1, (3 * model.n + 3) * members // every), every)
        if thinned
        else _chunk_length(n_steps, None)
    )

    pieces, offsets = [], []
    theta, omega = theta0, omega0
    done, sweeps, evaluations, wall = 0, 0.0, 0, 0.0
    bar = _Progress(n_steps, members, progress, f"ensemble ({method.name})")
    try:
        while done < n_steps:
            steps = min(length, n_steps - done)
            traj = _advance(
                model, theta, omega, steps, dt, method, every if thinned else steps, done * dt
            )
            pieces.append(traj)
            offsets.append(done * dt)
            sweeps += traj.mean_iterations * steps
            evaluations += traj.evaluations
            wall += traj.wall_time
            done += steps
            bar.update(steps)
            if not traj.completed:
                break
            theta, omega = traj.theta[-1], traj.omega[-1]
    finally:
        bar.close()

    if thinned:
        # Each piece starts where the previous one ended: drop the repeated state.
        t = np.concatenate(
            [pieces[0].t] + [off + pc.t[1:] for off, pc in zip(offsets[1:], pieces[1:])]
        )

        def join(name):
            return np.concatenate(
                [getattr(pieces[0], name)] + [getattr(pc, name)[1:] for pc in pieces[1:]]
            )
    else:
        t = np.array([0.0, offsets[-1] + pieces[-1].t[-1]])

        def join(name):
            return np.stack([getattr(pieces[0], name)[0], getattr(pieces[-1], name)[-1]])

    names = ("theta", "omega", "p", "kinetic", "potential", "energy")
    return Trajectory(
        t=t,
        **{name: join(name) for name in names},
        method=method,
        dt=dt,
        mean_iterations=sweeps / max(done, 1),
        evaluations=evaluations,
        wall_time=wall,
        completed=pieces[-1].completed,
    )


# --------------------------------------------------------------------------- separation
@dataclass(frozen=True)
class Separation:
    """Phase-space distance between a trajectory and a slightly perturbed copy.

    Attributes
    ----------
    t : ndarray, shape (S,)
    distance : ndarray, shape (S, ...)
        Euclidean distance in ``(theta, p)``, angle differences wrapped to
        ``[-pi, pi)`` (so it saturates at the size of the accessible region).
    delta : float
        Initial distance.
    trajectory : Trajectory
        Both runs, the reference first: ``theta`` of shape ``(S, 2, ..., n)``.
    """

    t: np.ndarray
    distance: np.ndarray
    delta: float
    trajectory: Trajectory

    def plot(self, ax=None, label=None, **kwargs):
        """Distance against time on a log scale; returns the Figure."""
        ax = _axes(ax)
        ax.semilogy(self.t, self.distance, label=label, **kwargs)
        ax.set(xlabel="t (s)", ylabel="distance in (theta, p)")
        if label is not None:
            ax.legend(fontsize="small")
        return ax.figure


def separation(
    model: PendulumModel,
    theta0,
    omega0,
    t_end: float,
    dt: float = 0.01,
    method="glrk4",
    *,
    delta: float = 1e-9,
    every: int = 1,
    seed=0,
    progress: bool | None = None,
) -> Separation:
    """Distance versus time between two trajectories that start ``delta`` apart.

    The perturbation has length ``delta`` in ``(theta, p)`` along a random
    direction fixed by ``seed``. Both runs are one ensemble of two members.
    On a chaotic orbit the distance grows like ``delta exp(lambda t)`` (a
    straight line on a log scale, slope the largest Lyapunov exponent) until
    it saturates; on a regular orbit it grows at most linearly.

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0 : array_like, shape (..., n)
    t_end, dt, method
        As for :func:`ensemble`.
    delta : float
        Initial distance, ``> 0``.
    every : int
        Keep every ``every``-th step.
    seed : int or None
        Seed of the perturbation direction.
    progress : bool, optional

    Returns
    -------
    Separation

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> sep = separation(pl.double_pendulum(), [2.0, 2.5], [0.0, 0.0], t_end=5.0,
    ...                  method="rk4")
    >>> bool(sep.distance[-1] > 100 * sep.delta)
    True
    """
    check_model(model)
    theta0, omega0 = _initial_state(model, theta0, omega0)
    delta = check.positive_number("delta", delta)
    n = model.n
    u = _unit_direction(2 * n, seed)
    p0 = model.momenta(theta0, omega0)
    theta1 = theta0 + delta * u[:n]
    omega1 = model.velocities(theta1, p0 + delta * u[n:])
    traj = ensemble(
        model,
        np.stack([theta0, theta1]),
        np.stack([omega0, omega1]),
        t_end,
        dt,
        method,
        keep="thinned",
        every=every,
        progress=progress,
    )
    distance = _phase_distance(
        traj.theta[:, 0], traj.p[:, 0], traj.theta[:, 1], traj.p[:, 1], wrap=True
    )
    return Separation(traj.t, distance, delta, traj)


def separation_panel(ax, trajectory: Trajectory, model: PendulumModel) -> None:
    """A panel for :func:`pendulum_lab.widgets.explore`: the separation from this start.

    Runs :func:`separation` from the trajectory's initial state, with its
    method, step and duration, and draws the distance on a log scale with a
    dashed line at the initial distance.
    """
    sep = separation(
        model,
        trajectory.theta[0],
        trajectory.omega[0],
        trajectory.t[-1],
        trajectory.dt,
        trajectory.method,
        progress=False,
    )
    sep.plot(ax=ax, color="tab:red", lw=1)
    ax.axhline(sep.delta, color="0.6", lw=0.8, ls="--")
    ax.set_title(f"Separation from a start {sep.delta:g} away")


# --------------------------------------------------------------------------- Lyapunov
@dataclass(frozen=True)
class LyapunovEstimate:
    """Running estimate of the largest Lyapunov exponent.

    Attributes
    ----------
    t : ndarray, shape (J,)
        Times of the estimates [s].
    running : ndarray, shape (J, ...)
        ``(1/t) sum log(growth)`` up to each time [1/s]; ``...`` is the
        ensemble shape of the initial state.
    approach : {"benettin", "variational"}
    method : str
        The integrator that produced the trajectory.
    dt : float
    wall_time : float
        Seconds of computation.
    """

    t: np.ndarray
    running: np.ndarray
    approach: str
    method: str
    dt: float
    wall_time: float

    @property
    def exponent(self):
        """The estimate at the final time [1/s] (float, or array for an ensemble)."""
        return _scalar_or_array(self.running[-1])

    def at(self, time: float):
        """The running estimate at the recorded time closest to ``time``."""
        return _scalar_or_array(self.running[int(np.argmin(np.abs(self.t - time)))])

    def plot(self, ax=None, label=None, **kwargs):
        """Running estimate against time (log time axis); returns the Figure.

        For an ensemble, one line per member.
        """
        ax = _axes(ax)
        if label is None:
            label = f"{self.approach}, {self.method}"
        lines = ax.semilogx(self.t, self.running.reshape(len(self.t), -1), **kwargs)
        lines[0].set_label(label)
        ax.axhline(0.0, color="0.6", lw=0.8)
        ax.set(xlabel="t (s)", ylabel="running estimate of lambda_1 (1/s)")
        ax.legend(fontsize="small")
        return ax.figure


def lyapunov_benettin(
    model: PendulumModel,
    theta0,
    omega0,
    t_end: float,
    dt: float = 0.01,
    method="glrk4",
    *,
    delta: float = 1e-8,
    renormalize_every: int = 50,
    seed=0,
    progress: bool | None = None,
) -> LyapunovEstimate:
    """Largest Lyapunov exponent by Benettin's two-trajectory method.

    A companion trajectory starts ``delta`` away from the reference (in
    ``(theta, p)``, direction fixed by ``seed``). Every ``renormalize_every``
    steps the distance ``d`` is measured, ``log(d / delta)`` is added to a sum,
    and the companion is pulled back along the same direction to distance
    ``delta``. The running estimate is the sum divided by the elapsed time.
    Renormalising keeps the separation in the linear regime (``delta`` small)
    while following the most unstable direction, which it aligns with after a
    transient. The reference trajectory is computed in the same segments as in
    :func:`lyapunov_variational`, so with the same ``method``, ``dt``,
    ``seed`` and interval the two estimators follow the same trajectory from
    the same initial direction and differ only in how the growth of a small
    perturbation is computed.

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0 : array_like, shape (..., n)
        One initial state or an ensemble of them.
    t_end, dt, method
        As for :func:`ensemble`; the estimate uses whole renormalisation
        intervals, ``floor(n_steps / renormalize_every)`` of them.
    delta : float
        Separation after each renormalisation, ``> 0``; 1e-8 keeps it both
        linear and well above round-off.
    renormalize_every : int
        Steps between renormalisations, ``>= 1``.
    seed : int or None
        Seed of the initial perturbation direction.
    progress : bool, optional

    Returns
    -------
    LyapunovEstimate

    Raises
    ------
    FloatingPointError
        If the integration blows up.

    References
    ----------
    Benettin, Galgani, Giorgilli, Strelcyn, Meccanica 15 (1980) 9-30.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> est = lyapunov_benettin(pl.double_pendulum(), [2.0, 2.5], [0.0, 0.0], t_end=5.0,
    ...                         method="rk4")
    >>> bool(est.exponent > 0.5)
    True
    """
    check_model(model)
    method = get_method(method)
    theta0, omega0 = _initial_state(model, theta0, omega0)
    t_end, dt, n_steps = _step_count(t_end, dt)
    delta = check.positive_number("delta", delta)
    every = check.integer_at_least("renormalize_every", renormalize_every, 1)
    intervals = n_steps // every
    if intervals < 1:
        raise ValueError(
            f"`t_end` ({t_end}) must cover at least one renormalisation interval "
            f"({every} steps of {dt})"
        )
    n, batch = model.n, theta0.shape[:-1]
    total = intervals * every
    length = _tangent_chunk(total, batch, n, every)
    u = _unit_direction(2 * n, seed)
    p0 = model.momenta(theta0, omega0)
    q_cmp, p_cmp = theta0 + delta * u[:n], p0 + delta * u[n:]
    omega_cmp = model.velocities(q_cmp, p_cmp)
    theta, omega = theta0, omega0
    log_sum = np.zeros(batch)
    running = np.empty((intervals, *batch))
    done, j = 0, 0
    start = time.perf_counter()
    bar = _Progress(total, 2 * log_sum.size, progress, "Benettin")
    try:
        while done < total:
            # The reference runs in the same segments as in lyapunov_variational, so the
            # two estimators follow the same trajectory; the companion runs interval by
            # interval because each renormalisation needs the previous one.
            steps = min(length, total - done)
            ref = _advance(model, theta, omega, steps, dt, method, every, done * dt)
            _require_finite(ref, "lyapunov_benettin")
            for k in range(1, len(ref.t)):
                cmp = _advance(model, q_cmp, omega_cmp, every, dt, method, every, (j * every) * dt)
                _require_finite(cmp, "lyapunov_benettin")
                q_ref, p_ref = ref.theta[k], ref.p[k]
                q_cmp, p_cmp = cmp.theta[-1], cmp.p[-1]
                d = _phase_distance(q_ref, p_ref, q_cmp, p_cmp)
                log_sum += np.log(d / delta)
                j += 1
                running[j - 1] = log_sum / (j * every * dt)
                shrink = (delta / d)[..., None]
                q_cmp = q_ref + shrink * (q_cmp - q_ref)
                omega_cmp = model.velocities(q_cmp, p_ref + shrink * (p_cmp - p_ref))
            theta, omega = ref.theta[-1], ref.omega[-1]
            done += steps
            bar.update(steps)
    finally:
        bar.close()
    t = (np.arange(intervals) + 1) * every * dt
    return LyapunovEstimate(t, running, "benettin", method.name, dt, time.perf_counter() - start)


def _tangent_chunk(total: int, batch: tuple, n: int, every: int) -> int:
    """Segment length shared by both Lyapunov estimators (memory: Jacobians of a segment)."""
    members = int(np.prod(batch, dtype=int))
    return _chunk_length(total, 4 * max(1, members) * (2 * n) ** 2, every)


def _ordered_product(mats: np.ndarray) -> np.ndarray:
    """``M[:, r-1] @ ... @ M[:, 1] @ M[:, 0]`` for ``mats`` of shape ``(B, r, ..., k, k)``.

    Pairwise (tree) reduction: ``log2(r)`` vectorised matrix products
    instead of ``r`` sequential ones. The later factor multiplies from the left.
    """
    while mats.shape[1] > 1:
        if mats.shape[1] % 2:
            eye = np.broadcast_to(np.eye(mats.shape[-1]), mats[:, :1].shape)
            mats = np.concatenate([mats, eye], axis=1)
        mats = mats[:, 1::2] @ mats[:, 0::2]
    return mats[:, 0]


def _magnus_propagators(model, traj: Trajectory, dt: float) -> np.ndarray:
    """Fourth-order Magnus propagators of ``v' = A(t) v`` for each step of ``traj``.

    Returns shape ``(L, ..., 2n, 2n)`` for ``L`` steps; see
    :func:`lyapunov_variational`.
    """
    n = traj.theta.shape[-1]
    z = np.concatenate([traj.theta, traj.p], axis=-1)
    slope = dt * np.concatenate([traj.omega, -model.dH_dq(traj.theta, traj.p)], axis=-1)
    z0, z1, d0, d1 = z[:-1], z[1:], slope[:-1], slope[1:]
    jacobians = []
    for s in (0.5 - np.sqrt(3) / 6, 0.5 + np.sqrt(3) / 6):
        zs = (
            (2 * s**3 - 3 * s**2 + 1) * z0
            + (s**3 - 2 * s**2 + s) * d0
            + (-2 * s**3 + 3 * s**2) * z1
            + (s**3 - s**2) * d1
        )
        jacobians.append(model.jacobian(zs[..., :n], zs[..., n:]))
    a1, a2 = jacobians
    w = (dt / 2) * (a1 + a2) + (np.sqrt(3) * dt**2 / 12) * (a2 @ a1 - a1 @ a2)
    w2 = (w @ w) / 12
    eye = np.eye(2 * n)
    return np.linalg.solve(eye - w / 2 + w2, eye + w / 2 + w2)


def lyapunov_variational(
    model: PendulumModel,
    theta0,
    omega0,
    t_end: float,
    dt: float = 0.01,
    method="glrk4",
    *,
    record_every: int = 50,
    seed=0,
    progress: bool | None = None,
) -> LyapunovEstimate:
    """Largest Lyapunov exponent from the variational (tangent) equations.

    Along a trajectory ``z(t) = (theta, p)`` from :func:`~pendulum_lab.simulate`,
    a tangent vector obeys the linear equation ``v' = A(t) v`` with
    ``A = model.jacobian(theta, p)``, the Jacobian of Hamilton's equations
    built from the symbolic second derivatives. The tangent is carried over
    each step ``[t_k, t_k + dt]`` by the fourth-order Magnus method:

    ``W = dt/2 (A_1 + A_2) + sqrt(3) dt^2 / 12 [A_2, A_1]``,
    ``v_{k+1} = (I - W/2 + W^2/12)^{-1} (I + W/2 + W^2/12) v_k``,

    where ``A_1``, ``A_2`` are the Jacobians at the two Gauss points
    ``t_k + (1/2 -+ sqrt(3)/6) dt`` (the state there from cubic Hermite
    interpolation between the saved steps, accurate to ``O(dt^4)``), and the
    last line is the (2,2) Pade approximant of ``exp(W)``. ``W`` is a
    Hamiltonian matrix and a diagonal Pade approximant maps Hamiltonian
    matrices to symplectic ones, so the tangent propagator is exactly
    symplectic, like the flow it linearises; the whole scheme is fourth order
    in ``dt``. The propagators of ``record_every`` steps are multiplied
    together, the tangent vector is advanced, its growth added to a sum of
    logarithms and the vector normalised.

    The state comes from the chosen integrator, the tangent only from the
    Jacobian, so this estimate is independent of :func:`lyapunov_benettin`
    (which uses no Jacobian); both follow the same reference trajectory.

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0 : array_like, shape (..., n)
    t_end, dt, method
        As for :func:`ensemble`; the estimate uses ``floor(n_steps /
        record_every)`` whole blocks of steps.
    record_every : int
        Steps between recorded estimates (and normalisations), ``>= 1``.
    seed : int or None
        Seed of the initial tangent direction (the same direction as
        :func:`lyapunov_benettin` with the same seed).
    progress : bool, optional

    Returns
    -------
    LyapunovEstimate

    Raises
    ------
    FloatingPointError
        If the integration blows up.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> est = lyapunov_variational(pl.double_pendulum(), [2.0, 2.5], [0.0, 0.0], t_end=5.0,
    ...                            method="rk4")
    >>> bool(est.exponent > 0.5)
    True
    """
    check_model(model)
    method = get_method(method)
    theta0, omega0 = _initial_state(model, theta0, omega0)
    t_end, dt, n_steps = _step_count(t_end, dt)
    every = check.integer_at_least("record_every", record_every, 1)
    blocks = n_steps // every
    if blocks < 1:
        raise ValueError(
            f"`t_end` ({t_end}) must cover at least one block of `record_every` "
            f"({every}) steps of {dt}"
        )
    n, batch = model.n, theta0.shape[:-1]
    members = max(1, theta0.size // n)
    total = blocks * every
    length = _tangent_chunk(total, batch, n, every)
    v = np.broadcast_to(_unit_direction(2 * n, seed), (*batch, 2 * n)).copy()
    log_sum = np.zeros(batch)
    running = np.empty((blocks, *batch))
    theta, omega = theta0, omega0
    done, recorded = 0, 0
    start = time.perf_counter()
    bar = _Progress(total, members, progress, "variational")
    try:
        while done < total:
            steps = min(length, total - done)
            traj = _advance(model, theta, omega, steps, dt, method, 1, done * dt)
            _require_finite(traj, "lyapunov_variational")
            step_maps = _magnus_propagators(model, traj, dt)
            props = _ordered_product(step_maps.reshape(steps // every, every, *step_maps.shape[1:]))
            for prop in props:
                v = np.einsum("...ij,...j->...i", prop, v)
                norm = np.linalg.norm(v, axis=-1)
                log_sum += np.log(norm)
                v /= norm[..., None]
                recorded += 1
                running[recorded - 1] = log_sum / (recorded * every * dt)
            theta, omega = traj.theta[-1], traj.omega[-1]
            done += steps
            bar.update(steps)
    finally:
        bar.close()
    t = (np.arange(blocks) + 1) * every * dt
    return LyapunovEstimate(t, running, "variational", method.name, dt, time.perf_counter() - start)


# --------------------------------------------------------------------------- Poincare sections
def section_states(
    model: PendulumModel,
    energy: float,
    theta_rest,
    p_rest,
    *,
    index: int = 0,
    value: float = 0.0,
    direction: int = 1,
) -> tuple[np.ndarray, np.ndarray]:
    """Initial states on the surface ``theta_index = value`` with a given energy.

    The other angles and momenta are given; the remaining momentum ``x =
    p_index`` solves ``H = energy``. ``H = 1/2 p^T A p + V`` with ``A = M^-1``
    is quadratic in ``x``: ``1/2 a x^2 + b x + c = 0`` with ``a = A_ii``,
    ``b = sum_{j != i} A_ij p_j`` and ``c = H(x = 0) - energy``. Its roots give
    ``theta_i' = dH/dp_i = a x + b = +-sqrt(b^2 - 2 a c)``, so the root with the
    sign of ``direction`` crosses the surface in that direction. Points where
    ``b^2 < 2 a c`` cannot reach the surface at this energy and are dropped.

    Parameters
    ----------
    model : PendulumModel
        ``n >= 2``.
    energy : float
        Total energy [J] (zero potential at the pivot's height).
    theta_rest, p_rest : array_like, shape (..., n - 1)
        The angles and momenta other than ``theta_index``, ``p_index``, in
        link order.
    index : int
        Which angle defines the surface (0-based).
    value : float
        The surface ``theta_index = value``.
    direction : {1, -1}
        Sign of ``theta_index'`` at the initial states.

    Returns
    -------
    theta0, omega0 : ndarray, shape (K, n)
        The ``K`` accessible points, flattened, ready for
        :func:`poincare_section`.

    Raises
    ------
    ValueError
        If no point is accessible at this energy.

    Examples
    --------
    >>> import numpy as np, pendulum_lab as pl
    >>> dp = pl.double_pendulum()
    >>> theta0, omega0 = section_states(dp, -15.0, [[0.0], [0.5]], [[0.0], [1.0]])
    >>> bool(np.allclose(dp.energy(theta0, omega0), -15.0)), bool(np.all(omega0[:, 0] > 0))
    (True, True)
    """
    check_model(model)
    n = model.n
    if n < 2:
        raise ValueError("`model` must have at least two links for a Poincare section")
    energy = check.real_number("energy", energy)
    index = _check_index(index, n)
    value = check.real_number("value", value)
    direction = _check_direction(direction, allow_both=False)
    theta_rest = check.state_array("theta_rest", theta_rest, n - 1)
    p_rest = check.state_array("p_rest", p_rest, n - 1)
    theta_rest, p_rest = np.broadcast_arrays(theta_rest, p_rest)
    theta = np.insert(theta_rest.reshape(-1, n - 1), index, value, axis=-1)
    p = np.insert(p_rest.reshape(-1, n - 1), index, 0.0, axis=-1)
    inverse = np.linalg.inv(model.mass_matrix_at(theta))
    a = inverse[:, index, index]
    b = np.einsum("kj,kj->k", inverse[:, index, :], p)
    c = model.hamiltonian_value(theta, p) - energy
    disc = b**2 - 2 * a * c
    ok = disc >= 0
    if not np.any(ok):
        raise ValueError(
            f"no point reaches the surface at `energy` = {energy} J: it is below "
            "the potential energy there"
        )
    p[ok, index] = (-b[ok] + direction * np.sqrt(disc[ok])) / a[ok]
    return theta[ok], model.velocities(theta[ok], p[ok])


def _check_index(index, n):
    index = check.integer_at_least("index", index, 0)
    if index >= n:
        raise ValueError(f"`index` must be in [0, {n - 1}], got {index}")
    return index


def _check_direction(direction, allow_both=True):
    allowed = (1, -1, 0) if allow_both else (1, -1)
    if isinstance(direction, bool) or direction not in allowed:
        raise ValueError(f"`direction` must be one of {list(allowed)}, got {direction!r}")
    return int(direction)


@dataclass(frozen=True)
class PoincareSection:
    """Crossings of the surface ``theta_index = value (mod 2 pi)``.

    Attributes
    ----------
    t : ndarray, shape (C,)
        Crossing times [s].
    theta : ndarray, shape (C, n)
        Angles at the crossings, wrapped to ``[-pi, pi)``.
    p : ndarray, shape (C, n)
        Momenta at the crossings.
    orbit : ndarray of int, shape (C,)
        Which initial state (flat index into the ensemble) each crossing
        belongs to.
    residual : ndarray, shape (C,)
        ``|theta_index - (value + 2 pi m)|`` at each located crossing: how far
        it lies from the surface.
    index, value, direction
        The surface and the crossing direction (``1``: ``theta_index``
        increasing, ``-1``: decreasing, ``0``: both).
    refined : bool
        True if crossings were located on the surface, False if they are the
        nearest saved steps.
    """

    t: np.ndarray
    theta: np.ndarray
    p: np.ndarray
    orbit: np.ndarray
    residual: np.ndarray
    index: int
    value: float
    direction: int
    refined: bool

    def coordinates(self, link: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``(theta_j, p_j)`` of the crossings, for the first link ``j`` off the surface."""
        if link is None:
            link = 1 if self.index == 0 else 0
        return self.theta[:, link], self.p[:, link]

    def plot(self, ax=None, link: int | None = None, s: float = 2.0, **kwargs):
        """The section in ``(theta_j, p_j)``, one colour per orbit; returns the Figure."""
        ax = _axes(ax, 4.8, 4.2)
        x, y = self.coordinates(link)
        if link is None:
            link = 1 if self.index == 0 else 0
        ax.scatter(
            x, y, c=self.orbit % 20, s=s, cmap="tab20", vmin=0, vmax=19, linewidths=0, **kwargs
        )
        ax.set(xlabel=f"theta{link + 1} (rad)", ylabel=f"p{link + 1} (kg m^2/s)")
        return ax.figure


def _hermite_root(f0, f1, d0, d1, iterations: int = 8):
    """Root in ``[0, 1]`` of the cubic Hermite interpolant of ``(f0, d0)``, ``(f1, d1)``.

    ``d0``, ``d1`` are derivatives with respect to the unit-interval variable
    (``dt`` times the time derivative). Newton from the linear-interpolation
    guess; the interval contains a sign change.
    """
    s = np.clip(f0 / (f0 - f1), 0.0, 1.0)
    for _ in range(iterations):
        s2, s3 = s * s, s * s * s
        val = (
            (2 * s3 - 3 * s2 + 1) * f0
            + (s3 - 2 * s2 + s) * d0
            + (-2 * s3 + 3 * s2) * f1
            + (s3 - s2) * d1
        )
        der = (
            (6 * s2 - 6 * s) * f0
            + (3 * s2 - 4 * s + 1) * d0
            + (-6 * s2 + 6 * s) * f1
            + (3 * s2 - 2 * s) * d1
        )
        s = np.clip(s - val / np.where(der == 0, 1.0, der), 0.0, 1.0)
    return s


def _land_on_surface(model, method, q, p, dt, tau, target, index, max_iterations=12):
    """Step ``tau`` from ``(q, p)`` with ``method``, adjusting ``tau`` until ``q_index = target``.

    Newton's method on the step length: ``d q_index / d tau`` is
    ``dH/dp_index`` at the landed state. The landed state is a genuine state of
    the method's numerical flow (one step of length ``tau``), so the crossing
    is as accurate as the integrator, and lies on the surface to round-off.
    """
    best = (np.inf, q, p, 0.0)
    for _ in range(max_iterations):
        q1, p1 = (q, p) if tau == 0.0 else step(model, method, q, p, tau)
        miss = q1[index] - target
        if abs(miss) < best[0]:
            best = (abs(miss), q1, p1, tau)
        if abs(miss) <= 4 * np.finfo(float).eps * max(1.0, abs(target)):
            break
        speed = model.dH_dp(q1, p1)[index]
        if speed == 0:
            break
        tau = float(np.clip(tau - miss / speed, -dt, 2 * dt))
    return best


def poincare_section(
    model: PendulumModel,
    theta0,
    omega0,
    t_end: float,
    dt: float = 0.01,
    method="glrk4",
    *,
    index: int = 0,
    value: float = 0.0,
    direction: int = 1,
    refine: bool = True,
    progress: bool | None = None,
) -> PoincareSection:
    """Crossings of ``theta_index = value (mod 2 pi)`` located to round-off.

    The ensemble runs in segments with every step kept; a crossing is a step
    over which ``floor((theta_index - value) / 2 pi)`` changes (the unwrapped
    angle passes ``value + 2 pi m``), upwards for ``direction = 1``. For each
    crossing between steps ``k`` and ``k+1``:

    1. the cubic Hermite interpolant of ``theta_index`` (values and slopes
       ``dH/dp_index`` at both steps) gives a first guess ``tau`` of the
       crossing time after ``t_k``;
    2. Newton's method on ``tau``, each iterate being one step of length
       ``tau`` of the same integrator from step ``k`` (:func:`~pendulum_lab.step`),
       drives ``theta_index`` onto the surface to round-off.

    The result is Henon's idea (land exactly on the surface with one extra
    step of the integrator) done by a root solve in time instead of a change
    of independent variable, so no new vector field is needed. With
    ``refine=False`` the nearest saved step is returned instead (off the
    surface by up to ``dt |theta_index'| / 2``: a negative control).

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0 : array_like, shape (..., n)
        Initial states (for example from :func:`section_states`).
    t_end, dt, method
        As for :func:`ensemble`.
    index : int
        Angle that defines the surface (0-based).
    value : float
        Surface ``theta_index = value``.
    direction : {1, -1, 0}
        ``1``: crossings with ``theta_index`` increasing (``dH/dp_index > 0``),
        ``-1``: decreasing, ``0``: both.
    refine : bool
        Locate each crossing on the surface (default) or return the nearest step.
    progress : bool, optional

    Returns
    -------
    PoincareSection
        Crossings sorted by orbit, then time.

    Notes
    -----
    For the double pendulum the section ``theta_1 = 0`` is often described
    with ``p_1 > 0``; the crossing direction is the sign of
    ``theta_1' = (M^-1 p)_1``, which is not always the sign of ``p_1``. The
    direction used here is that of ``theta_1'``: it makes the section a
    one-sided surface crossed transversally, on which the return map
    preserves area in ``(theta_2, p_2)``.

    References
    ----------
    M. Henon, Physica D 5 (1982) 412-414.

    Examples
    --------
    >>> import numpy as np, pendulum_lab as pl
    >>> dp = pl.double_pendulum()
    >>> theta0, omega0 = section_states(dp, -20.0, [[0.3]], [[0.0]])
    >>> sec = poincare_section(dp, theta0, omega0, t_end=5.0, method="rk4")
    >>> bool(np.all(sec.residual < 1e-10)), len(sec.t) > 0
    (True, True)
    """
    check_model(model)
    method = get_method(method)
    theta0, omega0 = _initial_state(model, theta0, omega0)
    t_end, dt, n_steps = _step_count(t_end, dt)
    n = model.n
    index = _check_index(index, n)
    value = check.real_number("value", value)
    direction = _check_direction(direction)
    theta = theta0.reshape(-1, n)
    omega = omega0.reshape(-1, n)
    members = theta.shape[0]
    length = _chunk_length(n_steps, 4 * members * n)
    found = {name: [] for name in ("t", "theta", "p", "orbit", "residual")}
    done = 0
    bar = _Progress(n_steps, members, progress, "Poincare section")
    try:
        while done < n_steps:
            steps = min(length, n_steps - done)
            traj = _advance(model, theta, omega, steps, dt, method, 1, done * dt)
            _require_finite(traj, "poincare_section")
            _crossings(model, method, traj, done * dt, index, value, direction, refine, found)
            theta, omega = traj.theta[-1], traj.omega[-1]
            done += steps
            bar.update(steps)
    finally:
        bar.close()
    arrays = {k: np.asarray(v) for k, v in found.items()}
    if arrays["t"].size == 0:
        arrays = {
            "t": np.empty(0),
            "theta": np.empty((0, n)),
            "p": np.empty((0, n)),
            "orbit": np.empty(0, dtype=int),
            "residual": np.empty(0),
        }
    order = np.lexsort((arrays["t"], arrays["orbit"]))
    return PoincareSection(
        t=arrays["t"][order],
        theta=_wrap(arrays["theta"][order]),
        p=arrays["p"][order],
        orbit=arrays["orbit"][order].astype(int),
        residual=arrays["residual"][order],
        index=index,
        value=value,
        direction=direction,
        refined=bool(refine),
    )


def _crossings(model, method, traj, t0, index, value, direction, refine, found):
    """Append the crossings in one segment ``traj`` (shape ``(L+1, K, n)``) to ``found``."""
    angle = traj.theta[..., index]
    sheet = np.floor((angle - value) / (2 * np.pi))
    up = sheet[1:] > sheet[:-1]
    down = sheet[1:] < sheet[:-1]
    hits = up if direction == 1 else down if direction == -1 else up | down
    steps, orbits = np.nonzero(hits)
    if steps.size == 0:
        return
    target = value + 2 * np.pi * np.maximum(sheet[steps, orbits], sheet[steps + 1, orbits])
    dt = traj.dt
    f0 = angle[steps, orbits] - target
    f1 = angle[steps + 1, orbits] - target
    if not refine:
        later = np.abs(f1) < np.abs(f0)
        k = steps + later
        found["t"].extend(t0 + traj.t[k])
        found["theta"].extend(traj.theta[k, orbits])
        found["p"].extend(traj.p[k, orbits])
        found["orbit"].extend(orbits)
        found["residual"].extend(np.where(later, np.abs(f1), np.abs(f0)))
        return
    d0 = dt * traj.omega[steps, orbits, index]
    d1 = dt * traj.omega[steps + 1, orbits, index]
    guess = _hermite_root(f0, f1, d0, d1)
    for k, j, s, tgt in zip(steps, orbits, guess, target):
        miss, q, p, tau = _land_on_surface(
            model, method, traj.theta[k, j], traj.p[k, j], dt, float(s * dt), float(tgt), index
        )
        found["t"].append(t0 + traj.t[k] + tau)
        found["theta"].append(q)
        found["p"].append(p)
        found["orbit"].append(j)
        found["residual"].append(miss)


def energy_sections(
    model: PendulumModel,
    energies,
    orbits: int = 10,
    t_end: float = 100.0,
    dt: float = 0.01,
    method="glrk4",
    *,
    progress: bool | None = None,
) -> dict[float, PoincareSection]:
    """Poincare sections ``theta_1 = 0``, ``theta_1' > 0`` of a double pendulum, several energies.

    For each energy, ``orbits`` initial states are spread over the section:
    half along ``p_2 = 0`` at ``theta_2`` between 0 and the largest accessible
    angle, half along ``theta_2 = 0`` at ``p_2 > 0`` up to the largest
    accessible momentum (all via :func:`section_states`). All orbits of all
    energies run as one ensemble.

    Parameters
    ----------
    model : PendulumModel
        A double pendulum.
    energies : sequence of float
        Energies [J], above the minimum ``V(0, 0)``.
    orbits : int
        Initial states per energy, ``>= 2``.
    t_end, dt, method, progress
        As for :func:`poincare_section`.

    Returns
    -------
    dict
        ``{energy: PoincareSection}``; each section's ``orbit`` numbers its
        own orbits from 0.
    """
    check_model(model)
    if model.n != 2:
        raise ValueError(f"`model` must be a double pendulum (n = 2), got n = {model.n}")
    orbits = check.integer_at_least("orbits", orbits, 2)
    energies = [check.real_number("energies", e) for e in np.atleast_1d(energies)]
    starts, owner = [], []
    for number, energy in enumerate(energies):
        theta0, omega0 = _spread_on_section(model, energy, orbits)
        starts.append((theta0, omega0))
        owner += [number] * len(theta0)
    theta0 = np.concatenate([s[0] for s in starts])
    omega0 = np.concatenate([s[1] for s in starts])
    sec = poincare_section(model, theta0, omega0, t_end, dt, method, progress=progress)
    owner = np.asarray(owner)
    first = np.cumsum([0] + [len(s[0]) for s in starts])
    result = {}
    for number, energy in enumerate(energies):
        keep = owner[sec.orbit] == number
        result[energy] = PoincareSection(
            t=sec.t[keep],
            theta=sec.theta[keep],
            p=sec.p[keep],
            orbit=sec.orbit[keep] - first[number],
            residual=sec.residual[keep],
            index=sec.index,
            value=sec.value,
            direction=sec.direction,
            refined=sec.refined,
        )
    return result


def plot_sections(sections: dict, ncols: int = 2):
    """Poincare sections side by side, one panel per energy; returns the Figure.

    Parameters
    ----------
    sections : dict
        ``{energy: PoincareSection}``, as from :func:`energy_sections`.
    ncols : int
        Panels per row.
    """
    from .plotting import new_figure

    ncols = check.integer_at_least("ncols", ncols, 1)
    count = len(sections)
    if count == 0:
        raise ValueError("`sections` must hold at least one section")
    ncols = min(ncols, count)
    nrows = math.ceil(count / ncols)
    fig, axes = new_figure(nrows, ncols, width=4.0 * ncols, height=3.6)
    axes = np.asarray(axes).reshape(-1)
    for ax, (energy, sec) in zip(axes, sections.items()):
        sec.plot(ax=ax)
        ax.set_title(f"E = {energy:g} J, {len(sec.t)} crossings", fontsize="medium")
    for ax in axes[count:]:
        ax.set_visible(False)
    return fig


def _spread_on_section(model, energy, orbits):
    """``orbits`` states on ``theta_1 = 0`` at ``energy``, spread along two lines."""
    along_theta = orbits - orbits // 2
    grid = np.linspace(0.0, np.pi, 400)
    bottom = model.potential_energy(np.column_stack([np.zeros_like(grid), grid]))
    reach = grid[bottom < energy]
    if reach.size == 0:
        raise ValueError(
            f"`energies` must lie above the minimum of the potential energy "
            f"({float(bottom[0]):.6g} J), got {energy}"
        )
    theta2 = np.linspace(0.0, reach[-1], along_theta + 1)[:-1] + reach[-1] / (2 * along_theta)
    # Largest p_2 on theta = 0: the discriminant of the quadratic for p_1 vanishes.
    inverse = np.linalg.inv(model.mass_matrix_at(np.zeros(2)))
    depth = energy - float(model.potential_energy(np.zeros(2)))
    p2_max = np.sqrt(2 * depth / (inverse[1, 1] - inverse[0, 1] ** 2 / inverse[0, 0]))
    count = orbits // 2
    p2 = (np.arange(count) + 0.5) / count * p2_max
    theta_rest = np.concatenate([theta2, np.zeros(count)])[:, None]
    p_rest = np.concatenate([np.zeros(along_theta), p2])[:, None]
    return section_states(model, energy, theta_rest, p_rest)


# --------------------------------------------------------------------------- flip-time map
def can_flip(model: PendulumModel, theta, omega=None) -> np.ndarray:
    """Whether energy allows any arm to pass over the top (``|theta_i| = pi``).

    With ``w_j = g l_j (m_j + ... + m_n)`` the potential energy is
    ``V = -sum_j w_j cos(theta_j)``. Arm ``i`` upside down (``theta_i = pi``)
    costs at least ``V_i = w_i - sum_{j != i} |w_j|`` (every other arm as low
    as it can be). Energy is conserved and kinetic energy is not negative, so
    if ``E < min_i V_i`` no arm can ever flip. For the double pendulum
    ``min_i V_i = -g |(m_1 + m_2) l_1 - m_2 l_2|``; released at rest with
    ``m = l = 1`` that reads ``2 cos(theta_1) + cos(theta_2) > 1`` for "cannot
    flip". (The often-quoted ``3 cos(theta_1) + cos(theta_2) > 2`` is the same
    bound for two uniform rods, whose centres of mass sit at mid-length.)

    Parameters
    ----------
    model : PendulumModel
    theta : array_like, shape (..., n)
    omega : array_like, shape (..., n), optional
        Angular velocities; at rest by default.

    Returns
    -------
    ndarray of bool, shape (...)
        True where the energy is at least the flipping threshold.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> dp = pl.double_pendulum()
    >>> can_flip(dp, [[0.5, 0.5], [2.0, 2.5]]).tolist()
    [False, True]
    """
    check_model(model)
    theta = check.state_array("theta", theta, model.n)
    omega = np.zeros_like(theta) if omega is None else check.state_array("omega", omega, model.n)
    energy = model.energy(theta, omega)
    return energy >= _flip_threshold(model)


def _flip_threshold(model) -> float:
    tail_mass = np.cumsum(np.asarray(model.masses)[::-1])[::-1]
    w = model.g * np.asarray(model.lengths) * tail_mass
    return float(np.min(w - (np.sum(np.abs(w)) - np.abs(w))))


@dataclass(frozen=True)
class FlipMap:
    """Time until either arm of a double pendulum released at rest flips over.

    Attributes
    ----------
    theta1 : ndarray, shape (N1,)
    theta2 : ndarray, shape (N2,)
        Grid of initial angles [rad]; exactly symmetric about 0.
    time : ndarray, shape (N2, N1)
        Flip time [s] (row = ``theta2``, column = ``theta1``); ``inf`` where no
        arm flipped before ``t_end`` or where energy forbids it.
    forbidden : ndarray of bool, shape (N2, N1)
        Cells that cannot flip on energy grounds (not simulated).
    t_end, dt : float
    method : str
    wall_time : float
    """

    theta1: np.ndarray
    theta2: np.ndarray
    time: np.ndarray
    forbidden: np.ndarray
    t_end: float
    dt: float
    method: str
    wall_time: float

    def plot(self, ax=None, colorbar: bool = True):
        """The map with a logarithmic colour scale; returns the Figure.

        Energy-forbidden cells are grey, cells that did not flip before
        ``t_end`` white.
        """
        from matplotlib import colormaps
        from matplotlib.colors import ListedColormap, LogNorm

        ax = _axes(ax, 5.4, 4.4)
        half1 = (self.theta1[1] - self.theta1[0]) / 2 if self.theta1.size > 1 else 0.5
        half2 = (self.theta2[1] - self.theta2[0]) / 2 if self.theta2.size > 1 else 0.5
        extent = (
            self.theta1[0] - half1,
            self.theta1[-1] + half1,
            self.theta2[0] - half2,
            self.theta2[-1] + half2,
        )
        flipped = np.ma.masked_invalid(np.where(np.isfinite(self.time), self.time, np.nan))
        lowest = float(flipped.min()) if flipped.count() else self.dt
        lowest = min(max(lowest, self.dt), self.t_end / 10)
        image = ax.imshow(
            flipped,
            origin="lower",
            extent=extent,
            interpolation="nearest",
            cmap=colormaps["viridis"].with_extremes(bad="white"),
            norm=LogNorm(vmin=lowest, vmax=self.t_end),
        )
        ax.imshow(
            np.ma.masked_where(~self.forbidden, self.forbidden.astype(float)),
            origin="lower",
            extent=extent,
            interpolation="nearest",
            cmap=ListedColormap(["0.75"]),
            vmin=0,
            vmax=1,
        )
        ax.set(xlabel="theta1(0) (rad)", ylabel="theta2(0) (rad)")
        if colorbar:
            ax.figure.colorbar(image, ax=ax, label="flip time (s)")
        return ax.figure


def _symmetric_grid(size: int, half_width: float) -> np.ndarray:
    """``size`` points on ``[-half_width, half_width]``, exactly symmetric about 0."""
    if size == 1:
        return np.zeros(1)
    return (2.0 * np.arange(size) - (size - 1)) * (half_width / (size - 1))


def flip_time_map(
    model: PendulumModel,
    size=20,
    *,
    t_end: float = 10.0,
    dt: float = 0.01,
    method="rk4",
    half_width: float = 3.0,
    progress: bool | None = None,
) -> FlipMap:
    """Heyl's flip-time map: time until either arm passes over the top.

    Every cell of a grid of initial angles ``(theta_1, theta_2)``, released at
    rest, is integrated until an arm flips (the unwrapped ``|theta_i|``
    reaches ``pi``; the time is interpolated linearly between steps) or until
    ``t_end``. Cells that cannot flip on energy grounds (:func:`can_flip`)
    are not simulated. The whole grid is one ensemble run in segments; cells
    that have flipped leave the ensemble at the end of their segment.

    Parameters
    ----------
    model : PendulumModel
        A double pendulum.
    size : int or (int, int)
        Grid points along ``theta_1`` and ``theta_2``.
    t_end : float
        Time limit [s].
    dt : float
        Step size [s].
    method : str or Method
        Integrator; RK4 by default: over a few seconds its error is far below
        what the map can show, and it is the cheapest fourth-order method.
    half_width : float
        The grid covers ``[-half_width, half_width]^2``, ``0 < half_width < pi``.
    progress : bool, optional

    Returns
    -------
    FlipMap

    Notes
    -----
    The equations are odd in ``(theta, p)``, so ``theta -> -theta`` maps a
    trajectory to its mirror image and the map is symmetric under a half
    turn of the grid; the grid is built to be exactly symmetric so this holds
    to round-off.

    References
    ----------
    J. S. Heyl, "The double pendulum fractal", 2008.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> fm = flip_time_map(pl.double_pendulum(), size=6, t_end=2.0)
    >>> fm.time.shape, bool(fm.forbidden[2:4, 2:4].all())
    ((6, 6), True)
    """
    check_model(model)
    if model.n != 2:
        raise ValueError(f"`model` must be a double pendulum (n = 2), got n = {model.n}")
    method = get_method(method)
    n1, n2 = (size, size) if np.ndim(size) == 0 else tuple(size)
    n1 = check.integer_at_least("size", n1, 1)
    n2 = check.integer_at_least("size", n2, 1)
    half_width = check.positive_number("half_width", half_width)
    if half_width >= np.pi:
        raise ValueError(
            f"`half_width` must be below pi (the grid starts below the top), got {half_width}"
        )
    t_end, dt, n_steps = _step_count(t_end, dt)
    theta1 = _symmetric_grid(n1, half_width)
    theta2 = _symmetric_grid(n2, half_width)
    grid = np.stack(np.meshgrid(theta1, theta2), axis=-1)
    forbidden = ~can_flip(model, grid)
    flip = np.full(forbidden.shape, np.inf)
    cells = np.flatnonzero(~forbidden)
    theta = grid.reshape(-1, 2)[cells]
    omega = np.zeros_like(theta)
    length = _chunk_length(n_steps, 4 * max(1, cells.size) * 2)
    done = 0
    start = time.perf_counter()
    bar = _Progress(n_steps, cells.size, progress, "flip-time map")
    try:
        while done < n_steps and cells.size:
            steps = min(length, n_steps - done)
            traj = _advance(model, theta, omega, steps, dt, method, 1, done * dt)
            _require_finite(traj, "flip_time_map")
            height = np.max(np.abs(traj.theta), axis=-1)
            over = height[1:] >= np.pi
            flipped = np.any(over, axis=0)
            k = np.argmax(over, axis=0)[flipped]
            cols = np.flatnonzero(flipped)
            before, after = height[k, cols], height[k + 1, cols]
            flip.flat[cells[cols]] = done * dt + (k + (np.pi - before) / (after - before)) * dt
            stay = ~flipped
            cells = cells[stay]
            theta, omega = traj.theta[-1][stay], traj.omega[-1][stay]
            done += steps
            bar.update(steps)
    finally:
        bar.close()
    return FlipMap(
        theta1, theta2, flip, forbidden, t_end, dt, method.name, time.perf_counter() - start
    )


# --------------------------------------------------------------------------- small angles
@dataclass(frozen=True)
class SmallAngleComparison:
    """The linearised motion about the hanging equilibrium against the full motion.

    Attributes
    ----------
    t : ndarray, shape (S,)
    theta_full, theta_linear : ndarray, shape (S, ..., n)
    difference : ndarray, shape (S, ...)
        ``max_i |theta_full_i - theta_linear_i|`` [rad].
    parting_time : float or ndarray, shape (...)
        First time the difference exceeds the threshold (``inf`` if never).
    threshold : float
    relative : bool
        Whether ``threshold`` is a fraction of the largest linear angle.
    """

    t: np.ndarray
    theta_full: np.ndarray
    theta_linear: np.ndarray
    difference: np.ndarray
    parting_time: float | np.ndarray
    threshold: float
    relative: bool

    def plot(self, ax=None, member=()):
        """Both motions of one ensemble member (index ``member``); returns the Figure."""
        ax = _axes(ax, 7.0, 3.6)
        member = (member,) if np.ndim(member) == 0 and member != () else tuple(member)
        full = self.theta_full[(slice(None), *member)]
        linear = self.theta_linear[(slice(None), *member)]
        for i in range(full.shape[-1]):
            line = ax.plot(self.t, full[:, i], label=f"theta{i + 1} full")[0]
            ax.plot(
                self.t, linear[:, i], "--", color=line.get_color(), label=f"theta{i + 1} linearised"
            )
        parting = np.asarray(self.parting_time)[member]
        if np.isfinite(parting):
            ax.axvline(parting, color="k", lw=0.8, ls=":", label="they part")
        ax.set(xlabel="t (s)", ylabel="angle (rad)")
        ax.legend(fontsize="small", ncol=2)
        return ax.figure

    def plot_parting(self, amplitudes, ax=None):
        """Parting time against release amplitude (log-log) with a fitted power law.

        Parameters
        ----------
        amplitudes : array_like, shape like ``parting_time``
            The size of each member's release (for example its largest angle).

        Returns
        -------
        matplotlib.figure.Figure
        """
        amplitudes = np.asarray(amplitudes, dtype=float)
        times = np.asarray(self.parting_time, dtype=float)
        if amplitudes.shape != times.shape:
            raise ValueError(
                f"`amplitudes` must have the shape of `parting_time` {times.shape}, "
                f"got {amplitudes.shape}"
            )
        ax = _axes(ax)
        ax.loglog(amplitudes, times, "o", label="measured")
        parted = np.isfinite(times) & (amplitudes > 0)
        if parted.sum() >= 2:
            slope, offset = np.polyfit(np.log(amplitudes[parted]), np.log(times[parted]), 1)
            ax.loglog(
                amplitudes[parted],
                np.exp(offset) * amplitudes[parted] ** slope,
                "--",
                color="0.4",
                label=f"fit: time ~ amplitude^{slope:.2f}",
            )
        ax.set(xlabel="release amplitude (rad)", ylabel="parting time (s)")
        ax.legend(fontsize="small")
        return ax.figure


def small_angle_comparison(
    model: PendulumModel,
    theta0,
    omega0,
    t_end: float,
    dt: float = 0.01,
    method="glrk4",
    *,
    threshold: float = 0.05,
    relative: bool = False,
    every: int = 1,
    progress: bool | None = None,
) -> SmallAngleComparison:
    """Where the linearised motion and the full nonlinear motion part.

    The linear motion about the all-down equilibrium is exact:
    :func:`pendulum_lab.analysis.linearized_solution` evaluates
    ``exp(A t) x0`` with the equilibrium's Jacobian ``A`` from
    ``model.chain.equilibria[0]``. The full motion comes from
    :func:`ensemble`. They "part" when the largest angle difference first
    exceeds ``threshold`` (in radians, or with ``relative=True`` as a
    fraction of the largest angle of the linear motion). The nonlinearity
    enters through terms of third order in the amplitude ``a``: it shifts the
    frequencies by an amount of order ``a^2``, so the difference grows like
    ``a^3 t`` and a relative threshold is crossed after a time of order
    ``a^-2``.

    Parameters
    ----------
    model : PendulumModel
        Meant for one or two links (the equilibria of longer chains are slow
        to derive).
    theta0, omega0 : array_like, shape (..., n)
    t_end, dt, method, every, progress
        As for :func:`ensemble` with ``keep="thinned"``.
    threshold : float
        Angle difference that counts as parting, ``> 0``.
    relative : bool
        Measure ``threshold`` as a fraction of ``max |theta_linear|`` (per
        ensemble member) instead of in radians.

    Returns
    -------
    SmallAngleComparison
    """
    from .analysis import linearized_solution

    check_model(model)
    theta0, omega0 = _initial_state(model, theta0, omega0)
    threshold = check.positive_number("threshold", threshold)
    traj = ensemble(
        model, theta0, omega0, t_end, dt, method, keep="thinned", every=every, progress=progress
    )
    n, batch = model.n, theta0.shape[:-1]
    bottom = model.chain.equilibria[0]
    flat0, flatw = theta0.reshape(-1, n), omega0.reshape(-1, n)
    linear = np.stack(
        [linearized_solution(model, bottom, th, om, traj.t)[0] for th, om in zip(flat0, flatw)],
        axis=1,
    )
    linear = linear.reshape(len(traj.t), *batch, n)
    difference = np.max(np.abs(traj.theta - linear), axis=-1)
    limit = threshold * np.max(np.abs(linear), axis=(0, -1)) if relative else threshold
    apart = difference > limit
    parting = np.where(np.any(apart, axis=0), traj.t[np.argmax(apart, axis=0)], np.inf)
    return SmallAngleComparison(
        traj.t, traj.theta, linear, difference, _scalar_or_array(parting), threshold, bool(relative)
    )


# --------------------------------------------------------------------------- n-pendulum
@dataclass(frozen=True)
class ChainCost:
    """What a chain of ``n`` links costs.

    Attributes
    ----------
    n : int
    derivation : float
        Seconds for a fresh symbolic derivation (:class:`~pendulum_lab.Chain`).
    build : float
        Seconds for :func:`~pendulum_lab.n_pendulum` (compiles the numeric
        functions the first time ``n`` is used in a session, then reuses them).
    first_simulation : float
        Seconds of the first :func:`~pendulum_lab.simulate` call after building.
    per_step : float
        Seconds per step of a repeated run (``Trajectory.wall_time / steps``,
        the best of three runs).
    method : str
    """

    n: int
    derivation: float
    build: float
    first_simulation: float
    per_step: float
    method: str


def chain_costs(
    ns=(3, 4, 5), *, t_end: float = 2.0, dt: float = 0.01, method="glrk4"
) -> list[ChainCost]:
    """Measure derivation time, first-use time and step cost of n-link chains.

    For each ``n``: a fresh :class:`~pendulum_lab.mechanics.Chain` is
    derived and timed (after clearing SymPy's cache); then the model is
    built, simulated once (first use) and three times more (steady state),
    all links starting at 0.5 rad at rest.

    Parameters
    ----------
    ns : sequence of int
        Numbers of links, each ``>= 1``.
    t_end, dt, method
        The test run.

    Returns
    -------
    list of ChainCost
        Timings depend on the machine and on what this session already
        compiled; they are measurements, not constants.
    """
    method = get_method(method)
    _, dt, steps = _step_count(t_end, dt)
    rows = []
    for n in ns:
        n = check.integer_at_least("ns", n, 1)
        clear_cache()  # SymPy's own cache would make a repeated derivation look cheap
        start = time.perf_counter()
        Chain(n)
        derivation = time.perf_counter() - start
        start = time.perf_counter()
        model = n_pendulum(n)
        build = time.perf_counter() - start
        theta0, omega0 = np.full(n, 0.5), np.zeros(n)
        start = time.perf_counter()
        simulate(model, theta0, omega0, t_end=t_end, dt=dt, method=method, progress=False)
        first = time.perf_counter() - start
        repeats = [
            simulate(
                model, theta0, omega0, t_end=t_end, dt=dt, method=method, progress=False
            ).wall_time
            for _ in range(3)
        ]
        rows.append(ChainCost(n, derivation, build, first, min(repeats) / steps, method.name))
    return rows


@dataclass(frozen=True)
class EnergyComparison:
    """One initial state integrated by several methods.

    Attributes
    ----------
    trajectories : dict
        ``{method name: Trajectory}``.
    """

    trajectories: dict

    def growth(self, fraction: float = 0.1) -> dict:
        """``{method: (first, last)}``: largest ``|E - E0|`` in the first and last ``fraction``.

        See :func:`pendulum_lab.analysis.energy_growth`. A ratio last/first
        near 1 means a bounded energy error, a large ratio a drift.
        """
        from .analysis import energy_growth

        return {name: energy_growth(traj, fraction) for name, traj in self.trajectories.items()}

    def max_relative_error(self) -> dict:
        """``{method: max |E - E0| / |E0|}`` over the run."""
        return {
            name: float(np.max(np.abs(traj.relative_energy_error)))
            for name, traj in self.trajectories.items()
        }

    def plot(self, ax=None):
        """``|E - E0| / |E0|`` against time, log scale, one line per method; returns the Figure.

        Exact zeros are not drawn (a log axis cannot show them).
        """
        ax = _axes(ax, 7.0, 3.6)
        for name, traj in self.trajectories.items():
            err = np.abs(traj.relative_energy_error)
            ax.semilogy(traj.t, np.where(err > 0, err, np.nan), label=name, lw=1)
        ax.set(xlabel="t (s)", ylabel="|E - E(0)| / |E(0)|")
        ax.legend(fontsize="small")
        return ax.figure


def compare_energy(
    model: PendulumModel,
    theta0,
    omega0,
    t_end: float,
    dt: float = 0.01,
    methods=("explicit_euler", "rk4", "leapfrog", "glrk4"),
    *,
    every: int = 1,
    progress: bool | None = None,
) -> EnergyComparison:
    """Integrate one initial state with each of ``methods`` (via :func:`ensemble`).

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0 : array_like, shape (n,)
    t_end, dt, every, progress
        As for :func:`ensemble` with ``keep="thinned"``.
    methods : sequence of str
        Keys of :data:`pendulum_lab.METHODS`.

    Returns
    -------
    EnergyComparison
    """
    check_model(model)
    return EnergyComparison(
        {
            get_method(m).name: ensemble(
                model, theta0, omega0, t_end, dt, m, keep="thinned", every=every, progress=progress
            )
            for m in methods
        }
    )
