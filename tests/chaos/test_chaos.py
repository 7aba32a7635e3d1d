"""Chaos measurements of the double pendulum checked against known facts.

Each property has a negative control: a case where the same check must fail.
Run lengths are chosen for the compiled core (the whole file takes well under
a minute on two cores).
"""

import dataclasses

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import pendulum_lab as pl
from pendulum_lab import chaos, segments
from pendulum_lab.chaos import flips

DP = pl.double_pendulum()
SP = pl.simple_pendulum()
CHAOTIC = [2.0, 2.5]  # at rest, m = l = 1, g = 9.81: far in the chaotic sea
REST = [0.0, 0.0]


# --------------------------------------------------------------------------- ensembles
def test_ensemble_agrees_with_one_simulate_call_and_keeps_only_what_is_asked():
    theta0 = np.array([[0.1, 0.2], [0.5, -0.3], [1.0, 0.8]])  # regular orbits
    omega0 = np.zeros_like(theta0)
    ref = pl.simulate(DP, theta0, omega0, t_end=30.005, dt=0.01, method="glrk4", save_every=7)
    final = pl.simulate(DP, theta0, omega0, t_end=30.005, dt=0.01, method="glrk4", keep="final")
    thinned = pl.simulate(
        DP, theta0, omega0, t_end=30.005, dt=0.01, method="glrk4", save_every=7
    )
    assert final.t.tolist() == [0.0, pytest.approx(30.0)]
    assert final.theta.shape == (2, 3, 2) and final.energy.shape == (2, 3)
    direct = pl.simulate(DP, theta0, omega0, t_end=30.0, dt=0.01, method="glrk4")
    assert np.max(np.abs(final.theta[-1] - direct.theta[-1])) < 1e-10
    assert np.allclose(thinned.t, ref.t, rtol=0, atol=1e-12)
    assert np.max(np.abs(thinned.theta - ref.theta)) < 1e-10
    assert np.max(np.abs(thinned.p - ref.p)) < 1e-10
    # Negative control: the same comparison at another step size is far off.
    coarse = pl.simulate(DP, theta0, omega0, t_end=30.0, dt=0.02, method="glrk4", keep="final")
    assert np.max(np.abs(coarse.theta[-1] - direct.theta[-1])) > 1e-8


def test_ensemble_rejects_bad_arguments():
    with pytest.raises(ValueError, match="`keep`"):
        pl.simulate(DP, CHAOTIC, REST, t_end=1.0, keep="thinned")
    with pytest.raises(ValueError, match="`save_every`"):
        pl.simulate(DP, CHAOTIC, REST, t_end=1.0, save_every=0)
    with pytest.raises(ValueError, match="`theta0`"):
        pl.simulate(DP, [1.0, 2.0, 3.0], [0.0, 0.0, 0.0], t_end=1.0, keep="final")
    with pytest.raises(TypeError, match="`model`"):
        pl.simulate("double", CHAOTIC, REST, t_end=1.0, keep="final")


# --------------------------------------------------------------------------- separation
def test_nearby_trajectories_separate_exponentially_only_when_chaotic():
    chaotic = chaos.separation(DP, CHAOTIC, REST, t_end=8.0, dt=0.01, method="rk4")
    regular = chaos.separation(DP, [0.1, 0.1], REST, t_end=8.0, dt=0.01, method="rk4")
    assert chaotic.distance[0] == pytest.approx(1e-9, rel=1e-6)
    assert chaotic.distance[-1] / chaotic.delta > 1e3
    assert regular.distance[-1] / regular.delta < 10  # negative control


# --------------------------------------------------------------------------- Lyapunov exponents
def test_benettin_and_variational_agree_on_a_chaotic_orbit():
    benettin = chaos.lyapunov_benettin(DP, CHAOTIC, REST, t_end=50.0, dt=0.01, method="glrk4")
    variational = chaos.lyapunov_variational(DP, CHAOTIC, REST, t_end=50.0, dt=0.01, method="glrk4")
    assert benettin.exponent > 1.0
    assert np.allclose(benettin.t, variational.t)
    # Agreement within 10 % is what the course needs; on the same reference trajectory they
    # agree far better.
    assert abs(variational.exponent / benettin.exponent - 1) < 0.01
    # Negative control: a Jacobian frozen at the hanging equilibrium (the small-angle
    # system) sees no stretching along this orbit, so the same check fails.
    frozen = pl.double_pendulum()
    frozen.jacobian = lambda theta, p: DP.jacobian(np.zeros_like(theta), np.zeros_like(p))
    wrong = chaos.lyapunov_variational(frozen, CHAOTIC, REST, t_end=50.0, dt=0.01, method="glrk4")
    assert abs(wrong.exponent / benettin.exponent - 1) > 0.5


