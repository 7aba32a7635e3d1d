"""The analysis, geometric and chaos tools on systems that are not chains: the elastic, the
Kapitza and the cart pendulum. Each tool gives the mathematics of the system it is handed,
or refuses it with a sentence saying why; never a chain's answer for a system."""

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab import analysis, chaos, geometric
from pendulum_lab.analysis.structure import finite_difference_jacobian
from pendulum_lab.plotting.figures import pendulum_name as figure_name
from pendulum_lab.widgets import explore_equilibrium


def values(model) -> dict:
    return {str(s): v for s, v in model.parameter_values.items()}


# ---- equilibria and normal modes ---------------------------------------------------------
def test_elastic_modes_are_the_spring_and_the_pendulum_of_the_stretched_length(elastic):
    v = values(elastic)
    stretched = v["l_0"] + v["m"] * v["g"] / v["k"]
    bottom = analysis.find_equilibrium(elastic)
    assert np.allclose(analysis.equilibrium_angles(elastic), [stretched, 0.0])
    assert bottom.name == "r = 1, theta = 0"
    frequencies, shapes = analysis.normal_modes(elastic)
    expected = sorted([np.sqrt(v["g"] / stretched), np.sqrt(v["k"] / v["m"])])
    assert np.allclose(frequencies, expected, rtol=1e-12)
    assert np.allclose(np.abs(shapes), [[0.0, 1.0], [1.0, 0.0]])  # swing, then stretch
    # negative control: the unstretched length gives another swing frequency
    assert not np.isclose(frequencies[0], np.sqrt(v["g"] / v["l_0"]), rtol=1e-3)


def test_cart_has_a_free_drift_and_the_pendulum_mode_of_the_reduced_mass(cart):
    v = values(cart)
    frequencies, shapes = analysis.normal_modes(cart)
    assert frequencies[0] == 0.0  # the cart's position is free
    assert np.isclose(frequencies[1], np.sqrt(v["g"] * (v["M"] + v["m"]) / (v["M"] * v["l"])),
                      rtol=1e-12)
    # the cart moves against the bob: x = -m l theta / (M + m) in the swinging mode
    assert np.isclose(shapes[1, 0] / shapes[1, 1], -v["m"] * v["l"] / (v["M"] + v["m"]))
    assert not np.isclose(frequencies[1], np.sqrt(v["g"] / v["l"]))  # a fixed pivot's


def test_equilibria_by_name_and_by_point_and_the_refusals(elastic, kapitza):
    names = [eq.name for eq in elastic.equilibria]
    assert names == ["r = 1, theta = 0", "r = 1/2, theta = pi"]  # lowest energy first
    up = analysis.find_equilibrium(elastic, "r = 1/2, theta = pi")
    assert up.classify(elastic.parameter_values) == "saddle-center"
    assert analysis.find_equilibrium(elastic, (0.5, np.pi)).classify(
        elastic.parameter_values) == "saddle-center"
    with pytest.raises(ValueError, match="is not an equilibrium"):
        analysis.find_equilibrium(elastic, (0.9, 0.0))
    with pytest.raises(ValueError, match="must be one of"):
        analysis.find_equilibrium(elastic, "down")
    with pytest.raises(ValueError, match="depend on"):
        analysis.normal_modes(kapitza)  # a state at rest does not stay at rest


def test_linearised_elastic_motion_matches_small_oscillations(elastic):
    bottom = analysis.equilibrium_angles(elastic)
    t = np.linspace(0.0, 5.0, 501)
    for size in (1e-3, 2e-3):
        start = bottom + size * np.array([1.0, 1.0])
        linear, _ = analysis.linearized_solution(elastic, start, [0.0, 0.0], t=t)
        run = pl.simulate(elastic, start, [0.0, 0.0], t_end=5.0, dt=0.01, method="glrk8",
                          progress=False)
        gap = np.max(np.abs(run.theta - linear))
        if size == 1e-3:
            first = gap
    assert first < 2e-5 and 3.0 < gap / first < 5.0  # the nonlinear terms: O(size**2)


def test_explore_equilibrium_follows_a_system_equilibrium_as_its_parameters_move(elastic):
    ex = explore_equilibrium(elastic, "r = 1/2, theta = pi", offset=[0.0, 0.1])
    assert np.allclose(ex.trajectory.theta[0], [0.5, np.pi + 0.1])
    ex.controls["k"].value *= 2  # a stiffer spring: the inverted bob sits at r = 5/8
    ex.update()
    assert ex.equilibrium.name == "r = 5/8, theta = pi"
    assert np.allclose(ex.trajectory.theta[0], [0.625, np.pi + 0.1])
    assert "saddle-center" in ex.summary()


