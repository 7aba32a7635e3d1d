"""Periodic orbits of the driven pendulum by shooting, their multipliers and bifurcations.

Each property is checked with a negative control that fails the same check.
"""

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab import chaos

DRIVEN = pl.driven_pendulum()  # Baker and Gollub: q = 2, Omega = 2/3
T = DRIVEN.drive_period
GAMMA = DRIVEN.conformal_damping_rate
CALM = DRIVEN.replace(drive_amplitude=0.9)  # a symmetric period-1 attractor
BEFORE_FLIP = DRIVEN.replace(drive_amplitude=1.06)  # an asymmetric period-1 attractor
STEPS = 400


def orbit_at(model, theta=(-0.25,), omega=(1.97,), **kwargs):
    return chaos.periodic_orbit(model, list(theta), list(omega), **kwargs)


def period_map_jacobian(model, orbit, eps=1e-6):
    """``DP`` at the orbit's point by central differences of pl.simulate (no tangent)."""
    z = np.concatenate([orbit.theta[0], orbit.p[0]])
    shifts = np.concatenate([np.eye(2), -np.eye(2)]) * eps
    starts = z + shifts
    run = pl.simulate(model, starts[:, :1], p0=starts[:, 1:], t_end=T, dt=T / STEPS,
                      method="rk4", keep="final")
    end = np.concatenate([run.theta[-1], run.p[-1]], axis=-1)
    return ((end[:2] - end[2:]) / (2 * eps)).T


def test_the_orbit_closes_and_is_the_attractor_a_long_run_finds():
    orbit = orbit_at(BEFORE_FLIP)
    assert orbit.residual < 1e-11 and orbit.periods == 1 and orbit.turns.tolist() == [0]
    settled = chaos.stroboscopic_section(BEFORE_FLIP, [0.0], [0.0], n_periods=1,
                                         transient_periods=400, steps_per_period=STEPS)
    assert np.allclose(settled.theta[-1], orbit.theta[0], atol=1e-8)
    assert np.allclose(settled.p[-1], orbit.p[0], atol=1e-8)
    # negative control: a point off the orbit does not close after one period
    run = pl.simulate(BEFORE_FLIP, orbit.theta[0] + 0.01, p0=orbit.p[0], t_end=T, dt=T / STEPS,
                      method="rk4", keep="final")
    assert abs(run.theta[-1, 0] - orbit.theta[0, 0]) > 1e-4


def test_monodromy_matches_the_period_map_differentiated_numerically():
    orbit = orbit_at(BEFORE_FLIP)
    numeric = period_map_jacobian(BEFORE_FLIP, orbit)
    # both approximate the flow's derivative to O(dt^4): (T / 400)^4 = 3e-7
    assert np.allclose(orbit.monodromy, numeric, rtol=0, atol=(T / STEPS) ** 4 * 10)
    # negative control: the orbit of a drive 0.2 % stronger has a visibly different derivative
    other = orbit_at(DRIVEN.replace(drive_amplitude=1.062), orbit.theta[0], orbit.omega[0])
    assert not np.allclose(other.monodromy, numeric, atol=1e-2)


def test_one_damped_link_contracts_areas_by_exp_minus_gamma_t_per_period():
    for model, theta, omega in ((CALM, (-0.56,), (1.93,)), (BEFORE_FLIP, (-0.25,), (1.97,))):
        orbit = orbit_at(model, theta, omega)
        assert np.isclose(np.prod(orbit.multipliers).real, np.exp(-GAMMA * T), rtol=1e-10)
        assert np.isclose(orbit.exponents.sum(), -GAMMA, rtol=1e-10)
    # complex multipliers have the same modulus; real ones do not
    calm = orbit_at(CALM, (-0.56,), (1.93,))
    assert np.allclose(np.abs(calm.multipliers), np.exp(-GAMMA * T / 2), rtol=1e-10)
    before = orbit_at(BEFORE_FLIP)
    assert np.all(np.isreal(before.multipliers))
    assert abs(np.abs(before.multipliers[0]) - np.exp(-GAMMA * T / 2)) > 0.5


