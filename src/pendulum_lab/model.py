"""Numeric pendulum models: the symbolic equations with their parameters bound.

Every numeric function here is lambdified from :mod:`pendulum_lab.mechanics`
once per number of links (with ``cse=True`` and the parameters as arguments),
so models that differ only in masses, lengths or ``g`` share the compiled code
and building one is cheap. All functions accept a batch of states: arrays of
shape ``(..., n)``, so one code path serves one trajectory and an ensemble.
"""

from __future__ import annotations

import functools

import numpy as np
import sympy as sp

from . import _validation as check
from .mechanics import Chain, derive_chain

__all__ = ["PendulumModel", "double_pendulum", "n_pendulum", "simple_pendulum"]


def _lambdify(args, exprs, shape):
    """Lambdify a list of expressions into one function returning shape ``(..., *shape)``.

    Entries that are constant (no state symbol in them) come back from
    lambdify as Python floats; broadcasting them against the state keeps
    every output the same batch shape.
    """
    fn = sp.lambdify(args, list(exprs), modules="numpy", cse=True)

    def evaluate(*values):
        parts = np.broadcast_arrays(*fn(*values), values[0])[:-1]
        return np.stack(parts, axis=-1).reshape(parts[0].shape + shape)

    evaluate.__doc__ = f"Arguments: {', '.join(map(str, args))}."
    return evaluate


class _CompiledChain:
    """The lambdified functions of one :class:`~pendulum_lab.mechanics.Chain`."""

    def __init__(self, chain: Chain):
        n, q, w = chain.n, list(chain.q), list(chain.omega)
        state_args = (*q, *w, *chain.parameters)
        config_args = (*q, *chain.parameters)
        lag_dq = chain.dlagrangian_dq
        lag_dw = sp.Matrix([chain.lagrangian.diff(wi) for wi in w])
        self.mass_matrix = _lambdify(config_args, chain.mass_matrix, (n, n))
        self.forcing = _lambdify(state_args, chain.forcing, (n,))
        self.dlagrangian_dq = _lambdify(state_args, lag_dq, (n,))
        self.kinetic = _lambdify(state_args, [chain.kinetic], ())
        self.potential = _lambdify(config_args, [chain.potential], ())
        # Pieces of the Jacobian of Hamilton's equations, all written in (q, omega):
        # d2L/dq2, d2L/dq domega and d(M omega)/dq; no symbolic inverse of M needed.
        self.lag_qq = _lambdify(state_args, lag_dq.jacobian(q), (n, n))
        self.lag_qw = _lambdify(state_args, lag_dq.jacobian(w), (n, n))
        self.dmomenta_dq = _lambdify(state_args, lag_dw.jacobian(q), (n, n))
        self.separable = not (chain.mass_matrix.free_symbols & set(q))


@functools.cache
def _compiled(n: int) -> _CompiledChain:
    return _CompiledChain(derive_chain(n))


