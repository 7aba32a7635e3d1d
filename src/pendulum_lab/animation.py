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
ffmpeg binary that the ``imageio-ffmpeg`` package ships).
"""

from __future__ import annotations

import base64
import io
import math
import re
import tempfile
from pathlib import Path

import ipywidgets as widgets
import numpy as np
from matplotlib.animation import FFMpegWriter, HTMLWriter, PillowWriter
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from PIL import Image

from . import _validation as check
from . import plotting
from ._png import png_bytes
from .model import PendulumModel
from .simulate import Trajectory, step_count
from .widgets.controls import (
    SIMULATOR_T_END,
    SPEEDS,
    TRAIL,
    build_simulator,
    pendulum_controls,
    simulate_controls,
)
from .widgets.instrument import Instrument

__all__ = [
    "FPS",
    "SPEEDS",
    "TRAIL",
    "PendulumScene",
    "Simulator",
    "count_frames",
    "frame_indices",
    "html_animation",
    "save_animation",
    "simulator",
    "still_frame",
]

#: Frames per second of the matplotlib simulator (the default of its exports too).
FPS = 20
TRAIL_COLOUR = "tab:purple"
BOB_COLOUR = "tab:red"


def frame_indices(traj: Trajectory, fps: float, speed: float) -> np.ndarray:
    """Indices into ``traj`` of the frames of an animation.

    Frame ``k`` shows time ``k * speed / fps`` (``speed`` simulated seconds per
    real second), rounded to the nearest saved state; the last frame is at or
    before the end of the run.

    Parameters
    ----------
    traj : Trajectory
    fps : float
        Frames per second, ``> 0``.
    speed : float
        Playback speed, ``> 0``.

    Returns
    -------
    ndarray of int, shape (frames,)

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> traj = pl.simulate(pl.simple_pendulum(), [1.0], [0.0], t_end=1.0, dt=0.01)
    >>> frame_indices(traj, fps=10, speed=1.0)
    array([  0,  10,  20,  30,  40,  50,  60,  70,  80,  90, 100])
    """
    fps = check.positive_number("fps", fps)
    speed = check.positive_number("speed", speed)
    spacing = traj.t[1] - traj.t[0] if len(traj.t) > 1 else 1.0
    frames = step_count(traj.t[-1] - traj.t[0], speed / fps) + 1
    times = np.arange(frames) * (speed / fps)
    return np.minimum(np.rint(times / spacing).astype(int), len(traj.t) - 1)


class PendulumScene:
    """The animated drawing of one trajectory: the chain and the energies up to now.

    Left: rods, bobs (area proportional to mass), pivot and the path of the
    last bob over the past ``trail`` seconds. Right: kinetic, potential and
    total energy from the start to the current time, over a faint line of the
    initial energy, and a readout of the time and the three energies.
    :meth:`show` moves everything to one saved state and returns the artists
    it changed (the only ones to redraw).

    Parameters
    ----------
    figure : matplotlib.figure.Figure
        An empty figure to draw into.
    model : PendulumModel
    traj : Trajectory
        A single trajectory of ``model``.
    trail : float
        Trail length [s], ``>= 0``.
    animated : bool
        Mark the moving artists as animated (left out of full redraws, for
        blitting).
    readout : bool
        Write the time and energies above the energy panel (the live
        simulator shows them in a widget instead: text is slow to draw).

    Attributes
    ----------
    rods, bobs, trail_line : matplotlib.lines.Line2D
    energy_lines : dict of str -> Line2D
        ``"kinetic"``, ``"potential"``, ``"total"``.
    readout : matplotlib.text.Text or None
    index : int
        The state shown.
    """

    def __init__(
        self,
        figure: Figure,
        model: PendulumModel,
        traj: Trajectory,
        trail: float = TRAIL,
        animated: bool = True,
        readout: bool = True,
    ):
        if traj.theta.ndim != 2 or traj.theta.shape[1] != model.n:
            raise ValueError(
                f"`traj` must be one trajectory of this {model.n}-link model, got "
                f"angles of shape {traj.theta.shape}"
            )
        trail = check.non_negative_number("trail", trail)
        self.model, self.traj = model, traj
        self.x, self.y = model.positions(traj.theta)
        spacing = traj.t[1] - traj.t[0] if len(traj.t) > 1 else 1.0
        self._trail_states = int(round(trail / spacing))
        self.index = 0

        grid = figure.add_gridspec(
            1, 2, width_ratios=(1, 1.6), left=0.07, right=0.98, bottom=0.15, top=0.86, wspace=0.2
        )
        chain = figure.add_subplot(grid[0])
        plotting.chain_frame(chain, model, margin=1.08)
        chain.set_title(f"{traj.method.name}, dt = {traj.dt:g} s", fontsize="medium")
        self.trail_line = chain.plot([], [], color=TRAIL_COLOUR, lw=1.0, alpha=0.6)[0]
        self.rods = chain.plot([], [], color="0.25", lw=2.5, zorder=2)[0]
        self.bobs = chain.plot(
            [],
            [],
            "o",
            color=BOB_COLOUR,
            mec="black",
            zorder=3,
            ms=10 * math.sqrt(min(model.masses) / max(model.masses)),
        )[0]

        energy = figure.add_subplot(grid[1])
        levels = np.concatenate([traj.kinetic, traj.potential, traj.energy])
        low, high = float(np.min(levels)), float(np.max(levels))
        pad = 0.06 * max(high - low, 1e-9)
        energy.set(
            xlim=(0, max(traj.t[-1], 1e-9)),
            ylim=(low - pad, high + pad),
            xlabel="t (s)",
            ylabel="energy (J)",
        )
        energy.axhline(traj.energy[0], color=plotting.TOTAL, lw=0.6, ls=":", label="E(0)")
        self.energy_lines = {
            "kinetic": energy.plot([], [], color=plotting.KINETIC, label="kinetic T")[0],
            "potential": energy.plot([], [], color=plotting.POTENTIAL, label="potential V")[0],
            "total": energy.plot([], [], color=plotting.TOTAL, lw=2, label="total E")[0],
        }
        energy.legend(
            loc="lower left",
            bbox_to_anchor=(0.0, 1.0),
            ncols=4,
            frameon=False,
            fontsize="small",
            borderaxespad=0.2,
        )
        self.artists = [self.trail_line, self.rods, self.bobs, *self.energy_lines.values()]
        self.readout = None
        if readout:
            self.readout = figure.text(
                0.5, 0.985, " ", ha="center", va="top", family="monospace", fontsize="medium"
            )
            self.artists.append(self.readout)
        for artist in self.artists:
            artist.set_animated(animated)
        self.show(0)

    def show(self, index: int) -> list:
        """Draw state ``index`` of the trajectory; return the changed artists."""
        index = int(np.clip(index, 0, len(self.traj.t) - 1))
        self.index = index
        first = max(0, index - self._trail_states)
        self.trail_line.set_data(self.x[first : index + 1, -1], self.y[first : index + 1, -1])
        self.rods.set_data(np.r_[0.0, self.x[index]], np.r_[0.0, self.y[index]])
        self.bobs.set_data(self.x[index], self.y[index])
        t = self.traj.t[: index + 1]
        for key, values in (
            ("kinetic", self.traj.kinetic),
            ("potential", self.traj.potential),
            ("total", self.traj.energy),
        ):
            self.energy_lines[key].set_data(t, values[: index + 1])
        if self.readout is not None:
            self.readout.set_text(self.readout_text(index))
        return self.artists

    def readout_text(self, index: int) -> str:
        """``t = ... s  T = ... J  V = ... J  E = ... J`` at state ``index``."""
        traj = self.traj
        return (
            f"t = {traj.t[index]:6.2f} s   T = {traj.kinetic[index]:8.3f} J   "
            f"V = {traj.potential[index]:8.3f} J   E = {traj.energy[index]:8.3f} J"
        )


def _encode(canvas: FigureCanvasAgg, image_format: str) -> bytes:
    """The canvas's current pixels as ``"jpeg"`` or ``"png"`` bytes.

    The live simulator sends JPEG: it encodes about four times faster than
    PNG, which keeps a frame well within its 50 ms. The embedded frames of
    :func:`html_animation` are PNG reduced to 64 colours, a third of the
    size of full-colour PNG for these line drawings.
    """
    width, height = canvas.get_width_height()
    image = Image.frombuffer("RGBA", (width, height), canvas.buffer_rgba(), "raw", "RGBA", 0, 1)
    image = image.convert("RGB")
    buffer = io.BytesIO()
    if image_format == "jpeg":
        image.save(buffer, format="jpeg", quality=90)
    else:
        image.quantize(colors=64).save(buffer, format="png", compress_level=6)
    return buffer.getvalue()


class Simulator(Instrument):
    """The live simulator; build it with :func:`simulator`.

    On top of the explorer's controls (``controls``; a change recomputes the
    run and restarts the animation at ``t = 0``) it has playback widgets that
    only move through the stored run.

    Attributes
    ----------
    play : ipywidgets.Play
        Play/pause; its value is the frame number, linked to ``frame``.
    frame : ipywidgets.IntSlider
        The frame shown.
    speed : ipywidgets.SelectionSlider
        Simulated seconds per real second, one of :data:`SPEEDS`.
    readout : ipywidgets.HTML
        Time and kinetic, potential and total energy of the state shown.
    scene : PendulumScene
        The drawing of the current run.
    """

    def __init__(
        self,
        model: PendulumModel,
        method,
        t_end: float,
        dt: float,
        theta0,
        omega0,
        speed: float,
        trail: float,
    ):
        controls, columns = pendulum_controls(
            model, theta0, omega0, t_end=t_end, dt=dt, method=method, t_end_range=SIMULATOR_T_END
        )
        super().__init__(model, controls, columns, rows=1.3)
        self.trail = trail
        self.scene: PendulumScene | None = None
        self._frames = np.zeros(1, dtype=int)
        self._background = None
        self._resetting = False
        self.play = widgets.Play(
            value=0,
            min=0,
            max=1,
            step=1,
            interval=round(1000 / FPS),
            description="play",
            show_repeat=True,
        )
        self.frame = widgets.IntSlider(
            value=0,
            min=0,
            max=1,
            description="frame",
            continuous_update=True,
            layout=widgets.Layout(width="420px"),
        )
        self.speed = widgets.SelectionSlider(
            options=[(f"{s:g}×", s) for s in SPEEDS],
            value=speed,
            description="speed",
            continuous_update=False,
            layout=widgets.Layout(width="260px"),
        )
        self.readout = widgets.HTML()
        self._image.format = "jpeg"
        widgets.link((self.play, "value"), (self.frame, "value"))
        self.frame.observe(self._on_frame, names="value")
        self.speed.observe(self._on_speed, names="value")
        boxes, status, image = self.widget.children
        playback = widgets.HBox([self.play, self.frame, self.speed])
        readout = widgets.HBox([self.readout], layout=widgets.Layout(margin="0 0 0 60px"))
        self.widget.children = (boxes, playback, status, readout, image)

    # ---- the explorer's hooks --------------------------------------------------------------
    def compute(self):
        return simulate_controls(self.model.n, self.controls)

    def draw(self, figure):
        self.scene = PendulumScene(figure, self.model, self.trajectory, self.trail, readout=False)
        self._set_frames(self.speed.value, keep_time=None)

    def render(self) -> None:
        self._canvas.draw()
        self._background = self._canvas.copy_from_bbox(self.figure.bbox)
        self._blit()

    # ---- playback ---------------------------------------------------------------------------
    @property
    def index(self) -> int:
        """Index into ``trajectory`` of the state shown."""
        return int(self._frames[min(self.frame.value, len(self._frames) - 1)])

    @property
    def time(self) -> float:
        """Simulated time of the state shown [s]."""
        return float(self.trajectory.t[self.index])

    def _set_frames(self, speed: float, keep_time: float | None) -> None:
        self._frames = frame_indices(self.trajectory, FPS, speed)
        last = len(self._frames) - 1
        value = 0 if keep_time is None else min(last, round(keep_time * FPS / speed))
        self._resetting = True
        try:
            for control in (self.play, self.frame):
                control.max = max(last, 1)
            self.frame.value = value  # the link sets play.value
        finally:
            self._resetting = False

    def _blit(self) -> None:
        self._canvas.restore_region(self._background)
        for artist in self.scene.show(self.index):
            self.figure.draw_artist(artist)
        self._image.value = _encode(self._canvas, "jpeg")
        self.readout.value = f"<pre style='margin:0'>{self.scene.readout_text(self.index)}</pre>"

    def _on_frame(self, change) -> None:
        if not self._resetting and self._background is not None:
            self._blit()

    def _on_speed(self, change) -> None:
        self._set_frames(change["new"], keep_time=self.time)
        if self._background is not None:
            self._blit()

    def summary(self) -> str:
        return f"{len(self._frames)} frames at {FPS} fps; " + super().summary()

    def html(self, **kwargs):
        """:func:`html_animation` of the current run (for viewing without a kernel)."""
        kwargs.setdefault("speed", self.speed.value)
        return html_animation(self.trajectory, self.model, **kwargs)

    def save(self, path, *, fps: float = FPS, seconds: float | None = None, **kwargs) -> Path:
        """Write the current run, at the current speed, as ``.gif`` or ``.mp4``.

        See :func:`save_animation` for the arguments; returns the path written.
        """
        kwargs.setdefault("speed", self.speed.value)
        kwargs.setdefault("trail", self.trail)
        return save_animation(self.trajectory, self.model, path, fps=fps, seconds=seconds,
                              **kwargs)


def simulator(
    model: PendulumModel,
    theta0=None,
    omega0=None,
    *,
    t_end: float = 20.0,
    dt: float = 0.01,
    method="glrk4",
    speed: float = 1.0,
    trail: float = TRAIL,
) -> Simulator:
    """The live pendulum simulator: an animated chain with its energies.

    Parameters
    ----------
    model : PendulumModel
        A simple, double or longer pendulum; its parameters are the sliders'
        start values.
    theta0, omega0 : array_like, shape (n,), optional
        Initial angles [rad] in ``[-pi, pi]`` and angular velocities [rad/s]
        in ``[-10, 10]``; by default 1 rad for one link, ``(2.0, 2.5)`` for
        two, at rest.
    t_end, dt : float
        Length of the run and step [s]; ``t_end`` in ``[1, 60]``.
    method : str
        A key of :data:`pendulum_lab.METHODS`.
    speed : float
        Playback speed, one of :data:`SPEEDS`.
    trail : float
        Length of the last bob's trail [s], ``>= 0``.

    Returns
    -------
    Simulator
        ``widget`` to display (a bare ``sim`` at the end of a cell shows it),
        ``controls`` (as :func:`pendulum_lab.widgets.explore`), ``play``,
        ``frame``, ``speed``, ``scene``, ``trajectory``, ``time``, ``index``,
        ``message`` and ``update()``.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> sim = simulator(pl.simple_pendulum(), t_end=2.0)
    >>> sim.play.value = 20          # one second at 20 frames per second
    >>> sim.time
    1.0
    """
    return build_simulator(
        Simulator, model, theta0, omega0, t_end=t_end, dt=dt, method=method, speed=speed,
        trail=trail,
    )


#: Default cap on the frames of :func:`html_animation` (each is an embedded PNG).
MAX_FRAMES = 300
#: Size of the exported animations' figure [inches].
EXPORT_SIZE = (9, 3.6)
# matplotlib's player links its button icons from a CDN; an animation must not load anything
# from outside (JupyterLab and the course website have the icon font already).
_EXTERNAL_LINK = re.compile(r"<link\b[^>]*\bhref=[\"']https?://[^>]*>\s*", re.IGNORECASE)


def _check_run(traj, model) -> None:
    """A single trajectory and a model, or a clear error naming the argument."""
    if not isinstance(traj, Trajectory):
        raise TypeError(f"`traj` must be a Trajectory, got {type(traj).__name__}")
    check.pendulum_model(model)


def _export_scene(
    traj, model, trail: float, dpi: float, animated: bool = True
) -> tuple[Figure, PendulumScene]:
    """The drawing the exports share: a :data:`EXPORT_SIZE` figure with the run's scene."""
    figure = Figure(figsize=EXPORT_SIZE, dpi=dpi)
    FigureCanvasAgg(figure)
    return figure, PendulumScene(figure, model, traj, trail, animated=animated)


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
        frame = base64.encodebytes(_encode(self.fig.canvas, self.frame_format)).decode("ascii")
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