def test_shooting_finds_an_unstable_orbit_that_a_run_leaves():
    past = DRIVEN.replace(drive_amplitude=1.07)  # past the first flip
    orbit = orbit_at(past)
    assert not orbit.stable and orbit.multipliers[0].real < -1
    nudged = chaos.stroboscopic_section(past, orbit.theta[0] + 1e-6, p0=orbit.p[0],
                                        n_periods=32, transient_periods=200,
                                        steps_per_period=STEPS)
    assert int(nudged.periods()) == 2
    assert np.max(np.abs(nudged.theta[-1] - orbit.theta[0])) > 1e-2


def test_the_flip_is_where_the_multiplier_is_minus_one_and_period_two_is_born():
    flip = chaos.locate_bifurcation(DRIVEN, "drive_amplitude", (1.06, 1.07), [-0.25], [1.97],
                                    steps_per_period=STEPS)
    assert flip.kind == "period doubling"
    assert abs(flip.orbit.crossing(-1)) < 1e-9
    assert np.isclose(flip.orbit.multipliers[0].real, -1.0, atol=1e-8)
    below = orbit_at(DRIVEN.replace(drive_amplitude=flip.value - 1e-4))
    above = orbit_at(DRIVEN.replace(drive_amplitude=flip.value + 1e-4))
    assert below.stable and not above.stable
    # negative control: no flip between 0.9 and 1.0, and the search says so
    with pytest.raises(ValueError, match="no multiplier"):
        chaos.locate_bifurcation(DRIVEN, "drive_amplitude", (0.9, 0.95), [-0.56], [1.93],
                                 steps_per_period=STEPS)


def test_the_symmetric_orbit_breaks_its_symmetry_before_any_doubling():
    """Swift and Wiesenfeld (1984): a pitchfork (+1) first; a symmetric orbit cannot flip."""
    pitchfork = chaos.locate_bifurcation(DRIVEN, "drive_amplitude", (0.9, 1.06), [-0.56],
                                         [1.93], multiplier=1, symmetric=True,
                                         steps_per_period=STEPS)
    assert pitchfork.kind == "fold or pitchfork"
    assert 0.99 < pitchfork.value < 1.02
    assert pitchfork.orbit.symmetry_gap < 1e-10 and abs(pitchfork.orbit.mean_theta[0]) < 1e-10
    assert np.isclose(pitchfork.orbit.multipliers[0].real, 1.0, atol=1e-8)
    with pytest.raises(ValueError, match="no multiplier"):
        chaos.locate_bifurcation(DRIVEN, "drive_amplitude", (0.9, 1.1), [-0.56], [1.93],
                                 multiplier=-1, symmetric=True, steps_per_period=STEPS)
    # negative control: the attractor past the pitchfork is not its own mirror image
    asymmetric = orbit_at(BEFORE_FLIP)
    assert asymmetric.symmetry_gap > 0.1 and abs(asymmetric.mean_theta[0]) > 0.1


def test_continuation_follows_one_branch_through_the_pitchfork():
    values = np.linspace(0.98, 1.03, 6)
    branch = chaos.continue_orbit(DRIVEN, "drive_amplitude", values, [-0.97], [1.91],
                                  symmetric=True, steps_per_period=STEPS)
    assert all(orbit.symmetry_gap < 1e-10 for orbit in branch)
    stable = [orbit.stable for orbit in branch]
    assert stable[0] and not stable[-1]


