"""What a run gives back (:class:`Trajectory`) and how it treats huge initial angles.

:class:`AngleReduction` reduces initial angles by whole turns before a run and gives the
saved angles back as continued from those given.
"""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass

import numpy as np

from ..integrators import Method
from ..model import reduce_turns

__all__ = ["ANGLE_SPACING_WARNING", "REDUCE_ANGLES_BEYOND", "AngleReduction", "Trajectory"]

#: Initial angles larger than this [rad] are reduced by whole turns before a run
#: (:class:`AngleReduction`): there floats are 2e-12 rad apart, 4000 times coarser than near pi.
REDUCE_ANGLES_BEYOND = 2.0**13
#: Saved angles spaced more coarsely than this [rad] by the floats warn.
ANGLE_SPACING_WARNING = 1e-8


@dataclass(frozen=True)
class Trajectory:
    """A computed trajectory. Arrays have the time axis first.

    Attributes
    ----------
    t : ndarray, shape (N+1,)
        Times [s], from the run's start time ``t0`` (0 by default).
    theta, omega, p : ndarray, shape (N+1, ..., n)
        Angles, angular velocities and canonical momenta (``...`` is the
        ensemble shape of the initial state, empty for one trajectory).
    kinetic, potential : ndarray, shape (N+1, ...)
        ``T`` and ``V`` [J] (for a moving pivot, ``T`` in the fixed frame).
    energy : ndarray, shape (N+1, ...)
        The mechanical energy ``T + V`` [J]. Where the pivot moves (the Kapitza
        pendulum) this is not the Hamiltonian, and neither is conserved.
    hamiltonian : ndarray, shape (N+1, ...)
        ``H(q, p, t) = p q' - L`` [J], the function whose Hamilton equations the run
        integrates: ``dH/dt = dH/dt|_(q, p)`` along the motion (constant if nothing depends
        on ``t``, and without damping). The same array as ``energy`` where ``H = T + V``
        (``model.hamiltonian_is_energy``: every chain, a system whose points the time does
        not move); for a moving pivot ``H = T + V - b q' - 2 T_0``.
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
        False if some trajectory reached a non-finite state or energy, a system's
        coordinate too large for a step to move it, or a place where a system's mass matrix
        is not positive definite (it then stops there, with a ``RuntimeWarning`` saying
        why; in an ensemble its later entries are NaN).
    compile_time : float
        Seconds the run spent before stepping on compiling its kernels and its time loop, or
        loading them from the disk cache (:mod:`pendulum_lab.codegen.compile_status`); 0 when
        this process had them ready. Not part of ``wall_time``.
    compiled : bool
        True when some of that time was spent compiling (a kernel was in no disk cache);
        False when it was spent loading machine code from the disk cache only.
    model : PendulumModel or None
        The model the run integrated (the drawings refuse another system's), None for a
        trajectory made by hand.
    """

    t: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    p: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray
    energy: np.ndarray
    hamiltonian: np.ndarray
    method: Method
    dt: float
    mean_iterations: float
    evaluations: int
    wall_time: float
    completed: bool
    compile_time: float = 0.0
    compiled: bool = False
    model: object = dataclasses.field(default=None, repr=False, compare=False)

    @property
    def energy_error(self) -> np.ndarray:
        """``E(t) - E(0)`` of the mechanical energy ``E = T + V`` (:attr:`energy`)."""
        return self.energy - self.energy[0]

    @property
    def relative_energy_error(self) -> np.ndarray:
        """``(E(t) - E(0)) / |E(0)|`` (absolute error where ``E(0) = 0``)."""
        scale = np.where(self.energy[0] == 0, 1.0, np.abs(self.energy[0]))
        return self.energy_error / scale


