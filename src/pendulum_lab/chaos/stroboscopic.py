"""Stroboscopic sections of a driven pendulum, and the periods of their orbits.

A pendulum driven with period ``T`` is a map in disguise: the state at
``t0 + (k + 1) T`` is a fixed function of the state at ``t0 + k T`` (the
stroboscopic or period map). A periodic response of period ``p T`` is a
cycle of ``p`` points of that map; a strange attractor is a fractal set of
points [BG]_. :func:`stroboscopic_section` samples the state once per drive
period; :func:`orbit_periods` counts the distinct points of each orbit.

References
----------
.. [BG] G. L. Baker, J. P. Gollub, *Chaotic Dynamics: An Introduction*, 2nd
   ed., Cambridge University Press 1996, ch. 3-5.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import validation as check
from ..driver.segments import simulate_segments
from ..driver.simulate import check_run_length
from ..model import require_model
from ..model.angles import wrap_angle
from ..model.pendulum import PendulumModel
from ..plot_dispatch import plot_with
from .common import require_finite

__all__ = ["StroboscopicSection", "drive_period", "orbit_periods", "stroboscopic_section"]

#: Default tolerance of :func:`orbit_periods` (max-norm in wrapped theta [rad]
#: and omega [rad/s]).
PERIOD_TOLERANCE = 1e-4


def drive_period(model: PendulumModel) -> float:
    """The drive period of ``model`` (one number, shared by every member of a family).

    Raises
    ------
    ValueError
        If ``model`` has no drive frequency, or a family's members have
        different drive periods.
    """
    require_model(model)
    period = model.drive_period
    if period is None:
        raise ValueError("`model` has no drive period (a chain's `drive_frequency` is None, or a "
                         "system was given no `period`): a stroboscopic section samples once "
                         "per drive period")
    period = np.asarray(period, dtype=float)
    if np.ptp(period) != 0:
        raise ValueError("the members of `model` have different drive periods; sample them "
                         "one frequency at a time (bifurcation_diagram over 'drive_frequency' "
                         "rescales time to a common period)")
    return float(period.flat[0])


def orbit_periods(theta, omega, tolerance: float = PERIOD_TOLERANCE,
                  max_period: int = 16) -> np.ndarray:
    """The period of each orbit of a stroboscopic section: its number of distinct points.

    The period of member ``m`` is the smallest ``p <= max_period`` such that
    every sample lies within ``tolerance`` of the sample ``p`` periods later
    (max-norm over the links of ``|wrap(theta_{k+p} - theta_k)|`` and
    ``|omega_{k+p} - omega_k|``). An orbit with no such ``p`` (chaotic, of a
    longer period, or not yet settled) gets 0.

    Parameters
    ----------
    theta, omega : array_like, shape (S, ..., n)
        ``S`` consecutive stroboscopic samples, ``S >= 2 max_period``.
    tolerance : float
        How close two samples must be to count as the same point.
    max_period : int

    Returns
    -------
    ndarray of int, shape (...)

    Examples
    --------
    >>> k = np.arange(40)[:, None]
    >>> theta = np.stack([0.5 * (-1.0) ** k, 0.3 + 0 * k], axis=1)  # periods 2 and 1
    >>> orbit_periods(theta, np.zeros_like(theta)).tolist()
    [2, 1]
    """
    theta, omega = np.asarray(theta, dtype=float), np.asarray(omega, dtype=float)
    tolerance = check.positive_number("tolerance", tolerance)
    max_period = check.integer_at_least("max_period", max_period, 1)
    if theta.shape != omega.shape or theta.ndim < 2:
        raise ValueError(f"`theta` and `omega` must have one shape (S, ..., n), got {theta.shape} "
                         f"and {omega.shape}")
    if len(theta) < 2 * max_period:
        raise ValueError(f"the section needs at least 2 max_period = {2 * max_period} samples to "
                         f"tell periods up to {max_period}, got {len(theta)}")
    periods = np.zeros(theta.shape[1:-1], dtype=int)
    for p in range(max_period, 0, -1):  # the smallest p that fits ends up in `periods`
        gap = np.maximum(np.abs(wrap_angle(theta[p:] - theta[:-p])),
                         np.abs(omega[p:] - omega[:-p]))
        periods = np.where(np.max(gap, axis=(0, -1)) < tolerance, p, periods)
    return periods


@dataclass(frozen=True)
class StroboscopicSection:
    """States sampled once per drive period, after a transient.

    The last sample is a state to go on from: ``theta[-1]`` (wrapping does
    not change the motion), ``p[-1]`` at time ``t[-1]``.

    Attributes
    ----------
    t : ndarray, shape (S,)
        Sample times ``t0 + k T`` [s], ``k = transient_periods + 1, ...``.
    theta : ndarray, shape (S, ..., n)
        Angles wrapped to ``(-pi, pi]`` [rad]; ``...`` is the ensemble shape.
    omega, p : ndarray, shape (S, ..., n)
        Angular velocities [rad/s] and canonical momenta.
    turns : ndarray, shape (..., n)
        Mean number of full turns per drive period over the samples (the
        angles unwrapped): 0 for an oscillation, +-1 for a pendulum that goes
        over the top once per period (NaN with one sample).
    drive_period : float
    steps_per_period, transient_periods : int
    method : str
    """

    t: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    p: np.ndarray
    turns: np.ndarray
    drive_period: float
    steps_per_period: int
    transient_periods: int
    method: str

    def periods(self, tolerance: float = PERIOD_TOLERANCE, max_period: int = 16) -> np.ndarray:
        """:func:`orbit_periods` of every member, shape ``(...)``."""
        return orbit_periods(self.theta, self.omega, tolerance, max_period)

    def plot(self, ax=None, link: int = 0, member=None, **kwargs):
        """The samples in the ``(theta, omega)`` plane of ``link``; returns the Figure."""
        return plot_with("plot_stroboscopic", self, ax=ax, link=link, member=member, **kwargs)


def stroboscopic_section(
    model: PendulumModel,
    theta0,
    omega0=None,
    *,
    n_periods: int,
    transient_periods: int = 100,
    steps_per_period: int = 100,
    method="rk4",
    p0=None,
    t0: float = 0.0,
    progress: bool | None = None,
    segment_steps: int | None = None,
) -> StroboscopicSection:
    """Sample a driven pendulum once per drive period, after a transient.

    One :func:`~pendulum_lab.simulate_segments` run with step
    ``dt = T / steps_per_period`` (so the samples fall on steps exactly) and
    ``save_every = steps_per_period``; the first ``transient_periods``
    samples are dropped.

    Parameters
    ----------
    model : PendulumModel
        A model with a drive frequency; or a
        :class:`~pendulum_lab.model.ModelFamily` sharing one drive period.
    theta0, omega0, p0 : array_like, shape (n,) or (..., n)
        The initial state, as for :func:`~pendulum_lab.simulate`.
    n_periods : int
        Samples to keep, ``>= 1``.
    transient_periods : int
        Drive periods run before the first kept sample, ``>= 0``.
    steps_per_period : int
        Steps per drive period, ``>= 1``.
    method, t0, progress
        As for :func:`~pendulum_lab.simulate`. ``t0`` fixes the drive's phase
        at the samples.
    segment_steps : int, optional
        As for :func:`~pendulum_lab.simulate_segments` (a multiple of
        ``steps_per_period``).

    Returns
    -------
    StroboscopicSection

    Raises
    ------
    FloatingPointError
        If the integration blows up (use more steps per period).

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> section = stroboscopic_section(pl.driven_pendulum(drive_amplitude=0.9), [0.2], [0.0],
    ...                                n_periods=32, transient_periods=100, steps_per_period=50)
    >>> section.theta.shape, int(section.periods())  # one point: a period-1 response
    ((32, 1), 1)
    """
    period = drive_period(model)
    n_periods = check.integer_at_least("n_periods", n_periods, 1)
    transient_periods = check.integer_at_least("transient_periods", transient_periods, 0)
    steps_per_period = check.integer_at_least("steps_per_period", steps_per_period, 1)
    total = transient_periods + n_periods
    check_run_length(total * steps_per_period, 1, opt_in=False,
                     what=f"`transient_periods` + `n_periods` = {total} periods of "
                     f"`steps_per_period` = {steps_per_period} steps",
                     advice="Choose fewer periods or fewer `steps_per_period`")
    run = simulate_segments(model, theta0, omega0, p0=p0, t_end=total * period,
                            dt=period / steps_per_period, method=method,
                            save_every=steps_per_period, t0=t0, progress=progress,
                            segment_steps=segment_steps, label="stroboscopic")
    parts = []
    for segment in run:
        require_finite(segment, "stroboscopic_section")
        parts.append(segment)  # each segment starts at the previous one's last sample
    kept = slice(transient_periods + 1, None)
    t = np.concatenate([parts[0].t[:1], *(s.t[1:] for s in parts)])[kept]

    def samples(name):
        joined = np.concatenate([getattr(parts[0], name)[:1],
                                 *(getattr(s, name)[1:] for s in parts)])[kept]
        return joined.reshape(len(t), *run.batch_shape, model.n)

    theta = samples("theta")
    with np.errstate(invalid="ignore", divide="ignore"):
        turns = (theta[-1] - theta[0]) / (2 * np.pi * (len(t) - 1))
    return StroboscopicSection(t, wrap_angle(theta), samples("omega"), samples("p"), turns,
                               period, steps_per_period, transient_periods, run.method.name)
