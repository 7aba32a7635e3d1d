"""The live simulator: the kernel computes the motion, the browser plays it.

:func:`live_simulator` shows the sliders of :func:`pendulum_lab.widgets.explore`
(initial state, parameters, method, step, duration) beside a canvas drawn in
the browser by a small ES module (``static/simulator.js``). On every change
the kernel integrates once with :func:`pendulum_lab.simulate` and sends the
run as float32 buffers (:func:`run_messages`), in chunks of at most
:data:`CHUNK_STATES` states; the browser plays it at the display's frame rate
(``requestAnimationFrame``), interpolating linearly between saved states, and
draws the chain with a trail, the kinetic, potential and total energy as bars,
the energy error as a trace, the time, the method and the step. Nothing is
sent per frame.

In the browser
    Play/pause, step, speed and a scrub bar under the canvas. Keyboard (click
    the canvas or tab to it first): Space or K play/pause, Left/Right (or
    comma/period) one saved state back/forward, Up/Down (or +/-) faster/slower,
    Home/End first/last state. Drag a bob with the mouse or a finger: the
    chain follows; on release the kernel restarts the motion from there, at
    rest (:meth:`LiveSimulator.drag`).

A system in space (``model.dimensions == 3``; its points travel as ``(x, y, z)``)
    is drawn in a projection the student turns: a drag on the picture turns it
    about the vertical and tilts it; "reset view", "top" and "side" pick one.
    Only in the top view does dragging a bob set the start, by its horizontal
    position ``(x, y)`` (kept within 95 % of its distance from the pivot); the
    release calls :meth:`LiveSimulator.drag` with that ``(x, y)``. Elsewhere a drag
    turns the view, and the status line says how to set the start.

A description of the state shown (time, kinetic, potential and total
energy, the energy error) sits in an ARIA live region beside the canvas,
updated when the state shown changes other than by playing (a step, a
scrub, pause, a new run) and when playing starts, so that a screen reader
announces it. For a model that does not conserve energy (damping, a drive),
the trace and the description call ``E - E(0)`` an energy change.

The drawing counts the frames it has drawn in the ``data-frames`` attribute
of its root element (``.plab-live``), for measuring the frame rate, and the
mean time it spent drawing one in ``data-draw-ms``.
"""

from __future__ import annotations

import math

import numpy as np
import traitlets

from .. import validation as check
from ..driver.simulate import Trajectory
from ..model import require_model, wrap_angle
from ..model.pendulum import PendulumModel
from ..plotting.scene import TRAIL, still_frame
from .browser import run_settings, with_run_settings
from .calls import SimulateCall
from .channel import STATIC, ReplayWidget, figure_message, float32_buffer
from .controls import (
    SIMULATOR_T_END,
    SPEEDS,
    build_simulator,
    call_from_controls,
    control_names,
    energy_changers,
    energy_is_conserved,
    forces_text,
    pendulum_controls,
)
from .instrument import Instrument

__all__ = [
    "CHUNK_STATES",
    "PLAYBACK_SPACING",
    "LiveSimulator",
    "PendulumView",
    "live_simulator",
    "released_angles",
    "run_messages",
]

#: Saved states are at most this far apart in time [s] (the browser interpolates between them).
PLAYBACK_SPACING = 0.01
#: Largest number of states in one message.
CHUNK_STATES = 4096


def playback_stride(dt: float) -> int:
    """Every how many steps a state is sent: the largest stride keeping states <= 10 ms apart."""
    return max(1, math.floor(PLAYBACK_SPACING / dt * (1 + 1e-9)))


