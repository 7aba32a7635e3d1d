"""The widgets run exactly the model they are given (its damping and its drive), offer only the
methods pl.simulate accepts for it, and call a non-conserved energy's change what it is."""

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab import animation, widgets
from pendulum_lab.widgets import controls

DRIVEN = pl.driven_pendulum()  # damping 0.5, drive 1.2 cos(2t/3): chaotic (Baker and Gollub)
SIMPLE = pl.simple_pendulum()


def accepted_by_simulate(model) -> list[str]:
    """The course's methods pl.simulate itself runs on ``model`` (a one-step run each)."""
    accepted = []
    for name in pl.METHODS:
        try:
            pl.simulate(model, [0.2] * model.n, [0.0] * model.n, t_end=0.01, dt=0.01,
                        method=name, progress=False)
        except ValueError:
            continue
        accepted.append(name)
    return accepted


@pytest.mark.parametrize("build", [widgets.live_simulator, animation.simulator],
                         ids=["live", "matplotlib"])
def test_the_simulators_run_the_driven_model_itself(build):
    sim = build(DRIVEN, [0.2], [0.0], t_end=20.0, dt=0.01, method="rk4")
    direct = pl.simulate(DRIVEN, [0.2], [0.0], t_end=20.0, dt=0.01, method="rk4")
    np.testing.assert_array_equal(sim.trajectory.theta, direct.theta)
    gain = float(np.max(np.abs(direct.energy_error)))
    assert gain > 1.0  # the drive pumps energy in: joules, not round-off
    # What the status line reports is that change, named as such.
    assert "not conserved" in sim.message and "damping 0.5 N m s/rad" in sim.message
    reported = float(sim.message.split("E − E(0) reached ")[1].split(" J")[0])
    assert abs(reported) == pytest.approx(gain, rel=1e-2)
    # Negative control: the conservative pendulum from the same start is another motion, and
    # its status line reports an error, not a change.
    plain = build(SIMPLE, [0.2], [0.0], t_end=20.0, dt=0.01, method="rk4")
    assert not np.allclose(plain.trajectory.theta, direct.theta)
    assert "not conserved" not in plain.message and "max |E − E(0)|" in plain.message


@pytest.mark.parametrize("build", [widgets.live_simulator, animation.simulator,
                                   widgets.explore], ids=["live", "matplotlib", "explore"])
def test_a_method_simulate_refuses_is_refused_with_its_reason(build):
    with pytest.raises(ValueError) as refused:
        pl.simulate(DRIVEN, [0.2], [0.0], t_end=1.0, dt=0.01, method="leapfrog")
    with pytest.raises(ValueError, match="`method` 'leapfrog' cannot integrate") as ours:
        build(DRIVEN, [0.2], [0.0], t_end=2.0, method="leapfrog")
    # The driver's reason, word for word.
    reason = "assumes a Hamiltonian vector field, and damping is not Hamiltonian"
    assert reason in str(refused.value) and reason in str(ours.value)
    # Negative control: the same method on the conservative pendulum is accepted.
    assert build(SIMPLE, [0.2], [0.0], t_end=2.0, method="leapfrog").trajectory is not None


@pytest.mark.plumbing  # every registered method compiled for four models, to compare menus
@pytest.mark.parametrize("model", [DRIVEN, pl.double_pendulum(damping=0.1), SIMPLE,
                                   pl.double_pendulum(drive_amplitude=1.0, drive_frequency=2.0)],
                         ids=["driven", "damped double", "simple", "driven double"])
def test_the_method_dropdown_offers_what_simulate_accepts(model):
    sim = widgets.live_simulator(model, t_end=2.0, method="rk4")
    assert list(sim.controls["method"].options) == accepted_by_simulate(model)


def test_the_dropdowns_differ_where_the_models_do():
    # Negative control of the test above: damping removes methods, so the comparison has
    # something to see.
    damped = widgets.explore(pl.double_pendulum(damping=0.1), t_end=1.0, method="rk4")
    plain = widgets.explore(pl.double_pendulum(), t_end=1.0, method="rk4")
    removed = set(plain.controls["method"].options) - set(damped.controls["method"].options)
    assert {"leapfrog", "semi_implicit_euler"} <= removed


def test_a_method_of_another_family_is_offered_when_asked_for():
    sim = widgets.live_simulator(DRIVEN, [0.2], [0.0], t_end=2.0, method="conformal_leapfrog")
    assert sim.trajectory.method.name == "conformal_leapfrog"
    assert "conformal_leapfrog" in sim.controls["method"].options
    assert "conformal_leapfrog" not in widgets.live_simulator(DRIVEN, t_end=2.0).controls[
        "method"].options


