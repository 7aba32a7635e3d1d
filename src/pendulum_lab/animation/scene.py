"""The animated drawing of one run: which saved state each frame shows, and the scene itself.

Shared by the matplotlib simulator (:mod:`.simulator`) and the exports
(:mod:`.export`): the chain with the trail of its last bob, the energies up
to the current time, and the encoding of a frame as JPEG or PNG.
"""

from __future__ import annotations

import io
import math

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from PIL import Image

from .. import _validation as check
from .. import plotting
from ..model import PendulumModel
from ..simulate import Trajectory, step_count
from ..widgets.controls import TRAIL

__all__ = ["BOB_COLOUR", "FPS", "TRAIL_COLOUR", "PendulumScene", "encode_frame", "frame_indices"]

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


def encode_frame(canvas: FigureCanvasAgg, image_format: str) -> bytes:
    """The canvas's current pixels as ``"jpeg"`` or ``"png"`` bytes.

    The matplotlib simulator sends JPEG: it encodes about four times faster
    than PNG, which keeps a frame well within its 50 ms. The embedded frames
    of :func:`~pendulum_lab.animation.html_animation` are PNG reduced to 64
    colours, a third of the size of full-colour PNG for these line drawings.
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
