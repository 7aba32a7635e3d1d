"""Bifurcation diagrams of a driven pendulum: the stroboscopic section against a parameter.

For each value of a parameter (the drive amplitude, the damping, ...) the
attractor's stroboscopic points are plotted above that value: one point for a
period-1 response, two after a period doubling, a cloud for a strange
attractor [BG]_. All values, and several initial states per value (attractors
coexist), are integrated as ONE ensemble run: the model is a
:class:`~pendulum_lab.model.ModelFamily`, one member per value, and the
compiled loop gives each member its own parameters. The periods are
detected from the computed samples (:func:`~pendulum_lab.chaos.orbit_periods`),
and so are the period doublings (:meth:`BifurcationDiagram.doublings`).

References
----------
.. [BG] G. L. Baker, J. P. Gollub, *Chaotic Dynamics: An Introduction*, 2nd
   ed., Cambridge University Press 1996, ch. 4 (bifurcation diagrams of the
   driven pendulum, period doubling).
.. [F] M. J. Feigenbaum, "Quantitative universality for a class of nonlinear
   transformations", J. Stat. Phys. 19 (1978) 25-52.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .. import validation as check
from ..driver.cluster import check_client, map_members, portable_method
from ..driver.segments import default_segment_steps
from ..driver.simulate import check_run_length
from ..integrators import get_method
from ..model import family_parameter, require_model
from ..model.angles import wrap_angle
from ..model.pendulum import PendulumModel
from ..plot_dispatch import plot_with
from .stroboscopic import PERIOD_TOLERANCE, orbit_periods, stroboscopic_section

__all__ = [
    "BifurcationDiagram",
    "PeriodDoubling",
    "PeriodWindow",
    "bifurcation_diagram",
    "bifurcation_samples",
]

#: Default of :meth:`BifurcationDiagram.doublings`: how far (max-norm in wrapped
#: theta [rad] and omega [rad/s]) a doubled orbit's points may lie from the old ones.
MAX_JUMP = 0.25


@dataclass(frozen=True)
class PeriodDoubling:
    """A period doubling found in a bifurcation diagram.

    Attributes
    ----------
    period : int
        The period before; after it the period is ``2 * period``.
    before, value : float
        The last parameter value with the old period and the first with the
        new one: the bifurcation lies between them.
    """

    period: int
    before: float
    value: float


@dataclass(frozen=True)
class PeriodWindow:
    """A run of neighbouring parameter values with the same detected periods.

    Attributes
    ----------
    first, last : float
        The first and last value of the run.
    periods : tuple of int
        The distinct periods the initial states found there, ascending; empty
        where none found a period (chaos, or periods beyond ``max_period``).
    count : int
        How many values the run holds.
    """

    first: float
    last: float
    periods: tuple
    count: int


@dataclass(frozen=True)
class BifurcationDiagram:
    """Stroboscopic samples of a driven pendulum against a parameter.

    Attributes
    ----------
    parameter : str
    values : ndarray, shape (V,)
    theta, omega : ndarray, shape (S, V, B, n)
        ``S`` stroboscopic samples for each of ``V`` values and ``B`` initial
        states; angles wrapped to ``(-pi, pi]`` [rad], velocities [rad/s].
    periods : ndarray of int, shape (V, B)
        The period of each orbit (:func:`~pendulum_lab.chaos.orbit_periods`;
        0: none up to ``max_period``).
    turns : ndarray, shape (V, B, n)
        Mean full turns per drive period over the samples (0: the pendulum
        oscillates; +-1: it goes over the top once per period).
    tolerance : float
        The tolerance the periods were detected with.
    max_period : int
    variable : {"omega", "theta"}
        The coordinate plotted.
    link : int
        The link whose coordinate is plotted (0-based).
    method : str
    wall_time : float
        Seconds of the run.
    """

    parameter: str
    values: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    periods: np.ndarray
    turns: np.ndarray
    tolerance: float
    max_period: int
    variable: str
    link: int
    method: str
    wall_time: float

    @property
    def points(self) -> np.ndarray:
        """The plotted coordinate, shape ``(S, V, B)``."""
        return getattr(self, self.variable)[..., self.link]

    def windows(self, min_count: int = 1) -> list[PeriodWindow]:
        """The values grouped into runs with the same set of detected periods, in order.

        Runs shorter than ``min_count`` values are left out (in a chaotic range
        single values flicker between "no period" and a long one).
        """
        min_count = check.integer_at_least("min_count", min_count, 1)
        found = [tuple(sorted(set(row[row > 0].tolist()))) for row in self.periods]
        runs, start = [], 0
        for i in range(1, len(found) + 1):
            if i == len(found) or found[i] != found[start]:
                if i - start >= min_count:
                    runs.append(PeriodWindow(float(self.values[start]),
                                             float(self.values[i - 1]), found[start], i - start))
                start = i
        return runs

    def doublings(self, max_jump: float = MAX_JUMP) -> list[PeriodDoubling]:
        """The period doublings the data show, in order of the parameter.

        A doubling lies between neighbouring values when an orbit of period
        ``2p`` at the second has every point within ``max_jump`` of a point
        of an orbit of period ``p >= 1`` at the first (from any initial
        states): a period doubling splits each point of the orbit in two near
        it, while an attractor of twice the period elsewhere, or a jump to
        another coexisting attractor, lies far away.

        The values bracket what the samples show, not the bifurcation itself:
        just before a flip the orbit's multiplier is near -1, so a transient
        of ``N`` periods still alternates with a relative size ``|mu|^N``
        (critical slowing down; ``0.98^300 = 2e-3``), above the period
        tolerance, and the orbit looks doubled too early. To locate a flip
        with a stated error, use
        :func:`~pendulum_lab.chaos.period_doubling_cascade`.
        """
        max_jump = check.positive_number("max_jump", max_jump)
        found = []
        for i in range(1, len(self.values)):
            for p in sorted(set(self.periods[i - 1][self.periods[i - 1] > 0].tolist())):
                olds = np.flatnonzero(self.periods[i - 1] == p)
                news = np.flatnonzero(self.periods[i] == 2 * p)
                if any(self._near(i - 1, old, i, new, p, max_jump)
                       for old in olds for new in news):
                    found.append(PeriodDoubling(p, float(self.values[i - 1]),
                                                float(self.values[i])))
        return found

    def _near(self, i_old, b_old, i_new, b_new, p, max_jump) -> bool:
        """Every point of orbit ``(i_new, b_new)`` (period 2p) is near one of ``(i_old, b_old)``."""
        theta_old, omega_old = self.theta[-p:, i_old, b_old], self.omega[-p:, i_old, b_old]
        theta_new = self.theta[-2 * p:, i_new, b_new]
        omega_new = self.omega[-2 * p:, i_new, b_new]
        gap = np.maximum(
            np.abs(wrap_angle(theta_new[:, None] - theta_old[None])).max(axis=-1),
            np.abs(omega_new[:, None] - omega_old[None]).max(axis=-1),
        )
        return bool(np.all(gap.min(axis=1) <= max_jump))

    def plot(self, ax=None, lyapunov=None, mark_doublings: bool = True, **kwargs):
        """The diagram, with the doublings marked; with ``lyapunov``, a panel of ``lambda_1`` below.

        ``lyapunov`` is a :class:`~pendulum_lab.chaos.LyapunovSpectrum` or
        :class:`~pendulum_lab.chaos.LyapunovEstimate` over the same values
        (ensemble shape ``(V,)`` or ``(V, B)``). Returns the Figure.
        """
        return plot_with("plot_bifurcation", self, ax=ax, lyapunov=lyapunov,
                         mark_doublings=mark_doublings, **kwargs)


def _starts(model, theta0, omega0):
    """Initial states as ``(B, n)`` arrays: one state or a list of them."""
    theta0 = check.state_array("theta0", theta0, model.n)
    omega0 = check.state_array("omega0", omega0, model.n)
    check.same_shape("theta0", theta0, "omega0", omega0)
    if theta0.ndim > 2:
        raise ValueError(f"`theta0` must be one state (n,) or a list of states (B, n), got shape "
                         f"{theta0.shape}")
    return theta0.reshape(-1, model.n), omega0.reshape(-1, model.n)


def _common_period_family(model: PendulumModel, frequencies: np.ndarray):
    """A family with the drive frequency of ``model`` standing in for each of ``frequencies``.

    With ``s = (Omega / Omega_0) t`` the equations
    ``M theta'' + (Coriolis) + C theta' + grad V = A cos(Omega t)`` become the
    same equations in ``s`` with ``C -> r C``, ``g -> r^2 g``, ``A -> r^2 A``
    and the drive ``cos(Omega_0 s)``, where ``r = Omega_0 / Omega`` (every
    inertial term is quadratic in the velocities, so they scale alike). All
    members then share the drive period ``2 pi / Omega_0``, and Runge-Kutta
    and splitting methods commute with the rescaling: ``steps_per_period``
    steps of each member are the same steps as in its own time. Angles are
    unchanged and velocities scale: ``omega_t = omega_s / r``.

    Returns
    -------
    family : ModelFamily
    ratio : ndarray, shape (V,)
        ``r``.
    """
    reference = model.drive_frequency
    if reference is None:
        raise ValueError("`model` has no drive (its `drive_frequency` is None)")
    if len(set(model.damping)) > 1:
        raise ValueError("a diagram over 'drive_frequency' rescales the damping, one number for "
                         f"every joint; `model` has different joint dampings {model.damping}")
    if np.any(frequencies <= 0):
        raise ValueError("`values` of 'drive_frequency' must be positive (> 0)")
    ratio = reference / frequencies
    family = model.family(damping=model.damping[0] * ratio, g=model.g * ratio**2,
                          drive_amplitude=model.drive_amplitude * ratio**2)
    return family, ratio


def bifurcation_diagram(
    model: PendulumModel,
    parameter: str,
    values,
    *,
    theta0,
    omega0,
    n_periods: int = 100,
    transient_periods: int = 300,
    steps_per_period: int = 100,
    method="rk4",
    variable: str = "omega",
    link: int = 0,
    tolerance: float = PERIOD_TOLERANCE,
    max_period: int = 16,
    progress: bool | None = None,
    client=None,
    chunk_size: int | None = None,
) -> BifurcationDiagram:
    """The stroboscopic section of a driven pendulum against one of its parameters.

    Every value of ``parameter`` and every initial state make one member of
    a single ensemble run (:func:`~pendulum_lab.chaos.stroboscopic_section` of
    the :class:`~pendulum_lab.model.ModelFamily` ``model.family(parameter=values)``),
    with a progress bar for long runs. A diagram over ``"drive_frequency"``
    rescales each member's time to the model's own drive period (exactly:
    the steps are the same), so it too is one run.

    Parameters
    ----------
    model : PendulumModel
        A driven model, or a system whose time dependence has a period (the Kapitza
        pendulum); its other parameters stay fixed.
    parameter : {"damping", "drive_amplitude", "drive_frequency", "g"}
        For a system, one of its own parameters except those that set its period
        (:func:`~pendulum_lab.model.family_parameter`).
    values : array_like, shape (V,)
        The parameter's values, in the order to plot.
    theta0, omega0 : array_like, shape (n,) or (B, n)
        Initial states, the same for every value (several find coexisting
        attractors).
    n_periods, transient_periods, steps_per_period, method
        As for :func:`~pendulum_lab.chaos.stroboscopic_section`;
        ``n_periods >= 2 max_period``.
    variable : {"omega", "theta"}
        The coordinate to plot.
    link : int
        Whose coordinate (0-based).
    tolerance, max_period
        Of the period detection (:func:`~pendulum_lab.chaos.orbit_periods`).
    progress : bool, optional
    client : dask.distributed.Client, optional
        Integrate the values on this Dask cluster, in chunks
        (:func:`pendulum_lab.driver.cluster.map_members`); the diagram is the same,
        bit for bit, as without it.
    chunk_size : int, optional
        Values per chunk on a cluster (by default a few chunks per worker).

    Returns
    -------
    BifurcationDiagram

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> diagram = bifurcation_diagram(pl.driven_pendulum(), "drive_amplitude", [0.9, 1.07],
    ...                               theta0=[0.2], omega0=[0.0], n_periods=32,
    ...                               transient_periods=200, steps_per_period=50)
    >>> diagram.periods.tolist()  # period 1, then period 2 past the first doubling
    [[1], [2]]
    """
    require_model(model)
    parameter = family_parameter(model, parameter)
    values = check.real_sequence("values", values)
    variable = check.choice("variable", variable, ("omega", "theta"))
    link = check.index_below("link", link, model.n)
    tolerance = check.positive_number("tolerance", tolerance)
    max_period = check.integer_at_least("max_period", max_period, 1)
    n_periods = check.integer_at_least("n_periods", n_periods, 1)
    if n_periods < 2 * max_period:
        raise ValueError(f"`n_periods` must be at least 2 max_period = {2 * max_period} to tell "
                         f"periods up to `max_period`, got {n_periods}")
    transient_periods = check.integer_at_least("transient_periods", transient_periods, 0)
    steps_per_period = check.integer_at_least("steps_per_period", steps_per_period, 1)
    theta0, omega0 = _starts(model, theta0, omega0)
    check_run_length((transient_periods + n_periods) * steps_per_period,
                     len(values) * len(theta0), opt_in=False,
                     what=f"{len(values)} `values` over `transient_periods` + `n_periods` = "
                     f"{transient_periods + n_periods} periods of `steps_per_period` = "
                     f"{steps_per_period} steps",
                     advice="Choose fewer `values` or periods, or fewer `steps_per_period`")
    if parameter == "drive_frequency" and model.is_chain:
        family, ratio = _common_period_family(model, values)
    else:
        family, ratio = model.family(**{parameter: values}), np.ones_like(values)
    method = get_method(method)
    client = check_client(client)
    # The segments of the whole batch, for every chunk of it (see default_segment_steps).
    segment_steps = default_segment_steps(model.n, len(values) * len(theta0),
                                          (transient_periods + n_periods) * steps_per_period,
                                          steps_per_period)
    start = time.perf_counter()
    theta, omega, turns = map_members(
        bifurcation_samples, (np.arange(len(values)),), client=client, chunk_size=chunk_size,
        label="bifurcation diagram", progress=progress,
        args=(family, ratio, theta0, omega0, n_periods, transient_periods, steps_per_period,
              portable_method(method, client), segment_steps,
              progress if client is None else False))
    theta, omega = np.moveaxis(theta, 0, 1), np.moveaxis(omega, 0, 1)
    periods = orbit_periods(theta, omega, tolerance, max_period)
    return BifurcationDiagram(parameter, values, theta, omega, periods, turns, tolerance,
                              max_period, variable, link, method.name,
                              time.perf_counter() - start)


def bifurcation_samples(rows, family, ratio, theta0, omega0, n_periods: int,
                        transient_periods: int, steps_per_period: int, method,
                        segment_steps: int, progress: bool | None = None) -> tuple:
    """The stroboscopic samples of the values ``rows`` of a bifurcation diagram.

    The work of :func:`bifurcation_diagram` (arguments validated there) on
    the members ``rows`` of ``family`` (time rescaled by ``ratio``), here or
    on a Dask worker (:func:`pendulum_lab.driver.cluster.map_members`).

    Returns
    -------
    theta, omega : ndarray, shape (R, S, B, n)
        Wrapped angles and velocities (in real time), the values first.
    turns : ndarray, shape (R, B, n)
    """
    family, scale = family.select(rows), ratio[rows][:, None, None]
    shape = (len(rows), len(theta0), theta0.shape[-1])
    section = stroboscopic_section(
        family.select((slice(None), None)), np.broadcast_to(theta0, shape),
        np.broadcast_to(omega0, shape) * scale, n_periods=n_periods,
        transient_periods=transient_periods, steps_per_period=steps_per_period, method=method,
        progress=progress, segment_steps=segment_steps,
    )
    # Velocities in the family's time are r times the real ones.
    return (np.moveaxis(section.theta, 1, 0), np.moveaxis(section.omega / scale, 1, 0),
            section.turns)
