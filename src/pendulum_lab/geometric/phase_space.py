"""Phase-space area: Liouville's theorem, symplecticity, Poincare's integral invariant.

The exact flow of a Hamiltonian system keeps the oriented area of every
two-dimensional family of states, summed over the planes ``(q_i, p_i)``
(Poincare's integral invariant); for one degree of freedom that is simply
the area of a blob (Liouville). A one-step map does the same exactly when
its Jacobian ``Psi`` satisfies ``Psi^T J Psi = J`` (symplecticity).

Here a family is the disc spanned by a closed loop of initial states,
``z(s) = c + cos(2 pi s) a + sin(2 pi s) b``. By Stokes' theorem its
invariant equals the sum of the oriented areas enclosed by the loop's
projections on the ``(q_i, p_i)`` planes, so only the loop is carried by the
method (as an ensemble). Each area is the shoelace area of the polygon
through the loop's points; the polygon's error falls like ``N^-2`` in the
number of points (the shoelace sum is a central difference of a periodic
integrand), so the areas at ``N`` and ``2N`` points are extrapolated
(Richardson) and ``N`` is doubled until the extrapolated areas agree to a
tolerance.

References
----------
.. [HLW] E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*,
   2nd ed., Springer 2006: Sect. VI.1-VI.2 (area preservation, Poincare's
   theorem, the integral invariant; their figures carry a cat's head
   through the methods).
.. [Arnold] V. I. Arnold, *Mathematical Methods of Classical Mechanics*,
   2nd ed., Springer 1989, Sect. 44 (integral invariants).
.. [MR] J. E. Marsden, T. S. Ratiu, *Introduction to Mechanics and Symmetry*,
   2nd ed., Springer 1999, Sect. 7.3 (the Legendre transform pulls the
   canonical 2-form back to the Lagrangian 2-form on velocity space).
"""

from __future__ import annotations

import functools
import warnings
from dataclasses import dataclass
from fractions import Fraction

import mpmath
import numpy as np
import sympy as sp

from .. import validation as check
from ..analysis import finite_difference_jacobian, step_jacobian, symplectic_form_defect
from ..driver.simulate import simulate, step
from ..integrators import get_method
from ..model import require_model
from ..model.pendulum import PendulumModel

__all__ = [
    "LoopAreas",
    "carried_loop_areas",
    "ellipse_loop",
    "jacobian_along_orbit",
    "jacobian_properties",
    "one_step_area_change",
    "polygon_area",
    "velocity_form_defect",
]


def ellipse_loop(center, axes, points: int) -> np.ndarray:
    """``points`` states on the loop ``c + cos(2 pi s) a + sin(2 pi s) b``, ``s = k / points``.

    Parameters
    ----------
    center : array_like, shape (2n,)
        ``(theta_1..theta_n, p_1..p_n)`` of the loop's centre.
    axes : array_like, shape (2, 2n)
        The vectors ``a`` and ``b``.
    points : int

    Returns
    -------
    ndarray, shape (points, 2n)

    Examples
    --------
    >>> ellipse_loop([0.0, 0.0], [[1.0, 0.0], [0.0, 2.0]], 4).round(12) + 0.0
    array([[ 1.,  0.],
           [ 0.,  2.],
           [-1.,  0.],
           [ 0., -2.]])
    """
    points = check.integer_at_least("points", points, 3)
    center = np.asarray(center, float)
    axes = np.asarray(axes, float)
    if center.ndim != 1 or center.size % 2 or axes.shape != (2, center.size):
        raise ValueError(
            f"`center` must have shape (2n,) and `axes` shape (2, 2n), got {center.shape} "
            f"and {axes.shape}"
        )
    s = 2 * np.pi * np.arange(points) / points
    return center + np.cos(s)[:, None] * axes[0] + np.sin(s)[:, None] * axes[1]