def test_chaotic_exponent_is_positive_and_independent_of_the_integrator():
    # Finite-time exponents of single orbits scatter by about 10 % at T = 100;
    # the mean over 32 starts in the chaotic sea is a property of the sea.
    rng = np.random.default_rng(1)
    theta0 = np.array(CHAOTIC) + 0.1 * rng.uniform(-1, 1, (32, 2))
    omega0 = np.zeros_like(theta0)
    gl = chaos.lyapunov_benettin(DP, theta0, omega0, t_end=100.0, dt=0.01, method="glrk4")
    rk = chaos.lyapunov_benettin(DP, theta0, omega0, t_end=100.0, dt=0.005, method="rk4")
    assert np.all(gl.exponent > 0.5) and np.all(rk.exponent > 0.5)
    assert abs(np.mean(gl.exponent) / np.mean(rk.exponent) - 1) < 0.10


@pytest.mark.parametrize(
    ("model", "theta0"),
    [(SP, [1.0]), (DP, [0.2, -0.1])],
    ids=["simple_pendulum", "small_angle_double"],
)
def test_regular_motion_has_an_exponent_decreasing_towards_zero(model, theta0):
    omega0 = np.zeros_like(theta0)
    benettin = chaos.lyapunov_benettin(model, theta0, omega0, t_end=100.0, dt=0.01, method="glrk4")
    variational = chaos.lyapunov_variational(
        model, theta0, omega0, t_end=100.0, dt=0.01, method="glrk4"
    )
    for est in (benettin, variational):
        assert abs(est.at(100.0)) < abs(est.at(20.0))
        assert abs(est.at(100.0)) < 0.05
    # Negative control: on the chaotic orbit the estimate stays large.
    chaotic = chaos.lyapunov_benettin(DP, CHAOTIC, REST, t_end=100.0, dt=0.01, method="rk4")
    assert chaotic.at(100.0) > 0.5 * chaotic.at(20.0) and chaotic.at(100.0) > 20 * 0.05


def test_lyapunov_rejects_a_run_shorter_than_one_interval():
    with pytest.raises(ValueError, match="`t_end`"):
        chaos.lyapunov_benettin(DP, CHAOTIC, REST, t_end=0.1, dt=0.01, renormalize_every=50)
    with pytest.raises(ValueError, match="`save_every`"):
        chaos.lyapunov_variational(DP, CHAOTIC, REST, t_end=1.0, save_every=0)


# --------------------------------------------------------------------------- Poincare sections
def section_start(energy=-15.0):
    return chaos.section_states(DP, energy, [[0.3], [1.0], [0.0]], [[0.0], [0.0], [1.5]])


def test_section_states_lie_on_the_energy_level_and_cross_upwards():
    theta0, omega0 = section_start()
    assert np.all(theta0[:, 0] == 0.0)
    assert np.max(np.abs(DP.energy(theta0, omega0) + 15.0)) < 1e-12
    assert np.all(omega0[:, 0] > 0)
    down_theta, down_omega = chaos.section_states(DP, -15.0, [[0.3]], [[0.0]], direction=-1)
    assert down_omega[0, 0] < 0 and np.isclose(DP.energy(down_theta, down_omega)[0], -15.0)
    # theta2 = 2.5 needs V(0, 2.5) = -11.8 J > -25 J: unreachable, dropped.
    kept, _ = chaos.section_states(DP, -25.0, [[0.3], [2.5]], [[0.0], [0.0]])
    assert kept.shape == (1, 2)
    with pytest.raises(ValueError, match="`energy`"):
        chaos.section_states(DP, -40.0, [[0.3]], [[0.0]])