# ---- step stability about a system's rest state -------------------------------------------
@pytest.mark.parametrize("method, edge", [("leapfrog", 2.0), ("rk4", 2 * np.sqrt(2))])
def test_stability_limit_is_set_by_the_fastest_normal_mode(elastic, cart, method, edge):
    for model in (elastic, cart):
        fastest = analysis.normal_modes(model)[0].max()
        limit = analysis.stability_limit(model, method=method, dt_max=0.95 * 3 / fastest)
        assert np.isclose(limit * fastest, edge, rtol=1e-4)
    # negative control: the bottom of a chain of the same lengths is not the elastic's
    assert not np.isclose(2.0 / analysis.normal_modes(pl.simple_pendulum(length=1.0))[0][0],
                          2.0 / analysis.normal_modes(elastic)[0].max(), rtol=1e-2)


def test_amplification_at_the_elastic_bottom_is_one_for_leapfrog_and_above_for_euler(elastic):
    assert np.allclose(analysis.amplification(elastic, [0.1, 0.3], method="leapfrog"), 1.0,
                       atol=1e-6)
    assert np.all(analysis.amplification(elastic, [0.1], method="explicit_euler") > 1.05)


def test_chain_only_tools_refuse_systems_with_a_reason(elastic, kapitza, cart):
    for model in (elastic, kapitza, cart):
        with pytest.raises(TypeError, match="chain of rods"):
            analysis.rest_state_at_energy(model, 0.0)
    with pytest.raises(TypeError, match="chain of rods"):
        geometric.modified_equation(elastic, "leapfrog", 2)  # the simple pendulum's fields
    for tool in (geometric.modified_equation, geometric.modified_hamiltonian):
        with pytest.raises(ValueError, match="depend on the time"):
            tool(kapitza, "leapfrog", 2)  # Kapitza has n = 1, like the simple pendulum
    with pytest.raises(ValueError, match="does not depend on the time.*Methods that can: .*glrk4"):
        pl.simulate(kapitza, [3.0], [0.0], t_end=0.1, dt=0.01, method="variational_midpoint")
    assert analysis.pendulum_name(cart) == "the pendulum on a cart"
    assert figure_name(elastic) == "the elastic pendulum"


# ---- the modified energy of a system ------------------------------------------------------
@pytest.mark.parametrize("system, start, ratio",
                         [("elastic", [1.1, 0.3], 0.05), ("cart", [0.0, 0.4], 0.02)])
def test_leapfrog_keeps_its_modified_energy_far_better_than_the_energy(system, start, ratio,
                                                                        request):
    model, dt = request.getfixturevalue(system), 0.05
    modified = geometric.modified_energy(model, "leapfrog", 2)

    def spreads(method):
        run = pl.simulate(model, start, [0.0, 0.0], t_end=200.0, dt=dt, method=method,
                          progress=False)
        return (np.ptp(model.hamiltonian_value(run.theta, run.p)),
                np.ptp(modified(run.theta, run.p, dt=dt)))

    energy, kept = spreads("leapfrog")
    assert kept < ratio * energy
    energy, kept = spreads("rk4")  # negative control: leapfrog's H~ is not RK4's
    assert kept > 0.5 * energy


# ---- the time of a time-dependent system, threaded through -------------------------------
def test_step_jacobian_at_a_later_time_is_the_jacobian_of_the_step_taken_then(kapitza):
    state, dt, t0 = np.array([2.9, 0.4]), 0.01, 0.3

    def step_at(time):
        return lambda z: np.concatenate(pl.step(kapitza, z[:1], p0=z[1:], dt=dt,
                                                method="rk4", t0=time))

    by_hand = finite_difference_jacobian(step_at(t0), state)
    jacobian = analysis.step_jacobian(kapitza, state[:1], p0=state[1:], dt=dt, method="rk4",
                                      t0=t0)
    assert np.allclose(jacobian, by_hand, atol=1e-9)
    assert not np.allclose(jacobian, finite_difference_jacobian(step_at(0.0), state),
                           atol=1e-3)  # negative control: the shaking pivot's phase matters


