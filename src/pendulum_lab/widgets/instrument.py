"""The machinery of every instrument: controls, a status line, and how a run is shown.

An :class:`Instrument` observes its controls; when one changes it prepares
the :func:`pendulum_lab.simulate` call they describe (a
:class:`~pendulum_lab.widgets.calls.SimulateCall`), runs it, catches what
cannot be simulated and says so in its status line
(:class:`~pendulum_lab.widgets.status.StatusLine`), and then shows the run.
By default it shows it in a matplotlib figure rendered to PNG into an
``ipywidgets.Image``, which works the same in JupyterLab, in a notebook run
by nbval and in a test without any front end, and needs no interactive
matplotlib backend. An instrument built with ``figure=False`` has no figure
and shows the run its own way (the live simulator of
:mod:`pendulum_lab.widgets.live` sends it to the browser).

While the run is computed, the status line says so (in the browser after
half a second, with the seconds elapsed) and the figure is marked stale:
:meth:`Instrument.working` is the one place for a "please wait" sentence.
After it, the status line offers the run as code ("Copy as code").

Displayed in a notebook, an instrument adds a one-line hint after itself,
seen only in JupyterLab where the widget cannot be shown (a notebook
reopened without its kernel): run the cell to bring the instrument back.
"""

from __future__ import annotations

import base64
import warnings
from collections.abc import Mapping
from contextlib import contextmanager

import ipywidgets as widgets
import matplotlib as mpl
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ..codegen.compile_status import listen
from ..driver.simulate import Trajectory, step_count
from ..integrators import ConvergenceError
from ..model.pendulum import PendulumModel
from ..plotting.png import png_bytes
from .calls import SimulateCall, panels_code
from .controls import column, energy_changers, energy_is_conserved, forces_text
from .status import StatusLine

__all__ = [
    "DPI",
    "EXPECTED_ERRORS",
    "REOPEN_HINT",
    "ROW_HEIGHT",
    "WIDTH",
    "Instrument",
    "WidgetWithPicture",
]

DPI = 90
ROW_HEIGHT = 3.4  # inches per row of panels
WIDTH = 10.5  # inches

#: Exceptions that mean "this combination of inputs cannot be simulated": an instrument
#: catches them and says so in its status line instead of raising.
EXPECTED_ERRORS = (ValueError, TypeError, ConvergenceError, FloatingPointError, OverflowError)

#: The hint shown after an instrument's output where JupyterLab cannot show the widget
#: (reopened without the widget's kernel state): hidden everywhere else (inline style), shown
#: by its own style rules only in an output area holding a widget that failed to display
#: (JupyterLab marks the failed output itself ``jupyter-widgets``; a shown widget is a child),
#: whose error line it hides.
REOPEN_HINT = (
    '<div class="plab-reopen-hint" style="display:none">'
    "This instrument needs its Python kernel: run this cell to bring it back.</div>"
    "<style>"
    ".jp-OutputArea:has(.jp-OutputArea-output.jupyter-widgets) .plab-reopen-hint"
    "{display:block !important;font-style:italic;color:#555}"
    ".jp-OutputArea:has(.plab-reopen-hint) .jp-OutputArea-output.jupyter-widgets"
    "{display:none}"
    "</style>"
)


#: CSS class of the row of control columns (``static/live.css`` lets it wrap).
CONTROLS_CLASS = "plab-controls"

class WidgetWithPicture:
    """Displays as its ``widget``, with a still :meth:`picture` of it in the same display.

    A live front end (JupyterLab) shows the widget; a page without a kernel
    (the course website, a notebook viewer) shows the picture instead of
    controls that would do nothing. In IPython a second output follows, the
    :data:`REOPEN_HINT` (seen only where JupyterLab cannot show the widget).
    """

    widget = None

    def picture(self) -> tuple[str, bytes]:
        """A still picture of what the widget shows: ``(mime type, bytes)``."""
        raise NotImplementedError

    def _repr_mimebundle_(self, **kwargs):
        bundle = self.widget._repr_mimebundle_(**kwargs)
        mime, data = self.picture()
        bundle[mime] = base64.b64encode(data).decode()
        return bundle

    def _ipython_display_(self):
        from IPython.display import display  # IPython is there whenever this is called

        display(self._repr_mimebundle_(), raw=True)
        display({"text/html": REOPEN_HINT, "text/plain": ""}, raw=True)


