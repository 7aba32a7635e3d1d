"""Click to launch: a Poincare section and a phase portrait where a click starts an orbit.

Both explorers show a picture (matplotlib, rendered in the kernel once per
change of its axes) under a canvas drawn in the browser by
``static/clickable.js``. A click on the canvas sends the point, in the
picture's data coordinates, to the kernel, which launches the orbit through
it and sends the orbit's points back as float32 buffers; the browser draws
them in a new colour over the picture. Undo removes the last orbit, clear
removes all, and "Copy as code" (in the Orbits column) copies the code that
computes the last one.

* :func:`section_explorer` (notebook 11): the section ``theta_1 = 0``,
  ``theta_1' > 0`` of the double pendulum at a chosen energy, in
  ``(theta_2, p_2)``. The missing momentum ``p_1`` comes from the energy
  (:func:`pendulum_lab.chaos.section_states`); the crossings from
  :func:`pendulum_lab.chaos.poincare_section`. Grey marks where no orbit of
  that energy reaches the section. Orbits belong to their energy: moving the
  energy slider shows the orbits launched at the new energy, keeps the
  others for when it comes back, and says so. A model with damping or a
  drive is refused: its orbits leave the energy surface.
* :func:`portrait_explorer` (notebook 03): the simple pendulum's level sets
  (:func:`pendulum_lab.plotting.plot_phase_portrait`) and the simulated
  orbit from the clicked ``(theta, omega)``, angles wrapped into
  ``(-pi, pi]``; the window widens when an orbit leaves it. The orbit is the
  model's own: with damping or a drive it crosses the level sets, which are
  those of the pendulum without them, and the explorer says so.

Keyboard: the arrow keys move a cross-hair, Enter launches there, U undoes.
A click where no orbit exists, or a run that fails, leaves the picture as it
was and shows a sentence saying why.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import ipywidgets as widgets
import matplotlib as mpl
import numpy as np
import traitlets
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from .. import chaos, plotting
from .. import validation as check
from ..driver.simulate import time_grid
from ..model import require_double_pendulum, require_model
from ..model.pendulum import PendulumModel
from ..plotting.png import png_bytes
from .calls import SimulateCall, model_code
from .channel import STATIC, ReplayWidget, float32_buffer
from .controls import (
    check_steps,
    column,
    energy_is_conserved,
    forces_text,
    run_controls,
    slider,
)
from .instrument import EXPECTED_ERRORS, WidgetWithPicture
from .status import StatusLine

__all__ = [
    "ClickablePlot",
    "ClickExplorer",
    "Orbit",
    "PortraitExplorer",
    "SectionExplorer",
    "portrait_explorer",
    "section_explorer",
    "section_reach",
]

#: The format of the Poincare section's energy on its slider (its values are whole steps of
#: :data:`ENERGY_STEP`, so the readout shows the value the title and messages state).
ENERGY_FORMAT = ".1f"
#: Step of the Poincare section's energy slider [J].
ENERGY_STEP = 0.5


def _hex(rgba) -> str:
    return "#" + "".join(f"{round(255 * c):02x}" for c in rgba[:3])


#: Colours of successive orbits: matplotlib's tab10, reordered so that the first ones differ
#: from the blue, green and red of the phase portrait's level sets.
COLOURS = tuple(_hex(mpl.colormaps["tab10"](k)) for k in (1, 4, 9, 5, 6, 8, 7, 0, 2, 3))
_SIZE = (600, 440)  # CSS pixels of the picture
_DPI = 100
_BOX = (0.12, 0.11, 0.84, 0.80)  # the axes in figure fractions: left, bottom, width, height


class ClickablePlot(ReplayWidget):
    """A picture with orbits drawn over it in the browser (an anywidget).

    Attributes
    ----------
    background : bytes
        PNG of the picture.
    frame : dict
        Where the axes are: ``box`` (left, top, right, bottom as fractions of
        the picture, from its top-left corner), ``xlim``, ``ylim``, ``size``
        (CSS pixels), ``labels`` (axis names for the pointer readout),
        ``title`` (the picture's, also its text for screen readers) and
        ``style`` (``"points"`` or ``"line"``).
    orbits : list of dict
        ``{"xy": float32 bytes of shape (K, 2), "colour": "#rrggbb",
        "label": str}``, drawn in order.
    """

    _esm = STATIC / "clickable.js"

    background = traitlets.Bytes(b"").tag(sync=True)
    frame = traitlets.Dict({}).tag(sync=True)
    orbits = traitlets.List([]).tag(sync=True)


@dataclass(frozen=True)
class Orbit:
    """One launched orbit: the points drawn (shape ``(K, 2)``), its colour, a label, and the
    code that computes it ("Copy as code")."""

    points: np.ndarray
    colour: str
    label: str
    code: str = ""


class ClickExplorer(WidgetWithPicture):
    """Controls, a clickable picture, undo and clear; the explorers below fill in the physics.

    Subclasses implement ``_draw_background(ax)`` (draw the picture into
    axes whose position is fixed) and ``_launch(x, y) -> (points, label,
    code)`` (raise ``ValueError`` with a readable sentence when there is no
    orbit through ``(x, y)``); ``_redraw_on`` names the controls whose change
    redraws the picture. Orbits belong to the values of those controls
    (:meth:`view`): the picture shows the orbits launched at the current
    ones, and keeps the others.

    Attributes
    ----------
    controls : dict of str -> ipywidgets widget
    plot : ClickablePlot
    orbits : list of Orbit
        The orbits shown (launched at the current values of ``_redraw_on``).
    message : str
    status : StatusLine
        Holds "Copy as code" (the code of the last orbit shown).
    widget : ipywidgets.VBox
    """

    _style = "points"
    _redraw_on: tuple[str, ...] = ()
    _hint = "Click the picture to launch an orbit."

    def __init__(self, model: PendulumModel, controls: dict, columns: list):
        self.model = model
        self.controls = controls
        self._orbits: dict[tuple, list[Orbit]] = {}
        self.plot = ClickablePlot()
        self.plot.handle("click", self._on_click)
        self.plot.handle("undo", lambda content: self.undo())
        self.status = StatusLine()
        undo = widgets.Button(description="Undo", tooltip="remove the last orbit (U)")
        clear = widgets.Button(description="Clear", tooltip="remove every orbit shown")
        undo.on_click(lambda _: self.undo())
        clear.on_click(lambda _: self.clear())
        boxes = [column(title, [controls[k] for k in keys]) for title, keys in columns]
        boxes.append(column("Orbits", [undo, clear, self.status]))
        self.widget = widgets.VBox([widgets.HBox(boxes), self.plot])
        for key in self._redraw_on:
            controls[key].observe(lambda change: self.redraw(), names="value")
        self.redraw()

    @property
    def message(self) -> str:
        """The sentence shown under the picture."""
        return self.plot.message

    @property
    def orbits(self) -> list[Orbit]:
        """The orbits shown: those launched at the current :meth:`view`."""
        return self._orbits.setdefault(self.view(), [])

    def view(self) -> tuple:
        """The values of the controls the picture depends on (``_redraw_on``)."""
        return tuple(self.controls[key].value for key in self._redraw_on)

    def describe_view(self, view: tuple) -> str:
        """``view`` in words, for messages (subclasses with ``_redraw_on`` say more)."""
        return ", ".join(map(str, view))

    # ---- the picture ------------------------------------------------------------------------
    def redraw(self) -> None:
        """Draw the picture again, with the orbits launched at the current :meth:`view`.

        The message says how many are shown and how many are kept at other
        values of the controls.
        """
        self._draw_picture()
        self._send_orbits()
        here = len(self.orbits)
        elsewhere = {view: len(orbits) for view, orbits in self._orbits.items()
                     if orbits and view != self.view()}
        parts = [self._hint]
        if here:
            parts.insert(0, f"{here} orbit(s) launched here before are shown.")
        if elsewhere:
            kept = "; ".join(f"{count} at {self.describe_view(view)}"
                             for view, count in elsewhere.items())
            parts.append(f"Orbits launched elsewhere are kept, not shown ({kept}): move the "
                         "slider back to see them.")
        self.plot.show_message(" ".join(parts))

    def _draw_picture(self) -> None:
        width, height = _SIZE
        figure = Figure(figsize=(width / _DPI, height / _DPI), dpi=_DPI)
        canvas = FigureCanvasAgg(figure)
        ax = figure.add_axes(_BOX)
        self._draw_background(ax)
        left, bottom, box_width, box_height = _BOX
        canvas.draw()
        with self.plot.hold_sync():
            self.plot.background = png_bytes(np.asarray(canvas.buffer_rgba()))
            self.plot.frame = {
                "box": [left, 1 - bottom - box_height, left + box_width, 1 - bottom],
                "xlim": [float(v) for v in ax.get_xlim()],
                "ylim": [float(v) for v in ax.get_ylim()],
                "size": [width, height],
                "labels": [ax.get_xlabel(), ax.get_ylabel()],
                "title": ax.get_title(),
                "style": self._style,
            }

    def _send_orbits(self) -> None:
        orbits = self.orbits
        self.plot.orbits = [
            {"xy": float32_buffer(o.points), "colour": o.colour, "label": o.label}
            for o in orbits
        ]
        self.status.code = orbits[-1].code if orbits else ""

    # ---- clicks -----------------------------------------------------------------------------
    def click(self, x: float, y: float) -> bool:
        """Launch the orbit through the point ``(x, y)`` of the picture; return whether it worked.

        On success the orbit is added in a new colour; otherwise the picture
        stays as it was and ``message`` says why.
        """
        try:
            x, y = check.real_number("x", x), check.real_number("y", y)
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", RuntimeWarning)
                points, label, code = self._launch(x, y)
        except EXPECTED_ERRORS as err:
            self.plot.show_message(f"No orbit launched: {err}.", "error")
            return False
        orbits = self.orbits
        colour = COLOURS[len(orbits) % len(COLOURS)]
        orbits.append(Orbit(np.asarray(points, dtype=float), colour, label, code))
        notes = [str(w.message) for w in caught if "encountered in" not in str(w.message)]
        self._send_orbits()
        self.plot.show_message(" ".join([label, *notes[:1]]), "error" if notes else "info")
        return True

    def undo(self) -> bool:
        """Remove the last orbit shown; return whether there was one."""
        if not self.orbits:
            self.plot.show_message("Nothing to undo.")
            return False
        self.orbits.pop()
        self._send_orbits()
        self.plot.show_message(f"{len(self.orbits)} orbit(s) shown.")
        return True

    def clear(self) -> None:
        """Remove every orbit shown (those kept at other values of the controls stay)."""
        self.orbits.clear()
        self._send_orbits()
        self.plot.show_message(self._hint)

    def code(self) -> str:
        """Source that computes the last orbit shown (``""`` when none is)."""
        return self.orbits[-1].code if self.orbits else ""

    def _on_click(self, content: dict) -> None:
        x, y = (float("nan") if content.get(k) is None else content.get(k) for k in ("x", "y"))
        ok = self.click(x, y)
        self.plot.send({"type": "launched", "ok": ok})

    def _run_settings(self) -> dict:
        """``t_end``, ``dt`` and ``method`` from the controls, checked like the explorers'."""
        c = self.controls
        check_steps(c["t_end"].value, c["dt"].value)
        return {"t_end": c["t_end"].value, "dt": c["dt"].value, "method": c["method"].value}

    def picture(self) -> tuple[str, bytes]:
        """The picture clicks launch orbits on, for a page without a kernel (which shows the
        explorer as it starts: the orbits launched in the browser are drawn there, not here)."""
        return "image/png", self.plot.background

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.model!r}, {len(self.orbits)} orbits)"

    def _draw_background(self, ax) -> None:
        raise NotImplementedError

    def _launch(self, x: float, y: float):
        raise NotImplementedError