def test_critical_slowing_down_makes_a_stable_orbit_look_doubled():
    """Why a grid of short runs places the flip too early."""
    model = DRIVEN.replace(drive_amplitude=1.0658)
    orbit = orbit_at(model)
    assert orbit.stable and -0.99 < orbit.multipliers[0].real < -0.97
    assert abs(orbit.multipliers[0]) ** 300 > 1e-4  # above the period tolerance
    kwargs = dict(theta0=[[0.0]], omega0=[[0.0]], n_periods=64, steps_per_period=60)
    short = chaos.bifurcation_diagram(DRIVEN, "drive_amplitude", [1.0658],
                                      transient_periods=300, **kwargs)
    long = chaos.bifurcation_diagram(DRIVEN, "drive_amplitude", [1.0658],
                                     transient_periods=3000, **kwargs)
    assert short.periods.tolist() == [[2]]
    assert long.periods.tolist() == [[1]]  # negative control: a long transient settles


def test_the_stated_error_falls_like_the_fourth_power_of_the_step():
    kwargs = dict(doublings=2, settle_periods=200)
    coarse = chaos.period_doubling_cascade(DRIVEN, "drive_amplitude", (1.06, 1.09), [0.0],
                                           [0.0], steps_per_period=100, **kwargs)
    fine = chaos.period_doubling_cascade(DRIVEN, "drive_amplitude", (1.06, 1.09), [0.0], [0.0],
                                         steps_per_period=200, **kwargs)
    assert coarse.periods.tolist() == [1, 2]
    ratio = coarse.errors / fine.errors
    assert np.all((ratio > 8) & (ratio < 32)), ratio  # 2**4 = 16
    # the stated error covers the fine values' distance from finer ones
    assert np.all(np.abs(fine.values - coarse.values) <= coarse.errors * 1.1)


@pytest.mark.parametrize("call, error, match", [
    (lambda: chaos.periodic_orbit(DRIVEN.family(drive_amplitude=[1.0, 1.1]), [0.0], [0.0]),
     ValueError, "one model"),
    (lambda: chaos.periodic_orbit(pl.simple_pendulum(), [0.1], [0.0]), ValueError, "no drive"),
    (lambda: chaos.periodic_orbit(DRIVEN, [0.1], [0.0], periods=2, symmetric=True), ValueError,
     "odd `periods`"),
    (lambda: chaos.periodic_orbit(DRIVEN, [0.1], [0.0], steps_per_period=1), ValueError,
     "steps_per_period"),
    (lambda: chaos.locate_bifurcation(DRIVEN, "drive_amplitude", (1.0, 1.0), [0.1], [0.0]),
     ValueError, "bracket"),
    (lambda: chaos.locate_bifurcation(DRIVEN, "drive_amplitude", (1.0, 1.1), [0.1], [0.0],
                                      multiplier=0), ValueError, "multiplier"),
    (lambda: chaos.locate_bifurcation(DRIVEN, "mass", (1.0, 1.1), [0.1], [0.0]), ValueError,
     "parameter"),
    (lambda: chaos.periodic_orbit(DRIVEN.replace(drive_amplitude=1.2), [0.1], [0.0],
                                  max_iterations=2), RuntimeError, "Newton"),
])
def test_bad_arguments_are_refused_naming_them(call, error, match):
    with pytest.raises(error, match=match):
        call()


def test_branches_are_drawn_solid_where_stable_and_dashed_where_not():
    values = np.linspace(1.0, 1.03, 4)
    branch = chaos.continue_orbit(DRIVEN, "drive_amplitude", values, [-1.05], [1.90],
                                  symmetric=True)
    fig = pl.plotting.plot_orbit_branches({"symmetric": (values, branch)})
    left, right = fig.axes
    solid, dashed = left.lines[0], left.lines[1]
    assert np.isfinite(solid.get_ydata()).sum() >= 1 and np.isfinite(dashed.get_ydata()).sum() >= 2
    assert len(right.lines) >= 4  # two pieces and the lines +1 and -1
    with pytest.raises(ValueError, match="values but"):  # negative control: a mismatched branch
        pl.plotting.plot_orbit_branches({"symmetric": (values[:2], branch)})
