"""The step ratio of the time transformations; wandering energy levels on chaotic motion."""

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab.geometric import adaptive

SP = pl.simple_pendulum(mass=1.0, length=1.0, g=9.81)
DP = pl.double_pendulum(m1=1.0, m2=1.0, l1=1.0, l2=1.0, g=9.81)


@pytest.mark.parametrize("amplitude", [1.0, 2.5, 3.1])
def test_step_ratio_of_a_libration_follows_sigma(amplitude):
    run = adaptive.reversible_adaptive_leapfrog(SP, [amplitude], [0.0], t_end=20.0, epsilon=0.05)
    measured = run.step_sizes.max() / run.step_sizes.min()
    predicted = adaptive.libration_step_ratio(SP, amplitude)
    assert measured == pytest.approx(predicted, rel=5e-3)
    assert predicted < np.sqrt(5)
    poincare = adaptive.poincare_adaptive_midpoint(SP, [amplitude], [0.0], t_end=5.0,
                                                   epsilon=0.05)
    assert poincare.step_sizes.max() / poincare.step_sizes.min() == pytest.approx(
        predicted, rel=5e-3)


def test_the_separatrix_bounds_every_libration():
    assert adaptive.libration_step_ratio(SP, np.pi) == pytest.approx(np.sqrt(5), rel=1e-14)
    ratios = [adaptive.libration_step_ratio(SP, a) for a in np.linspace(0.1, np.pi, 20)]
    assert np.all(np.diff(ratios) > 0)
    # negative control: the bound belongs to this sigma; with w = w0 / 2 a libration exceeds it
    slower = 0.5 * np.sqrt(9.81)
    run = adaptive.reversible_adaptive_leapfrog(SP, [3.1], [0.0], t_end=20.0, epsilon=0.05,
                                                frequency=slower)
    assert run.step_sizes.max() / run.step_sizes.min() > np.sqrt(5)
    assert adaptive.libration_step_ratio(SP, 3.1, frequency=slower) == pytest.approx(
        run.step_sizes.max() / run.step_sizes.min(), rel=1e-2)
    with pytest.raises(ValueError, match="`amplitude`"):
        adaptive.libration_step_ratio(SP, 3.5)
    with pytest.raises(ValueError, match="simple pendulum"):
        adaptive.libration_step_ratio(DP, 1.0)


def test_window_means():
    t = np.linspace(0.0, 10.0, 101)
    assert adaptive.window_means(t, np.ones_like(t), 2.0).tolist() == [1.0] * 5
    ramp = adaptive.window_means(t, t, 5.0)
    assert ramp == pytest.approx([2.45, 7.45], abs=1e-9)  # windows [a, a + width)
    assert adaptive.window_means(t, t, 5.0, t_end=5.0) == pytest.approx([2.45])
    with pytest.raises(ValueError, match="`t` and `error`"):
        adaptive.window_means(t, t[:-1], 1.0)


def test_levels_wander_on_chaotic_motion_not_on_regular_motion():
    spreads = adaptive.level_spreads(DP, [[2.0, 2.5], [0.4, 0.6]], lengths=(40.0, 80.0),
                                     epsilon=0.05, width=10.0)
    chaotic, regular = spreads.reversible
    assert chaotic[1] >= chaotic[0] > 0.05
    assert regular[1] < 0.01  # negative control: the same measure on a regular orbit
    assert spreads.fixed.shape == (2, 2) and np.all(spreads.steps > 0)
    with pytest.raises(ValueError, match="`lengths`"):
        adaptive.level_spreads(DP, [[2.0, 2.5]], lengths=(10.0,), epsilon=0.05, width=10.0)
