"""Every figure of the package (matplotlib, no pyplot state).

Every ``plot_*`` function draws into ``ax`` when given one and otherwise
makes a new :class:`matplotlib.figure.Figure`; it returns the Figure, so a
notebook cell ending with the call shows it (with ``%matplotlib inline``),
and a test can inspect the artists under any backend. By topic:

* :mod:`.figures`: new figures, the axes helpers, axis labels and link
  subscripts, colours;
* :mod:`.trajectories`: energies, angles, phase space, the configuration, the
  explorers' :data:`PANELS`;
* :mod:`.drawing`: a model's points, rods and springs as line data (every
  drawing of a configuration, chains and systems alike);
* :mod:`.methods`: observed order, energy error growth, work-precision,
  amplification of small swings (linear stability), the contraction of an
  implicit method's stage iteration, the decay of energy under damping;
* :mod:`.chaos`: separation, Lyapunov exponents, Poincare sections, the
  flip-time map, the small-angle comparison;
* :mod:`.geometric`: geometric integration (notebooks 13-16): carried loops
  and their areas, level sets of modified Hamiltonians, energy drift and error
  growth, the standard map, adaptive steps;
* :mod:`.driven`: stroboscopic sections, bifurcation diagrams, basins of
  attraction of the driven pendulum, periodic orbits followed through a parameter.
"""

from .chaos import (
    plot_flip_map,
    plot_landing_errors,
    plot_lyapunov,
    plot_lyapunov_energy,
    plot_lyapunov_spectrum,
    plot_parting,
    plot_section,
    plot_sections,
    plot_separation,
    plot_small_angle,
)
from .drawing import drawing_frame
from .driven import plot_basins, plot_bifurcation, plot_orbit_branches, plot_stroboscopic
from .figures import (
    KINETIC,
    LIBRATION,
    POTENTIAL,
    QUANTITIES,
    ROTATION,
    SEPARATRIX,
    TOTAL,
    axis_label,
    get_axes,
    get_axes_grid,
    link_label,
    new_figure,
    subscript,
    wrap_angle,
)
from .geometric import (
    plot_adaptive_energy,
    plot_area_ratio,
    plot_carried_loops,
    plot_crossing_times,
    plot_energy_drift,
    plot_error_growth,
    plot_level_sets,
    plot_modified_energy_orders,
    plot_orbit_on_level_sets,
    plot_projected_areas,
    plot_root_branch,
    plot_standard_map,
    plot_step_sizes,
    plot_transport_threshold,
)
from .methods import (
    plot_amplification,
    plot_energy_comparison,
    plot_energy_decay,
    plot_energy_error_growth,
    plot_order,
    plot_stage_contraction,
    plot_work_precision,
)
from .trajectories import (
    PANELS,
    draw_pendulum,
    plot_angles,
    plot_energy,
    plot_energy_error,
    plot_linear_vs_nonlinear,
    plot_link_projections,
    plot_modified_level_sets,
    plot_normal_modes,
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
    "QUANTITIES",
    "ROTATION",
    "SEPARATRIX",
    "TOTAL",
    "axis_label",
    "draw_pendulum",
    "drawing_frame",
    "get_axes",
    "get_axes_grid",
    "link_label",
    "new_figure",
    "plot_adaptive_energy",
    "plot_amplification",
    "plot_angles",
    "plot_area_ratio",
    "plot_basins",
    "plot_bifurcation",
    "plot_carried_loops",
    "plot_crossing_times",
    "plot_energy",
    "plot_energy_comparison",
    "plot_energy_decay",
    "plot_energy_drift",
    "plot_energy_error",
    "plot_energy_error_growth",
    "plot_error_growth",
    "plot_flip_map",
    "plot_landing_errors",
    "plot_level_sets",
    "plot_linear_vs_nonlinear",
    "plot_link_projections",
    "plot_lyapunov",
    "plot_lyapunov_energy",
    "plot_lyapunov_spectrum",
    "plot_modified_energy_orders",
    "plot_modified_level_sets",
    "plot_normal_modes",
    "plot_orbit_branches",
    "plot_orbit_on_level_sets",
    "plot_order",
    "plot_parting",
    "plot_period_vs_amplitude",
    "plot_phase",
    "plot_phase_portrait",
    "plot_projected_areas",
    "plot_root_branch",
    "plot_section",
    "plot_sections",
    "plot_separation",
    "plot_small_angle",
    "plot_spectrum",
    "plot_stage_contraction",
    "plot_standard_map",
    "plot_step_sizes",
    "plot_stroboscopic",
    "plot_transport_threshold",
    "plot_work_precision",
    "subscript",
    "wrap_angle",
]
