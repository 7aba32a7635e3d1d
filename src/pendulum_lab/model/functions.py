"""The numeric functions every model shares: energies, momenta, Hamilton's vector field and
its Jacobian, evaluated for a batch of states of shape ``(..., n)``.

:class:`ModelFunctions` checks the states and the time and hands them, with the model's
parameters, to the model's compiled functions (``model._fn``: a chain's lambdified or looped
functions, :mod:`pendulum_lab.model.numeric`).
"""

from __future__ import annotations

import numpy as np

from .numeric import solve_small

__all__ = ["ModelFunctions"]


class ModelFunctions:
    """The numeric methods of a model (the base of :class:`~pendulum_lab.PendulumModel`).

    A subclass has ``n`` (coordinates), ``_fn`` (its compiled functions), ``_params`` (their
    parameters), ``is_autonomous``, ``is_conservative`` and ``_described()`` (how error
    messages name the model, and why it needs the time).
    """

    def _time(self, t):
        """``t`` as floats; it may be left out only when the equations do not depend on it."""
        if t is None:
            if not self.is_autonomous:
                raise ValueError(f"`t` is required: {self._described()[1]}")
            return 0.0
        t = np.asarray(t, dtype=float)
        if not np.all(np.isfinite(t)):
            raise ValueError("`t` must be finite")
        return t

    def _states(self, name: str, value) -> np.ndarray:
        """``value`` as floats of shape ``(..., n)``, or an error naming ``name``."""
        try:
            array = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise TypeError(f"`{name}` must be an array of real numbers of shape (..., "
                            f"{self.n})") from None
        if array.ndim == 0 or array.shape[-1] != self.n:
            raise ValueError(f"`{name}` must have shape (..., {self.n}) for "
                             f"{self._described()[0]}, got shape {array.shape}")
        return array

    def _configuration_time(self, t):
        """The time the functions of the configuration take: the mass matrix, the momenta, the
        energies, ``dH/dq``. A chain's do not depend on it (its pivot is fixed), so ``t`` is
        accepted, not asked for and not used; a system whose points may move with the time
        checks it as :meth:`_time` does."""
        return 0.0

    def mass_matrix_at(self, theta, t=None) -> np.ndarray:
        """``M(theta)``, shape ``(..., n, n)`` (``M(q, t)`` where a system's points move)."""
        return self._fn.mass_matrix(self._states("theta", theta), self._params,
                                    self._configuration_time(t))

    def accelerations(self, theta, omega, t=None) -> np.ndarray:
        """``omega' = M(theta)^-1 (F(theta, omega) + Q(omega, t))``, shape ``(..., n)``.

        ``t`` (a float, or an array of the batch shape ``...``) is needed for a
        driven model only.
        """
        return self._fn.accelerations(self._states("theta", theta),
                                      self._states("omega", omega), self._params, self._time(t))

    def generalized_forces(self, theta, omega, t=None) -> np.ndarray:
        """``Q(omega, t)``: joint damping and drive torques, shape ``(..., n)``; 0 if unforced."""
        return self._fn.generalized_forces(self._states("theta", theta),
                                           self._states("omega", omega), self._params,
                                           self._time(t))

    def vector_field(self, theta, p, t=None) -> tuple[np.ndarray, np.ndarray]:
        """``(dtheta/dt, dp/dt) = (dH/dp, -dH/dq + Q)`` in canonical variables, each ``(..., n)``.

        The right-hand side every integrator integrates (the compiled kernels
        compute the same). ``t`` is needed for a driven model only.
        """
        theta, t = self._states("theta", theta), self._time(t)
        omega = self.velocities(theta, p, t)
        return omega, (self._fn.dlagrangian_dq(theta, omega, self._params, t)
                       + self._fn.generalized_forces(theta, omega, self._params, t))

    def momenta(self, theta, omega, t=None) -> np.ndarray:
        """``p = M(theta) omega``; ``M(q, t) omega + b(q, t)`` where a system's points move with
        the time (a chain's momenta do not depend on ``t``)."""
        return self._fn.momenta(self._states("theta", theta), self._states("omega", omega),
                                self._params, self._configuration_time(t))

    def velocities(self, theta, p, t=None) -> np.ndarray:
        """``omega = M(theta)^-1 p`` (this is ``dH/dp``); ``M(q, t)^-1 (p - b(q, t))`` where a
        system's points move with the time."""
        return self._fn.velocities(self._states("theta", theta), self._states("p", p),
                                   self._params, self._configuration_time(t))

    def kinetic_energy(self, theta, omega, t=None) -> np.ndarray:
        """Kinetic energy ``T`` (of a system's points in the fixed frame where they move with
        the time, as seen in the turning frame where they are written in one; a chain's does
        not depend on ``t``)."""
        return self._fn.kinetic(self._states("theta", theta), self._states("omega", omega),
                                self._params, self._configuration_time(t))

    def potential_energy(self, theta, t=None) -> np.ndarray:
        """Potential energy; a chain's is zero at the pivot's height."""
        return self._fn.potential(self._states("theta", theta), self._params,
                                  self._configuration_time(t))

    def energy(self, theta, omega, t=None) -> np.ndarray:
        return self.kinetic_energy(theta, omega, t) + self.potential_energy(theta, t)

    # Hamilton's equations in canonical variables. dH/dq at fixed p equals
    # -dL/dq at omega = M^-1 p (a property of the Legendre transform), which
    # avoids differentiating a symbolic inverse. H is the mechanical energy:
    # the forces Q of a forced model are not in it (see vector_field).
    def dH_dp(self, theta, p, t=None) -> np.ndarray:
        return self.velocities(theta, p, t)

    def dH_dq(self, theta, p, t=None) -> np.ndarray:
        theta, t = self._states("theta", theta), self._configuration_time(t)
        return -self._fn.dlagrangian_dq(theta, self.velocities(theta, p, t), self._params, t)

    def hamiltonian_value(self, theta, p, t=None) -> np.ndarray:
        """``H(theta, p)`` evaluated numerically: ``T + V`` for a chain; for a system
        ``1/2 omega^T M omega - L(q, 0, t)`` at ``omega = M^-1 (p - b)``, equal to ``T + V``
        unless its points move with the time (``hamiltonian_is_energy``)."""
        theta, t = self._states("theta", theta), self._configuration_time(t)
        return self._fn.hamiltonian(theta, self.velocities(theta, p, t), self._params, t)

    def jacobian(self, theta, p, t=None) -> np.ndarray:
        """Jacobian of :meth:`vector_field` with respect to ``(theta, p)``, shape ``(..., 2n, 2n)``.

        With ``omega = M^-1 p``: ``d omega/dp = M^-1``,
        ``d omega/dq = -M^-1 d(M omega)/dq``, and ``-dH/dq = dL/dq(q, omega)``
        differentiates by the chain rule. The damping force ``-C omega`` adds
        ``-C`` to ``d(dp/dt)/d omega``; the drive depends on ``t`` only.
        """
        self._time(t)  # a driven model's field depends on t (its Jacobian does not)
        theta = self._states("theta", theta)
        mass = self.mass_matrix_at(theta)
        omega = solve_small(mass, self._states("p", p))
        args = (theta, omega, self._params, 0.0)  # a chain's pieces do not depend on t
        inv_mass = np.linalg.inv(mass)
        dw_dq = -inv_mass @ self._fn.dmomenta_dq(*args)
        rate_w = self._fn.lag_qw(*args)  # d(dp/dt)/d omega
        if not self.is_conservative:
            rate_w = rate_w - self._fn.damping_matrix(self._params)
        top = np.concatenate([dw_dq, inv_mass], axis=-1)
        bottom = np.concatenate([self._fn.lag_qq(*args) + rate_w @ dw_dq, rate_w @ inv_mass], -1)
        return np.concatenate([top, bottom], axis=-2)