# --------------------------------------------------------------------------- Poincare section
def section_reach(model: PendulumModel, energy: float, theta2) -> np.ndarray:
    """Largest ``|p_2|`` on the section ``theta_1 = 0`` at ``energy``, for each ``theta_2``.

    A point ``(theta_2, p_2)`` of the section has an orbit of energy ``E``
    when some ``p_1`` gives ``H = E``. With ``A = M^-1``, the least kinetic
    energy over ``p_1`` is ``p_2^2 / (2 M_22)`` (the Schur complement
    ``A_22 - A_12^2 / A_11`` of ``A`` equals ``1 / M_22``), so the reachable
    points are ``p_2^2 <= 2 M_22(theta) (E - V(0, theta_2))``. Where the
    potential alone exceeds ``E`` the result is NaN.

    Parameters
    ----------
    model : PendulumModel
        A double pendulum.
    energy : float
    theta2 : array_like
        Angles of the second arm [rad].

    Returns
    -------
    ndarray, shape like ``theta2`` [kg m^2/s]

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> dp = pl.double_pendulum()
    >>> float(section_reach(dp, -20.0, 0.0) ** 2 / 2)   # M_22 = 1: the energy above V(0, 0)
    9.43
    """
    require_model(model)
    energy = check.real_number("energy", energy)
    theta2 = np.asarray(theta2, dtype=float)
    theta = np.stack([np.zeros_like(theta2), theta2], axis=-1)
    room = energy - model.potential_energy(theta)
    m22 = model.mass_matrix_at(theta)[..., 1, 1]
    with np.errstate(invalid="ignore"):
        return np.where(room >= 0, np.sqrt(2 * m22 * np.maximum(room, 0)), np.nan)


