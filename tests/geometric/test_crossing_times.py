"""Median first-crossing times of the standard map against K - K_c."""

import subprocess
import sys
import textwrap

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


def test_the_first_call_in_a_process_says_it_prepares_the_loop_and_later_calls_do_not():
    # A fresh process: the crossing counter has no compiled signature yet there.
    code = textwrap.dedent("""
        from pendulum_lab.codegen import compile_status
        from pendulum_lab.geometric import standard_map as sm
        seen = []
        with compile_status.listen(seen.append):
            sm.first_crossings([1.0], [0.1], [0.0], 10)
            first = len(seen)
            sm.first_crossings([1.0], [0.1], [0.0], 10)
        print(first, len(seen), seen[0].what, seen[0].state, seen[-1].state)
    """)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300, check=True)
    first, total, *rest = done.stdout.split()
    assert (first, total) == ("2", "2")  # started and finished, once
    assert "crossing counter" in " ".join(rest) and rest[-2:] == ["started", "finished"]
