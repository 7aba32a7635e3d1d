"""Reference steps: every registered method written out in plain NumPy, as its formula reads.

The compiled steps (:mod:`~pendulum_lab.integrators.runge_kutta`,
:mod:`~pendulum_lab.integrators.symplectic`, :mod:`~pendulum_lab.integrators.velocity`,
:mod:`~pendulum_lab.integrators.variational`) are written for speed: workspaces, views, stage
sums padded to vector lanes. The functions here compute the same steps the way a textbook
writes them; each method carries its own (:attr:`Method.reference
<pendulum_lab.integrators.method.Method.reference>`), the notebooks show it
(:func:`~pendulum_lab.integrators.source.method_source`), and the tests compare the compiled
kernels with it step by step. They are never used in a run.

One module rather than one per family: the families share the field's functions
(:class:`ReferenceField`) and one solver for every implicit equation (:func:`fixed_point`, with
the package's stopping rule written out), and a reader finds every method on one page.

A reference step has the signature ``step(field, t, q, p, h) -> (q1, p1)``: ``field`` a
:class:`ReferenceField`, ``t`` the time at the start of the step, ``q, p`` arrays of shape
``(n,)`` (``p`` the velocity for the two ``*_velocity`` methods), ``h`` the step. The implicit
Runge-Kutta step also takes ``previous`` (the stage slopes of the previous step, from which
the compiled step starts) and returns its own slopes third. An implicit equation that does not
converge raises :class:`~pendulum_lab.integrators.field.ConvergenceError`.

References
----------
.. [HLW] E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
   Springer 2006: explicit and symplectic Euler (Sect. I.1, Thm VI.3.3), Stormer-Verlet for a
   general H (eq. VI.3.4), Runge-Kutta methods and collocation (Sect. II.1), starting values
   for the stage iteration (Sect. VIII.6.1).
.. [MP] R. I. McLachlan, M. Perlmutter, "Conformal Hamiltonian systems", J. Geom. Phys. 39
   (2001) 276-300.
.. [MW] J. E. Marsden, M. West, "Discrete mechanics and variational integrators", Acta
   Numerica 10 (2001) 357-514, Sect. 1.3.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from . import composition as compositions
from .field import ConvergenceError, HamiltonianField
from .stopping import EPSILON, MAX_SWEEPS, ROUNDOFF_TOLERANCE
from .tableau import ButcherTableau

__all__ = [
    "ReferenceField",
    "adjoint_symplectic_euler",
    "composition",
    "conformal_euler",
    "conformal_leapfrog",
    "explicit_euler",
    "explicit_runge_kutta",
    "fixed_point",
    "implicit_runge_kutta",
    "leapfrog",
    "leapfrog_velocity",
    "runge_kutta_reference",
    "semi_implicit_euler_velocity",
    "symplectic_euler",
    "variational",
]


# ---------------------------------------------------------------- the field, as functions
class ReferenceField:
    """A compiled field's kernels as NumPy functions of the state, for the reference steps.

    Parameters
    ----------
    field : HamiltonianField
    member : int
        The row of ``field.params`` (and of its damping rates) for an ensemble's field.

    Attributes
    ----------
    gamma : float
        The damping rate of a conformal field (``dp/dt = -H_q - gamma p``), 0 for a
        Hamiltonian one, NaN for damping of another form.
    evaluations : int
        Kernel calls made so far (each function below makes one).
    """

    def __init__(self, field: HamiltonianField, member: int = 0):
        if not isinstance(field, HamiltonianField):
            raise TypeError(f"`field` must be a HamiltonianField, got {type(field).__name__}")
        rows = np.atleast_2d(np.asarray(field.params, dtype=float))
        if isinstance(member, bool) or not isinstance(member, (int, np.integer)) \
                or not 0 <= member < rows.shape[0]:
            raise ValueError(f"`member` must be an integer in [0, {rows.shape[0]}), got {member!r}")
        self.kernels = field
        self.params = np.ascontiguousarray(rows[member])
        self.gamma = float(np.broadcast_to(field.damping_rate, rows.shape[:1])[member])
        self.evaluations = 0

    def hamilton(self, t, q, p):
        """``(dq/dt, dp/dt) = (H_p, -H_q + Q)`` at ``(t, q, p)``; ``Q``: damping, if any."""
        q, p = (np.ascontiguousarray(x, dtype=float) for x in (q, p))
        dq, dp = np.empty_like(q), np.empty_like(p)
        self.kernels.hamilton(float(t), q, p, self.params, dq, dp)
        self.evaluations += 1
        return dq, dp

    def f(self, t, y):
        """``dy/dt`` for the state ``y = (q, p)`` as one array: Hamilton's equations and forces."""
        n = np.size(y) // 2
        return np.concatenate(self.hamilton(t, y[:n], y[n:]))

    def H_p(self, t, q, p):
        """``dH/dp`` at ``(t, q, p)``."""
        return self.hamilton(t, q, p)[0]

    def H_q(self, t, q, p):
        """``dH/dq`` at ``(t, q, p)``: ``-dp/dt`` without the damping ``-gamma p`` (conformal)."""
        if not math.isfinite(self.gamma):
            raise ValueError("this field's damping is not of the conformal form -gamma p, so "
                             "dH/dq cannot be told apart from it")
        return -(self.hamilton(t, q, p)[1] + self.gamma * np.asarray(p, dtype=float))

    def acceleration(self, t, q, v):
        """``d^2 q/dt^2`` at angles ``q`` and velocities ``v`` (the report's variables)."""
        q, v = (np.ascontiguousarray(x, dtype=float) for x in (q, v))
        out = np.empty_like(q)
        self.kernels.acceleration(float(t), q, v, self.params, out)
        self.evaluations += 1
        return out

    def discrete(self, rule: str) -> dict:
        """The generated kernels of the discrete Lagrangian ``rule`` as functions.

        ``fixed_point_update(h, q0, q1, p0)`` and ``newton_update(h, q0, q1, p0)``: the next
        iterate for ``q1`` of the transform ``p0 = -D_1 L_d(q0, q1)``;
        ``impulse(h, q0, q1) = D_2 L_d(q0, q1) + D_1 L_d(q0, q1)``, the change of momentum.
        """
        if self.kernels.discrete is None:
            raise ValueError("this field has no discrete Lagrangian (damping, a drive or a "
                             "time-dependent L)")
        kernels = self.kernels.discrete(rule)

        def call(kernel, h, *arrays):
            arrays = [np.ascontiguousarray(x, dtype=float) for x in arrays]
            out = np.empty_like(arrays[0])
            kernel(float(h), *arrays[:2], self.params, *arrays[2:], out)
            self.evaluations += 1
            return out

        return {name: functools.partial(call, getattr(kernels, name))
                for name in ("fixed_point_update", "newton_update", "impulse")}


