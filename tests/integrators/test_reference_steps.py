"""The compiled steps against their plain NumPy reference steps, step by step.

Every registered method carries a reference step (``Method.reference``,
:mod:`pendulum_lab.integrators.reference`) that reads like its formula; the notebooks show it
(``method_source``). Here each method's compiled kernel is compared with it on chains of 1, 2
and 3 links, conservative, damped, driven, and damped and driven, wherever the registry's
``unsuitability`` lets the method integrate the field:

* one step from the same state (``pl.step``, which starts from a fresh memory), and
* along a compiled run: the run's state at step ``k``, one reference step, the run's state at
  step ``k + 1``. The implicit Runge-Kutta steps carry their stage slopes (the next step's
  starting values) and the rounding of the state (compensated summation) from step to step;
  the reference continues the slopes of its own previous step, as the compiled step does.

The tolerance (:func:`allowed`) is round-off: ``(4 + sweeps) eps max|y|``, with ``max|y|``
the largest component of the two states compared and ``sweeps`` the reference step's
fixed-point sweeps. Why: both sides evaluate the same kernels at states that differ only by
rounding (stage sums added in another order, the compiled implicit steps' vectorized sines
and cosines, a last place carried by the compensated summation, which is below half an ulp of
``y``); rounding a state costs ``eps max|y|``, and a few such roundings make the 4. An implicit
solve accepts its iterate once the increments no longer shrink or the rest is predicted below
half an ulp, and every sweep re-evaluates the stages at states rounded to the last place of
``y``: each sweep can leave one such rounding that the contraction has not damped away, hence
the term that grows with the sweeps. A slip in a formula (a wrong weight, a kick at the wrong
time, an iteration stopped early) misses by orders of magnitude more (the negative controls).

``python tests/integrators/test_reference_steps.py`` prints the table of the largest
differences (in units of ``eps max|y|``) for every method, chain and forcing.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab.integrators import (
    GAUSS4_TABLEAU,
    MAX_SWEEPS,
    RK4_TABLEAU,
    ButcherTableau,
    ConvergenceError,
    Method,
    fixed_point_status,
    gauss_legendre_tableau,
    get_method,
    reference,
    unsuitability,
)
from pendulum_lab.integrators.registry import CONFORMAL_METHODS, METHODS, VARIATIONAL_METHODS

EPS = np.finfo(float).eps
NAMES = (*METHODS, *CONFORMAL_METHODS, *VARIATIONAL_METHODS)
LINKS = (1, 2, 3)
FORCINGS = ("conservative", "damped", "driven", "damped and driven")
FORCES = {
    "conservative": {},
    "damped": {"damping": 0.3},
    "driven": {"drive_amplitude": 1.2, "drive_frequency": 2 / 3},
    "damped and driven": {"damping": 0.3, "drive_amplitude": 1.2, "drive_frequency": 2 / 3},
}
#: Unequal masses and lengths, so that a parameter taken for another shows.
CHAINS = {1: ((0.8,), (1.2,)), 2: ((1.0, 1.5), (1.0, 0.7)), 3: ((1.0, 0.8, 0.6), (1.0, 0.9, 0.7))}
STARTS = {1: ([2.0], [0.5]), 2: ([1.0, 1.5], [0.3, -0.2]), 3: ([0.4, -0.3, 0.8], [0.2, -0.1, 0.3])}
T0, H, STEPS = 0.3, 0.02, 40


@functools.cache
def model(n: int, forcing: str):
    masses, lengths = CHAINS[n]
    return pl.n_pendulum(n, masses, lengths, 9.81, **FORCES[forcing])


def allowed(scale: float, sweeps: int) -> float:
    """The round-off allowed between a compiled and a reference step (the module docstring)."""
    return (4 + sweeps) * EPS * scale


@contextlib.contextmanager
def counted_sweeps():
    """Count the sweeps of the reference steps' fixed-point solves: ``with ... as count:``."""
    count, solve = [0], reference.fixed_point

    def counting(update, x, floor=0.0):
        def counted(x):
            count[0] += 1
            return update(x)

        return solve(counted, x, floor)

    reference.fixed_point = counting
    try:
        yield count
    finally:
        reference.fixed_point = solve


