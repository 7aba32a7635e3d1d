"""Export of the simulator for slides: files decoded and their frames counted."""

import sys

import numpy as np
import pytest
from PIL import Image

import pendulum_lab as pl
from pendulum_lab import animation

DP = pl.double_pendulum()


@pytest.fixture(scope="module")
def sim():
    return animation.simulator(DP, t_end=3.0, dt=0.01)


def gif_frames(path):
    image = Image.open(path)
    frames = []
    for k in range(image.n_frames):
        image.seek(k)
        frames.append((np.asarray(image.convert("RGB")), image.info.get("duration")))
    return frames


def test_gif_has_one_frame_per_tenth_of_a_second(sim, tmp_path):
    path = sim.save(tmp_path / "swing.gif", fps=10, seconds=1.5)
    assert path == tmp_path / "swing.gif"
    frames = gif_frames(path)
    assert len(frames) == 15
    assert all(duration == 100 for _, duration in frames)
    assert frames[0][0].shape == (288, 720, 3)  # 9 x 3.6 inches at 80 dpi
    # The pendulum moves: consecutive frames differ, and frame 0 is the start state.
    assert not np.array_equal(frames[0][0], frames[1][0])
    assert not np.array_equal(frames[5][0], frames[14][0])


def test_gif_of_the_whole_run_at_the_simulators_speed(sim, tmp_path):
    sim.speed.value = 2.0
    try:
        path = sim.save(tmp_path / "whole.gif", fps=5)
    finally:
        sim.speed.value = 1.0
    expected = len(animation.frame_indices(sim.trajectory, 5, 2.0))  # 3 s at 2x, 5 fps
    assert expected == 8 and Image.open(path).n_frames == expected
    # More seconds than the run has: the whole run, no more.
    longer = animation.save_animation(
        sim.trajectory, sim.model, tmp_path / "longer.gif", fps=5, seconds=100.0, dpi=40
    )
    assert Image.open(longer).n_frames == len(animation.frame_indices(sim.trajectory, 5, 1.0))


def test_mp4_decodes_to_the_frames_written(sim, tmp_path):
    ffmpeg = pytest.importorskip(
        "imageio_ffmpeg", reason="imageio-ffmpeg (pendulum_lab[export]) is not installed"
    )
    path = sim.save(tmp_path / "swing.mp4", fps=20, seconds=2.0)
    frames, seconds = ffmpeg.count_frames_and_secs(str(path))
    assert (frames, seconds) == (40, pytest.approx(2.0))
    reader = ffmpeg.read_frames(str(path))
    meta = next(reader)
    assert tuple(meta["size"]) == (720, 288)
    decoded = list(reader)
    assert len(decoded) == 40
    assert all(len(frame) == 720 * 288 * 3 for frame in decoded)
    assert decoded[0] != decoded[-1]  # the pendulum moved


def test_mp4_without_ffmpeg_says_what_to_install(sim, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)  # makes the import fail
    with pytest.raises(ImportError, match="pip install imageio-ffmpeg"):
        sim.save(tmp_path / "swing.mp4", fps=10, seconds=1.0)
    assert not (tmp_path / "swing.mp4").exists()
    assert Image.open(sim.save(tmp_path / "still.gif", fps=10, seconds=0.2)).n_frames == 2


@pytest.mark.parametrize(
    ("name", "kwargs", "message"),
    [
        ("swing.avi", {}, "must end in .gif or .mp4"),
        ("swing.gif", {"seconds": 0.0}, "`seconds` must be a positive number"),
        ("swing.gif", {"seconds": float("nan")}, "`seconds` must be finite"),
        ("swing.gif", {"fps": -1}, r"`fps` must be in \(0, 50\] frames per second"),
    ],
)
def test_bad_export_arguments_are_refused(sim, tmp_path, name, kwargs, message):
    with pytest.raises(ValueError, match=message):
        sim.save(tmp_path / name, **kwargs)
    assert not (tmp_path / name).exists()
