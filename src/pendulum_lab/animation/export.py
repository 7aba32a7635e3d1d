"""A run's animation for places without a kernel: HTML, GIF, MP4, a still PNG.

:func:`html_animation` embeds the frames in a self-contained HTML player
(matplotlib's, the one behind
:meth:`matplotlib.animation.Animation.to_jshtml`); :func:`save_animation`
writes an animated GIF (Pillow) or an MP4 (the ffmpeg binary that the
``imageio-ffmpeg`` package ships). Both draw the scene of :mod:`pendulum_lab.plotting.scene`
(whose :func:`~pendulum_lab.plotting.scene.still_frame` draws one frame), blitting only the
moving artists, and both take one run or several runs of a model saved at the same times,
overlaid.
"""

from __future__ import annotations

import base64
import os
import re
import subprocess
import tempfile
from pathlib import Path

import numpy as np
from matplotlib.animation import FFMpegWriter, HTMLWriter, PillowWriter
from PIL import Image

from .. import validation as check
from ..model.pendulum import PendulumModel
from ..plotting.scene import (
    FPS,
    TRAIL,
    PendulumScene,
    check_run,
    encode_frame,
    export_scene,
    frame_count,
    frame_indices,
    scene_runs,
)

__all__ = [
    "MAX_FPS",
    "MAX_FRAMES",
    "MAX_SAVED_FRAMES",
    "count_frames",
    "html_animation",
    "save_animation",
]


#: Default cap on the frames of :func:`html_animation` (each is an embedded PNG).
MAX_FRAMES = 300
#: Default cap on the frames of :func:`save_animation`: 2.5 minutes at the default 20 fps.
MAX_SAVED_FRAMES = 3000
#: The highest frame rate of each output [frames per second]: a GIF stores each frame's delay
#: in whole hundredths of a second and browsers slow delays under 0.02 s down to 0.1 s; the
#: HTML player runs at most at a screen's 60 frames per second; an MP4 plays 120 on screens
#: that have them.
MAX_FPS = {"html": 60, ".gif": 50, ".mp4": 120}
# matplotlib's player links its button icons from a CDN; an animation must not load anything
# from outside (JupyterLab and the course website have the icon font already).
_EXTERNAL_LINK = re.compile(r"<link\b[^>]*\bhref=[\"']https?://[^>]*>\s*", re.IGNORECASE)


class _Blitting:
    """A movie writer whose frames are blitted by a scene (mixed into matplotlib's writers).

    The stock writers save the whole figure for every frame; redrawing only
    the moving artists over a cached background is several times faster.
    """

    def __init__(self, scene: PendulumScene, **kwargs):
        super().__init__(**kwargs)
        self._scene, self._background = scene, None

    def _blit(self) -> memoryview:
        """Draw the scene's current state; return the canvas's RGBA pixels."""
        canvas = self.fig.canvas
        if self._background is None:  # after setup(), which may adjust the size
            canvas.draw()
            self._background = canvas.copy_from_bbox(self.fig.bbox)
        canvas.restore_region(self._background)
        for artist in self._scene.artists:
            self.fig.draw_artist(artist)
        return canvas.buffer_rgba()


class _BlittingHTMLWriter(_Blitting, HTMLWriter):
    """matplotlib's HTML player, each frame an embedded image."""

    def __init__(self, scene: PendulumScene, **kwargs):
        super().__init__(scene, embed_frames=True, **kwargs)

    def grab_frame(self, **savefig_kwargs):
        self._blit()
        frame = base64.encodebytes(encode_frame(self.fig.canvas, self.frame_format)).decode("ascii")
        self._saved_frames.append(frame)


class _BlittingGIFWriter(_Blitting, PillowWriter):
    """matplotlib's Pillow writer (animated GIF)."""

    def grab_frame(self, **savefig_kwargs):
        rgba = self._blit()
        image = Image.frombuffer("RGBA", self.frame_size, rgba, "raw", "RGBA", 0, 1)
        self._frames.append(image.convert("RGB"))


class _BlittingMP4Writer(_Blitting, FFMpegWriter):
    """matplotlib's ffmpeg pipe writer (raw RGBA frames in, H.264 out)."""

    def grab_frame(self, **savefig_kwargs):
        self._proc.stdin.write(self._blit())