def polygon_area(x, y) -> np.ndarray:
    """Oriented (shoelace) area of the closed polygon through the points ``(x, y)``.

    The points run along the last axis; leading axes are kept.
    Counter-clockwise polygons have positive area.

    Examples
    --------
    >>> float(polygon_area([0.0, 1.0, 1.0, 0.0], [0.0, 0.0, 1.0, 1.0]))
    1.0
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    if x.shape != y.shape or x.ndim == 0:
        raise ValueError(f"`x` and `y` must be arrays of the same shape (points along the last "
                         f"axis), got shapes {x.shape} and {y.shape}")
    return 0.5 * np.sum(x * np.roll(y, -1, axis=-1) - np.roll(x, -1, axis=-1) * y, axis=-1)


@dataclass(frozen=True)
class LoopAreas:
    """Oriented areas enclosed by a loop of states as a method carries it.

    Attributes
    ----------
    method : str
    dt : float
    t : ndarray, shape (m,)
        Saved times.
    canonical : ndarray, shape (m, n)
        Area of the loop's projection on each ``(theta_i, p_i)`` plane.
    velocity : ndarray, shape (m, n)
        The same in the planes ``(theta_i, omega_i)``.
    points : int
        Points on the loop when the areas had converged.
    error : float
        Estimated absolute error of the areas (the change of the
        extrapolated areas at the last doubling).
    loops : ndarray, shape (m, points, 2n)
        The carried loop in ``(theta, p)``, for pictures.
    """

    method: str
    dt: float
    t: np.ndarray
    canonical: np.ndarray
    velocity: np.ndarray
    points: int
    error: float
    loops: np.ndarray

    @property
    def invariant(self) -> np.ndarray:
        """Poincare's integral invariant: the sum of the canonical areas, shape (m,)."""
        return self.canonical.sum(axis=-1)

    @property
    def ratio(self) -> np.ndarray:
        """``invariant(t) / invariant(0)``."""
        return self.invariant / self.invariant[0]


@dataclass(frozen=True)
class _Loop:
    """A carried loop: saved times and states, points along axis 1 in loop order."""

    t: np.ndarray
    theta: np.ndarray
    p: np.ndarray
    omega: np.ndarray

    def areas(self):
        """Projected areas on the ``(theta_i, p_i)`` and ``(theta_i, omega_i)`` planes, (m, n)."""
        theta, p, omega = (np.moveaxis(x, 1, -1) for x in (self.theta, self.p, self.omega))
        return polygon_area(theta, p), polygon_area(theta, omega)

    def interleave(self, other) -> _Loop:
        """This loop's points with ``other``'s between them (``other`` at the midpoints)."""
        merged = []
        for name in ("theta", "p", "omega"):
            a, b = getattr(self, name), getattr(other, name)
            out = np.empty((a.shape[0], 2 * a.shape[1], a.shape[2]))
            out[:, 0::2], out[:, 1::2] = a, b
            merged.append(out)
        return _Loop(self.t, *merged)


def _carry(model, method, states, t_end, dt, save_every) -> _Loop:
    n = model.n
    run = simulate(model, states[:, :n], p0=states[:, n:], t_end=t_end, dt=dt, method=method,
                   save_every=save_every, progress=False)
    if not run.completed:
        raise ValueError(f"{get_method(method).name} blew up on the loop: use a smaller `dt`")
    return _Loop(run.t, run.theta, run.p, run.omega)


