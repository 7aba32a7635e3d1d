"""The damped, driven pendulum: model families, Lyapunov spectra, stroboscopic sections,
bifurcation diagrams, basins and the decay of energy under damping.

Each property is paired with a negative control that fails the same check.
"""

import doctest
import importlib

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab import chaos
from pendulum_lab.analysis import energy_decay, linear_decay
from pendulum_lab.chaos.bifurcation import BifurcationDiagram

DRIVEN = pl.driven_pendulum()  # Baker and Gollub: q = 2, A = 1.2, Omega = 2/3
T = DRIVEN.drive_period
# Other numbers, so that no formula can hide behind m = l = g = 1.
HEAVY = pl.driven_pendulum(damping=0.3, drive_amplitude=4.0, drive_frequency=1.3, mass=2.0,
                           length=0.7, g=9.81)
DAMPED = pl.driven_pendulum(drive_amplitude=0.0)  # damping 0.5, no drive
STEPS = 60  # steps per drive period in these tests


def settled(model, theta0=(0.2,), omega0=(0.0,), periods=100):
    """The state after ``periods`` drive periods: ``(theta, p, t)``."""
    section = chaos.stroboscopic_section(model, list(theta0), list(omega0), n_periods=1,
                                         transient_periods=periods, steps_per_period=STEPS)
    return section.theta[-1], section.p[-1], section.t[-1]


# ---------------------------------------------------------------- model families
def test_a_family_runs_each_member_with_its_own_parameters_in_one_run():
    amplitudes = np.array([0.9, 1.2, 1.5])
    family = DRIVEN.family(drive_amplitude=amplitudes[:, None])  # shape (3, 1)
    theta0 = np.broadcast_to([[[0.2], [-1.0]]], (3, 2, 1))
    run = pl.simulate(family, theta0, np.zeros_like(theta0), t_end=3.0, dt=0.01,
                      method="conformal_leapfrog", t0=0.4)
    for k, amplitude in enumerate(amplitudes):
        for b, start in enumerate((0.2, -1.0)):
            one = pl.simulate(DRIVEN.replace(drive_amplitude=amplitude), [start], [0.0],
                              t_end=3.0, dt=0.01, method="conformal_leapfrog", t0=0.4)
            assert np.array_equal(run.theta[:, k, b], one.theta)
            assert np.array_equal(run.omega[:, k, b], one.omega)
            assert np.array_equal(run.energy[:, k, b], one.energy)
    # negative control: the members really differ
    assert abs(run.theta[-1, 0, 0, 0] - run.theta[-1, 2, 0, 0]) > 1e-3


def test_a_family_in_segments_is_the_same_run():
    family = DRIVEN.family(damping=[0.0, 0.3, 0.5], drive_amplitude=[0.0, 1.0, 1.2])
    theta0 = np.array([[0.3], [0.3], [0.3]])
    whole = pl.simulate(family, theta0, np.zeros_like(theta0), t_end=4.0, dt=0.02, method="rk4")
    run = pl.simulate_segments(family, theta0, np.zeros_like(theta0), t_end=4.0, dt=0.02,
                               method="rk4", segment_steps=30)
    last = list(run)[-1]
    # the same steps; only the step times of a driven run may round differently
    assert np.allclose(last.theta[-1], whole.theta[-1], rtol=0, atol=1e-14)
    assert np.allclose(last.omega[-1], whole.omega[-1], rtol=0, atol=1e-14)
    assert not np.allclose(whole.theta[-1, 0], whole.theta[-1, 2])  # the members differ
    # the unforced member runs on the forced kernels, and still equals the plain model bit
    # for bit (its forces add exact zeros)
    plain = pl.simulate(pl.driven_pendulum(damping=0.0, drive_amplitude=0.0), [0.3], [0.0],
                        t_end=4.0, dt=0.02, method="rk4")
    assert np.array_equal(whole.theta[:, 0], plain.theta)