@dataclass(frozen=True)
class AngleReduction:
    """Initial angles reduced by whole turns, and the way back to the angles given.

    Every model of the package is 2 pi-periodic in each absolute angle: its Hamiltonian
    depends on them through ``cos theta_i`` (gravity) and ``cos(theta_i - theta_j)`` (the rods'
    coupling), the damping torques on the angular velocities, the drive on the time. So the run
    from ``theta0 + 2 pi k`` is the run from ``theta0`` with every angle shifted by ``2 pi k``,
    in canonical variables and in the velocity variables of ``*_velocity`` methods alike (a
    whole turn changes neither ``omega`` nor ``p = M(theta) omega``). What is not periodic in the
    angles is what a caller computes from them as numbers (an angle plotted against time, a
    crossing of ``theta = 0`` rather than of ``0 mod 2 pi``): hence the angles given back. The
    drive is periodic in ``t``, but that is no reason to reduce the time, whose saved values
    must stay the caller's: a huge ``t0`` is refused or warned about instead
    (:func:`~pendulum_lab.driver.arguments.check_clock`).

    Far from zero, floats are spaced too widely for the small changes of a step (1e15 rad: 0.125
    rad apart, and a run there made relative energy errors of 1e3). So angles beyond
    :data:`REDUCE_ANGLES_BEYOND` are reduced exactly (:func:`~pendulum_lab.model.reduce_turns`)
    and the run steps from there; the saved angles are given back as ``theta0 + (theta -
    reduced)``: they start at the ``theta0`` given and are continuous (never wrapped), and the
    energies, velocities and momenta are computed from the reduced angles, where they are
    accurate.

    Attributes
    ----------
    given, reduced : ndarray, shape (K, n)
        The initial angles as given (flattened) and reduced; equal where not reduced.
    mask : ndarray of bool, shape (K, n)
        The entries reduced.
    """

    given: np.ndarray
    reduced: np.ndarray
    mask: np.ndarray

    @classmethod
    def of(cls, theta: np.ndarray, stacklevel: int = 3) -> AngleReduction | None:
        """The reduction of the angles ``theta`` (shape ``(K, n)``), or None if none is needed.

        Warns where the angles given are so large that floats there are spaced more than
        :data:`ANGLE_SPACING_WARNING` apart: the saved angles are rounded to that spacing.
        """
        mask = np.abs(theta) > REDUCE_ANGLES_BEYOND
        if not mask.any():
            return None
        largest = float(np.max(np.abs(theta)))
        spacing = float(np.spacing(largest))
        if spacing > ANGLE_SPACING_WARNING:
            warnings.warn(
                f"`theta0` holds angles up to {largest:.3g} rad, where floats are {spacing:.3g}"
                " rad apart: the saved angles (theta0 plus the motion) are rounded to that. The "
                "run itself, and its energies, velocities and momenta, use the angles reduced "
                "by whole turns (the model is 2 pi-periodic in each angle); start from "
                "pendulum_lab.model.reduce_turns(theta0) to see the motion in the angles.",
                RuntimeWarning,
                stacklevel=stacklevel,
            )
        reduced = np.where(mask, reduce_turns(np.where(mask, theta, 0.0)), theta)
        return cls(theta.copy(), reduced, mask)

    def restore(self, theta: np.ndarray) -> np.ndarray:
        """Angles ``theta`` of the reduced run (shape ``(..., K, n)``) as continued from those
        given."""
        return np.where(self.mask, self.given + (theta - self.reduced), theta)

    def select(self, rows) -> AngleReduction:
        """The reduction of some members (rows) only."""
        return AngleReduction(self.given[rows], self.reduced[rows], self.mask[rows])

    def restored(self, traj: Trajectory, batch_shape: tuple) -> Trajectory:
        """``traj`` (of the reduced run, ensemble ``batch_shape``) with the angles restored."""
        n = traj.theta.shape[-1]
        flat = traj.theta.reshape(len(traj.t), -1, n)
        return dataclasses.replace(traj, theta=self.restore(flat).reshape(traj.theta.shape))