def reference_step(step, field, t, q, y, h, previous=None):
    """``step`` from ``(q, y)``: ``(q1, y1, slopes or None, sweeps)``."""
    implicit_rk = getattr(step, "func", None) is reference.implicit_runge_kutta
    with counted_sweeps() as sweeps:
        if implicit_rk:
            q1, y1, slopes = step(field, t, q, y, h, previous=previous)
        else:
            (q1, y1), slopes = step(field, t, q, y, h), None
    return np.asarray(q1), np.asarray(y1), slopes, sweeps[0]


def misfit(compiled, referenced, sweeps):
    """The largest difference of two states: in units of ``eps max|y|``, absolute, allowed?"""
    both = np.concatenate([*compiled, *referenced])
    scale = np.max(np.abs(both))
    difference = np.max(np.abs(np.concatenate(compiled) - np.concatenate(referenced)))
    return difference / (EPS * scale), difference, difference <= allowed(scale, sweeps)


def start(method: Method, pendulum):
    """The initial state in the method's variables: ``(theta, p)`` or ``(theta, omega)``."""
    theta, omega = (np.array(x) for x in STARTS[pendulum.n])
    if method.variables == "velocity":
        return theta, omega
    return theta, pendulum.momenta(theta, omega)


def compare(method: Method, pendulum, step=None) -> dict:
    """Compiled against reference (``step``, by default the method's): one step, then a run.

    Returns the largest misfits (units of ``eps max|y|``) of the single step and along the
    run, the largest absolute difference, whether all were allowed, and the mean sweeps per
    step of the compiled run and of the reference steps along it.
    """
    step = method.reference if step is None else step
    field = reference.ReferenceField(pl.hamiltonian_field(pendulum))
    velocity = method.variables == "velocity"
    q, y = start(method, pendulum)
    # one step from the same state, as pl.step takes it (canonical momenta out)
    given = {"omega0": y} if velocity else {"p0": y}
    q1, p1 = pl.step(pendulum, q, dt=H, method=method, t0=T0, **given)
    rq, ry, _, sweeps = reference_step(step, field, T0, q, y, H)
    single, largest, single_ok = misfit(
        (q1, p1), (rq, pendulum.momenta(rq, ry) if velocity else ry), sweeps)
    # along a compiled run
    run = pl.simulate(pendulum, q, t_end=STEPS * H, dt=H, method=method, t0=T0, **given)
    states = run.omega if velocity else run.p
    worst, ok, previous, reference_sweeps = 0.0, True, None, 0
    for k in range(STEPS):
        rq, ry, previous, sweeps = reference_step(step, field, run.t[k], run.theta[k],
                                                  states[k], H, previous)
        reference_sweeps += sweeps
        value, difference, fits = misfit((run.theta[k + 1], states[k + 1]), (rq, ry), sweeps)
        worst, largest, ok = max(worst, value), max(largest, difference), ok and fits
    return {"single": single, "run": worst, "largest": largest, "ok": single_ok and ok,
            "sweeps": run.mean_iterations, "reference sweeps": reference_sweeps / STEPS}


def cases(name: str, n: int):
    """The forcings ``name`` can integrate on ``n`` links, and the others with the reason."""
    method = get_method(name)
    fits, refused = [], {}
    for forcing in FORCINGS:
        reason = unsuitability(method, pl.hamiltonian_field(model(n, forcing)))
        (fits.append(forcing) if reason is None else refused.setdefault(forcing, reason))
    return fits, refused


