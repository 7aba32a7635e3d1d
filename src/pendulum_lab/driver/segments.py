"""Long runs in segments: one driver for every computation that cannot keep all its steps.

A Poincare section, a flip-time map or a Lyapunov exponent needs every step of
a run, but not all of them at once: each piece of the run is examined and
dropped. :func:`simulate_segments` cuts a run into consecutive
:func:`~pendulum_lab.simulate` calls and hands them out one by one:

* each segment starts exactly where the previous one ended, in the method's
  own variables (``(theta, p)`` for the canonical methods), and at the right
  time: step ``s`` of the whole run starts at ``t0 + (s - 1) dt``, computed from
  ``s`` as one long call does, so the segmented run is the same run as one long
  call, to the last bit, a driven one included;
* the steps are counted once, by :func:`~pendulum_lab.step_count`, and one
  progress bar covers the whole run;
* between segments the caller may drop ensemble members it is done with
  (:meth:`SegmentedRun.keep`) or move the current state
  (:meth:`SegmentedRun.restart`, for renormalisations).

Examples
--------
>>> import numpy as np, pendulum_lab as pl
>>> run = pl.simulate_segments(pl.double_pendulum(), [[0.1, 0.2], [2.0, 2.5]],
...                            [[0.0, 0.0], [0.0, 0.0]], t_end=1.0, dt=0.01,
...                            method="rk4", segment_steps=40)
>>> [(round(float(seg.t[0]), 2), seg.theta.shape) for seg in run]
[(0.0, (41, 2, 2)), (0.4, (41, 2, 2)), (0.8, (21, 2, 2))]
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator

import numpy as np

from .. import validation as check
from ..codegen.compile_status import compile_seconds
from ..model import PendulumModel
from .arguments import check_memory, check_progress, memory_needed, progress_bar, run_arguments
from .integration import integrate
from .loops import compile_method
from .simulate import check_method_fits, hamiltonian_field, to_method_variables
from .trajectory import AngleReduction, Trajectory

__all__ = ["SegmentedRun", "default_segment_steps", "segment_length", "simulate_segments"]

# Largest number of floats one segment may hold (about 16 MB).
SEGMENT_FLOATS = 1 << 21
# Long runs are cut into at least this many segments so a progress bar moves.
PROGRESS_UPDATES = 50
# Fewer steps than this per segment would make the per-call overhead dominate.
MIN_SEGMENT = 1000


def segment_length(n_steps: int, floats_per_step: int, multiple: int = 1) -> int:
    """Steps per segment: few calls, bounded memory, a moving progress bar.

    Parameters
    ----------
    n_steps : int
        Steps of the whole run.
    floats_per_step : int
        Memory one step of a segment costs, in floats, over all members
        (what the segment keeps and what the caller builds from it).
    multiple : int
        The length is a multiple of this (``save_every``, a renormalisation
        interval).

    Returns
    -------
    int
        At most ``n_steps``.
    """
    length = max(math.ceil(n_steps / PROGRESS_UPDATES), MIN_SEGMENT)
    length = min(length, max(multiple, SEGMENT_FLOATS // max(1, floats_per_step)))
    length = multiple * max(1, math.ceil(length / multiple))
    return min(length, n_steps)


def default_segment_steps(n: int, members: int, n_steps: int, save_every: int) -> int:
    """Steps per segment of :func:`simulate_segments` for ``members`` states of ``n`` links.

    A caller that cuts a batch into chunks (:mod:`pendulum_lab.driver.cluster`) and
    wants every chunk to run in the segments of the whole batch passes this,
    computed for the whole batch, as ``segment_steps``, so that the chunks' segments end
    at the same steps.
    """
    # A kept state costs about four floats per link and member (angles and
    # momenta, while stepping and in the segment handed out).
    return segment_length(n_steps, 4 * n * members // save_every, save_every)


class SegmentedRun:
    """A run handed out in consecutive segments; build it with :func:`simulate_segments`.

    Iterating yields one :class:`~pendulum_lab.Trajectory` per segment, with
    the ensemble flattened: ``theta`` of shape ``(L+1, K, n)`` for the ``K``
    members still running (``members`` gives their flat indices in the
    initial ensemble). A segment's first state is the previous segment's last
    one. The run stops after a segment in which some state became
    non-finite (``completed`` is then False).

    Attributes
    ----------
    model : PendulumModel
        The model of the run; for a :class:`~pendulum_lab.model.ModelFamily`,
        one member per running member (flat), so that it fits the segments.
    method : Method
    dt, t_end : float
    t0 : float
        Start time of the run [s].
    n_steps : int
        Steps of the whole run.
    save_every, segment_steps : int
    batch_shape : tuple
        Ensemble shape of the initial state.
    members : ndarray of int, shape (K,)
        Flat indices of the members still running.
    done : int
        Steps taken so far.
    time : float
        Time of the current state [s]: ``t0 + done * dt``.
    completed : bool
    evaluations : int
        Vector-field evaluations so far, over all members.
    sweeps : float
        Implicit-solver iterations so far, summed over members.
    wall_time : float
        Seconds spent stepping.
    compile_time : float
        Seconds spent before stepping on compiling (or loading) the kernels and the time
        loop; 0 when they were ready (see ``Trajectory.compile_time``).
    compiled : bool
        Whether that time was spent compiling, not only loading (``Trajectory.compiled``).
    """

    def __init__(self, model, theta0, start, given_momenta: bool, *, method, dt: float,
                 t_end: float, n_steps: int, save_every: int, segment_steps: int, t0: float,
                 progress, label: str):
        self.method, self.dt, self.t0, self.t_end = method, dt, t0, t_end
        self.n_steps, self.save_every, self.segment_steps = n_steps, save_every, segment_steps
        self.batch_shape = theta0.shape[:-1]
        self.model = model.for_ensemble(self.batch_shape)
        self._theta = theta0.reshape(-1, model.n).copy()
        self._size = self._theta.shape[0]
        # Huge angles step reduced by whole turns; the segments show them continued from
        # the angles given (see AngleReduction).
        self._reduction = (AngleReduction.of(self._theta, stacklevel=4)
                           if model.periodic_coordinates else None)
        if self._reduction is not None:
            self._theta = self._reduction.reduced.copy()
        self._state = to_method_variables(self.model, method, self._theta,
                                           start.reshape(-1, model.n), given_momenta, t=t0)
        # What the method carries from step to step (its last stage slopes, the
        # rounding it compensates): kept across segments, so that the segmented
        # run is the one long run to the last bit.
        compiled_before = compile_seconds(), compile_seconds(compiled_only=True)
        field = hamiltonian_field(self.model)
        check_method_fits(model, method, field)
        self._compiled = compile_method(method, field, model.n)
        self.compile_time = compile_seconds() - compiled_before[0]
        self.compiled = compile_seconds(compiled_only=True) > compiled_before[1]
        self._memory = self._compiled.new_memory(self._theta.shape[0])
        self.members = np.arange(self._theta.shape[0])
        self.done = 0
        self.completed = True
        self.evaluations, self.sweeps, self.wall_time = 0, 0.0, 0.0
        self._progress, self._label = progress, label

    @property
    def time(self) -> float:
        """Time of the current state [s], where the next segment starts."""
        return self.t0 + self.done * self.dt

    def __iter__(self) -> Iterator[Trajectory]:
        n = self.model.n
        given = "p0" if self.method.variables == "canonical" else "omega0"
        bar = progress_bar(self.n_steps, self.n_steps * len(self.members), self._progress,
                           self._label)
        try:
            while self.done < self.n_steps and self.completed and len(self.members):
                steps = min(self.segment_steps, self.n_steps - self.done)
                segment = integrate(
                    self.model, self._compiled, self._theta.copy(), self._state.copy(),
                    (len(self.members),), t_end=steps * self.dt, dt=self.dt, n_steps=steps,
                    save_every=self.save_every, t0=self.t0, first_step=self.done,
                    progress=False, memory=self._memory,
                )
                self.done += steps
                self.completed = segment.completed
                self.evaluations += segment.evaluations
                self.sweeps += segment.mean_iterations * steps * len(self.members)
                self.wall_time += segment.wall_time
                # The method's own variables: a restart involves no conversion.
                self._theta = segment.theta[-1].reshape(-1, n)
                own = segment.p if given == "p0" else segment.omega
                self._state = own[-1].reshape(-1, n)
                if bar is not None:
                    bar.update(steps)
                if self._reduction is not None:
                    segment = self._reduction.select(self.members).restored(
                        segment, (len(self.members),))
                yield segment
        finally:
            if bar is not None:
                bar.close()

    def keep(self, mask) -> None:
        """Go on with the members where ``mask`` (shape ``(K,)``, over ``members``) is True."""
        mask = np.asarray(mask, dtype=bool)
        if mask.shape != self.members.shape:
            raise ValueError(f"`mask` must have shape {self.members.shape} (one entry per "
                             f"running member), got {mask.shape}")
        self.members = self.members[mask]
        self._theta, self._state = self._theta[mask], self._state[mask]
        self._memory = self._memory[mask]
        if self.model.shape:
            self.model = self.model.select(mask)
            # the same kernels and compiled loop, with the remaining members' parameters
            self._compiled = dataclasses.replace(self._compiled,
                                                 field=hamiltonian_field(self.model))

    def restart(self, theta, p, where=None) -> None:
        """Go on from ``(theta, p)`` instead of the current state.

        Parameters
        ----------
        theta, p : array_like, shape (k, n)
            The new angles and canonical momenta.
        where : array_like of bool, shape (K,), optional
            Which running members move (``k`` of them); all by default. The
            others go on from exactly where they are.
        """
        n = self.model.n
        where = (np.ones(len(self.members), dtype=bool) if where is None
                 else np.asarray(where, dtype=bool))
        if where.shape != self.members.shape:
            raise ValueError(f"`where` must have shape {self.members.shape} (one entry per "
                             f"running member), got {where.shape}")
        shape = (int(where.sum()), n)
        theta = check.state_array("theta", theta, n)
        p = check.state_array("p", p, n)
        if theta.shape != shape or p.shape != shape:
            raise ValueError(f"`theta` and `p` must have shape {shape}, got {theta.shape} and "
                             f"{p.shape}")
        # Copies: the current state is a view into the last segment handed out.
        self._theta, self._state = self._theta.copy(), self._state.copy()
        # the new angles are given as the segments show them
        moved = AngleReduction.of(theta) if self.model.periodic_coordinates else None
        if moved is not None or self._reduction is not None:
            none = np.zeros((self._size, n))
            current = self._reduction or AngleReduction(none, none, none.astype(bool))
            given, reduced, mask = (a.copy() for a in (current.given, current.reduced,
                                                       current.mask))
            moved = moved or AngleReduction(theta, theta, np.zeros(theta.shape, bool))
            rows = self.members[where]
            given[rows], reduced[rows], mask[rows] = moved.given, moved.reduced, moved.mask
            self._reduction = AngleReduction(given, reduced, mask)
            theta = moved.reduced
        self._theta[where] = theta
        moved = self.model.select(where) if self.model.shape else self.model
        self._state[where] = to_method_variables(moved, self.method, theta, p,
                                                  given_momenta=True)
        self._memory[where] = 0.0  # a moved member starts afresh


def simulate_segments(
    model: PendulumModel,
    theta0,
    omega0=None,
    *,
    t_end: float,
    dt: float = 0.01,
    method="glrk4",
    save_every: int = 1,
    p0=None,
    t0: float = 0.0,
    segment_steps: int | None = None,
    progress: bool | None = None,
    label: str | None = None,
    allow_long_run: bool = False,
) -> SegmentedRun:
    """A run of :func:`~pendulum_lab.simulate`, handed out in consecutive segments.

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0, p0 : array_like, shape (n,) or (..., n)
        The initial state, as for :func:`~pendulum_lab.simulate`.
    t_end, dt, method, save_every, t0
        As for :func:`~pendulum_lab.simulate`; the run takes
        ``step_count(t_end, dt)`` steps in all.
    segment_steps : int, optional
        Steps per segment, a multiple of ``save_every``; by default
        :func:`segment_length` of the states a segment keeps.
    progress : bool, optional
        One progress bar for the whole run; by default only for long runs.
    label : str, optional
        Text of the progress bar (default: the method's name).
    allow_long_run : bool
        Run even beyond the work budget (see :func:`~pendulum_lab.simulate`).

    Returns
    -------
    SegmentedRun
        Iterate over it for the segments.

    Raises
    ------
    ValueError
        For invalid arguments, and before any work for a run beyond the work
        budget without ``allow_long_run``, or one whose segments would not fit
        in the memory available (the message names ``segment_steps``).
    """
    method, theta0, start, (t_end, dt, n_steps), save_every, t0 = run_arguments(
        model, theta0, omega0, p0, t_end, dt, method, save_every, t0, allow_long_run
    )
    progress = check_progress(progress)
    if label is not None and not isinstance(label, str):
        raise TypeError(f"`label` must be a string (the progress bar's text), got "
                        f"{type(label).__name__}")
    members = theta0.size // model.n
    if segment_steps is None:
        segment_steps = default_segment_steps(model.n, members, n_steps, save_every)
    else:
        segment_steps = check.integer_at_least("segment_steps", segment_steps, 1)
        if segment_steps % save_every:
            raise ValueError(f"`segment_steps` must be a multiple of `save_every` "
                             f"({save_every}), got {segment_steps}")
    steps = min(segment_steps, n_steps)
    check_memory(memory_needed(model.n, method, members, steps // save_every + 1),
                 f"a segment of {steps:.3g} steps keeping {steps // save_every + 1:.3g} states of "
                 + ("1 trajectory" if members == 1 else f"{members} trajectories"),
                 "Choose a smaller `segment_steps` (or leave it out: by default a segment "
                 "holds about 16 MB) or a larger `save_every`.")
    return SegmentedRun(model, theta0, start, p0 is not None, method=method, dt=dt,
                        t_end=t_end, n_steps=n_steps, save_every=save_every,
                        segment_steps=segment_steps, t0=t0, progress=progress,
                        label=label or method.name)