def test_symplecticity_and_reversibility_of_the_shaken_pendulum(kapitza):
    start = dict(theta0=[2.9], omega0=[0.4], dt=0.01, t0=0.3)
    for method in ("glrk4", "leapfrog"):
        assert analysis.symplecticity_defect(kapitza, **start, method=method) < 1e-8
    assert analysis.symplecticity_defect(kapitza, **start, method="rk4") > 1e-6
    assert analysis.symplecticity_defect(kapitza, **start, method="explicit_euler") > 1e-4
    assert analysis.reversibility_error(kapitza, **start, method="leapfrog") < 1e-13
    # negative control: stepping back from t0 instead of t0 + dt does not return
    q1, p1 = pl.step(kapitza, [2.9], [0.4], dt=0.01, method="leapfrog", t0=0.3)
    q2, _ = pl.step(kapitza, q1, p0=p1, dt=-0.01, method="leapfrog", t0=0.3)
    assert abs(q2[0] - 2.9) > 1e-4


def test_stage_iteration_contracts_in_proportion_to_the_step_at_any_time(kapitza):
    big, small = (analysis.stage_contraction(kapitza, [2.9], [0.4], dt=h, t0=0.3)
                  for h in (0.002, 0.001))
    assert 1.6 < big.contraction / small.contraction < 2.5
    assert 0.5 < small.contraction / small.predicted < 1.5


def test_reference_order_and_comparison_start_at_t0(kapitza):
    later = analysis.reference_solution(kapitza, [2.9], [0.4], t_end=0.5, t0=0.3)
    run = pl.simulate(kapitza, [2.9], [0.4], t_end=0.5, dt=1e-4, method="glrk8", t0=0.3,
                      keep="final", progress=False)
    assert np.allclose(later[0], run.theta[-1], atol=1e-9)
    assert not np.allclose(later[0], analysis.reference_solution(
        kapitza, [2.9], [0.4], t_end=0.5)[0], atol=1e-2)  # negative control: from t = 0
    order = analysis.observed_order(kapitza, [2.9], [0.4], t_end=0.2,
                                    dts=[0.004, 0.002, 0.001], method="rk4", t0=0.3)
    assert 3.8 < order.slope < 4.3
    traj = pl.simulate(kapitza, [2.9], [0.4], t_end=1.0, dt=0.001, method="leapfrog", t0=0.3,
                       progress=False)
    row = analysis.compare_trajectory(kapitza, traj, order_t_end=0.1,
                                      order_dts=[0.002, 0.001], check_dt=0.001)
    assert row.pendulum == "the Kapitza pendulum"
    assert 1.8 < row.observed_order < 2.2 and row.symplecticity_defect < 1e-8


def test_scipy_run_of_the_shaken_pendulum_agrees_with_a_gauss_run(kapitza):
    adaptive = analysis.scipy_run(kapitza, [2.9], [0.4], t_end=1.0, rtol=1e-11)
    gauss = pl.simulate(kapitza, [2.9], [0.4], t_end=1.0, dt=1e-4, method="glrk8",
                        keep="final", progress=False)
    assert np.allclose(adaptive.theta[-1], gauss.theta[-1], atol=1e-8)
    assert np.allclose(adaptive.p[-1], gauss.p[-1], atol=1e-7)


# ---- sections and chaos ------------------------------------------------------------------
@pytest.mark.parametrize("system, start", [("elastic", [1.1, 0.3]), ("cart", [0.0, 0.4])])
def test_henon_landing_uses_the_system_equations(system, start, request):
    model = request.getfixturevalue(system)
    newton, henon = (chaos.poincare_section(model, start, [0.0, 0.0], t_end=6.0, dt=0.01,
                                            link=1, landing=landing, progress=False)
                     for landing in ("newton", "henon"))
    assert len(newton.t) >= 2 and np.array_equal(newton.orbit, henon.orbit)
    assert np.max(np.abs(newton.p - henon.p)) < 1e-8  # both land the system's own flow
    assert np.max(henon.residual) < 1e-12


def test_sections_of_the_shaken_pendulum_land_on_the_exact_flow_at_their_times(kapitza):
    sections = [chaos.poincare_section(kapitza, [0.5], [0.0], t_end=4.0, dt=0.001, t0=0.3,
                                       landing=landing, progress=False)
                for landing in ("newton", "henon")]
    assert len(sections[0].t) >= 2
    assert np.allclose(sections[0].t, sections[1].t, atol=1e-10)
    first = sections[0]
    exact_theta, exact_omega = analysis.reference_solution(kapitza, [0.5], [0.0],
                                                          t_end=first.t[0] - 0.3, t0=0.3)
    assert abs(exact_theta[0]) < 1e-7  # on the surface at the time found
    assert np.allclose(kapitza.velocities(first.theta[0], first.p[0], first.t[0]),
                       exact_omega, atol=1e-6)
    with pytest.raises(ValueError, match="depends on the time"):
        chaos.section_states(kapitza, 0.0, [[0.0]], [[0.0]])


