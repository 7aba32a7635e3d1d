"""The numeric functions of a chain: its SymPy expressions lambdified, or its closed form looped.

:func:`compiled_chain` gives, once per number of links (conservative or forced), an object
whose methods evaluate the mass matrix, the forces, the energies and the pieces of the
Jacobian for a batch of states of shape ``(..., n)``, with the parameters as arguments: models
that differ only in their numbers share it. Short chains are lambdified here (``cse=True``);
long ones use :class:`~pendulum_lab.codegen.long_chains.LoopedChain`, which has the same methods.
"""

from __future__ import annotations

import functools

import numpy as np
import sympy as sp

from ..codegen.kernels import UNROLLED_MAX_LINKS
from ..symbolic.mechanics import Chain, derive_chain

__all__ = ["CompiledChain", "CompiledSystem", "compiled_chain", "compiled_system", "solve_small"]


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


def _state(theta, other, params) -> tuple:
    """Arguments of a lambdified state function: each angle, each velocity, each parameter."""
    return (*np.moveaxis(np.asarray(theta, float), -1, 0),
            *np.moveaxis(np.asarray(other, float), -1, 0), *params)


def _config(theta, params) -> tuple:
    return (*np.moveaxis(np.asarray(theta, float), -1, 0), *params)


class CompiledChain:
    """The lambdified functions of one :class:`~pendulum_lab.symbolic.mechanics.Chain` (a short
    one).

    Each method takes states of shape ``(..., n)``, ``params`` in the order of
    ``Chain.parameters`` and the time ``t``, as :class:`CompiledSystem`'s do, so that one set of
    model methods serves chains and systems; only the drive uses ``t`` (in ``forcing``,
    ``accelerations``, ``generalized_forces``), the other methods ignore it.
    :class:`~pendulum_lab.codegen.long_chains.LoopedChain` has the same methods for long chains.
    """

    def __init__(self, chain: Chain):
        n, q, w = chain.n, list(chain.q), list(chain.omega)
        state_args = (*q, *w, *chain.parameters)
        config_args = (*q, *chain.parameters)
        lag_dq = chain.dlagrangian_dq
        lag_dw = sp.Matrix([chain.lagrangian.diff(wi) for wi in w])
        self._mass_matrix = _lambdify(config_args, chain.mass_matrix, (n, n))
        # The time comes last; the conservative forcing does not use it.
        self._forcing = _lambdify((*state_args, chain.t), chain.forcing, (n,))
        self._generalized_forces = _lambdify((*state_args, chain.t), chain.generalized_forces,
                                             (n,))
        self._damping_matrix = _lambdify(chain.parameters, chain.damping_matrix, (n, n))
        self._dlagrangian_dq = _lambdify(state_args, lag_dq, (n,))
        self._kinetic = _lambdify(state_args, [chain.kinetic], ())
        self._potential = _lambdify(config_args, [chain.potential], ())
        # Pieces of the Jacobian of Hamilton's equations, all written in (q, omega):
        # d2L/dq2, d2L/dq domega and d(M omega)/dq; no symbolic inverse of M needed.
        self._lag_qq = _lambdify(state_args, lag_dq.jacobian(q), (n, n))
        self._lag_qw = _lambdify(state_args, lag_dq.jacobian(w), (n, n))
        self._dmomenta_dq = _lambdify(state_args, lag_dw.jacobian(q), (n, n))
        self.separable = not (chain.mass_matrix.free_symbols & set(q))

    def mass_matrix(self, theta, params, t):
        return self._mass_matrix(*_config(theta, params))

    def velocities(self, theta, p, params, t):
        return solve_small(self.mass_matrix(theta, params, t), np.asarray(p, float))

    def momenta(self, theta, omega, params, t):
        return np.einsum("...ij,...j->...i", self.mass_matrix(theta, params, t), omega)

    def dlagrangian_dq(self, theta, omega, params, t):
        return self._dlagrangian_dq(*_state(theta, omega, params))

    def forcing(self, theta, omega, params, t):
        return self._forcing(*_state(theta, omega, params), t)

    def accelerations(self, theta, omega, params, t):
        return solve_small(self.mass_matrix(theta, params, t),
                           self.forcing(theta, omega, params, t))

    def generalized_forces(self, theta, omega, params, t):
        return self._generalized_forces(*_state(theta, omega, params), t)

    def kinetic(self, theta, omega, params, t):
        return self._kinetic(*_state(theta, omega, params))

    def potential(self, theta, params, t):
        return self._potential(*_config(theta, params))

    def hamiltonian(self, theta, omega, params, t):
        """``H = T + V`` at the velocities ``omega``."""
        return self.kinetic(theta, omega, params, t) + self.potential(theta, params, t)

    def damping_matrix(self, params):
        return self._damping_matrix(*params)

    def lag_qq(self, theta, omega, params, t):
        return self._lag_qq(*_state(theta, omega, params))

    def lag_qw(self, theta, omega, params, t):
        return self._lag_qw(*_state(theta, omega, params))

    def dmomenta_dq(self, theta, omega, params, t):
        return self._dmomenta_dq(*_state(theta, omega, params))


