"""Long chains: the closed form of a chain's equations, evaluated link by link.

For one or two links, :mod:`pendulum_lab.codegen.kernels` prints the SymPy expressions as
straight-line Numba kernels and :mod:`pendulum_lab.model.numeric` lambdifies them. The
expressions of ``n`` links hold ``O(n^2)`` terms, so that code, and the time to generate and
compile it, grows fast with ``n`` (measured: docs/design/long-chains.md). Chains of more than
``UNROLLED_MAX_LINKS`` (:mod:`pendulum_lab.codegen.kernels`) links are evaluated here instead,
from the closed form (:mod:`pendulum_lab.symbolic.mechanics`):
with the tail masses ``mu_i = m_i + ... + m_n``, ``s_i = sin(theta_i)``, ``c_i = cos(theta_i)``,

``M_ij = mu_max(i,j) l_i l_j cos(theta_i - theta_j)``,
``dL/dtheta_i = -omega_i l_i sum_j mu_max(i,j) l_j sin(theta_i - theta_j) omega_j
- g mu_i l_i s_i``,
``F_i = -l_i sum_j mu_max(i,j) l_j sin(theta_i - theta_j) omega_j^2 - g mu_i l_i s_i``.

Two facts make one evaluation of the vector field cost ``O(n)`` operations
and ``2n`` sines and cosines, where the expressions hold ``O(n^2)`` terms
and a dense solve costs ``O(n^3)``:

* ``cos(theta_i - theta_j) = c_i c_j + s_i s_j``,
  ``sin(theta_i - theta_j) = s_i c_j - c_i s_j``, and every sum
  ``sum_j mu_max(i,j) f_j = mu_i sum_(j<i) f_j + sum_(j>i) mu_j f_j`` is one
  running sum forwards and one backwards (:func:`link_sums`);
* ``M`` is semiseparable of rank two: for ``i >= j``, ``M_ij = y_i . x_j``
  with ``x_j = l_j (c_j, s_j)`` and ``y_i = mu_i l_i (c_i, s_i)``. Its
  Cholesky factor has the same form, ``L_ij = y_i . g_j`` for ``i >= j``,
  with 2-vectors ``g_j`` found in one pass, and the triangular solves are
  running sums too (:func:`solve_mass`). It is the factor a dense Cholesky
  factorisation computes [VBM]_; for a chain it does the work of the
  articulated-body recursion [F]_.

The two kernels :func:`hamilton` and :func:`acceleration` have the
signatures of :mod:`pendulum_lab.codegen.signatures` and serve every chain longer
than ``UNROLLED_MAX_LINKS``, conservative or forced: ``n`` is
``q.size``, and ``params`` is ``(m_1..m_n, l_1..l_n, g)``, followed for a
forced chain by ``(c_1..c_n, A, Omega)`` (``Chain.parameters``); its length
tells which. They are compiled once per machine, for every ``n``, and kept on
disk (:func:`~pendulum_lab.codegen.cache.cached_njit`). :class:`LoopedChain`
gives :class:`~pendulum_lab.PendulumModel` the same functions for batches of
states. This module is imported on first use of a long chain, so ``import
pendulum_lab`` does not compile it.

References
----------
.. [VBM] R. Vandebril, M. Van Barel, N. Mastronardi, *Matrix Computations and
   Semiseparable Matrices*, vol. 1, Johns Hopkins University Press 2008.
.. [F] R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008, ch. 7.
"""

from __future__ import annotations

import math

import numpy as np

from .cache import cached_njit
from .signatures import ACCELERATION, HAMILTON

__all__ = [
    "LoopedChain",
    "acceleration",
    "hamilton",
    "link_sums",
    "solve_mass",
]

# Rows of the workspace every kernel allocates once per call.
SIN, COS, TAIL, G0, G1, DIAG, SUM_C, SUM_S = range(8)
WORK_ROWS = 8