def run_messages(
    traj: Trajectory, model: PendulumModel, *, run: int, chunk_states: int = CHUNK_STATES
) -> list[tuple[dict, list]]:
    """The messages that carry one run to the browser: ``(content, buffers)`` pairs.

    Every :func:`playback_stride`-th state is sent. Each message holds up to
    ``chunk_states`` consecutive states as three little-endian float32
    buffers, all row-major:

    0. angles, shape ``(count, n)`` [rad];
    1. kinetic, potential and total energy, shape ``(count, 3)`` [J];
    2. the energy error ``E - E(0)``, shape ``(count,)`` [J], computed in
       float64 before the cast (float32 energies would hide errors below
       about 1e-6 J);
    3. for a system given by its points (not a chain), the points' positions,
       shape ``(count, points, 2)`` [m], ``(count, points, 3)`` for points in space
       (``figure["dimensions"]``): the browser cannot compute them.

    ``content`` says where the chunk goes (``run``, ``chunk`` of ``chunks``,
    ``first`` state, ``count``, ``chunk_states``) and repeats what the drawing needs: ``links``
    (the number of coordinates), ``lengths`` (a chain's; empty for a system), ``figure``
    (:func:`figure_message`), ``states`` (all chunks together), ``spacing`` (s
    between sent states), ``dt``, ``stride``, ``steps``, ``method``,
    ``energy0``, ``energy_range`` (bar scale, including 0), ``error_max``
    (largest ``|E - E(0)|`` over every step), ``completed``, ``conserved``
    (whether the model conserves energy: else ``E - E(0)`` is the work of
    ``changed_by`` plus the method's error, and the browser says so:
    :func:`~pendulum_lab.widgets.controls.energy_changers`, such as "the damping and the
    drive" or "the point moved with the time") and ``forces``
    (:func:`~pendulum_lab.widgets.controls.forces_text`).

    Parameters
    ----------
    traj : Trajectory
        A single trajectory of ``model``.
    model : PendulumModel
    run : int
        Number of the run (the browser drops chunks of older runs).
    chunk_states : int
        States per message, ``>= 1``.

    Returns
    -------
    list of (dict, list of memoryview)

    Examples
    --------
    >>> import numpy as np, pendulum_lab as pl
    >>> sp_ = pl.simple_pendulum()
    >>> traj = pl.simulate(sp_, [1.0], [0.0], t_end=1.0, dt=0.01)
    >>> (content, buffers), = run_messages(traj, sp_, run=1)
    >>> content["states"], [b.nbytes for b in buffers]
    (101, [404, 1212, 404])
    >>> content["figure"]["rods"], content["figure"]["reach"]
    ([[-1, 0]], 1.0)
    >>> float(np.frombuffer(buffers[0], "<f4")[0])
    1.0
    """
    if not isinstance(traj, Trajectory) or traj.theta.ndim != 2:
        raise TypeError("`traj` must be a single Trajectory (angles of shape (N+1, n))")
    require_model(model)
    chunk_states = check.integer_at_least("chunk_states", chunk_states, 1)
    stride = playback_stride(traj.dt)
    kept = np.arange(0, len(traj.t), stride)
    angles = traj.theta[kept]
    points = None
    if not model.is_chain:
        points = np.stack(model.positions(angles, traj.t[kept]), axis=-1)
    energies = np.column_stack([traj.kinetic, traj.potential, traj.energy])[kept]
    error = traj.energy_error[kept]
    levels = np.concatenate([[0.0], energies[np.isfinite(energies)]])
    finite_error = np.abs(traj.energy_error[np.isfinite(traj.energy_error)])
    chunks = math.ceil(len(kept) / chunk_states)
    meta = {
        "type": "run",
        "run": int(run),
        "chunks": chunks,
        "chunk_states": chunk_states,
        "states": len(kept),
        "links": model.n,
        "lengths": list(model.lengths) if model.is_chain else [],
        "figure": figure_message(model, points),
        "spacing": stride * traj.dt,
        "dt": traj.dt,
        "stride": stride,
        "steps": len(traj.t) - 1,
        "method": traj.method.name,
        "energy0": float(traj.energy[0]),
        "energy_range": [float(levels.min()), float(levels.max())],
        "error_max": float(finite_error.max()) if finite_error.size else 0.0,
        "completed": bool(traj.completed),
        "conserved": energy_is_conserved(model),
        "forces": forces_text(model),
        "changed_by": energy_changers(model),
    }
    messages = []
    for chunk, first in enumerate(range(0, len(kept), chunk_states)):
        part = slice(first, first + chunk_states)
        count = len(kept[part])
        content = {**meta, "chunk": chunk, "first": first, "count": count}
        sent = (angles, energies, error) if points is None else (angles, energies, error, points)
        buffers = [float32_buffer(a[part]) for a in sent]
        messages.append((content, buffers))
    return messages


