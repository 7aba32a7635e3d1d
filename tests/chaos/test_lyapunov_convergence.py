"""Every Lyapunov estimate says how far it has converged: its running estimate, the estimate
after the first half of the run, and the distance between the two.

The negative control is a regular orbit, whose estimate has not converged to a plateau.
"""

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab import chaos

DP = pl.double_pendulum()
CHAOTIC = ([2.0, 2.5], [0.0, 0.0])
KW = dict(dt=0.01, method="rk4")


@pytest.mark.parametrize("estimator", [chaos.lyapunov_benettin, chaos.lyapunov_variational])
def test_half_run_is_the_estimate_of_a_run_of_half_the_length(estimator):
    full = estimator(DP, *CHAOTIC, t_end=40.0, **KW)
    half = estimator(DP, *CHAOTIC, t_end=20.0, **KW)
    assert full.half_time == half.t[-1] == 20.0
    assert np.isclose(full.half_run, half.exponent, rtol=0, atol=1e-12)
    assert np.isclose(full.half_run_difference, abs(full.exponent - half.exponent), atol=1e-12)


def test_the_spectrum_and_the_energy_scan_carry_the_same_measure():
    full = chaos.lyapunov_spectrum(DP, *CHAOTIC, t_end=40.0, **KW)
    half = chaos.lyapunov_spectrum(DP, *CHAOTIC, t_end=20.0, **KW)
    assert np.allclose(full.half_run, half.exponents, rtol=0, atol=1e-12)
    assert full.half_run_difference.shape == (4,)
    scan = chaos.lyapunov_by_energy(DP, [16.0], orbits=2, t_end=20.0, method="rk4")
    assert scan.half_run.shape == scan.exponent.shape == (2,)
    assert np.all(scan.half_run_difference >= 0)
    assert scan.running.shape == (len(scan.t), 2)
    assert np.array_equal(scan.running[-1], scan.exponent)
    assert np.array_equal(scan.running[len(scan.t) // 2 - 1], scan.half_run)


def test_a_chaotic_estimate_settles_and_a_regular_one_does_not():
    chaotic = chaos.lyapunov_benettin(DP, *CHAOTIC, t_end=100.0, **KW)
    assert chaotic.exponent > 0.5
    assert chaotic.half_run_difference < 0.1 * chaotic.exponent
    # negative control: on a regular orbit the estimate falls like ln(t)/t, so the first
    # half's estimate is about twice the full run's
    regular = chaos.lyapunov_benettin(pl.simple_pendulum(), [1.0], [0.0], t_end=100.0, **KW)
    assert regular.half_run_difference > 0.3 * regular.exponent
    assert 1.3 < regular.half_run / regular.exponent < 2.5


def test_one_record_has_no_half():
    one = chaos.lyapunov_benettin(DP, *CHAOTIC, t_end=0.5, **KW)  # 50 steps: one interval
    assert len(one.t) == 1 and np.isnan(one.half_run) and np.isnan(one.half_time)
