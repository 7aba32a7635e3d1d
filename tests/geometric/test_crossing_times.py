"""Median first-crossing times of the standard map against K - K_c."""

import numpy as np
import pytest

from pendulum_lab.geometric import standard_map as sm


@pytest.fixture(scope="module")
def crossings():
    return sm.crossing_times(np.geomspace(0.4, 0.1, 4), orbits=64, max_iterations=10**6)


def test_median_grows_like_mmp_law(crossings):
    assert np.all(np.isfinite(crossings.median))
    assert np.all(np.diff(crossings.median) > 0)
    assert -4.0 < crossings.slope < -2.5


def test_median_does_not_drift_with_the_number_of_orbits(crossings):
    halves = crossings.half_medians
    assert np.all(np.abs(np.log(halves[:, 0] / halves[:, 1])) < np.log(2.0))
    # negative control: the fastest orbit is a statistic of the ensemble's size
    assert np.all(crossings.fastest <= crossings.half_fastest.min(axis=1))
    assert np.all(crossings.fastest < 0.5 * crossings.median)


def test_censored_medians_are_unknown():
    short = sm.crossing_times([0.05, 0.5], orbits=16, max_iterations=1000)
    assert np.isnan(short.median[0]) and np.isfinite(short.median[1])
    assert np.isnan(short.slope)  # one known median: no slope


def test_medians_below_greene_do_not_exist():
    phi0 = np.geomspace(1e-3, 1e-1, 8)
    assert np.all(sm.first_crossings([sm.GREENE_K - 0.02], phi0, np.zeros(8), 10**5) == -1)