def html_animation(
    traj: Trajectory,
    model: PendulumModel,
    *,
    fps: float = 15,
    speed: float = 1.0,
    trail: float = TRAIL,
    dpi: float = 64,
    max_frames: int = MAX_FRAMES,
):
    """A self-contained HTML/JavaScript animation of a run, for use without a kernel.

    The frames (PNG, embedded in the output) show the same drawing as the
    live :func:`simulator`, with the time and energies written above the
    energy panel; matplotlib's player (:class:`matplotlib.animation.HTMLWriter`)
    adds play/pause, step and speed buttons and a frame slider, all running
    in the browser.

    Parameters
    ----------
    traj : Trajectory
        A single trajectory of ``model``.
    model : PendulumModel
    fps : float
        Frames per second of the player, ``> 0``.
    speed : float
        Simulated seconds per real second, ``> 0``.
    trail : float
        Trail length [s].
    dpi : float
        Resolution of the frames; the figure is 9 x 3.6 inches.
    max_frames : int
        Refuse to make more frames than this (the output grows by tens of
        kilobytes per frame): shorten the run, or raise ``speed`` or lower
        ``fps``.

    Returns
    -------
    IPython.display.HTML
        Its ``data`` holds one embedded image per frame of
        :func:`frame_indices` (count them with :func:`count_frames`).

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> sp_ = pl.simple_pendulum()
    >>> traj = pl.simulate(sp_, [1.0], [0.0], t_end=1.0, dt=0.01)
    >>> count_frames(html_animation(traj, sp_, fps=5).data)
    6
    """
    from IPython.display import HTML

    _check_run(traj, model)
    max_frames = check.integer_at_least("max_frames", max_frames, 1)
    frames = frame_indices(traj, fps, speed)
    if len(frames) > max_frames:
        raise ValueError(
            f"the animation would have {len(frames)} frames, more than `max_frames` = "
            f"{max_frames}; shorten the run, raise `speed` or lower `fps`"
        )
    figure, scene = _export_scene(traj, model, trail, dpi)
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
    traj: Trajectory,
    model: PendulumModel,
    path,
    *,
    fps: float = FPS,
    seconds: float | None = None,
    speed: float = 1.0,
    trail: float = TRAIL,
    dpi: float = 80,
) -> Path:
    """Write a run as an animated GIF or an MP4 video, for slides.

    The frames show the drawing of :func:`simulator` (chain, trail,
    energies, with the time and energies written above), one per
    :func:`frame_indices`. The file type follows the suffix: ``.gif`` through
    Pillow (matplotlib's ``PillowWriter``), ``.mp4`` (H.264) through
    matplotlib's ``FFMpegWriter`` with the ffmpeg of ``imageio-ffmpeg``.

    Parameters
    ----------
    traj : Trajectory
        A single trajectory of ``model``.
    model : PendulumModel
    path : str or Path
        Ends in ``.gif`` or ``.mp4``.
    fps : float
        Frames per second of the file, ``> 0``.
    seconds : float, optional
        Length of the animation [s of playing time], ``> 0``; by default the
        whole run. Never more frames than the run has.
    speed : float
        Simulated seconds per second of animation.
    trail : float
        Trail length [s].
    dpi : float
        Resolution; the figure is 9 x 3.6 inches.

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    ImportError
        For ``.mp4`` without ``imageio-ffmpeg``, saying how to install it.

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

    _check_run(traj, model)
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".gif", ".mp4"):
        raise ValueError(f"`path` must end in .gif or .mp4, got {path.name!r}")
    frames = frame_indices(traj, fps, speed)
    if seconds is not None:
        seconds = check.positive_number("seconds", seconds)
        frames = frames[: max(1, round(seconds * fps))]
    settings = {} if suffix == ".gif" else {"animation.ffmpeg_path": _ffmpeg()}
    figure, scene = _export_scene(traj, model, trail, dpi)
    if suffix == ".gif":
        writer = _BlittingGIFWriter(scene, fps=fps)
    else:
        writer = _BlittingMP4Writer(scene, fps=fps, codec="h264")
    with rc_context(settings), writer.saving(figure, str(path), dpi):
        for index in frames:
            scene.show(index)
            writer.grab_frame()
    return path


def still_frame(
    traj: Trajectory,
    model: PendulumModel,
    *,
    index: int | None = None,
    trail: float = TRAIL,
    dpi: float = 80,
) -> bytes:
    """One frame of a run's animation as a PNG: by default the last, with the whole run's energies.

    The drawing of :func:`html_animation` and :func:`save_animation` (chain,
    trail, kinetic, potential and total energy up to that state, the time
    and energies written above), for a page that cannot play anything: the
    browser-drawn :func:`pendulum_lab.widgets.live_simulator` shows it where
    no kernel runs.

    Parameters
    ----------
    traj : Trajectory
        A single trajectory of ``model``.
    model : PendulumModel
    index : int, optional
        The saved state shown, ``0 <= index < len(traj.t)``; default the last.
    trail : float
        Trail length [s].
    dpi : float
        Resolution; the figure is 9 x 3.6 inches.

    Returns
    -------
    bytes
        The PNG file's bytes.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> sp_ = pl.simple_pendulum()
    >>> traj = pl.simulate(sp_, [1.0], [0.0], t_end=1.0, dt=0.01)
    >>> still_frame(traj, sp_, dpi=40)[:8]
    b'\\x89PNG\\r\\n\\x1a\\n'
    """
    _check_run(traj, model)
    last = len(traj.t) - 1
    index = last if index is None else check.index_below("index", index, last + 1)
    figure, scene = _export_scene(traj, model, trail, dpi, animated=False)
    scene.show(index)
    figure.canvas.draw()
    return png_bytes(np.asarray(figure.canvas.buffer_rgba()))
