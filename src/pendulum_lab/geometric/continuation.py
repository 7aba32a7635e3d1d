"""The roots of a variational integrator's implicit equation, followed as the step grows.

One step of a variational integrator solves ``p_k = -D_1 L_d(q_k, q_{k+1}; h)``
for ``q_{k+1}`` (:mod:`pendulum_lab.discrete_mechanics`). For small ``h`` the
root the method wants is the one near ``q_k + h M(q_k)^-1 p_k``; as ``h`` grows it
moves along a smooth branch ``q_{k+1}(h)`` until, possibly, the branch turns
back at a *fold* (a saddle-node), where the Jacobian ``dp_k/dq_{k+1}`` is
singular. Beyond the fold's step the small-step root no longer exists, and a
solver can only find roots of other branches.

:func:`variational_root_branch` follows the branch by pseudo-arclength
continuation (Keller): the unknowns are ``x = (q_{k+1}, h)``, each point is
found by Newton's method on the residual plus one arclength condition, so the
branch can be followed through the fold, where continuation in ``h`` alone
would fail. The fold itself is located by Newton's method on the extended
system ``residual = 0, det(dp_k/dq_{k+1}) = 0``.

References
----------
.. [Keller] H. B. Keller, "Numerical solution of bifurcation and nonlinear
   eigenvalue problems", in *Applications of Bifurcation Theory*,
   P. H. Rabinowitz (ed.), Academic Press 1977, 359-384 (pseudo-arclength
   continuation).
.. [Kuznetsov] Yu. A. Kuznetsov, *Elements of Applied Bifurcation Theory*,
   3rd ed., Springer 2004, Sect. 10.2 (continuation of equilibria, detection
   and location of folds).
.. [MW] J. E. Marsden, M. West, "Discrete mechanics and variational
   integrators", Acta Numerica 10 (2001) 357-514, Sect. 1.3.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import sympy as sp

from .. import validation as check
from ..model.pendulum import PendulumModel
from ..symbolic.discrete_mechanics import RULES, discrete_lagrangian
from .model_checks import conservative_model

__all__ = ["RootBranch", "variational_root_branch"]


@functools.cache
def _transform_functions(n: int, rule: str):
    """``-D_1 L_d``, its Jacobian in ``q_{k+1}`` and its derivative in ``h``, for floats."""
    dl = discrete_lagrangian(n, rule)
    args = (*dl.q, *dl.q_next, dl.h, *dl.chain.parameters)
    minus = dl.momentum_minus
    return (sp.lambdify(args, list(minus), cse=True, dummify=True),
            sp.lambdify(args, minus.jacobian(dl.q_next).tolist(), cse=True, dummify=True),
            sp.lambdify(args, list(minus.diff(dl.h)), cse=True, dummify=True))


@dataclass(frozen=True)
class RootBranch:
    """The branch of roots ``q_{k+1}(h)`` that continues the small-step solution.

    Attributes
    ----------
    rule : str
    h : ndarray, shape (m,)
        Steps along the branch, in arclength order (they rise to the fold and,
        beyond it, fall again).
    q_next : ndarray, shape (m, n)
        The roots ``q_{k+1}`` at those points.
    determinant : ndarray, shape (m,)
        ``det(dp_k / dq_{k+1})`` there: it changes sign at the fold.
    fold_h : float
        The step at the fold (``nan`` if the branch did not fold before
        ``h_max``): no root of this branch exists for larger steps.
    fold_q_next : ndarray, shape (n,)
        The root at the fold (``nan`` if none).
    """

    rule: str
    h: np.ndarray
    q_next: np.ndarray
    determinant: np.ndarray
    fold_h: float
    fold_q_next: np.ndarray

    @property
    def folded(self) -> bool:
        """Whether the branch turned back before ``h_max``."""
        return bool(np.isfinite(self.fold_h))

    def roots_at(self, h: float) -> np.ndarray:
        """The branch's roots at step ``h`` (interpolated between neighbouring points).

        Returns an array of shape ``(r, n)``: one root on the way to the fold,
        a second one beyond it when the branch comes back to ``h``.
        """
        h = check.positive_number("h", h)
        roots = []
        for i in range(self.h.size - 1):
            a, b = self.h[i], self.h[i + 1]
            if (a - h) * (b - h) <= 0 and a != b:
                w = (h - a) / (b - a)
                roots.append((1 - w) * self.q_next[i] + w * self.q_next[i + 1])
        return np.array(roots).reshape(-1, self.q_next.shape[1])


def _newton(function, jacobian, x, tol=1e-13, iterations=30):
    for _ in range(iterations):
        update = np.linalg.solve(jacobian(x), function(x))
        x = x - update
        if np.max(np.abs(update)) <= tol * (1 + np.max(np.abs(x))):
            return x
    raise RuntimeError("Newton's method did not converge on the branch: use a smaller `ds`")


def variational_root_branch(model: PendulumModel, rule: str, theta0, p0, *, h_start: float = 0.01,
                            h_max: float = 1.0, h_stop: float | None = None, ds: float = 0.005,
                            max_points: int = 5000) -> RootBranch:
    """Follow the root of ``p0 = -D_1 L_d(theta0, q1; h)`` that continues the small-step one.

    Parameters
    ----------
    model : PendulumModel
        An unforced chain (its parameter values are used).
    rule : {"midpoint", "trapezoid"}
        The discrete Lagrangian of :func:`pendulum_lab.discrete_mechanics.discrete_lagrangian`.
    theta0, p0 : array_like, shape (n,)
        The state the step starts from, in canonical variables.
    h_start : float
        The small step the branch starts at, from Newton's method with the
        guess ``theta0 + h M^-1 p0``.
    h_max : float
        Stop if the branch reaches this step without folding.
    h_stop : float, optional
        After the fold, follow the branch back down until ``h`` falls below
        this (default ``h_start``), to find the roots beyond the fold.
    ds : float
        Arclength increment in ``(q1 [rad], h [s])``.
    max_points : int
        The most points computed.

    Returns
    -------
    RootBranch

    Raises
    ------
    RuntimeError
        If a corrector step does not converge (``ds`` too large for the
        branch's curvature).

    References
    ----------
    Keller; Kuznetsov, Sect. 10.2.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> branch = variational_root_branch(pl.simple_pendulum(), "trapezoid", [0.5], [1.0],
    ...                                  h_max=0.2)
    >>> branch.folded    # one link: the trapezoid equation is explicit in q1, no fold
    False
    """
    model = conservative_model(model, chain=True)
    rule = check.choice("rule", rule, RULES)
    n = model.n
    theta0 = check.state_vector("theta0", theta0, n)
    p0 = check.state_vector("p0", p0, n)
    h_start = check.positive_number("h_start", h_start)
    h_max = check.positive_number("h_max", h_max)
    if h_max <= h_start:
        raise ValueError(f"`h_max` must exceed `h_start` = {h_start}, got {h_max}")
    h_stop = h_start if h_stop is None else check.positive_number("h_stop", h_stop)
    ds = check.positive_number("ds", ds)
    max_points = check.integer_at_least("max_points", max_points, 3)
    minus, jac_q, jac_h = _transform_functions(n, rule)
    dl = discrete_lagrangian(n, rule)
    values = [float(model.parameter_values[s]) for s in dl.chain.parameters]

    def residual(x):
        return np.asarray(minus(*theta0, *x[:n], x[n], *values), float) - p0

    def full_jacobian(x):
        d_q = np.asarray(jac_q(*theta0, *x[:n], x[n], *values), float).reshape(n, n)
        d_h = np.asarray(jac_h(*theta0, *x[:n], x[n], *values), float).reshape(n, 1)
        return np.hstack([d_q, d_h])

    def tangent(x, previous):
        t = np.linalg.svd(full_jacobian(x))[2][-1]
        return -t if t @ previous < 0 else t

    guess = theta0 + h_start * np.linalg.solve(model.mass_matrix_at(theta0), p0)
    q1 = _newton(lambda q: residual(np.append(q, h_start)),
                 lambda q: full_jacobian(np.append(q, h_start))[:, :n], guess)
    x = np.append(q1, h_start)
    t = tangent(x, np.append(np.zeros(n), 1.0))
    points, fold = [x], None
    for _ in range(max_points - 1):
        predicted = x + ds * t

        def extended(y, predicted=predicted, t=t):
            return np.append(residual(y), t @ (y - predicted))

        def extended_jacobian(y, t=t):
            return np.vstack([full_jacobian(y), t])

        x_new = _newton(extended, extended_jacobian, predicted)
        t_new = tangent(x_new, t)
        if fold is None and t[n] > 0 >= t_new[n]:
            fold = _locate_fold(residual, full_jacobian, n, 0.5 * (x + x_new))
        x, t = x_new, t_new
        points.append(x)
        if (fold is None and x[n] >= h_max) or (fold is not None and x[n] <= h_stop):
            break
    points = np.array(points)
    determinants = np.array([np.linalg.det(full_jacobian(y)[:, :n]) for y in points])
    fold_h, fold_q = (fold[n], fold[:n]) if fold is not None else (np.nan, np.full(n, np.nan))
    return RootBranch(rule, points[:, n], points[:, :n], determinants, float(fold_h),
                      np.asarray(fold_q, float))


def _locate_fold(residual, full_jacobian, n, x):
    """Newton on ``(residual, det dp/dq1) = 0`` in ``(q1, h)``, the Jacobian by differences."""

    def system(y):
        return np.append(residual(y), np.linalg.det(full_jacobian(y)[:, :n]))

    def system_jacobian(y, delta=1e-7):
        columns = []
        for k in range(n + 1):
            dy = np.zeros(n + 1)
            dy[k] = delta
            columns.append((system(y + dy) - system(y - dy)) / (2 * delta))
        return np.array(columns).T

    return _newton(system, system_jacobian, x, tol=1e-11)
