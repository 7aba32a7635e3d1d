"""Measurements: integrators, oscillations and motion near equilibria.

Each function returns numbers a test or a notebook can assert on; none
prints or plots (figures are in :mod:`pendulum_lab.plotting`, tables in
:mod:`pendulum_lab.app.tables`). By topic:

* :mod:`.structure`: Jacobians by finite differences, the symplectic-form defect of
  a matrix and of one step, the reversibility error of one step, linear stability
  (amplification of small swings);
* :mod:`.accuracy`: observed order against a DOP853 reference, energy error
  over time, the global error at a time;
* :mod:`.comparison`: work-precision (energy and global error), SciPy's adaptive
  solvers (:func:`scipy_run`), the comparison table of every method on every
  problem, one initial state by several methods;
* :mod:`.iteration`: how fast an implicit step's stage iteration contracts;
* :mod:`.oscillations`: exact and measured periods, spectra;
* :mod:`.linearization`: equilibria, normal modes, the linearised motion;
* :mod:`.damping`: area contraction and the decay of energy under damping,
  by method and step.

Modified Hamiltonians (backward error analysis) live in
:mod:`pendulum_lab.geometric`.
"""

from .accuracy import (
    HIGH_ORDER_DTS,
    ORDER_DTS,
    OrderResult,
    energy_growth,
    global_error,
    observed_order,
    order_steps,
    reference_solution,
    windowed_energy_error,
)
from .comparison import (
    SCIPY_METHODS,
    AdaptiveRun,
    ComparisonRow,
    EnergyComparison,
    MethodComparison,
    WorkPrecision,
    compare_energy,
    compare_methods,
    compare_trajectory,
    dop853_work_precision,
    pendulum_name,
    scipy_run,
    work_precision,
)
from .damping import EnergyDecay, LinearDecay, energy_decay, linear_decay
from .iteration import StageIteration, stage_contraction
from .linearization import (
    equilibrium_angles,
    find_equilibrium,
    linearized_solution,
    normal_mode_frequencies,
    normal_modes,
    rest_coordinates,
    rest_state_at_energy,
)
from .oscillations import dominant_frequencies, exact_period, oscillation_period, spectrum
from .structure import (
    amplification,
    finite_difference_jacobian,
    reversibility_error,
    stability_limit,
    step_jacobian,
    symplectic_form_defect,
    symplecticity_defect,
)

__all__ = [
    "HIGH_ORDER_DTS",
    "ORDER_DTS",
    "SCIPY_METHODS",
    "AdaptiveRun",
    "ComparisonRow",
    "EnergyComparison",
    "EnergyDecay",
    "LinearDecay",
    "MethodComparison",
    "OrderResult",
    "StageIteration",
    "WorkPrecision",
    "amplification",
    "compare_energy",
    "compare_methods",
    "compare_trajectory",
    "dominant_frequencies",
    "dop853_work_precision",
    "energy_decay",
    "energy_growth",
    "equilibrium_angles",
    "exact_period",
    "find_equilibrium",
    "finite_difference_jacobian",
    "global_error",
    "linear_decay",
    "linearized_solution",
    "normal_mode_frequencies",
    "normal_modes",
    "observed_order",
    "order_steps",
    "oscillation_period",
    "pendulum_name",
    "reference_solution",
    "rest_coordinates",
    "rest_state_at_energy",
    "reversibility_error",
    "scipy_run",
    "spectrum",
    "stability_limit",
    "stage_contraction",
    "step_jacobian",
    "symplectic_form_defect",
    "symplecticity_defect",
    "windowed_energy_error",
    "work_precision",
]
