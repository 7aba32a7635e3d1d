"""The live simulator's kernel side (pendulum_lab.widgets.live), headlessly: buffers, state
sync, drags, replay."""

import json
import math
import re

import numpy as np
import pytest
import traitlets

import pendulum_lab as pl
from pendulum_lab import widgets
from pendulum_lab.widgets import channel, clickable, live
from pendulum_lab.widgets.live import (
    live_simulator,
    playback_stride,
    released_angles,
    run_messages,
)

DP = pl.double_pendulum()


def decode(messages):
    """Concatenate the chunks of one run back into arrays (the layout run_messages documents)."""
    angles, energies, errors = [], [], []
    expected_first = 0
    for content, buffers in messages:
        assert content["first"] == expected_first  # chunks in order, no gap, no overlap
        n, count = content["links"], content["count"]
        angles.append(np.frombuffer(buffers[0], dtype="<f4").reshape(count, n))
        energies.append(np.frombuffer(buffers[1], dtype="<f4").reshape(count, 3))
        errors.append(np.frombuffer(buffers[2], dtype="<f4"))
        expected_first += count
    return np.concatenate(angles), np.concatenate(energies), np.concatenate(errors)


@pytest.fixture
def sim():
    return live_simulator(DP, t_end=4.0, dt=0.01)


def capture_sends(widget, monkeypatch):
    sent = []
    monkeypatch.setattr(
        widget, "send", lambda content, buffers=None: sent.append((content, buffers or []))
    )
    return sent


# --------------------------------------------------------------------------- buffers
def test_a_long_run_round_trips_through_chunked_float32_buffers():
    traj = pl.simulate(DP, [2.0, 2.5], [0.0, 0.0], t_end=3.0, dt=0.005, method="glrk4")
    messages = run_messages(traj, DP, run=7, chunk_states=64)
    kept = slice(None, None, 2)  # dt = 5 ms: every second state keeps them 10 ms apart
    assert len(messages) == math.ceil(301 / 64) == 5
    angles, energies, error = decode(messages)
    np.testing.assert_array_equal(angles, traj.theta[kept].astype(np.float32))
    both = np.column_stack([traj.kinetic, traj.potential, traj.energy])[kept]
    np.testing.assert_array_equal(energies, both.astype(np.float32))
    np.testing.assert_array_equal(error, traj.energy_error[kept].astype(np.float32))
    header = messages[-1][0]
    assert header["run"] == 7 and header["chunks"] == 5 and header["states"] == 301
    assert header["spacing"] == pytest.approx(0.01) and header["steps"] == 600
    assert header["error_max"] == pytest.approx(np.max(np.abs(traj.energy_error)))
    assert header["energy_range"][0] <= min(0.0, both.min())
    assert header["energy_range"][1] >= max(0.0, both.max())
    # Negative control, and why the error travels on its own: the difference of float32
    # energies cannot resolve an error of 1e-8 J on 16 J.
    from_energies = energies[:, 2] - energies[0, 2]
    assert np.max(np.abs(from_energies - error)) > 1e-7


def test_buffers_are_raw_bytes_and_headers_hold_no_arrays():
    traj = pl.simulate(DP, [2.0, 2.5], [0.0, 0.0], t_end=20.0, dt=0.01, method="glrk4")
    ((content, buffers),) = run_messages(traj, DP, run=1)
    assert [b.nbytes for b in buffers] == [2001 * 2 * 4, 2001 * 3 * 4, 2001 * 4]
    assert all(isinstance(b, memoryview) and b.format == "B" for b in buffers)
    text = json.dumps(content)
    assert len(text) < 800 and not re.search(r"\[[^\]]{60,}\]", text)


@pytest.mark.parametrize(
    ("dt", "stride"), [(0.01, 1), (0.005, 2), (0.002, 5), (0.0005, 20), (0.02, 1), (0.5, 1)]
)
def test_sent_states_are_at_most_ten_milliseconds_apart(dt, stride):
    assert playback_stride(dt) == stride
    assert stride * dt <= 0.01 + 1e-12 or stride == 1


def test_run_messages_refuses_an_ensemble():
    batch = pl.simulate(DP, [[2.0, 2.5], [1.0, 1.0]], [[0.0, 0.0]] * 2, t_end=0.1, dt=0.01)
    with pytest.raises(TypeError, match="single Trajectory"):
        run_messages(batch, DP, run=1)


# --------------------------------------------------------------------------- state sync
def test_a_slider_change_sends_a_new_run_and_restarts_playback(sim, monkeypatch):
    sent = capture_sends(sim.view, monkeypatch)
    sim.view.time = 2.5
    run = sim.view.run
    sim.controls["theta1"].value = 0.3
    assert sim.view.run == run + 1 and sim.view.time == 0.0
    ((content, buffers),) = sent
    assert content["run"] == run + 1
    angles, _, _ = decode(sent)
    assert angles[0].tolist() == pytest.approx([0.3, 2.5])
    assert sim.trajectory.theta[0].tolist() == [0.3, 2.5]