def test_a_segmented_family_keeps_each_members_parameters_when_members_leave():
    family = DRIVEN.family(drive_amplitude=[0.9, 1.2, 1.5])
    theta0 = np.full((3, 1), 0.3)
    run = pl.simulate_segments(family, theta0, np.zeros_like(theta0), t_end=4.0, dt=0.02,
                               method="rk4", segment_steps=50)
    segments = iter(run)
    next(segments)
    run.keep(np.array([True, False, True]))  # the middle member leaves after one segment
    last = list(segments)[-1]
    assert run.members.tolist() == [0, 2] and run.model.shape == (2,)
    for row, k in enumerate((0, 2)):
        one = pl.simulate(family.member(k), [0.3], [0.0], t_end=4.0, dt=0.02, method="rk4")
        assert np.allclose(last.theta[-1, row], one.theta[-1], rtol=0, atol=1e-13)
    # negative control: the kept members are not the first two
    wrong = pl.simulate(family.member(1), [0.3], [0.0], t_end=4.0, dt=0.02, method="rk4")
    assert not np.allclose(last.theta[-1, 1], wrong.theta[-1], atol=1e-6)


def test_family_functions_broadcast_like_their_members():
    family = pl.double_pendulum(damping=0.1).family(damping=[0.1, 0.4], g=[9.81, 3.0])
    rng = np.random.default_rng(2)
    theta, p = rng.normal(size=(2, 2, 2))
    jac = family.jacobian(theta, p)
    for k in range(2):
        assert np.allclose(jac[k], family.member(k).jacobian(theta[k], p[k]), rtol=1e-14,
                           atol=1e-14)
        assert np.allclose(family.energy(theta, p)[k], family.member(k).energy(theta[k], p[k]))
    assert family.conformal_damping_rate is None  # joint damping of a chain
    rates = DRIVEN.family(damping=[0.2, 0.5]).conformal_damping_rate
    assert np.allclose(rates, [0.2, 0.5])
    # negative control: a member's Jacobian differs from the other's
    assert not np.allclose(jac[0], jac[1])


@pytest.mark.parametrize("values, error, match", [
    (dict(mass=[1.0, 2.0]), ValueError, "cannot vary 'mass'"),
    (dict(damping=[0.1, -0.2]), ValueError, "`damping`"),
    (dict(drive_amplitude=[1.0, np.inf]), ValueError, "`drive_amplitude`"),
    (dict(drive_frequency=[0.5, 0.0]), ValueError, "`drive_frequency`"),
    (dict(damping=["a"]), TypeError, "`damping`"),
    (dict(damping=[0.1, 0.2], g=[1.0, 2.0, 3.0]), ValueError, "broadcast"),
    (dict(), ValueError, "at least one parameter"),
])
def test_bad_families_are_refused_naming_the_argument(values, error, match):
    with pytest.raises(error, match=match):
        DRIVEN.family(**values)


def test_a_family_must_fit_the_ensemble():
    family = DRIVEN.family(drive_amplitude=[1.0, 1.2])
    with pytest.raises(ValueError, match="family has shape"):
        pl.simulate(family, [[0.1], [0.2], [0.3]], [[0.0], [0.0], [0.0]], t_end=0.1, dt=0.01)