# --------------------------------------------------------------------------- pieces
@cached_njit
def chain_geometry(q, params, work):
    """Fill ``work[SIN]``, ``work[COS]`` and the tail masses ``work[TAIL]``."""
    total = 0.0
    for i in range(q.size - 1, -1, -1):
        total += params[i]
        work[TAIL, i] = total
        work[SIN, i] = math.sin(q[i])
        work[COS, i] = math.cos(q[i])


@cached_njit
def solve_mass(params, work, rhs, out):
    """Solve ``M(q) out = rhs`` in ``O(n)``; :func:`chain_geometry` must have filled ``work``.

    Cholesky ``M = L L^T`` with ``L_ij = y_i . g_j`` (``i >= j``): from
    ``M_ij = y_i . x_j`` follows ``P_j y_j = x_j`` with
    ``P_j = g_1 g_1^T + ... + g_j g_j^T``, so ``r_j = x_j - P_(j-1) y_j``,
    ``L_jj = sqrt(y_j . r_j)`` (the pivot) and ``g_j = r_j / L_jj``. The
    forward and back substitutions carry ``sum_k g_k z_k`` and
    ``sum_k y_k out_k`` as running 2-vectors. ``out`` may be ``rhs``.
    """
    n = rhs.size
    p00, p01, p11 = 0.0, 0.0, 0.0
    for j in range(n):
        length, tail = params[n + j], work[TAIL, j]
        x0, x1 = length * work[COS, j], length * work[SIN, j]
        y0, y1 = tail * x0, tail * x1
        r0 = x0 - (p00 * y0 + p01 * y1)
        r1 = x1 - (p01 * y0 + p11 * y1)
        pivot = math.sqrt(y0 * r0 + y1 * r1)
        g0, g1 = r0 / pivot, r1 / pivot
        work[G0, j], work[G1, j], work[DIAG, j] = g0, g1, pivot
        p00 += g0 * g0
        p01 += g0 * g1
        p11 += g1 * g1
    s0, s1 = 0.0, 0.0
    for i in range(n):
        scale = work[TAIL, i] * params[n + i]
        z = (rhs[i] - scale * (work[COS, i] * s0 + work[SIN, i] * s1)) / work[DIAG, i]
        s0 += work[G0, i] * z
        s1 += work[G1, i] * z
        out[i] = z
    s0, s1 = 0.0, 0.0
    for i in range(n - 1, -1, -1):
        x = (out[i] - (work[G0, i] * s0 + work[G1, i] * s1)) / work[DIAG, i]
        out[i] = x
        scale = work[TAIL, i] * params[n + i] * x
        s0 += scale * work[COS, i]
        s1 += scale * work[SIN, i]


@cached_njit
def link_sums(params, work, u):
    """``work[SUM_C]_i = sum_(j != i) mu_max(i,j) l_j c_j u_j``, and ``work[SUM_S]`` with ``s_j``.

    Each is a backward running sum ``sum_(j>i) mu_j l_j c_j u_j`` plus
    ``mu_i`` times a forward one ``sum_(j<i) l_j c_j u_j``. Then
    ``sum_j mu_max(i,j) l_j sin(theta_i - theta_j) u_j = s_i C_i - c_i S_i``
    and ``sum_j mu_max(i,j) l_j cos(theta_i - theta_j) u_j
    = c_i C_i + s_i S_i + mu_i l_i u_i``; leaving ``j = i`` out of the sums
    keeps the sine sum free of cancellation.
    """
    n = u.size
    back_c, back_s = 0.0, 0.0
    for i in range(n - 1, -1, -1):
        work[SUM_C, i], work[SUM_S, i] = back_c, back_s
        weight = work[TAIL, i] * params[n + i] * u[i]
        back_c += weight * work[COS, i]
        back_s += weight * work[SIN, i]
    front_c, front_s = 0.0, 0.0
    for i in range(n):
        tail = work[TAIL, i]
        work[SUM_C, i] += tail * front_c
        work[SUM_S, i] += tail * front_s
        weight = params[n + i] * u[i]
        front_c += weight * work[COS, i]
        front_s += weight * work[SIN, i]


