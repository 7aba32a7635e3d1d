"""The course report's two methods on ``(q, v)``: semi-implicit Euler and the leapfrog.

They update positions and velocities as for a separable Hamiltonian. On a chain of two or
more links the kinetic energy depends on the angles, so in these variables neither map is
symplectic; the course keeps them to show what goes wrong (notebooks 05, 06 and 13).
"""

from __future__ import annotations

from ..codegen.lowlevel import vector
from .step import jit_step
from .symplectic import add_scaled

__all__ = ["leapfrog_velocity_step", "semi_implicit_euler_velocity_step"]


@jit_step(memory=lambda n: 3 * n)
def semi_implicit_euler_velocity_step(hamilton, acceleration, t, q, v, h, params, separable,
                                      damping_rate, memory):
    """The course report's version on ``(q, v)``: ``v1 = v + h a(t, q, v)``; ``q1 = q + h v1``."""
    n = q.size
    a, v1, q1 = vector(memory, 0, n), vector(memory, 1, n), vector(memory, 2, n)
    acceleration(t, q, v, params, a)
    add_scaled(v1, v, h, a)  # v1 = v + h a
    add_scaled(q1, q, h, v1)  # q1 = q + h v1
    return q1, v1, 0, 1


@jit_step(memory=lambda n: 4 * n)
def leapfrog_velocity_step(hamilton, acceleration, t, q, v, h, params, separable, damping_rate,
                           memory):
    """The course report's leapfrog on ``(q, v)``, written as kick-drift-kick:

    ``v_half = v + h/2 a(t, q, v)``; ``q1 = q + h v_half``;
    ``v1 = v_half + h/2 a(t + h, q1, v_half)``.
    Second order only when ``a`` does not depend on ``v``.
    """
    n = q.size
    a, v_half = vector(memory, 0, n), vector(memory, 1, n)
    q1, v1 = vector(memory, 2, n), vector(memory, 3, n)
    acceleration(t, q, v, params, a)
    add_scaled(v_half, v, 0.5 * h, a)  # v_half = v + h/2 a
    add_scaled(q1, q, h, v_half)  # q1 = q + h v_half
    acceleration(t + h, q1, v_half, params, a)
    add_scaled(v1, v_half, 0.5 * h, a)  # v1 = v_half + h/2 a
    return q1, v1, 0, 2