def solve_small(matrix: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Solve ``matrix @ x = rhs`` for a batch of small systems.

    ``matrix`` has shape ``(..., n, n)`` and ``rhs`` shape ``(..., n)``. For
    ``n <= 2`` the closed form is several times faster than
    ``numpy.linalg.solve`` on tiny matrices; beyond that LAPACK does the work.
    """
    n = matrix.shape[-1]
    if n == 1:
        return rhs / matrix[..., 0, :]
    if n == 2:
        a, b = matrix[..., 0, 0], matrix[..., 0, 1]
        c, d = matrix[..., 1, 0], matrix[..., 1, 1]
        det = a * d - b * c
        x0 = (d * rhs[..., 0] - b * rhs[..., 1]) / det
        x1 = (a * rhs[..., 1] - c * rhs[..., 0]) / det
        return np.stack((x0, x1), axis=-1)
    return np.linalg.solve(matrix, rhs[..., None])[..., 0]


class PendulumModel:
    """A planar chain of ``n`` pendulums with numeric masses, lengths and ``g``.

    Build one with :func:`simple_pendulum`, :func:`double_pendulum` or
    :func:`n_pendulum`. Angles are absolute, measured from the downward
    vertical; ``theta``, ``omega`` (angular velocities) and ``p`` (canonical
    momenta) are arrays of shape ``(n,)`` or ``(..., n)``.

    Attributes
    ----------
    n : int
        Number of links.
    masses, lengths : tuple of float
    g : float
    chain : pendulum_lab.mechanics.Chain
        The symbolic equations (parameters symbolic).
    """

    def __init__(self, n: int, masses, lengths, g: float):
        self.n = check.integer_at_least("n", n, 1)
        self.masses = check.positive_vector("masses", masses, self.n)
        self.lengths = check.positive_vector("lengths", lengths, self.n)
        self.g = check.real_number("g", g)
        self.chain = derive_chain(self.n)
        self._fn = _compiled(self.n)
        self._params = (*self.masses, *self.lengths, self.g)

    # ---- symbolic views (parameters symbolic) -----------------------------
    @property
    def lagrangian(self) -> sp.Expr:
        return self.chain.lagrangian

    @property
    def hamiltonian(self) -> sp.Expr:
        """``H(q, p)``; built on first access (it needs ``M^-1``)."""
        return self.chain.hamiltonian

    @property
    def mass_matrix(self) -> sp.Matrix:
        return self.chain.mass_matrix

    @property
    def forcing(self) -> sp.Matrix:
        return self.chain.forcing

    @property
    def parameter_values(self) -> dict:
        """``{symbol: value}`` for substituting this model's numbers into the symbolic forms."""
        return dict(zip(self.chain.parameters, self._params))

    @property
    def separable(self) -> bool:
        """True when ``H = T(p) + V(q)`` (constant mass matrix: the simple pendulum)."""
        return self._fn.separable

    # ---- numeric functions -------------------------------------------------
    def _state(self, theta, other):
        return (*np.moveaxis(np.asarray(theta, float), -1, 0),
                *np.moveaxis(np.asarray(other, float), -1, 0), *self._params)

    def _config(self, theta):
        return (*np.moveaxis(np.asarray(theta, float), -1, 0), *self._params)

    def mass_matrix_at(self, theta) -> np.ndarray:
        """``M(theta)``, shape ``(..., n, n)``."""
        return self._fn.mass_matrix(*self._config(theta))

    def accelerations(self, theta, omega) -> np.ndarray:
        """``omega' = M(theta)^-1 F(theta, omega)``, shape ``(..., n)``."""
        return solve_small(self.mass_matrix_at(theta), self._fn.forcing(*self._state(theta, omega)))

    def momenta(self, theta, omega) -> np.ndarray:
        """``p = M(theta) omega``."""
        return np.einsum("...ij,...j->...i", self.mass_matrix_at(theta), omega)

    def velocities(self, theta, p) -> np.ndarray:
        """``omega = M(theta)^-1 p`` (this is ``dH/dp``)."""
        return solve_small(self.mass_matrix_at(theta), np.asarray(p, float))

    def kinetic_energy(self, theta, omega) -> np.ndarray:
        return self._fn.kinetic(*self._state(theta, omega))

    def potential_energy(self, theta) -> np.ndarray:
        """Potential energy, zero at the pivot's height."""
        return self._fn.potential(*self._config(theta))

    def energy(self, theta, omega) -> np.ndarray:
        return self.kinetic_energy(theta, omega) + self.potential_energy(theta)

    # Hamilton's equations in canonical variables. dH/dq at fixed p equals
    # -dL/dq at omega = M^-1 p (a property of the Legendre transform), which
    # avoids differentiating a symbolic inverse.
    def dH_dp(self, theta, p) -> np.ndarray:
        return self.velocities(theta, p)

    def dH_dq(self, theta, p) -> np.ndarray:
        return -self._fn.dlagrangian_dq(*self._state(theta, self.velocities(theta, p)))

    def hamiltonian_value(self, theta, p) -> np.ndarray:
        """``H(theta, p)`` evaluated numerically."""
        return self.energy(theta, self.velocities(theta, p))

    def jacobian(self, theta, p) -> np.ndarray:
        """Jacobian of ``(dH/dp, -dH/dq)`` with respect to ``(theta, p)``, shape ``(..., 2n, 2n)``.

        With ``omega = M^-1 p``: ``d omega/dp = M^-1``,
        ``d omega/dq = -M^-1 d(M omega)/dq``, and ``-dH/dq = dL/dq(q, omega)``
        differentiates by the chain rule.
        """
        theta = np.asarray(theta, float)
        mass = self.mass_matrix_at(theta)
        omega = solve_small(mass, np.asarray(p, float))
        args = self._state(theta, omega)
        inv_mass = np.linalg.inv(mass)
        dw_dq = -inv_mass @ self._fn.dmomenta_dq(*args)
        lag_qw = self._fn.lag_qw(*args)
        top = np.concatenate([dw_dq, inv_mass], axis=-1)
        bottom = np.concatenate([self._fn.lag_qq(*args) + lag_qw @ dw_dq, lag_qw @ inv_mass], -1)
        return np.concatenate([top, bottom], axis=-2)

    def positions(self, theta) -> tuple[np.ndarray, np.ndarray]:
        """Cartesian bob positions ``(x, y)``, each shape ``(..., n)``, pivot at the origin."""
        theta = np.asarray(theta, float)
        lengths = np.asarray(self.lengths)
        return (np.cumsum(lengths * np.sin(theta), axis=-1),
                -np.cumsum(lengths * np.cos(theta), axis=-1))

    def __repr__(self) -> str:
        return (f"PendulumModel(n={self.n}, masses={self.masses}, lengths={self.lengths}, "
                f"g={self.g})")


def simple_pendulum(mass: float = 1.0, length: float = 1.0, g: float = 9.81) -> PendulumModel:
    """A simple pendulum: one point mass on a massless rod.

    Examples
    --------
    >>> sp_ = simple_pendulum(length=2.0)
    >>> float(sp_.accelerations([np.pi / 2], [0.0])[0])
    -4.905
    """
    return PendulumModel(1, (check.positive_number("mass", mass),),
                         (check.positive_number("length", length),), g)


def double_pendulum(m1: float = 1.0, m2: float = 1.0, l1: float = 1.0, l2: float = 1.0,
                    g: float = 9.81) -> PendulumModel:
    """A double pendulum with absolute angles ``theta_1``, ``theta_2`` from the vertical."""
    masses = (check.positive_number("m1", m1), check.positive_number("m2", m2))
    lengths = (check.positive_number("l1", l1), check.positive_number("l2", l2))
    return PendulumModel(2, masses, lengths, g)


def n_pendulum(n: int, masses=None, lengths=None, g: float = 9.81) -> PendulumModel:
    """A chain of ``n`` pendulums; masses and lengths default to 1."""
    n = check.integer_at_least("n", n, 1)
    return PendulumModel(n, (1.0,) * n if masses is None else masses,
                         (1.0,) * n if lengths is None else lengths, g)