def _frames(traj, model, fps: float, speed: float, dpi: float, kind: str, max_frames: int,
            seconds: float | None = None) -> np.ndarray:
    """The frames of an export, once its arguments are checked (before any is drawn)."""
    first = check_run(traj, model)
    fps = check.number_in("fps", fps, 0, MAX_FPS[kind], "frames per second", open_low=True)
    speed = check.positive_number("speed", speed)
    check.positive_number("dpi", dpi)
    runs = scene_runs(traj)[0]
    for k, run in enumerate(runs):
        finite = np.isfinite(run.theta).all(axis=-1) & np.isfinite(run.energy)
        if not finite.all():
            which = f" (run {k})" if len(runs) > 1 else ""
            raise ValueError(
                f"`traj`{which} holds non-finite angles or energies from t = "
                f"{run.t[np.argmin(finite)]:g} s on (the run blew up; completed = "
                f"{run.completed}), which no frame can show: run it with a smaller `dt`"
            )
    count = frame_count(first, fps, speed)
    if seconds is not None:
        count = min(count, max(1, round(check.positive_number("seconds", seconds) * fps)))
    if count > max_frames:
        raise ValueError(
            f"the animation would have {count} frames, more than `max_frames` = {max_frames}; "
            + ("shorten it (`seconds`), " if kind != "html" else "shorten the run, ")
            + "raise `speed` or lower `fps`"
            + ("" if kind == "html" else ", or raise `max_frames`")
        )
    return frame_indices(first, fps, speed, limit=count)


def _writable(path) -> Path:
    """``path`` (a .gif or .mp4 file) if a file can be written there, checked by creating it."""
    try:
        path = Path(path)
    except TypeError:
        raise TypeError(f"`path` must be a file path, got {type(path).__name__}") from None
    if path.suffix.lower() not in (".gif", ".mp4"):
        raise ValueError(f"`path` must end in .gif or .mp4, got {path.name!r}")
    if not path.parent.is_dir():
        raise ValueError(f"`path` must be in an existing folder, but {str(path.parent)!r} is "
                         "not one")
    existed = path.exists()
    try:
        with open(path, "ab"):
            pass
    except OSError as err:
        raise ValueError(f"`path` must be a file that can be written, but {str(path)!r} cannot "
                         f"be ({err.strerror or err})") from None
    if not existed:
        os.remove(path)
    return path


def html_animation(
    traj,
    model: PendulumModel,
    *,
    fps: float = 15,
    speed: float = 1.0,
    trail: float = TRAIL,
    dpi: float = 64,
    max_frames: int = MAX_FRAMES,
    labels=None,
):
    """A self-contained HTML/JavaScript animation of a run, for use without a kernel.

    The frames (PNG, embedded in the output) show the same drawing as the
    matplotlib :func:`~pendulum_lab.animation.simulator`, with the time and
    energies written above the energy panel; matplotlib's player
    (:class:`matplotlib.animation.HTMLWriter`) adds play/pause, step and speed
    buttons and a frame slider, all running in the browser.

    Several runs saved at the same times (two nearby releases, two methods
    from one release) are overlaid in one animation, each in its colour, with
    their total and kinetic energies (:class:`~pendulum_lab.animation.PendulumScene`).

    Parameters
    ----------
    traj : Trajectory or sequence of Trajectory
        A single trajectory of ``model``, or up to five saved at the same times.
    model : PendulumModel
    fps : float
        Frames per second of the player, in ``(0, 60]``.
    speed : float
        Simulated seconds per real second, ``> 0``.
    trail : float
        Trail length [s].
    dpi : float
        Resolution of the frames, ``> 0``; the figure is 9 x 3.6 inches.
    max_frames : int
        Refuse to make more frames than this (the output grows by tens of
        kilobytes per frame): shorten the run, or raise ``speed`` or lower
        ``fps``.
    labels : sequence of str, optional
        Names of the runs in the legend when there are several; by default
        their methods and steps.

    Returns
    -------
    IPython.display.HTML
        Its ``data`` holds one embedded image per frame of
        :func:`~pendulum_lab.animation.frame_indices` (count them with :func:`count_frames`).

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> sp_ = pl.simple_pendulum()
    >>> traj = pl.simulate(sp_, [1.0], [0.0], t_end=1.0, dt=0.01)
    >>> count_frames(html_animation(traj, sp_, fps=5).data)
    6
    >>> nudged = pl.simulate(sp_, [1.01], [0.0], t_end=1.0, dt=0.01)
    >>> count_frames(html_animation([traj, nudged], sp_, fps=5, labels=["1", "1.01"]).data)
    6
    """
    from IPython.display import HTML

    max_frames = check.integer_at_least("max_frames", max_frames, 1)
    frames = _frames(traj, model, fps, speed, dpi, "html", max_frames)
    figure, scene = export_scene(traj, model, trail, dpi, labels)
    writer = _BlittingHTMLWriter(
        scene, fps=fps, default_mode="loop", embed_limit=max_frames
    )  # MB: never the binding limit
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder, "animation.html")
        with writer.saving(figure, path, dpi):
            for index in frames:
                scene.show(index)
                writer.grab_frame()
        return HTML(_EXTERNAL_LINK.sub("", path.read_text(encoding="utf-8")))


