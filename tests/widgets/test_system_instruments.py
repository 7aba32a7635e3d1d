"""The instruments on systems given by their points: sliders named after the system's
coordinates and parameters, the runs they compute, the code they copy and what the live
simulator sends the browser."""

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab import widgets
from pendulum_lab.widgets.calls import model_code
from pendulum_lab.widgets.live import released_angles, run_messages


def test_the_sliders_are_the_systems_coordinates_and_parameters(elastic):
    ex = widgets.explore(elastic, t_end=1.0, dt=0.01, method="rk4")
    described = {key: c.description for key, c in ex.controls.items()}
    assert described["theta1"] == "r" and described["theta2"] == "θ (rad)"
    assert described["omega2"] == "dθ/dt (rad/s)"
    assert {"m", "k", "l_0", "g"} <= set(ex.controls)
    # An angle's slider spans a turn; the length's does not stop at pi.
    assert ex.controls["theta2"].max == pytest.approx(3.14)
    assert ex.controls["theta1"].max > np.pi


def test_a_parameter_slider_changes_the_model_that_runs(elastic):
    ex = widgets.explore(elastic, t_end=1.0, dt=0.01, method="rk4")
    stiff = pl.simulate(elastic.replace(k=60.0), elastic.start, [0.0, 0.0], t_end=1.0, dt=0.01,
                        method="rk4", progress=False)
    assert not np.allclose(ex.trajectory.theta, stiff.theta)  # control: k differs at first
    assert ex.set_controls({"k": 60.0})
    np.testing.assert_array_equal(ex.trajectory.theta, stiff.theta)


def test_copied_code_builds_the_same_system_again():
    model = pl.cart_pendulum(mass=0.25).replace(l=0.8)
    code = model_code(model)
    rebuilt = eval(code, {"pl": pl})
    assert rebuilt.parameter_values == model.parameter_values
    assert rebuilt.parameter_values != pl.cart_pendulum().parameter_values  # control


def test_the_live_simulator_sends_a_systems_points(elastic):
    traj = pl.simulate(elastic, elastic.start, [0.0, 0.0], t_end=0.5, dt=0.01, method="rk4",
                       progress=False)
    (content, buffers), = run_messages(traj, elastic, run=1)
    figure = content["figure"]
    assert figure["kind"] == "points" and figure["springs"] == [[-1, 0]]
    assert len(buffers) == 4
    points = np.frombuffer(buffers[3], "<f4").reshape(content["states"], 1, 2)
    x, y = elastic.positions(traj.theta, traj.t)
    np.testing.assert_allclose(points[..., 0], x, rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(points[..., 1], y, rtol=1e-6, atol=1e-7)
    assert figure["reach"] == pytest.approx(np.abs(np.r_[x.ravel(), y.ravel()]).max(), rel=1e-12)
    # A chain sends no points: the browser computes them from the angles.
    dp = pl.double_pendulum()
    chain_run = pl.simulate(dp, [1.0, 0.5], [0.0, 0.0], t_end=0.5, dt=0.01, progress=False)
    (chain, chain_buffers), = run_messages(chain_run, dp, run=1)
    assert chain["figure"]["kind"] == "chain" and len(chain_buffers) == 3


def test_a_drag_on_the_kapitza_pendulum_places_the_bob_and_refuses_the_pivot():
    kapitza = pl.kapitza_pendulum()
    sim = widgets.live_simulator(kapitza, t_end=1.0, dt=0.002)
    assert sim.drag(1, 0.6, -0.7)
    x, y = kapitza.positions(sim.trajectory.theta[0], 0.0)
    bob_direction = np.arctan2(x[1] - x[0], -(y[1] - y[0]))
    assert bob_direction == pytest.approx(np.arctan2(0.6, -(-0.7 - 0.05)))
    with pytest.raises(ValueError, match="prescribed"):
        released_angles(kapitza, sim.trajectory.theta[0], 0, 0.0, 0.5)
