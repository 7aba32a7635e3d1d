"""Symplectic Euler and the Stormer-Verlet leapfrog for a general ``H(t, q, p)``, and their
conformal versions for linear damping.

The steps follow the textbook formulas line by line [HLW]_; the implicit kicks and drifts
are iterated to round-off (:mod:`pendulum_lab.integrators.stopping`) and are explicit when
``H`` is separable. The time is attached to the positions (extended phase space: the first
kick at ``t``, the last at ``t + h``). The conformal methods compose them with the exact flow
of the damping ``-gamma p`` [MP]_.

References
----------
.. [HLW] E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
   Springer 2006: symplectic Euler (Thm VI.3.3), Stormer-Verlet for general H (eq. VI.3.4).
.. [MP] R. I. McLachlan, M. Perlmutter, "Conformal Hamiltonian systems", J. Geom. Phys. 39
   (2001) 276-300.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ..codegen.cache import cached_njit
from ..codegen.lowlevel import span, vector
from .composition import EULER, LEAPFROG, Composition
from .step import Step, jit_step, kernel_function
from .stopping import MAX_SWEEPS, fixed_point_status

__all__ = [
    "add_scaled",
    "adjoint_symplectic_euler",
    "composed",
    "composition_step",
    "conformal_euler_step",
    "conformal_leapfrog_step",
    "implicit_kick",
    "leapfrog_step",
    "remove_damping",
    "semi_implicit_euler_step",
    "stormer_verlet",
    "symplectic_euler",
]


@numba.njit
def add_scaled(out, x, factor, y):
    """``out = x + factor * y``, element by element (no temporary arrays)."""
    for i in range(out.size):
        out[i] = x[i] + factor * y[i]


@cached_njit
def remove_damping(p, damping_rate, dp):
    """``dp += damping_rate p``: from a conformal field's ``dp/dt`` to its Hamiltonian part's.

    A conformal Hamiltonian field has ``dp/dt = -H_q - gamma p`` [MP]; the
    symplectic steps below integrate ``-H_q`` and leave the damping to the
    conformal methods' exact flow. They call this only when ``gamma != 0``,
    so that a Hamiltonian field pays no call per evaluation.
    """
    for i in range(p.size):
        dp[i] += damping_rate * p[i]


@kernel_function
def implicit_kick(hamilton, t, q, p, k, params, separable, damping_rate, dq, dp, p_k, p_new,
                  smallest):
    """Solve ``p_k = p - k H_q(t, q, p_k)`` for ``p_k`` (written into ``p_k``): the momentum update.

    Starts from ``p + k dp``, so ``dp`` must hold ``-H_q(t, q, p)`` on entry
    (see :func:`remove_damping` for ``damping_rate``);
    the guess is exact when ``H`` is separable. Otherwise iterates
    ``p_k <- p + k dp(t, q, p_k)`` until :func:`fixed_point_status` finds
    round-off. ``dq``, ``dp``, ``p_new`` and ``smallest`` are workspace.
    Returns the sweeps, ``-1`` if the iteration did not converge (after
    ``MAX_SWEEPS``).
    """
    add_scaled(p_k, p, k, dp)  # p_k = p + k dp
    if separable:
        return 0
    smallest[:] = np.inf
    status, sweeps = 0, 0
    while status == 0 and sweeps < MAX_SWEEPS:
        sweeps += 1
        hamilton(t, q, p_k, params, dq, dp)
        if damping_rate != 0.0:
            remove_damping(p_k, damping_rate, dp)
        add_scaled(p_new, p, k, dp)  # p_new = p + k dp(t, q, p_k)
        status = fixed_point_status(p_new, p_k, smallest)
        p_k[:] = p_new
    return sweeps if status == 1 else -1


@kernel_function
def symplectic_euler(hamilton, t, q, p, h, params, separable, damping_rate, work):
    """Symplectic Euler for a general ``H(t, q, p)``:

    ``p1 = p - h H_q(t, q, p1)``   (implicit in ``p1`` only)
    ``q1 = q + h H_p(t, q, p1)``

    ``work`` holds ``6 n`` floats; ``q1, p1`` are returned as views into it.
    """
    n = q.size
    dq, dp, q1 = vector(work, 0, n), vector(work, 1, n), vector(work, 2, n)
    p1, p_new, smallest = vector(work, 3, n), vector(work, 4, n), vector(work, 5, n)
    hamilton(t, q, p, params, dq, dp)
    if damping_rate != 0.0:
        remove_damping(p, damping_rate, dp)
    sweeps = implicit_kick(hamilton, t, q, p, h, params, separable, damping_rate, dq, dp, p1,
                           p_new, smallest)
    if sweeps < 0:
        return q, p, -1, 1 + MAX_SWEEPS
    hamilton(t, q, p1, params, dq, dp)  # only dq = H_p is used
    add_scaled(q1, q, h, dq)  # q1 = q + h dq
    return q1, p1, sweeps, sweeps + 2


@kernel_function
def adjoint_symplectic_euler(hamilton, t, q, p, h, params, separable, damping_rate, work):
    """The adjoint of symplectic Euler for a general ``H(t, q, p)``, the drift first:

    ``q1 = q + h H_p(t + h, q1, p)``   (implicit in ``q1`` only)
    ``p1 = p - h H_q(t + h, q1, p)``

    Symplectic Euler for ``h/2`` followed by this for ``h/2`` is :func:`stormer_verlet`; the
    compositions of the two (:mod:`~pendulum_lab.integrators.composition`) include the
    splitting methods. The drift starts from ``q + h H_p(t, q, p)``, exact when ``H`` is
    separable. ``work`` holds ``6 n`` floats; ``q1, p1`` are returned as views into it.
    """
    n = q.size
    dq, dp, q1 = vector(work, 0, n), vector(work, 1, n), vector(work, 2, n)
    p1, new, smallest = vector(work, 3, n), vector(work, 4, n), vector(work, 5, n)
    hamilton(t, q, p, params, dq, dp)  # only dq = H_p is used
    add_scaled(q1, q, h, dq)
    sweeps, calls = 0, 1
    if not separable:
        smallest[:] = np.inf
        status = 0
        while status == 0 and sweeps < MAX_SWEEPS:
            sweeps += 1
            hamilton(t + h, q1, p, params, dq, dp)
            add_scaled(new, q, h, dq)  # q1 <- q + h dq(t + h, q1, p)
            status = fixed_point_status(new, q1, smallest)
            q1[:] = new
        calls += sweeps
        if status != 1:
            return q, p, -1, calls
    hamilton(t + h, q1, p, params, dq, dp)
    if damping_rate != 0.0:
        remove_damping(p, damping_rate, dp)
    add_scaled(p1, p, h, dp)  # p1 = p + h dp
    return q1, p1, sweeps, calls + 1


@kernel_function
def stormer_verlet(hamilton, t, q, p, h, params, separable, damping_rate, work):
    """Stormer-Verlet for a general ``H(t, q, p)`` (the Lobatto IIIA-IIIB pair):

    ``p_half = p - h/2 H_q(t, q, p_half)``                          (implicit)
    ``q1 = q + h/2 [H_p(t, q, p_half) + H_p(t + h, q1, p_half)]``   (implicit)
    ``p1 = p_half - h/2 H_q(t + h, q1, p_half)``                    (explicit)

    ``work`` holds ``8 n`` floats; ``q1, p1`` are returned as views into it.
    """
    n = q.size
    dq, dp = vector(work, 0, n), vector(work, 1, n)
    p_half, q1 = vector(work, 2, n), vector(work, 3, n)
    p1, drift = vector(work, 4, n), vector(work, 5, n)
    new, smallest = vector(work, 6, n), vector(work, 7, n)
    hamilton(t, q, p, params, dq, dp)
    if damping_rate != 0.0:
        remove_damping(p, damping_rate, dp)
    sweeps = implicit_kick(hamilton, t, q, p, 0.5 * h, params, separable, damping_rate, dq, dp,
                           p_half, new, smallest)
    if sweeps < 0:
        return q, p, -1, 1 + MAX_SWEEPS
    calls = 1 + sweeps
    hamilton(t, q, p_half, params, dq, dp)  # only dq = H_p is used
    add_scaled(drift, q, 0.5 * h, dq)  # drift = q + h/2 dq
    add_scaled(q1, q, h, dq)  # q1 = q + h dq: exact when H is separable, else the first guess
    calls += 1
    if not separable:
        smallest[:] = np.inf
        status, first_sweeps = 0, sweeps
        while status == 0 and sweeps - first_sweeps < MAX_SWEEPS:
            sweeps += 1
            hamilton(t + h, q1, p_half, params, dq, dp)
            add_scaled(new, drift, 0.5 * h, dq)  # q1 <- drift + h/2 dq(t + h, q1, p_half)
            status = fixed_point_status(new, q1, smallest)
            q1[:] = new
        calls += sweeps - first_sweeps
        if status != 1:
            return q, p, -1, calls
    hamilton(t + h, q1, p_half, params, dq, dp)
    if damping_rate != 0.0:
        remove_damping(p_half, damping_rate, dp)
    add_scaled(p1, p_half, 0.5 * h, dp)  # p1 = p_half + h/2 dp
    return q1, p1, sweeps, calls + 1


@jit_step(memory=lambda n: 6 * n)
def semi_implicit_euler_step(hamilton, acceleration, t, q, p, h, params, separable,
                             damping_rate, memory):
    """Symplectic Euler in ``(q, p)``: :func:`symplectic_euler` of the Hamiltonian."""
    return symplectic_euler(hamilton, t, q, p, h, params, separable, damping_rate, memory)


@jit_step(memory=lambda n: 8 * n)
def leapfrog_step(hamilton, acceleration, t, q, p, h, params, separable, damping_rate, memory):
    """Stormer-Verlet in ``(q, p)``: :func:`stormer_verlet` of the Hamiltonian."""
    return stormer_verlet(hamilton, t, q, p, h, params, separable, damping_rate, memory)


@jit_step(memory=lambda n: 6 * n)
def conformal_euler_step(hamilton, acceleration, t, q, p, h, params, separable, damping_rate,
                         memory):
    """Conformal symplectic Euler [MP]: symplectic Euler, then the exact damping flow.

    ``(q, p) <- symplectic Euler of H``;  ``p <- exp(-gamma h) p``.
    """
    q1, p1, sweeps, calls = symplectic_euler(hamilton, t, q, p, h, params, separable,
                                             damping_rate, memory)
    contraction = math.exp(-damping_rate * h)
    for i in range(p1.size):
        p1[i] = contraction * p1[i]
    return q1, p1, sweeps, calls


@jit_step(memory=lambda n: 9 * n)
def conformal_leapfrog_step(hamilton, acceleration, t, q, p, h, params, separable,
                            damping_rate, memory):
    """Conformal Stormer-Verlet [MP]: half the damping, a leapfrog step of ``H``, half again.

    ``p <- exp(-gamma h/2) p``;  ``(q, p) <- Stormer-Verlet of H``;
    ``p <- exp(-gamma h/2) p``. The damping flow is exact and the middle step
    symplectic, so each step contracts phase-space volume by exactly
    ``exp(-n gamma h)``, as the true flow does; symmetric, second order.
    """
    contraction, n = math.exp(-0.5 * damping_rate * h), q.size
    contracted = vector(memory, 0, n)
    for i in range(n):
        contracted[i] = contraction * p[i]
    q1, p1, sweeps, calls = stormer_verlet(hamilton, t, q, contracted, h, params, separable,
                                           damping_rate, span(memory, n, 8 * n))
    for i in range(n):
        p1[i] = contraction * p1[i]
    return q1, p1, sweeps, calls


#: Floats of workspace per coordinate that a substep of a composition may use (the leapfrog's).
SUBSTEP_MEMORY = 8


@kernel_function
def composed(hamilton, t, q, p, h, params, separable, damping_rate, kinds, weights, work):
    """The composition of the substeps ``kinds`` with steps ``weights * h``, one after another.

    ``kinds[i]`` says which map the ``i``-th substep is (``composition.LEAPFROG``, ``EULER``,
    ``ADJOINT``); each starts at the time and state where the last ended. Substeps write into
    two workspaces in turn, so that a substep never overwrites the state it starts from;
    ``work`` holds ``(2 SUBSTEP_MEMORY + 2) n`` floats; ``q1, p1`` are returned as views into it.
    """
    n = q.size
    size = SUBSTEP_MEMORY * n
    qi, pi = vector(work, 2 * SUBSTEP_MEMORY, n), vector(work, 2 * SUBSTEP_MEMORY + 1, n)
    qi[:] = q
    pi[:] = p
    time, sweeps, calls = t, 0, 0
    for i in range(kinds.size):
        substep_work = span(work, (i % 2) * size, size)
        k = weights[i] * h
        if kinds[i] == LEAPFROG:
            q1, p1, substep_sweeps, substep_calls = stormer_verlet(
                hamilton, time, qi, pi, k, params, separable, damping_rate, substep_work)
        elif kinds[i] == EULER:
            q1, p1, substep_sweeps, substep_calls = symplectic_euler(
                hamilton, time, qi, pi, k, params, separable, damping_rate, substep_work)
        else:
            q1, p1, substep_sweeps, substep_calls = adjoint_symplectic_euler(
                hamilton, time, qi, pi, k, params, separable, damping_rate, substep_work)
        calls += substep_calls
        if substep_sweeps < 0:
            return q, p, -1, calls
        sweeps += substep_sweeps
        qi, pi = q1, p1
        time += k
    return qi, pi, sweeps, calls


def composition_step(composition: Composition, name: str) -> Step:
    """The step function of the composition method ``name``: :func:`composed` of its substeps.

    The kinds and weights are closed over, so Numba compiles them in as constants, as
    :func:`~pendulum_lab.integrators.runge_kutta.tableau_step` does with a tableau. Each
    method's step is named ``<name>_step``.
    """
    if not isinstance(composition, Composition):
        raise TypeError(f"`composition` must be a Composition, got {type(composition).__name__}")
    kinds = np.array([kind for kind, _ in composition.substeps], dtype=np.int64)
    weights = np.array(composition.weights)

    def composition_of_substeps(hamilton, acceleration, t, q, p, h, params, separable,
                                damping_rate, memory):
        """One step of a composition method: its substeps one after another."""
        return composed(hamilton, t, q, p, h, params, separable, damping_rate, kinds, weights,
                        memory)

    step = composition_of_substeps
    step.__name__ = step.__qualname__ = f"{name}_step"
    return jit_step(step, memory=lambda n: (2 * SUBSTEP_MEMORY + 2) * n)
