"""The animated drawing of a run: which saved state each frame shows, and the scene itself.

Shared by the matplotlib simulator (:mod:`pendulum_lab.animation.simulator`), the exports
(:mod:`pendulum_lab.animation.export`) and the static picture of the browser-drawn live
simulator (:func:`still_frame`): the chain with the trail of its last bob, the energies up to
the current time, and the encoding of a frame as JPEG or PNG. A scene can also draw several
runs of one model over the same times, overlaid (two nearby releases parting, or two methods
from one release), each in its own colour.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass

import matplotlib as mpl
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from PIL import Image

from .. import validation as check
from ..driver.simulate import Trajectory, step_count
from ..model import PendulumModel, require_model
from .drawing import VIEWS, drawing_frame, joined_paths
from .figures import KINETIC, POTENTIAL, TOTAL
from .png import png_bytes

__all__ = [
    "BOB_COLOUR",
    "EXPORT_SIZE",
    "MIN_DPI",
    "MIN_TEXT_PIXELS",
    "TRAIL",
    "FPS",
    "RUN_COLOURS",
    "TRAIL_COLOUR",
    "PendulumScene",
    "SceneView",
    "check_run",
    "encode_frame",
    "export_scene",
    "frame_count",
    "frame_indices",
    "scene_runs",
    "still_frame",
]

#: Frames per second of the matplotlib simulator (the default of its exports too).
FPS = 20
#: Default length of the trail of the last bob [s].
TRAIL = 2.0
#: Size of the exported animations' figure [inches].
EXPORT_SIZE = (9, 3.6)
#: Smallest height of the exports' text [pixels of the frame]: at a low ``dpi`` the text is
#: set larger than matplotlib's default so that it stays legible.
MIN_TEXT_PIXELS = 11
#: Lowest resolution of an export [dots per inch]: below it a frame of :data:`EXPORT_SIZE` has
#: no room for its text at :data:`MIN_TEXT_PIXELS` (at 20 the layout cannot be made).
MIN_DPI = 30
TRAIL_COLOUR = "tab:purple"
BOB_COLOUR = "tab:red"
#: One colour per run when a scene overlays several (chain, trail and energies of that run).
RUN_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple")


@dataclass
class SceneView:
    """One view of a scene: its axes, the two coordinates it draws (indices into
    ``model.positions``), each run's ``(rods, bobs, trail)`` and ``(springs, pivots)``
    artists, each run's projected positions ``(u, v)`` (shape ``(states, points)`` each), and
    the view's reach [m]."""

    ax: object
    axes: tuple
    chains: list
    parts: list
    positions: list
    reach: float


def _check_runs(runs, model) -> None:
    """Refuse runs that are not single trajectories of ``model``."""
    for run in runs:
        if run.theta.ndim != 2 or run.theta.shape[1] != model.n:
            raise ValueError(
                f"`traj` must be one trajectory of this {model.n}-link model, got "
                f"angles of shape {run.theta.shape}"
            )
        require_same_system(run, model)


def _run_title(traj: Trajectory) -> str:
    return f"{traj.method.name}, dt = {traj.dt:g} s"


def scene_runs(traj, labels=None) -> tuple[tuple[Trajectory, ...], list[str]]:
    """The runs a scene draws and their legend labels, checked.

    Parameters
    ----------
    traj : Trajectory or sequence of Trajectory
        One run, or up to ``len(RUN_COLOURS)`` runs saved at the same times
        (same ``t_end``, ``dt`` and ``save_every``).
    labels : sequence of str, optional
        One per run; by default ``"METHOD, dt = DT s"``, or ``"run 1"``,
        ``"run 2"``, ... when those are not all different.

    Returns
    -------
    runs : tuple of Trajectory
    labels : list of str

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> sp_ = pl.simple_pendulum()
    >>> a = pl.simulate(sp_, [1.0], [0.0], t_end=1.0, dt=0.01, method="rk4")
    >>> b = pl.simulate(sp_, [1.0], [0.0], t_end=1.0, dt=0.01, method="leapfrog")
    >>> scene_runs([a, b])[1]
    ['rk4, dt = 0.01 s', 'leapfrog, dt = 0.01 s']
    """
    if isinstance(traj, Trajectory):
        runs = (traj,)
    elif isinstance(traj, (list, tuple)) and all(isinstance(run, Trajectory) for run in traj):
        runs = tuple(traj)
    else:
        raise TypeError(
            f"`traj` must be a Trajectory or a list of Trajectory, got {type(traj).__name__}"
        )
    if not 1 <= len(runs) <= len(RUN_COLOURS):
        raise ValueError(f"`traj` must hold 1 to {len(RUN_COLOURS)} trajectories, got {len(runs)}")
    for k, run in enumerate(runs[1:], start=1):
        if run.t.shape != runs[0].t.shape or not np.allclose(run.t, runs[0].t):
            raise ValueError(
                f"the runs in `traj` must be saved at the same times (same t_end, dt and "
                f"save_every); run {k} has {len(run.t)} states from {run.t[0]:g} to "
                f"{run.t[-1]:g} s, run 0 {len(runs[0].t)} from {runs[0].t[0]:g} to "
                f"{runs[0].t[-1]:g} s"
            )
    if labels is None:
        labels = [_run_title(run) for run in runs]
        if len(set(labels)) < len(labels):
            labels = [f"run {k + 1}" for k in range(len(runs))]
    else:
        labels = [str(label) for label in labels]
        if len(labels) != len(runs):
            raise ValueError(
                f"`labels` must have one entry per run ({len(runs)}), got {len(labels)}"
            )
    return runs, labels


