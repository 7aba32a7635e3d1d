"""Geometric structure of one step: symplecticity, time reversibility, linear stability.

A step of an integrator is a map ``(theta, p) -> (theta1, p1)``. It is
symplectic when its Jacobian ``Psi`` satisfies ``Psi^T J Psi = J`` and
symmetric (time-reversible) when stepping by ``+h`` then ``-h`` returns to the
start. At the bottom equilibrium ``Psi`` is the step of the linearised
pendulum (a harmonic oscillator per normal mode), and its largest eigenvalue
modulus decides whether small swings stay bounded (linear stability). All are
measured here on the map :func:`pendulum_lab.step` computes, in canonical
variables for every method.

References
----------
E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
Springer 2006, sect. VI.2 (symplectic maps), V.1 (symmetric methods) and I.5
(linear stability of the Stormer-Verlet method); E. Hairer, G. Wanner,
*Solving Ordinary Differential Equations II*, 2nd ed., Springer 1996,
sect. IV.2 (stability functions).
"""

from __future__ import annotations

import math

import numpy as np

from .. import validation as check
from ..driver.simulate import canonical_state, step
from ..model import require_model
from ..model.pendulum import PendulumModel
from .linearization import rest_coordinates

__all__ = [
    "amplification",
    "finite_difference_jacobian",
    "reversibility_error",
    "stability_limit",
    "step_jacobian",
    "symplectic_form_defect",
    "symplecticity_defect",
]


def finite_difference_jacobian(function, z, delta: float = 1e-6) -> np.ndarray:
    """Jacobian of a map ``z -> function(z)`` of ``R^d`` by central differences.

    Accurate to about ``delta^2`` times the third derivatives plus round-off
    over ``delta``. :func:`step_jacobian` applies it to one step of a method;
    use it directly for other maps (a variable step, a reference solver).

    Parameters
    ----------
    function : callable
        ``function(z)`` returns an array of shape ``(m,)`` for ``z`` of shape ``(d,)``.
    z : array_like, shape (d,)
    delta : float
        The increment in each variable, ``> 0``.

    Returns
    -------
    ndarray, shape (m, d)

    Examples
    --------
    >>> finite_difference_jacobian(lambda z: np.array([z[0] * z[1], z[0]]), [2.0, 3.0]).round(8)
    array([[3., 2.],
           [1., 0.]])
    """
    if not callable(function):
        raise TypeError(f"`function` must be callable, got {type(function).__name__}")
    z = np.asarray(z, float)
    if z.ndim != 1:
        raise ValueError(f"`z` must be a 1-d array (one point), got shape {z.shape}")
    delta = check.positive_number("delta", delta)
    columns = []
    for k in range(z.size):
        dz = np.zeros(z.size)
        dz[k] = delta
        columns.append((np.asarray(function(z + dz), float)
                        - np.asarray(function(z - dz), float)) / (2 * delta))
    return np.array(columns).T


def symplectic_form_defect(matrix) -> float:
    """``max |Psi^T J Psi - J|`` for a ``(2n, 2n)`` matrix ``Psi`` in ``(q, p)`` order.

    Zero exactly for a symplectic matrix. A unit determinant is necessary
    but, for ``n >= 2``, not sufficient:

    Examples
    --------
    >>> stretch = np.diag([2.0, 1.0, 1.0, 0.5])   # det 1, but q1 and p1 are not paired
    >>> float(np.linalg.det(stretch)), symplectic_form_defect(stretch)
    (1.0, 1.0)
    """
    psi = np.asarray(matrix, float)
    dim = psi.shape[0] if psi.ndim == 2 else -1
    if psi.shape != (dim, dim) or dim % 2:
        raise ValueError(f"`matrix` must be square of even size (2n, 2n), got shape {psi.shape}")
    n = dim // 2
    j = np.block([[np.zeros((n, n)), np.eye(n)], [-np.eye(n), np.zeros((n, n))]])
    return float(np.max(np.abs(psi.T @ j @ psi - j)))


def step_jacobian(model: PendulumModel, theta0, omega0=None, *, dt: float, method="glrk4",
                  p0=None, eps: float = 1e-6, variables: str = "canonical",
                  t0: float = 0.0) -> np.ndarray:
    """Jacobian of one step ``(theta, p) -> (theta1, p1)`` by central differences.

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0, p0 : array_like, shape (n,)
        The state the step starts from (give ``omega0`` or ``p0``).
    dt : float
        Step size [s].
    method : str or Method
    eps : float
        Finite-difference increment in each of the ``2n`` variables.
    variables : {"canonical", "velocity"}
        The coordinates the step is seen in: ``(theta, p)``, or ``(theta,
        omega)`` with ``omega = M(theta)^-1 p`` (the same map, other
        coordinates; symplectic in both only when ``M`` is constant).
    t0 : float
        The time the step starts at [s] (it matters where the equations
        depend on the time: a drive, a moving pivot).

    Returns
    -------
    ndarray, shape (2n, 2n)

    Examples
    --------
    >>> import numpy as np, pendulum_lab as pl
    >>> jac = step_jacobian(pl.simple_pendulum(), [0.0], [0.0], dt=0.01, method="explicit_euler")
    >>> round(float(np.linalg.det(jac)), 6)  # explicit Euler enlarges areas by 1 + h^2 g
    1.000981
    """
    n = model.n
    theta0, p0 = canonical_state(model, theta0, omega0, p0, t0=t0)
    if theta0.ndim != 1:
        raise ValueError(f"`theta0` must have shape (n,) (one state), got {theta0.shape}")
    if check.choice("variables", variables, ("canonical", "velocity")) == "velocity":

        def one_step(z):
            theta1, p1 = step(model, z[:n], z[n:], dt=dt, method=method, t0=t0)
            return np.concatenate([theta1, model.velocities(theta1, p1, t=t0 + dt)])

        return finite_difference_jacobian(
            one_step, np.concatenate([theta0, model.velocities(theta0, p0, t=t0)]), eps)

    def one_step(z):
        return np.concatenate(step(model, z[:n], p0=z[n:], dt=dt, method=method, t0=t0))

    return finite_difference_jacobian(one_step, np.concatenate([theta0, p0]), eps)