def released_angles(model: PendulumModel, theta, bob: int, x: float, y: float) -> np.ndarray:
    """The coordinates after point ``bob`` is dragged to ``(x, y)`` and released (at ``t = 0``,
    where the new run starts): :meth:`~pendulum_lab.PendulumModel.place_point`.

    For a chain, bob ``bob`` (0-based) moves on its circle around the joint before it, to
    the point of the circle in the direction of ``(x, y)``; the other arms keep
    their angles. A point beyond the arm's reach is therefore clamped onto the
    circle (a rod does not stretch): only its direction counts. For a system given by its
    points, the coordinates nearest ``theta`` that put the point there (a point its
    coordinates do not place, such as a shaken pivot, is refused with the reason). Angles
    come back wrapped into ``(-pi, pi]``, the range of the angle sliders.

    Parameters
    ----------
    model : PendulumModel
    theta : array_like, shape (n,)
        The angles when the drag started [rad].
    bob : int
        Which bob was dragged, ``0 <= bob < n``.
    x, y : float
        The release point [m], pivot at the origin, ``y`` up; for a system in space its
        horizontal position (as seen from above, ``z`` up).

    Returns
    -------
    ndarray, shape (n,)

    Raises
    ------
    TypeError, ValueError
        If a value is not finite, ``bob`` is not a link number, or the
        release point is the joint itself (no direction).

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> released_angles(pl.double_pendulum(), [0.0, 0.0], 0, 5.0, 0.0)  # far right: clamped
    array([1.57079633, 0.        ])
    """
    require_model(model)
    theta = check.state_vector("theta", theta, model.n)
    bob = check.index_below("bob", bob, len(model.drawing.masses))
    x, y = check.real_number("x", x), check.real_number("y", y)
    placed = model.place_point(bob, x, y, theta, t=0.0)
    return np.where(model.angle_coordinates, wrap_angle(placed), placed)


class PendulumView(ReplayWidget):
    """The canvas of the live simulator (an anywidget); :class:`LiveSimulator` drives it.

    Attributes
    ----------
    playing : bool
        Playing or paused (the browser's play button and keys change it too).
    speed : float
        Simulated seconds per real second, one of ``speeds``.
    trail : float
        Length of the last bob's trail [s].
    loop : bool
        Start again at the end of the run.
    time : float
        The time shown [s], as the browser last reported it (on pause, a step
        or a scrub; not every frame); setting it moves the browser there.
    run : int
        Number of the run shown; each new trajectory increments it.
    """

    _esm = STATIC / "simulator.js"

    playing = traitlets.Bool(True).tag(sync=True)
    speed = traitlets.Float(1.0).tag(sync=True)
    speeds = traitlets.List(list(SPEEDS)).tag(sync=True)
    trail = traitlets.Float(TRAIL).tag(sync=True)
    loop = traitlets.Bool(True).tag(sync=True)
    time = traitlets.Float(0.0).tag(sync=True)
    run = traitlets.Int(0).tag(sync=True)

    @traitlets.validate("speed")
    def _valid_speed(self, proposal):
        return _trait_checked(check.choice, "speed", proposal["value"], self.speeds)

    @traitlets.validate("trail")
    def _valid_trail(self, proposal):
        return _trait_checked(check.non_negative_number, "trail", proposal["value"])

    def show_run(self, traj: Trajectory, model: PendulumModel) -> None:
        """Send ``traj`` as the new run; the browser plays it from ``t = 0``."""
        messages = run_messages(traj, model, run=self.run + 1)
        self.run += 1
        self.time = 0.0
        self._publish(messages)


