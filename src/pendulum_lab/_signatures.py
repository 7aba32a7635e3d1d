"""The calling convention shared by generated vector fields and compiled integrators.

A vector field is a pair of Numba kernels that write into output arrays:

``hamilton(t, q, p, params, dq, dp)``: ``dq = dH/dp``, ``dp = -dH/dq + Q``;
``acceleration(t, q, v, params, out)``: ``out = d^2 q/dt^2`` given velocity ``v``.

``t`` is the time (the drive of a forced pendulum depends on it; other
fields ignore it) and ``Q`` the generalized forces that no Hamiltonian
describes (damping; zero for a conservative field). Integrators receive the
kernels as first-class functions of these exact types, so the compiled
integrators do not depend on which vector field they integrate and Numba can
cache them on disk.
"""

from numba import types

VECTOR = types.float64[::1]
HAMILTON = types.void(types.float64, VECTOR, VECTOR, VECTOR, VECTOR, VECTOR)
ACCELERATION = types.void(types.float64, VECTOR, VECTOR, VECTOR, VECTOR)

# Variational integrators solve the discrete Legendre transform
# ``p0 = -D_1 L_d(q0, q1)`` for ``q1`` and then evaluate ``p1 = D_2 L_d(q0, q1)``,
# as ``p0`` plus the impulse ``D_2 L_d + D_1 L_d``
# (see :mod:`pendulum_lab.discrete_mechanics`). Their kernels have the same
# Numba types as the two above, so a variational step has the signature of
# every other step and receives them in the same two places:
#
# ``update(h, q0, q1, params, p0, out)``: ``out`` = the next iterate for ``q1``;
# ``impulse(h, q0, q1, params, out)``: ``out = D_2 L_d(q0, q1) + D_1 L_d(q0, q1)``.
DISCRETE_UPDATE = HAMILTON
DISCRETE_MOMENTUM = ACCELERATION