def test_poincare_crossings_lie_on_the_surface_to_1e_10():
    theta0, omega0 = section_start()
    sec = chaos.poincare_section(DP, theta0, omega0, t_end=50.0, dt=0.01, method="glrk4")
    assert len(sec.t) > 60 and set(sec.orbit) == {0, 1, 2}
    assert np.max(np.abs(sec.theta[:, 0])) < 1e-10
    assert np.max(sec.residual) < 1e-10
    # Negative control: the nearest step is not on the surface.
    nearest = chaos.poincare_section(
        DP, theta0, omega0, t_end=50.0, dt=0.01, method="glrk4", landing="nearest"
    )
    assert len(nearest.t) == len(sec.t)
    assert np.max(np.abs(nearest.theta[:, 0])) > 1e-10
    assert np.median(nearest.residual) > 1e-5


def test_poincare_crossings_respect_the_direction():
    theta0, omega0 = section_start()
    kwargs = dict(t_end=30.0, dt=0.01, method="rk4")
    up = chaos.poincare_section(DP, theta0, omega0, direction=1, **kwargs)
    down = chaos.poincare_section(DP, theta0, omega0, direction=-1, **kwargs)
    both = chaos.poincare_section(DP, theta0, omega0, direction=0, **kwargs)
    assert np.all(DP.dH_dp(up.theta, up.p)[:, 0] > 0)
    assert np.all(DP.dH_dp(down.theta, down.p)[:, 0] < 0)
    assert len(both.t) == len(up.t) + len(down.t)
    # theta1' > 0 is not the same as p1 > 0 (p1 = 2 theta1' + cos(theta1 - theta2) theta2'):
    # some upward crossings have p1 < 0.
    assert np.any(up.p[:, 0] < 0)
    with pytest.raises(ValueError, match="`direction`"):
        chaos.poincare_section(DP, theta0, omega0, direction=2, **kwargs)


def test_poincare_crossings_agree_with_scipy_event_location():
    theta0, omega0 = section_start()
    y0 = np.concatenate([theta0[0], DP.momenta(theta0[0], omega0[0])])

    def rhs(_t, y):
        return np.concatenate([DP.dH_dp(y[:2], y[2:]), -DP.dH_dq(y[:2], y[2:])])

    def surface(_t, y):  # arm 1 never rotates at E = -15 J: no wrapping needed
        return y[0]

    surface.direction = 1
    sol = solve_ivp(rhs, (0.0, 20.0), y0, method="DOP853", rtol=1e-12, atol=1e-12, events=surface)
    t_ref = sol.t_events[0][sol.t_events[0] > 1e-9]  # the start lies on the surface
    p_ref = sol.y_events[0][sol.t_events[0] > 1e-9, 2:]
    sec = chaos.poincare_section(DP, theta0[:1], omega0[:1], t_end=20.0, dt=0.01, method="glrk4")
    assert len(sec.t) == len(t_ref) > 5
    # As close as GL4 at dt = 0.01 follows the exact flow over 20 s.
    assert np.max(np.abs(sec.t - t_ref)) < 1e-6
    assert np.max(np.abs(sec.p - p_ref)) < 1e-5
    nearest = chaos.poincare_section(
        DP, theta0[:1], omega0[:1], t_end=20.0, dt=0.01, method="glrk4", landing="nearest"
    )
    assert np.max(np.abs(nearest.t - t_ref)) > 1e-4  # negative control


# --------------------------------------------------------------------------- flip-time map
@pytest.mark.parametrize("size", [12, 11])
def test_flip_map_is_symmetric_under_theta_to_minus_theta(size):
    fm = chaos.flip_time_map(DP, size, t_end=4.0, dt=0.01)
    assert fm.time.shape == (size, size)
    assert np.array_equal(fm.theta1, -fm.theta1[::-1])
    assert np.array_equal(fm.time, fm.time[::-1, ::-1])
    assert np.isfinite(fm.time).sum() > size  # some cells flip
    # Negative control: mirroring one angle alone is not a symmetry.
    assert not np.array_equal(fm.time, fm.time[:, ::-1])