# ---------------------------------------------------------------- Lyapunov spectrum
@pytest.mark.parametrize("model", [DRIVEN, HEAVY, DAMPED])
def test_spectrum_of_the_damped_pendulum_sums_to_minus_damping_over_m_l2(model):
    """The trace of the Jacobian, in (theta, p) as in (theta, omega): an exact check."""
    gamma = model.damping[0] / (model.masses[0] * model.lengths[0] ** 2)
    dt = (model.drive_period or 2.0) / STEPS
    spectrum = chaos.lyapunov_spectrum(model, [0.4], [0.3], t_end=300 * dt * 10, dt=dt,
                                       method="rk4", save_every=STEPS)
    assert abs(spectrum.sum + gamma) < 1e-11 * max(1.0, gamma), spectrum.sum
    assert np.allclose(spectrum.running.sum(axis=-1), -gamma, rtol=0, atol=1e-11)
    # the trace of the Jacobian in (theta, omega) is the same constant
    theta, omega = np.random.default_rng(0).normal(size=(2, 5, 1))
    eps, t = 1e-6, 0.3
    d_acc = (model.accelerations(theta, omega + eps, t) - model.accelerations(theta, omega - eps,
                                                                            t)) / (2 * eps)
    assert np.allclose(d_acc, -gamma, rtol=1e-7)  # d(theta')/d theta = 0, d(omega')/d omega
    assert np.allclose(np.trace(model.jacobian(theta, model.momenta(theta, omega), t),
                                axis1=-2, axis2=-1), -gamma, rtol=1e-13)
    # negative control: the conservative model's Jacobian on the same run sums to 0
    blind = model.replace(damping=0.0)
    blind_field = blind.jacobian
    wrong = model.replace()
    wrong.jacobian = lambda theta, p, *t: blind_field(theta, p, *t)
    off = chaos.lyapunov_spectrum(wrong, [0.4], [0.3], t_end=300 * dt * 10, dt=dt,
                                  method="rk4", save_every=STEPS)
    assert abs(off.sum + gamma) > 0.5 * gamma


def test_hamiltonian_spectrum_comes_in_pairs():
    """For one link the pair sum is the total, which the propagators fix (a check of the
    Jacobian's trace); the pairing of a larger spectrum, which they do not fix, is checked in
    tests/chaos/test_published_values.py."""
    undamped = pl.driven_pendulum(damping=0.0)
    spectrum = chaos.lyapunov_spectrum(undamped, [0.2], [0.0], t_end=100 * T, dt=T / STEPS,
                                       method="rk4", save_every=STEPS)
    assert abs(spectrum.sum) < 1e-11
    assert spectrum.largest > 0.05  # the undamped driven pendulum is chaotic here
    # negative control: with damping the pair is not symmetric
    damped = chaos.lyapunov_spectrum(DRIVEN, [0.2], [0.0], t_end=100 * T, dt=T / STEPS,
                                     method="rk4", save_every=STEPS)
    assert abs(damped.sum) > 0.4


def test_largest_exponent_positive_on_the_strange_attractor_negative_on_a_periodic_one():
    kwargs = dict(dt=T / STEPS, method="rk4", save_every=STEPS, t_end=200 * T)
    results = {}
    for amplitude in (1.2, 0.9, 1.35):  # chaotic; period 1; period 1 (a rotation)
        model = DRIVEN.replace(drive_amplitude=amplitude)
        theta, p, t0 = settled(model)
        spectrum = chaos.lyapunov_spectrum(model, theta, p0=p, t0=t0, **kwargs)
        variational = chaos.lyapunov_variational(model, theta, p0=p, t0=t0, **kwargs)
        benettin = chaos.lyapunov_benettin(model, theta, p0=p, t0=t0, dt=T / STEPS,
                                           method="rk4", renormalize_every=STEPS, t_end=200 * T)
        results[amplitude] = spectrum.largest
        # the same reference trajectory: the first exponent agrees with the other two
        assert abs(spectrum.largest - variational.exponent) < 0.01 * abs(variational.exponent)
        assert abs(spectrum.largest - benettin.exponent) < 0.15 * abs(benettin.exponent)
    assert results[1.2] > 0.08
    # on a periodic attractor both exponents are negative (about -damping / 2 each)
    assert results[0.9] < -0.2 and results[1.35] < -0.2


def test_spectrum_of_a_family_is_the_spectra_of_its_members():
    amplitudes = [0.9, 1.2]
    family = DRIVEN.family(drive_amplitude=amplitudes)
    kwargs = dict(t_end=20 * T, dt=T / STEPS, method="rk4", save_every=STEPS)
    both = chaos.lyapunov_spectrum(family, [[0.2], [0.2]], [[0.0], [0.0]], **kwargs)
    for k, amplitude in enumerate(amplitudes):
        one = chaos.lyapunov_spectrum(DRIVEN.replace(drive_amplitude=amplitude), [0.2], [0.0],
                                      **kwargs)
        assert np.allclose(both.running[:, k], one.running, rtol=0, atol=1e-12)
    assert not np.allclose(both.exponents[0], both.exponents[1], atol=1e-3)  # they differ


