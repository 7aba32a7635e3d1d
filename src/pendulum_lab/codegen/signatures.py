"""The calling convention shared by generated vector fields and compiled integrators.

A vector field is a set of Numba kernels that write into output arrays:

``hamilton(t, q, p, params, dq, dp)``: ``dq = dH/dp``, ``dp = -dH/dq + Q``;
``acceleration(t, q, v, params, out)``: ``out = d^2 q/dt^2`` given velocity ``v``;
``stages(ts, y, params, dy, work)``: ``hamilton`` at several states at once,
for the stages of an implicit Runge-Kutta step. Column ``k`` of ``y``
(shape ``(2 n, lanes)``) is a state ``(q, p)`` at time ``ts[k]``; column
``k`` of ``dy`` receives ``(dq, dp)`` there; ``work`` holds ``4 n`` floats of
scratch. Generated for one or two links as one loop over the columns that
the compiler vectorizes (:mod:`pendulum_lab.codegen.lowlevel`); two 2-d arrays
rather than four, because the vectorized loop first checks at run time
that no output overlaps an input, pair by pair, and fewer arrays make fewer
pairs to check (docs/design/stage-kernel.md).

``t`` is the time (the drive of a forced pendulum depends on it; other
fields ignore it) and ``Q`` the generalized forces that no Hamiltonian
describes (damping; zero for a conservative field). The kernels are compiled
with these exact types, so that Numba compiles each once and keeps it on disk.
"""

from numba import types

VECTOR = types.float64[::1]
HAMILTON = types.void(types.float64, VECTOR, VECTOR, VECTOR, VECTOR, VECTOR)
ACCELERATION = types.void(types.float64, VECTOR, VECTOR, VECTOR, VECTOR)
MATRIX = types.float64[:, ::1]
STAGES = types.void(VECTOR, MATRIX, VECTOR, MATRIX, VECTOR)

# Variational integrators solve the discrete Legendre transform
# ``p0 = -D_1 L_d(q0, q1)`` for ``q1`` and then evaluate ``p1 = D_2 L_d(q0, q1)``,
# as ``p0`` plus the impulse ``D_2 L_d + D_1 L_d``
# (see :mod:`pendulum_lab.symbolic.discrete_mechanics`). Their kernels have the same
# Numba types as ``hamilton`` and ``acceleration``, so a variational step has the signature of
# every other step and receives them in the same two places:
#
# ``update(h, q0, q1, params, p0, out)``: ``out`` = the next iterate for ``q1``;
# ``impulse(h, q0, q1, params, out)``: ``out = D_2 L_d(q0, q1) + D_1 L_d(q0, q1)``.
DISCRETE_UPDATE = HAMILTON
DISCRETE_MOMENTUM = ACCELERATION
