"""pendulum_lab: Hamiltonian mechanics and geometric integration, through pendulums.

Layers, each using only the ones before it:

``mechanics`` (SymPy derivation) -> ``model`` (numeric: lambdified, or looped over
the links of a long chain in ``long_chains``) ->
``integrators`` (one-step maps of Hamiltonian vector fields) -> ``simulate``
(and ``segments``, the same runs handed out piece by piece) -> ``events``,
``analysis``, ``chaos``, ``plotting``, ``widgets``, ``animation``, ``report``;
``cluster`` runs ensembles on a Dask cluster.

Quick start
-----------
>>> import pendulum_lab as pl
>>> dp = pl.double_pendulum()
>>> traj = pl.simulate(dp, [2.0, 2.5], [0.0, 0.0], t_end=1.0, dt=0.01, method="glrk4")
>>> bool(abs(traj.energy[-1] - traj.energy[0]) < 1e-5)
True
"""

from .family import ModelFamily
from .henon import henon_step
from .integrators import (
    CONFORMAL_METHODS,
    METHODS,
    VARIATIONAL_METHODS,
    ConvergenceError,
    Method,
    get_method,
)
from .mechanics import Chain, derive_chain
from .model import PendulumModel, double_pendulum, driven_pendulum, n_pendulum, simple_pendulum
from .segments import SegmentedRun, simulate_segments
from .simulate import Trajectory, hamiltonian_field, simulate, step, step_count

__version__ = "0.1.0"

# Submodules that pull in heavy dependencies (ipywidgets, matplotlib) load on
# first use, so `pl.widgets.explore(...)` works without slowing `import pendulum_lab`.
_LAZY_SUBMODULES = {"analysis", "animation", "chaos", "cluster", "codegen", "discrete_mechanics",
                    "events", "geometric", "long_chains", "mechanics", "plotting", "report",
                    "source", "tables", "timing", "warmup", "widgets"}


def __getattr__(name):
    if name == "modified_hamiltonian":  # backward error analysis (notebook 14), loaded on use
        from .geometric import modified_hamiltonian

        return modified_hamiltonian
    if name == "warm_up":  # reaches every layer's kernels, loaded on use
        from .warmup import warm_up

        return warm_up
    if name in _LAZY_SUBMODULES:
        import importlib

        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

__all__ = [
    "CONFORMAL_METHODS",
    "METHODS",
    "Chain",
    "ConvergenceError",
    "Method",
    "ModelFamily",
    "PendulumModel",
    "SegmentedRun",
    "Trajectory",
    "VARIATIONAL_METHODS",
    "derive_chain",
    "double_pendulum",
    "driven_pendulum",
    "get_method",
    "hamiltonian_field",
    "henon_step",
    "modified_hamiltonian",
    "n_pendulum",
    "simple_pendulum",
    "simulate",
    "simulate_segments",
    "step",
    "step_count",
    "warm_up",
]
