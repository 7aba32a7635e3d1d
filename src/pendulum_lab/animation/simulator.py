"""The matplotlib simulator: the explorers' sliders, play/pause, speed, a frame per picture."""

from __future__ import annotations

from pathlib import Path

import ipywidgets as widgets
import numpy as np

from ..model.pendulum import PendulumModel
from ..plotting.scene import FPS, TRAIL, PendulumScene, encode_frame, frame_indices
from ..widgets.calls import SimulateCall
from ..widgets.controls import (
    SIMULATOR_T_END,
    SPEEDS,
    build_simulator,
    call_from_controls,
    pendulum_controls,
)
from ..widgets.instrument import Instrument
from .export import html_animation, save_animation

__all__ = ["Simulator", "simulator"]


class Simulator(Instrument):
    """The matplotlib simulator; build it with :func:`simulator`.

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
    def prepare(self) -> SimulateCall:
        return call_from_controls(self.model, self.controls)

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
        self._image.value = encode_frame(self._canvas, "jpeg")
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
        """:func:`~pendulum_lab.animation.html_animation` of the current run (without a kernel)."""
        kwargs.setdefault("speed", self.speed.value)
        return html_animation(self.trajectory, self.model, **kwargs)

    def save(self, path, *, fps: float = FPS, seconds: float | None = None, **kwargs) -> Path:
        """Write the current run, at the current speed, as ``.gif`` or ``.mp4``.

        See :func:`~pendulum_lab.animation.save_animation` for the arguments; returns the path
        written.
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