class Instrument(WidgetWithPicture):
    """Controls, a status line and a view of the run that :meth:`update` recomputes.

    Subclasses implement :meth:`prepare` (the :func:`pendulum_lab.simulate`
    call the controls describe; raise ``ValueError`` for an invalid
    combination) and either :meth:`draw` (draw the run into the figure) or,
    for an instrument built with ``figure=False``, :meth:`show`. Everything
    else -- observing the controls, running the call, catching errors, the
    status line -- lives here once.

    Parameters
    ----------
    model : PendulumModel
        The model before the first update.
    controls : dict of str -> ipywidgets.ValueWidget
        A change of any of them recomputes.
    columns : list of (str, list of str or ipywidgets.Widget)
        Titles and contents of the columns of controls: control names, or
        widgets shown as they are (a note, say).
    rows : float
        Height of the figure in rows of panels.
    figure : bool
        Whether the instrument shows its run in a matplotlib figure.

    Attributes
    ----------
    controls : dict of str -> ipywidgets.ValueWidget
    model : PendulumModel
        The model of the latest successful update.
    trajectory : Trajectory
        The latest successful trajectory.
    call : SimulateCall
        The call that computed it (:meth:`code` gives it as source).
    figure : matplotlib.figure.Figure or None
        The figure shown (redrawn in place); None for ``figure=False``.
    status : StatusLine
        The status line (its ``code`` is :meth:`code`, for "Copy as code").
    widget : ipywidgets.VBox
        Controls, status line and figure; display this.
    """

    def __init__(
        self,
        model: PendulumModel,
        controls: dict,
        columns: list[tuple[str, list]],
        rows: float = 1,
        *,
        figure: bool = True,
    ):
        self.model = model
        self.controls = controls
        self.trajectory: Trajectory | None = None
        self.call: SimulateCall | None = None
        self._holding = False
        self.status = StatusLine()
        boxes = [
            column(title, [controls[k] if isinstance(k, str) else k for k in keys])
            for title, keys in columns
            if keys
        ]
        row = widgets.HBox(boxes)
        # Columns that do not fit beside each other wrap under each other (live.css): five
        # parameters pushed the last column's controls past the right edge.
        row.add_class(CONTROLS_CLASS)
        children = [row, self.status]
        self.figure = self._canvas = self._image = None
        if figure:
            self.figure = Figure(figsize=(WIDTH, ROW_HEIGHT * rows), dpi=DPI)
            self._canvas = FigureCanvasAgg(self.figure)
            self._image = widgets.Image(format="png")
            children.append(self._image)
        self.widget = widgets.VBox(children)
        for control in controls.values():
            control.observe(self._on_change, names="value")

    # ---- what subclasses provide ------------------------------------------------------------
    def prepare(self) -> SimulateCall:
        """The :func:`pendulum_lab.simulate` call the controls describe (subclasses implement
        this; it should be quick: :meth:`update` runs the call).

        Raises one of :data:`EXPECTED_ERRORS` for a combination that cannot be
        simulated; :meth:`update` turns it into a message.
        """
        raise NotImplementedError

    def draw(self, figure: Figure) -> None:
        """Draw :attr:`trajectory` into the emptied ``figure`` (figure instruments implement it)."""
        raise NotImplementedError

    def summary(self) -> str:
        """The status line after a successful update: steps, method, run time (and compile time
        apart, when the run had to compile first), and the energy:
        its error where the model conserves it, its change (and why) where it does not."""
        traj = self.trajectory
        change = traj.energy_error
        compiled = ""
        if traj.compile_time >= 0.05 and traj.compiled:
            compiled = f" (after compiling for {traj.compile_time:.1f} s, once per machine)"
        elif traj.compile_time >= 0.05:
            compiled = (f" (after loading its compiled kernels from the disk cache in "
                        f"{traj.compile_time:.1f} s)")
        run = (
            f"{len(traj.t) - 1} steps of {traj.method.name} (dt = {traj.dt:g} s) in "
            f"{traj.wall_time:.2f} s{compiled}; E(0) = {traj.energy[0]:.4f} J, "
        )
        if energy_is_conserved(self.model):
            return run + f"max |E − E(0)| = {float(np.max(np.abs(change))):.2e} J"
        largest = float(change[np.argmax(np.abs(np.nan_to_num(change)))])
        return run + (
            f"E − E(0) reached {largest:+.3g} J: energy is not conserved "
            f"({forces_text(self.model)}), so this is the work of "
            f"{energy_changers(self.model)} plus the method's error, not an error alone"
        )

    def show(self) -> None:
        """Show the latest trajectory: by default :meth:`redraw` the figure and :meth:`render` it.

        An instrument without a figure overrides this. It may raise one of
        :data:`EXPECTED_ERRORS`; :meth:`update` then reports it.
        """
        self.redraw()
        self.render()

    def redraw(self) -> None:
        """Draw the current trajectory into an emptied figure (:meth:`draw`)."""
        self.figure.clear()
        self.draw(self.figure)

    def render(self) -> None:
        """Rasterise the figure and send it to the image widget as PNG."""
        # FreeType's hinting of every glyph is a fifth of a redraw; unhinted
        # text looks the same at this size and resolution.
        with mpl.rc_context({"text.hinting": "none"}):
            self.rasterise()
        self._image.value = png_bytes(np.asarray(self._canvas.buffer_rgba()))

    def rasterise(self) -> None:
        """Draw the figure into its canvas's pixels (the explorer reuses its frames' pixels)."""
        self._canvas.draw()

    # ---- the shared machinery ----------------------------------------------------------------
    @property
    def message(self) -> str:
        """The text of the status line: a summary of the run, a warning or an error."""
        return self.status.text

    def set_message(self, text: str, kind: str = "info") -> None:
        """Show ``text`` in the status line; ``kind``: ``"info"``, ``"warning"`` or ``"error"``."""
        self.status.show(text, kind)

    @contextmanager
    def working(self, text: str):
        """Say ``text`` in the status line and mark the figure stale while the block runs.

        The browser shows both only once the block has taken half a second
        (:data:`~pendulum_lab.widgets.status.BUSY_DELAY`), with the seconds
        elapsed; :meth:`update` wraps the run in it. The place for any
        other wait an instrument has (a first-use compile, say).
        """
        with self.status.working(text, box=self.widget):
            yield

    def code(self) -> str:
        """Source that computes the trajectory shown and draws it (``""`` before the first
        run)."""
        return "" if self.call is None else self.call.code(self.drawing_code())

    def drawing_code(self) -> str:
        """Source that draws ``traj`` of ``model`` as this instrument's picture does (for
        "copy as code"): the configuration and the energies, as the simulators show them."""
        return panels_code(["pendulum", "energy"])

    def set_controls(self, values: Mapping[str, object]) -> bool:
        """Set several controls at once and recompute once; return whether the update succeeded.

        Setting them one by one would recompute after each. Unknown names
        raise ``ValueError`` before any control changes.
        """
        unknown = [name for name in values if name not in self.controls]
        if unknown:
            raise ValueError(f"no control named {unknown}; the controls are {list(self.controls)}")
        for name, value in values.items():  # a choice control takes one of its options only
            options = getattr(self.controls[name], "options", None)
            if options is not None:
                choices = [option[1] if isinstance(option, tuple) else option
                           for option in options]
                if value not in choices:
                    raise ValueError(f"`{name}` must be one of {choices}, got {value!r}")
        self._holding = True
        try:
            for name, value in values.items():
                self.controls[name].value = value
        finally:
            self._holding = False
        return self.update()

    def _on_change(self, change) -> None:
        if not self._holding:
            self.update()

    def update(self) -> bool:
        """Recompute from the controls and show the run; return whether it succeeded.

        On an invalid combination the previous trajectory and view stay and
        ``message`` says what is wrong. A run that blew up (non-finite state)
        is shown up to where it stopped, with the warning in ``message``.
        """
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", RuntimeWarning)
                call = self.prepare()
                steps = step_count(call.t_end, call.dt)
                computing = f"computing {steps} steps of {call.method} (dt = {call.dt:g} s)…"

                def say(event):  # a first use compiles before it computes: say which
                    self.status.text = event.message if event.state == "started" else computing

                with self.working(computing), listen(say):
                    trajectory = call.run()
        except EXPECTED_ERRORS as err:
            what = (
                "The solver did not converge"
                if isinstance(err, ConvergenceError)
                else "Cannot run this combination"
            )
            kept = (
                "The figure still shows the previous run."
                if self.figure is not None
                else "The previous run goes on."
            )
            self.set_message(f"{what}: {err}. {kept}", "error")
            return False
        self.model, self.trajectory, self.call = call.model, trajectory, call
        try:
            self.show()
        except EXPECTED_ERRORS as err:
            self.set_message(f"Could not show the run: {err}", "error")
            return False
        self.status.code = self.code()
        # The driver's own warning (a blow-up) says what happened; NumPy's
        # "overflow encountered in ..." that may follow it adds nothing.
        notes = list(
            dict.fromkeys(
                str(w.message)
                for w in caught
                if issubclass(w.category, RuntimeWarning) and "encountered in" not in str(w.message)
            )
        )
        if notes:
            self.set_message(" ".join([*notes[:2], self.summary()]), "warning")
        else:
            self.set_message(self.summary())
        return True

    def picture(self) -> tuple[str, bytes]:
        """The figure as drawn now: ``(mime type, bytes)``; one without a figure overrides this."""
        return f"image/{self._image.format}", self._image.value

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.model!r})"
