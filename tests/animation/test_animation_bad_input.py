"""Bad input to the exports (GIF, MP4, HTML, a still frame): refused before a frame is drawn.

A path that cannot be written, a missing folder, a resolution of zero, a run that blew up,
a frame rate no file can play and more frames than any slide needs each give a message
naming the argument (or the run) and what is accepted, where they used to give PIL's,
pathlib's or matplotlib's errors, ffmpeg's command line, or hours of drawing.
"""

import dataclasses
import warnings
from pathlib import Path

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab import animation

SP = pl.simple_pendulum()
DP = pl.double_pendulum()
RUN = pl.simulate(SP, [1.0], [0.0], t_end=1.0, dt=0.01, method="rk4")
with warnings.catch_warnings():
    warnings.simplefilter("ignore", RuntimeWarning)
    STOPPED = pl.simulate(DP, [2.0, 2.5], [0.0, 0.0], t_end=100.0, dt=0.9,
                          method="explicit_euler")
# simulate stops a run where its state or its energy leaves the finite numbers (STOPPED ends
# there, not completed); a run holding a non-finite energy can still be made by hand
BLOWN_UP = dataclasses.replace(STOPPED, energy=np.append(STOPPED.energy[:-1], np.inf))


@pytest.fixture
def folder(tmp_path):
    return tmp_path


CASES = {
    "GIF in /proc": (lambda d: animation.save_animation(RUN, SP, "/proc/x.gif"), ValueError,
                     "`path` must be a file that can be written, but '/proc/x.gif' cannot be"),
    "MP4 in /proc": (lambda d: animation.save_animation(RUN, SP, "/proc/y.mp4"), ValueError,
                     "`path` must be a file that can be written"),
    "a missing folder": (lambda d: animation.save_animation(RUN, SP, d / "missing" / "x.gif"),
                         ValueError, "`path` must be in an existing folder"),
    "another suffix": (lambda d: animation.save_animation(RUN, SP, d / "x.png"), ValueError,
                       "`path` must end in .gif or .mp4"),
    "dpi = 0": (lambda d: animation.save_animation(RUN, SP, d / "x.gif", dpi=0), ValueError,
                r"`dpi` must be a positive number \(> 0\), got 0"),
    "a blown-up run": (lambda d: animation.save_animation(BLOWN_UP, DP, d / "x.gif"),
                       ValueError, "`traj` holds non-finite angles or energies from t = "),
    "fps = 1e6": (lambda d: animation.save_animation(RUN, SP, d / "x.gif", fps=1e6, seconds=1),
                  ValueError, r"`fps` must be in \(0, 50\] frames per second"),
    "MP4 at 1000 fps": (lambda d: animation.save_animation(RUN, SP, d / "x.mp4", fps=1000),
                        ValueError, r"`fps` must be in \(0, 120\]"),
    "a trillion frames": (lambda d: animation.save_animation(RUN, SP, d / "x.gif",
                                                             speed=1e-12),
                          ValueError, "would have 20000000000021 frames, more than `max_frames`"),
    "max_frames = 0": (lambda d: animation.save_animation(RUN, SP, d / "x.gif", max_frames=0),
                       ValueError, "`max_frames` must be an integer >= 1"),
    "dpi = 20": (lambda d: animation.save_animation(RUN, SP, d / "x.gif", dpi=20), ValueError,
                 r"`dpi` must be at least 30 .*got 20"),
    "HTML, dpi = 0": (lambda d: animation.html_animation(RUN, SP, dpi=0), ValueError, "`dpi`"),
    "HTML, fps = 1000": (lambda d: animation.html_animation(RUN, SP, fps=1000), ValueError,
                         r"`fps` must be in \(0, 60\]"),
    "HTML, a blown-up run": (lambda d: animation.html_animation(BLOWN_UP, DP), ValueError,
                             "`traj` holds non-finite"),
    "still frame, dpi = -1": (lambda d: animation.still_frame(RUN, SP, dpi=-1), ValueError,
                              "`dpi` must be a positive number"),
}


@pytest.mark.parametrize("case", CASES)
def test_bad_input_is_refused_before_any_frame_is_drawn(case, folder, before_any_work):
    if "/proc" in case and not Path("/proc").is_dir():
        pytest.skip("no /proc on this system (macOS, Windows): a folder that cannot be written")
    call, error, message = CASES[case]
    with before_any_work(), pytest.raises(error, match=message):
        call(folder)
    assert list(folder.iterdir()) == []  # nothing left behind


def test_the_valid_neighbours_are_written(folder):
    from PIL import Image

    gif = animation.save_animation(RUN, SP, folder / "swing.gif", fps=50, dpi=30, seconds=0.2)
    assert Image.open(gif).n_frames == 10
    assert animation.save_animation(RUN, SP, folder / "swing.gif", fps=5, dpi=30,
                                    max_frames=6).exists()  # an existing file is replaced
    with pytest.raises(ValueError, match="would have 6 frames, more than `max_frames` = 5"):
        animation.save_animation(RUN, SP, folder / "swing.gif", fps=5, dpi=30, max_frames=5)


def test_a_run_simulate_stopped_holds_finite_states_and_energies_only():
    assert not STOPPED.completed
    assert np.isfinite(STOPPED.theta).all() and np.isfinite(STOPPED.energy).all()
    assert not np.isfinite(BLOWN_UP.energy).all()  # the hand-made run the exports refuse