# ---------------------------------------------------------------- implicit equations
def fixed_point(update, x, floor=0.0):
    """Iterate ``x <- update(x)`` from the guess ``x`` to round-off, by the package's stopping
    rule (``stopping.fixed_point_status``): every increment tiny, and none shrinking any more
    or the contraction seen so far predicting the rest below half an ulp."""
    smallest = np.full(np.shape(x), np.inf)  # each component's smallest increment so far
    for _ in range(MAX_SWEEPS):
        x, old = update(x), x
        delta, size, previous = np.abs(x - old), np.abs(x), smallest
        smallest = np.minimum(previous, delta)
        if not np.all(np.isfinite(x)):
            break
        if np.any(delta > ROUNDOFF_TOLERANCE * (1.0 + floor + size)):
            continue  # far from round-off
        shrinking = (delta < previous) & (delta > 0)
        if not shrinking.any():
            return x  # every component stalled
        measured = np.isfinite(previous) & (previous > 256 * EPSILON * size)  # not noise
        rate = np.max(delta[measured] / previous[measured], initial=0.0)  # contraction
        worst = np.max(delta[shrinking] / size[shrinking])
        if measured.any() and rate < 1 and rate * worst <= 0.5 * EPSILON * (1 - rate):
            return x  # the corrections still to come are below half an ulp
    raise ConvergenceError(f"the fixed-point iteration did not converge in {MAX_SWEEPS} sweeps")


