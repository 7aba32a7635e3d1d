"""Interactive instruments: ipywidgets controls driving a simulation and a matplotlib figure.

Three explorers share one machinery (:class:`Instrument`): a dict of
controls, a status line, and a figure rendered to PNG into an
``ipywidgets.Image``. Every control has ``continuous_update=False``: the
simulation reruns when a slider is released, not while it moves.

* :func:`explore` -- initial state, step, duration, method and the physical
  parameters of any pendulum; choose the panels with ``plots=``.
* :func:`explore_equilibrium` -- start near one of the ``2**n`` equilibria
  and see the linearised and the nonlinear motion side by side.
* :func:`explore_energy` -- pick the total energy; the chain starts at rest
  on that energy level and each link's phase-space projection is drawn.

In a notebook cell, ``pl.widgets.explore(model)`` shows the explorer. Its
display carries the widget and a picture of the current figure
(``image/png``, or ``image/jpeg`` for the simulator): a live front end shows
the widget, a static page (the course website, a notebook viewer) the
picture. Each explorer keeps what it shows inspectable:
``controls`` (name -> widget), ``trajectory``, ``figure``, ``message`` and
``update()``, so it can be driven without a browser::

    ex = explore(pl.double_pendulum(), t_end=5.0)
    ex.controls["theta1"].value = 0.5      # reruns and redraws
    ex.trajectory.theta[0]                 # array([0.5, 2.5])

Invalid combinations (``t_end < dt``, too many steps, an implicit solver that
does not converge) leave the last trajectory and figure in place and put a
readable sentence in ``message`` instead of raising.

Layout: :mod:`.controls` (the sliders every instrument shares, also used by
:mod:`pendulum_lab.animation`), :mod:`.instrument` (the machinery),
:mod:`.explorers`, :mod:`.panels` (extra explorer panels). Browser-side
instruments go in ``live.py`` with their ES modules and CSS in ``static/``.
"""

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
from .panels import separation_panel

__all__ = [
    "DT_CHOICES",
    "MAX_STEPS",
    "EnergyExplorer",
    "EquilibriumExplorer",
    "Explorer",
    "Instrument",
    "explore",
    "explore_energy",
    "explore_equilibrium",
    "separation_panel",
]
