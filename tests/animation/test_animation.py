"""The live simulator and the HTML animation, driven without a browser."""

import re

import numpy as np
import pytest
from matplotlib.animation import FuncAnimation
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

import pendulum_lab as pl
from pendulum_lab import animation

DP = pl.double_pendulum()
SP = pl.simple_pendulum()


@pytest.fixture
def sim():
    return animation.simulator(DP, t_end=4.0, dt=0.01)


def test_frames_advance_when_play_changes(sim):
    first_image = sim._image.value
    assert sim.frame.value == 0 and sim.time == 0.0
    sim.play.value = 10
    assert sim.frame.value == 10  # play is linked to the frame slider
    assert sim.time == pytest.approx(10 / animation.FPS)
    assert sim._image.value != first_image
    sim.play.value = 11
    assert sim.time == pytest.approx(11 / animation.FPS)
    assert sim.frame.max == 4.0 * animation.FPS


def test_drawn_chain_is_the_models_positions(sim):
    sim.play.value = 37
    independent = pl.simulate(DP, [2.0, 2.5], [0.0, 0.0], t_end=4.0, dt=0.01, method="glrk4")
    theta = independent.theta[sim.index]
    x, y = DP.positions(theta)
    rod_x, rod_y = sim.scene.rods.get_data()
    assert np.allclose(rod_x, [0.0, *x], atol=1e-12) and np.allclose(rod_y, [0.0, *y], atol=1e-12)
    bob_x, bob_y = sim.scene.bobs.get_data()
    assert np.allclose(bob_x, x) and np.allclose(bob_y, y)
    trail_x, trail_y = sim.scene.trail_line.get_data()
    assert (trail_x[-1], trail_y[-1]) == (x[-1], y[-1])
    # the trail covers the last two seconds of the last bob's path, no more
    assert len(trail_x) == min(sim.index, round(animation.TRAIL / 0.01)) + 1
    # negative control: another frame shows another configuration
    sim.play.value = 3
    assert not np.allclose(sim.scene.rods.get_data()[0], [0.0, *x])


def test_energy_readout_matches_the_trajectory(sim):
    sim.play.value = 25
    traj, k = sim.trajectory, sim.index
    assert sim.time == traj.t[k] == pytest.approx(25 / animation.FPS)
    text = sim.readout.value
    for value in (traj.t[k], traj.kinetic[k], traj.potential[k], traj.energy[k]):
        assert f"{value:.2f}" in text
    for key, values in (
        ("kinetic", traj.kinetic),
        ("potential", traj.potential),
        ("total", traj.energy),
    ):
        t, shown = sim.scene.energy_lines[key].get_data()
        assert len(shown) == k + 1 and shown[-1] == values[k] and t[-1] == traj.t[k]
    assert traj.kinetic[k] + traj.potential[k] == pytest.approx(traj.energy[k])
    before = sim.readout.value
    sim.play.value = 60
    assert sim.readout.value != before


def test_speed_keeps_the_time_shown(sim):
    sim.play.value = 20
    assert sim.time == pytest.approx(1.0)
    sim.speed.value = 2.0
    assert sim.time == pytest.approx(1.0) and sim.frame.value == 10
    assert sim.frame.max == 4.0 * animation.FPS / 2
    sim.play.value = 11
    assert sim.time == pytest.approx(1.1)


def test_changing_a_control_reruns_and_restarts(sim):
    sim.play.value = 30
    sim.controls["theta1"].value = 1.0
    assert sim.trajectory.theta[0, 0] == 1.0 and sim.frame.value == 0 and sim.time == 0.0
    sim.controls["method"].value = "rk4"
    assert sim.trajectory.method.name == "rk4"
    assert "glrk4" not in sim.message and "rk4" in sim.message


def test_simple_pendulum_simulator():
    sim = animation.simulator(SP, theta0=[0.5], t_end=2.0, method="leapfrog")
    sim.play.value = 20
    x, y = SP.positions(sim.trajectory.theta[sim.index])
    assert sim.scene.bobs.get_data()[0].shape == (1,)
    assert np.allclose(sim.scene.rods.get_data()[0], [0.0, x[0]])
    assert set(sim.controls) >= {"theta", "omega", "dt", "method", "t_end"}


def test_blitting_draws_the_same_picture_as_a_full_redraw():
    traj = pl.simulate(DP, [2.0, 2.5], [0.0, 0.0], t_end=2.0, dt=0.01)

    def pixels(blit: bool, restore: bool = True):
        figure = Figure(figsize=(6, 3), dpi=60)
        canvas = FigureCanvasAgg(figure)
        scene = animation.PendulumScene(figure, DP, traj, animated=blit)
        if not blit:
            scene.show(150)
            canvas.draw()
            return np.asarray(canvas.buffer_rgba())[..., :3].astype(int)
        canvas.draw()
        background = canvas.copy_from_bbox(figure.bbox)
        for index in (0, 150):
            if restore:
                canvas.restore_region(background)
            for artist in scene.show(index):
                figure.draw_artist(artist)
        return np.asarray(canvas.buffer_rgba())[..., :3].astype(int)

    full = pixels(blit=False)

    def differing(image):
        return np.mean(np.any(np.abs(image - full) > 40, axis=-1))

    assert differing(pixels(blit=True)) < 0.002
    # negative control: without restoring the background, frame 0 stays visible
    assert differing(pixels(blit=True, restore=False)) > 0.005


def test_frame_indices():
    traj = pl.simulate(SP, [1.0], [0.0], t_end=2.0, dt=0.01)
    frames = animation.frame_indices(traj, fps=10, speed=0.5)
    assert len(frames) == 41 and frames[-1] == 200
    assert np.allclose(traj.t[frames], np.arange(41) * 0.05)
    with pytest.raises(ValueError, match="`fps` must be a positive number"):
        animation.frame_indices(traj, fps=0, speed=1.0)


