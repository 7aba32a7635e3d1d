"""Backward error analysis of the course's integrators on the pendulum.

A symplectic method is, up to terms smaller than any power of ``h``, the
exact flow of a *modified Hamiltonian* ``H~ = H + h H_1 + h^2 H_2 + ...``
[HLW, Chapter IX]. :func:`modified_hamiltonian` derives it symbolically (see
:mod:`pendulum_lab.geometric.modified_equations` for the method: matching
Taylor expansions, not the BCH formula, which applies only to splittings of a
separable ``H``). The rest of this module checks the theory with numbers:

* :func:`modified_energy_orders`: along a computed orbit the error of
  ``H~`` truncated after ``h^k`` shrinks like the first omitted power of ``h``;
* :func:`hamiltonian_fit`: the attempt, term by term, to write a method's
  modified vector field (for a general ``H``) as a Hamiltonian one; it fails
  for explicit Euler and RK4, and succeeds for the symplectic methods;
* :func:`first_dissipative_term`, :func:`mean_energy_rate` and
  :func:`energy_drift`: RK4 has a modified *equation* but no modified
  Hamiltonian; its first term with non-zero divergence predicts its energy
  drift rate;
* the growth of the global error over long times is measured in
  :mod:`pendulum_lab.geometric.long_time`.

The derivations are in :mod:`.modified_hamiltonians`, the numbers of the modified
Hamiltonian in :mod:`.modified_energy`, RK4's drift in :mod:`.energy_drift`; every name is
importable from here, as the notebooks use it.

References
----------
.. [HLW] E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*,
   2nd ed., Springer 2006: Chapter IX (backward error analysis), Sect. X.3
   (linear error growth of symplectic methods on integrable systems).
"""

from __future__ import annotations

from .energy_drift import (
    DissipativeTerm,
    EnergyDrift,
    energy_drift,
    first_dissipative_term,
    mean_energy_rate,
)
from .modified_energy import (
    ModifiedEnergy,
    ModifiedEnergyOrders,
    hamiltonian_function,
    modified_energy,
    modified_energy_orders,
)
from .modified_hamiltonians import (
    STEP_SIZE,
    HamiltonianFit,
    generic_modified_hamiltonian,
    hamiltonian_fit,
    modified_equation,
    modified_hamiltonian,
)

__all__ = [
    "STEP_SIZE",
    "DissipativeTerm",
    "EnergyDrift",
    "HamiltonianFit",
    "ModifiedEnergy",
    "ModifiedEnergyOrders",
    "energy_drift",
    "first_dissipative_term",
    "generic_modified_hamiltonian",
    "hamiltonian_fit",
    "hamiltonian_function",
    "mean_energy_rate",
    "modified_energy",
    "modified_energy_orders",
    "modified_equation",
    "modified_hamiltonian",
]