class SectionExplorer(ClickExplorer):
    """The clickable Poincare section; build it with :func:`section_explorer`."""

    _style = "points"
    _redraw_on = ("energy",)
    _hint = "Click inside the white region to launch an orbit of this energy."

    def __init__(self, model: PendulumModel, energy: float, t_end: float, dt: float, method):
        depth = -float(model.potential_energy(np.zeros(2)))
        # On the slider's grid, so that its readout shows the energy the title states.
        low = math.floor(-depth / ENERGY_STEP + 1) * ENERGY_STEP
        high = math.floor(depth / ENERGY_STEP) * ENERGY_STEP
        controls = {
            "energy": slider(energy, low, high, ENERGY_STEP, "E (J)", ENERGY_FORMAT),
            **run_controls(model, method, t_end, dt, t_end_range=(10.0, 500.0)),
        }
        columns = [("Energy surface", ["energy"]), ("Integration", ["method", "dt", "t_end"])]
        super().__init__(model, controls, columns)

    @property
    def energy(self) -> float:
        return float(self.controls["energy"].value)

    def describe_view(self, view: tuple) -> str:
        return f"E = {view[0]:g} J"

    def _draw_background(self, ax) -> None:
        theta2 = np.linspace(-np.pi, np.pi, 721)
        reach = section_reach(self.model, self.energy, theta2)
        top = 1.12 * float(np.nanmax(reach)) if np.any(np.isfinite(reach)) else 1.0
        ax.set_facecolor("0.85")
        ax.fill_between(theta2, -reach, reach, color="white", lw=0)
        ax.plot(theta2, reach, color=plotting.SEPARATRIX, lw=1)
        ax.plot(theta2, -reach, color=plotting.SEPARATRIX, lw=1)
        ax.set(
            xlim=(-np.pi, np.pi),
            ylim=(-top, top),
            xlabel=plotting.axis_label("theta", "₂"),
            ylabel=plotting.axis_label("p", "₂"),
            title=f"Poincaré section θ₁ = 0, θ₁′ > 0 at {self.describe_view((self.energy,))}",
        )

    def _launch(self, x, y):
        energy = self.describe_view((self.energy,))
        reach = float(section_reach(self.model, self.energy, x))
        if not abs(y) <= reach:  # also catches reach = NaN
            where = (
                "the potential energy alone" if math.isnan(reach) else "the least kinetic energy"
            )
            raise ValueError(
                f"at {energy} no orbit passes through θ₂ = {x:.3f} rad, "
                f"p₂ = {y:.3f} kg m²/s: with {where} there the energy would exceed E "
                "(the grey region). Click inside the white region"
            )
        settings = self._run_settings()
        theta0, omega0 = chaos.section_states(self.model, self.energy, [[x]], [[y]])
        sec = chaos.poincare_section(self.model, theta0, omega0, **settings, progress=False)
        xs, ys = sec.coordinates()
        points = np.column_stack([np.r_[x, xs], np.r_[y, ys]])
        label = (
            f"Orbit {len(self.orbits) + 1} from θ₂ = {x:.3f} rad, p₂ = {y:.3f} kg m²/s at "
            f"{energy}: {len(xs)} crossings in {settings['t_end']:g} s ({settings['method']}, "
            f"Δt = {settings['dt']:g} s)."
        )
        call = SimulateCall(self.model, np.reshape(theta0, (-1, 2))[0],
                            np.reshape(omega0, (-1, 2))[0], **settings)
        arguments = (f"t_end={float(settings['t_end'])!r}, dt={float(settings['dt'])!r}, "
                     f"method={settings['method']!r}")
        code = (
            "import pendulum_lab as pl\n"
            "from pendulum_lab import chaos\n\n"
            f"model = {model_code(self.model)}\n"
            f"# The state on the section theta1 = 0 through (theta2, p2) = ({x!r}, {y!r}) at "
            f"E = {self.energy!r} J:\n"
            f"theta0, omega0 = chaos.section_states(model, {self.energy!r}, [[{x!r}]], "
            f"[[{y!r}]])\n"
            f"traj = pl.simulate(model, {call.arguments()})\n"
            "# Its crossings, the points drawn (after the clicked one):\n"
            f"section = chaos.poincare_section(model, theta0, omega0, {arguments})\n"
            "theta2, p2 = section.coordinates()\n"
            "section.plot()\n"
        )
        return points, label, code


