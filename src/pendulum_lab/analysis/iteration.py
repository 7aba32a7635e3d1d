"""How fast the stage equations of an implicit Runge-Kutta step converge.

An implicit method defines its stage slopes by ``K = F(K)`` with
``F(K)_i = f(y + h sum_j a_ij K_j)``; the library solves this by fixed-point
iteration ``K <- F(K)`` from ``K_i = f(y)``. Near the solution each sweep
multiplies the error by the spectral radius of the iteration's Jacobian
``h (A kron df/dy)``, which is ``h rho(A) rho(df/dy)``: the contraction is
proportional to the step. :func:`stage_contraction` runs the same iteration
in NumPy, records every increment and measures that factor.

References
----------
E. Hairer, G. Wanner, *Solving Ordinary Differential Equations II*, 2nd ed.,
Springer 1996, sect. IV.8 (fixed-point iteration for implicit Runge-Kutta
methods and its contraction).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import validation as check
from ..driver.simulate import canonical_state
from ..integrators import GAUSS4_TABLEAU, ButcherTableau
from ..model.pendulum import PendulumModel

__all__ = ["StageIteration", "stage_contraction"]


@dataclass(frozen=True)
class StageIteration:
    """The fixed-point iteration of one implicit step, sweep by sweep.

    Attributes
    ----------
    increments : ndarray, shape (S,)
        ``max |K^(m+1) - K^m|`` for sweeps ``m = 0 .. S-1``.
    contraction : float
        The measured factor per sweep: the geometric mean of the ratios of
        successive increments while they lie well above round-off (NaN if
        fewer than two such ratios exist).
    predicted : float
        ``h rho(A) rho(df/dy)`` at the initial state.
    dt : float
    """

    increments: np.ndarray
    contraction: float
    predicted: float
    dt: float


def stage_contraction(model: PendulumModel, theta0, omega0=None, *, dt: float,
                      tableau: ButcherTableau = GAUSS4_TABLEAU, p0=None,
                      max_sweeps: int = 60, t0: float = 0.0) -> StageIteration:
    """Run the stage iteration of one step and measure its contraction per sweep.

    The iteration is the library's (``K <- F(K)`` from ``K_i = f(t0 + c_i h, y)``, on
    the vector field in ``(theta, p)`` that the integrators step, forces and
    time included), written out in NumPy so that
    every increment can be recorded; it stops at round-off, when the
    increments grow a million-fold (divergence) or after ``max_sweeps``.

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0, p0 : array_like, shape (n,)
        The state the step starts from (give ``omega0`` or ``p0``).
    dt : float
        Step size [s], ``> 0``.
    tableau : ButcherTableau
        An implicit tableau; two-stage Gauss-Legendre by default.
    max_sweeps : int
        Upper limit of sweeps, ``>= 3``.
    t0 : float
        The time the step starts at [s]; stage ``i`` is evaluated at ``t0 + c_i dt``.

    Returns
    -------
    StageIteration

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> dp = pl.double_pendulum()
    >>> big, small = (stage_contraction(dp, [2.0, 2.5], [0.0, 0.0], dt=h) for h in (0.02, 0.01))
    >>> bool(1.6 < big.contraction / small.contraction < 2.5)   # about 2: proportional to h
    True
    """
    theta0, p0 = canonical_state(model, theta0, omega0, p0, t0=t0)
    if theta0.ndim != 1:
        raise ValueError(f"`theta0` must have shape (n,) (one state), got {theta0.shape}")
    dt = check.positive_number("dt", dt)
    max_sweeps = check.integer_at_least("max_sweeps", max_sweeps, 3)
    if not isinstance(tableau, ButcherTableau):
        raise TypeError(f"`tableau` must be a ButcherTableau, got {type(tableau).__name__}")
    n = model.n
    y = np.concatenate([theta0, p0])

    times = t0 + dt * np.asarray(tableau.c, dtype=float)

    def field(states):
        return np.concatenate(model.vector_field(states[:, :n], states[:, n:], times), axis=1)

    slopes = field(np.tile(y, (tableau.stages, 1)))
    # increments below this are round-off of the slopes
    floor = 1e3 * np.finfo(float).eps * np.max(np.abs(slopes))
    increments = []
    for _ in range(max_sweeps):
        new = field(y + dt * tableau.a @ slopes)
        increments.append(float(np.max(np.abs(new - slopes))))
        slopes = new
        if not np.isfinite(increments[-1]) or increments[-1] <= floor:
            break
        if increments[-1] > 1e6 * increments[0]:
            break  # diverging
    increments = np.array(increments)
    # The dominant eigenvalues of h (A kron df/dy) are complex for Gauss-Legendre
    # tableaus, so the ratio of successive increments oscillates: average the
    # logarithms (a geometric mean) over the sweeps above round-off.
    usable = (increments[:-1] > floor) & (increments[1:] > floor)
    ratios = increments[1:][usable] / increments[:-1][usable]
    contraction = float(np.exp(np.mean(np.log(ratios)))) if ratios.size >= 2 else np.nan
    rho_a = float(np.max(np.abs(np.linalg.eigvals(tableau.a))))
    rho_f = float(np.max(np.abs(np.linalg.eigvals(model.jacobian(theta0, p0, t0)))))
    return StageIteration(increments, contraction, dt * rho_a * rho_f, dt)