# ---------------------------------------------------------------- Runge-Kutta
def explicit_euler(field, t, q, p, h):
    """Explicit Euler [HLW, Sect. I.1]: ``y1 = y + h f(t, y)`` for the state ``y = (q, p)``."""
    y = np.concatenate([q, p])
    y1 = y + h * field.f(t, y)
    return np.split(y1, 2)


def explicit_runge_kutta(field, t, q, p, h, tableau):
    """An explicit Runge-Kutta method from its Butcher tableau ``(a, b, c)`` [HLW, Sect. II.1]:

    ``k_i = f(t + c_i h, y + h sum_{j<i} a_ij k_j)``;  ``y1 = y + h sum_i b_i k_i``.
    """
    a, b, c = tableau.a, tableau.b, tableau.c
    y, k = np.concatenate([q, p]), []
    for i in range(len(b)):
        k.append(field.f(t + c[i] * h, y + h * sum(a[i, j] * k[j] for j in range(i))))
    y1 = y + h * sum(b[i] * k[i] for i in range(len(b)))
    return np.split(y1, 2)


def implicit_runge_kutta(field, t, q, p, h, tableau, previous=None):
    """An implicit Runge-Kutta method, such as Gauss-Legendre collocation [HLW, Sect. II.1.3]:
    ``K_i = f(t + c_i h, y + h sum_j a_ij K_j)`` by fixed-point iteration to round-off, then
    ``y1 = y + h sum_i b_i K_i``. It starts as the compiled step does: from ``previous`` (the
    last step's slopes, same h) continued, ``K^0 = E K_prev`` [HLW, VIII.6.1]; else ``f(t, y)``.
    """
    a, b, c = tableau.a, tableau.b, tableau.c
    y = np.concatenate([q, p])
    def sweep(K):  # every stage evaluated at the latest slopes
        return np.array([field.f(t + c[i] * h, y + h * (a[i] @ K)) for i in range(len(b))])
    first = previous is None or tableau.extrapolation is None  # nothing to continue
    K = np.tile(field.f(t, y), (len(b), 1)) if first else tableau.extrapolation @ previous
    # a slope's round-off follows the state it is added to: "tiny" is judged against |y| / h
    K = fixed_point(sweep, K, floor=np.max(np.abs(y)) / abs(h))
    q1, p1 = np.split(y + h * (b @ K), 2)
    return q1, p1, K


def runge_kutta_reference(tableau: ButcherTableau):
    """The reference step of the Runge-Kutta method of ``tableau`` (explicit or implicit)."""
    if not isinstance(tableau, ButcherTableau):
        raise TypeError(f"`tableau` must be a ButcherTableau, got {type(tableau).__name__}")
    step = explicit_runge_kutta if tableau.explicit else implicit_runge_kutta
    return functools.partial(step, tableau=tableau)


# ---------------------------------------------------------------- symplectic, for any H(t, q, p)
def symplectic_euler(field, t, q, p, h):
    """Symplectic Euler for a general ``H(t, q, p)`` [HLW, Thm VI.3.3], iterated from the
    explicit guess (exact for a separable H):

    ``p1 = p - h H_q(t, q, p1)``   (implicit in p1)
    ``q1 = q + h H_p(t, q, p1)``
    """
    def kick(x):
        return p - h * field.H_q(t, q, x)
    p1 = fixed_point(kick, kick(p))
    return q + h * field.H_p(t, q, p1), p1


