"""How a computed result draws itself without the computing layers importing the plotting layer.

Results of ``analysis``, ``chaos`` and ``geometric`` have a ``plot`` method, but those layers
lie below ``plotting`` and never import it. A result's ``plot`` names its plotting function, and
:func:`plot_with` finds it in :mod:`pendulum_lab.plotting` by that name when the result is
first drawn, the way pandas finds its plotting backend by name. This is the one place in the
package that reaches a higher layer, and it does so by name only.
"""

from __future__ import annotations

import importlib

__all__ = ["PLOTTING", "plot_with"]

#: The module whose functions draw the results.
PLOTTING = "pendulum_lab.plotting"


def plot_with(function: str, *args, **kwargs):
    """``pendulum_lab.plotting.<function>(*args, **kwargs)``: the Figure of a result."""
    return getattr(importlib.import_module(PLOTTING), function)(*args, **kwargs)
