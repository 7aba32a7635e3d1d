"""What the integrators see of a system: a compiled vector field; and how an implicit step fails."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["ConvergenceError", "HamiltonianField"]


class ConvergenceError(RuntimeError):
    """An implicit step's equations did not converge."""


@dataclass(frozen=True)
class HamiltonianField:
    """A vector field as the integrators see it: Hamiltonian, possibly with damping.

    Attributes
    ----------
    hamilton, acceleration : compiled kernels (see :mod:`pendulum_lab.codegen.signatures`)
    params : ndarray, shape (P,) or (K, P)
        Parameters passed through to the kernels; with ``K`` rows, row ``k``
        belongs to ensemble member ``k`` (one run over many parameter values).
    separable : bool
        True when ``dH/dq`` does not depend on ``p`` nor ``dH/dp`` on ``q``
        (damping aside); the symplectic methods are then explicit.
    damping_rate : float or ndarray, shape (K,)
        ``gamma`` when the non-Hamiltonian part of ``dp/dt`` is exactly
        ``-gamma p`` (a conformal Hamiltonian field [MP]); ``0`` for a
        Hamiltonian field; NaN for damping of any other form.
    discrete : callable or None
        ``discrete(rule)`` returns the compiled discrete Legendre transforms
        of the field's discrete Lagrangian by ``rule`` (a namespace with
        ``fixed_point_update``, ``newton_update``, ``impulse``); None
        when the field has no Lagrangian of its own (damping or a drive).
    stages : compiled kernel or None
        ``hamilton`` at several states at once (see
        :mod:`pendulum_lab.codegen.signatures`), for the implicit Runge-Kutta
        methods; without it they cannot integrate the field.
    name : str
        What the field describes, for people ("the double pendulum"): messages about
        compiling a method for it say so.
    """

    hamilton: object
    acceleration: object
    params: np.ndarray
    separable: bool
    damping_rate: float | np.ndarray = 0.0
    discrete: object = field(default=None, repr=False)
    stages: object = field(default=None, repr=False)
    name: str = "a vector field"