def test_joint_damping_of_the_double_pendulum_is_not_conformal():
    """Its Jacobian's trace depends on theta: no constant contraction rate to check."""
    damped = pl.double_pendulum(damping=0.3)
    traces = [np.trace(damped.jacobian(theta, [0.0, 0.0]))
              for theta in ([0.0, 0.0], [0.0, 1.5], [1.0, -2.0])]
    assert np.ptp(traces) > 0.1
    assert damped.conformal_damping_rate is None
    # negative control: one link's trace is the same everywhere
    one = [np.trace(DAMPED.jacobian([theta], [0.0])) for theta in (0.0, 1.5, -2.0)]
    assert np.ptp(one) < 1e-15


# ---------------------------------------------------------------- stroboscopic sections
def test_section_samples_the_run_once_per_period_with_wrapped_angles():
    kwargs = dict(n_periods=40, transient_periods=10, steps_per_period=STEPS)
    for model in (DRIVEN.replace(drive_amplitude=1.35), DRIVEN):  # a rotation; chaos
        section = chaos.stroboscopic_section(model, [0.2], [0.0], **kwargs)
        run = pl.simulate(model, [0.2], [0.0], t_end=50 * T, dt=T / STEPS, method="rk4",
                          save_every=STEPS)
        assert section.theta.shape == (40, 1)
        assert np.allclose(section.t, np.arange(11, 51) * T, rtol=1e-14)
        assert np.all((section.theta > -np.pi) & (section.theta <= np.pi))
        # negative control: the run's own angles leave (-pi, pi]
        assert np.any(np.abs(run.theta[11:]) > np.pi)
    # one segmented run: the same steps, up to the rounding of the step times, which the
    # strange attractor amplifies (checked on the rotation, which forgets it)
    rotation = DRIVEN.replace(drive_amplitude=1.35)
    section = chaos.stroboscopic_section(rotation, [0.2], [0.0], **kwargs)
    run = pl.simulate(rotation, [0.2], [0.0], t_end=50 * T, dt=T / STEPS, method="rk4",
                      save_every=STEPS)
    assert np.allclose(section.omega, run.omega[11:], rtol=0, atol=1e-12)
    assert np.allclose(section.theta, pl.plotting.wrap_angle(run.theta[11:]), rtol=0, atol=1e-12)


@pytest.mark.parametrize("amplitude, period", [(0.9, 1), (1.075, 2), (1.0816, 4), (1.2, 0)])
def test_periods_are_counted_from_the_samples(amplitude, period):
    # 1 -> 2 -> 4 along the period-doubling route; 0 (no period) on the strange attractor
    model = DRIVEN.replace(drive_amplitude=amplitude)
    section = chaos.stroboscopic_section(model, [1.0], [0.0], n_periods=32,
                                         transient_periods=300, steps_per_period=STEPS)
    assert int(section.periods()) == period


def test_orbit_periods_of_synthetic_orbits_and_the_tolerance():
    k = np.arange(48)[:, None, None]
    cycle = np.array([0.1, 1.0, -2.0])[k % 3]
    rotation = 0.5 + 2 * np.pi * k  # one turn per period: one point once wrapped
    theta = np.concatenate([cycle, rotation], axis=1)
    noise = 1e-6 * np.random.default_rng(0).normal(size=theta.shape)
    assert chaos.orbit_periods(theta + noise, np.zeros_like(theta)).tolist() == [3, 1]
    # negative control: noise above the tolerance hides every period
    assert chaos.orbit_periods(theta + 1e3 * noise, np.zeros_like(theta),
                               tolerance=1e-4).tolist() == [0, 0]