@cached_njit
def conservative_rates(params, work, u, weights, out):
    """``out_i = -weights_i l_i sum_j mu_max(i,j) l_j sin(theta_i - theta_j) u_j - g mu_i l_i s_i``.

    With ``u = weights = omega`` this is ``dL/dtheta``; with ``u = omega^2``
    and unit weights the forcing ``F``.
    """
    n = u.size
    g = params[2 * n]
    link_sums(params, work, u)
    for i in range(n):
        sine_sum = work[SIN, i] * work[SUM_C, i] - work[COS, i] * work[SUM_S, i]
        length = params[n + i]
        out[i] = -weights[i] * length * sine_sum - g * work[TAIL, i] * length * work[SIN, i]


@cached_njit
def add_forces(t, v, params, out):
    """``out += Q(v, t)`` for a forced chain (``params`` of length ``3n + 3``); else nothing.

    ``Q_i = -c_i (v_i - v_(i-1)) + c_(i+1) (v_(i+1) - v_i)`` (joint damping,
    ``v_0 = 0`` at the pivot, no joint below the last link), plus
    ``A cos(Omega t)`` on the first link.
    """
    n = v.size
    if params.size != 3 * n + 3:
        return
    below = 0.0  # the torque of joint i + 1, which acts on link i reversed
    for i in range(n - 1, -1, -1):
        above = v[i - 1] if i > 0 else 0.0
        joint = params[2 * n + 1 + i] * (v[i] - above)
        out[i] += below - joint
        below = joint
    out[0] += params[3 * n + 1] * math.cos(params[3 * n + 2] * t)


# --------------------------------------------------------------------------- kernels
@cached_njit(HAMILTON)
def hamilton(t, q, p, params, dq, dp):
    """``dq = M(q)^-1 p``; ``dp = dL/dq (+ Q)`` at ``omega = dq``, for any ``n``."""
    work = np.empty((WORK_ROWS, q.size))
    chain_geometry(q, params, work)
    solve_mass(params, work, p, dq)
    conservative_rates(params, work, dq, dq, dp)
    add_forces(t, dq, params, dp)


@cached_njit(ACCELERATION)
def acceleration(t, q, v, params, out):
    """``out = M(q)^-1 (F(q, v) (+ Q(v, t)))``, for any ``n``."""
    work = np.empty((WORK_ROWS, q.size))
    chain_geometry(q, params, work)
    conservative_rates(params, work, v * v, np.ones(q.size), out)
    add_forces(t, v, params, out)
    solve_mass(params, work, out, out)


# --------------------------------------------------------------------------- batches
# Row by row over a batch of states (shape (K, n)), for the model's functions.
# `kind` picks the quantity; one compiled loop serves them all.
VELOCITIES, MOMENTA, RATES, FORCING, ACCELERATIONS, FORCES = range(6)


@cached_njit
def _rows(kind, theta, other, parameter_rows, t, out):
    """``parameter_rows``: shape (1, P), shared, or (K, P), one row per state."""
    n = theta.shape[1]
    work = np.empty((WORK_ROWS, n))
    ones = np.ones(n)
    shared = parameter_rows.shape[0] == 1
    for k in range(theta.shape[0]):
        q, u, row = theta[k], other[k], out[k]
        params = parameter_rows[0 if shared else k]
        if kind == ACCELERATIONS:
            acceleration(t[k], q, u, params, row)
            continue
        if kind == FORCES:
            row[:] = 0.0
            add_forces(t[k], u, params, row)
            continue
        chain_geometry(q, params, work)
        if kind == VELOCITIES:
            solve_mass(params, work, u, row)
        elif kind == MOMENTA:
            link_sums(params, work, u)
            for i in range(n):
                length = params[n + i]
                row[i] = length * (work[COS, i] * work[SUM_C, i] + work[SIN, i] * work[SUM_S, i]
                                   + work[TAIL, i] * length * u[i])
        elif kind == RATES:
            conservative_rates(params, work, u, u, row)
        else:  # FORCING
            conservative_rates(params, work, u * u, ones, row)
            add_forces(t[k], u, params, row)