# ---------------------------------------------------------------- every method, step by step
def test_every_registered_method_carries_its_reference_step():
    for name in NAMES:
        method = get_method(name)
        assert callable(method.reference), name
        assert method.reference is get_method(name).reference  # one object, the registry's
    assert get_method("explicit_euler").reference is reference.explicit_euler
    assert get_method("glrk4").reference.keywords["tableau"] is GAUSS4_TABLEAU
    # a method made from a tableau gets the tableau's reference step
    heun = Method.from_tableau("heun2", ButcherTableau(a=[[0, 0], [1, 0]], b=[0.5, 0.5]),
                               "Heun's method")
    assert heun.reference.func is reference.explicit_runge_kutta


def _grid(name: str) -> bool:
    """Whether ``name`` is compared on every chain and forcing, or only on the simple pendulum.

    The composition methods share one compiled kernel and one reference step, which differ
    between them only by their constants (the weights and the kinds of substep): one of each
    pattern of substeps (the leapfrog's, symplectic Euler's with its adjoint first, and with
    itself first) goes over the whole grid, the others over the simple pendulum, which checks
    that their own constants reach both sides. Each one compiled on a chain costs seconds of
    Numba, in the suite and again at the floors.
    """
    composition = get_method(name).composition
    if composition is None:
        return True
    patterns = {}
    for other in NAMES:
        other_composition = get_method(other).composition
        if other_composition is not None:
            key = (other_composition.base, other_composition.adjoint_first)
            patterns.setdefault(key, other)
    return patterns[(composition.base, composition.adjoint_first)] == name


@pytest.mark.parametrize("name, n", [(name, n) for name in NAMES for n in LINKS
                                     if n == 1 or _grid(name)])
def test_compiled_step_is_the_reference_step(name, n):
    method = get_method(name)
    fits, refused = cases(name, n)
    if not _grid(name):
        fits, refused = fits[:1], {}
    assert "conservative" in fits  # every method integrates a conservative chain
    for forcing in fits:
        result = compare(method, model(n, forcing))
        assert result["ok"], (forcing, result)
    for forcing, reason in refused.items():  # where the method does not apply, it says so
        with pytest.raises(ValueError, match=name):
            pl.step(model(n, forcing), *start(method, model(n, forcing))[:1], p0=np.zeros(n),
                    dt=H, method=name)
        assert reason


@pytest.mark.parametrize("name", ["leapfrog", "glrk4", "glrk16", "variational_trapezoid"])
def test_reference_starts_where_the_compiled_step_starts(name):
    """Same starting values, same stopping rule: the same sweeps per step, on average.

    The mean over the run may differ a little: a sweep's verdict can flip where an increment
    sits at round-off, and the compiled stage sums of glrk8 and glrk12 carry padding columns
    that the rule also sees.
    """
    result = compare(get_method(name), model(3, "conservative"))
    assert result["sweeps"] > 2  # a non-separable chain: the equations are implicit
    assert abs(result["reference sweeps"] - result["sweeps"]) <= 0.2, result


@pytest.mark.parametrize("name", ["glrk8", "glrk16"])
def test_restarting_every_step_from_f_of_y_costs_sweeps(name):
    """Negative control of the one above: a reference that started every stage iteration from
    ``K_i = f(y)`` computes the same steps but needs clearly more sweeps than the compiled run
    (the continued polynomial is O(h^s) close, f(y) only O(h)). With two stages, glrk4, the
    saving is about half a sweep at these settings, too little for a margin."""
    alone = functools.partial(reference.implicit_runge_kutta, tableau=get_method(name).tableau)

    def from_f_of_y(field, t, q, p, h, previous=None):
        return alone(field, t, q, p, h)

    from_f_of_y.func = reference.implicit_runge_kutta
    compiled = compare(get_method(name), model(3, "conservative"))
    restarted = compare(get_method(name), model(3, "conservative"), step=from_f_of_y)
    assert restarted["ok"]  # the same steps to round-off ...
    assert restarted["reference sweeps"] > compiled["sweeps"] + 1.0, restarted  # ... dearer


