"""The factories of chains: the simple, the driven and the double pendulum, a chain of n."""

from __future__ import annotations

import numpy as np  # noqa: F401 (the doctests use it)

from .parameters import link_count, model_number
from .pendulum import PendulumModel

__all__ = ["double_pendulum", "driven_pendulum", "n_pendulum", "simple_pendulum"]


def simple_pendulum(mass: float = 1.0, length: float = 1.0, g: float = 9.81) -> PendulumModel:
    """A simple pendulum: one point mass on a massless rod.

    Examples
    --------
    >>> sp_ = simple_pendulum(length=2.0)
    >>> float(sp_.accelerations([np.pi / 2], [0.0])[0])
    -4.905
    """
    return PendulumModel(1, (model_number("mass", mass),), (model_number("length", length),), g)


def driven_pendulum(damping: float = 0.5, drive_amplitude: float = 1.2,
                    drive_frequency: float = 2 / 3, mass: float = 1.0, length: float = 1.0,
                    g: float = 1.0) -> PendulumModel:
    """The damped, driven simple pendulum.

    ``m l^2 theta'' + damping theta' + m g l sin(theta) = drive_amplitude cos(drive_frequency t)``.
    With ``m = l = g = 1`` (the defaults) this is the dimensionless form of
    Baker and Gollub, with quality factor ``q = 1 / damping``; the defaults
    (``q = 2``, amplitude 1.2, frequency 2/3) lie in its chaotic range.
    ``damping = drive_amplitude = 0`` gives the conservative simple pendulum.

    Parameters
    ----------
    damping : float >= 0
        Viscous damping coefficient [N m s/rad].
    drive_amplitude : float
        Amplitude of the drive torque [N m].
    drive_frequency : float > 0
        Angular frequency of the drive [rad/s].
    mass, length : float > 0
    g : float

    References
    ----------
    G. L. Baker, J. P. Gollub, *Chaotic Dynamics: An Introduction*, 2nd ed.,
    Cambridge University Press 1996, ch. 3.

    Examples
    --------
    >>> model = driven_pendulum()
    >>> model.conformal_damping_rate, round(model.drive_period, 6)
    (0.5, 9.424778)
    >>> float(model.accelerations([0.0], [0.0], t=0.0)[0])  # the drive alone at t = 0
    1.2
    """
    return PendulumModel(1, (model_number("mass", mass),), (model_number("length", length),), g,
                         damping=damping, drive_amplitude=drive_amplitude,
                         drive_frequency=drive_frequency)


def double_pendulum(m1: float = 1.0, m2: float = 1.0, l1: float = 1.0, l2: float = 1.0,
                    g: float = 9.81, *, damping=0.0, drive_amplitude: float = 0.0,
                    drive_frequency: float | None = None) -> PendulumModel:
    """A double pendulum with absolute angles ``theta_1``, ``theta_2`` from the vertical.

    ``damping`` (one number for both joints, or one per joint),
    ``drive_amplitude`` and ``drive_frequency`` add joint damping and a drive
    torque at the pivot; see :class:`PendulumModel`.
    """
    masses = (model_number("m1", m1), model_number("m2", m2))
    lengths = (model_number("l1", l1), model_number("l2", l2))
    return PendulumModel(2, masses, lengths, g, damping=damping, drive_amplitude=drive_amplitude,
                         drive_frequency=drive_frequency)


def n_pendulum(n: int, masses=None, lengths=None, g: float = 9.81, *, damping=0.0,
               drive_amplitude: float = 0.0, drive_frequency: float | None = None
               ) -> PendulumModel:
    """A chain of ``n`` pendulums; masses and lengths default to 1.

    ``damping``, ``drive_amplitude`` and ``drive_frequency`` as for
    :class:`PendulumModel`.
    """
    n = link_count(n)  # before the default masses and lengths are made for it
    return PendulumModel(n, (1.0,) * n if masses is None else masses,
                         (1.0,) * n if lengths is None else lengths, g, damping=damping,
                         drive_amplitude=drive_amplitude, drive_frequency=drive_frequency)