def symplecticity_defect(model: PendulumModel, theta0, omega0=None, *, dt: float,
                         method="glrk4", p0=None, variables: str = "canonical",
                         t0: float = 0.0) -> float:
    """``max |Psi^T J Psi - J|`` for the Jacobian ``Psi`` of one step in ``(theta, p)``.

    Zero (to the finite-difference accuracy, about 1e-10) for a symplectic map.
    Arguments as for :func:`step_jacobian`; with ``variables="velocity"`` the
    step is measured as a map of ``(theta, omega)``.
    """
    return symplectic_form_defect(step_jacobian(model, theta0, omega0, dt=dt, method=method,
                                                p0=p0, variables=variables, t0=t0))


def reversibility_error(model: PendulumModel, theta0, omega0=None, *, dt: float,
                        method="glrk4", p0=None, t0: float = 0.0) -> float:
    """``max |Phi_{-h}(Phi_h(z)) - z|``: zero for a symmetric (time-reversible) method.

    Arguments as for :func:`step_jacobian`; ``z = (theta, p)``. The step back
    starts where the first ended, at ``t0 + dt``.
    """
    q, p = canonical_state(model, theta0, omega0, p0, t0=t0)
    q1, p1 = step(model, q, p0=p, dt=dt, method=method, t0=t0)
    q2, p2 = step(model, q1, p0=p1, dt=-dt, method=method, t0=t0 + dt)
    return float(max(np.max(np.abs(q2 - q)), np.max(np.abs(p2 - p))))


def amplification(model: PendulumModel, dts, *, method="glrk4", eps: float = 1e-3) -> np.ndarray:
    """Largest eigenvalue modulus of one step's Jacobian at the bottom equilibrium.

    Near the bottom the pendulum is a set of harmonic oscillators (its normal
    modes, frequencies ``omega_k``), and one step multiplies each by a fixed
    matrix. Above 1, small swings grow by that factor per step (their energy
    by its square); at most 1, they stay bounded. For a Runge-Kutta method it
    is ``max_k |R(i h omega_k)|`` with the stability function ``R``.

    Parameters
    ----------
    model : PendulumModel
    dts : array_like, shape (N,)
        Step sizes [s]; with one link, ``dts * omega_0`` is the usual ``h omega``.
    method : str or Method
    eps : float
        Finite-difference increment of :func:`step_jacobian`. Too small, and
        the implicit solvers' round-off stopping rule shows in the
        eigenvalues; too large, and the pendulum's nonlinearity does (an
        ``O(eps^2)`` relative effect).

    Returns
    -------
    ndarray, shape (N,)

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> unit = pl.simple_pendulum(length=1.0, g=1.0)  # omega_0 = 1: dt is h omega
    >>> np.round(amplification(unit, [1.0, 3.0], method="leapfrog"), 4)
    array([1.    , 6.8541])
    """
    require_model(model)
    dts = np.atleast_1d(np.asarray(dts, dtype=float))
    rest = rest_coordinates(model)
    factors = [
        np.max(np.abs(np.linalg.eigvals(
            step_jacobian(model, rest, p0=np.zeros(model.n), dt=dt, method=method,
                          eps=eps))))
        for dt in dts
    ]
    return np.array(factors)


def stability_limit(model: PendulumModel, *, method="glrk4", dt_max: float,
                    tolerance: float = 1e-5, points: int = 64) -> float:
    """The largest step [s] for which small swings about the bottom stay bounded.

    Scans :func:`amplification` on ``points`` steps up to ``dt_max`` and
    bisects the first interval where it exceeds ``1 + tolerance`` (the
    tolerance absorbs the finite-difference noise, about 1e-7).

    Parameters
    ----------
    model : PendulumModel
    method : str or Method
    dt_max : float
        Largest step scanned [s]. Implicit methods solved by fixed-point
        iteration stop converging beyond ``h omega`` of about 3.
    tolerance : float
    points : int

    Returns
    -------
    float
        ``0.0`` when even the smallest step scanned amplifies (no stability
        interval, as for explicit Euler); ``math.inf`` when no step up to
        ``dt_max`` does.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> unit = pl.simple_pendulum(length=1.0, g=1.0)
    >>> round(stability_limit(unit, method="rk4", dt_max=3.2), 4)  # 2 sqrt(2)
    2.8284
    """
    dt_max = check.positive_number("dt_max", dt_max)
    points = check.integer_at_least("points", points, 2)

    def unstable(dt):
        return amplification(model, [dt], method=method)[0] > 1.0 + tolerance

    grid = np.linspace(dt_max / points, dt_max, points)
    if unstable(grid[0]):
        return 0.0
    first = next((k for k in range(1, points) if unstable(grid[k])), None)
    if first is None:
        return math.inf
    low, high = grid[first - 1], grid[first]
    for _ in range(60):
        middle = 0.5 * (low + high)
        low, high = (low, middle) if unstable(middle) else (middle, high)
        if high - low <= 1e-12 * high:
            break
    return float(low)