# ---------------------------------------------------------------- negative controls
def test_a_wrong_weight_fails_the_agreement():
    """A slipped reference attached to the method (what the agreement test reads) fails."""
    swapped = ButcherTableau(a=RK4_TABLEAU.a, b=[1 / 6, 1 / 6, 1 / 3, 1 / 3])
    slipped = dataclasses.replace(get_method("rk4"),
                                  reference=reference.runge_kutta_reference(swapped))
    result = compare(slipped, model(2, "conservative"))
    assert not result["ok"] and result["single"] > 1e6, result
    assert compare(get_method("rk4"), model(2, "conservative"))["ok"]  # the right weights pass


def test_a_kick_at_the_wrong_time_fails_the_agreement():
    def late_kick_at_the_start_time(field, t, q, p, h):
        def kick(x):
            return p - h / 2 * field.H_q(t, q, x)

        p_half = reference.fixed_point(kick, kick(p))
        velocity = field.H_p(t, q, p_half)

        def drift_on(x):
            return q + h / 2 * velocity + h / 2 * field.H_p(t + h, x, p_half)

        q1 = reference.fixed_point(drift_on, q + h * velocity)
        return q1, p_half - h / 2 * field.H_q(t, q1, p_half)  # slip: t where t + h belongs

    leapfrog = get_method("leapfrog")
    result = compare(leapfrog, model(2, "driven"), step=late_kick_at_the_start_time)
    assert not result["ok"] and result["single"] > 1e6, result
    # without a drive the time does not matter: the check is about the slip, nothing else
    assert compare(leapfrog, model(2, "conservative"), step=late_kick_at_the_start_time)["ok"]


def test_an_iteration_stopped_early_fails_the_agreement():
    glrk4 = get_method("glrk4")
    solve = reference.fixed_point

    def three_sweeps(update, x, floor=0.0):
        for _ in range(3):
            x = update(x)
        return x

    reference.fixed_point = three_sweeps
    try:
        result = compare(glrk4, model(2, "conservative"))
    finally:
        reference.fixed_point = solve
    assert not result["ok"] and result["single"] > 1e3, result


# ---------------------------------------------------------------- the stopping rule
def compiled_solve(update, x, floor=0.0):
    """``x <- update(x)`` stopped by the compiled rule, as the compiled steps drive it.

    Returns the last iterate and the sweeps, or None for the iterate if the rule reported a
    non-finite iterate or never stopped.
    """
    x, smallest = np.asarray(x, float), np.full(np.size(x), np.inf)
    for sweep in range(1, MAX_SWEEPS + 1):
        new = update(x)
        status = fixed_point_status(np.ravel(new), np.ravel(x), smallest, floor)
        x = new
        if status != 0:
            return (x if status == 1 else None), sweep
    return None, MAX_SWEEPS


def reference_solve(update, x, floor=0.0):
    """The reference solver on the same iteration: its iterate and sweeps (None: it refused)."""
    with counted_sweeps() as sweeps:
        try:
            x = reference.fixed_point(update, np.asarray(x, float), floor)
        except ConvergenceError:
            x = None
    return x, sweeps[0]


