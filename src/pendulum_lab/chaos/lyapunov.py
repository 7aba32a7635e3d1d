"""Lyapunov exponents: the largest by two independent methods, and the whole spectrum.

:func:`lyapunov_benettin` follows a companion trajectory and renormalises it
[Benettin]_; :func:`lyapunov_variational` carries a tangent vector along the
trajectory with the Jacobian of the vector field (forces included, so damped
and driven fields too); :func:`lyapunov_spectrum` carries ``2n`` of them and
re-orthonormalises them by QR factorisations. All run as one
:func:`~pendulum_lab.simulate_segments` run, so with the same method, step,
seed and interval they follow the same reference trajectory to the last bit
and differ only in how the growth of a small perturbation is computed.

The exponent of a chaotic orbit is a property of the chaotic component it
explores, and that component lies on one energy surface:
:func:`lyapunov_by_energy` estimates it for orbits spread over each of
several energy surfaces, and tells the orbits of regular islands apart.

Every estimate says how far it has converged. Besides its running estimate
(the sum of logarithms divided by the elapsed time, at every record), each
result holds the estimate after the first half of the run (``half_run``) and
its distance from the full run's (``half_run_difference``), the agreement of
two run lengths on one trajectory. On a chaotic orbit the second half moves
the estimate by about its statistical error: the finite-time exponent
fluctuates like ``t^(-1/2)`` around its limit, and for two nearly independent
halves the difference has the spread of the full run's error. On a regular
orbit the estimate falls like ``ln(c t) / t``, so the first half's estimate is
about twice the full run's and the difference is as large as the estimate
itself: no plateau reached.

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
from typing import NamedTuple

import numpy as np

from .. import validation as check
from ..driver.cluster import check_client, map_members, members_of, portable_method
from ..driver.segments import segment_length, simulate_segments
from ..driver.simulate import canonical_state, time_grid
from ..integrators import get_method
from ..model import require_double_pendulum, require_model
from ..model.pendulum import PendulumModel
from ..plot_dispatch import plot_with
from .common import phase_distance, require_finite, scalar_or_array, unit_direction
from .sections import section_spread
from .separation import perturbed
from .tangent import magnus_propagators, ordered_product

__all__ = [
    "REGULAR_BELOW",
    "EnergyExponent",
    "EnergyLyapunov",
    "LyapunovEstimate",
    "LyapunovSpectrum",
    "benettin_running",
    "half_run_estimate",
    "lyapunov_benettin",
    "lyapunov_by_energy",
    "lyapunov_spectrum",
    "lyapunov_variational",
    "tangent_running",
]

#: An orbit whose estimate after 100 s lies below this [1/s] is counted as
#: regular: on a regular orbit the estimate falls like ``ln(c t) / t``
#: (``ln(100) / 100 = 0.046``), on a chaotic one it settles on a plateau.
REGULAR_BELOW = 0.1


def half_run_estimate(running: np.ndarray) -> np.ndarray:
    """The running estimate after the first half of the records, ``running[J // 2 - 1]``.

    ``running`` has the records first, shape ``(J, ...)``; NaN where ``J < 2``.

    Examples
    --------
    >>> half_run_estimate(np.array([4.0, 3.0, 2.5, 2.0])).tolist()  # after 2 of 4 records
    3.0
    """
    running = np.asarray(running, dtype=float)
    if len(running) < 2:
        return np.full(running.shape[1:], np.nan)
    return running[len(running) // 2 - 1]


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

    Notes
    -----
    :attr:`half_run` and :attr:`half_run_difference` say whether the
    estimate has converged (see the module's description): the estimate
    after the first half of the run, from the same trajectory, and how far
    the second half moved it.
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

    @property
    def half_time(self) -> float:
        """The time of :attr:`half_run`, ``t[J // 2 - 1]`` [s] (NaN with one record)."""
        return float(self.t[len(self.t) // 2 - 1]) if len(self.t) >= 2 else np.nan

    @property
    def half_run(self):
        """The estimate after the first half of the run [1/s], as a run of half the length gives."""
        return scalar_or_array(half_run_estimate(self.running))

    @property
    def half_run_difference(self):
        """``|exponent - half_run|`` [1/s]: how far the second half of the run moved the estimate.

        Of the order of the estimate's statistical error on a chaotic orbit;
        as large as the estimate itself on a regular one (no plateau yet).
        """
        return scalar_or_array(np.abs(self.running[-1] - half_run_estimate(self.running)))

    def at(self, time: float):
        """The running estimate at the recorded time closest to ``time``."""
        return scalar_or_array(self.running[int(np.argmin(np.abs(self.t - time)))])

    def plot(self, ax=None, label=None, **kwargs):
        """Running estimate against time (log time axis); returns the Figure.

        For an ensemble, one line per member.
        """
        return plot_with("plot_lyapunov", self, ax=ax, label=label, **kwargs)


def _prepare(model, theta0, omega0, p0, t_end, dt, name: str, interval, t0):
    """Validated start of an estimate: flat states, the step and whole intervals of the run.

    Returns
    -------
    model : PendulumModel
        The model of each of the ``K`` flat members (a family flattened).
    theta0, p0 : ndarray, shape (K, n)
        The ``K`` initial states, flattened, in canonical variables.
    batch : tuple
        Their ensemble shape.
    dt : float
    interval, count : int
        Steps per interval (the checked argument ``name``) and how many whole
        intervals the run holds.
    """
    theta0, p0 = canonical_state(model, theta0, omega0, p0, t0=t0)
    t_end, dt, n_steps = time_grid(t_end, dt)
    interval = check.integer_at_least(name, interval, 1)
    count = n_steps // interval
    if count < 1:
        raise ValueError(
            f"`t_end` ({t_end}) must cover at least one interval of `{name}` "
            f"({interval} steps of {dt})"
        )
    n, batch = model.n, theta0.shape[:-1]
    return (model.for_ensemble(batch), theta0.reshape(-1, n), p0.reshape(-1, n), batch, dt,
            interval, count)


def lyapunov_benettin(
    model: PendulumModel,
    theta0,
    omega0=None,
    *,
    t_end: float,
    dt: float = 0.01,
    method="glrk4",
    p0=None,
    t0: float = 0.0,
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
    t_end, dt, method, t0, progress
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
        chunks of members (:func:`pendulum_lab.driver.cluster.map_members`); the
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
    model, theta0, p0, batch, dt, every, intervals = _prepare(
        model, theta0, omega0, p0, t_end, dt, "renormalize_every", renormalize_every, t0
    )
    delta = check.positive_number("delta", delta)
    seed = check.seed("seed", seed)
    method = get_method(method)
    client = check_client(client)
    start = time.perf_counter()
    running = map_members(
        benettin_running, (theta0, p0, np.arange(len(theta0))), client=client,
        chunk_size=chunk_size, label="Benettin", progress=progress,
        args=(model, dt, every, intervals, portable_method(method, client), delta, seed, t0,
              progress if client is None else False))
    t = (np.arange(intervals) + 1) * every * dt
    return LyapunovEstimate(t, running.T.reshape(intervals, *batch), "benettin", method.name,
                            dt, time.perf_counter() - start)


def benettin_running(theta0, p0, rows, model: PendulumModel, dt: float, every: int,
                     intervals: int, method, delta: float, seed, t0: float = 0.0,
                     progress: bool | None = None) -> np.ndarray:
    """Benettin's running estimates of a batch of states, shape ``(K, intervals)``.

    The work of :func:`lyapunov_benettin` (arguments validated there) on
    states ``theta0, p0`` of shape ``(K, n)``, rows ``rows`` of the whole
    flattened batch (a family's members are taken there), here or on a Dask
    worker (:func:`pendulum_lab.driver.cluster.map_members`).
    """
    model = members_of(model, rows)
    members = len(theta0)
    q_cmp, p_cmp = perturbed(theta0, p0, delta, seed)
    # Shape (2, K, n): the references, then their companions (a family's
    # members broadcast over both).
    run = simulate_segments(
        model, np.stack([theta0, q_cmp]), p0=np.stack([p0, p_cmp]),
        t_end=intervals * every * dt, dt=dt, method=method, save_every=every,
        segment_steps=every, t0=t0, progress=progress, label="Benettin",
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


def _tangent_growth(model, theta0, omega0, p0, *, t_end, dt, method, save_every, t0, progress,
                    directions, label, client, chunk_size):
    """Carry the tangent vectors ``directions`` (shape ``(2n, k)``) along one run.

    Validates the arguments, then runs :func:`tangent_running` on the whole
    batch, here or in chunks on a Dask cluster.

    Returns
    -------
    t : ndarray, shape (J,)
    running : ndarray, shape (J, ..., k)
        The sums of logarithms divided by the elapsed time.
    method : str
    dt, seconds : float
    """
    start = time.perf_counter()
    model, theta0, p0, batch, dt, every, blocks = _prepare(
        model, theta0, omega0, p0, t_end, dt, "save_every", save_every, t0
    )
    method = get_method(method)
    client = check_client(client)
    # Memory of a segment: the Jacobians and propagators of each of its steps. Sized
    # for the whole batch and passed to every chunk (see default_segment_steps).
    length = segment_length(blocks * every, 4 * len(theta0) * (2 * model.n) ** 2, every)
    running = map_members(
        tangent_running, (theta0, p0, np.arange(len(theta0))), client=client,
        chunk_size=chunk_size, label=label, progress=progress,
        args=(model, dt, every, blocks, portable_method(method, client), directions, length,
              check.real_number("t0", t0), label, progress if client is None else False))
    t = (np.arange(blocks) + 1) * every * dt
    return (t, np.moveaxis(running, 0, 1).reshape(blocks, *batch, directions.shape[1]),
            method.name, dt, time.perf_counter() - start)


def tangent_running(theta0, p0, rows, model: PendulumModel, dt: float, every: int, blocks: int,
                    method, directions, segment_steps: int, t0: float = 0.0,
                    label: str = "variational", progress: bool | None = None) -> np.ndarray:
    """Running estimates of tangent growth for a batch of states, shape ``(K, blocks, k)``.

    The work of :func:`lyapunov_variational` and :func:`lyapunov_spectrum`
    (arguments validated there) on states ``theta0, p0`` of shape ``(K, n)``,
    rows ``rows`` of the whole flattened batch (a family's members are taken
    there), here or on a Dask worker (:func:`pendulum_lab.driver.cluster.map_members`).
    The tangent vectors ``directions`` (shape ``(2n, k)``) are carried along;
    every ``every`` steps the propagated vectors are re-orthonormalised by a QR
    factorisation, ``V = Q R``, and ``log |R_ii|`` is the growth of the
    ``i``-th direction not already spanned by the first ``i - 1``.
    """
    model = members_of(model, rows)
    members = len(theta0)
    run = simulate_segments(model, theta0, p0=p0, t_end=blocks * every * dt, dt=dt,
                            method=method, segment_steps=segment_steps, t0=t0,
                            progress=progress, label=label)
    basis = np.broadcast_to(directions, (members, *directions.shape)).copy()
    log_sum = np.zeros((members, directions.shape[1]))
    running = np.empty((blocks, *log_sum.shape))
    recorded = 0
    for segment in run:
        require_finite(segment, f"lyapunov ({label})")
        step_maps = magnus_propagators(run.model, segment, dt)
        steps = len(segment.t) - 1
        props = ordered_product(step_maps.reshape(steps // every, every, *step_maps.shape[1:]))
        for prop in props:
            basis, r = np.linalg.qr(prop @ basis)
            log_sum += np.log(np.abs(np.diagonal(r, axis1=-2, axis2=-1)))
            recorded += 1
            running[recorded - 1] = log_sum / (recorded * every * dt)
    return np.moveaxis(running, 0, 1)


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
    t0: float = 0.0,
    seed=0,
    progress: bool | None = None,
    client=None,
    chunk_size: int | None = None,
) -> LyapunovEstimate:
    """Largest Lyapunov exponent from the variational (tangent) equations.

    Along a trajectory ``z(t) = (theta, p)`` from :func:`~pendulum_lab.simulate`,
    a tangent vector obeys the linear equation ``v' = A(t) v`` with
    ``A = model.jacobian(theta, p, t)``, the Jacobian of the whole vector
    field (damping and drive included) built from the symbolic second
    derivatives. The tangent is carried over each step ``[t_k, t_k + dt]`` by
    the fourth-order Magnus method:

    ``W = dt/2 (A_1 + A_2) + sqrt(3) dt^2 / 12 [A_2, A_1]``,
    ``v_{k+1} = exp(W) v_k``,

    where ``A_1``, ``A_2`` are the Jacobians at the two Gauss points
    ``t_k + (1/2 -+ sqrt(3)/6) dt`` (the state there from cubic Hermite
    interpolation between the saved steps, :func:`pendulum_lab.driver.events.hermite`,
    accurate to ``O(dt^4)``). The exponential is split as
    ``exp(tr W / 2n) exp(W0)``, ``W0 = W - (tr W / 2n) I``: the scalar factor
    is exact, and ``exp(W0)`` is replaced by its (2,2) Pade approximant
    ``(I - W0/2 + W0^2/12)^{-1} (I + W0/2 + W0^2/12)``. For a Hamiltonian
    field ``W = W0`` is a Hamiltonian matrix, and a diagonal Pade approximant
    maps it to a symplectic one: the tangent propagator is exactly
    symplectic, like the flow it linearises. For the damped simple pendulum
    (``tr A = -gamma``) ``W0`` is a traceless 2 x 2 matrix, whose Pade
    approximant has determinant 1: the propagator contracts areas by exactly
    ``exp(-gamma dt)``, as the flow does. The whole scheme is fourth order in
    ``dt``. The propagators of ``save_every`` steps are multiplied together,
    the tangent vector is advanced, its growth added to a sum of logarithms
    and the vector normalised.

    The state comes from the chosen integrator, the tangent only from the
    Jacobian, so this estimate is independent of :func:`lyapunov_benettin`
    (which uses no Jacobian); both follow the same reference trajectory.
    :func:`lyapunov_spectrum` carries ``2n`` tangent vectors the same way.

    Parameters
    ----------
    model : PendulumModel
        Or a :class:`~pendulum_lab.model.ModelFamily` (one estimate per member).
    theta0, omega0, p0 : array_like, shape (..., n)
    t_end, dt, method, t0, progress
        As for :func:`~pendulum_lab.simulate`; the estimate uses
        ``floor(n_steps / save_every)`` whole blocks of steps.
    save_every : int
        Steps between recorded estimates (and normalisations), ``>= 1``.
    seed : int or None
        Seed of the initial tangent direction (the same direction as
        :func:`lyapunov_benettin` with the same seed).
    client : dask.distributed.Client, optional
        Integrate an ensemble (a Lyapunov map) on this Dask cluster, in
        chunks of members (:func:`pendulum_lab.driver.cluster.map_members`); the
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
    S. Blanes, F. Casas, J. A. Oteo, J. Ros, "The Magnus expansion and some of
    its applications", Phys. Rep. 470 (2009) 151-238 (the fourth-order method).

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> est = lyapunov_variational(pl.double_pendulum(), [2.0, 2.5], [0.0, 0.0], t_end=5.0,
    ...                            method="rk4")
    >>> bool(est.exponent > 0.5)
    True
    """
    require_model(model)
    seed = check.seed("seed", seed)
    t, running, name, dt, seconds = _tangent_growth(
        model, theta0, omega0, p0, t_end=t_end, dt=dt, method=method, save_every=save_every,
        t0=t0, progress=progress, directions=unit_direction(2 * model.n, seed)[:, None],
        label="variational", client=client, chunk_size=chunk_size,
    )
    return LyapunovEstimate(t, running[..., 0], "variational", name, dt, seconds)


@dataclass(frozen=True)
class LyapunovSpectrum:
    """Running estimates of all ``2n`` Lyapunov exponents.

    Attributes
    ----------
    t : ndarray, shape (J,)
        Times of the estimates, from the start of the run [s].
    running : ndarray, shape (J, ..., 2n)
        Running estimates [1/s]; ``...`` is the ensemble shape. Exponent
        ``i`` is the growth rate of the ``i``-th direction orthogonal to the
        first ``i - 1`` (QR order): after a transient, largest first.
    method : str
        The integrator that produced the trajectory.
    dt : float
    wall_time : float
    """

    t: np.ndarray
    running: np.ndarray
    method: str
    dt: float
    wall_time: float

    @property
    def exponents(self) -> np.ndarray:
        """The estimates at the final time, shape ``(..., 2n)`` [1/s]."""
        return self.running[-1]

    @property
    def largest(self):
        """The first exponent at the final time (float, or array for an ensemble)."""
        return scalar_or_array(self.running[-1, ..., 0])

    @property
    def half_time(self) -> float:
        """The time of :attr:`half_run`, ``t[J // 2 - 1]`` [s] (NaN with one record)."""
        return float(self.t[len(self.t) // 2 - 1]) if len(self.t) >= 2 else np.nan

    @property
    def half_run(self) -> np.ndarray:
        """Every exponent after the first half of the run, shape ``(..., 2n)`` [1/s]."""
        return half_run_estimate(self.running)

    @property
    def half_run_difference(self) -> np.ndarray:
        """``|exponents - half_run|``, shape ``(..., 2n)`` [1/s]: the second half's change of each.

        See :class:`LyapunovEstimate` and the module's description for how to read it.
        """
        return np.abs(self.running[-1] - half_run_estimate(self.running))

    @property
    def sum(self):
        """Sum of the exponents at the final time: the mean phase-space contraction rate."""
        return scalar_or_array(self.running[-1].sum(axis=-1))

    def plot(self, ax=None, **kwargs):
        """Running estimates of every exponent against time; returns the Figure."""
        return plot_with("plot_lyapunov_spectrum", self, ax=ax, **kwargs)


def lyapunov_spectrum(
    model: PendulumModel,
    theta0,
    omega0=None,
    *,
    t_end: float,
    dt: float = 0.01,
    method="glrk4",
    save_every: int = 50,
    p0=None,
    t0: float = 0.0,
    progress: bool | None = None,
    client=None,
    chunk_size: int | None = None,
) -> LyapunovSpectrum:
    """All ``2n`` Lyapunov exponents, by QR re-orthonormalisation of the tangent vectors.

    ``2n`` tangent vectors, starting as the coordinate axes of
    ``(theta, p)``, are carried along the trajectory exactly as in
    :func:`lyapunov_variational` (fourth-order Magnus propagators of the
    Jacobian of the whole field, forces included). Every ``save_every``
    steps they are re-orthonormalised, ``V = Q R`` (Gram-Schmidt in matrix
    form); ``Q`` goes on, and ``log |R_ii|`` is added to the sum of
    exponent ``i`` (Benettin, Galgani, Giorgilli and Strelcyn, 1980, in the References).

    The sum of all exponents is the mean rate at which the flow changes
    phase-space volume, the time average of ``tr A`` (Liouville's formula).
    The propagators reproduce it by construction: their determinant is
    ``exp(tr W)`` exactly (see :func:`~pendulum_lab.chaos.tangent.magnus_propagators`),
    and ``sum log |R_ii| = log |det|``. So for the damped simple pendulum
    (``tr A = -damping / (m l^2)`` at every state) the computed sum equals
    ``-damping / (m l^2)`` to round-off after any run, converged or not, and
    for a Hamiltonian field it is 0: an identity of the algorithm, which checks
    the Jacobian's trace and nothing else. What does test the estimates is
    their convergence (:attr:`LyapunovSpectrum.half_run_difference`) and, for
    a Hamiltonian field, the pairing of the spectrum: the exponents come in
    pairs ``lambda_i + lambda_(2n+1-i) = 0`` and two of them vanish (the
    direction of the flow and the gradient of the energy), a property of the
    limit that finite runs approach.

    Parameters
    ----------
    model : PendulumModel
        Or a :class:`~pendulum_lab.model.ModelFamily` (one spectrum per member).
    theta0, omega0, p0 : array_like, shape (..., n)
    t_end, dt, method, t0, progress
        As for :func:`~pendulum_lab.simulate`; the estimate uses
        ``floor(n_steps / save_every)`` whole blocks of steps.
    save_every : int
        Steps between re-orthonormalisations (and recorded estimates), ``>= 1``.
    client : dask.distributed.Client, optional
        Integrate an ensemble on this Dask cluster, in chunks of members
        (:func:`pendulum_lab.driver.cluster.map_members`); the spectra are the same,
        bit for bit, as without it.
    chunk_size : int, optional
        Members per chunk on a cluster (by default a few chunks per worker).

    Returns
    -------
    LyapunovSpectrum

    Raises
    ------
    FloatingPointError
        If the integration blows up.

    References
    ----------
    Benettin, Galgani, Giorgilli, Strelcyn, Meccanica 15 (1980) 21-30 (all
    the exponents); K. Geist, U. Parlitz, W. Lauterborn, "Comparison of
    different methods for computing Lyapunov exponents", Prog. Theor. Phys.
    83 (1990) 875-893.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> spectrum = lyapunov_spectrum(pl.driven_pendulum(), [0.2], [0.0], t_end=30.0, dt=0.1,
    ...                              method="rk4")
    >>> round(spectrum.sum, 12)  # -damping / (m l^2)
    -0.5
    """
    require_model(model)
    t, running, name, dt, seconds = _tangent_growth(
        model, theta0, omega0, p0, t_end=t_end, dt=dt, method=method, save_every=save_every,
        t0=t0, progress=progress, directions=np.eye(2 * model.n), label="spectrum",
        client=client, chunk_size=chunk_size,
    )
    return LyapunovSpectrum(t, running, name, dt, seconds)

class EnergyExponent(NamedTuple):
    """The exponent on one energy surface: mean and standard error over its chaotic orbits."""

    energy: float
    mean: float
    standard_error: float
    chaotic: int
    orbits: int


@dataclass(frozen=True)
class EnergyLyapunov:
    """Lyapunov exponents of orbits spread over energy surfaces; see :func:`lyapunov_by_energy`.

    Attributes
    ----------
    energies : ndarray, shape (E,)
        The energy surfaces [J].
    energy : ndarray, shape (K,)
        The energy of each orbit [J].
    theta0, omega0 : ndarray, shape (K, n)
        The initial states.
    exponent : ndarray, shape (K,)
        Benettin's estimate after ``t_end`` [1/s].
    threshold : float
        Orbits with ``exponent < threshold`` count as regular.
    t_end, dt : float
    method : str
    wall_time : float
    half_run : ndarray, shape (K,), optional
        Benettin's estimate after the first half of the run [1/s] (see
        :class:`LyapunovEstimate`); None when not recorded.
    t : ndarray, shape (J,), optional
    running : ndarray, shape (J, K), optional
        The running estimates of every orbit at the times ``t`` [1/s].
    """

    energies: np.ndarray
    energy: np.ndarray
    theta0: np.ndarray
    omega0: np.ndarray
    exponent: np.ndarray
    threshold: float
    t_end: float
    dt: float
    method: str
    wall_time: float
    half_run: np.ndarray | None = None
    t: np.ndarray | None = None
    running: np.ndarray | None = None

    @property
    def half_run_difference(self) -> np.ndarray:
        """``|exponent - half_run|``, shape (K,) [1/s]: two run lengths compared, per orbit."""
        if self.half_run is None:
            raise ValueError("this scan holds no half-run estimates (built without `half_run`)")
        return np.abs(self.exponent - self.half_run)

    @property
    def regular(self) -> np.ndarray:
        """Boolean mask, shape (K,): orbits whose estimate lies below ``threshold``."""
        return self.exponent < self.threshold

    def per_energy(self) -> list[EnergyExponent]:
        """One :class:`EnergyExponent` per energy (mean NaN where no orbit is chaotic)."""
        rows = []
        for energy in self.energies:
            here = self.energy == energy
            chaotic = self.exponent[here & ~self.regular]
            mean = float(chaotic.mean()) if chaotic.size else np.nan
            error = float(chaotic.std(ddof=1) / np.sqrt(chaotic.size)) if chaotic.size > 1 \
                else np.nan
            rows.append(EnergyExponent(float(energy), mean, error, int(chaotic.size),
                                       int(here.sum())))
        return rows

    def plot(self, ax=None):
        """Exponent against energy: every orbit, and the mean over the chaotic ones."""
        return plot_with("plot_lyapunov_energy", self, ax=ax)


def lyapunov_by_energy(
    model: PendulumModel,
    energies,
    *,
    orbits: int = 12,
    t_end: float = 100.0,
    dt: float = 0.01,
    method="glrk4",
    threshold: float = REGULAR_BELOW,
    seed=0,
    progress: bool | None = None,
) -> EnergyLyapunov:
    """Benettin's exponent for orbits spread over each of several energy surfaces.

    The exponent belongs to a chaotic component, and a component lies on one
    energy surface: averaging over releases of different energies mixes
    different components, and releases in regular islands add near-zero
    values. Here the starts of each energy are those of its Poincare section
    (:func:`~pendulum_lab.chaos.section_spread`), all orbits run as one
    ensemble (:func:`lyapunov_benettin`), and the orbits whose estimate after
    ``t_end`` stays below ``threshold`` are counted as regular and left out of
    the mean (:meth:`EnergyLyapunov.per_energy`).

    Parameters
    ----------
    model : PendulumModel
        A double pendulum.
    energies : sequence of float
        Energies [J], above the minimum of the potential energy.
    orbits : int
        Orbits per energy, ``>= 2``.
    t_end, dt, method, seed, progress
        As for :func:`lyapunov_benettin`.
    threshold : float
        Estimates below it [1/s] count as regular orbits, ``> 0``; the default
        :data:`REGULAR_BELOW` suits ``t_end`` near 100 s.

    Returns
    -------
    EnergyLyapunov

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> scan = lyapunov_by_energy(pl.double_pendulum(), [-20.0, 16.0], orbits=2, t_end=20.0,
    ...                           method="rk4", threshold=0.3)
    >>> [(row.energy, row.chaotic) for row in scan.per_energy()]
    [(-20.0, 0), (16.0, 2)]
    """
    require_double_pendulum(model)
    energies = np.array([check.real_number("energies", e) for e in np.atleast_1d(energies)])
    lowest = float(model.potential_energy(np.zeros(2)))
    if energies.size == 0 or np.any(energies <= lowest):
        raise ValueError(f"`energies` must lie above the minimum of the potential energy "
                         f"({lowest:.6g} J), got {energies.tolist()}")
    orbits = check.integer_at_least("orbits", orbits, 2)
    threshold = check.positive_number("threshold", threshold)
    seed = check.seed("seed", seed)
    starts = [section_spread(model, energy, orbits) for energy in energies]
    theta0 = np.concatenate([theta for theta, _ in starts])
    omega0 = np.concatenate([omega for _, omega in starts])
    energy = np.repeat(energies, [len(theta) for theta, _ in starts])
    estimate = lyapunov_benettin(model, theta0, omega0, t_end=t_end, dt=dt, method=method,
                                 seed=seed, progress=progress)
    return EnergyLyapunov(energies, energy, theta0, omega0, np.asarray(estimate.exponent),
                          threshold, float(estimate.t[-1]), estimate.dt, estimate.method,
                          estimate.wall_time, np.asarray(estimate.half_run), estimate.t,
                          estimate.running)
