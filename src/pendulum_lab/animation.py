"""The live pendulum simulator, and the same animation as self-contained HTML.

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
buffer) and sends the PNG to an ``ipywidgets.Image``. An ``ipywidgets.Play``
drives the frame slider at :data:`FPS` frames per second. This works in
JupyterLab with the inline backend and needs no interactive matplotlib
backend.

Where no kernel is attached (a notebook viewed as a static page), widgets
cannot run; :func:`html_animation` renders the same drawing as a
self-contained JavaScript/HTML animation (matplotlib's HTML player, the one
behind :meth:`matplotlib.animation.Animation.to_jshtml`) whose frames are
embedded in the output.
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
from matplotlib.animation import HTMLWriter
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from PIL import Image

from . import _validation as check
from . import plotting
from .model import PendulumModel
from .simulate import Trajectory, step_count
from .widgets.controls import (
    control_names,
    parameter_controls,
    run_controls,
    simulate_controls,
    start_state,
    state_controls,
)
from .widgets.instrument import Instrument

__all__ = [
    "FPS",
    "SPEEDS",
    "PendulumScene",
    "Simulator",
    "count_frames",
    "frame_indices",
    "html_animation",
    "simulator",
]

#: Frames per second of the live simulator.
FPS = 20
#: Playback speeds offered: simulated seconds per real second.
SPEEDS = (0.25, 0.5, 1.0, 2.0, 4.0)
#: Length of the trail behind the last bob [s].
TRAIL = 2.0
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
        n, keys = model.n, control_names(model.n)
        controls = {
            **state_controls(n, theta0, omega0),
            **parameter_controls(model),
            **run_controls(method, t_end, dt, t_end_range=(1.0, 60.0)),
        }
        columns = [
            ("Initial state", keys["theta"] + keys["omega"]),
            ("Parameters", keys["mass"] + keys["length"] + ["g"]),
            ("Integration", ["method", "dt", "t_end"]),
        ]
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
    def _compute(self):
        return simulate_controls(self.model.n, self.controls)

    def _draw(self, figure):
        self.scene = PendulumScene(figure, self.model, self.trajectory, self.trail, readout=False)
        self._set_frames(self.speed.value, keep_time=None)

    def _render(self) -> None:
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

    def _summary(self) -> str:
        return f"{len(self._frames)} frames at {FPS} fps; " + super()._summary()

    def html(self, **kwargs):
        """:func:`html_animation` of the current run (for viewing without a kernel)."""
        kwargs.setdefault("speed", self.speed.value)
        return html_animation(self.trajectory, self.model, **kwargs)


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
    model = check.pendulum_model(model)
    theta0, omega0 = start_state(model.n, theta0, omega0)
    speed = check.choice("speed", speed, SPEEDS)
    trail = check.non_negative_number("trail", trail)
    t_end = check.number_in("t_end", t_end, 1.0, 60.0, "s")
    sim = Simulator(model, method, t_end, dt, theta0, omega0, speed, trail)
    if not sim.update():
        raise ValueError(sim.message)
    return sim


#: Default cap on the frames of :func:`html_animation` (each is an embedded PNG).
MAX_FRAMES = 300
# matplotlib's player links its button icons from a CDN; an animation must not load anything
# from outside (JupyterLab and the course website have the icon font already).
_EXTERNAL_LINK = re.compile(r"<link\b[^>]*\bhref=[\"']https?://[^>]*>\s*", re.IGNORECASE)


class _BlittingHTMLWriter(HTMLWriter):
    """matplotlib's HTML player, fed with frames blitted by a scene.

    The stock writer saves the whole figure for every frame; redrawing only
    the moving artists over a cached background is several times faster.
    """

    def __init__(self, scene: PendulumScene, **kwargs):
        super().__init__(embed_frames=True, **kwargs)
        self._scene, self._background = scene, None

    def grab_frame(self, **savefig_kwargs):
        canvas = self.fig.canvas
        if self._background is None:  # after setup(), which may adjust the size
            canvas.draw()
            self._background = canvas.copy_from_bbox(self.fig.bbox)
        canvas.restore_region(self._background)
        for artist in self._scene.artists:
            self.fig.draw_artist(artist)
        frame = base64.encodebytes(_encode(canvas, self.frame_format)).decode("ascii")
        self._saved_frames.append(frame)


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

    if not isinstance(traj, Trajectory):
        raise TypeError(f"`traj` must be a Trajectory, got {type(traj).__name__}")
    check.pendulum_model(model)
    max_frames = check.integer_at_least("max_frames", max_frames, 1)
    frames = frame_indices(traj, fps, speed)
    if len(frames) > max_frames:
        raise ValueError(
            f"the animation would have {len(frames)} frames, more than `max_frames` = "
            f"{max_frames}; shorten the run, raise `speed` or lower `fps`"
        )
    figure = Figure(figsize=(9, 3.6), dpi=dpi)
    FigureCanvasAgg(figure)
    scene = PendulumScene(figure, model, traj, trail, animated=True)
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