def test_html_animation_embeds_one_image_per_frame():
    traj = pl.simulate(DP, [2.0, 2.5], [0.0, 0.0], t_end=2.0, dt=0.01)
    html = animation.html_animation(traj, DP, fps=10)
    expected = len(animation.frame_indices(traj, 10, 1.0))
    assert expected == 21
    assert animation.count_frames(html.data) == expected
    assert html.data.count("data:image/png;base64,") == expected
    assert "<script" in html.data and "http" not in html.data.split("<script")[1][:200]
    # Nothing is loaded from outside the page (matplotlib's own player links a CDN stylesheet,
    # the negative control), so the animation plays offline.
    external = re.compile(r"""(?:href|src)\s*=\s*["']https?://""")
    assert not external.search(html.data)
    figure = Figure()
    raw = FuncAnimation(figure, lambda k: [], frames=2).to_jshtml()
    assert external.search(raw)
    faster = animation.html_animation(traj, DP, fps=10, speed=2.0)
    assert animation.count_frames(faster.data) == 11
    with pytest.raises(ValueError, match="more than `max_frames` = 5"):
        animation.html_animation(traj, DP, fps=10, max_frames=5)


def test_bad_arguments():
    with pytest.raises(ValueError, match="`speed` must be one of"):
        animation.simulator(DP, speed=3.0)
    with pytest.raises(ValueError, match=r"`t_end` must be in \[1, 60\]"):
        animation.simulator(DP, t_end=500.0)
    with pytest.raises(TypeError, match="`model` must be a PendulumModel"):
        animation.simulator("double")
    ensemble = pl.simulate(SP, [[1.0], [0.5]], [[0.0], [0.0]], t_end=1.0, dt=0.1)
    with pytest.raises(ValueError, match="one trajectory"):
        animation.html_animation(ensemble, SP)


def two_releases(t_end=12.0, nudge=1e-6):
    """The chaotic release and one a micro-radian away, saved at the same times."""
    return [
        pl.simulate(DP, [2.0 + d, 2.5], [0.0, 0.0], t_end=t_end, dt=0.01, method="glrk4")
        for d in (0.0, nudge)
    ]


def test_a_scene_overlays_several_runs_each_at_its_own_state():
    runs = two_releases()
    figure = Figure(figsize=(6, 3), dpi=40)
    FigureCanvasAgg(figure)
    scene = animation.PendulumScene(figure, DP, runs, labels=["a", "b"])
    assert scene.labels == ["a", "b"] and len(scene.chains) == 2
    for index in (0, 500, 1100):
        scene.show(index)
        for (rods, bobs, trail), run in zip(scene.chains, runs):
            x, y = DP.positions(run.theta[index])
            assert np.allclose(rods.get_data()[0], [0.0, *x]) and np.allclose(bobs.get_data()[1], y)
            assert (trail.get_data()[0][-1], trail.get_data()[1][-1]) == (x[-1], y[-1])
        for k, run in enumerate(runs):
            t, total = scene.energy_lines["total", k].get_data()
            assert t[-1] == run.t[index] and total[-1] == run.energy[index]
            assert scene.energy_lines["kinetic", k].get_data()[1][-1] == run.kinetic[index]
        assert scene.readout_text(index).endswith(
            f"{runs[0].energy[index]:.3f} | {runs[1].energy[index]:.3f} J"
        )
    # At the start the two chains coincide; after 11 s the runs have parted, so each chain is
    # drawn from its own run (negative control: the first run's positions are not the second's).
    lower_bobs = [scene.chains[k][1].get_data() for k in (0, 1)]
    assert np.hypot(*(np.subtract(lower_bobs[0], lower_bobs[1])[:, -1])) > 0.1
    scene.show(0)
    assert np.allclose(scene.chains[0][0].get_data(), scene.chains[1][0].get_data(), atol=1e-5)


def test_several_runs_in_one_animation_and_their_labels():
    runs = [
        pl.simulate(DP, [2.0, 2.5], [0.0, 0.0], t_end=2.0, dt=0.01, method=name)
        for name in ("leapfrog", "leapfrog_velocity")
    ]
    html = animation.html_animation(runs, DP, fps=5)
    assert animation.count_frames(html.data) == len(animation.frame_indices(runs[0], 5, 1.0))
    assert animation.scene_runs(runs)[1] == [
        "leapfrog, dt = 0.01 s",
        "leapfrog_velocity, dt = 0.01 s",
    ]
    same = two_releases(t_end=1.0)
    assert animation.scene_runs(same)[1] == ["run 1", "run 2"]  # method and step alike
    # The second run is drawn: the picture differs from the first run's alone.
    assert animation.still_frame(runs, DP, dpi=30) != animation.still_frame(runs[0], DP, dpi=30)


def test_runs_that_cannot_share_a_scene_are_refused():
    runs = two_releases(t_end=1.0)
    shorter = pl.simulate(DP, [2.0, 2.5], [0.0, 0.0], t_end=0.5, dt=0.01, method="glrk4")
    with pytest.raises(ValueError, match="must be saved at the same times"):
        animation.html_animation([runs[0], shorter], DP)
    with pytest.raises(ValueError, match="`labels` must have one entry per run"):
        animation.still_frame(runs, DP, labels=["only one"])
    with pytest.raises(ValueError, match="1 to 5 trajectories"):
        animation.still_frame(runs * 3, DP)
    with pytest.raises(TypeError, match="`traj` must be a Trajectory or a list"):
        animation.html_animation([runs[0], "run"], DP)
    with pytest.raises(ValueError, match="one trajectory of this 1-link model"):
        animation.still_frame(runs, SP)
