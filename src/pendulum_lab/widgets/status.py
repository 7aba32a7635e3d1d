"""The status line of an instrument: what happened, what is being done, and "copy as code".

:class:`StatusLine` is a small anywidget (``static/status.js``) under an
instrument's controls. It shows one sentence (``text``) of a ``kind``:

* ``"info"``, ``"warning"``, ``"error"``: the result of the latest update;
* ``"busy"``: work under way (:meth:`StatusLine.working`). The browser keeps
  the previous sentence for :data:`BUSY_DELAY` seconds and then shows the busy
  one with the seconds elapsed, so that a quick update does not flicker and
  any longer wait says what it is doing. While busy, the instrument's box
  carries the CSS class :data:`STALE_CLASS`, which fades its figure after
  the same delay: the picture shown is not the one the controls describe.

The sentence is an ARIA live region (``role="status"``): a screen reader
announces each new one. Beside it, a "Copy as code" button puts ``code``
(the exact :func:`pendulum_lab.simulate` call behind the picture) on the
clipboard; where the browser refuses the clipboard, the code is shown
selected in a text box to copy by hand. The button is hidden while ``code``
is empty.
"""

from __future__ import annotations

from contextlib import contextmanager

import anywidget
import traitlets

from .channel import STATIC

__all__ = ["BUSY_DELAY", "KINDS", "STALE_CLASS", "StatusLine"]

#: Seconds of work after which the browser shows a busy sentence and marks the figure stale.
BUSY_DELAY = 0.5
#: The kinds of sentence a status line shows.
KINDS = ("info", "warning", "error", "busy")
#: CSS class of an instrument's box while its figure does not show what the controls say.
STALE_CLASS = "plab-stale"


class StatusLine(anywidget.AnyWidget):
    """One sentence about an instrument's run, and a "Copy as code" button.

    Attributes
    ----------
    text : str
        The sentence.
    kind : {"info", "warning", "error", "busy"}
    code : str
        Python code the button copies; empty hides the button.
    busy_delay : float
        Seconds the browser waits before it shows a busy sentence.
    """

    _esm = STATIC / "status.js"
    _css = STATIC / "live.css"

    text = traitlets.Unicode("").tag(sync=True)
    kind = traitlets.Unicode("info").tag(sync=True)
    code = traitlets.Unicode("").tag(sync=True)
    busy_delay = traitlets.Float(BUSY_DELAY).tag(sync=True)

    @traitlets.validate("kind")
    def _valid_kind(self, proposal):
        if proposal["value"] not in KINDS:
            raise traitlets.TraitError(f"`kind` must be one of {list(KINDS)}, got "
                                       f"{proposal['value']!r}")
        return proposal["value"]

    def show(self, text: str, kind: str = "info") -> None:
        """Show ``text``; ``kind`` one of :data:`KINDS` except ``"busy"`` (see :meth:`working`)."""
        if kind not in KINDS or kind == "busy":
            raise ValueError(
                f"`kind` must be one of {[k for k in KINDS if k != 'busy']}, got {kind!r} "
                "(a busy sentence is shown by `working`)"
            )
        with self.hold_sync():
            self.kind = kind
            self.text = text

    @contextmanager
    def working(self, text: str, box=None):
        """Say ``text`` while the block runs (after :data:`BUSY_DELAY` s in the browser).

        ``box`` (an ipywidgets ``Box``, the instrument's) carries
        :data:`STALE_CLASS` meanwhile. The sentence before comes back
        afterwards unless the block showed another. The kernel sends the
        sentence before the work starts, so it reaches the browser while the
        kernel is still busy::

            with status.working("compiling glrk4 for the double pendulum, once per machine…"):
                ...  # the work

        """
        before = (self.text, self.kind)
        with self.hold_sync():
            self.kind = "busy"
            self.text = text
        if box is not None:
            box.add_class(STALE_CLASS)
        try:
            yield self
        finally:
            if box is not None:
                box.remove_class(STALE_CLASS)
            if self.kind == "busy":
                self.show(*before)
