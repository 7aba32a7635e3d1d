"""Symplectic Euler on the pendulum is the standard map; transport above Greene's K_c."""

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab import step
from pendulum_lab.geometric import standard_map as sm

MODEL = pl.simple_pendulum(mass=0.7, length=1.3, g=9.81)


@pytest.mark.parametrize("h, iterations", [(0.05, 60), (0.2, 60), (0.5, 8)])
def test_symplectic_euler_is_the_standard_map(h, iterations):
    # (at h = 0.5, K = 1.9: the orbits are chaotic and round-off grows, so fewer iterations)
    theta = np.array([0.3, 2.0, -1.0])[:, None]
    p = np.array([1.1, -0.4, 2.5])[:, None]
    phi, action = sm.to_standard_map(MODEL, theta, p, h)
    k = sm.stochasticity_parameter(MODEL, h)
    phis, actions = sm.iterate(phi, action, k, iterations, wrap=False)
    for _ in range(iterations):
        theta, p = step(MODEL, theta, p0=p, dt=h, method="semi_implicit_euler")
    back_theta, back_p = sm.from_standard_map(MODEL, phis[-1], actions[-1], h)
    assert np.max(np.abs(back_theta - theta)) < 1e-11
    assert np.max(np.abs(back_p - p)) < 1e-11 * (1 + np.max(np.abs(p)))
    # negative controls: without the shift by pi, or with K off by 1 %, the orbits part
    unshifted, _ = sm.iterate(phi - np.pi, action, k, iterations, wrap=False)
    assert np.max(np.abs(unshifted[-1] - theta)) > 1e-3
    detuned, _ = sm.iterate(phi, action, 1.01 * k, iterations, wrap=False)
    assert np.max(np.abs(detuned[-1] - np.pi - theta)) > 1e-6


def test_critical_step_translates_greenes_k():
    h = sm.critical_step(MODEL)
    assert sm.stochasticity_parameter(MODEL, h) == pytest.approx(sm.GREENE_K, rel=1e-12)
    assert h == pytest.approx(np.sqrt(sm.GREENE_K * 1.3 / 9.81))


def test_invariant_circles_block_transport_below_greene_but_not_above():
    phi0 = np.geomspace(1e-3, 1e-1, 8)
    below = sm.first_crossings([0.95], phi0, np.zeros(8), 200_000)
    assert np.all(below == -1)
    above = sm.first_crossings([1.5], phi0, np.zeros(8), 200_000)
    assert np.all(above > 0)


def test_finite_time_threshold_decreases_towards_greene():
    result = sm.transport_threshold((100, 1000, 10_000), ks=np.arange(0.95, 2.0, 0.01))
    assert np.all(result.thresholds > sm.GREENE_K)
    assert np.all(np.diff(result.thresholds) < 0)
    assert result.thresholds[-1] < 1.25


def test_the_fastest_orbit_threshold_depends_on_the_number_of_orbits():
    # why the notebook uses the median: with 16 times more orbits the threshold falls
    ks = np.arange(1.0, 1.6, 0.01)
    few = sm.transport_threshold((1000,), ks=ks, orbits=4).thresholds[0]
    many = sm.transport_threshold((1000,), ks=ks, orbits=64).thresholds[0]
    assert many < few


def test_standard_map_bad_input():
    with pytest.raises(ValueError, match="`k`"):
        sm.iterate([0.0], [0.0], -1.0, 3)
    with pytest.raises(ValueError, match="simple pendulum"):
        sm.stochasticity_parameter(pl.double_pendulum(), 0.1)
    with pytest.raises(ValueError, match="`h`"):
        sm.to_standard_map(MODEL, [0.0], [0.0], 0.0)
    with pytest.raises(ValueError, match="`ks`"):
        sm.first_crossings([-1.0], [0.1], [0.0], 10)
    with pytest.raises(ValueError, match="`ks`"):
        sm.transport_threshold((10,), ks=[1.0])
    with pytest.raises(ValueError, match="`phi0`"):
        sm.first_crossings([1.0], [0.0, 1.0], [0.0], 10)