def count_frames(html: str) -> int:
    """The number of embedded frames in the output of :func:`html_animation`."""
    return len(re.findall(r"frames\[\d+\] = \"data:image/", html))


def _ffmpeg() -> str:
    """The ffmpeg binary shipped in the ``imageio-ffmpeg`` wheel, or a clear ImportError."""
    try:
        import imageio_ffmpeg
    except ImportError:
        raise ImportError(
            "saving an MP4 needs ffmpeg, which the imageio-ffmpeg package ships: "
            "pip install imageio-ffmpeg (or pendulum_lab[export]); a .gif needs nothing more"
        ) from None
    return imageio_ffmpeg.get_ffmpeg_exe()


def save_animation(
    traj,
    model: PendulumModel,
    path,
    *,
    fps: float = FPS,
    seconds: float | None = None,
    speed: float = 1.0,
    trail: float = TRAIL,
    dpi: float = 80,
    labels=None,
    max_frames: int = MAX_SAVED_FRAMES,
) -> Path:
    """Write a run as an animated GIF or an MP4 video, for slides.

    The frames show the drawing of :func:`~pendulum_lab.animation.simulator`
    (chain, trail, energies, with the time and energies written above), one
    per :func:`~pendulum_lab.animation.frame_indices`. The file type follows
    the suffix: ``.gif`` through Pillow (matplotlib's ``PillowWriter``), ``.mp4`` (H.264) through
    matplotlib's ``FFMpegWriter`` with the ffmpeg of ``imageio-ffmpeg``.

    Parameters
    ----------
    traj : Trajectory or sequence of Trajectory
        A single trajectory of ``model``, or several saved at the same times
        (overlaid, as in :func:`html_animation`).
    model : PendulumModel
    path : str or Path
        Ends in ``.gif`` or ``.mp4``, in an existing folder.
    fps : float
        Frames per second of the file, in ``(0, 50]`` for a GIF and ``(0, 120]``
        for an MP4 (:data:`MAX_FPS`).
    seconds : float, optional
        Length of the animation [s of playing time], ``> 0``; by default the
        whole run. Never more frames than the run has.
    speed : float
        Simulated seconds per second of animation.
    trail : float
        Trail length [s].
    dpi : float
        Resolution, ``> 0``; the figure is 9 x 3.6 inches.
    labels : sequence of str, optional
        Names of the runs in the legend when there are several.
    max_frames : int
        Refuse to make more frames than this (:data:`MAX_SAVED_FRAMES` by
        default): a mistyped ``fps`` or ``speed`` would otherwise draw for hours.

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    ImportError
        For ``.mp4`` without ``imageio-ffmpeg``, saying how to install it.
    ValueError
        Before any frame is drawn, for a ``path`` that cannot be written, a run
        that blew up (non-finite states), or too many frames.
    RuntimeError
        If ffmpeg fails while writing the MP4 (its message is included).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from PIL import Image
    >>> import pendulum_lab as pl
    >>> sp_ = pl.simple_pendulum()
    >>> traj = pl.simulate(sp_, [1.0], [0.0], t_end=1.0, dt=0.01)
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     gif = save_animation(traj, sp_, pathlib.Path(folder, "swing.gif"), fps=5, dpi=40)
    ...     Image.open(gif).n_frames
    6
    """
    from matplotlib import rc_context

    max_frames = check.integer_at_least("max_frames", max_frames, 1)
    check_run(traj, model)
    path = _writable(path)
    suffix = path.suffix.lower()
    frames = _frames(traj, model, fps, speed, dpi, suffix, max_frames, seconds)
    settings = {} if suffix == ".gif" else {"animation.ffmpeg_path": _ffmpeg()}
    figure, scene = export_scene(traj, model, trail, dpi, labels)
    if suffix == ".gif":
        writer = _BlittingGIFWriter(scene, fps=fps)
    else:
        writer = _BlittingMP4Writer(scene, fps=fps, codec="h264")
    try:
        with rc_context(settings), writer.saving(figure, str(path), dpi):
            for index in frames:
                scene.show(index)
                writer.grab_frame()
    except (subprocess.CalledProcessError, BrokenPipeError) as err:
        detail = getattr(err, "stderr", None) or b""
        detail = detail.decode(errors="replace").strip() if isinstance(detail, bytes) else detail
        raise RuntimeError(f"ffmpeg could not write {str(path)!r}"
                           + (f": {detail}" if detail else f" ({err})")) from None
    return path
