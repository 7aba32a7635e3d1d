"""Tangent propagators along a computed trajectory: the variational equations, solved.

A small perturbation ``v`` of a trajectory ``z(t) = (theta, p)`` obeys the
linear equation ``v' = A(t) v``, where ``A = model.jacobian(theta, p, t)`` is
the Jacobian of the model's whole vector field (damping and drive included).
:func:`magnus_propagators` solves it over each step of a trajectory with the
fourth-order Magnus method; :func:`ordered_product` multiplies the step
propagators into the propagator of a longer stretch. The Lyapunov exponents
(:mod:`.lyapunov`) and the Floquet multipliers of periodic orbits
(:mod:`.floquet`) are both built on these two functions.

References
----------
.. [Magnus] S. Blanes, F. Casas, J. A. Oteo, J. Ros, "The Magnus expansion and
   some of its applications", Phys. Rep. 470 (2009) 151-238 (the fourth-order
   method with two Gauss points).
"""

from __future__ import annotations

import numpy as np

from ..driver.events import hermite
from ..driver.simulate import Trajectory
from ..model.pendulum import PendulumModel

__all__ = ["magnus_propagators", "ordered_product"]


def ordered_product(mats: np.ndarray) -> np.ndarray:
    """``M[:, r-1] @ ... @ M[:, 1] @ M[:, 0]`` for ``mats`` of shape ``(B, r, ..., k, k)``.

    Pairwise (tree) reduction: ``log2(r)`` vectorised matrix products
    instead of ``r`` sequential ones. The later factor multiplies from the left.

    Examples
    --------
    >>> a, b = np.array([[1.0, 1.0], [0.0, 1.0]]), np.array([[2.0, 0.0], [0.0, 1.0]])
    >>> ordered_product(np.stack([a, b])[None])[0].tolist()  # b @ a
    [[2.0, 2.0], [0.0, 1.0]]
    """
    while mats.shape[1] > 1:
        if mats.shape[1] % 2:
            eye = np.broadcast_to(np.eye(mats.shape[-1]), mats[:, :1].shape)
            mats = np.concatenate([mats, eye], axis=1)
        mats = mats[:, 1::2] @ mats[:, 0::2]
    return mats[:, 0]


def magnus_propagators(model: PendulumModel, traj: Trajectory, dt: float) -> np.ndarray:
    """Fourth-order Magnus propagators of ``v' = A(t) v`` for each step of ``traj``.

    Over the step ``[t_k, t_k + dt]``

    ``W = dt/2 (A_1 + A_2) + sqrt(3) dt^2 / 12 [A_2, A_1]``,  ``v_{k+1} = exp(W) v_k``,

    with ``A_1``, ``A_2`` the Jacobians at the two Gauss points
    ``t_k + (1/2 -+ sqrt(3)/6) dt`` (the state there from cubic Hermite
    interpolation between the saved steps, :func:`pendulum_lab.driver.events.hermite`,
    accurate to ``O(dt^4)``). The exponential is split as
    ``exp(tr W / 2n) exp(W0)``, ``W0 = W - (tr W / 2n) I``: the scalar factor
    exactly, ``exp(W0)`` by its (2,2) Pade approximant
    ``(I - W0/2 + W0^2/12)^{-1} (I + W0/2 + W0^2/12)``. For a Hamiltonian field
    ``W0`` is a Hamiltonian matrix and the propagator is exactly symplectic;
    for one damped link (``tr A = -gamma``) it contracts areas by exactly
    ``exp(-gamma dt)``. The scheme is fourth order in ``dt``.

    Parameters
    ----------
    model : PendulumModel
        The model whose Jacobian linearises the motion (a family's members
        broadcast over the ensemble axes).
    traj : Trajectory
        Every step saved (``save_every = 1``).
    dt : float
        Its step.

    Returns
    -------
    ndarray, shape (L, ..., 2n, 2n)
        One propagator per step, ``L = len(traj.t) - 1``; ``...`` is the ensemble shape.
    """
    n = traj.theta.shape[-1]
    # A driven field depends on t (shaped to broadcast against the ensemble axes).
    t = traj.t.reshape(-1, *(1,) * (traj.theta.ndim - 2))
    at = (lambda tau: ()) if model.is_autonomous else (lambda tau: (tau,))
    z = np.concatenate([traj.theta, traj.p], axis=-1)
    slope = dt * np.concatenate(model.vector_field(traj.theta, traj.p, *at(t)), axis=-1)
    z0, z1, d0, d1 = z[:-1], z[1:], slope[:-1], slope[1:]
    jacobians = []
    for s in (0.5 - np.sqrt(3) / 6, 0.5 + np.sqrt(3) / 6):
        zs = hermite(s, z0, z1, d0, d1)
        jacobians.append(model.jacobian(zs[..., :n], zs[..., n:], *at(t[:-1] + s * dt)))
    a1, a2 = jacobians
    w = (dt / 2) * (a1 + a2) + (np.sqrt(3) * dt**2 / 12) * (a2 @ a1 - a1 @ a2)
    shift = np.trace(w, axis1=-2, axis2=-1)[..., None, None] / (2 * n)
    eye = np.eye(2 * n)
    w0 = w - shift * eye
    w2 = (w0 @ w0) / 12
    return np.exp(shift) * np.linalg.solve(eye - w0 / 2 + w2, eye + w0 / 2 + w2)