def section_explorer(
    model: PendulumModel,
    energy: float = -15.0,
    *,
    t_end: float = 100.0,
    dt: float = 0.01,
    method="glrk4",
) -> SectionExplorer:
    """A Poincare section of the double pendulum where a click launches an orbit.

    The section is ``theta_1 = 0`` crossed with ``theta_1' > 0``, drawn in
    ``(theta_2, p_2)`` (as :func:`pendulum_lab.chaos.energy_sections`). A
    click at ``(theta_2, p_2)`` solves the energy for the missing ``p_1``
    (:func:`pendulum_lab.chaos.section_states`), integrates for ``t_end``
    seconds and adds the crossings (:func:`pendulum_lab.chaos.poincare_section`)
    in a new colour, the clicked point first. Regular orbits trace closed
    curves, chaotic ones scatter.

    Parameters
    ----------
    model : PendulumModel
        A double pendulum.
    energy : float
        Total energy [J], above the bottom of the potential.
    t_end, dt : float
        Duration of each orbit and step [s].
    method : str

    Returns
    -------
    SectionExplorer
        ``widget`` to display, ``controls`` (``"energy"``, ``"method"``,
        ``"dt"``, ``"t_end"``), ``click(theta2, p2)``, ``undo()``,
        ``clear()``, ``orbits`` (those of the energy shown), ``code()``,
        ``message``.

    Raises
    ------
    ValueError
        For a model that is not a double pendulum, or one with damping or a
        drive (its energy is not conserved, so its orbits leave the energy
        surface the section is drawn on), with the reason.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> ex = section_explorer(pl.double_pendulum(), energy=-15.0, t_end=20.0)
    >>> ex.click(0.5, 0.0), ex.click(3.0, 8.0)   # the second is outside the reachable region
    (True, False)
    >>> len(ex.orbits), ex.message.startswith("No orbit launched")
    (1, True)
    """
    model = require_double_pendulum(model)
    if not energy_is_conserved(model):
        raise ValueError(
            "`model` must have no damping and no drive: section_explorer launches orbits on one "
            f"energy surface, and with {forces_text(model)} the energy is not conserved, so an "
            "orbit leaves its surface; chaos.poincare_section computes the crossings of such "
            "a model"
        )
    time_grid(t_end, dt)  # the rule of every run, checked before the first click
    depth = -float(model.potential_energy(np.zeros(2)))
    energy = check.number_in("energy", energy, -depth, depth, "J", open_low=True)
    return SectionExplorer(model, energy, t_end, dt, method)


