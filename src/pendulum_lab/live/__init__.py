"""Widgets drawn in the browser: the kernel computes, the browser draws.

The explorers of :mod:`pendulum_lab.widgets` render a matplotlib figure in the
kernel and send it as an image on every change, and the matplotlib simulator
of :mod:`pendulum_lab.animation` sends one image per frame. On a remote kernel
every image crosses the network. The widgets here send the computed motion
once, as binary float32 arrays, and small ES modules shipped in the package
(``static/``, no bundler, nothing from a CDN) draw it on a canvas:

* :func:`live_simulator`: the pendulum played at the display's frame rate,
  with energy bars, the energy-error trace and draggable bobs;
* :func:`section_explorer`: a Poincare section of the double pendulum; a
  click launches the orbit through that point on the chosen energy surface;
* :func:`portrait_explorer`: the simple pendulum's phase portrait; a click
  launches the orbit through that point.

Built on ``anywidget``, they run in JupyterLab, Notebook 7, VS Code and the
other front ends anywidget supports.
"""

from .clickable import (
    ClickablePlot,
    PortraitExplorer,
    SectionExplorer,
    portrait_explorer,
    section_explorer,
)
from .simulator import LiveSimulator, PendulumView, live_simulator, released_angles, run_messages

__all__ = [
    "ClickablePlot",
    "LiveSimulator",
    "PendulumView",
    "PortraitExplorer",
    "SectionExplorer",
    "live_simulator",
    "portrait_explorer",
    "released_angles",
    "run_messages",
    "section_explorer",
]
