"""Oscillations: exact and measured periods, spectra and their peaks.

The simple pendulum's period is known in closed form (an elliptic integral);
a simulated period comes from the zero crossings of an angle
(:func:`pendulum_lab.driver.events.find_crossings`), frequencies from the peaks of a
windowed power spectrum.
"""

from __future__ import annotations

import numpy as np
from scipy.special import ellipk

from .. import validation as check
from ..driver.events import find_crossings
from ..driver.simulate import Trajectory
from ..model.pendulum import PendulumModel

__all__ = ["dominant_frequencies", "exact_period", "oscillation_period", "spectrum"]


def exact_period(model: PendulumModel, amplitude):
    """Exact period of the simple pendulum released at rest from ``amplitude``.

    ``T = 4 sqrt(l / g) K(k^2)`` with ``k = sin(amplitude / 2)`` and ``K`` the
    complete elliptic integral of the first kind (``scipy.special.ellipk``
    takes the parameter ``m = k^2``). At small amplitude it tends to
    ``2 pi sqrt(l / g)``; it diverges as the amplitude approaches ``pi``.

    Parameters
    ----------
    model : PendulumModel
        A simple pendulum (``n = 1``) with ``g > 0``.
    amplitude : float or array_like
        Release angle(s) [rad], ``0 <= |amplitude| < pi``.

    Returns
    -------
    float or ndarray
        Period(s) [s], the shape of ``amplitude``.

    References
    ----------
    G. L. Baker, J. A. Blackburn, *The Pendulum*, Oxford 2005, ch. 1.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> sp_ = pl.simple_pendulum(length=1.0, g=9.81)
    >>> round(float(exact_period(sp_, 1e-8) / (2 * np.pi * np.sqrt(1 / 9.81))), 12)
    1.0
    """
    if not isinstance(model, PendulumModel) or model.n != 1:
        raise ValueError("`model` must be a simple pendulum (n = 1) for the exact period")
    if model.g <= 0:
        raise ValueError(f"the model's `g` must be positive for oscillations, got {model.g}")
    amplitude = np.asarray(amplitude, dtype=float)
    if not np.all(np.isfinite(amplitude)) or np.any(np.abs(amplitude) >= np.pi):
        raise ValueError(
            f"`amplitude` must lie in (-pi, pi) (a release below the top), got {amplitude}"
        )
    period = 4.0 * np.sqrt(model.lengths[0] / model.g) * ellipk(np.sin(amplitude / 2) ** 2)
    return float(period) if period.ndim == 0 else period


def oscillation_period(traj: Trajectory, link: int = 0):
    """Mean period of a libration, from the upward zero crossings of ``theta[link]``.

    The crossing times are found by linear interpolation between saved
    steps; at a crossing of a libration about the downward vertical the angle
    has no curvature (``theta'' ~ -sin(theta) = 0``), so the interpolation
    error is third order in the step.

    Parameters
    ----------
    traj : Trajectory
        One trajectory or an ensemble, angles of shape ``(N+1, ..., n)``.
    link : int
        Which link's angle to time (0-based).

    Returns
    -------
    float or ndarray
        The period [s]; an array of the ensemble shape for an ensemble.

    Raises
    ------
    ValueError
        If some trajectory has fewer than two upward crossings (it did not
        complete a full oscillation, or it rotates instead of swinging).
    """
    link = check.index_below("link", link, traj.theta.shape[-1])
    angles = traj.theta[..., link]
    crossings = find_crossings(angles, direction=1)
    k = crossings.step
    times = traj.t[k] + crossings.fraction() * (traj.t[k + 1] - traj.t[k])
    periods = np.empty(int(np.prod(angles.shape[1:], dtype=int)))
    for j in range(periods.size):
        mine = times[crossings.member == j]
        if len(mine) < 2:
            raise ValueError(
                f"trajectory {j} has {len(mine)} upward zero crossing(s) of theta[{link}]; "
                "a period needs at least two (run longer, or the link rotates)"
            )
        periods[j] = (mine[-1] - mine[0]) / (len(mine) - 1)
    periods = periods.reshape(angles.shape[1:])
    return float(periods) if periods.ndim == 0 else periods


def spectrum(traj: Trajectory, link: int | None = None, pad: int = 8):
    """Power spectrum of the angles of one trajectory.

    The mean is removed, a Hann window applied and the signal zero-padded to
    ``pad`` times its length (a finer frequency grid for locating peaks; it
    adds no resolution).

    Parameters
    ----------
    traj : Trajectory
        A single trajectory (angles of shape ``(N+1, n)``).
    link : int, optional
        One link's angle (0-based); by default the power of all angles is summed.
    pad : int
        Zero-padding factor, ``>= 1``.

    Returns
    -------
    omega : ndarray, shape (M,)
        Angular frequencies [rad/s].
    power : ndarray, shape (M,)
        Power, normalised to a maximum of 1.
    """
    if traj.theta.ndim != 2:
        raise ValueError(
            "`traj` must be a single trajectory (angles of shape (N+1, n)), "
            f"got angles of shape {traj.theta.shape}"
        )
    pad = check.integer_at_least("pad", pad, 1)
    if link is not None:
        link = check.index_below("link", link, traj.theta.shape[-1])
    angles = traj.theta if link is None else traj.theta[:, [link]]
    if len(traj.t) < 16:
        raise ValueError(f"`traj` is too short for a spectrum ({len(traj.t)} samples)")
    spacing = traj.t[1] - traj.t[0]
    signal = (angles - angles.mean(axis=0)) * np.hanning(len(traj.t))[:, None]
    size = pad * len(traj.t)
    power = np.sum(np.abs(np.fft.rfft(signal, n=size, axis=0)) ** 2, axis=1)
    omega = 2 * np.pi * np.fft.rfftfreq(size, d=spacing)
    return omega, power / power.max()


def dominant_frequencies(traj: Trajectory, count: int = 2, link: int | None = None) -> np.ndarray:
    """Angular frequencies [rad/s] of the ``count`` strongest peaks of :func:`spectrum`.

    Each peak is refined by a parabola through the logarithm of the power at
    the highest bin and its two neighbours. The accuracy is limited by the
    length ``T`` of the run (peaks are about ``4 pi / T`` wide with the Hann
    window), not by the step.

    Returns
    -------
    ndarray, shape (count,)
        Ascending.
    """
    count = check.integer_at_least("count", count, 1)
    omega, power = spectrum(traj, link=link)
    inner = np.arange(1, len(power) - 1)
    peaks = inner[(power[inner] > power[inner - 1]) & (power[inner] >= power[inner + 1])]
    if len(peaks) < count:
        raise ValueError(f"the spectrum has {len(peaks)} peak(s), fewer than `count` = {count}")
    strongest = peaks[np.argsort(power[peaks])[::-1][:count]]
    logp = np.log(power)
    left, mid, right = logp[strongest - 1], logp[strongest], logp[strongest + 1]
    shift = 0.5 * (left - right) / (left - 2 * mid + right)
    return np.sort(omega[strongest] + shift * (omega[1] - omega[0]))
