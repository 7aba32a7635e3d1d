"""The largest Lyapunov exponent, by two independent methods.

:func:`lyapunov_benettin` follows a companion trajectory and renormalises it
[Benettin]_; :func:`lyapunov_variational` carries a tangent vector along the
trajectory with the Jacobian of Hamilton's equations. Both run as one
:func:`~pendulum_lab.simulate_segments` run, so with the same method, step,
seed and interval they follow the same reference trajectory to the last bit
and differ only in how the growth of a small perturbation is computed.

References
----------
.. [Benettin] G. Benettin, L. Galgani, A. Giorgilli, J.-M. Strelcyn,
   "Lyapunov characteristic exponents for smooth dynamical systems and for
   Hamiltonian systems; a method for computing all of them", Meccanica 15
   (1980) 9-20 and 21-30.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .. import _validation as check
from ..cluster import check_client, map_members, portable_method
from ..events import hermite
from ..integrators import get_method
from ..model import PendulumModel
from ..segments import segment_length, simulate_segments
from ..simulate import Trajectory, canonical_state, time_grid
from ._common import phase_distance, require_finite, scalar_or_array, unit_direction
from .separation import perturbed

__all__ = ["LyapunovEstimate", "benettin_running", "lyapunov_benettin", "lyapunov_variational"]


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
        return scalar_or_array(self.running[-1])

    def at(self, time: float):
        """The running estimate at the recorded time closest to ``time``."""
        return scalar_or_array(self.running[int(np.argmin(np.abs(self.t - time)))])

    def plot(self, ax=None, label=None, **kwargs):
        """Running estimate against time (log time axis); returns the Figure.

        For an ensemble, one line per member.
        """
        from ..plotting import plot_lyapunov

        return plot_lyapunov(self, ax=ax, label=label, **kwargs)


def _prepare(model, theta0, omega0, p0, t_end, dt, name: str, interval):
    """Validated start of an estimate: flat states, the step and whole intervals of the run.

    Returns
    -------
    theta0, p0 : ndarray, shape (K, n)
        The ``K`` initial states, flattened, in canonical variables.
    batch : tuple
        Their ensemble shape.
    dt : float
    interval, count : int
        Steps per interval (the checked argument ``name``) and how many whole
        intervals the run holds.
    """
    theta0, p0 = canonical_state(model, theta0, omega0, p0)
    t_end, dt, n_steps = time_grid(t_end, dt)
    interval = check.integer_at_least(name, interval, 1)
    count = n_steps // interval
    if count < 1:
        raise ValueError(
            f"`t_end` ({t_end}) must cover at least one interval of `{name}` "
            f"({interval} steps of {dt})"
        )
    n = model.n
    return theta0.reshape(-1, n), p0.reshape(-1, n), theta0.shape[:-1], dt, interval, count


def lyapunov_benettin(
    model: PendulumModel,
    theta0,
    omega0=None,
    *,
    t_end: float,
    dt: float = 0.01,
    method="glrk4",
    p0=None,
    delta: float = 1e-8,
    renormalize_every: int = 50,
    seed=0,
    progress: bool | None = None,
    client=None,
    chunk_size: int | None = None,
) -> LyapunovEstimate:
    """Largest Lyapunov exponent by Benettin's two-trajectory method.

    A companion trajectory starts ``delta`` away from the reference (in
    ``(theta, p)``, direction fixed by ``seed``). Every ``renormalize_every``
    steps the distance ``d`` is measured, ``log(d / delta)`` is added to a sum,
    and the companion is pulled back along the same direction to distance
    ``delta``. The running estimate is the sum divided by the elapsed time.
    Renormalising keeps the separation in the linear regime (``delta`` small)
    while following the most unstable direction, which it aligns with after a
    transient. Reference and companion are one ensemble, run one
    renormalisation interval per segment; the reference is never touched, so
    it is the same trajectory as in :func:`lyapunov_variational`.

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0, p0 : array_like, shape (..., n)
        One initial state or an ensemble of them, as for
        :func:`~pendulum_lab.simulate`.
    t_end, dt, method, progress
        As for :func:`~pendulum_lab.simulate`; the estimate uses whole
        renormalisation intervals, ``floor(n_steps / renormalize_every)`` of them.
    delta : float
        Separation after each renormalisation, ``> 0``; 1e-8 keeps it both
        linear and well above round-off.
    renormalize_every : int
        Steps between renormalisations, ``>= 1``.
    seed : int or None
        Seed of the initial perturbation direction (one direction for every
        member of an ensemble).
    client : dask.distributed.Client, optional
        Integrate an ensemble (a Lyapunov map) on this Dask cluster, in
        chunks of members (:func:`pendulum_lab.cluster.map_members`); the
        estimates are the same, bit for bit, as without it.
    chunk_size : int, optional
        Members per chunk on a cluster (by default a few chunks per worker).

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
    theta0, p0, batch, dt, every, intervals = _prepare(
        model, theta0, omega0, p0, t_end, dt, "renormalize_every", renormalize_every
    )
    delta = check.positive_number("delta", delta)
    method = get_method(method)
    client = check_client(client)
    start = time.perf_counter()
    running = map_members(
        benettin_running, (theta0, p0), client=client, chunk_size=chunk_size, label="Benettin",
        progress=progress,
        args=(model, dt, every, intervals, portable_method(method, client), delta, seed,
              progress if client is None else False))
    t = (np.arange(intervals) + 1) * every * dt
    return LyapunovEstimate(t, running.T.reshape(intervals, *batch), "benettin", method.name,
                            dt, time.perf_counter() - start)


