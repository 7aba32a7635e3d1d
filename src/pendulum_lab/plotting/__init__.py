"""Every figure of the package (matplotlib, no pyplot state).

Every ``plot_*`` function draws into ``ax`` when given one and otherwise
makes a new :class:`matplotlib.figure.Figure`; it returns the Figure, so a
notebook cell ending with the call shows it (with ``%matplotlib inline``),
and a test can inspect the artists under any backend. By topic:

* :mod:`.figures`: new figures, the one axes helper, link subscripts, colours;
* :mod:`.trajectories`: energies, angles, phase space, the chain, the
  explorers' :data:`PANELS`;
* :mod:`.methods`: observed order, energy error growth, work-precision, the
  decay of energy under damping;
* :mod:`.chaos`: separation, Lyapunov exponents, Poincare sections, the
  flip-time map, the small-angle comparison;
* :mod:`.driven`: stroboscopic sections, bifurcation diagrams, basins of
  attraction of the driven pendulum.
"""

from .chaos import (
    plot_flip_map,
    plot_lyapunov,
    plot_lyapunov_spectrum,
    plot_parting,
    plot_section,
    plot_sections,
    plot_separation,
    plot_small_angle,
)
from .driven import plot_basins, plot_bifurcation, plot_stroboscopic
from .figures import (
    KINETIC,
    LIBRATION,
    POTENTIAL,
    ROTATION,
    SEPARATRIX,
    TOTAL,
    get_axes,
    link_label,
    new_figure,
    subscript,
    wrap_angle,
)
from .methods import (
    plot_energy_comparison,
    plot_energy_decay,
    plot_energy_error_growth,
    plot_order,
    plot_work_precision,
)
from .trajectories import (
    PANELS,
    chain_frame,
    draw_pendulum,
    plot_angles,
    plot_energy,
    plot_energy_error,
    plot_linear_vs_nonlinear,
    plot_link_projections,
    plot_period_vs_amplitude,
    plot_phase,
    plot_phase_portrait,
    plot_spectrum,
)

__all__ = [
    "KINETIC",
    "LIBRATION",
    "PANELS",
    "POTENTIAL",
    "ROTATION",
    "SEPARATRIX",
    "TOTAL",
    "chain_frame",
    "draw_pendulum",
    "get_axes",
    "link_label",
    "new_figure",
    "plot_angles",
    "plot_basins",
    "plot_bifurcation",
    "plot_energy",
    "plot_energy_comparison",
    "plot_energy_decay",
    "plot_energy_error",
    "plot_energy_error_growth",
    "plot_flip_map",
    "plot_linear_vs_nonlinear",
    "plot_link_projections",
    "plot_lyapunov",
    "plot_lyapunov_spectrum",
    "plot_order",
    "plot_parting",
    "plot_period_vs_amplitude",
    "plot_phase",
    "plot_phase_portrait",
    "plot_section",
    "plot_sections",
    "plot_separation",
    "plot_small_angle",
    "plot_spectrum",
    "plot_stroboscopic",
    "plot_work_precision",
    "subscript",
    "wrap_angle",
]
