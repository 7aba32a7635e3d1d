"""What every family of models shares (:class:`FamilyMembers`): members counted, picked,
selected and broadcast to a run's ensemble.

A bifurcation diagram needs the same pendulum at hundreds of drive amplitudes.
Running them one by one would pay the run's fixed costs hundreds of times;
the compiled time loop instead accepts one row of parameters per ensemble
member (:class:`~pendulum_lab.integrators.HamiltonianField`). A
:class:`~pendulum_lab.model.ModelFamily` is the model side of that: a
:class:`~pendulum_lab.PendulumModel` whose numbers are arrays, one entry per
member. Its NumPy functions broadcast those arrays against the states (the
lambdified functions take the parameters as arguments), so energies,
momenta and Jacobians of the whole family come out of one call, and
:func:`~pendulum_lab.simulate` and :func:`~pendulum_lab.simulate_segments`
run it like any model. A chain's family is
:class:`~pendulum_lab.model.ModelFamily`, a system's :class:`~pendulum_lab.model.SystemFamily`.
"""

from __future__ import annotations

import numpy as np

__all__ = ["FamilyMembers", "broadcast_values", "require_ensemble_fit"]


class FamilyMembers:
    """The members of a family (:class:`~pendulum_lab.model.ModelFamily`,
    :class:`~pendulum_lab.model.SystemFamily`): counted, picked, selected and broadcast to a
    run's ensemble. A family has ``base`` (the model varied), ``values`` (``{name: array}``)
    and ``_mapped(transform)``, the same family with ``transform`` applied to every array."""

    def __len__(self) -> int:
        return int(np.prod(self.shape))

    def member(self, index):
        """The member at ``index`` (an index into ``shape``) as a model of its own."""
        return self.base.replace(**{k: float(a[index]) for k, a in self.values.items()})

    def select(self, index):
        """The members ``self.values[...][index]`` (NumPy indexing: a mask, a slice)."""
        return self._mapped(lambda a: a[index])

    def for_ensemble(self, batch_shape: tuple):
        """The members broadcast to an ensemble of ``batch_shape`` and flattened.

        Raises
        ------
        ValueError
            If the family's shape does not broadcast to ``batch_shape``.
        """
        batch_shape = require_ensemble_fit(self.shape, batch_shape)
        return self._mapped(lambda a: np.broadcast_to(a, batch_shape).reshape(-1))


def broadcast_values(arrays: dict) -> tuple[tuple, dict]:
    """The common shape of a family's arrays of values and the arrays broadcast to it; a
    ``ValueError`` naming their shapes if they do not broadcast together."""
    try:
        shape = np.broadcast_shapes(*(a.shape for a in arrays.values()))
    except ValueError:
        shapes = {k: a.shape for k, a in arrays.items()}
        raise ValueError(f"the arrays of values must broadcast together, got {shapes}") from None
    return shape, {k: np.broadcast_to(a, shape) for k, a in arrays.items()}


def require_ensemble_fit(shape: tuple, batch_shape) -> tuple:
    """``batch_shape`` as a tuple if a family of ``shape`` broadcasts to it, else a
    ``ValueError`` (the members of a run are its initial states' batch)."""
    batch_shape = tuple(batch_shape)
    try:
        fits = np.broadcast_shapes(shape, batch_shape) == batch_shape
    except ValueError:
        fits = False
    if not fits:
        raise ValueError(
            f"the model family has shape {shape}, which must broadcast to the ensemble shape "
            f"of the initial state, {batch_shape} (`theta0` of shape (..., n))")
    return batch_shape