def carried_loop_areas(model: PendulumModel, method, center, axes, *, t_end: float, dt: float,
                       save_every: int = 1, tol: float = 1e-11, min_points: int = 64,
                       max_points: int = 16384) -> LoopAreas:
    """Carry a loop of initial states with ``method`` and measure its projected areas.

    Parameters
    ----------
    model : PendulumModel
    method : str or Method
        Any registered method; a high-order one at a small step stands for
        the exact flow.
    center, axes : array_like
        The loop, as in :func:`ellipse_loop` (states in ``(theta, p)``).
    t_end, dt, save_every
        As for :func:`pendulum_lab.simulate`.
    tol : float
        Relative tolerance on the areas, against the largest area seen.
    min_points, max_points : int
        Points on the loop to start with and the most allowed.

    Returns
    -------
    LoopAreas

    Warns
    -----
    RuntimeWarning
        If the areas have not converged with ``max_points`` points (the loop
        is stretched into filaments); ``error`` then says how far off they are.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> areas = carried_loop_areas(pl.simple_pendulum(), "leapfrog", [1.0, 0.0],
    ...                            [[0.2, 0.0], [0.0, 0.4]], t_end=1.0, dt=0.1)
    >>> bool(abs(areas.ratio[-1] - 1) < 1e-10)
    True
    """
    model = require_model(model)
    tol = check.positive_number("tol", tol)
    points = check.integer_at_least("min_points", min_points, 8)
    max_points = check.integer_at_least("max_points", max_points, 2 * points)
    states = ellipse_loop(center, axes, points)
    if states.shape[1] != 2 * model.n:
        raise ValueError(f"`center` must have {2 * model.n} entries (theta and p), "
                         f"got {states.shape[1]}")
    loop = _carry(model, method, states, t_end, dt, save_every)
    coarse, previous, error = loop.areas(), None, np.inf
    while True:
        midpoints = ellipse_loop(center, axes, 2 * points)[1::2]
        loop = loop.interleave(_carry(model, method, midpoints, t_end, dt, save_every))
        points *= 2
        fine = loop.areas()
        estimate = [(4 * f - c) / 3 for f, c in zip(fine, coarse)]  # removes the N^-2 term
        scale = max(np.max(np.abs(a)) for a in fine)
        if previous is not None:
            error = max(np.max(np.abs(e - q)) for e, q in zip(estimate, previous))
            if error <= tol * scale or 2 * points > max_points:
                break
        previous, coarse = estimate, fine
    if error > tol * scale:
        warnings.warn(
            f"loop areas not converged with {points} points (estimated error {error:.1e}, "
            f"tolerance {tol * scale:.1e}): the loop is stretched into filaments; raise "
            "`max_points` or shorten `t_end`",
            RuntimeWarning,
            stacklevel=2,
        )
    loops = np.concatenate([loop.theta, loop.p], axis=-1)
    return LoopAreas(get_method(method).name, float(dt), loop.t, estimate[0], estimate[1],
                     points, float(error), loops)


def jacobian_properties(model: PendulumModel, method, theta, p, dt: float) -> tuple[float, float]:
    """Determinant and symplectic-form defect of one step's Jacobian at ``(theta, p)``.

    The Jacobian is taken by central differences (accurate to about
    ``1e-10``) with :func:`pendulum_lab.analysis.step_jacobian`.

    Returns
    -------
    determinant, defect : float

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> det, defect = jacobian_properties(pl.simple_pendulum(), "explicit_euler", [0.0], [0.0], 0.1)
    >>> round(det, 6)          # 1 + h^2 g / l cos(0)
    1.0981
    """
    model = require_model(model)
    jac = step_jacobian(model, theta, p0=p, dt=dt, method=method)
    return float(np.linalg.det(jac)), symplectic_form_defect(jac)


def jacobian_along_orbit(model: PendulumModel, method, theta0, p0, *, dt: float,
                         steps: int) -> tuple[np.ndarray, np.ndarray]:
    """Determinant and symplectic-form defect of the one-step Jacobian along an orbit.

    The orbit starts at ``(theta0, p0)`` and is computed by the method
    itself; the product of the determinants is the factor by which a small
    blob around the orbit changes its area (or volume).

    Returns
    -------
    determinants, defects : ndarray, shape (steps,)
        At the states ``0 .. steps - 1`` of the orbit.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> det, _ = jacobian_along_orbit(pl.simple_pendulum(), "leapfrog", [1.0], [0.0], dt=0.1,
    ...                               steps=3)
    >>> bool(np.all(np.abs(det - 1) < 1e-8))
    True
    """
    model = require_model(model)
    steps = check.integer_at_least("steps", steps, 1)
    run = simulate(model, theta0, p0=p0, t_end=steps * dt, dt=dt, method=method,
                   progress=False)
    pairs = [jacobian_properties(model, method, q, p, dt)
             for q, p in zip(run.theta[:steps], run.p[:steps])]
    return np.array([d for d, _ in pairs]), np.array([s for _, s in pairs])


