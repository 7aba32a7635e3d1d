"""Why symplectic methods work: phase-space area, backward error analysis, adaptive steps.

Submodules
----------
``phase_space``
    Areas of blobs of initial states carried by the flow and by the methods,
    one-step Jacobians (and an explicit Runge-Kutta step's area factor in
    high precision), Poincare's integral invariant for chains, the invariant
    2-form written in ``(theta, omega)``.
``modified_equations``
    The symbolic engine: Taylor expansions of one step, modified vector
    fields, elementary Hamiltonians.
``modified_hamiltonians``
    :func:`modified_hamiltonian` and :func:`modified_equation` for the pendulums, the
    attempted Hamiltonian fit of any expanded method's modified equation.
``backward_error``
    The numerical checks of that theory: the modified Hamiltonian evaluated along orbits,
    RK4's energy drift from its modified equation (and the names above, importable here).
``long_time``
    Global error growth over long times.
``standard_map``
    Symplectic Euler on the pendulum as Chirikov's standard map; the median
    time of transport across the last invariant circle's remnant.
``continuation``
    The root of a variational step's implicit equation followed in the step
    size, through its fold.
``adaptive``
    A naive variable-step leapfrog, the reversible Sundman-transformed
    adaptive leapfrog and the Poincare-transformed midpoint rule (SciPy's
    adaptive solvers are :func:`pendulum_lab.analysis.scipy_run`), the step
    ratio of the time transformation, wandering energy levels.

Their figures are in :mod:`pendulum_lab.plotting` (``plotting.geometric``),
the variational integrators in the registry of
:mod:`pendulum_lab.integrators` (``VARIATIONAL_METHODS``).
"""

from .backward_error import (
    STEP_SIZE,
    ModifiedEnergy,
    modified_energy,
    modified_equation,
    modified_hamiltonian,
)

__all__ = [
    "STEP_SIZE",
    "ModifiedEnergy",
    "modified_energy",
    "modified_equation",
    "modified_hamiltonian",
]
