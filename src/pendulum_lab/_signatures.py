"""The calling convention shared by generated vector fields and compiled integrators.

A vector field is a pair of Numba kernels that write into output arrays:

``hamilton(q, p, params, dq, dp)``: ``dq = dH/dp``, ``dp = -dH/dq``;
``acceleration(q, v, params, out)``: ``out = d^2 q/dt^2`` given velocity ``v``.

Integrators receive them as first-class functions of these exact types, so
the compiled integrators do not depend on which vector field they integrate
and Numba can cache them on disk.
"""

from numba import types

VECTOR = types.float64[::1]
HAMILTON = types.void(VECTOR, VECTOR, VECTOR, VECTOR, VECTOR)
ACCELERATION = types.void(VECTOR, VECTOR, VECTOR, VECTOR)
