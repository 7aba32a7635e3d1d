"""Measurements: integrators, oscillations and motion near equilibria.

Each function returns numbers a test or a notebook can assert on; none
prints or plots (figures are in :mod:`pendulum_lab.plotting`, tables in
:mod:`pendulum_lab.tables`). By topic:

* :mod:`.structure`: symplecticity defect, reversibility error and linear
  stability (amplification of small swings) of one step;
* :mod:`.accuracy`: observed order against a DOP853 reference, energy error
  over time;
* :mod:`.comparison`: work-precision (energy and global error), a DOP853 run,
  the comparison table of every method on every problem, one initial state by
  several methods;
* :mod:`.iteration`: how fast an implicit step's stage iteration contracts;
* :mod:`.oscillations`: exact and measured periods, spectra;
* :mod:`.linearization`: equilibria, normal modes, the linearised motion.

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
    ComparisonRow,
    EnergyComparison,
    MethodComparison,
    ReferenceRun,
    WorkPrecision,
    compare_energy,
    compare_methods,
    compare_trajectory,
    dop853_run,
    dop853_work_precision,
    pendulum_name,
    work_precision,
)
from .iteration import StageIteration, stage_contraction
from .linearization import (
    equilibrium_angles,
    find_equilibrium,
    linearized_solution,
    normal_mode_frequencies,
    normal_modes,
    rest_state_at_energy,
)
from .oscillations import dominant_frequencies, exact_period, oscillation_period, spectrum
from .structure import (
    amplification,
    reversibility_error,
    stability_limit,
    step_jacobian,
    symplecticity_defect,
)

__all__ = [
    "HIGH_ORDER_DTS",
    "ORDER_DTS",
    "ComparisonRow",
    "EnergyComparison",
    "MethodComparison",
    "OrderResult",
    "ReferenceRun",
    "StageIteration",
    "WorkPrecision",
    "amplification",
    "compare_energy",
    "compare_methods",
    "compare_trajectory",
    "dominant_frequencies",
    "dop853_run",
    "dop853_work_precision",
    "energy_growth",
    "equilibrium_angles",
    "exact_period",
    "find_equilibrium",
    "global_error",
    "linearized_solution",
    "normal_mode_frequencies",
    "normal_modes",
    "observed_order",
    "order_steps",
    "oscillation_period",
    "pendulum_name",
    "reference_solution",
    "rest_state_at_energy",
    "reversibility_error",
    "spectrum",
    "stability_limit",
    "stage_contraction",
    "step_jacobian",
    "symplecticity_defect",
    "windowed_energy_error",
    "work_precision",
]
