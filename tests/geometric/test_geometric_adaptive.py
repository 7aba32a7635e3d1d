"""Adaptive steps: SciPy's drift, the naive leapfrog's lost bound, the reversible leapfrog."""

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab import analysis
from pendulum_lab.geometric import adaptive as ad

SP = pl.simple_pendulum(mass=1.0, length=1.0, g=9.81)


def test_scipy_energy_error_drifts():
    run = analysis.scipy_run(SP, [2.5], [0.0], t_end=100.0, method="RK45", rtol=1e-6)
    first, last = run.largest_error(0, 10), run.largest_error(90, 100)
    assert last > 3 * first
    assert abs(run.drift) * 100 > 0.5 * last  # the error is mostly a linear drift


def test_reversible_adaptive_leapfrog_keeps_the_energy_bounded():
    run = ad.reversible_adaptive_leapfrog(SP, [2.5], [0.0], t_end=60.0, epsilon=0.1)
    first, last = run.largest_error(0, 6), run.largest_error(54, 60)
    assert abs(last / first - 1) < 0.05
    sizes = run.step_sizes
    assert sizes.max() > 1.8 * sizes.min()  # it adapts: about epsilon at rest, less when fast
    # negative control: the naive controller loses the bound at a similar number of steps
    naive = ad.naive_adaptive_leapfrog(SP, [2.5], [0.0], t_end=60.0, tol=1e-2)
    assert naive.largest_error(54, 60) > 2 * naive.largest_error(0, 6)


def test_steps_follow_the_speed():
    run = ad.reversible_adaptive_leapfrog(SP, [2.5], [0.0], t_end=5.0, epsilon=0.05)
    sigma = ad.step_density(SP, run.theta[:-1], run.p[:-1])[0]
    assert np.max(np.abs(run.step_sizes / (0.05 * sigma) - 1)) < 0.05


def test_reversibility_of_the_sundman_method_and_not_of_the_naive_one():
    assert ad.round_trip_error(SP, "reversible", [2.5], [0.0], steps=200, epsilon=0.05) < 1e-10
    assert ad.round_trip_error(SP, "naive", [2.5], [0.0], steps=200, tol=1e-3) > 1e-6


def test_adaptive_bad_input():
    with pytest.raises(ValueError, match="`method`"):
        analysis.scipy_run(SP, [1.0], [0.0], t_end=1.0, method="LSODA")
    with pytest.raises(ValueError, match="`rtol`"):
        analysis.scipy_run(SP, [1.0], [0.0], t_end=1.0, rtol=1.0)
    with pytest.raises(ValueError, match="`epsilon`"):
        ad.reversible_adaptive_leapfrog(SP, [1.0], [0.0], t_end=1.0, epsilon=-0.1)
    with pytest.raises(ValueError, match="`method`"):
        ad.round_trip_error(SP, "adaptive", [1.0], [0.0], steps=3)
    with pytest.raises(ValueError, match="shape"):
        ad.naive_adaptive_leapfrog(SP, [[1.0]], [[0.0]], t_end=1.0, tol=1e-3)


def test_a_state_dependent_step_is_not_symplectic():
    variable, frozen = ad.state_dependent_step_defect(SP, [2.0], [1.0], epsilon=0.1)
    assert variable > 1e-3
    assert frozen < 1e-8  # negative control: the same step, frozen, is symplectic


def test_poincare_transform_keeps_the_energy_bounded_with_variable_steps():
    run = ad.poincare_adaptive_midpoint(SP, [2.5], [0.0], t_end=60.0, epsilon=0.1)
    first, last = run.largest_error(0, 6), run.largest_error(54, 60)
    assert abs(last / first - 1) < 0.05
    assert run.step_sizes.max() > 1.8 * run.step_sizes.min()
    # the steps follow sigma: epsilon at rest, smaller at speed
    assert abs(run.step_sizes.max() / 0.1 - 1) < 0.01


def test_poincare_transform_bad_input():
    with pytest.raises(ValueError, match="1 or 2 links"):
        ad.poincare_adaptive_midpoint(pl.n_pendulum(3), [0.1] * 3, [0.0] * 3, t_end=1.0,
                                      epsilon=0.1)
