"""pendulum_lab: Hamiltonian mechanics and geometric integration, through pendulums.

The package is layered; each layer uses only the ones before it:

``symbolic`` (SymPy derivations) -> ``codegen`` (compiled kernels) -> ``model`` (numeric
models) -> ``integrators`` (one-step maps of vector fields) -> ``driver`` (simulate, the time
loop, segments, events) -> ``analysis``, ``chaos``, ``geometric`` -> ``plotting``, ``widgets``,
``animation`` -> ``app`` (the command line, the report, warm-up). Below them all,
``validation`` checks arguments and ``exercises`` checks the notebooks' exercises.

Quick start
-----------
>>> import pendulum_lab as pl
>>> dp = pl.double_pendulum()
>>> traj = pl.simulate(dp, [2.0, 2.5], [0.0, 0.0], t_end=1.0, dt=0.01, method="glrk4")
>>> bool(abs(traj.energy[-1] - traj.energy[0]) < 1e-5)
True
"""

from .driver import (
    SegmentedRun,
    Trajectory,
    hamiltonian_field,
    henon_step,
    simulate,
    simulate_segments,
    step,
    step_count,
)
from .integrators import (
    CONFORMAL_METHODS,
    METHODS,
    VARIATIONAL_METHODS,
    ConvergenceError,
    Method,
    get_method,
)
from .integrators.source import method_source
from .model import (
    ModelFamily,
    PendulumModel,
    SystemModel,
    cart_pendulum,
    double_pendulum,
    driven_pendulum,
    elastic_pendulum,
    foucault_pendulum,
    kapitza_pendulum,
    mechanical_system,
    n_pendulum,
    simple_pendulum,
    spherical_pendulum,
)
from .symbolic import Chain, MechanicalSystem, derive_chain
from .version import __version__

# Layers loaded on first use (ipywidgets and matplotlib are slow to import), and the names the
# modules had before the package was layered, each kept as an alias of its new place.
_SUBMODULES = {
    "analysis": "analysis",
    "animation": "animation",
    "app": "app",
    "chaos": "chaos",
    "cli": "app.cli",
    "cluster": "driver.cluster",
    "codegen": "codegen",
    "discrete_mechanics": "symbolic.discrete_mechanics",
    "driver": "driver",
    "errata": "symbolic.errata",
    "events": "driver.events",
    "exercises": "exercises",
    "family": "model.pendulum",
    "geometric": "geometric",
    "henon": "driver.henon",
    "integrators": "integrators",
    "long_chains": "codegen.long_chains",
    "loops": "driver.loops",
    "mechanics": "symbolic.mechanics",
    "model": "model",
    "plotting": "plotting",
    "report": "app.report",
    "segments": "driver.segments",
    "source": "integrators.source",
    "symbolic": "symbolic",
    "tableau": "integrators.tableau",
    "tables": "app.tables",
    "timing": "app.timing",
    "validation": "validation",
    "warmup": "app.warmup",
    "widgets": "widgets",
}


def __getattr__(name):
    if name == "modified_hamiltonian":  # backward error analysis (notebook 14), loaded on use
        from .geometric import modified_hamiltonian

        return modified_hamiltonian
    if name == "warm_up":  # reaches every layer's kernels, loaded on use
        from .app.warmup import warm_up

        return warm_up
    if name in _SUBMODULES:
        import importlib

        return importlib.import_module(f".{_SUBMODULES[name]}", __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "__version__",
    "CONFORMAL_METHODS",
    "METHODS",
    "Chain",
    "ConvergenceError",
    "MechanicalSystem",
    "Method",
    "ModelFamily",
    "PendulumModel",
    "SegmentedRun",
    "SystemModel",
    "Trajectory",
    "VARIATIONAL_METHODS",
    "cart_pendulum",
    "derive_chain",
    "double_pendulum",
    "driven_pendulum",
    "elastic_pendulum",
    "foucault_pendulum",
    "get_method",
    "hamiltonian_field",
    "henon_step",
    "kapitza_pendulum",
    "mechanical_system",
    "method_source",
    "modified_hamiltonian",
    "n_pendulum",
    "simple_pendulum",
    "simulate",
    "simulate_segments",
    "spherical_pendulum",
    "step",
    "step_count",
    "warm_up",
]