def test_elastic_section_states_lie_on_the_energy_level(elastic):
    energy = float(elastic.energy([1.1, 0.3], [0.0, 0.0]))
    theta, omega = chaos.section_states(elastic, energy, [[1.0], [1.1]], [[0.0], [0.2]],
                                        link=1)
    assert np.allclose(elastic.energy(theta, omega), energy, atol=1e-12)
    assert np.all(theta[:, 1] == 0.0) and np.all(omega[:, 1] > 0)


def test_separation_and_lyapunov_start_at_t0(kapitza):
    sep = chaos.separation(kapitza, [2.9], [0.4], t_end=1.0, dt=0.001, t0=0.3, progress=False)
    assert sep.t[0] == pytest.approx(0.3)
    benettin, variational = (
        tool(kapitza, [2.9], [0.4], t_end=1.0, dt=0.001, t0=0.3, progress=False).exponent
        for tool in (chaos.lyapunov_benettin, chaos.lyapunov_variational))
    assert benettin == pytest.approx(variational, rel=1e-4)
    shifted = chaos.lyapunov_variational(kapitza, [2.9], [0.4], t_end=1.0, dt=0.001,
                                         progress=False).exponent
    assert abs(shifted - variational) > 1e-3  # negative control: another phase of the pivot


# ---- orbits of the shaken pendulum followed in its own parameters --------------------------
def test_inverted_kapitza_orbit_loses_stability_near_the_averaging_threshold():
    kapitza = pl.kapitza_pendulum(amplitude=0.05, frequency=100.0)
    threshold = np.sqrt(2 * 9.81 * 1.0) / 100.0  # a w = sqrt(2 g l)
    flip = chaos.locate_bifurcation(kapitza, "a", (0.05, 0.04), [np.pi], [0.0], multiplier=1,
                                    steps_per_period=200)
    assert flip.kind == "fold or pitchfork"
    # averaging is a first approximation in 1/w: the exact threshold lies 0.04 % above it
    assert 1.0 < flip.value / threshold < 1.002
    orbits = chaos.continue_orbit(kapitza, "a", [0.05, 0.043], [np.pi], [0.0],
                                  steps_per_period=200)
    assert [orbit.stable for orbit in orbits] == [True, False]  # negative control below it
    with pytest.raises(ValueError, match="depends on the time"):
        chaos.continue_orbit(kapitza, "w", [100.0, 99.0], [np.pi], [0.0])
    with pytest.raises(ValueError, match="depends on the time"):
        chaos.bifurcation_diagram(kapitza, "w", [100.0], theta0=[np.pi], omega0=[0.0])


def test_kapitza_bifurcation_diagram_over_the_shaking_amplitude(kapitza):
    """One ensemble of a family in ``a``: above a w = sqrt(2 g l) the stroboscopic samples
    stay near the inverted position, below it the pendulum falls (the negative control)."""
    threshold = np.sqrt(2 * 9.81 * 1.0) / 100.0
    values = [0.8 * threshold, 1.3 * threshold, 1.6 * threshold]
    diagram = chaos.bifurcation_diagram(kapitza, "a", values, theta0=[np.pi - 0.05],
                                        omega0=[0.0], n_periods=32, transient_periods=100,
                                        steps_per_period=100)
    distance = np.abs(np.abs(diagram.theta[..., 0]) - np.pi).max(axis=(0, 2))  # per a
    assert distance[1] < 0.1 and distance[2] < 0.1
    assert distance[0] > 1.0
    # each member is the model with its own amplitude: the first one run alone agrees
    alone = chaos.stroboscopic_section(kapitza.replace(a=values[0]), [np.pi - 0.05], [0.0],
                                       n_periods=32, transient_periods=100,
                                       steps_per_period=100)
    assert np.allclose(alone.theta[:, 0], diagram.theta[:, 0, 0, 0], atol=1e-9)
    with pytest.raises(ValueError, match="no drive period"):
        chaos.bifurcation_diagram(pl.elastic_pendulum(), "k", [30.0], theta0=[1.0, 0.1],
                                  omega0=[0.0, 0.0])
