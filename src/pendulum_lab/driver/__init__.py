"""The driver layer: a model, a method and a time grid make a trajectory.

``simulate`` (runs and single steps), ``arguments`` (a run's arguments validated, and its
limits), ``integration`` (the run from validated arguments), ``trajectory`` (the result),
``loops`` (the compiled time loop of each method on each
field), ``segments`` (long runs handed out piece by piece), ``events`` (crossings located
between steps), ``henon`` (Henon's step onto a surface of section) and ``cluster`` (ensembles
on a Dask cluster).
"""

from .henon import henon_step
from .segments import SegmentedRun, simulate_segments
from .simulate import Trajectory, hamiltonian_field, simulate, step, step_count

__all__ = [
    "SegmentedRun",
    "Trajectory",
    "hamiltonian_field",
    "henon_step",
    "simulate",
    "simulate_segments",
    "step",
    "step_count",
]
