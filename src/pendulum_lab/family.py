"""A family of models that differ in some parameters: one run over many parameter values.

A bifurcation diagram needs the same pendulum at hundreds of drive amplitudes.
Running them one by one would pay the run's fixed costs hundreds of times;
the compiled time loop instead accepts one row of parameters per ensemble
member (:class:`~pendulum_lab.integrators.HamiltonianField`). A
:class:`ModelFamily` is the model side of that: a
:class:`~pendulum_lab.PendulumModel` whose numbers are arrays, one entry per
member. Its NumPy functions broadcast those arrays against the states (the
lambdified functions take the parameters as arguments), so energies,
momenta and Jacobians of the whole family come out of one call, and
:func:`~pendulum_lab.simulate` and :func:`~pendulum_lab.simulate_segments`
run it like any model.

Examples
--------
>>> import numpy as np, pendulum_lab as pl
>>> family = pl.driven_pendulum().family(drive_amplitude=[1.0, 1.5])
>>> run = pl.simulate(family, [[0.2], [0.2]], [[0.0], [0.0]], t_end=1.0, dt=0.1, method="rk4")
>>> one = pl.simulate(family.member(1), [0.2], [0.0], t_end=1.0, dt=0.1, method="rk4")
>>> bool(np.array_equal(run.theta[:, 1], one.theta))
True
"""

from __future__ import annotations

import numpy as np

from . import _validation as check
from .mechanics import derive_chain
from .model import PendulumModel, _compiled

__all__ = ["FAMILY_PARAMETERS", "ModelFamily"]

#: The parameters a family can vary (one number per member).
FAMILY_PARAMETERS = ("damping", "drive_amplitude", "drive_frequency", "g")


class ModelFamily(PendulumModel):
    """Models differing only in the values of some parameters, one per entry of ``shape``.

    Build one with :meth:`PendulumModel.family`. Its parameter attributes
    (``damping``, ``drive_amplitude``, ``g``, ...) are arrays of ``shape``;
    the numeric functions of :class:`~pendulum_lab.PendulumModel` broadcast
    them against the state, whose batch shape must end in a shape that
    ``shape`` broadcasts to.

    Every member is validated as a model of its own (a negative damping is a
    ``ValueError`` naming ``damping``). If any member has damping or a drive,
    all members use the forced equations (where the forces vanish they add
    exactly zero).

    Attributes
    ----------
    base : PendulumModel
        The model whose parameters are varied.
    values : dict
        ``{name: ndarray of shape}``, the varied parameters.
    shape : tuple
    """

    def __init__(self, base: PendulumModel, values: dict):
        check.pendulum_model(base)
        if isinstance(base, ModelFamily):
            raise TypeError("`model` is already a ModelFamily; vary its `base` instead")
        if not values:
            raise ValueError(f"name at least one parameter to vary, among {FAMILY_PARAMETERS}")
        arrays = {}
        for name, value in values.items():
            if name not in FAMILY_PARAMETERS:
                raise ValueError(f"a family cannot vary {name!r}: the parameters it can vary "
                                 f"are {list(FAMILY_PARAMETERS)}")
            arrays[name] = check.real_array(name, value)
        try:
            shape = np.broadcast_shapes(*(a.shape for a in arrays.values()))
        except ValueError:
            shapes = {k: a.shape for k, a in arrays.items()}
            raise ValueError(f"the arrays of values must broadcast together, got "
                             f"{shapes}") from None
        arrays = {k: np.broadcast_to(a, shape) for k, a in arrays.items()}
        # Each member is a model of its own: the factories' checks apply to every value.
        members = [base.replace(**{k: float(a[index]) for k, a in arrays.items()})
                   for index in np.ndindex(shape)]
        forced = any(m.forced for m in members)
        rows = np.array([m._parameters(forced) for m in members], dtype=float)
        self._setup(base, arrays, forced, tuple(rows.T.reshape(-1, *shape)),
                    has_frequency=all(m.drive_frequency is not None for m in members))

    def _setup(self, base, values, forced, params, has_frequency):
        self.base, self.n, self.forced = base, base.n, forced
        self.values = values
        self.chain = derive_chain(self.n, forced)
        self._fn = _compiled(self.n, forced)
        self._params = params
        self._has_frequency = has_frequency

    def __reduce__(self):
        # Pickled as the base model and the values (for Dask workers, as PendulumModel is).
        return ModelFamily, (self.base, dict(self.values))

    def _mapped(self, transform) -> ModelFamily:
        """A family with ``transform`` (an array -> array function) applied to every array."""
        family = object.__new__(ModelFamily)
        family._setup(self.base, {k: transform(a) for k, a in self.values.items()}, self.forced,
                      tuple(transform(a) for a in self._params), self._has_frequency)
        return family

    # ---- parameters as arrays ------------------------------------------------
    @property
    def shape(self) -> tuple:
        return self._params[0].shape

    @property
    def masses(self) -> tuple:
        return self._params[: self.n]

    @property
    def lengths(self) -> tuple:
        return self._params[self.n : 2 * self.n]

    @property
    def g(self) -> np.ndarray:
        return self._params[2 * self.n]

    @property
    def damping(self) -> tuple:
        if not self.forced:
            return (np.zeros(self.shape),) * self.n
        return self._params[2 * self.n + 1 : 3 * self.n + 1]

    @property
    def drive_amplitude(self) -> np.ndarray:
        return self._params[3 * self.n + 1] if self.forced else np.zeros(self.shape)

    @property
    def drive_frequency(self) -> np.ndarray | None:
        if not self._has_frequency:
            return None
        if not self.forced:
            return np.broadcast_to(float(self.base.drive_frequency), self.shape)
        return self._params[3 * self.n + 2]

    # ---- members -------------------------------------------------------------
    def __len__(self) -> int:
        return int(np.prod(self.shape))

    def member(self, index) -> PendulumModel:
        """The member at ``index`` (an index into ``shape``) as a model of its own."""
        return self.base.replace(**{k: float(a[index]) for k, a in self.values.items()})

    def select(self, index) -> ModelFamily:
        """The members ``self.values[...][index]`` (NumPy indexing: a mask, a slice)."""
        return self._mapped(lambda a: a[index])

    def for_ensemble(self, batch_shape: tuple) -> ModelFamily:
        """The members broadcast to an ensemble of ``batch_shape`` and flattened.

        Raises
        ------
        ValueError
            If the family's shape does not broadcast to ``batch_shape``.
        """
        batch_shape = tuple(batch_shape)
        try:
            fits = np.broadcast_shapes(self.shape, batch_shape) == batch_shape
        except ValueError:
            fits = False
        if not fits:
            raise ValueError(
                f"the model family has shape {self.shape}, which must broadcast to the ensemble "
                f"shape of the initial state, {batch_shape} (`theta0` of shape (..., n))")
        return self._mapped(lambda a: np.broadcast_to(a, batch_shape).reshape(-1))

    def replace(self, **changes) -> ModelFamily:
        """The same family of a base model with some constructor arguments changed."""
        return ModelFamily(self.base.replace(**changes), self.values)

    def family(self, **values):
        raise TypeError("`model` is already a ModelFamily; vary its `base` instead")

    def __repr__(self) -> str:
        return f"ModelFamily({self.base!r}, varying {list(self.values)} over shape {self.shape})"