def test_rotations_count_their_turns():
    model = DRIVEN.replace(drive_amplitude=1.35)
    section = chaos.stroboscopic_section(model, [[0.88], [-0.05]], [[1.91], [0.76]],
                                         n_periods=20, steps_per_period=STEPS)
    assert np.allclose(section.turns[:, 0], [1.0, -1.0], atol=1e-6)
    low = chaos.stroboscopic_section(DRIVEN.replace(drive_amplitude=0.9), [0.2], [0.0],
                                     n_periods=20, steps_per_period=STEPS)
    assert abs(low.turns[0]) < 1e-6  # negative control: an oscillation does not turn


@pytest.mark.parametrize("kwargs, error, match", [
    (dict(model=pl.simple_pendulum()), ValueError, "`model` has no drive"),
    (dict(model=DRIVEN.family(drive_frequency=[0.5, 0.7])), ValueError, "different drive"),
    (dict(n_periods=2.5), TypeError, "`n_periods`"),
    (dict(n_periods=0), ValueError, "`n_periods`"),
    (dict(transient_periods=-1), ValueError, "`transient_periods`"),
    (dict(transient_periods=10.0), TypeError, "`transient_periods`"),
    (dict(steps_per_period=0), ValueError, "`steps_per_period`"),
    (dict(method="leapfrog"), ValueError, "Hamiltonian"),
])
def test_bad_sections_are_refused_naming_the_argument(kwargs, error, match):
    arguments = dict(model=DRIVEN, n_periods=4, transient_periods=0, steps_per_period=10)
    arguments |= kwargs
    model = arguments.pop("model")
    theta0 = [[0.1], [0.2]] if model.shape else [0.1]
    with pytest.raises(error, match=match):
        chaos.stroboscopic_section(model, theta0, np.zeros_like(theta0), **arguments)


# ---------------------------------------------------------------- bifurcation diagrams
def diagram(parameter, values, model=DRIVEN, **kwargs):
    arguments = dict(theta0=[[0.0], [1.0]], omega0=[[0.0], [0.0]], n_periods=32,
                     transient_periods=200, steps_per_period=STEPS, progress=False)
    return chaos.bifurcation_diagram(model, parameter, values, **(arguments | kwargs))


@pytest.mark.parametrize("parameter, values", [("drive_amplitude", [0.9, 1.2]),
                                               ("damping", [0.3, 0.5])])
def test_diagram_is_one_run_equal_to_separate_sections(parameter, values):
    result = diagram(parameter, values, transient_periods=20)
    for k, value in enumerate(values):
        for b, start in enumerate((0.0, 1.0)):
            one = chaos.stroboscopic_section(DRIVEN.replace(**{parameter: value}), [start],
                                             [0.0], n_periods=32, transient_periods=20,
                                             steps_per_period=STEPS)
            assert np.array_equal(result.theta[:, k, b], one.theta)
            assert np.array_equal(result.omega[:, k, b], one.omega)
    assert not np.allclose(result.omega[:, 0], result.omega[:, 1])  # negative control


def test_diagram_over_the_drive_frequency_rescales_time_exactly():
    model = DRIVEN.replace(drive_amplitude=0.9)
    frequencies = [0.6, 0.75]
    result = diagram("drive_frequency", frequencies, model=model, transient_periods=30,
                     theta0=[0.2], omega0=[0.4])
    for k, frequency in enumerate(frequencies):
        one = chaos.stroboscopic_section(model.replace(drive_frequency=frequency), [0.2], [0.4],
                                         n_periods=32, transient_periods=30,
                                         steps_per_period=STEPS)
        assert np.allclose(result.theta[:, k, 0], one.theta, rtol=0, atol=1e-11)
        assert np.allclose(result.omega[:, k, 0], one.omega, rtol=0, atol=1e-11)
    # negative control: the omega the rescaled members integrate is not the real one
    ratio = model.drive_frequency / frequencies[0]
    assert not np.allclose(result.omega[:, 0, 0] * ratio, result.omega[:, 0, 0], atol=1e-3)


