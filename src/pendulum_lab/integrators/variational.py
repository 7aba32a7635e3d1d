"""Variational integrators: the discrete Legendre transforms of a discrete Lagrangian, solved.

References
----------
.. [MW] J. E. Marsden, M. West, "Discrete mechanics and variational integrators", Acta
   Numerica 10 (2001) 357-514, Sect. 1.3 and 2.1.
"""

from __future__ import annotations

import functools

import numpy as np

from .. import validation as check
from ..symbolic.discrete_mechanics import RULES
from .method import LAGRANGIAN_FIELD, Method
from .reference import variational
from .step import jit_step
from .stopping import MAX_SWEEPS, fixed_point_status

__all__ = ["VARIATIONAL_SOLVERS", "variational_method", "variational_step"]


@jit_step
def variational_step(update, impulse, t, q, p, h, params, separable, damping_rate):
    """A variational integrator [MW]: the discrete Legendre transforms, solved.

    ``p = -D_1 L_d(q, q1)``   (implicit in ``q1``)
    ``p1 = D_2 L_d(q, q1)``   (explicit; computed as ``p + D_2 L_d + D_1 L_d``)

    ``update(h, q, q1, params, p, out)`` writes the next iterate for ``q1``
    (a fixed-point or a Newton step, generated from the discrete Lagrangian);
    it is iterated from ``q1 = q`` until :func:`fixed_point_status` finds
    round-off (the first iterate is already a symplectic-Euler-like guess).
    ``impulse(h, q, q1, params, out)`` writes ``p1 - p``. ``t``,
    ``separable`` and ``damping_rate`` are not used: the discrete Lagrangian
    is autonomous and conservative. ``calls`` counts kernel evaluations.
    """
    q1, new = q.copy(), np.empty_like(q)
    smallest, status, sweeps = np.full(q.size, np.inf), 0, 0
    while status == 0 and sweeps < MAX_SWEEPS:
        sweeps += 1
        update(h, q, q1, params, p, new)
        status = fixed_point_status(new, q1, smallest)
        q1, new = new, q1
    if status != 1:
        return q, p, -1, sweeps
    kick = np.empty_like(p)
    impulse(h, q, q1, params, kick)
    return q1, p + kick, sweeps, sweeps + 1


#: How a variational step solves for ``q1``: the generated kernel it iterates.
VARIATIONAL_SOLVERS = {"fixed_point": "fixed_point_update", "newton": "newton_update"}


def variational_method(rule: str, solver: str, name: str | None = None) -> Method:
    """The variational integrator of the discrete Lagrangian ``rule``, solved by ``solver``.

    Parameters
    ----------
    rule : {"midpoint", "trapezoid"}
        The quadrature of the action (see :mod:`pendulum_lab.symbolic.discrete_mechanics`).
    solver : {"fixed_point", "newton"}
        How the step solves ``p = -D_1 L_d(q, q1)`` for ``q1``.
    name : str, optional
        By default ``"variational_<rule>"``.
    """
    rule = check.choice("rule", rule, RULES)
    solver = check.choice("solver", solver, VARIATIONAL_SOLVERS)
    quadrature = "M and L at the midpoint" if rule == "midpoint" else "L averaged over both ends"
    return Method(name or f"variational_{rule}", 2, True, True, "canonical",
                  f"variational integrator of the {rule} rule ({quadrature}): symmetric, "
                  "symplectic in (theta, p)", variational_step, applies_to=LAGRANGIAN_FIELD,
                  symmetric=True, rule=rule, solver=solver,
                  reference=functools.partial(variational, rule=rule,
                                              solver=VARIATIONAL_SOLVERS[solver]))