def test_flip_map_in_blocks_is_the_map_of_one_ensemble(monkeypatch):
    # Little memory per segment: the whole grid and a block of it then run in segments
    # of different lengths (7 and 111 steps), as a large map's do.
    monkeypatch.setattr(segments, "SEGMENT_FLOATS", 8000)
    whole = chaos.flip_time_map(DP, 14, t_end=2.0)  # 140 cells: one ensemble
    monkeypatch.setattr(flips, "BLOCK_CELLS", 9)
    in_blocks = chaos.flip_time_map(DP, 14, t_end=2.0)  # 16 blocks, the last of 5 cells
    assert np.isfinite(whole.time).sum() > 10  # some cells flip: the map is not trivial
    assert np.array_equal(in_blocks.time, whole.time)
    # Negative control: a longer run flips more cells, so equality is a real check.
    longer = chaos.flip_time_map(DP, 14, t_end=2.5)
    assert not np.array_equal(longer.time, whole.time)


def test_energy_forbidden_cells_are_those_derived_and_never_flip():
    fm = chaos.flip_time_map(DP, 16, t_end=3.0, dt=0.01)
    t1, t2 = np.meshgrid(fm.theta1, fm.theta2)
    # m = l = 1: E = -g (2 cos theta1 + cos theta2) < -g  <=>  2 cos theta1 + cos theta2 > 1.
    assert np.array_equal(fm.forbidden, 2 * np.cos(t1) + np.cos(t2) > 1)
    assert np.all(np.isinf(fm.time[fm.forbidden]))
    # The bound for two uniform rods marks a different set (not this model).
    assert not np.array_equal(fm.forbidden, 3 * np.cos(t1) + np.cos(t2) > 2)
    # Integrate the forbidden cells anyway: no arm ever passes the top.
    theta0 = np.stack([t1[fm.forbidden], t2[fm.forbidden]], axis=-1)
    traj = pl.simulate(
        DP, theta0, np.zeros_like(theta0), t_end=20.0, dt=0.01, method="glrk4", save_every=2
    )
    assert np.max(np.abs(traj.theta)) < np.pi
    # Negative control: started just above the bound, an arm does flip.
    allowed = np.array([[2.0, 2.5], [1.5, 2.9]])
    assert np.all(chaos.can_flip(DP, allowed))
    traj = pl.simulate(DP, allowed, np.zeros_like(allowed), t_end=20.0, dt=0.01, method="glrk4")
    assert np.all(np.max(np.abs(traj.theta), axis=(0, 2)) > np.pi)


def test_can_flip_general_masses_and_lengths():
    model = pl.double_pendulum(m1=2.0, m2=1.0, l1=1.0, l2=0.5, g=9.81)
    # Threshold -g |(m1 + m2) l1 - m2 l2| = -2.5 g; at rest E = -g (3 cos t1 + 0.5 cos t2).
    theta = np.array([[np.arccos(0.99), 0.0], [np.arccos(0.5), 0.0]])  # E = -3.47 g, -2.0 g
    assert chaos.can_flip(model, theta).tolist() == [False, True]
    # At the bottom, E = -3.5 g + 1/2 m2 l2^2 omega2^2: 8 rad/s is too slow, 12 rad/s enough.
    assert chaos.can_flip(model, [[0.0, 0.0]] * 2, [[0.0, 8.0], [0.0, 12.0]]).tolist() == [
        False,
        True,
    ]


def test_flip_map_rejects_bad_arguments():
    with pytest.raises(ValueError, match="`model`"):
        chaos.flip_time_map(SP, 4)
    with pytest.raises(ValueError, match="`half_width`"):
        chaos.flip_time_map(DP, 4, half_width=3.5)
    with pytest.raises(ValueError, match="`size`"):
        chaos.flip_time_map(DP, 0)


# --------------------------------------------------------------------------- small angles
def test_linearised_and_full_motion_part_later_for_smaller_amplitudes():
    amplitudes = np.array([0.001, 0.15, 0.25, 0.4])
    theta0 = amplitudes[:, None] * np.array([1.0, 1.0])
    cmp = chaos.small_angle_comparison(
        DP,
        theta0,
        np.zeros_like(theta0),
        t_end=40.0,
        dt=0.01,
        method="glrk4",
        threshold=0.1,
        relative=True,
    )
    # Tiny amplitude: the nonlinear terms are of order a^3 = 1e-9.
    assert np.max(cmp.difference[:, 0]) < 1e-7
    assert np.isinf(cmp.parting_time[0])
    times = cmp.parting_time[1:]
    assert np.all(np.isfinite(times)) and np.all(np.diff(times) < 0)
    # Frequency shifts of order a^2: parting time of order a^-2.
    slope = np.polyfit(np.log(amplitudes[1:]), np.log(times), 1)[0]
    assert -2.5 < slope < -1.5
    # Negative control: at 0.4 rad the difference is large.
    assert np.max(cmp.difference[:, -1]) > 0.1


