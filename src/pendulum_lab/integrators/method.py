"""A method as data: its name, order, structure and compiled step."""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

from . import reference as references
from .composition import Composition
from .reference import runge_kutta_reference
from .runge_kutta import tableau_step
from .symplectic import composition_step
from .tableau import ButcherTableau

__all__ = ["ANY_FIELD", "CONFORMAL_FIELD", "HAMILTONIAN_FIELD", "LAGRANGIAN_FIELD", "Method"]

#: Values of :attr:`Method.applies_to`.
ANY_FIELD, HAMILTONIAN_FIELD, CONFORMAL_FIELD = "any", "hamiltonian", "conformal"
LAGRANGIAN_FIELD = "lagrangian"


@dataclass(frozen=True)
class Method:
    """An integrator: its properties and its compiled one-step map.

    Build a Runge-Kutta method with :meth:`from_tableau` and a composition method with
    :meth:`from_composition`: each derives every property from its data. The tests take
    their lists of methods from these properties (``tests/integrators/test_integrators.py``).

    Attributes
    ----------
    name : str
    order : int
        Classical order of accuracy.
    symplectic : bool
        Symplectic for every Hamiltonian (in the variables it works in); for
        the conformal methods: conformal symplectic on damped fields.
    implicit : bool
        Solves equations at each step (for non-separable ``H``).
    variables : {"canonical", "velocity"}
        ``(q, p)`` or, for the course report's versions, ``(q, v)``.
    summary : str
        One line for tables and dropdowns.
    kernel : Step
        The step function (see the module docstring); ``kernel.py_func`` is
        its Python source, ``kernel.memory(n)`` the floats it keeps per
        trajectory; :mod:`pendulum_lab.driver.loops` compiles it with each field.
    applies_to : {"any", "hamiltonian", "conformal", "lagrangian"}
        The fields it integrates: any; Hamiltonian ones (``damping_rate``
        zero); conformal ones (``damping_rate`` finite, zero included);
        those with a discrete Lagrangian (no damping, no drive, no time in L:
        an unforced chain, the elastic or the cart pendulum).
    symmetric : bool
        ``Phi_{-h}(Phi_h(y)) = y``: time-reversible, with even order.
    tableau : ButcherTableau or None
        The Butcher tableau of a Runge-Kutta method.
    composition : Composition or None
        The weights and base method of a composition method.
    rule, solver : str or None
        For a variational method (:func:`variational_method`): the discrete
        Lagrangian's quadrature rule and how its step solves for ``q1``.
    reference : callable or None
        The same step in plain NumPy, written as its formula reads
        (:mod:`pendulum_lab.integrators.reference`): what the notebooks show
        (:func:`~pendulum_lab.integrators.source.method_source`) and what the
        compiled ``kernel`` is tested against, step by step. Never used in a run.
    """

    name: str
    order: int
    symplectic: bool
    implicit: bool
    variables: str
    summary: str
    kernel: object = field(repr=False)
    applies_to: str = ANY_FIELD
    symmetric: bool = False
    tableau: ButcherTableau | None = field(default=None, repr=False)
    composition: Composition | None = field(default=None, repr=False)
    rule: str | None = None
    solver: str | None = None
    reference: object = field(default=None, repr=False)

    @classmethod
    def from_tableau(cls, name: str, tableau: ButcherTableau, summary: str,
                     reference=None) -> Method:
        """The Runge-Kutta method of ``tableau`` on ``(q, p)``; nothing typed but the name.

        Order, implicitness and symplecticity come from the tableau
        (:class:`~pendulum_lab.integrators.tableau.ButcherTableau`), the step function from
        :func:`tableau_step`, the reference step from
        :func:`~pendulum_lab.integrators.reference.runge_kutta_reference` unless
        ``reference`` gives the method's formula written out (explicit Euler's). A
        Runge-Kutta method integrates any field.
        """
        return cls(name, tableau.order, tableau.symplectic_condition().holds,
                   not tableau.explicit, "canonical", summary, tableau_step(tableau, name),
                   symmetric=tableau.symmetric, tableau=tableau,
                   reference=runge_kutta_reference(tableau) if reference is None else reference)

    @classmethod
    def from_composition(cls, name: str, composition: Composition, summary: str) -> Method:
        """The composition method of ``composition`` on ``(q, p)``; nothing typed but the name.

        Order and symmetry are the composition's (checked when it was made); it is symplectic
        because its base methods are, implicit as they are (for a non-separable ``H``), and
        for Hamiltonian fields as they are. The step is
        :func:`~pendulum_lab.integrators.symplectic.composition_step`, the reference step
        :func:`~pendulum_lab.integrators.reference.composition`.
        """
        if not isinstance(composition, Composition):
            raise TypeError(f"`composition` must be a Composition, got "
                            f"{type(composition).__name__}")
        return cls(name, composition.order, True, True, "canonical", summary,
                   composition_step(composition, name), applies_to=HAMILTONIAN_FIELD,
                   symmetric=composition.symmetric, composition=composition,
                   reference=functools.partial(references.composition,
                                               composition=composition))

    def __str__(self) -> str:
        return self.name
