"""RK4's energy drift from its modified equation: RK4 has a modified *equation* but no
modified Hamiltonian; its first term with non-zero divergence (:func:`first_dissipative_term`)
predicts the rate of its energy drift (:func:`mean_energy_rate`), which :func:`energy_drift`
measures."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import sympy as sp

from .. import validation as check
from ..analysis import exact_period
from ..driver.simulate import simulate
from ..integrators import get_method
from ..model.pendulum import PendulumModel
from ..symbolic.mechanics import is_identically_zero
from .long_time import exact_libration
from .model_checks import conservative_model
from .modified_energy import hamiltonian_function
from .modified_hamiltonians import MAX_FIELD_ORDER, checked_order, modified_equation

__all__ = ["DissipativeTerm", "EnergyDrift", "energy_drift", "first_dissipative_term",
           "mean_energy_rate"]


@dataclass(frozen=True)
class DissipativeTerm:
    """The first term of a modified equation whose divergence is not identically zero.

    Attributes
    ----------
    power : int
        It multiplies ``h^power``.
    field : sympy.Matrix, shape (2, 1)
        ``f_{power+1}``.
    divergence : sympy.Expr
        Its divergence, simplified (parameters symbolic).
    energy_rate : sympy.Expr
        ``grad H . f_{power+1}``: its contribution to ``dH/dt`` (times ``h^power``).
    divergence_free_powers : tuple of int
        The earlier non-zero terms, each shown divergence-free.
    """

    power: int
    field: sp.Matrix
    divergence: sp.Expr
    energy_rate: sp.Expr
    divergence_free_powers: tuple


def first_dissipative_term(model: PendulumModel, method, max_power: int = 6) -> DissipativeTerm:
    """Find the first term of ``method``'s modified equation with non-zero divergence.

    A divergence-free term changes no area, and over a closed orbit its
    ``grad H . f`` integrates to the flux through the orbit, which is zero;
    the first term with non-zero divergence sets the energy drift.

    Raises
    ------
    ValueError
        If every term up to ``h^max_power`` is divergence-free (a symplectic
        method, or too small ``max_power``).

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> first_dissipative_term(pl.simple_pendulum(), "explicit_euler").power
    1
    """
    model = conservative_model(model, (1,), chain=True)
    max_power = checked_order(max_power, MAX_FIELD_ORDER - 1, "for the modified equation")
    theta, p = model.chain.q[0], model.chain.p[0]
    fields = modified_equation(model, method, max_power)
    quiet = []
    for power, field in enumerate(fields[1:], start=1):
        if field == sp.zeros(2, 1):
            continue
        divergence = sp.diff(field[0], theta) + sp.diff(field[1], p)
        if is_identically_zero(divergence):
            quiet.append(power)
            continue
        h_theta, h_p = (sp.diff(model.hamiltonian, x) for x in (theta, p))
        # factor_terms, not factor: SymPy's multivariate factorization picks random
        # evaluation points and now and then takes many minutes here (seen in CI)
        return DissipativeTerm(power, field, sp.factor_terms(divergence),
                               sp.factor_terms(h_theta * field[0] + h_p * field[1]),
                               tuple(quiet))
    raise ValueError(f"every term of {get_method(method).name!r}'s modified equation up to "
                     f"h^{max_power} is divergence-free (a symplectic method has no such term)")


@dataclass(frozen=True)
class EnergyDrift:
    """Measured and predicted energy drift rates of a non-symplectic method.

    Attributes
    ----------
    method : str
    amplitude : float
    dts : ndarray, shape (m,)
    measured : ndarray, shape (m,)
        Slope of a least-squares line through ``H(t) - H(0)`` [J/s].
    predicted : ndarray, shape (m,)
        ``h^P <grad H . f_{P+1}>``, the orbit average over the exact libration.
    power : int
        ``P``, from :func:`first_dissipative_term`.
    measured_exponent : float
        Slope of ``log |measured|`` against ``log h``; theory: ``P``.
    t_end : float
    """

    method: str
    amplitude: float
    dts: np.ndarray
    measured: np.ndarray
    predicted: np.ndarray
    power: int
    measured_exponent: float
    t_end: float


def mean_energy_rate(model: PendulumModel, method, amplitude: float, power: int) -> float:
    """The orbit average of ``grad H . f_{power+1}``: what the ``h^power`` term does to the energy.

    Along the modified equation ``y' = f + h f_2 + ...`` the energy changes at
    the rate ``sum_j h^j grad H . f_{j+1}``; averaged over one period of the
    exact libration released at rest from ``amplitude`` (512 equally spaced
    times, the trapezoidal rule of a periodic function), the term ``h^power``
    contributes ``h^power`` times the number returned [J/s per s^power].

    Parameters
    ----------
    model : PendulumModel
        A simple pendulum.
    method : str or Method
        Any method :func:`modified_equation` expands.
    amplitude : float
        Release angle at rest, ``0 < |amplitude| < pi`` [rad].
    power : int
        ``1 <= power <= 6``.

    Returns
    -------
    float

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> rate = mean_energy_rate(pl.simple_pendulum(), "leapfrog", 1.0, 2)
    >>> bool(abs(rate) < 1e-12)      # a symplectic method's terms do not drain energy
    True
    """
    model = conservative_model(model, (1,), chain=True)
    power = checked_order(power, MAX_FIELD_ORDER - 1, "for the modified equation")
    if power < 1:
        raise ValueError("`power` must be >= 1 (power 0 is Hamilton's field, which keeps H)")
    field = modified_equation(model, method, power)[power]
    theta, p = model.chain.q[0], model.chain.p[0]
    rate = sp.diff(model.hamiltonian, theta) * field[0] + sp.diff(model.hamiltonian, p) * field[1]
    return _libration_mean(model, amplitude, rate)


def _libration_mean(model, amplitude, expr) -> float:
    """The mean of ``expr(theta, p)`` over one period of the exact libration from ``amplitude``."""
    period = exact_period(model, amplitude)
    theta, p = exact_libration(model, amplitude, np.arange(512) * period / 512)
    return float(np.mean(hamiltonian_function(model, expr)(theta, p, 0.0)))


def energy_drift(model: PendulumModel, method, amplitude: float, *, dts,
                 t_end: float) -> EnergyDrift:
    """Compare a method's measured energy drift rate with its modified equation's prediction.

    The prediction averages ``grad H . f_{P+1}`` over one period of the exact
    libration (512 equally spaced times: the trapezoidal rule of a periodic
    function, accurate to round-off) and multiplies by ``h^P``.

    Parameters
    ----------
    model : PendulumModel
        A simple pendulum.
    method : str or Method
        A method with a dissipative term (``rk4``, ``explicit_euler``).
    amplitude : float
        Release angle at rest [rad].
    dts : sequence of float
    t_end : float
        Length of each run; long enough for the drift to dominate the
        oscillation of ``H``.
    """
    term = first_dissipative_term(model, method)
    t_end = check.positive_number("t_end", t_end)
    dts = np.asarray([check.positive_number("dts", dt) for dt in dts])
    if dts.size < 2:
        raise ValueError(f"`dts` must hold at least two step sizes (for the exponent), got "
                         f"{dts.size}")
    coefficient = _libration_mean(model, amplitude, term.energy_rate)
    measured = []
    for dt in dts:
        run = simulate(model, [amplitude], [0.0], t_end=t_end, dt=dt, method=get_method(method),
                       save_every=max(1, int(round(0.05 / dt))))
        measured.append(np.polyfit(run.t, run.energy_error, 1)[0])
    measured = np.asarray(measured)
    exponent = float(np.polyfit(np.log(dts), np.log(np.abs(measured)), 1)[0])
    return EnergyDrift(get_method(method).name, float(amplitude), dts, measured,
                       coefficient * dts**term.power, term.power, exponent, t_end)
