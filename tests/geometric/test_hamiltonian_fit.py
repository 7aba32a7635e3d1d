"""Fitting Hamiltonians to modified equations; the energy each term drains on average."""

import numpy as np
import pytest
import sympy as sp

import pendulum_lab as pl
from pendulum_lab.geometric import backward_error as be

SP = pl.simple_pendulum(mass=1.0, length=1.0, g=9.81)


@pytest.mark.parametrize("separable", [True, False])
def test_symplectic_methods_fit_at_every_power(separable):
    assert be.hamiltonian_fit("semi_implicit_euler", 3, separable=separable).outcomes == (
        "fitted", "fitted", "fitted")
    leapfrog = be.hamiltonian_fit("leapfrog", 4, separable=separable)
    assert leapfrog.outcomes == ("zero", "fitted", "zero", "fitted")
    assert leapfrog.first_failure is None and leapfrog.message == ""


@pytest.mark.parametrize("separable", [True, False])
def test_explicit_euler_and_rk4_fail_the_fit(separable):
    euler = be.hamiltonian_fit("explicit_euler", 2, separable=separable)
    assert euler.first_failure == 1 and "not Hamiltonian" in euler.message
    rk4 = be.hamiltonian_fit("rk4", 4, separable=separable)
    assert rk4.outcomes == ("zero", "zero", "zero", "no fit") and rk4.first_failure == 4


def test_fitted_terms_are_the_modified_hamiltonians():
    fit = be.hamiltonian_fit("semi_implicit_euler", 2)
    general = be.generic_modified_hamiltonian("semi_implicit_euler", 2)
    h = be.STEP_SIZE
    assert sp.expand(general - (general.coeff(h, 0) + h * fit.hamiltonians[0]
                                + h**2 * fit.hamiltonians[1])) == 0


def test_rk4_energy_rates_by_power():
    # h^4: divergence-free, no drain; h^5: the drift; h^6: odd under p -> -p, averages out
    assert abs(be.mean_energy_rate(SP, "rk4", 1.5, 4)) < 1e-12
    assert be.mean_energy_rate(SP, "rk4", 1.5, 5) < -60
    assert abs(be.mean_energy_rate(SP, "rk4", 1.5, 6)) < 1e-10
    # small swings: (1/E) dE/dt -> -w0^6 h^5 / 72, E above the bottom
    amplitude = 0.05
    energy = 9.81 * (1 - np.cos(amplitude))
    ratio = be.mean_energy_rate(SP, "rk4", amplitude, 5) / energy
    assert ratio == pytest.approx(-(9.81**3) / 72, rel=2e-3)
    # negative control: explicit Euler gains energy at its first power
    assert be.mean_energy_rate(SP, "explicit_euler", 1.5, 1) > 0


def test_energy_drift_uses_the_same_average():
    drift = be.energy_drift(SP, "rk4", 1.5, dts=(0.1, 0.07), t_end=40.0)
    coefficient = be.mean_energy_rate(SP, "rk4", 1.5, 5)
    np.testing.assert_allclose(drift.predicted, coefficient * drift.dts**5, rtol=1e-12)


def test_bad_input():
    with pytest.raises(ValueError, match="`method`"):
        be.hamiltonian_fit("glrk8", 2)
    with pytest.raises(ValueError, match="`max_power`"):
        be.hamiltonian_fit("rk4", 5)
    with pytest.raises(ValueError, match="`power`"):
        be.mean_energy_rate(SP, "rk4", 1.0, 0)
    with pytest.raises(ValueError, match="simple pendulum"):
        be.mean_energy_rate(pl.double_pendulum(), "rk4", 1.0, 5)
