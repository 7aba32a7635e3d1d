"""Interactive instruments: controls driving a simulation, drawn in the kernel or in the browser.

The explorers share one machinery (:class:`Instrument`): a dict of
controls, a status line, and a figure rendered to PNG into an
``ipywidgets.Image``. Every control has ``continuous_update=False``: the
simulation reruns when a slider is released, not while it moves.

* :func:`explore` -- initial state, step, duration, method and the physical
  parameters of any pendulum; choose the panels with ``plots=``.
* :func:`explore_equilibrium` -- start near one of the ``2**n`` equilibria
  and see the linearised and the nonlinear motion side by side.
* :func:`explore_energy` -- pick the total energy; the chain starts at rest
  on that energy level and each link's phase-space projection is drawn.

Drawn in the browser (``anywidget``; the kernel computes and sends the
numbers once as binary buffers, small ES modules shipped in ``static/``
draw them; nothing is fetched from a CDN):

* :func:`live_simulator` -- the course's simulator: the pendulum played at
  the display's frame rate, energy bars and the energy-error trace, drag a
  bob to restart from there, keyboard controls, and a description of the
  state shown for screen readers.
* :func:`section_explorer` -- a Poincare section of the double pendulum; a
  click launches the orbit through that point on the chosen energy surface.
* :func:`portrait_explorer` -- the simple pendulum's phase portrait; a click
  launches the orbit through that point.

In a notebook cell, ``pl.widgets.explore(model)`` shows the explorer. Its
display carries the widget and a picture of what it shows (``image/png``, or
``image/jpeg`` for the simulator): a live front end shows the widget, a
static page (the course website, a notebook viewer) the picture. Each
explorer keeps what it shows inspectable:
``controls`` (name -> widget), ``trajectory``, ``figure``, ``message`` and
``update()``, so it can be driven without a browser::

    ex = explore(pl.double_pendulum(), t_end=5.0)
    ex.controls["theta1"].value = 0.5      # reruns and redraws
    ex.trajectory.theta[0]                 # array([0.5, 2.5])

Invalid combinations (``t_end < dt``, too many steps, an implicit solver that
does not converge) leave the last trajectory and figure in place and put a
readable sentence in ``message`` instead of raising.

Every instrument runs exactly the model it is given, damping and drive
included, and offers only the methods :func:`pendulum_lab.simulate` accepts
for it; where the model does not conserve energy, what is shown as
``E - E(0)`` is called an energy change, not an error. The explorers built on
energy levels (:func:`explore_energy`, :func:`section_explorer`) and on the
conservative chain's linearisation (:func:`explore_equilibrium`) refuse a
damped or driven model, saying why.

Each instrument's status line (:class:`~pendulum_lab.widgets.status.StatusLine`)
is an ARIA live region, says what a wait of more than half a second is
doing (:meth:`Instrument.working`) while the figure is marked stale, and has
a "Copy as code" button: the exact ``pl.simulate(...)`` call behind the
picture (``code()``), which reproduces it number for number. In a notebook
reopened without its kernel, each instrument's output shows a one-line hint
to run its cell again instead of JupyterLab's "Error displaying widget".

Layout: :mod:`.controls` (the sliders every instrument shares, also used by
:mod:`pendulum_lab.animation`), :mod:`.calls` (the run behind a picture, as a
value and as code), :mod:`.status` (the status line), :mod:`.instrument`
(the machinery), :mod:`.explorers`, :mod:`.panels` (extra explorer panels);
browser-drawn: :mod:`.channel` (binary messages to the browser), :mod:`.live`
(the live simulator), :mod:`.clickable` (click to launch), ``static/`` (their
ES modules and stylesheet).
"""

from .calls import SimulateCall
from .clickable import (
    PortraitExplorer,
    SectionExplorer,
    portrait_explorer,
    section_explorer,
    section_reach,
)
from .controls import DT_CHOICES, MAX_STEPS
from .explorers import (
    EnergyExplorer,
    EquilibriumExplorer,
    Explorer,
    explore,
    explore_energy,
    explore_equilibrium,
)
from .instrument import Instrument
from .live import LiveSimulator, live_simulator
from .panels import separation_panel
from .status import StatusLine

__all__ = [
    "DT_CHOICES",
    "MAX_STEPS",
    "EnergyExplorer",
    "EquilibriumExplorer",
    "Explorer",
    "Instrument",
    "LiveSimulator",
    "PortraitExplorer",
    "SectionExplorer",
    "SimulateCall",
    "StatusLine",
    "explore",
    "explore_energy",
    "explore_equilibrium",
    "live_simulator",
    "portrait_explorer",
    "section_explorer",
    "section_reach",
    "separation_panel",
]