def test_the_sliders_change_parameters_and_keep_damping_and_drive():
    sim = widgets.live_simulator(DRIVEN, [0.2], [0.0], t_end=5.0, method="rk4")
    sim.controls["mass"].value = 2.0
    assert sim.model.masses == (2.0,)
    assert sim.model.damping == DRIVEN.damping
    assert (sim.model.drive_amplitude, sim.model.drive_frequency) == (1.2, DRIVEN.drive_frequency)
    direct = pl.simulate(DRIVEN.replace(masses=(2.0,)), [0.2], [0.0], t_end=5.0, method="rk4")
    np.testing.assert_array_equal(sim.trajectory.theta, direct.theta)


def test_the_browser_is_told_the_energy_is_not_conserved():
    sim = widgets.live_simulator(DRIVEN, [0.2], [0.0], t_end=2.0, method="rk4")
    (content, _), *_ = widgets.live.run_messages(sim.trajectory, sim.model, run=1)
    assert content["conserved"] is False
    assert content["forces"] == "damping 0.5 N m s/rad, drive 1.2 cos(0.6667 t) N m"
    (plain, _), *_ = widgets.live.run_messages(
        pl.simulate(SIMPLE, [0.2], [0.0], t_end=1.0), SIMPLE, run=1
    )
    assert plain["conserved"] is True


def test_the_explorer_runs_the_damped_double_pendulum_and_notes_its_forces():
    damped = pl.double_pendulum(damping=0.1)
    ex = widgets.explore(damped, t_end=5.0, method="glrk4", plots=("energy", "energy_error"))
    direct = pl.simulate(damped, [2.0, 2.5], [0.0, 0.0], t_end=5.0, method="glrk4")
    np.testing.assert_array_equal(ex.trajectory.theta, direct.theta)
    assert direct.energy[-1] < direct.energy[0] - 1.0  # damping takes joules out
    assert ex.figure.axes[1].get_title().startswith("Energy change")
    notes = [w.value for w in ex.widget.children[0].children[1].children if hasattr(w, "value")
             and isinstance(w.value, str)]
    assert any("damping 0.1 N m s/rad" in note for note in notes)
    plain = widgets.explore(pl.double_pendulum(), t_end=5.0, plots=("energy", "energy_error"))
    assert plain.figure.axes[1].get_title().startswith("Energy error")


@pytest.mark.parametrize("explorer", [widgets.section_explorer, widgets.explore_energy,
                                      widgets.explore_equilibrium],
                         ids=["section", "energy", "equilibrium"])
def test_explorers_of_conserved_energy_refuse_a_damped_model(explorer):
    with pytest.raises(ValueError, match="no damping and no drive") as refused:
        explorer(pl.double_pendulum(damping=0.1))
    assert "damping 0.1 N m s/rad" in str(refused.value)
    # Negative control: the conservative double pendulum is accepted.
    assert explorer(pl.double_pendulum()) is not None


def test_the_portrait_explorer_launches_the_driven_orbit_and_says_the_curves_are_not_its():
    ex = widgets.portrait_explorer(DRIVEN, t_end=10.0, dt=0.01, method="rk4")
    assert "without damping and drive" in ex.message
    assert ex.click(0.2, 0.0)
    direct = pl.simulate(DRIVEN, [0.2], [0.0], t_end=10.0, dt=0.01, method="rk4")
    np.testing.assert_allclose(ex.orbits[0].points[:, 1], direct.omega[:, 0])
    assert "not conserved" in ex.message
    plain = widgets.portrait_explorer(SIMPLE, t_end=10.0)
    assert "without damping" not in plain.message
    assert plain.click(0.2, 0.0) and "not conserved" not in plain.message


def test_forces_text_names_every_joint_when_they_differ():
    model = pl.n_pendulum(3, damping=[0.1, 0.0, 0.2])
    assert controls.forces_text(model) == "damping 0.1, 0, 0.2 N m s/rad, no drive"
    assert controls.forces_text(SIMPLE) == "no damping, no drive"
    assert controls.energy_is_conserved(SIMPLE) and not controls.energy_is_conserved(model)


def test_what_changes_a_systems_energy_is_said_from_the_system_itself():
    from pendulum_lab.widgets.live import run_messages

    kapitza = widgets.live_simulator(pl.kapitza_pendulum(), t_end=1.0, dt=0.002, method="rk4")
    message = kapitza.message
    assert "not conserved (no damping or applied forces, a point moved with the time" in message
    assert "the work of the moving point plus the method's error" in message
    # no force is named that the system does not have
    assert "besides the potential" not in message and "the forces' work" not in message
    meta = run_messages(kapitza.trajectory, kapitza.model, run=1)[0][0]
    assert meta["changed_by"] == "the moving point" and not meta["conserved"]
    # negative controls: the damped, driven chain names both; a conservative system nothing
    assert controls.energy_changers(DRIVEN) == "the damping and the drive"
    assert controls.energy_changers(pl.driven_pendulum(drive_amplitude=0.0)) == "the damping"
    assert controls.energy_changers(pl.elastic_pendulum()) == ""
    elastic = widgets.live_simulator(pl.elastic_pendulum(), t_end=1.0, dt=0.01, method="rk4")
    assert "not conserved" not in elastic.message