def test_a_new_view_gets_the_current_run_again(sim, monkeypatch):
    sent = capture_sends(sim.view, monkeypatch)
    sim.view._dispatch(sim.view, {"type": "ready"}, [])
    assert [c for c, _ in sent] == [c for c, _ in sim.view._log]
    assert len(sent) == 1 and sent[0][0]["run"] == sim.view.run
    sim.view._dispatch(sim.view, {"type": "no such thing"}, [])
    sim.view._dispatch(sim.view, "not a dict", [])
    assert len(sent) == 1  # unknown messages are ignored


def test_playback_traits_are_validated(sim):
    sim.view.speed = 2.0
    with pytest.raises(traitlets.TraitError, match="speed"):
        sim.view.speed = 3.0
    with pytest.raises(traitlets.TraitError, match="trail"):
        sim.view.trail = -1.0
    assert sim.view.speed == 2.0 and sim.view.trail == 2.0
    with pytest.raises(ValueError, match="speed"):
        live_simulator(DP, t_end=2.0, speed=3.0)
    with pytest.raises(ValueError, match="t_end"):
        live_simulator(DP, t_end=100.0)


def test_the_live_simulator_is_an_instrument_without_a_figure(sim):
    import ipywidgets

    assert isinstance(sim, widgets.Instrument) and sim.figure is None
    children = sim.widget.children
    assert not any(isinstance(child, ipywidgets.Image) for child in children)
    assert isinstance(children[-1], live.PendulumView) and children[-1] is sim.view
    # Its controls are the matplotlib simulator's (one definition for both).
    from pendulum_lab import animation

    other = animation.simulator(DP, t_end=4.0, dt=0.01)
    assert list(sim.controls) == list(other.controls)
    assert sim.controls["t_end"].max == other.controls["t_end"].max == 60.0


def test_a_failed_run_keeps_the_previous_one_and_says_why(sim, monkeypatch):
    sim.controls["dt"].value = 0.0005  # 8000 steps of 0.5 ms: fine
    kept, run = sim.trajectory, sim.view.run
    sent = capture_sends(sim.view, monkeypatch)
    sim.controls["t_end"].value = 60.0  # 120 000 steps: over the explorers' limit
    assert sim.view.message_kind == "error" and "limit" in sim.view.message
    assert sim.trajectory is kept and sim.view.run == run and not sent
    # Negative control: a shorter run goes through and is sent.
    sim.controls["t_end"].value = 30.0
    assert sim.view.message_kind == "info" and sim.view.run == run + 1 and len(sent) == 1


# --------------------------------------------------------------------------- dragging
def test_released_angles_point_the_arm_at_the_release():
    # Straight right of the pivot, then straight up from the first bob's joint.
    assert released_angles(DP, [0.0, 0.0], 0, 0.7, 0.0) == pytest.approx([np.pi / 2, 0.0])
    np.testing.assert_allclose(
        released_angles(DP, [np.pi / 2, 0.0], 1, 1.0, 0.4), [np.pi / 2, np.pi]
    )
    # The first bob is the second arm's joint: a release below it hangs the arm down.
    np.testing.assert_allclose(
        released_angles(DP, [np.pi / 2, 1.0], 1, 1.0, -3.0), [np.pi / 2, 0.0], atol=1e-15
    )
    # Angles come back in (-pi, pi], the sliders' range.
    wrapped = released_angles(DP, [7.0, -np.pi], 0, -1.0, -1.0)
    assert wrapped == pytest.approx([-np.pi / 4, np.pi])


def test_a_release_beyond_the_reach_of_the_chain_is_clamped_not_an_error():
    near = released_angles(DP, [0.3, 0.4], 0, 0.5, 0.5)
    far = released_angles(DP, [0.3, 0.4], 0, 500.0, 500.0)  # 700 m away, rods of 1 m
    np.testing.assert_allclose(far, near, rtol=0, atol=1e-15)
    x, y = DP.positions(far)
    assert math.hypot(x[0], y[0]) == pytest.approx(1.0)  # the bob stays on its rod's circle


@pytest.mark.parametrize(
    ("bob", "x", "y", "theta", "what"),
    [
        (0, float("nan"), 0.0, [0.0, 0.0], "`x` must be finite"),
        (0, 0.5, float("inf"), [0.0, 0.0], "`y` must be finite"),
        (0, 0.5, 0.5, [float("nan"), 0.0], "`theta` must be finite"),
        (2, 0.5, 0.5, [0.0, 0.0], "`bob` must be in [0, 1]"),
        (True, 0.5, 0.5, [0.0, 0.0], "`bob` must be an integer"),
        (0, 0.5, 0.5, [0.0, 0.0, 0.0], "`theta` must have shape (..., 2)"),
        (0, 0.0, 0.0, [0.0, 0.0], "joint of arm 1"),
        (1, 0.0, -1.0, [0.0, 0.0], "joint of arm 2"),
    ],
)
def test_bad_releases_are_refused_with_a_sentence(bob, x, y, theta, what):
    with pytest.raises((TypeError, ValueError), match=re.escape(what)):
        released_angles(DP, theta, bob, x, y)