# ------------------------------------------------------------------ one step in high precision
def _exact_coefficient(value: float):
    """A tableau entry as an exact number: the small rational it rounds, else its binary value.

    Tableaus are stored in double precision; ``1/6`` is not exactly representable.
    When a fraction with denominator below ``10^6`` rounds to the stored float,
    that fraction is the coefficient the method means.
    """
    fraction = Fraction(value).limit_denominator(10**6)
    if float(fraction) == value:
        return mpmath.mpf(fraction.numerator) / fraction.denominator
    return mpmath.mpf(value)


@functools.cache
def _field_and_jacobian(model: PendulumModel):
    """Hamilton's field ``(H_p, -H_q)`` and its Jacobian as mpmath functions of ``(q, p)``."""
    chain = model.chain
    variables = [*chain.q, *chain.p]
    hamiltonian = model.hamiltonian.xreplace(model.parameter_values)
    field = sp.Matrix([hamiltonian.diff(x) for x in chain.p]
                      + [-hamiltonian.diff(x) for x in chain.q])
    field_fn = sp.lambdify(variables, list(field), modules="mpmath", cse=True)
    jacobian_fn = sp.lambdify(variables, field.jacobian(variables).tolist(), modules="mpmath",
                              cse=True)
    return field_fn, jacobian_fn


def one_step_area_change(model: PendulumModel, method, theta, p, dt: float, *,
                         digits: int = 40) -> np.ndarray:
    """``det DPhi_h - 1`` of one step of an explicit Runge-Kutta method, in high precision.

    A small blob around a state has its area (its volume, for several links)
    multiplied by ``det DPhi_h`` in one step. The Jacobian is propagated
    through the stages exactly (forward-mode differentiation of
    ``k_i = f(y + h sum_j a_ij k_j)``) in ``digits``-digit arithmetic, so the
    result is free of finite-difference and round-off error even where
    ``det - 1`` is far below ``1e-10``. Tableau entries that are double
    roundings of small rationals (``1/6``, ``1/3``) are taken as those rationals.

    Parameters
    ----------
    model : PendulumModel
        An unforced chain.
    method : str or Method
        A registered method with an explicit Butcher tableau
        (``"explicit_euler"``, ``"rk4"``).
    theta, p : array_like, shape (..., n)
        States in canonical variables.
    dt : float
        The step [s].
    digits : int
        Decimal digits of the arithmetic, ``>= 16``.

    Returns
    -------
    ndarray, shape (...)
        ``det DPhi_h - 1`` at each state, rounded to double precision at the end.

    Raises
    ------
    ValueError
        For a method without an explicit tableau (symplectic methods, whose
        determinant is one, are measured with :func:`jacobian_properties`).

    References
    ----------
    HLW, Sect. VI.4 (symplectic Runge-Kutta methods; RK4 is not one) and
    IV.3 (the stability function ``R``: for the harmonic oscillator
    ``det = |R(i w h)|^2 = 1 - (w h)^6 / 72 + (w h)^8 / 576`` for RK4).

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> change = one_step_area_change(pl.simple_pendulum(), "explicit_euler", [0.0], [0.0], 0.1)
    >>> round(float(change), 12)     # h^2 (g/l) cos(theta)
    0.0981
    """
    model = require_model(model)
    if model.forced:
        raise ValueError("`model` must be unforced: the area change of a damped or driven "
                         "step is notebook 17's subject")
    tableau = get_method(method).tableau
    if tableau is None or not tableau.explicit:
        raise ValueError(f"`method` must have an explicit Butcher tableau (explicit_euler, rk4), "
                         f"got {get_method(method).name!r}")
    dt = check.real_number("dt", dt)
    digits = check.integer_at_least("digits", digits, 16)
    theta = check.state_array("theta", theta, model.n)
    p = check.state_array("p", p, model.n)
    check.same_shape("theta", theta, "p", p)
    field, jacobian = _field_and_jacobian(model)
    stages, dim = tableau.stages, 2 * model.n
    states = np.concatenate([theta, p], axis=-1).reshape(-1, dim)
    out = np.empty(len(states))
    with mpmath.workdps(digits):
        a = [[_exact_coefficient(float(x)) for x in row] for row in np.asarray(tableau.a)]
        b = [_exact_coefficient(float(x)) for x in np.asarray(tableau.b)]
        h = mpmath.mpf(dt)
        for index, state in enumerate(states):
            y = mpmath.matrix([mpmath.mpf(float(x)) for x in state])
            slopes, tangents = [], []
            for i in range(stages):
                point, d_point = y.copy(), mpmath.eye(dim)
                for j in range(i):
                    if a[i][j]:
                        point += h * a[i][j] * slopes[j]
                        d_point += h * a[i][j] * tangents[j]
                slopes.append(mpmath.matrix(field(*point)))
                tangents.append(mpmath.matrix(jacobian(*point)) * d_point)
            step_jacobian_exact = mpmath.eye(dim)
            for i in range(stages):
                step_jacobian_exact += h * b[i] * tangents[i]
            out[index] = float(mpmath.det(step_jacobian_exact) - 1)
    return out.reshape(theta.shape[:-1])


