"""The matplotlib pendulum simulator, its exports (HTML, GIF, MP4) for use without a kernel.

The course report (Kanoun, Cowley, Ivachtchenko, MAT332, 2024) studied its
integrators in an interactive simulator: a swinging pendulum, its kinetic,
potential and total energy, and the time. :func:`simulator` brings it into the
notebook: the chain with the trail of its last bob, the energies drawn up to
the current time with a numeric readout, play/pause and speed controls, and
the sliders of :func:`pendulum_lab.widgets.explore` for the initial state, the
parameters, the method and the step.

How it renders: the trajectory is computed once per change of a slider (with
the fast core, a 20 s double-pendulum run takes milliseconds); playing only
moves through the stored states. Each frame updates the data of a few
artists, redraws just those over a cached background (blitting into the Agg
buffer) and sends it as a JPEG to an ``ipywidgets.Image``. An ``ipywidgets.Play``
drives the frame slider at :data:`FPS` frames per second. This works in
JupyterLab with the inline backend and needs no interactive matplotlib
backend. The course's default simulator is the browser-drawn
:func:`pendulum_lab.widgets.live_simulator`, which sends the run once instead
of an image per frame; this one draws the pictures of the report and the
exports.

Where no kernel is attached (a notebook viewed as a static page), widgets
cannot run; :func:`html_animation` renders the same drawing as a
self-contained JavaScript/HTML animation (matplotlib's HTML player, the one
behind :meth:`matplotlib.animation.Animation.to_jshtml`) whose frames are
embedded in the output. For slides, :func:`save_animation` (and
:meth:`Simulator.save`) writes it as an animated GIF (Pillow) or an MP4 (the
ffmpeg binary that the ``imageio-ffmpeg`` package ships), and :func:`still_frame`
one frame as PNG.

Layout: :mod:`pendulum_lab.plotting.scene` (the drawing and the frames of a run, and a still
PNG), :mod:`.simulator` (the matplotlib simulator), :mod:`.export` (HTML, GIF, MP4).
"""

from ..plotting.scene import (
    EXPORT_SIZE,
    FPS,
    RUN_COLOURS,
    TRAIL,
    PendulumScene,
    encode_frame,
    frame_indices,
    scene_runs,
    still_frame,
)
from ..widgets.controls import SPEEDS
from .export import MAX_FRAMES, count_frames, html_animation, save_animation
from .simulator import Simulator, simulator

__all__ = [
    "EXPORT_SIZE",
    "FPS",
    "MAX_FRAMES",
    "RUN_COLOURS",
    "SPEEDS",
    "TRAIL",
    "PendulumScene",
    "Simulator",
    "count_frames",
    "encode_frame",
    "frame_indices",
    "html_animation",
    "save_animation",
    "scene_runs",
    "simulator",
    "still_frame",
]
