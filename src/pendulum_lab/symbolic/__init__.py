"""The symbolic layer: the equations of motion derived with SymPy, before any number is bound.

``mechanics`` derives chains of n links (Lagrangian, mass matrix, forcing, Hamiltonian,
equilibria); ``systems`` any holonomic system from its points or its Lagrangian (a chain is
one case); ``discrete_mechanics`` the discrete Lagrangians of chains and conservative,
autonomous systems for the variational methods; ``errata`` checks the course report's formulas
against the derivation, symbol by symbol.
It knows pendulums and nothing of integrators.
"""

from .mechanics import Chain, derive_chain
from .systems import MechanicalSystem

__all__ = ["Chain", "MechanicalSystem", "derive_chain"]