def leapfrog(field, t, q, p, h):
    """The leapfrog (Stormer-Verlet) for a general ``H(t, q, p)`` [HLW, eq. VI.3.4], each
    implicit equation iterated from its explicit guess (exact for a separable H):

    ``p_half = p - h/2 H_q(t, q, p_half)``                          (implicit in p_half)
    ``q1 = q + h/2 [H_p(t, q, p_half) + H_p(t + h, q1, p_half)]``   (implicit in q1)
    ``p1 = p_half - h/2 H_q(t + h, q1, p_half)``
    """
    def kick(x):
        return p - h / 2 * field.H_q(t, q, x)
    p_half = fixed_point(kick, kick(p))
    velocity = field.H_p(t, q, p_half)
    def drift(x):
        return q + h / 2 * velocity + h / 2 * field.H_p(t + h, x, p_half)
    q1 = fixed_point(drift, q + h * velocity)
    return q1, p_half - h / 2 * field.H_q(t + h, q1, p_half)


def adjoint_symplectic_euler(field, t, q, p, h):
    """The adjoint of symplectic Euler for a general ``H(t, q, p)`` [HLW, Sect. II.3], the drift
    first, iterated from the explicit guess (exact for a separable H):

    ``q1 = q + h H_p(t + h, q1, p)``   (implicit in q1)
    ``p1 = p - h H_q(t + h, q1, p)``
    """
    def drift(x):
        return q + h * field.H_p(t + h, x, p)
    q1 = fixed_point(drift, q + h * field.H_p(t, q, p))
    return q1, p - h * field.H_q(t + h, q1, p)


def composition(field, t, q, p, h, composition):
    """A composition method [HLW, Sect. II.4]: its substeps one after another, the ``i``-th the
    base method (leapfrog, symplectic Euler or its adjoint) with the step ``w_i h``, each from
    the time and state where the last ended."""
    base = {"leapfrog": leapfrog, "symplectic_euler": symplectic_euler,
            "adjoint_symplectic_euler": adjoint_symplectic_euler}
    for kind, w in composition.substeps:
        q, p = base[compositions.SUBSTEP_NAMES[kind]](field, t, q, p, w * h)
        t = t + w * h
    return q, p


def conformal_euler(field, t, q, p, h):
    """Conformal symplectic Euler [MP]: symplectic Euler of H, then the exact damping flow
    ``p <- exp(-gamma h) p`` of ``dp/dt = -gamma p``."""
    q1, p1 = symplectic_euler(field, t, q, p, h)
    return q1, math.exp(-field.gamma * h) * p1


def conformal_leapfrog(field, t, q, p, h):
    """Conformal Stormer-Verlet [MP]: the exact damping for ``h/2``, leapfrog, ``h/2`` again."""
    contraction = math.exp(-field.gamma * h / 2)
    q1, p1 = leapfrog(field, t, q, contraction * p, h)
    return q1, contraction * p1


# ---------------------------------------------------------------- the course report's, on (q, v)
def semi_implicit_euler_velocity(field, t, q, v, h):
    """The course report's semi-implicit Euler on angles and velocities:

    ``v1 = v + h a(t, q, v)``;  ``q1 = q + h v1``.
    """
    v1 = v + h * field.acceleration(t, q, v)
    return q + h * v1, v1


def leapfrog_velocity(field, t, q, v, h):
    """The course report's leapfrog on angles and velocities, as kick-drift-kick:

    ``v_half = v + h/2 a(t, q, v)``;  ``q1 = q + h v_half``;
    ``v1 = v_half + h/2 a(t + h, q1, v_half)``: the half-step velocity where ``v1`` belongs.
    """
    v_half = v + h / 2 * field.acceleration(t, q, v)
    q1 = q + h * v_half
    return q1, v_half + h / 2 * field.acceleration(t + h, q1, v_half)


# ---------------------------------------------------------------- variational
def variational(field, t, q, p, h, rule, solver="fixed_point_update"):
    """A variational integrator [MW] (autonomous: ``t`` is not used). With the discrete
    Lagrangian ``L_d`` of ``rule``: solve ``p = -D_1 L_d(q, q1)`` for ``q1`` by iterating the
    kernel ``solver`` from ``q1 = q``; then ``p1 = D_2 L_d(q, q1) = p + (D_1 + D_2) L_d(q, q1)``.
    """
    legendre = field.discrete(rule)
    q1 = fixed_point(lambda x: legendre[solver](h, q, x, p), q)
    return q1, p + legendre["impulse"](h, q, q1)
