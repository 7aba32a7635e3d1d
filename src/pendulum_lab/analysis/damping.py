"""How integrators treat damping: contraction of areas and the decay of energy.

Damping shrinks phase-space areas: for the damped simple pendulum the flow
multiplies every area by ``exp(-gamma t)``, ``gamma = damping / (m l^2)``
(the trace of its Jacobian is ``-gamma`` everywhere). A conformal symplectic
method (McLachlan and Perlmutter) does the same to every area at any step,
and near the hanging equilibrium, where the motion is linear, its decay rate
is exact as long as the step keeps the motion oscillatory. For large swings
its decay is only as accurate as its order. :func:`linear_decay` measures the
one-step map at the equilibrium; :func:`energy_decay` the decay rate of the
energy along runs (between turning points, :func:`decay_rate`), against a
reference.

References
----------
R. I. McLachlan, M. Perlmutter, "Conformal Hamiltonian systems", J. Geom.
Phys. 39 (2001) 276-300.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import validation as check
from ..driver.events import find_crossings, hermite
from ..driver.simulate import Trajectory, simulate
from ..integrators import get_method
from ..model import require_model
from ..model.pendulum import PendulumModel
from ..plot_dispatch import plot_with
from .linearization import rest_coordinates
from .structure import step_jacobian

__all__ = [
    "EnergyDecay",
    "LinearDecay",
    "decay_rate",
    "energy_decay",
    "linear_decay",
    "turning_points",
]


def _unforced(model: PendulumModel) -> PendulumModel:
    require_model(model)
    if not model.is_autonomous:
        raise ValueError("`model` must have no drive (drive_amplitude = 0): the decay of energy "
                         "is measured on the damped, unforced pendulum")
    return model


@dataclass(frozen=True)
class LinearDecay:
    """One step of a method at the hanging equilibrium, against the exact flow.

    Attributes
    ----------
    method : str
    dt : ndarray, shape (D,)
    determinant : ndarray, shape (D,)
        ``det`` of the one-step Jacobian: the factor by which the step
        multiplies areas (volumes).
    exact_determinant : ndarray, shape (D,)
        The flow's factor over one step, ``exp(dt tr A)``.
    rate : ndarray, shape (D,)
        ``-log(rho) / dt`` with ``rho`` the spectral radius of the step's
        Jacobian: the rate at which small swings decay [1/s] (negative: they grow).
    exact_rate : float
        The flow's: ``-max Re(eig A)`` [1/s].
    oscillatory : ndarray of bool, shape (D,)
        The step's eigenvalues are complex: it still oscillates, like the
        underdamped pendulum.
    """

    method: str
    dt: np.ndarray
    determinant: np.ndarray
    exact_determinant: np.ndarray
    rate: np.ndarray
    exact_rate: float
    oscillatory: np.ndarray


def linear_decay(model: PendulumModel, method, dts) -> LinearDecay:
    """Area factor and decay rate of one step of ``method`` at the hanging equilibrium.

    The Jacobian of a step at the equilibrium is the step of the linearised
    equations (Runge-Kutta and splitting methods commute with linearisation),
    so this is the method applied to the linear damped oscillator.

    Parameters
    ----------
    model : PendulumModel
        Without a drive.
    method : str or Method
    dts : array_like, shape (D,)
        Step sizes [s].

    Returns
    -------
    LinearDecay

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> damped = pl.driven_pendulum(damping=0.5, drive_amplitude=0.0)
    >>> decay = linear_decay(damped, "conformal_leapfrog", [0.5, 1.0])
    >>> round(decay.exact_rate, 9), decay.rate.round(9).tolist()  # gamma / 2 at either step
    (0.25, [0.25, 0.25])
    """
    model = _unforced(model)
    name = get_method(method).name
    dts = check.real_sequence("dts", dts)
    if np.any(dts <= 0):
        raise ValueError("`dts` must be positive")
    rest = rest_coordinates(model)
    jacobians = [step_jacobian(model, rest, np.zeros(model.n), dt=float(dt), method=name)
                 for dt in dts]
    field = model.jacobian(rest, np.zeros(model.n))
    eigenvalues = [np.linalg.eigvals(j) for j in jacobians]
    return LinearDecay(
        name,
        dts,
        np.array([np.linalg.det(j) for j in jacobians]),
        np.exp(dts * np.trace(field)),
        np.array([-np.log(np.max(np.abs(mu))) / dt for mu, dt in zip(eigenvalues, dts)]),
        float(-np.max(np.linalg.eigvals(field).real)),
        np.array([bool(np.any(mu.imag != 0)) for mu in eigenvalues]),
    )


def turning_points(model: PendulumModel, traj: Trajectory) -> tuple[np.ndarray, np.ndarray]:
    """Times and energies above rest of the swing's highest points (``omega`` from + to -).

    Located inside the steps on the cubic Hermite interpolant of ``omega``
    (its slopes are the accelerations) and of ``theta`` (slopes ``omega``);
    at a turning point ``omega = 0``, so the energy above rest is
    ``V(theta) - V(0)``. For one link.

    Returns
    -------
    t, energy : ndarray, shape (K,)
    """
    omega, theta, dt = traj.omega[:, 0], traj.theta[:, 0], traj.dt
    acceleration = model.accelerations(traj.theta, traj.omega)[:, 0]
    crossings = find_crossings(omega, direction=-1)
    k = crossings.step
    s = crossings.fraction(dt * acceleration[k], dt * acceleration[k + 1])
    top = hermite(s, theta[k], theta[k + 1], dt * omega[k], dt * omega[k + 1])
    rest = model.potential_energy(np.zeros(1))
    return traj.t[k] + s * dt, model.potential_energy(top[:, None]) - rest


def decay_rate(model: PendulumModel, traj: Trajectory) -> float:
    """Mean decay rate of the energy between the first and the last turning point [1/s].

    ``log(E*_first / E*_last) / (t_last - t_first)`` with ``E*`` the energy
    above rest at the :func:`turning_points`: for the linear damped
    oscillator exactly ``gamma = damping / (m l^2)``, whatever the phase.
    """
    t, energy = turning_points(model, traj)
    if len(t) < 2:
        raise ValueError("the run must pass at least two turning points; make `t_end` longer")
    return float(np.log(energy[0] / energy[-1]) / (t[-1] - t[0]))


@dataclass(frozen=True)
class EnergyDecay:
    """The decay of energy along runs of several methods and steps, against a reference.

    Attributes
    ----------
    methods : tuple of str
    dt : ndarray, shape (D,)
    rate : ndarray, shape (M, D)
        :func:`decay_rate` of each method at each step [1/s].
    reference_rate : float
        The same for the reference run.
    trajectories : dict
        ``{method: [Trajectory per step]}``.
    reference : Trajectory
    rest_energy : float
        The energy at rest, hanging [J].
    model : PendulumModel
    """

    methods: tuple
    dt: np.ndarray
    rate: np.ndarray
    reference_rate: float
    trajectories: dict
    reference: Trajectory
    rest_energy: float
    model: PendulumModel

    @property
    def error(self) -> np.ndarray:
        """``|rate - reference_rate|``, shape ``(M, D)``."""
        return np.abs(self.rate - self.reference_rate)

    @property
    def orders(self) -> np.ndarray:
        """Slope of ``log(error)`` against ``log(dt)`` for each method, shape ``(M,)``."""
        return np.array([np.polyfit(np.log(self.dt), np.log(e), 1)[0] for e in self.error])

    @property
    def local_orders(self) -> np.ndarray:
        """``log(e_i / e_{i+1}) / log(dt_i / dt_{i+1})`` between neighbouring steps, ``(M, D-1)``.

        Where they settle shows the asymptotic order; the first ones may be
        pre-asymptotic.
        """
        return np.log(self.error[:, :-1] / self.error[:, 1:]) / np.log(self.dt[:-1] / self.dt[1:])

    def plot(self, dt: float | None = None, ax=None):
        """Energy at each turning point over the reference's, at step ``dt`` (the largest by
        default); returns the Figure."""
        return plot_with("plot_energy_decay", self, dt=dt, ax=ax)


def energy_decay(
    model: PendulumModel,
    theta0,
    omega0=None,
    *,
    t_end: float,
    dts,
    methods=("rk4", "conformal_leapfrog"),
    reference_method="glrk8",
    reference_dt: float | None = None,
) -> EnergyDecay:
    """The decay rate of the energy (:func:`decay_rate`) by each method and step.

    Parameters
    ----------
    model : PendulumModel
        One link, damped, without a drive.
    theta0, omega0 : array_like, shape (1,)
    t_end : float
        Length of each run [s].
    dts : array_like, shape (D,)
    methods : sequence of str
    reference_method : str
    reference_dt : float, optional
        Step of the reference run; a tenth of the smallest of ``dts`` by
        default.

    Returns
    -------
    EnergyDecay

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> damped = pl.driven_pendulum(damping=0.5, drive_amplitude=0.0)
    >>> decay = energy_decay(damped, [2.5], [0.0], t_end=32.0, dts=[0.4, 0.2, 0.1],
    ...                      methods=["conformal_leapfrog"])
    >>> round(float(decay.orders[0]))  # second order at large swings
    2
    """
    model = _unforced(model)
    if model.n != 1:
        raise ValueError(f"`model` must have one link (the energy at a turning point is then "
                         f"potential only), got n = {model.n}")
    t_end = check.positive_number("t_end", t_end)
    dts = check.real_sequence("dts", dts)
    if np.any(dts <= 0):
        raise ValueError(f"`dts` must be positive, got {dts}")
    if reference_dt is None:
        reference_dt = float(np.min(dts)) / 10
    methods = tuple(get_method(m).name for m in methods)

    def run(method, dt):
        return simulate(model, theta0, omega0, t_end=t_end, dt=float(dt), method=method,
                        progress=False)

    reference = run(reference_method, reference_dt)
    trajectories = {m: [run(m, dt) for dt in dts] for m in methods}
    rates = np.array([[decay_rate(model, traj) for traj in trajectories[m]] for m in methods])
    return EnergyDecay(methods, dts, rates, decay_rate(model, reference), trajectories,
                       reference, float(model.potential_energy(np.zeros(1))), model)