# ------------------------------------------------------------------ the 2-form in (theta, omega)
def _canonical_coordinates(model):
    n = model.n
    return lambda z: np.concatenate([z[:n], model.momenta(z[:n], z[n:])])


def velocity_form_defect(model: PendulumModel, method, theta, omega, dt: float, *,
                         delta: float = 1e-6) -> float:
    """How far one step, seen in ``(theta, omega)``, is from keeping the invariant 2-form there.

    The exact flow keeps ``sum_i d theta_i ^ d p_i``. Written in the
    velocities ``omega = M(theta)^-1 p`` that form is
    ``sum_ij M_ij d theta_i ^ d omega_j + sum_ijk (dM_ij/d theta_k) omega_j d theta_k ^ d theta_i``,
    whose matrix is ``Omega(z) = T(z)^T J T(z)`` with ``T`` the Jacobian of
    ``(theta, omega) -> (theta, M(theta) omega)``: its coefficients depend on
    the angles. A map ``Psi`` of ``(theta, omega)`` keeps it when
    ``Psi^T Omega(z1) Psi = Omega(z0)``. For one link ``Omega = m l^2 J``, a
    constant multiple of the constant form ``J``; for two links it is not
    constant, and the constant form ``J`` (what
    :func:`pendulum_lab.analysis.symplecticity_defect` with
    ``variables="velocity"`` measures) is not kept even by the exact flow.

    Parameters
    ----------
    model : PendulumModel
    method : str or Method
    theta, omega : array_like, shape (n,)
        The state the step starts from, in angles and angular velocities.
    dt : float
    delta : float
        Finite-difference increment for both Jacobians.

    Returns
    -------
    float
        ``max |Psi^T Omega(z1) Psi - Omega(z0)|``, with ``Psi``, ``T`` by
        central differences (accurate to about ``1e-9``).

    References
    ----------
    MR, Sect. 7.3; HLW, Sect. VI.2.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> dp = pl.double_pendulum()
    >>> bool(velocity_form_defect(dp, "glrk8", [1.0, 1.5], [0.3, -0.2], 0.05) < 1e-7)
    True
    """
    model = require_model(model)
    theta = check.state_vector("theta", theta, model.n)
    omega = check.state_vector("omega", omega, model.n)
    dt = check.real_number("dt", dt)
    n = model.n

    def one_step(z):
        theta1, p1 = step(model, z[:n], p0=model.momenta(z[:n], z[n:]), dt=dt, method=method)
        return np.concatenate([theta1, model.velocities(theta1, p1)])

    def form(z):
        t = finite_difference_jacobian(_canonical_coordinates(model), z, delta)
        j = np.block([[np.zeros((n, n)), np.eye(n)], [-np.eye(n), np.zeros((n, n))]])
        return t.T @ j @ t

    z0 = np.concatenate([theta, omega])
    psi = finite_difference_jacobian(one_step, z0, delta)
    z1 = one_step(z0)
    return float(np.max(np.abs(psi.T @ form(z1) @ psi - form(z0))))