@functools.cache
def compiled_chain(n: int, forced: bool):
    """The numeric functions of ``n`` links: lambdified for short chains, looped for long ones."""
    if n > UNROLLED_MAX_LINKS:
        from ..codegen.long_chains import LoopedChain  # compiles (once per machine) on first use

        return LoopedChain(n, forced)
    return CompiledChain(derive_chain(n, forced))


def solve_small(matrix: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Solve ``matrix @ x = rhs`` for a batch of small systems.

    ``matrix`` has shape ``(..., n, n)`` and ``rhs`` shape ``(..., n)``. For
    ``n <= 2`` the closed form, faster than ``numpy.linalg.solve`` on tiny
    matrices; beyond that LAPACK does the work.
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


class CompiledSystem:
    """The lambdified functions of a :class:`~pendulum_lab.symbolic.systems.MechanicalSystem`.

    The methods of :class:`CompiledChain` (the time ``t`` last: a moving pivot makes the mass
    matrix, the momenta and the energies depend on it), plus ``momentum_offset`` (``b`` of
    ``p = M omega + b``), ``lagrangian_rest`` (``L`` at rest), the Jacobian's pieces ``rate_q``
    and ``rate_w`` (the forces included) and the points' ``positions``. Same helpers as a
    chain's (``_lambdify``, ``solve_small``).
    """

    def __init__(self, system):
        n, q, w, t = system.n, list(system.q), list(system.omega), system.t
        state_args = (*q, *w, *system.parameters, t)
        config_args = (*q, *system.parameters, t)
        forces = system.generalized_forces
        dl_dq = system.dlagrangian_dq
        dl_dw = sp.Matrix([system.lagrangian.diff(wi) for wi in w])
        rest = system.lagrangian.xreplace({wi: 0 for wi in w})
        self._mass_matrix = _lambdify(config_args, system.mass_matrix, (n, n))
        self._offset = _lambdify(config_args, system.momentum_offset, (n,))
        self._forcing = _lambdify(state_args, system.forcing, (n,))
        self._generalized_forces = _lambdify(state_args, forces, (n,))
        self._dlagrangian_dq = _lambdify(state_args, dl_dq, (n,))
        self._kinetic = _lambdify(state_args, [system.kinetic], ())
        self._potential = _lambdify(config_args, [system.potential], ())
        self._rest = _lambdify(config_args, [rest], ())
        # Jacobian pieces of Hamilton's equations in (q, omega), the forces Q included.
        self._rate_q = _lambdify(state_args, (dl_dq + forces).jacobian(q), (n, n))
        self._rate_w = _lambdify(state_args, (dl_dq + forces).jacobian(w), (n, n))
        self._dmomenta_dq = _lambdify(state_args, dl_dw.jacobian(q), (n, n))
        coordinates = [c for point in system.points for c in point]
        self.points = len(system.points)
        if coordinates:
            self._positions = _lambdify(config_args, coordinates,
                                        (self.points, system.dimensions))
        self.has_offset = any(b != 0 for b in system.momentum_offset)

    def mass_matrix(self, q, params, t):
        return self._mass_matrix(*_config(q, (*params, t)))

    def momentum_offset(self, q, params, t):
        return self._offset(*_config(q, (*params, t)))

    def velocities(self, q, p, params, t):
        p = np.asarray(p, float)
        if self.has_offset:
            p = p - self.momentum_offset(q, params, t)
        return solve_small(self.mass_matrix(q, params, t), p)

    def momenta(self, q, omega, params, t):
        p = np.einsum("...ij,...j->...i", self.mass_matrix(q, params, t), omega)
        return p + self.momentum_offset(q, params, t) if self.has_offset else p

    def dlagrangian_dq(self, q, omega, params, t):
        return self._dlagrangian_dq(*_state(q, omega, (*params, t)))

    def forcing(self, q, omega, params, t):
        return self._forcing(*_state(q, omega, (*params, t)))

    def accelerations(self, q, omega, params, t):
        return solve_small(self.mass_matrix(q, params, t), self.forcing(q, omega, params, t))

    def generalized_forces(self, q, omega, params, t):
        return self._generalized_forces(*_state(q, omega, (*params, t)))

    def kinetic(self, q, omega, params, t):
        return self._kinetic(*_state(q, omega, (*params, t)))

    def potential(self, q, params, t):
        return self._potential(*_config(q, (*params, t)))

    def lagrangian_rest(self, q, params, t):
        return self._rest(*_config(q, (*params, t)))

    def hamiltonian(self, q, omega, params, t):
        """``H = 1/2 omega^T M omega - L(q, 0, t)`` at the velocities ``omega``."""
        mass = self.mass_matrix(q, params, t)
        quadratic = 0.5 * np.einsum("...i,...ij,...j->...", omega, mass, omega)
        return quadratic - self.lagrangian_rest(q, params, t)

    def rate_q(self, q, omega, params, t):
        return self._rate_q(*_state(q, omega, (*params, t)))

    def rate_w(self, q, omega, params, t):
        return self._rate_w(*_state(q, omega, (*params, t)))

    def dmomenta_dq(self, q, omega, params, t):
        return self._dmomenta_dq(*_state(q, omega, (*params, t)))

    def positions(self, q, params, t):
        return self._positions(*_config(q, (*params, t)))


@functools.cache
def compiled_system(system) -> CompiledSystem:
    """The numeric functions of ``system``, made once per system."""
    return CompiledSystem(system)