def test_period_doublings_are_found_in_the_data():
    # four starts: the two mirror-image branches both double, and each start finds one
    result = diagram("drive_amplitude", [1.06, 1.075, 1.0816, 1.2],
                     theta0=[[0.0], [1.0], [-1.0], [2.0]], omega0=[[0.0]] * 4)
    assert result.periods.max(axis=1).tolist() == [1, 2, 4, 0]
    found = [(d.period, d.before, d.value) for d in result.doublings()]
    assert found == [(1, 1.06, 1.075), (2, 1.075, 1.0816)]
    # negative control: a jump limit below the splitting finds none
    assert result.doublings(max_jump=1e-6) == []
    windows = [(w.first, w.last, w.periods) for w in result.windows()]
    assert windows == [(1.06, 1.06, (1,)), (1.075, 1.075, (2,)), (1.0816, 1.0816, (3, 4)),
                       (1.2, 1.2, ())]


def test_a_jump_to_a_distant_orbit_of_twice_the_period_is_no_doubling():
    def synthetic(omega_after):
        k = np.arange(32)[:, None, None, None]
        omega = np.concatenate([np.full((32, 1, 1, 1), 1.0),
                                omega_after + 0.05 * (-1.0) ** k], axis=1)
        return BifurcationDiagram("drive_amplitude", np.array([1.0, 1.1]), np.zeros_like(omega),
                                  omega, np.array([[1], [2]]), np.zeros((2, 1, 1)), 1e-4, 16,
                                  "omega", 0, "rk4", 0.0)
    assert len(synthetic(1.0).doublings()) == 1  # split in two near the old point
    assert synthetic(2.5).doublings() == []  # negative control: far away


@pytest.mark.parametrize("parameter, values, kwargs, error, match", [
    ("mass", [1.0, 2.0], {}, ValueError, "`parameter`"),
    ("damping", [0.5, -0.1], {}, ValueError, "`damping`"),
    ("drive_amplitude", [1.0, np.nan], {}, ValueError, "`values`"),
    ("drive_amplitude", [[1.0, 1.1]], {}, ValueError, "`values`"),
    ("drive_frequency", [0.5, -0.5], {}, ValueError, "`values`"),
    ("drive_amplitude", [1.0], dict(n_periods=31.5), TypeError, "`n_periods`"),
    ("drive_amplitude", [1.0], dict(n_periods=8), ValueError, "`n_periods`"),
    ("drive_amplitude", [1.0], dict(transient_periods=1.5), TypeError, "`transient_periods`"),
    ("drive_amplitude", [1.0], dict(variable="p"), ValueError, "`variable`"),
    ("drive_amplitude", [1.0], dict(theta0=[[[0.1]]], omega0=[[[0.1]]]), ValueError, "`theta0`"),
])
def test_bad_diagrams_are_refused_naming_the_argument(parameter, values, kwargs, error, match):
    with pytest.raises(error, match=match):
        diagram(parameter, values, **kwargs)


def test_diagram_shows_a_progress_bar_when_asked(capsys):
    diagram("drive_amplitude", [1.0], transient_periods=1, progress=True)
    assert "stroboscopic" in capsys.readouterr().err
    diagram("drive_amplitude", [1.0], transient_periods=1, progress=False)
    assert capsys.readouterr().err == ""  # negative control


