"""Comparing methods: work-precision, SciPy's adaptive solvers, one table row per method.

Each function returns numbers a test or a notebook can assert on; the
figures of these results are in :mod:`pendulum_lab.plotting` and their
Markdown table in :mod:`pendulum_lab.app.tables`. :func:`compare_methods` is the
study behind the comparison table of notebook 09 and of ``pendulum-lab
report``: both call it.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from .. import validation as check
from ..driver.simulate import Trajectory, simulate, velocity_state
from ..integrators import METHODS, ConvergenceError, get_method
from ..model import require_model
from ..model.pendulum import PendulumModel
from ..plot_dispatch import plot_with
from .accuracy import (
    energy_growth,
    final_state_at,
    global_error,
    observed_order,
    order_steps,
    reference_solution,
    scipy_solution,
)
from .structure import reversibility_error, symplecticity_defect

__all__ = [
    "SCIPY_METHODS",
    "AdaptiveRun",
    "ComparisonRow",
    "EnergyComparison",
    "MethodComparison",
    "WorkPrecision",
    "compare_energy",
    "compare_methods",
    "compare_trajectory",
    "dop853_work_precision",
    "errors_shrink",
    "pendulum_name",
    "scipy_run",
    "work_precision",
]

#: The adaptive solvers of ``scipy.integrate.solve_ivp`` the course compares with.
SCIPY_METHODS = ("RK45", "DOP853")


@dataclass(frozen=True)
class WorkPrecision:
    """Cost and accuracy of one run, by two measures.

    Attributes
    ----------
    method : str
    setting : float
        The step ``dt`` for a fixed-step method, the tolerance ``rtol`` for DOP853.
    energy_error : float
        ``max |H - H(0)|`` over the saved states of the run.
    state_error : float
        The global error at the final time ``T``: max-norm distance in
        ``(theta, omega)`` from a reference solution (:func:`global_error`).
        Unlike the energy error, it does not favour the methods that keep
        the energy near its initial value.
    wall_time : float
        Seconds spent integrating.
    evaluations : int
        Vector-field evaluations (both of Hamilton's equations, or the
        acceleration, at one state count as one).
    completed : bool
    """

    method: str
    setting: float
    energy_error: float
    state_error: float
    wall_time: float
    evaluations: int
    completed: bool


def work_precision(model: PendulumModel, theta0, omega0=None, *, t_end: float, dts,
                   method="glrk4", p0=None, repeats: int = 1,
                   reference=None) -> list[WorkPrecision]:
    """Energy error and global error against cost for a fixed-step method at several steps.

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0, p0 : array_like, shape (n,)
        The initial state (give ``omega0`` or ``p0``).
    t_end : float
        Length of each run; each step of ``dts`` must divide it into whole steps.
    dts : sequence of float
        Step sizes, each ``> 0``.
    method : str or Method
    repeats : int
        Run each step size this many times and keep the shortest wall time
        (runs of a few milliseconds are noisy), ``>= 1``.
    reference : (ndarray, ndarray), optional
        ``(theta, omega)`` at ``t_end``; by default :func:`reference_solution`.
        Pass one to share it between methods.

    Returns
    -------
    list of WorkPrecision
        One per step size, in the order given.
    """
    method = get_method(method)
    repeats = check.integer_at_least("repeats", repeats, 1)
    if reference is None:
        reference = reference_solution(model, theta0, omega0, t_end=t_end, p0=p0)
    points = []
    for dt in dts:
        runs = [simulate(model, theta0, omega0, t_end=t_end, dt=dt, method=method, p0=p0,
                         progress=False) for _ in range(repeats)]
        traj = runs[0]
        error = (global_error(*final_state_at(traj, t_end), reference) if traj.completed
                 else np.inf)
        points.append(WorkPrecision(method.name, float(dt),
                                    float(np.max(np.abs(traj.energy_error))), error,
                                    min(run.wall_time for run in runs), traj.evaluations,
                                    traj.completed))
    return points


@dataclass(frozen=True)
class AdaptiveRun:
    """A run with variable steps: SciPy's adaptive solvers, or an adaptive geometric method.

    Attributes
    ----------
    label : str
        The method and its setting, for legends and tables.
    t : ndarray, shape (N+1,)
        The accepted step times [s].
    theta, p : ndarray, shape (N+1, n)
        Angles and canonical momenta.
    energy_error : ndarray, shape (N+1,)
        ``E(t) - E(0)``.
    steps : int
        Accepted steps.
    evaluations : int
        Right-hand-side evaluations (SciPy: ``nfev``, one acceleration each)
        or one-step calls (adaptive leapfrogs, counting rejected attempts
        and error estimates).
    wall_time : float
        Seconds spent integrating.
    """

    label: str
    t: np.ndarray
    theta: np.ndarray
    p: np.ndarray
    energy_error: np.ndarray
    steps: int
    evaluations: int
    wall_time: float

    @property
    def step_sizes(self) -> np.ndarray:
        """``t[k+1] - t[k]``, shape (N,)."""
        return np.diff(self.t)

    @property
    def drift(self) -> float:
        """Slope [J/s] of a least-squares line through the energy error."""
        return float(np.polyfit(self.t, self.energy_error, 1)[0])

    def largest_error(self, start: float = 0.0, stop: float = np.inf) -> float:
        """``max |E - E(0)|`` over ``start <= t <= stop``."""
        inside = (self.t >= start) & (self.t <= stop)
        return float(np.max(np.abs(self.energy_error[inside])))


def scipy_run(model: PendulumModel, theta0, omega0=None, *, t_end: float,
              method: str = "DOP853", rtol: float = 1e-10, p0=None) -> AdaptiveRun:
    """Integrate with ``scipy.integrate.solve_ivp``, keeping every accepted step.

    These are the general-purpose adaptive methods a student would otherwise
    reach for (DOP853: eighth order; RK45: Dormand-Prince 5(4)); neither is
    symplectic nor fixed-step. They step ``(theta, omega)`` with the model's
    accelerations (one evaluation per right-hand side, as for the velocity
    methods); ``atol`` equals ``rtol``.

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0, p0 : array_like, shape (n,)
        The initial state (give ``omega0`` or ``p0``).
    t_end : float
        ``> 0``.
    method : {"RK45", "DOP853"}
    rtol : float
        Relative (and absolute) tolerance, in ``[1e-14, 1e-2]``.

    Returns
    -------
    AdaptiveRun
        Labelled ``"<method>, rtol <rtol>"``.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> run = scipy_run(pl.simple_pendulum(), [1.0], [0.0], t_end=10.0, method="RK45", rtol=1e-6)
    >>> run.label, bool(run.largest_error() < 1e-3)
    ('RK45, rtol 1e-06', True)
    """
    theta0, omega0 = velocity_state(model, theta0, omega0, p0, single=True)
    n = model.n
    t_end = check.positive_number("t_end", t_end)
    method = check.choice("method", method, SCIPY_METHODS)
    rtol = check.number_in("rtol", rtol, 1e-14, 1e-2)
    start = time.perf_counter()
    sol = scipy_solution(model, theta0, omega0, t_end, rtol, method)
    wall = time.perf_counter() - start
    theta, omega = sol.y[:n].T, sol.y[n:].T
    energy = model.energy(theta, omega, sol.t)
    return AdaptiveRun(f"{method}, rtol {rtol:g}", sol.t, theta,
                       model.momenta(theta, omega, sol.t), energy - energy[0], len(sol.t) - 1,
                       int(sol.nfev), wall)


def dop853_work_precision(model: PendulumModel, theta0, omega0=None, *, t_end: float,
                          rtols, p0=None, repeats: int = 1,
                          reference=None) -> list[WorkPrecision]:
    """:func:`work_precision` for DOP853 at several tolerances ``rtols``."""
    repeats = check.integer_at_least("repeats", repeats, 1)
    if reference is None:
        reference = reference_solution(model, theta0, omega0, t_end=t_end, p0=p0)
    points = []
    for rtol in rtols:
        runs = [scipy_run(model, theta0, omega0, t_end=t_end, rtol=rtol, p0=p0)
                for _ in range(repeats)]
        run = runs[0]
        omega_end = model.velocities(run.theta[-1], run.p[-1], run.t[-1])
        points.append(WorkPrecision("DOP853", float(rtol),
                                    float(np.max(np.abs(run.energy_error))),
                                    global_error(run.theta[-1], omega_end, reference),
                                    min(r.wall_time for r in runs), run.evaluations, True))
    return points


@dataclass(frozen=True)
class ComparisonRow:
    """One method on one problem: the numbers of the comparison table.

    Attributes
    ----------
    pendulum : str
        ``"simple"``, ``"double"`` or ``"n=3"`` and so on.
    method : str
    variables : str
        ``"canonical"`` or ``"velocity"``.
    order : int
        The method's classical order.
    observed_order : float
        Fitted slope of the global error at ``order_t_end`` against ``dt``; ``nan`` when the
        errors do not shrink with the step (they are at round-off, or at the reference's
        accuracy: there is no order to measure, and a slope would be noise).
    energy_first, energy_last : float
        Largest ``|E - E0|`` in the first and last tenth of the run
        (:func:`energy_growth`).
    max_relative_energy_error : float
        Largest ``|E - E0| / |E0|`` over the run.
    symplecticity_defect, reversibility_error : float
        At the run's initial state, step ``check_dt``.
    t_end, dt : float
    wall_time : float
    evaluations : int
    mean_iterations : float
    completed : bool
    """

    pendulum: str
    method: str
    variables: str
    order: int
    observed_order: float
    energy_first: float
    energy_last: float
    max_relative_energy_error: float
    symplecticity_defect: float
    reversibility_error: float
    t_end: float
    dt: float
    wall_time: float
    evaluations: int
    mean_iterations: float
    completed: bool


def errors_shrink(errors) -> bool:
    """Whether an order fit's errors (largest step first) fell by at least a factor of 2.

    Over the steps of :func:`~pendulum_lab.analysis.accuracy.order_steps` (a ratio of 2.5 or
    more) a method of order one already divides its error by 2.5; errors that fall less are at
    a floor (round-off, or the reference's own error), not in the asymptotic regime.

    Examples
    --------
    >>> errors_shrink([1e-4, 1e-5, 1e-6]), errors_shrink([1.3e-13, 1.5e-13, 1.4e-13])
    (True, False)
    """
    errors = np.asarray(errors, dtype=float)
    return bool(errors.size >= 2 and errors[-1] <= 0.5 * errors[0])


def pendulum_name(model: PendulumModel) -> str:
    """``"simple"``, ``"double"``, or ``"n=3"`` and so on; a system's own name otherwise."""
    if not model.is_chain:
        return model.name
    return {1: "simple", 2: "double"}.get(model.n, f"n={model.n}")


def compare_trajectory(model: PendulumModel, traj: Trajectory, *, order_t_end: float = 1.0,
                       order_dts=None, reference=None,
                       check_dt: float = 0.1) -> ComparisonRow:
    """Measure the method that made ``traj``: energy behaviour, order, structure.

    The energy columns come from ``traj``. The observed order is fitted by
    :func:`observed_order` from ``traj``'s initial state over ``order_t_end``;
    the symplecticity defect and reversibility error are those of one step of
    size ``check_dt`` from the same initial state.

    Parameters
    ----------
    model : PendulumModel
        The model ``traj`` was computed with.
    traj : Trajectory
        A single trajectory (not an ensemble).
    order_t_end : float
    order_dts : sequence of float, optional
        Each must divide ``order_t_end`` into whole steps; by default
        :func:`order_steps` of the method.
    reference : tuple of ndarray, optional
        ``(theta, omega)`` at ``order_t_end`` from ``traj``'s initial state;
        computed by :func:`reference_solution` if not given. Pass it to reuse
        one reference for several methods.
    check_dt : float
        Step of the symplecticity and reversibility checks, ``> 0``. At the
        default 0.1 s the symplectic methods show defects of about 1e-10
        (finite-difference noise) and RK4, the least non-symplectic method
        here, 1e-7 on the simple pendulum: a wide gap. At smaller steps
        RK4's defect, which shrinks like ``h**6``, comes close to the noise.

    Returns
    -------
    ComparisonRow
    """
    if traj.theta.ndim != 2:
        raise ValueError("`traj` must be a single trajectory (angles of shape (N+1, n)), "
                         f"got angles of shape {traj.theta.shape}")
    if traj.theta.shape[1] != model.n:
        raise ValueError(f"`traj` has {traj.theta.shape[1]} coordinate(s) but `model` has "
                         f"{model.n}")
    check_dt = check.positive_number("check_dt", check_dt)
    theta0, omega0, p0, t0 = traj.theta[0], traj.omega[0], traj.p[0], float(traj.t[0])
    if order_dts is None:
        order_dts = order_steps(traj.method)
    order = observed_order(model, theta0, omega0, t_end=order_t_end, dts=order_dts,
                           method=traj.method, reference=reference, t0=t0)
    first, last = energy_growth(traj)
    return ComparisonRow(
        pendulum=pendulum_name(model),
        method=traj.method.name,
        variables=traj.method.variables,
        order=traj.method.order,
        observed_order=order.slope if errors_shrink(order.errors) else math.nan,
        energy_first=first,
        energy_last=last,
        max_relative_energy_error=float(np.max(np.abs(traj.relative_energy_error))),
        symplecticity_defect=symplecticity_defect(model, theta0, p0=p0, dt=check_dt,
                                                  method=traj.method, t0=t0),
        reversibility_error=reversibility_error(model, theta0, p0=p0, dt=check_dt,
                                                method=traj.method, t0=t0),
        t_end=float(traj.t[-1]),
        dt=traj.dt,
        wall_time=traj.wall_time,
        evaluations=traj.evaluations,
        mean_iterations=traj.mean_iterations,
        completed=traj.completed,
    )


@dataclass(frozen=True)
class MethodComparison:
    """Every method on every problem: see :func:`compare_methods`.

    Attributes
    ----------
    rows : list of ComparisonRow
        One per run that completed its implicit equations, in run order.
    trajectories : dict
        ``{pendulum name: [Trajectory, ...]}``, the runs behind ``rows``.
    failures : list of (str, str, str)
        ``(pendulum, method, message)`` for runs whose implicit equations did
        not converge.
    """

    rows: list
    trajectories: dict
    failures: list


def compare_methods(problems, methods=tuple(METHODS), *, t_end: float = 200.0,
                    dt: float = 0.01, progress: bool = False) -> MethodComparison:
    """Run each method on each problem and measure it: the comparison table.

    For each problem, one DOP853 reference at ``t = 1 s`` serves the order
    fits of all methods; each method runs ``t_end`` at step ``dt`` and
    :func:`compare_trajectory` turns the run into a :class:`ComparisonRow`.
    Notebook 09 and ``pendulum-lab report`` both build their table with this
    function.

    Parameters
    ----------
    problems : sequence of (PendulumModel, array_like, array_like)
        ``(model, theta0, omega0)`` for each pendulum.
    methods : sequence of str
        Keys of :data:`pendulum_lab.METHODS`; all of them by default.
    t_end, dt : float
        Length and step of every run [s].
    progress : bool
        Show a progress bar over the runs.

    Returns
    -------
    MethodComparison

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> result = compare_methods([(pl.simple_pendulum(), [1.0], [0.0])], ["rk4", "leapfrog"],
    ...                          t_end=2.0)
    >>> [(row.pendulum, row.method, round(row.observed_order)) for row in result.rows]
    [('simple', 'rk4', 4), ('simple', 'leapfrog', 2)]
    """
    methods = check.choices("methods", methods, METHODS)
    problems = list(problems)
    for problem in problems:
        if not (isinstance(problem, tuple | list) and len(problem) == 3):
            raise TypeError("`problems` must hold (model, theta0, omega0) triples, got "
                            f"{problem!r}")
        require_model(problem[0])
    from tqdm.auto import tqdm

    rows, failures, trajectories = [], [], {}
    bar = tqdm(total=len(problems) * len(methods), disable=not progress, unit="run")
    try:
        for model, theta0, omega0 in problems:
            pendulum = pendulum_name(model)
            reference = reference_solution(model, theta0, omega0, t_end=1.0)
            runs = trajectories.setdefault(pendulum, [])
            for name in methods:
                bar.set_description(f"{pendulum} {name}")
                try:
                    traj = simulate(model, theta0, omega0, t_end=t_end, dt=dt, method=name,
                                    progress=False)
                except ConvergenceError as err:
                    failures.append((pendulum, name, str(err)))
                else:
                    rows.append(compare_trajectory(model, traj, reference=reference))
                    runs.append(traj)
                bar.update(1)
    finally:
        bar.close()
    return MethodComparison(rows, trajectories, failures)


@dataclass(frozen=True)
class EnergyComparison:
    """One initial state integrated by several methods.

    Attributes
    ----------
    trajectories : dict
        ``{method name: Trajectory}``.
    """

    trajectories: dict

    def growth(self, fraction: float = 0.1) -> dict:
        """``{method: (first, last)}``: largest ``|E - E0|`` in the first and last ``fraction``.

        See :func:`pendulum_lab.analysis.energy_growth`. A ratio last/first
        near 1 means a bounded energy error, a large ratio a drift.
        """
        return {name: energy_growth(traj, fraction) for name, traj in self.trajectories.items()}

    def max_relative_error(self) -> dict:
        """``{method: max |E - E0| / |E0|}`` over the run."""
        return {
            name: float(np.max(np.abs(traj.relative_energy_error)))
            for name, traj in self.trajectories.items()
        }

    def plot(self, ax=None):
        """``|E - E0| / |E0|`` against time, log scale, one line per method; returns the Figure.

        Exact zeros are not drawn (a log axis cannot show them).
        """
        return plot_with("plot_energy_comparison", self, ax=ax)


def compare_energy(
    model: PendulumModel,
    theta0,
    omega0=None,
    *,
    t_end: float,
    dt: float = 0.01,
    methods=("explicit_euler", "rk4", "leapfrog", "glrk4"),
    save_every: int = 1,
    p0=None,
    progress: bool | None = None,
) -> EnergyComparison:
    """Integrate one initial state with each of ``methods``.

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0, p0 : array_like, shape (n,)
    t_end, dt, save_every, progress
        As for :func:`~pendulum_lab.simulate`.
    methods : sequence of str
        Keys of :data:`pendulum_lab.METHODS`.

    Returns
    -------
    EnergyComparison
    """
    require_model(model)
    return EnergyComparison(
        {
            get_method(m).name: simulate(model, theta0, omega0, t_end=t_end, dt=dt, method=m,
                                         save_every=save_every, p0=p0, progress=progress)
            for m in methods
        }
    )