# --------------------------------------------------------------------------- phase portrait
class PortraitExplorer(ClickExplorer):
    """The clickable phase portrait; build it with :func:`portrait_explorer`."""

    _style = "line"
    _hint = "Click anywhere to launch the orbit through that point."

    def __init__(self, model: PendulumModel, t_end: float, dt: float, method):
        self.omega_max = 1.6 * 2.0 * math.sqrt(abs(model.g) / model.lengths[0])
        if not energy_is_conserved(model):
            self._hint = (
                f"{self._hint} The curves are the energy levels of the pendulum without "
                f"damping and drive; this one ({forces_text(model)}) crosses them."
            )
        controls = run_controls(model, method, t_end, dt, t_end_range=(1.0, 60.0))
        super().__init__(model, controls, [("Integration", ["method", "dt", "t_end"])])

    def _draw_background(self, ax) -> None:
        plotting.plot_phase_portrait(self.model, ax=ax, omega_max=self.omega_max)

    def _launch(self, x, y):
        settings = self._run_settings()
        call = SimulateCall(self.model, np.array([x]), np.array([y]), **settings)
        traj = call.run()
        theta, omega = plotting.wrap_angle(traj.theta[:, 0]), traj.omega[:, 0]
        finite = np.isfinite(theta) & np.isfinite(omega)
        points = np.column_stack([theta[finite], omega[finite]])
        top = float(np.max(np.abs(points[:, 1])))
        if top > self.omega_max:
            # Widen the window to hold the new orbit; the earlier ones stay.
            self.omega_max = 1.1 * top
            self._draw_picture()
        change = traj.energy[finite] - traj.energy[0]
        if energy_is_conserved(self.model):
            energy = f"max |E − E(0)| = {np.max(np.abs(change)):.2e} J"
        else:
            energy = (f"E − E(0) reached {change[np.argmax(np.abs(change))]:+.3g} J (not "
                      f"conserved: {forces_text(self.model)})")
        label = (
            f"Orbit {len(self.orbits) + 1} from θ = {x:.3f} rad, ω = {y:.3f} rad/s: "
            f"E(0) = {traj.energy[0]:.3f} J, {energy} over {traj.t[-1]:g} s "
            f"({settings['method']}, Δt = {settings['dt']:g} s)."
        )
        code = call.code() + (
            "# The curve drawn: angles wrapped into (-pi, pi]\n"
            "theta, omega = pl.plotting.wrap_angle(traj.theta[:, 0]), traj.omega[:, 0]\n"
            "# drawn on the phase portrait:\n"
            "pl.plotting.plot_phase_portrait(model, trajectory=traj)\n"
        )
        return points, label, code


