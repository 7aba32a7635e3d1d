"""The arguments of a run, validated, and the limits a run is held to before any work.

Every function of the package that runs a simulation takes its initial state and time grid
through these: :func:`step_count` (the one rule from ``t_end`` and ``dt`` to steps),
:func:`time_grid` and :func:`run_arguments`; the conversions :func:`canonical_state` and
:func:`velocity_state`; and the refusals of a run too long (:data:`WORK_BUDGET`), too large
for the memory available (:func:`check_memory`) or with a clock that stands still
(:func:`check_clock`).
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from .. import validation as check
from ..integrators import Method, get_method
from ..model import PendulumModel, require_model
from ..model.family import FamilyMembers

__all__ = [
    "canonical_state",
    "check_clock",
    "check_memory",
    "check_progress",
    "check_run_length",
    "initial_state",
    "memory_needed",
    "progress_bar",
    "run_arguments",
    "step_count",
    "time_grid",
    "velocity_state",
]

# Show a progress bar by default once a run does this many state updates
# (steps times ensemble size): a few seconds of work or more.
PROGRESS_THRESHOLD = 2_000_000
# The compiled loop counts steps in int64; stay well clear of its end.
MAX_STEPS = 2**62
#: State updates (steps times trajectories) a run may take without ``allow_long_run=True``:
#: hours of computing at about a microsecond per update (RK4 on the double pendulum takes
#: 0.45 us, Gauss-Legendre methods and long chains more), 25 times the largest run of the
#: course (a basin map of 40,000 releases over 10,000 steps).
WORK_BUDGET = 10**10
# Floats a run holds at its peak, found with tracemalloc for chains of 1 to 12 links and
# explicit, implicit and symplectic methods (tests/driver/test_run_limits.py checks it): per
# kept state of a member, 9 per link plus 3 (the states saved while stepping, theta, omega, p
# and the energies afterwards, and the temporaries that convert them); per member, the
# method's memory (``method.kernel.memory(n)``) plus 3 per link plus 4 (the state being
# stepped in both variables, the conversions of the initial state, the counters).
FLOATS_PER_STATE = (9, 3)
FLOATS_PER_MEMBER = (3, 4)
#: Bytes a run may need without asking the system how much memory it has available.
SMALL_RUN = 2**26
#: A driven model's step times rounded by more than this fraction of ``dt`` warn.
CLOCK_ROUNDING_WARNING = 1e-6


def step_count(t_end: float, dt: float) -> int:
    """The number of steps of size ``dt`` in ``[0, t_end]``: ``floor(t_end / dt)``.

    A relative slack of ``1e-12`` forgives the rounding of a quotient that
    should be whole (``0.3 / 0.1`` is ``2.9999999999999996``). This is the
    one rule every run of the package uses.

    Parameters
    ----------
    t_end : float
        Length of the interval [s], ``>= 0``.
    dt : float
        Step size [s], ``> 0``.

    Raises
    ------
    ValueError
        If ``t_end < 0``, ``dt <= 0``, either is not finite, or ``t_end / dt`` overflows.

    Examples
    --------
    >>> step_count(0.3, 0.1), step_count(1.0, 0.3)
    (3, 3)
    """
    t_end = check.non_negative_number("t_end", t_end)
    dt = check.positive_number("dt", dt)
    steps = t_end / dt * (1 + 1e-12)
    if not math.isfinite(steps):
        raise ValueError(f"`t_end` / `dt` = {t_end:g} / {dt:g} overflows: more steps than "
                         "can be counted; choose a larger `dt`")
    return int(steps)


def time_grid(t_end, dt, *, members: int = 1, allow_long_run: bool = False
              ) -> tuple[float, float, int]:
    """Validated ``(t_end, dt, number of steps)`` of a run; ``t_end >= dt > 0``.

    A run of more than :data:`WORK_BUDGET` state updates (steps times ``members``) is refused
    unless ``allow_long_run`` (:func:`check_run_length`).
    """
    dt = check.positive_number("dt", dt)
    t_end = check.positive_number("t_end", t_end)
    if t_end < dt:
        raise ValueError(f"`t_end` must be at least `dt` ({dt}), got {t_end}")
    n_steps = step_count(t_end, dt)
    if n_steps > MAX_STEPS:
        raise ValueError(
            f"`t_end` / `dt` = {t_end:g} / {dt:g} = {n_steps:.3g} steps, more than a run can "
            f"count ({MAX_STEPS:.3g}); choose a larger `dt` or a shorter `t_end`"
        )
    check_run_length(n_steps, members, what=f"`t_end` / `dt` = {t_end:g} s / {dt:g} s",
                     advice="Choose a larger `dt` or a shorter `t_end`",
                     allow_long_run=allow_long_run)
    return t_end, dt, n_steps


def check_run_length(n_steps: int, members: int, *, what: str, advice: str,
                     allow_long_run: bool = False, opt_in: bool = True) -> None:
    """Refuse a run of more than :data:`WORK_BUDGET` state updates unless ``allow_long_run``.

    The message gives the count and the budget: a mistyped ``dt`` (``1e-12`` for ``1e-2``)
    or ``t_end`` would otherwise start a run of days behind a progress bar. ``what`` names
    the arguments that make the ``n_steps`` steps, ``advice`` what to change; ``opt_in`` says
    whether the caller offers ``allow_long_run``.
    """
    if not isinstance(allow_long_run, bool):
        raise TypeError(f"`allow_long_run` must be True or False, got {allow_long_run!r}")
    work = n_steps * members
    if allow_long_run or work <= WORK_BUDGET:
        return
    runs = "" if members == 1 else f" x {members} trajectories = {work:.3g} state updates"
    raise ValueError(
        f"{what} = {n_steps:.3g} steps{runs}, more than the budget of {WORK_BUDGET:.0e} state "
        f"updates for one run (at about a microsecond each, {work * 1e-6 / 3600:.3g} hours). "
        f"{advice}"
        + ("; to run it anyway, pass allow_long_run=True (to simulate or simulate_segments)."
           if opt_in else ".")
    )


def check_clock(model: PendulumModel, t0: float, span: float, dt: float,
                stacklevel: int = 3) -> None:
    """Refuse times so large that ``t + dt == t``; warn where a driven model's times round.

    Floats near ``t`` are ``np.spacing(t)`` apart. Once that exceeds twice ``|dt|`` the clock
    of the run stands still (every step starts at the same time), which would leave a driven
    model's drive frozen and every model's saved times equal. Short of that, a driven model's
    drive is evaluated at rounded times: a ``RuntimeWarning`` says by how much when the
    rounding exceeds :data:`CLOCK_ROUNDING_WARNING` of a step.
    """
    last = max(abs(t0), abs(t0 + span))
    spacing = math.ulp(last)
    if last + abs(dt) != last and spacing <= CLOCK_ROUNDING_WARNING * abs(dt):
        return  # the usual case, decided without asking the model
    driven = not model.is_autonomous
    if last + abs(dt) == last or (driven and spacing > CLOCK_ROUNDING_WARNING * abs(dt)):
        period = model.drive_period
        if not driven:
            remedy = ("This model does not depend on the time, so t0 only labels the saved "
                      "times: start at t0 = 0 for the same motion.")
        elif np.ndim(period) == 0:
            remedy = (f"The drive repeats every {period:.6g} s: start at t0 % {period:.6g} = "
                      f"{math.fmod(t0, period):.6g} s for about the same drive phase.")
        else:  # a family's periods
            remedy = ("The drive repeats with its period 2 pi / drive_frequency: start at t0 "
                      "modulo it for about the same drive phase.")
    # the argument that makes the times large
    where = f"`t0` = {t0:g} s" if abs(t0) >= abs(span) else f"`t0` + `t_end` = {t0 + span:g} s"
    if last + abs(dt) == last:
        raise ValueError(
            f"{where}: floats near t = {last:.3g} s are {spacing:.3g} s apart, more "
            f"than twice `dt` = {abs(dt):g} s, so t + dt == t and the clock of the run would "
            f"stand still. {remedy}"
        )
    if driven and spacing > CLOCK_ROUNDING_WARNING * abs(dt):
        warnings.warn(
            f"{where}: floats near t = {last:.3g} s are {spacing:.3g} s apart, "
            f"{spacing / abs(dt):.2g} of `dt`, so the drive is evaluated at times rounded by "
            f"up to that much. {remedy}",
            RuntimeWarning,
            stacklevel=stacklevel,
        )



def initial_state(model: PendulumModel, theta0, omega0, p0) -> tuple[np.ndarray, np.ndarray]:
    """Validated ``theta0`` and the one of ``omega0`` and ``p0`` that was given."""
    theta0 = check.state_array("theta0", theta0, model.n)
    if (omega0 is None) == (p0 is None):
        raise TypeError("give exactly one of `omega0` (angular velocities) and `p0` (momenta)")
    name, start = ("omega0", omega0) if p0 is None else ("p0", p0)
    start = check.state_array(name, start, model.n)
    check.same_shape("theta0", theta0, name, start)
    if theta0.size == 0:
        raise ValueError(f"`theta0` must hold at least one state, got shape {theta0.shape} "
                         "(an empty ensemble)")
    return theta0, start


def run_arguments(model, theta0, omega0, p0, t_end, dt, method, save_every, t0,
                  allow_long_run: bool = False):
    """The arguments of a run, validated in the order :func:`~pendulum_lab.simulate` names them.

    Also refuses, before any work: a run beyond :data:`WORK_BUDGET` unless ``allow_long_run``
    (:func:`check_run_length`), a ``save_every`` longer than the run, and a clock that would
    stand still (:func:`check_clock`).

    Returns
    -------
    method : Method
    theta0, start : ndarray
        The initial angles and the one of ``omega0``, ``p0`` that was given.
    (t_end, dt, n_steps) : tuple
    save_every : int
    t0 : float
    """
    require_model(model)
    method = get_method(method)
    theta0, start = initial_state(model, theta0, omega0, p0)
    grid = time_grid(t_end, dt, members=theta0.size // model.n, allow_long_run=allow_long_run)
    save_every = check.integer_at_least("save_every", save_every, 1)
    if save_every > grid[2]:
        raise ValueError(
            f"`save_every` = {save_every} is more than the run's {grid[2]} steps (`t_end` / "
            f"`dt` = {grid[0]:g} / {grid[1]:g}), so only the initial state would be kept; "
            f"choose `save_every` <= {grid[2]} or a longer `t_end`"
        )
    t0 = check.real_number("t0", t0)
    check_clock(model, t0, grid[0], grid[1], stacklevel=4)
    check_start_defined(model, theta0, t0)
    return method, theta0, start, grid, save_every, t0


def check_start_defined(model: PendulumModel, theta0: np.ndarray, t0: float) -> None:
    """Refuse a start where the model's coordinates describe no place.

    A spherical pendulum's ``(x, y)`` beyond its rod has no height (the square root of a
    negative number), so its energies there are NaN; a run from there fails at its first step
    with a message about the step size. A chain's angles are defined everywhere.
    """
    batch = theta0.shape[:-1]
    states = theta0.reshape(-1, model.n)
    if isinstance(model, FamilyMembers):  # one member per state (refused if it does not fit)
        model = model.for_ensemble(batch)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        potential = np.asarray(model.potential_energy(states, t=t0), dtype=float).reshape(-1)
    undefined = ~np.isfinite(potential)
    if not np.any(undefined):
        return
    first = int(np.argmax(undefined))
    index = tuple(int(i) for i in np.unravel_index(first, batch))
    member = f" (ensemble member {index})" if batch else ""
    name = getattr(model, "name", None) or "the model"
    values = [round(float(v), 6) for v in states[first]]
    raise ValueError(f"`theta0` = {values}{member} is not a place {name} can be: its "
                     f"potential energy there is not a finite number (for a point on a rod, "
                     f"beyond the rod's reach); start nearer its rest position")


def canonical_state(model: PendulumModel, theta0, omega0=None, p0=None, *, t0: float = 0.0):
    """The initial state ``(theta0, p0)`` in canonical variables, validated.

    Give exactly one of ``omega0`` (converted by ``p = M(theta) omega``, or
    ``M(theta, t0) omega + b(theta, t0)`` where the equations depend on the
    time) and ``p0`` (taken as it is).

    Returns
    -------
    theta0, p0 : ndarray, shape (..., n)
    """
    require_model(model)
    t0 = check.real_number("t0", t0)
    theta0, start = initial_state(model, theta0, omega0, p0)
    check_start_defined(model, theta0, t0)
    return theta0, (start if p0 is not None else model.momenta(theta0, start, t=t0))


def velocity_state(model: PendulumModel, theta0, omega0=None, p0=None, *,
                   single: bool = False, t0: float = 0.0):
    """The initial state ``(theta0, omega0)`` in velocity variables, validated.

    Give exactly one of ``omega0`` (taken as it is) and ``p0`` (converted by
    ``omega = M(theta)^-1 p``, at the time ``t0`` where the equations depend
    on it). With ``single``, it must be one state of shape ``(n,)``.

    Returns
    -------
    theta0, omega0 : ndarray, shape (..., n)
    """
    require_model(model)
    t0 = check.real_number("t0", t0)
    theta0, start = initial_state(model, theta0, omega0, p0)
    check_start_defined(model, theta0, t0)
    if single and theta0.ndim != 1:
        raise ValueError("`theta0` and `omega0` must have shape (n,) (one trajectory)")
    return theta0, (start if p0 is None else model.velocities(theta0, start, t=t0))



def progress_bar(total: int, work: int, enabled: bool | None, label: str, unit: str = "step"):
    """A tqdm bar over ``total`` steps (or other ``unit``), or None.

    ``enabled=None`` shows one only for work of a few seconds or more
    (``work`` = state updates, steps times ensemble members).
    """
    if enabled is None:
        enabled = work >= PROGRESS_THRESHOLD
    if not enabled:
        return None
    from tqdm.auto import tqdm

    return tqdm(total=total, desc=label, unit=unit, mininterval=0.5)


def memory_needed(n: int, method: Method, members: int, n_saved: int) -> float:
    """Bytes a run of ``members`` trajectories of ``n`` links keeping ``n_saved`` states each
    holds at its peak: the kept states and their conversions, the method's working memory
    (``method.kernel.memory(n)`` floats per trajectory) and the state being stepped.

    Measured peaks (tracemalloc) stay below it; see :data:`FLOATS_PER_STATE`.
    """
    per_member = (max(1, method.kernel.memory(n)) + FLOATS_PER_MEMBER[0] * n
                  + FLOATS_PER_MEMBER[1])
    per_state = FLOATS_PER_STATE[0] * n + FLOATS_PER_STATE[1]
    return 8.0 * members * (n_saved * per_state + per_member)


def check_memory(needed: float, what: str, advice: str) -> None:
    """Refuse, before any work, ``what`` (a run) needing ``needed`` bytes if this machine does
    not have them available now; ``advice`` says which arguments to change.

    Runs below :data:`SMALL_RUN` bytes pass unasked: asking the system costs 0.1 ms, as much
    as a short run.
    """
    if needed < SMALL_RUN:
        return
    available = check.available_memory()
    if available is None or needed <= available:
        return
    raise ValueError(
        f"{what} needs about {check.bytes_text(needed)} of memory, more than the "
        f"{check.bytes_text(available)} this machine has available. {advice}"
    )



def check_progress(progress) -> bool | None:
    """``progress`` if it is True, False or None (decide by the length of the run)."""
    if progress is not None and not isinstance(progress, (bool, np.bool_)):
        raise TypeError(f"`progress` must be True, False or None (by the run's length), got "
                        f"{progress!r}")
    return None if progress is None else bool(progress)

