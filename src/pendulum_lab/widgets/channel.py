"""The kernel end of the browser-drawn widgets: synced state, binary messages, replay.

Two kinds of data reach the browser. Small state (speed, a message, the
picture's axes) travels as synced traitlets. Bulk data (a trajectory, the
points of an orbit) travels as binary buffers: NumPy arrays cast to float32
and sent with ``Widget.send`` as raw bytes, never as JSON lists of numbers.

A custom message reaches only the views that exist when it is sent, so a
:class:`ReplayWidget` keeps the messages that make up what it currently shows
(its *log*) and sends them again whenever a view announces itself with
``{"type": "ready"}`` (a cell displayed again, a notebook reopened while the
kernel runs). Views ignore what they already have.

Messages from the browser are dicts with a ``"type"``; :meth:`ReplayWidget.handle`
registers the function called with each message of one type. Messages of
other types are ignored.
"""

from __future__ import annotations

from pathlib import Path

import anywidget
import numpy as np
import traitlets

from ..model.pendulum import PendulumModel

__all__ = ["BROWSER_SETTINGS", "STATIC", "ReplayWidget", "figure_message", "float32_buffer"]

#: The ES modules and the stylesheet shipped with the package.
STATIC = Path(__file__).resolve().parent / "static"
#: The key, in the widget view's data, of what a page without a kernel needs to run the
#: simulator in the browser (:func:`pendulum_lab.widgets.browser.browser_config`, or
#: ``{"refusal": sentence}``). Inside the widget view, not a mime type of its own: the site's
#: notebook reader skips (and warns about) mime types it does not know, and the widget
#: managers read only ``model_id`` from the view.
BROWSER_SETTINGS = "pendulum_lab_browser"


def float32_buffer(values) -> memoryview:
    """``values`` as the bytes of a C-ordered float32 array (a ``Float32Array`` in the browser).

    Examples
    --------
    >>> import numpy as np
    >>> buffer = float32_buffer([[1.0, 2.0], [3.0, 4.0]])
    >>> buffer.nbytes, np.frombuffer(buffer, dtype="<f4").tolist()
    (16, [1.0, 2.0, 3.0, 4.0])
    """
    array = np.ascontiguousarray(values, dtype="<f4")
    return memoryview(array).cast("B")


class ReplayWidget(anywidget.AnyWidget):
    """An anywidget that replays its current messages to each new view.

    Attributes
    ----------
    message : str
        A sentence shown inside the widget (an error or a hint); empty for none.
    message_kind : {"info", "error"}
    """

    _css = STATIC / "live.css"

    message = traitlets.Unicode("").tag(sync=True)
    message_kind = traitlets.Unicode("info").tag(sync=True)

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._log: list[tuple[dict, list]] = []
        self._handlers = {"ready": self._replay}
        #: Bytes of binary buffers sent so far (JSON headers not counted).
        self.sent_bytes = 0
        self.on_msg(self._dispatch)

    # ---- kernel -> browser ------------------------------------------------------------------
    def _publish(self, messages: list[tuple[dict, list]]) -> None:
        """Replace the log by ``messages`` (``(content, buffers)`` pairs) and send them."""
        self._log = list(messages)
        for content, buffers in self._log:
            self._send_counted(content, buffers)

    def _send_counted(self, content: dict, buffers: list) -> None:
        self.sent_bytes += sum(memoryview(b).nbytes for b in buffers)
        self.send(content, buffers)

    def show_message(self, text: str, kind: str = "info") -> None:
        """Show ``text`` inside the widget (``kind``: ``"info"`` or ``"error"``)."""
        if kind not in ("info", "error"):
            raise ValueError(f"`kind` must be 'info' or 'error', got {kind!r}")
        with self.hold_sync():
            self.message_kind = kind
            self.message = text

    # ---- browser -> kernel ------------------------------------------------------------------
    def handle(self, kind: str, callback) -> None:
        """Call ``callback(content)`` for each message ``{"type": kind, ...}`` from the browser."""
        self._handlers[kind] = callback

    def _dispatch(self, _widget, content, buffers) -> None:
        if isinstance(content, dict) and content.get("type") in self._handlers:
            self._handlers[content["type"]](content)

    def _replay(self, content=None) -> None:
        for message, buffers in self._log:
            self._send_counted(message, buffers)


def figure_message(model: PendulumModel, points=None) -> dict:
    """What the browser draws the model with: ``kind`` (``"chain"``, whose points the browser
    computes from the angles and ``lengths``, or ``"points"``, sent), the
    :class:`~pendulum_lab.model.Drawing`'s ``masses``, ``rods``, ``springs`` and ``movable``
    (None or the sentence refusing a drag), ``uses_origin``, ``trailed`` (the point whose
    path is the trail: the last massive one), ``dimensions`` (2, or 3 for points in space,
    whose positions come as ``(x, y, z)``, ``z`` up) and ``reach`` [m] (a chain's length, else
    the largest coordinate of ``points``, shape ``(states, points, dimensions)``, in size)."""
    drawing = model.drawing
    masses = [float(m) for m in drawing.masses]
    reach = drawing.reach
    if reach is None:
        finite = np.abs(points[np.isfinite(points)])
        reach = float(finite.max()) if finite.size and finite.max() > 0 else 1.0
    return {
        "kind": "chain" if model.is_chain else "points",
        "masses": masses,
        "rods": [list(pair) for pair in drawing.rods],
        "springs": [list(pair) for pair in drawing.springs],
        "movable": list(drawing.movable),
        "uses_origin": drawing.uses_origin,
        "trailed": max(k for k, m in enumerate(masses) if m > 0),
        "dimensions": int(getattr(model, "dimensions", 2)),
        "reach": float(reach),
    }