def portrait_explorer(
    model: PendulumModel, *, t_end: float = 10.0, dt: float = 0.01, method="glrk4"
) -> PortraitExplorer:
    """The simple pendulum's phase portrait, where a click launches the orbit through that point.

    The picture is :func:`pendulum_lab.plotting.plot_phase_portrait`
    (librations, rotations, the separatrix). A click at ``(theta, omega)``
    integrates from there for ``t_end`` seconds and draws the orbit, angles
    wrapped into ``(-pi, pi]``, in a new colour; with a method that does not
    conserve energy (``"explicit_euler"``) the orbit visibly spirals out. If
    an orbit reaches beyond the window, the window widens to hold it.

    Parameters
    ----------
    model : PendulumModel
        A simple pendulum. With damping or a drive (``pl.driven_pendulum()``)
        the orbit is that model's and crosses the level sets, which are those
        of the pendulum without them; the explorer says so.
    t_end, dt : float
        Duration of each orbit and step [s].
    method : str

    Returns
    -------
    PortraitExplorer
        ``widget`` to display, ``controls`` (``"method"``, ``"dt"``,
        ``"t_end"``), ``click(theta, omega)``, ``undo()``, ``clear()``,
        ``orbits``, ``omega_max``, ``code()``, ``message``.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> ex = portrait_explorer(pl.simple_pendulum(), t_end=5.0)
    >>> ex.click(-3.1, -9.5)            # a fast rotation: the window widens to hold it
    True
    >>> bool(ex.omega_max > 9.5 and ex.orbits[0].points[:, 0].min() > -3.1416)
    True
    """
    model = require_model(model)
    if model.n != 1:
        raise ValueError(f"`model` must be a simple pendulum (n = 1), got n = {model.n}")
    time_grid(t_end, dt)  # the rule of every run, checked before the first click
    return PortraitExplorer(model, t_end, dt, method)