def test_a_drag_sets_the_initial_state_at_rest_and_recomputes_once(sim):
    sim.controls["omega2"].value = 1.5
    run = sim.view.run
    assert sim.drag(1, 5.0, -2.0, theta=[0.4, 0.1])
    expected = released_angles(DP, [0.4, 0.1], 1, 5.0, -2.0)
    np.testing.assert_allclose(sim.trajectory.theta[0], expected)
    np.testing.assert_array_equal(sim.trajectory.omega[0], [0.0, 0.0])
    assert [sim.controls[k].value for k in ("theta1", "theta2", "omega1", "omega2")] == (
        pytest.approx([*expected, 0.0, 0.0])
    )
    assert sim.view.run == run + 1  # one recompute for four slider changes
    assert sim.view.playing and sim.view.message == ""
    # Negative control: moving two sliders by hand recomputes twice.
    sim.controls["theta1"].value = 0.1
    sim.controls["theta2"].value = 0.2
    assert sim.view.run == run + 3


def test_a_bad_drag_from_code_raises_and_leaves_the_simulator_as_it_was(sim):
    previous, run = sim.trajectory, sim.view.run
    theta_before, message_before = sim.controls["theta1"].value, sim.message
    with pytest.raises(ValueError, match="`x` must be finite"):
        sim.drag(0, float("nan"), 0.3)
    assert sim.trajectory is previous and sim.view.run == run
    assert sim.controls["theta1"].value == theta_before
    # Nothing red is left in the widget: the refusal belongs to the caller's cell.
    assert sim.message == message_before and sim.status.kind == "info"
    assert sim.view.message == "" and sim.view.message_kind == "info"


def test_a_bad_drag_in_the_browser_says_why_in_the_widget(sim):
    previous, run = sim.trajectory, sim.view.run
    sim.view._dispatch(sim.view, {"type": "release", "bob": 0, "x": None, "y": 0.3}, [])
    assert sim.trajectory is previous and sim.view.run == run
    assert sim.view.message_kind == "error" and sim.status.kind == "error"
    assert "`x` must be finite" in sim.view.message and "previous motion" in sim.view.message


def test_the_browser_release_message_gets_an_answer(sim, monkeypatch):
    sent = capture_sends(sim.view, monkeypatch)
    run = sim.view.run
    # JavaScript's NaN arrives as null (None) in JSON.
    sim.view._dispatch(
        sim.view, {"type": "release", "bob": 0, "x": None, "y": 0.0, "theta": [1.0, 2.0]}, []
    )
    assert sent[-1][0] == {"type": "released", "ok": False, "message": sim.message}
    sim.view._dispatch(
        sim.view, {"type": "release", "bob": 0, "x": -2.0, "y": 0.0, "theta": [1.0, 2.0]}, []
    )
    assert sent[-1][0]["type"] == "released" and sent[-1][0]["ok"] is True
    assert sent[-2][0]["type"] == "run" and sim.view.run == run + 1
    assert sim.trajectory.theta[0].tolist() == pytest.approx([-np.pi / 2, 2.0])


def test_display_carries_a_picture_of_the_whole_run(sim):
    """Where no kernel runs (the course website) the display's PNG stands in for the canvas:
    the run drawn at its last state, so the picture changes with the run."""
    import base64
    import io

    from PIL import Image

    from pendulum_lab import animation

    bundle = sim._repr_mimebundle_()
    assert "application/vnd.jupyter.widget-view+json" in bundle
    data = base64.b64decode(bundle["image/png"])
    assert data == animation.still_frame(sim.trajectory, sim.model)
    assert Image.open(io.BytesIO(data)).size == (720, 288)  # 9 x 3.6 inches at 80 dpi
    # The last state, not the first: the first frame of the same run differs.
    assert data != animation.still_frame(sim.trajectory, sim.model, index=0)
    sim.controls["theta1"].value = 0.3
    assert base64.b64decode(sim._repr_mimebundle_()["image/png"]) != data


# --------------------------------------------------------------------------- the package
def test_front_end_modules_ship_with_the_package_and_fetch_nothing():
    for name in ("simulator.js", "clickable.js", "status.js", "live.css"):
        text = (channel.STATIC / name).read_text(encoding="utf-8")
        assert not re.search(r"https?://", text), f"{name} names a URL"
        assert not re.search(r"^\s*import\s", text, re.MULTILINE), f"{name} imports a module"
    assert str(live.PendulumView._esm) == (channel.STATIC / "simulator.js").read_text()
    assert "export default { render }" in str(clickable.ClickablePlot._esm)
