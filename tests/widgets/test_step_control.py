"""The step box: a value typed into the box at the right end of the Δt slider (and committed
with Enter, which sets the box's value) redoes the run with that step, as a drag does."""

import pytest

import pendulum_lab as pl
from pendulum_lab import widgets
from pendulum_lab.widgets.controls import DT_LIMITS, StepControl


@pytest.fixture
def explorer():
    return widgets.explore(pl.simple_pendulum(), t_end=2.0, method="explicit_euler")


def counting_updates(instrument):
    calls = []
    original = instrument.prepare

    def prepare():
        calls.append(1)
        return original()

    instrument.prepare = prepare
    return calls


def test_a_typed_step_reruns_once_with_that_step(explorer):
    step = explorer.controls["dt"]
    assert isinstance(step, StepControl) and explorer.trajectory.dt == 0.01
    runs = counting_updates(explorer)
    step.box.value = 0.05  # what typing 0.05 and Enter does
    assert explorer.trajectory.dt == 0.05 and step.value == 0.05 and len(runs) == 1
    assert step.ladder.value == 0.05  # the slider moved to it
    assert "dt = 0.05 s" in explorer.message and "40 steps" in explorer.message
    step.box.value = 0.005  # the exercise of notebook 04, second step
    assert explorer.trajectory.dt == 0.005 and len(runs) == 2
    # negative control: the same value again is no change, and runs nothing
    step.box.value = 0.005
    assert len(runs) == 2


def test_a_step_off_the_ladder_is_kept_and_the_slider_rests_on_the_nearest_rung(explorer):
    step = explorer.controls["dt"]
    step.box.value = 0.003
    assert explorer.trajectory.dt == 0.003 and step.value == 0.003
    assert step.ladder.value == 0.002  # log-nearest: 0.003 / 0.002 < 0.005 / 0.003
    # the copied code holds the typed step, to the bit
    assert "dt=0.003," in explorer.code()


def test_a_drag_and_code_set_the_box(explorer):
    step = explorer.controls["dt"]
    step.ladder.value = 0.2
    assert step.box.value == 0.2 and explorer.trajectory.dt == 0.2
    assert explorer.set_controls({"dt": 0.02})
    assert step.box.value == 0.02 and step.ladder.value == 0.02
    assert explorer.trajectory.dt == 0.02


def test_a_step_beyond_the_limits_is_clamped_and_a_run_too_long_is_refused(explorer):
    step = explorer.controls["dt"]
    step.box.value = 0.0  # the box clamps what is typed into it
    assert step.value == DT_LIMITS[0]
    assert "more than the explorer's limit" in explorer.message
    assert explorer.trajectory.dt == 0.01  # the previous run stays, and says why


def test_the_live_simulator_takes_a_typed_step():
    sim = widgets.live_simulator(pl.double_pendulum(), t_end=2.0, method="rk4")
    sim.controls["dt"].box.value = 0.005
    assert sim.trajectory.dt == 0.005
