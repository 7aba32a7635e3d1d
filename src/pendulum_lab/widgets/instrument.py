"""The machinery of every instrument: controls, a status line, a figure rendered to PNG.

Rendering to an ``ipywidgets.Image`` works the same in JupyterLab, in a
notebook run by nbval and in a test without any front end, and needs no
interactive matplotlib backend.
"""

from __future__ import annotations

import base64
import warnings

import ipywidgets as widgets
import matplotlib as mpl
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from .._png import png_bytes
from ..integrators import ConvergenceError
from ..model import PendulumModel
from ..simulate import Trajectory
from .controls import column

__all__ = ["DPI", "ROW_HEIGHT", "WIDTH", "Instrument"]

DPI = 90
ROW_HEIGHT = 3.4  # inches per row of panels
WIDTH = 10.5  # inches


class Instrument:
    """Controls, a status line and a figure that :meth:`update` recomputes and redraws.

    Subclasses implement ``_compute()`` (build the model and the trajectory
    from the controls; raise ``ValueError`` for an invalid combination) and
    ``_draw(figure)``. Everything else -- observing the controls, catching
    errors, rendering the figure, the message -- lives here once.

    Attributes
    ----------
    controls : dict of str -> ipywidgets.ValueWidget
    model : PendulumModel
        The model of the latest successful update.
    trajectory : Trajectory
        The latest successful trajectory.
    figure : matplotlib.figure.Figure
        The figure shown (redrawn in place).
    widget : ipywidgets.VBox
        Controls, status line and figure; display this.
    """

    #: Exceptions that mean "this combination of inputs cannot be simulated".
    _EXPECTED = (ValueError, TypeError, ConvergenceError, FloatingPointError, OverflowError)

    def __init__(
        self,
        model: PendulumModel,
        controls: dict,
        columns: list[tuple[str, list[str]]],
        rows: int = 1,
    ):
        self.model = model
        self.controls = controls
        self.trajectory: Trajectory | None = None
        self._message = ""
        self.figure = Figure(figsize=(WIDTH, ROW_HEIGHT * rows), dpi=DPI)
        self._canvas = FigureCanvasAgg(self.figure)
        self._status = widgets.HTML(layout=widgets.Layout(min_height="1.6em"))
        self._image = widgets.Image(format="png")
        boxes = [column(title, [controls[k] for k in keys]) for title, keys in columns if keys]
        self.widget = widgets.VBox([widgets.HBox(boxes), self._status, self._image])
        for control in controls.values():
            control.observe(self._on_change, names="value")

    # ---- what subclasses provide ------------------------------------------------------------
    def _compute(self) -> tuple[PendulumModel, Trajectory]:
        raise NotImplementedError

    def _draw(self, figure: Figure) -> None:
        raise NotImplementedError

    def _summary(self) -> str:
        traj = self.trajectory
        err = float(np.max(np.abs(traj.energy_error)))
        return (
            f"{len(traj.t) - 1} steps of {traj.method.name} (dt = {traj.dt:g} s) in "
            f"{traj.wall_time:.2f} s; E(0) = {traj.energy[0]:.4f} J, "
            f"max |E − E(0)| = {err:.2e} J"
        )

    # ---- the shared machinery ----------------------------------------------------------------
    @property
    def message(self) -> str:
        """The text of the status line: a summary of the run, a warning or an error."""
        return self._message

    def _set_message(self, text: str, kind: str = "info") -> None:
        self._message = text
        colour = {"info": "#333", "warning": "#9a6700", "error": "#b00020"}[kind]
        escaped = text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
        self._status.value = f'<span style="color:{colour}">{escaped}</span>'

    def _on_change(self, change) -> None:
        self.update()

    def update(self) -> bool:
        """Recompute from the controls and redraw; return whether it succeeded.

        On an invalid combination the previous trajectory and figure stay and
        ``message`` says what is wrong. A run that blew up (non-finite state)
        is drawn up to where it stopped, with the warning in ``message``.
        """
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", RuntimeWarning)
                model, trajectory = self._compute()
        except self._EXPECTED as err:
            what = (
                "The solver did not converge"
                if isinstance(err, ConvergenceError)
                else ("Cannot run this combination")
            )
            self._set_message(f"{what}: {err}. The figure still shows the previous run.", "error")
            return False
        self.model, self.trajectory = model, trajectory
        try:
            self._redraw()
        except self._EXPECTED as err:
            self._set_message(f"Could not draw the figure: {err}", "error")
            return False
        self._render()
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
            self._set_message(" ".join([*notes[:2], self._summary()]), "warning")
        else:
            self._set_message(self._summary())
        return True

    def _redraw(self) -> None:
        """Draw the current trajectory into an emptied figure."""
        self.figure.clear()
        self._draw(self.figure)

    def _render(self) -> None:
        # FreeType's hinting of every glyph is a fifth of a redraw; unhinted
        # text looks the same at this size and resolution.
        with mpl.rc_context({"text.hinting": "none"}):
            self._canvas.draw()
        self._image.value = png_bytes(np.asarray(self._canvas.buffer_rgba()))

    def _repr_mimebundle_(self, **kwargs):
        # The widget for a live front end, and the figure as it is now for a page without a
        # kernel (which shows the picture instead of controls that would do nothing).
        bundle = self.widget._repr_mimebundle_(**kwargs)
        bundle[f"image/{self._image.format}"] = base64.b64encode(self._image.value).decode()
        return bundle

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.model!r})"