def frame_count(traj: Trajectory, fps: float, speed: float) -> int:
    """The number of frames of :func:`frame_indices`, counted without making them."""
    fps = check.positive_number("fps", fps)
    speed = check.positive_number("speed", speed)
    return step_count(traj.t[-1] - traj.t[0], speed / fps) + 1


def frame_indices(traj: Trajectory, fps: float, speed: float,
                  limit: int | None = None) -> np.ndarray:
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
    limit : int, optional
        Only the first ``limit`` frames (see :func:`frame_count` for all of them).

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
    frames = frame_count(traj, fps, speed)
    if limit is not None:
        frames = min(frames, check.integer_at_least("limit", limit, 1))
    spacing = traj.t[1] - traj.t[0] if len(traj.t) > 1 else 1.0
    times = np.arange(frames) * (speed / fps)
    return np.minimum(np.rint(times / spacing).astype(int), len(traj.t) - 1)


class PendulumScene:
    """The animated drawing of a trajectory: the model's configuration and the energies up to now.

    Left: rods, springs, bobs (one size for a chain's equal masses, smaller for lighter ones),
    massless points (a shaken pivot) as small marks, the fixed pivot, and the path of the
    last massive point over the past ``trail`` seconds (a chain and a system given by its
    points, through :attr:`~pendulum_lab.PendulumModel.drawing`); a system in space
    (``model.dimensions == 3``) in two views side by side, from above (x, y) and from the
    side (x, z), each with the trail (:data:`~pendulum_lab.plotting.drawing.VIEWS`).
    Right: kinetic, potential and total energy from the start to the current time, over a
    faint line of the initial energy, and a readout of the time and the three energies.
    :meth:`show` moves everything to one saved state and returns the artists
    it changed (the only ones to redraw).

    Given several runs of the model saved at the same times, the scene
    overlays them, each in its colour of :data:`RUN_COLOURS`: every run's
    chain and trail on the left (a later run drawn over an earlier one, so
    two runs that coincide show as one chain), and on the right each run's
    total energy (thick) and kinetic energy (thin), with the legend naming the
    runs and the readout giving the time and each run's total energy.

    Parameters
    ----------
    figure : matplotlib.figure.Figure
        An empty figure to draw into.
    model : PendulumModel
    traj : Trajectory or sequence of Trajectory
        A single trajectory of ``model``, or several saved at the same times
        (see :func:`scene_runs`).
    trail : float
        Trail length [s], ``>= 0``.
    animated : bool
        Mark the moving artists as animated (left out of full redraws, for
        blitting).
    readout : bool
        Write the time and energies above the energy panel (the live
        simulator shows them in a widget instead: text is slow to draw).
    labels : sequence of str, optional
        The runs' names in the legend (several runs only); see :func:`scene_runs`.
    font_size : float, optional
        Size of every text of the scene [points]; by default matplotlib's
        ``font.size``. The exports pass a size that stays legible at their
        resolution (:data:`MIN_TEXT_PIXELS`).

    Attributes
    ----------
    runs : tuple of Trajectory
        The runs drawn; ``traj`` is the first.
    labels : list of str
    rods, bobs, trail_line : matplotlib.lines.Line2D
        Those of the first run; ``chains`` holds ``(rods, bobs, trail_line)`` of each run,
        ``parts`` its ``(springs, pivots)`` (massless points), in the first view.
    views : list of SceneView
        Every view (one in a plane, two in space) with its own artists.
    energy_lines : dict
        One run: ``"kinetic"``, ``"potential"``, ``"total"`` -> Line2D.
        Several: ``("kinetic", k)`` and ``("total", k)`` for run ``k``.
    readout : matplotlib.text.Text or None
    index : int
        The state shown.
    """

    def __init__(
        self,
        figure: Figure,
        model: PendulumModel,
        traj,
        trail: float = TRAIL,
        animated: bool = True,
        readout: bool = True,
        labels=None,
        font_size: float | None = None,
    ):
        runs, self.labels = scene_runs(traj, labels)
        _check_runs(runs, model)
        trail = check.non_negative_number("trail", trail)
        self.model, self.runs, self.traj = model, runs, runs[0]
        positions = [model.positions(run.theta, run.t) for run in runs]
        self.x, self.y = positions[0][:2]
        self.drawing = model.drawing
        masses = np.asarray(self.drawing.masses)
        self._heavy = masses > 0
        self._trailed = int(np.flatnonzero(self._heavy)[-1])  # the last massive point
        spacing = self.traj.t[1] - self.traj.t[0] if len(self.traj.t) > 1 else 1.0
        self._trail_states = int(round(trail / spacing))
        self.index = 0
        size = float(mpl.rcParams["font.size"]) if font_size is None else float(font_size)
        # Room above the panels for the readout and the legend: two lines of text.
        top = 1 - 3.6 * size / 72 / figure.get_figheight()
        bottom = 3.4 * size / 72 / figure.get_figheight()  # tick labels and the axis label
        views = VIEWS[model.dimensions]
        grid = figure.add_gridspec(
            1, 2, width_ratios=(1.9 if len(views) > 1 else 1, 1.6), left=0.07, right=0.965,
            bottom=bottom, top=top, wspace=0.2,
        )
        cells = [grid[0]] if len(views) == 1 else list(grid[0].subgridspec(1, len(views),
                                                                           wspace=0.35))
        self.views = self._draw_views(figure, cells, views, positions, size)
        first = self.views[0]
        titles = {_run_title(run) for run in runs}
        first.ax.set_title(titles.pop() if len(titles) == 1 else "", fontsize=size)
        self.chains, self.parts, self._reach = first.chains, first.parts, first.reach
        self.rods, self.bobs, self.trail_line = self.chains[0]
        energy = self._draw_energy_panel(figure.add_subplot(grid[1]), size)
        # Blitting draws in this order: each run's trail, rods, bobs; a later run over an earlier.
        self.artists = [
            artist
            for view in self.views
            for (rods, bobs, trail), (springs, pivots) in zip(view.chains, view.parts)
            for artist in (trail, rods, springs, bobs, pivots)
        ]
        self.artists += list(self.energy_lines.values())
        self.readout = None
        if readout:
            self.readout = figure.text(
                0.5, 0.985, " ", ha="center", va="top", family="monospace", fontsize=size
            )
            self.artists.append(self.readout)
        for ax in (*(view.ax for view in self.views), energy):
            ax.tick_params(labelsize=0.9 * size)
            ax.xaxis.label.set_fontsize(size)
            ax.yaxis.label.set_fontsize(size)
        for artist in self.artists:
            artist.set_animated(animated)
        self.show(0)

    def _draw_views(self, figure: Figure, cells, views, positions, size: float) -> list:
        """One drawing per view (a plane: one; space: from above and from the side), each with
        every run's chain, parts and trail, drawn from the view's two axes."""
        masses = np.asarray(self.drawing.masses)
        bob_size = 10 * math.sqrt(masses[self._heavy].min() / masses.max())
        if len(self.runs) == 1:
            colours = [(TRAIL_COLOUR, "0.25", BOB_COLOUR)]
        else:
            colours = [(colour, colour, colour) for colour in RUN_COLOURS[: len(self.runs)]]
        every = [np.concatenate([np.ravel(c) for run in positions for c in run])]
        drawn = []
        for cell, (axes, labels, name) in zip(cells, views):
            chain = figure.add_subplot(cell)
            reach = drawing_frame(chain, self.model, every, every, margin=1.08, labels=labels)
            if name:
                chain.text(0.03, 0.97, name, transform=chain.transAxes, ha="left", va="top",
                           fontsize=0.85 * size, color="0.35")
            chains, parts = [], []
            for k, (trail_colour, rod_colour, bob_colour) in enumerate(colours):
                trail_line = chain.plot([], [], color=trail_colour, lw=1.0, alpha=0.6,
                                        zorder=1 + k)[0]
                rods = chain.plot([], [], color=rod_colour, lw=2.5, zorder=2 + k)[0]
                bobs = chain.plot(
                    [], [], "o", color=bob_colour, mec="black", zorder=2.5 + k, ms=bob_size
                )[0]
                chains.append((rods, bobs, trail_line))
                springs = chain.plot([], [], color=rod_colour, lw=1.2, zorder=2 + k)[0]
                pivots = chain.plot([], [], "s", color="black", ms=5, zorder=2.6 + k)[0]
                parts.append((springs, pivots))
            projected = [(run[axes[0]], run[axes[1]]) for run in positions]
            drawn.append(SceneView(chain, axes, chains, parts, projected, reach))
        return drawn

    def _draw_energy_panel(self, energy, size: float):
        """The energies against the time on ``energy`` (axes): one run's kinetic, potential and
        total; several runs' total (thick) and kinetic (thin) each in its colour. Sets
        ``energy_lines``; returns the axes."""
        runs = self.runs
        if len(runs) == 1:
            self._energies = {
                "kinetic": self.traj.kinetic,
                "potential": self.traj.potential,
                "total": self.traj.energy,
            }
            styles = {
                "kinetic": {"color": KINETIC, "label": "kinetic T"},
                "potential": {"color": POTENTIAL, "label": "potential V"},
                "total": {"color": TOTAL, "lw": 2, "label": "total E"},
            }
            energy.axhline(self.traj.energy[0], color=TOTAL, lw=0.6, ls=":", label="E(0)")
        else:
            self._energies, styles = {}, {}
            for k, (run, label, colour) in enumerate(zip(runs, self.labels, RUN_COLOURS)):
                self._energies["kinetic", k] = run.kinetic
                self._energies["total", k] = run.energy
                styles["kinetic", k] = {"color": colour, "lw": 0.8, "alpha": 0.7}
                styles["total", k] = {"color": colour, "lw": 2, "label": label}
                energy.axhline(run.energy[0], color=colour, lw=0.6, ls=":")
            # What the two widths mean, once for all runs.
            energy.plot([], [], color="0.3", lw=2, label="total E")
            energy.plot([], [], color="0.3", lw=0.8, label="kinetic T")
        levels = np.concatenate([*self._energies.values(), [run.energy[0] for run in runs]])
        low, high = float(np.min(levels)), float(np.max(levels))
        pad = 0.06 * max(high - low, 1e-9)
        energy.set(
            xlim=(0, max(self.traj.t[-1], 1e-9)),
            ylim=(low - pad, high + pad),
            xlabel="t (s)",
            ylabel="energy (J)",
        )
        self.energy_lines = {key: energy.plot([], [], **styles[key])[0] for key in self._energies}
        energy.legend(
            loc="lower left",
            bbox_to_anchor=(0.0, 1.0),
            ncols=4 if len(runs) == 1 else len(runs) + 2,
            frameon=False,
            fontsize=0.85 * size,
            borderaxespad=0.2,
            handlelength=1.2,
            handletextpad=0.4,
            columnspacing=0.9,
        )
        return energy

    def show(self, index: int) -> list:
        """Draw state ``index`` of the trajectory (of every run); return the changed artists."""
        index = int(np.clip(index, 0, len(self.traj.t) - 1))
        self.index = index
        first = max(0, index - self._trail_states)
        heavy, last = self._heavy, self._trailed
        for view in self.views:
            for (rods, bobs, trail_line), (springs, pivots), (x, y) in zip(
                view.chains, view.parts, view.positions
            ):
                trail_line.set_data(x[first : index + 1, last], y[first : index + 1, last])
                rod_path, spring_path = joined_paths(self.drawing, x[index], y[index],
                                                     view.reach)
                rods.set_data(rod_path[:, 0], rod_path[:, 1])
                springs.set_data(spring_path[:, 0], spring_path[:, 1])
                bobs.set_data(x[index][heavy], y[index][heavy])
                pivots.set_data(x[index][~heavy], y[index][~heavy])
        t = self.traj.t[: index + 1]
        for key, values in self._energies.items():
            self.energy_lines[key].set_data(t, values[: index + 1])
        if self.readout is not None:
            self.readout.set_text(self.readout_text(index))
        return self.artists

    def readout_text(self, index: int) -> str:
        """``t = ... s  T = ... J  V = ... J  E = ... J`` at state ``index``; with several
        runs ``t = ... s  E = ... | ... J``, one total energy per run."""
        traj = self.traj
        if len(self.runs) > 1:
            totals = " | ".join(f"{run.energy[index]:.3f}" for run in self.runs)
            return f"t = {traj.t[index]:6.2f} s   E = {totals} J"
        return (
            f"t = {traj.t[index]:6.2f} s   T = {traj.kinetic[index]:8.3f} J   "
            f"V = {traj.potential[index]:8.3f} J   E = {traj.energy[index]:8.3f} J"
        )