class LoopedChain:
    """The numeric functions of a chain of ``n`` links, for :class:`~pendulum_lab.PendulumModel`.

    The same methods as the lambdified functions of a short chain
    (:class:`~pendulum_lab.model.numeric.CompiledChain`), each taking states of shape
    ``(..., n)``, ``params`` in the order of ``Chain.parameters`` and the time ``t`` (used by
    the drive only): the
    vector field, momenta, velocities and energies in ``O(n)`` per state (the
    loops above), the ``n x n`` matrices (``M`` and the second derivatives of
    ``L`` that :meth:`~pendulum_lab.PendulumModel.jacobian` needs) from their
    closed form in ``O(n^2)``.
    """

    def __init__(self, n: int, forced: bool):
        self.n, self.forced = n, forced
        self.separable = n == 1

    # ---- helpers -----------------------------------------------------------
    # ``params`` is a sequence of numbers, or (for a ModelFamily) of arrays that
    # broadcast against the states' batch shape: one model per member.
    @staticmethod
    def _parameter_array(params) -> np.ndarray:
        """``params`` as one array, shape ``(P,)`` or ``(..., P)`` for a family."""
        parts = [np.asarray(value, float) for value in params]
        shape = np.broadcast_shapes(*(part.shape for part in parts))
        return np.stack([np.broadcast_to(part, shape) for part in parts], axis=-1)

    def _batch(self, kind, theta, other, params, t=0.0):
        table = self._parameter_array(params)
        times = np.asarray(t, float)
        shape = np.broadcast_shapes(np.shape(theta)[:-1], np.shape(other)[:-1],
                                    table.shape[:-1], times.shape)
        full = (*shape, self.n)

        def rows_of(array, width):  # a writable C-ordered copy (the kernels take no views)
            # order="C": a copy of a Fortran-ordered or broadcast input would keep its order,
            # and rows of it are not the contiguous arrays the compiled kernels are typed for
            return np.array(np.broadcast_to(array, (*shape, width)).reshape(-1, width), float,
                            order="C")

        flat, others = rows_of(np.asarray(theta, float), self.n), rows_of(other, self.n)
        rows = table.reshape(1, -1) if table.ndim == 1 else rows_of(table, table.shape[-1])
        out = np.empty_like(flat)
        _rows(kind, flat, others, rows, rows_of(times[..., None], 1)[:, 0].copy(), out)
        return out.reshape(full)

    def _tails(self, params) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(mu, l, g)``: tail masses and lengths, shape (..., n), and ``g``, shape (...)."""
        n, table = self.n, self._parameter_array(params)
        masses = table[..., :n]
        tails = np.flip(np.cumsum(np.flip(masses, axis=-1), axis=-1), axis=-1)
        return tails, table[..., n : 2 * n], table[..., 2 * n]

    def _coupling(self, params) -> np.ndarray:
        """``mu_max(i,j) l_i l_j``, shape (..., n, n)."""
        tails, lengths, _ = self._tails(params)
        index = np.arange(self.n)
        return (tails[..., np.maximum.outer(index, index)] * lengths[..., :, None]
                * lengths[..., None, :])

    def _differences(self, theta):
        """``cos`` and ``sin`` of ``theta_i - theta_j``, each shape (..., n, n)."""
        theta = np.asarray(theta, float)
        angle = theta[..., :, None] - theta[..., None, :]
        return np.cos(angle), np.sin(angle)

    # ---- the model's functions ----------------------------------------------
    def mass_matrix(self, theta, params, t):
        return self._coupling(params) * self._differences(theta)[0]

    def velocities(self, theta, p, params, t):
        return self._batch(VELOCITIES, theta, p, params)

    def momenta(self, theta, omega, params, t):
        return self._batch(MOMENTA, theta, omega, params)

    def dlagrangian_dq(self, theta, omega, params, t):
        return self._batch(RATES, theta, omega, params)

    def forcing(self, theta, omega, params, t):
        return self._batch(FORCING, theta, omega, params, t)

    def accelerations(self, theta, omega, params, t):
        return self._batch(ACCELERATIONS, theta, omega, params, t)

    def generalized_forces(self, theta, omega, params, t):
        return self._batch(FORCES, theta, omega, params, t)

    def kinetic(self, theta, omega, params, t):
        omega = np.asarray(omega, float)
        return 0.5 * np.sum(omega * self.momenta(theta, omega, params, t), axis=-1)

    def potential(self, theta, params, t):
        tails, lengths, g = self._tails(params)
        return -g * np.sum(tails * lengths * np.cos(np.asarray(theta, float)), axis=-1)

    def hamiltonian(self, theta, omega, params, t):
        """``H = T + V`` at the velocities ``omega``."""
        return self.kinetic(theta, omega, params, t) + self.potential(theta, params, t)

    def damping_matrix(self, params) -> np.ndarray:
        """``C``, tridiagonal: ``C_ii = c_i + c_(i+1)``, ``C_(i,i+1) = -c_(i+1)``; (..., n, n)."""
        n, table = self.n, self._parameter_array(params)
        result = np.zeros((*table.shape[:-1], n, n))
        if not self.forced:
            return result
        joints = table[..., 2 * n + 1 : 3 * n + 1]
        index = np.arange(n)
        result[..., index, index] = joints
        result[..., index[:-1], index[:-1]] += joints[..., 1:]
        result[..., index[:-1], index[1:]] = -joints[..., 1:]
        result[..., index[1:], index[:-1]] = -joints[..., 1:]
        return result

    # Second derivatives of L, with a = mu_max(i,j) l_i l_j and the off-diagonal
    # entries first; each diagonal entry is minus the sum of its row's others
    # (plus the gravity term), because the sums leave j = i out.
    def lag_qq(self, theta, omega, params, t):
        """``d^2 L / dtheta dtheta``: ``a_ik cos(theta_i - theta_k) omega_i omega_k`` off the
        diagonal; ``-sum_(j != i) (those) - g mu_i l_i cos(theta_i)`` on it."""
        omega = np.asarray(omega, float)
        cos, _ = self._differences(theta)
        tails, lengths, g = self._tails(params)
        off = self._coupling(params) * cos * omega[..., :, None] * omega[..., None, :]
        gravity = -np.asarray(g)[..., None] * tails * lengths * np.cos(np.asarray(theta, float))
        return self._with_diagonal(off, gravity)

    def lag_qw(self, theta, omega, params, t):
        """``d^2 L / dtheta domega``: ``-a_ik sin(theta_i - theta_k) omega_i`` off the diagonal;
        ``-sum_(j != i) a_ij sin(theta_i - theta_j) omega_j`` on it."""
        omega = np.asarray(omega, float)
        _, sin = self._differences(theta)
        a_sin = self._coupling(params) * sin
        off = -a_sin * omega[..., :, None]
        diagonal = -np.einsum("...ij,...j->...i", a_sin, omega)
        return self._with_diagonal(off, diagonal, subtract=False)

    def dmomenta_dq(self, theta, omega, params, t):
        """``d(M omega) / dtheta``: ``a_ik sin(theta_i - theta_k) omega_k`` off the diagonal;
        ``-sum_(j != i)`` (those) on it."""
        omega = np.asarray(omega, float)
        _, sin = self._differences(theta)
        off = self._coupling(params) * sin * omega[..., None, :]
        return self._with_diagonal(off, 0.0)

    @staticmethod
    def _with_diagonal(off, extra, subtract: bool = True):
        """``off`` with its diagonal replaced by ``extra`` (minus its row sum, if ``subtract``).

        The diagonal of ``off`` is zero on entry (a ``sin(0)`` factor) or is
        overwritten: rows sum over ``j != i`` only.
        """
        n = off.shape[-1]
        index = np.arange(n)
        diagonal = off[..., index, index].copy()
        rows = off.sum(axis=-1) - diagonal
        result = off.copy()
        result[..., index, index] = (extra - rows) if subtract else extra
        return result