def benettin_running(theta0, p0, model: PendulumModel, dt: float, every: int, intervals: int,
                     method, delta: float, seed, progress: bool | None = None
                     ) -> np.ndarray:
    """Benettin's running estimates of a batch of states, shape ``(K, intervals)``.

    The work of :func:`lyapunov_benettin` (arguments validated there) on
    states ``theta0, p0`` of shape ``(K, n)``, here or on a Dask worker
    (:func:`pendulum_lab.cluster.map_members`).
    """
    members = len(theta0)
    q_cmp, p_cmp = perturbed(theta0, p0, delta, seed)
    run = simulate_segments(
        model, np.concatenate([theta0, q_cmp]), p0=np.concatenate([p0, p_cmp]),
        t_end=intervals * every * dt, dt=dt, method=method, save_every=every,
        segment_steps=every, progress=progress, label="Benettin",
    )
    companion = np.arange(2 * members) >= members
    log_sum = np.zeros(members)
    running = np.empty((members, intervals))
    for j, segment in enumerate(run, start=1):
        require_finite(segment, "lyapunov_benettin")
        q_ref, q_cmp = segment.theta[-1, :members], segment.theta[-1, members:]
        p_ref, p_cmp = segment.p[-1, :members], segment.p[-1, members:]
        d = phase_distance(q_ref, p_ref, q_cmp, p_cmp)
        log_sum += np.log(d / delta)
        running[:, j - 1] = log_sum / (j * every * dt)
        shrink = (delta / d)[:, None]
        run.restart(q_ref + shrink * (q_cmp - q_ref), p_ref + shrink * (p_cmp - p_ref),
                    where=companion)
    return running


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
        zs = hermite(s, z0, z1, d0, d1)
        jacobians.append(model.jacobian(zs[..., :n], zs[..., n:]))
    a1, a2 = jacobians
    w = (dt / 2) * (a1 + a2) + (np.sqrt(3) * dt**2 / 12) * (a2 @ a1 - a1 @ a2)
    w2 = (w @ w) / 12
    eye = np.eye(2 * n)
    return np.linalg.solve(eye - w / 2 + w2, eye + w / 2 + w2)


def lyapunov_variational(
    model: PendulumModel,
    theta0,
    omega0=None,
    *,
    t_end: float,
    dt: float = 0.01,
    method="glrk4",
    save_every: int = 50,
    p0=None,
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
    interpolation between the saved steps, :func:`pendulum_lab.events.hermite`,
    accurate to ``O(dt^4)``), and the last line is the (2,2) Pade approximant
    of ``exp(W)``. ``W`` is a Hamiltonian matrix and a diagonal Pade
    approximant maps Hamiltonian matrices to symplectic ones, so the tangent
    propagator is exactly symplectic, like the flow it linearises; the whole
    scheme is fourth order in ``dt``. The propagators of ``save_every`` steps
    are multiplied together, the tangent vector is advanced, its growth added
    to a sum of logarithms and the vector normalised.

    The state comes from the chosen integrator, the tangent only from the
    Jacobian, so this estimate is independent of :func:`lyapunov_benettin`
    (which uses no Jacobian); both follow the same reference trajectory.

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0, p0 : array_like, shape (..., n)
    t_end, dt, method, progress
        As for :func:`~pendulum_lab.simulate`; the estimate uses
        ``floor(n_steps / save_every)`` whole blocks of steps.
    save_every : int
        Steps between recorded estimates (and normalisations), ``>= 1``.
    seed : int or None
        Seed of the initial tangent direction (the same direction as
        :func:`lyapunov_benettin` with the same seed).

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
    theta0, p0, batch, dt, every, blocks = _prepare(
        model, theta0, omega0, p0, t_end, dt, "save_every", save_every
    )
    n, members = model.n, len(theta0)
    total = blocks * every
    # Memory of a segment: the Jacobians and propagators of each of its steps.
    length = segment_length(total, 4 * members * (2 * n) ** 2, every)
    run = simulate_segments(model, theta0, p0=p0, t_end=total * dt, dt=dt, method=method,
                            segment_steps=length, progress=progress, label="variational")
    v = np.broadcast_to(unit_direction(2 * n, seed), (members, 2 * n)).copy()
    log_sum = np.zeros(members)
    running = np.empty((blocks, members))
    recorded = 0
    start = time.perf_counter()
    for segment in run:
        require_finite(segment, "lyapunov_variational")
        step_maps = _magnus_propagators(model, segment, dt)
        steps = len(segment.t) - 1
        props = _ordered_product(step_maps.reshape(steps // every, every, *step_maps.shape[1:]))
        for prop in props:
            v = np.einsum("...ij,...j->...i", prop, v)
            norm = np.linalg.norm(v, axis=-1)
            log_sum += np.log(norm)
            v /= norm[..., None]
            recorded += 1
            running[recorded - 1] = log_sum / (recorded * every * dt)
    t = (np.arange(blocks) + 1) * every * dt
    return LyapunovEstimate(t, running.reshape(blocks, *batch), "variational", run.method.name,
                            dt, time.perf_counter() - start)