def encode_frame(canvas: FigureCanvasAgg, image_format: str) -> bytes:
    """The canvas's current pixels as ``"jpeg"`` or ``"png"`` bytes.

    The matplotlib simulator sends JPEG, which encodes faster than PNG and keeps a
    frame within its 50 ms (docs/design/explorer-redraw.md). The embedded frames
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


def _system_of(model) -> str:
    return getattr(model, "name", None) or f"a chain of {model.n} links"


def require_same_system(run: Trajectory, model) -> None:
    """Refuse to draw ``run`` with ``model`` if the run came from another system (the same
    number of coordinates is not enough: the elastic pendulum's ``(r, theta)`` drawn as the
    cart pendulum's ``(x, theta)`` would be a wrong picture). Parameter values may differ."""
    source = run.model
    if source is None or source is model:
        return
    first, second = getattr(source, "system", None), getattr(model, "system", None)
    if first is None and second is None:
        same = source.n == model.n
    elif first is None or second is None:
        same = False
    else:
        same = first is second or (first.name == second.name and first.q == second.q
                                   and first.lagrangian == second.lagrangian
                                   and first.points == second.points)
    if not same:
        raise ValueError(f"`traj` is a run of {_system_of(source)}, and `model` is "
                         f"{_system_of(model)}: draw a run with the model it came from")


def check_run(traj, model) -> Trajectory:
    """The first of the runs (which fixes the frames' times) once ``traj`` (a trajectory or
    several, see :func:`~pendulum_lab.animation.scene_runs`) and ``model`` are checked."""
    require_model(model)
    return scene_runs(traj)[0][0]


def export_scene(
    traj, model, trail: float, dpi: float, labels=None, animated: bool = True
) -> tuple[Figure, PendulumScene]:
    """The drawing the exports share: a :data:`EXPORT_SIZE` figure with the runs' scene, its
    text at least :data:`MIN_TEXT_PIXELS` high; ``dpi`` at least :data:`MIN_DPI`."""
    if dpi < MIN_DPI:
        raise ValueError(f"`dpi` must be at least {MIN_DPI} (a frame of {EXPORT_SIZE[0]} x "
                         f"{EXPORT_SIZE[1]} inches has no room for its text below), got {dpi:g}")
    figure = Figure(figsize=EXPORT_SIZE, dpi=dpi)
    FigureCanvasAgg(figure)
    size = max(float(mpl.rcParams["font.size"]), MIN_TEXT_PIXELS * 72 / float(dpi))
    scene = PendulumScene(figure, model, traj, trail, animated=animated, labels=labels,
                          font_size=size)
    return figure, scene


def still_frame(
    traj,
    model: PendulumModel,
    *,
    index: int | None = None,
    trail: float = TRAIL,
    dpi: float = 80,
    labels=None,
) -> bytes:
    """One frame of a run's animation as a PNG: by default the last, with the whole run's energies.

    The drawing of :func:`html_animation` and :func:`save_animation` (chain,
    trail, kinetic, potential and total energy up to that state, the time
    and energies written above), for a page that cannot play anything: the
    browser-drawn :func:`pendulum_lab.widgets.live_simulator` shows it where
    no kernel runs.

    Parameters
    ----------
    traj : Trajectory or sequence of Trajectory
        A single trajectory of ``model``, or several saved at the same times.
    model : PendulumModel
    index : int, optional
        The saved state shown, ``0 <= index < len(traj.t)``; default the last.
    trail : float
        Trail length [s].
    dpi : float
        Resolution; the figure is 9 x 3.6 inches.
    labels : sequence of str, optional
        Names of the runs in the legend when there are several.

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
    last = len(check_run(traj, model).t) - 1
    index = last if index is None else check.index_below("index", index, last + 1)
    dpi = check.positive_number("dpi", dpi)
    figure, scene = export_scene(traj, model, trail, dpi, labels, animated=False)
    scene.show(index)
    figure.canvas.draw()
    return png_bytes(np.asarray(figure.canvas.buffer_rgba()))