def test_reference_solver_stops_where_the_compiled_rule_stops():
    c = 0.7390851332151607
    field = reference.ReferenceField(pl.hamiltonian_field(model(2, "conservative")))
    y = np.concatenate(start(get_method("glrk4"), model(2, "conservative")))

    def stages(K):
        return np.array([field.f(0.0, y + 0.05 * (row @ K)) for row in GAUSS4_TABLEAU.a])

    iterations = [
        (np.cos, [1.0, 0.2], 0.0),
        (lambda x: c + 1e-4 * (x - c), [c + 1.0], 0.0),  # predicted done before any stall
        (lambda x: c + 0.5 * (x - c), [c + 1.0], 0.0),  # stalls first
        (lambda x: np.array([1.0 + 1e-10]), [1.0], 1e5),  # a stall accepted thanks to the floor
        (stages, np.tile(field.f(0.0, y), (2, 1)), np.max(np.abs(y)) / 0.05),
        (lambda x: 0.5 * x, [1e-9], 0.0),  # small but still shrinking: never accepted
        (lambda x: 2.0 * x + 1.0, [1.0], 0.0),  # diverging
    ]
    for update, x, floor in iterations:
        (expected, expected_sweeps), (got, sweeps) = (solve(update, x, floor) for solve in
                                                      (compiled_solve, reference_solve))
        assert sweeps == expected_sweeps
        assert (got is None and expected is None) or np.array_equal(got, expected)
    assert reference_solve(lambda x: 0.5 * x, [1e-9])[0] is None

    # negative control: a plain tolerance stops elsewhere on the same iterations
    def tolerance_solve(update, x, floor=0.0):
        for sweep in range(1, MAX_SWEEPS + 1):
            x, old = update(x), x
            if np.all(np.abs(x - old) <= 1e-11 * (1 + np.abs(x))):
                return x, sweep
        return None, MAX_SWEEPS

    assert any(tolerance_solve(u, x, f)[1] != compiled_solve(u, x, f)[1]
               for u, x, f in iterations)


def test_reference_solver_refuses_what_does_not_converge():
    with pytest.raises(ConvergenceError, match="did not converge"):
        reference.fixed_point(lambda x: 2.0 * x + 1.0, np.array([1.0]))
    with np.errstate(over="ignore"), pytest.raises(ConvergenceError):
        reference.fixed_point(lambda x: np.exp(x * 1e3), np.array([1.0]))


def test_reference_field_is_checked_at_its_boundary():
    field = pl.hamiltonian_field(model(1, "conservative"))
    with pytest.raises(TypeError, match="`field` must be a HamiltonianField"):
        reference.ReferenceField("hamilton")
    with pytest.raises(ValueError, match="`member` must be an integer in"):
        reference.ReferenceField(field, member=1)
    with pytest.raises(TypeError, match="`tableau` must be a ButcherTableau"):
        reference.runge_kutta_reference([[0.5]])
    with pytest.raises(ValueError, match="no discrete Lagrangian"):
        reference.ReferenceField(pl.hamiltonian_field(model(1, "driven"))).discrete("midpoint")


def test_reference_for_a_tableau_outside_the_registry():
    """``Method.from_tableau`` attaches the reference to any tableau: the implicit midpoint."""
    midpoint = Method.from_tableau("implicit_midpoint", gauss_legendre_tableau(1), "midpoint")
    assert compare(midpoint, model(2, "conservative"))["ok"]


# ---------------------------------------------------------------- the table
def agreement_table() -> str:
    """Method x links x forcing: the largest misfits in units of ``eps max|y|``.

    Each cell: one step from the same state / along the run; then the largest absolute
    difference over the row's forcings. "-": the method does not apply to that field.
    """
    header = "  ".join(f"{f:>17s}" for f in FORCINGS)
    rows = [f"{'method':28s} {'n':>1s}  {header}  {'max |diff|':>10s}"]
    for name in NAMES:
        for n in LINKS:
            fits, _ = cases(name, n)
            cells, largest = [], 0.0
            for forcing in FORCINGS:
                if forcing not in fits:
                    cells.append(f"{'-':>17s}")
                    continue
                result = compare(get_method(name), model(n, forcing))
                mark = " " if result["ok"] else "!"
                cells.append(f"{result['single']:5.2f} / {result['run']:5.2f}{mark:>5s}")
                largest = max(largest, result["largest"])
            rows.append(f"{name:28s} {n:1d}  {'  '.join(cells)}  {largest:10.1e}")
    return "\n".join(rows)


if __name__ == "__main__":
    print(agreement_table())
