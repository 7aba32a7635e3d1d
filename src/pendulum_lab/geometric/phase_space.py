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
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from .. import validation as check
from ..analysis import step_jacobian, symplectic_form_defect
from ..driver.simulate import simulate
from ..integrators import get_method
from ..model import require_model
from ..model.pendulum import PendulumModel

__all__ = [
    "LoopAreas",
    "carried_loop_areas",
    "ellipse_loop",
    "jacobian_along_orbit",
    "jacobian_properties",
    "polygon_area",
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