# ---------------------------------------------------------------- basins of attraction
def test_two_rotations_share_the_plane_and_each_start_ends_on_its_own():
    model = DRIVEN.replace(drive_amplitude=1.35)
    theta0, omega0 = np.linspace(-3, 3, 7), np.linspace(-2.5, 2.5, 6)
    basins = chaos.basins_of_attraction(model, theta0, omega0, transient_periods=60,
                                        steps_per_period=STEPS, max_period=4)
    assert basins.periods == (1, 1) and sorted(basins.turns) == [-1.0, 1.0]
    assert basins.label.shape == (6, 7) and np.all(basins.label >= 0)
    assert np.isclose(basins.fractions.sum(), 1.0)
    # a start from the grid, run on its own, ends on the attractor it is labelled with
    for j, i in ((0, 0), (3, 3), (5, 6)):
        section = chaos.stroboscopic_section(model, [theta0[i]], [omega0[j]], n_periods=8,
                                             transient_periods=60, steps_per_period=STEPS)
        point = basins.attractors[basins.label[j, i]][0]
        assert np.allclose([section.theta[-1, 0], section.omega[-1, 0]], point, atol=1e-3)
    # negative control: at amplitude 0.9 there is one attractor only
    single = chaos.basins_of_attraction(DRIVEN.replace(drive_amplitude=0.9), theta0[::3],
                                        omega0[::3], transient_periods=60, steps_per_period=STEPS,
                                        max_period=4)
    assert single.periods == (1,) and np.all(single.label == 0)


def test_basins_refuse_chains_and_bad_axes():
    with pytest.raises(ValueError, match="one link"):
        chaos.basins_of_attraction(pl.double_pendulum(drive_amplitude=1.0, drive_frequency=1.0),
                                   [0.0], [0.0])
    with pytest.raises(ValueError, match="`omega0`"):
        chaos.basins_of_attraction(DRIVEN, [0.0], [[0.0, 1.0]])


# ---------------------------------------------------------------- damping and integrators
def test_conformal_step_decays_small_swings_at_exactly_the_true_rate():
    gamma = DAMPED.conformal_damping_rate
    steps = [0.25, 1.0, 1.9]
    conformal = linear_decay(DAMPED, "conformal_leapfrog", steps)
    assert np.allclose(conformal.determinant, np.exp(-gamma * np.array(steps)), rtol=1e-9)
    assert np.allclose(conformal.rate, gamma / 2, rtol=1e-8) and conformal.exact_rate == (
        pytest.approx(gamma / 2, rel=1e-14))
    assert np.all(conformal.oscillatory)
    # beyond the stability interval the step no longer oscillates, and the rate is lost
    beyond = linear_decay(DAMPED, "conformal_leapfrog", [2.2])
    assert not beyond.oscillatory[0] and abs(beyond.rate[0] - gamma / 2) > 0.1
    # negative control: RK4 misses both at the same steps
    rk4 = linear_decay(DAMPED, "rk4", steps[1:])
    assert np.all(np.abs(rk4.determinant / np.exp(-gamma * np.array(steps[1:])) - 1) > 1e-3)
    assert np.all(np.abs(rk4.rate - gamma / 2) > 1e-3)


def test_large_swings_decay_only_to_the_order_of_the_method():
    decay = energy_decay(DAMPED, [2.5], [0.0], t_end=32.0, dts=[0.4, 0.2, 0.1])
    orders = dict(zip(decay.methods, decay.orders))
    local = dict(zip(decay.methods, decay.local_orders[:, -1]))
    assert abs(orders["conformal_leapfrog"] - 2) < 0.2
    assert abs(local["conformal_leapfrog"] - 2) < 0.1
    assert abs(orders["rk4"] - 4) < 0.3  # negative control: a fourth-order method
    small = energy_decay(DAMPED, [0.05], [0.0], t_end=32.0, dts=[0.8],
                         methods=["conformal_leapfrog", "rk4"])
    # nearly linear: the conformal rate is right far beyond its order at a large step
    assert small.error[0, 0] < 0.05 * small.error[1, 0]


# ---------------------------------------------------------------- docstring examples
@pytest.mark.parametrize("module", ["pendulum_lab.model.pendulum",
                                    "pendulum_lab.chaos.stroboscopic",
                                    "pendulum_lab.chaos.bifurcation", "pendulum_lab.chaos.basins",
                                    "pendulum_lab.analysis.damping"])
def test_docstring_examples_run(module):
    result = doctest.testmod(importlib.import_module(module), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