# --------------------------------------------------------------------------- per energy
def test_section_spread_lies_on_one_energy_surface():
    theta0, omega0 = chaos.section_spread(DP, 16.0, orbits=7)
    assert theta0.shape == (7, 2) and np.all(theta0[:, 0] == 0.0)
    assert np.max(np.abs(DP.energy(theta0, omega0) - 16.0)) < 1e-12
    # Negative control: releases at rest near (2.0, 2.5) spread over several joules.
    releases = np.array(CHAOTIC) + 0.1 * np.random.default_rng(1).uniform(-1, 1, (16, 2))
    assert np.ptp(DP.energy(releases, np.zeros_like(releases))) > 2.0
    with pytest.raises(ValueError, match="`energy` must lie above"):
        chaos.section_spread(DP, -40.0)
    with pytest.raises(ValueError, match="double pendulum"):
        chaos.section_spread(SP, 1.0)


def test_lyapunov_by_energy_separates_regular_and_chaotic_surfaces():
    scan = chaos.lyapunov_by_energy(DP, [-20.0, 16.0], orbits=4, t_end=60.0, dt=0.01,
                                    method="rk4")
    assert scan.energy.tolist() == [-20.0] * 4 + [16.0] * 4
    assert np.max(np.abs(DP.energy(scan.theta0, scan.omega0) - scan.energy)) < 1e-12
    low, high = scan.per_energy()
    assert low.chaotic == 0 and np.isnan(low.mean)  # tori everywhere at -20 J
    assert high.chaotic == high.orbits == 4 and high.mean > 0.8
    assert high.standard_error < 0.2 * high.mean
    # The same orbits by lyapunov_benettin directly.
    direct = chaos.lyapunov_benettin(DP, scan.theta0, scan.omega0, t_end=60.0, dt=0.01,
                                     method="rk4")
    assert np.array_equal(direct.exponent, scan.exponent)
    # Negative control: a threshold above every estimate calls every orbit regular.
    everything = dataclasses.replace(scan, threshold=10.0)
    assert [row.chaotic for row in everything.per_energy()] == [0, 0]
    with pytest.raises(ValueError, match="`energies` must lie above"):
        chaos.lyapunov_by_energy(DP, [-30.0], t_end=1.0)


def test_separation_between_two_runs():
    one_ulp = [np.nextafter(2.0, 3.0), 2.5]
    assert one_ulp[0] > 2.0 and 2.0 + 1e-16 == 2.0  # a 1e-16 perturbation would be none
    base = pl.simulate(DP, CHAOTIC, REST, t_end=12.0, dt=0.005, method="rk4")
    ulp = chaos.separation_between(base, pl.simulate(DP, one_ulp, REST, t_end=12.0, dt=0.005,
                                                     method="rk4"))
    half = pl.simulate(DP, CHAOTIC, REST, t_end=12.0, dt=0.0025, method="rk4", save_every=2)
    truncation = chaos.separation_between(base, half)
    assert ulp.delta == pytest.approx(4.44e-16, rel=1e-2) and truncation.delta == 0.0
    at_1s = np.searchsorted(base.t, 1.0)
    # after 1 s RK4's truncation error at dt = 0.005 is about 1e-6, far above round-off
    assert 1e-7 < truncation.distance[at_1s] < 1e-5
    assert truncation.distance[at_1s] > 1e6 * ulp.distance[at_1s]
    # both grow: chaos amplifies any difference (negative control: equal runs stay equal)
    assert ulp.distance[-1] > 1e6 * ulp.delta
    assert np.all(chaos.separation_between(base, base).distance == 0.0)
    with pytest.raises(ValueError, match="same times"):
        chaos.separation_between(base, pl.simulate(DP, CHAOTIC, REST, t_end=12.0, dt=0.0025,
                                                   method="rk4"))
