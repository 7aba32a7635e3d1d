"""The live simulator's kernel side for a system in space (the spherical pendulum): the run goes
to the browser with the points' heights, a release seen from above sets the bob's horizontal
start, one beyond the rod's reach is refused with the reason. The drawing, its turning and its
drag are checked in Chromium (tests/browser/test_simulator_in_space.py)."""

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab.widgets.browser import browser_config
from pendulum_lab.widgets.live import run_messages


@pytest.fixture(scope="module")
def sim(spherical):
    return pl.widgets.live_simulator(spherical, [0.4, 0.0], [0.0, 1.5], t_end=1.0, dt=0.01,
                                     method="rk4")


def test_a_run_in_space_travels_with_the_points_heights(sim, spherical):
    (content, buffers), = run_messages(sim.trajectory, spherical, run=1)
    figure = content["figure"]
    assert figure["dimensions"] == 3 and figure["kind"] == "points"
    sent = np.frombuffer(buffers[3], "<f4").reshape(content["states"], 1, 3)
    x, y, z = spherical.positions(sim.trajectory.theta)
    assert np.allclose(sent[..., 2], z, atol=1e-6) and np.allclose(sent[..., 0], x, atol=1e-6)
    assert np.allclose(x ** 2 + y ** 2 + z ** 2, 1.0)  # the rod's length, bob below the pivot
    assert np.all(z < 0)
    # negative control: a planar system's points come as (x, y)
    elastic = pl.elastic_pendulum()
    flat = pl.simulate(elastic, elastic.start, [0.0, 0.0], t_end=0.1, dt=0.01, method="rk4",
                       progress=False)
    (flat_content, flat_buffers), = run_messages(flat, elastic, run=1)
    assert flat_content["figure"]["dimensions"] == 2
    assert np.frombuffer(flat_buffers[3], "<f4").size == flat_content["states"] * 2


def test_a_release_seen_from_above_sets_the_bobs_horizontal_start(sim):
    assert sim.drag(0, 0.3, -0.2)
    assert sim.trajectory.theta[0] == pytest.approx([0.3, -0.2])
    assert sim.trajectory.omega[0] == pytest.approx([0.0, 0.0])
    # what the browser's engine is handed for the same start
    assert sim.browser_settings()["theta0"] == pytest.approx([0.3, -0.2])
    assert browser_config(pl.spherical_pendulum())["figure"]["dimensions"] == 3


def test_a_release_beyond_the_rods_reach_is_refused_and_the_motion_goes_on(sim):
    assert sim.drag(0, 0.3, -0.2)
    sent = []
    sim.view.send = lambda content, buffers=None: sent.append(content)
    sim._on_release({"type": "release", "bob": 0, "x": 1.4, "y": 0.0, "theta": [0.3, -0.2]})
    assert sent == [{"type": "released", "ok": False, "message": sim.message}]
    assert "its rods do not reach there" in sim.message
    assert sim.trajectory.theta[0] == pytest.approx([0.3, -0.2])  # the previous motion
    # negative control: within reach the same message starts a new motion
    sim._on_release({"type": "release", "bob": 0, "x": 0.6, "y": 0.1, "theta": [0.3, -0.2]})
    assert sent[-1]["ok"] is True and sim.trajectory.theta[0] == pytest.approx([0.6, 0.1])
