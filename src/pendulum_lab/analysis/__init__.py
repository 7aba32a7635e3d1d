"""Measurements: integrators, oscillations and motion near equilibria.

Each function returns numbers a test or a notebook can assert on; none
prints or plots (figures are in :mod:`pendulum_lab.plotting`, tables in
:mod:`pendulum_lab.tables`). By topic:

* :mod:`.structure`: symplecticity defect and reversibility error of one step;
* :mod:`.accuracy`: observed order against a DOP853 reference, energy error
  over time;
* :mod:`.comparison`: work-precision, a DOP853 run, one table row per method,
  one initial state by several methods;
* :mod:`.oscillations`: exact and measured periods, spectra;
* :mod:`.linearization`: equilibria, normal modes, the linearised motion;
* :mod:`.damping`: area contraction and the decay of energy under damping,
  by method and step.
"""

from .accuracy import (
    HIGH_ORDER_DTS,
    ORDER_DTS,
    OrderResult,
    energy_growth,
    observed_order,
    order_steps,
    reference_solution,
    windowed_energy_error,
)
from .comparison import (
    ComparisonRow,
    EnergyComparison,
    ReferenceRun,
    WorkPrecision,
    compare_energy,
    compare_trajectory,
    dop853_run,
    dop853_work_precision,
    pendulum_name,
    work_precision,
)
from .damping import EnergyDecay, LinearDecay, energy_decay, linear_decay
from .linearization import (
    equilibrium_angles,
    find_equilibrium,
    linearized_solution,
    normal_mode_frequencies,
    rest_state_at_energy,
)
from .oscillations import dominant_frequencies, exact_period, oscillation_period, spectrum
from .structure import reversibility_error, step_jacobian, symplecticity_defect

__all__ = [
    "HIGH_ORDER_DTS",
    "ORDER_DTS",
    "ComparisonRow",
    "EnergyComparison",
    "EnergyDecay",
    "LinearDecay",
    "OrderResult",
    "ReferenceRun",
    "WorkPrecision",
    "compare_energy",
    "compare_trajectory",
    "dominant_frequencies",
    "dop853_run",
    "dop853_work_precision",
    "energy_decay",
    "energy_growth",
    "equilibrium_angles",
    "exact_period",
    "find_equilibrium",
    "linear_decay",
    "linearized_solution",
    "normal_mode_frequencies",
    "observed_order",
    "order_steps",
    "oscillation_period",
    "pendulum_name",
    "reference_solution",
    "rest_state_at_energy",
    "reversibility_error",
    "spectrum",
    "step_jacobian",
    "symplecticity_defect",
    "windowed_energy_error",
    "work_precision",
]