class LiveSimulator(Instrument):
    """The live simulator; build it with :func:`live_simulator`.

    An :class:`~pendulum_lab.widgets.Instrument` without a matplotlib
    figure: it shows each run by sending it to :attr:`view`.

    Attributes
    ----------
    controls : dict of str -> ipywidgets widget
        As for :func:`pendulum_lab.widgets.explore`; a change recomputes.
    view : PendulumView
        The canvas (playback state: ``view.playing``, ``view.speed``, ...).
    trajectory : Trajectory
        The run shown (every step; the browser receives every
        :func:`playback_stride`-th state).
    widget : ipywidgets.VBox
        Controls, status line and canvas; display this.
    """

    def __init__(self, model, method, t_end, dt, theta0, omega0, speed, trail):
        controls, columns = pendulum_controls(
            model, theta0, omega0, t_end=t_end, dt=dt, method=method, t_end_range=SIMULATOR_T_END
        )
        self.view = PendulumView(speed=speed, trail=trail)
        super().__init__(model, controls, columns, figure=False)
        self.view.handle("release", self._on_release)
        self.widget.children = (*self.widget.children, self.view)

    # ---- the Instrument's hooks: no figure, the run goes to the browser ------------------------
    def prepare(self) -> SimulateCall:
        return call_from_controls(self.model, self.controls)

    def show(self) -> None:
        """Send the current run to the browser, which plays it from ``t = 0``."""
        self.view.show_run(self.trajectory, self.model)

    def set_message(self, text: str, kind: str = "info") -> None:
        """The status line, and inside the canvas what went wrong (the status line reports
        every run; the canvas shows only warnings and errors)."""
        super().set_message(text, kind)
        problem = kind != "info"
        self.view.show_message(text if problem else "", "error" if problem else "info")

    def picture(self) -> tuple[str, bytes]:
        """The run drawn by :func:`pendulum_lab.animation.still_frame` at its last state (the
        whole motion's energies), for a page without a kernel, where nothing can play."""
        return "image/png", still_frame(self.trajectory, self.model, trail=self.view.trail)

    def _repr_mimebundle_(self, **kwargs):
        """The widget, its still picture and, for a page without a kernel (the course website),
        the run's settings as the browser's engine takes them (:data:`BROWSER_SETTINGS`)."""
        return with_run_settings(super()._repr_mimebundle_(**kwargs), self.browser_settings())

    def browser_settings(self) -> dict:
        """The current run as :func:`~pendulum_lab.widgets.browser.browser_config` gives it to
        the browser's engine, or ``{"refusal": sentence}`` if the browser cannot run it."""
        return run_settings(self.model, self.trajectory, self.view.trail)

    # ---- dragging ---------------------------------------------------------------------------
    def drag(self, bob: int, x: float, y: float, theta=None) -> bool:
        """Release bob ``bob`` (0-based) at ``(x, y)`` [m] and start the motion from there, at rest.

        What a release of a dragged bob in the browser does: the angles
        become :func:`released_angles` (``theta`` are the angles when the drag
        started, by default the current initial angles), the angular
        velocities zero; the sliders move there and the run is recomputed
        once. Returns whether the run was computed; if not, ``message`` says
        why and the previous motion goes on.

        Raises
        ------
        TypeError, ValueError
            For a release that cannot start a motion (a value that is not a
            finite number, ``bob`` not a link number, a release on the joint),
            saying why; the simulator is left as it was. (A release in the
            browser shows the same sentence in the status line and in the
            picture instead.)
        """
        keys = control_names(self.model.n)
        if theta is None:
            theta = [self.controls[k].value for k in keys["theta"]]
        angles = released_angles(self.model, theta, bob, x, y)
        start = dict(zip(keys["theta"], angles.tolist()))
        start.update(dict.fromkeys(keys["omega"], 0.0))
        self.view.playing = True
        return self.set_controls(start)

    def _on_release(self, content: dict) -> None:
        try:
            ok = self.drag(
                _as_number(content.get("bob")),
                _as_number(content.get("x")),
                _as_number(content.get("y")),
                content.get("theta"),
            )
        except (TypeError, ValueError) as err:
            self.set_message(
                f"Cannot start from that drag: {err}. The previous motion goes on.", "error"
            )
            ok = False
        self.view.send({"type": "released", "ok": bool(ok), "message": self.message})

    @property
    def time(self) -> float:
        """The time shown in the browser [s] (as last reported: on pause, step or scrub)."""
        return self.view.time


def _trait_checked(check_value, name, value, *args):
    """A check of :mod:`pendulum_lab.validation` as a trait validator (a ``TraitError``)."""
    try:
        return check_value(name, value, *args)
    except (TypeError, ValueError) as err:
        raise traitlets.TraitError(str(err)) from None


def _as_number(value):
    """JSON numbers as Python numbers; JavaScript's NaN and infinities arrive as None."""
    return float("nan") if value is None else value


def live_simulator(
    model: PendulumModel,
    theta0=None,
    omega0=None,
    *,
    t_end: float = 20.0,
    dt: float = 0.01,
    method="glrk4",
    speed: float = 1.0,
    trail: float = TRAIL,
) -> LiveSimulator:
    """The live pendulum simulator, drawn in the browser at the display's frame rate.

    Takes the arguments of :func:`pendulum_lab.animation.simulator`, the
    matplotlib simulator kept for the report and for export: the model (its
    parameters are the sliders' start values), the initial angles [rad] in
    ``[-pi, pi]`` and angular velocities [rad/s] in ``[-10, 10]`` (by default
    1 rad for one link, ``(2.0, 2.5)`` for two, at rest), the run's length
    ``t_end`` in ``[1, 60]`` s and step ``dt``, the method, the playback
    ``speed`` (one of :data:`~pendulum_lab.widgets.controls.SPEEDS`) and the
    length of the last bob's ``trail`` [s].

    Returns
    -------
    LiveSimulator
        ``widget`` to display (a bare ``sim`` at the end of a cell shows it),
        ``controls``, ``view``, ``trajectory``, ``message``, ``drag()`` and
        ``update()``.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> sim = live_simulator(pl.double_pendulum(), t_end=2.0)
    >>> sim.drag(0, 1.0, 0.0)          # the first bob to the right of the pivot
    True
    >>> sim.trajectory.theta[0].round(4).tolist(), sim.trajectory.omega[0].tolist()
    ([1.5708, 2.5], [0.0, 0.0])
    """
    return build_simulator(
        LiveSimulator, model, theta0, omega0, t_end=t_end, dt=dt, method=method, speed=speed,
        trail=trail,
    )
