"""Geometric structure of one step: symplecticity and time reversibility.

A step of an integrator is a map ``(theta, p) -> (theta1, p1)``. It is
symplectic when its Jacobian ``Psi`` satisfies ``Psi^T J Psi = J`` and
symmetric (time-reversible) when stepping by ``+h`` then ``-h`` returns to the
start. Both are measured here on the map :func:`pendulum_lab.step` computes,
in canonical variables for every method.

References
----------
E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
Springer 2006, sect. VI.2 (symplectic maps) and V.1 (symmetric methods).
"""

from __future__ import annotations

import numpy as np

from ..model import PendulumModel
from ..simulate import canonical_state, step

__all__ = ["reversibility_error", "step_jacobian", "symplecticity_defect"]


def _canonical_j(n: int) -> np.ndarray:
    return np.block([[np.zeros((n, n)), np.eye(n)], [-np.eye(n), np.zeros((n, n))]])


def step_jacobian(model: PendulumModel, theta0, omega0=None, *, dt: float, method="glrk4",
                  p0=None, eps: float = 1e-6) -> np.ndarray:
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
    theta0, p0 = canonical_state(model, theta0, omega0, p0)
    z = np.concatenate([theta0, p0])
    jac = np.empty((2 * n, 2 * n))
    for k in range(2 * n):
        dz = np.zeros(2 * n)
        dz[k] = eps
        plus = np.concatenate(step(model, (z + dz)[:n], p0=(z + dz)[n:], dt=dt, method=method))
        minus = np.concatenate(step(model, (z - dz)[:n], p0=(z - dz)[n:], dt=dt, method=method))
        jac[:, k] = (plus - minus) / (2 * eps)
    return jac


def symplecticity_defect(model: PendulumModel, theta0, omega0=None, *, dt: float,
                         method="glrk4", p0=None) -> float:
    """``max |Psi^T J Psi - J|`` for the Jacobian ``Psi`` of one step in ``(theta, p)``.

    Zero (to the finite-difference accuracy, about 1e-10) for a symplectic map.
    Arguments as for :func:`step_jacobian`.
    """
    psi = step_jacobian(model, theta0, omega0, dt=dt, method=method, p0=p0)
    j = _canonical_j(model.n)
    return float(np.max(np.abs(psi.T @ j @ psi - j)))


def reversibility_error(model: PendulumModel, theta0, omega0=None, *, dt: float,
                        method="glrk4", p0=None) -> float:
    """``max |Phi_{-h}(Phi_h(z)) - z|``: zero for a symmetric (time-reversible) method.

    Arguments as for :func:`step_jacobian`; ``z = (theta, p)``.
    """
    q, p = canonical_state(model, theta0, omega0, p0)
    q1, p1 = step(model, q, p0=p, dt=dt, method=method)
    q2, p2 = step(model, q1, p0=p1, dt=-dt, method=method)
    return float(max(np.max(np.abs(q2 - q)), np.max(np.abs(p2 - p))))
