"""The integrators' mathematics: order, symplecticity, reversibility, energy.

Every property check is paired with a negative control: a method that must
fail the same check, so the check is shown able to fail.
"""

import dataclasses

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab import analysis
from pendulum_lab.driver.simulate import hamiltonian_field
from pendulum_lab.integrators import (
    GAUSS4_TABLEAU,
    GAUSS8_TABLEAU,
    GAUSS12_TABLEAU,
    GAUSS16_TABLEAU,
    RK4_TABLEAU,
    ButcherTableau,
    fixed_point_status,
    get_method,
    suitable_methods,
)

DP = pl.double_pendulum(m1=1.0, m2=1.0, l1=1.0, l2=1.0, g=9.81)
SP = pl.simple_pendulum(mass=1.0, length=1.0, g=9.81)
# The course's methods by their declared properties (Method.symplectic, Method.symmetric):
# a method registered tomorrow is checked for what it declares.
SYMPLECTIC = tuple(name for name, method in pl.METHODS.items() if method.symplectic)
NOT_SYMPLECTIC = tuple(name for name, method in pl.METHODS.items() if not method.symplectic)
SYMMETRIC = tuple(name for name, method in pl.METHODS.items() if method.symmetric)
NOT_SYMMETRIC = tuple(name for name, method in pl.METHODS.items() if not method.symmetric)


# ---------------------------------------------------------------- tableaus
@pytest.mark.parametrize("tableau", [RK4_TABLEAU, GAUSS4_TABLEAU])
def test_tableau_satisfies_order_four_conditions(tableau):
    a, b, c = tableau.a, tableau.b, tableau.c
    conditions = [
        (b.sum(), 1.0), (b @ c, 1 / 2), (b @ c**2, 1 / 3), (b @ a @ c, 1 / 6),
        (b @ c**3, 1 / 4), (b @ (c * (a @ c)), 1 / 8), (b @ a @ c**2, 1 / 12),
        (b @ a @ a @ c, 1 / 24),
    ]
    for value, expected in conditions:
        assert abs(value - expected) < 1e-15


def test_gauss_legendre_tableau_is_the_reports_and_is_implicit():
    r3 = np.sqrt(3)
    assert np.allclose(GAUSS4_TABLEAU.c, [0.5 - r3 / 6, 0.5 + r3 / 6], atol=0, rtol=1e-15)
    assert np.allclose(GAUSS4_TABLEAU.a, [[0.25, 0.25 - r3 / 6], [0.25 + r3 / 6, 0.25]])
    assert not GAUSS4_TABLEAU.explicit and RK4_TABLEAU.explicit


def collocation_conditions(tableau, stages):
    """Largest violation of B(2s) and C(s), the conditions that make collocation order 2s."""
    a, b, c = tableau.a, tableau.b, tableau.c
    quadrature = max(abs(b @ c ** (k - 1) - 1 / k) for k in range(1, 2 * stages + 1))
    stage_order = max(np.max(np.abs(a @ c ** (k - 1) - c**k / k)) for k in range(1, stages + 1))
    return max(quadrature, stage_order)


def test_gauss_tableaus_are_collocation_of_order_2s():
    assert collocation_conditions(GAUSS4_TABLEAU, 2) < 1e-15
    assert collocation_conditions(GAUSS8_TABLEAU, 4) < 1e-14
    assert GAUSS8_TABLEAU.order == 8 and GAUSS8_TABLEAU.stages == 4
    assert collocation_conditions(GAUSS12_TABLEAU, 6) < 1e-14
    assert GAUSS12_TABLEAU.order == 12 and GAUSS12_TABLEAU.stages == 6
    assert collocation_conditions(GAUSS16_TABLEAU, 8) < 1e-14
    assert GAUSS16_TABLEAU.order == 16 and GAUSS16_TABLEAU.stages == 8
    # negative control: RK4 is order 4 but not a 4-stage collocation method
    assert collocation_conditions(RK4_TABLEAU, 4) > 1e-3


def test_inconsistent_tableau_is_rejected():
    with pytest.raises(ValueError, match="sum to 1"):
        ButcherTableau(a=[[0, 0], [0.5, 0]], b=[0.5, 0.6], c=[0, 0.5])
    with pytest.raises(ValueError, match="row sums"):
        ButcherTableau(a=[[0, 0], [0.4, 0]], b=[0, 1], c=[0, 0.5])


def test_method_registry_properties():
    expected = {"explicit_euler": (1, False), "semi_implicit_euler": (1, True),
                "leapfrog": (2, True), "rk4": (4, False), "glrk4": (4, True),
                "glrk8": (8, True), "glrk12": (12, True), "glrk16": (16, True)}
    for name, (order, symplectic) in expected.items():
        method = pl.METHODS[name]
        assert (method.order, method.symplectic) == (order, symplectic)
    assert pl.METHODS["glrk4"].implicit and not pl.METHODS["rk4"].implicit
    for name in ("semi_implicit_euler_velocity", "leapfrog_velocity"):
        assert pl.METHODS[name].variables == "velocity" and not pl.METHODS[name].symplectic


# ---------------------------------------------------------------- order
@pytest.fixture(scope="module")
def dp_reference():
    return analysis.reference_solution(DP, [0.8, 1.2], [0.0, 0.0], t_end=1.0)


@pytest.fixture(scope="module")
def sp_reference():
    return analysis.reference_solution(SP, [1.2], [0.0], t_end=1.0)


ORDER_DTS = (0.01, 0.005, 0.0025, 0.00125)
# Order 4 stops a step earlier: the optimised compositions have error constants small enough
# that at 0.00125 their error (1e-13) meets the reference's and bends the fit.
ORDER4_DTS = ORDER_DTS[:3]
# Order 8 reaches round-off fast: larger steps, and a gentler start for the
# double pendulum so that these steps are in the asymptotic regime.
ORDER8_DTS = (0.125, 0.1, 0.0625, 0.05)


def order_setup(order: int, pendulum: str):
    """``(theta0, t_end, dts, tolerance, floor)`` of an order fit on ``pendulum``.

    The steps are in the asymptotic regime and the errors stay above the reference's (and
    above ``floor``, checked): the higher the order, the larger the steps and the wider the
    swings. An order with no setup fails the test, asking for one.
    """
    double = pendulum == "double"
    if order < 4:
        return ([0.8, 1.2] if double else [1.2]), 1.0, ORDER_DTS, 0.15, 0.0
    if order == 4:
        return ([0.8, 1.2] if double else [1.2]), 1.0, ORDER4_DTS, 0.15, 1e-13
    if order == 6:  # Yoshida's weights are large: steps of 0.05 are still asymptotic
        return ([0.8, 1.2] if double else [1.2]), 1.0, (0.05, 0.04, 0.025, 0.02), 0.15, 1e-13
    if order == 8:
        return ([0.5, 0.6] if double else [1.2]), 1.0, ORDER8_DTS, 0.3, 1e-13
    if order == 12:  # round-off faster still: larger steps and wider swings
        if double:
            return [1.0, 1.5], 2.0, (0.25, 0.2, 0.125, 0.1), 0.5, 1e-13
        return [2.5], 4.0, (0.4, 0.25, 0.2, 0.16), 0.5, 1e-13
    if order == 16:  # larger steps still (which fixed-point iteration on these swings solves)
        return ([0.5, 0.6] if double else [2.5]), 8.0, (0.5, 0.4, 0.32, 0.25), 0.5, 1e-12
    pytest.fail(f"no order-fit setup for order {order}: add one to order_setup")


PENDULUMS = {"simple": SP, "double": DP}


def order_fit(method, pendulum, references):
    """The observed order of ``method`` on ``pendulum``, with the setup of its declared order."""
    method = get_method(method)
    theta0, t_end, dts, tolerance, floor = order_setup(method.order, pendulum)
    model = PENDULUMS[pendulum]
    shared = references[pendulum] if t_end == 1.0 and theta0 in ([0.8, 1.2], [1.2]) else None
    result = analysis.observed_order(model, theta0, np.zeros(model.n), t_end=t_end, dts=dts,
                                     method=method, reference=shared)
    return result, tolerance, floor


@pytest.fixture(scope="module")
def references(dp_reference, sp_reference):
    return {"double": dp_reference, "simple": sp_reference}


@pytest.mark.parametrize("pendulum, name", [
    (pendulum, name) for pendulum, model in PENDULUMS.items()
    for name in suitable_methods(hamiltonian_field(model))
])
def test_every_method_has_its_declared_order(pendulum, name, references):
    """Every registered method that integrates the pendulum, at the order it declares.

    On one link the velocity methods' ``(theta, omega)`` are canonical up to a factor and the
    report's leapfrog is the canonical one: there they may exceed the order they declare for
    chains (second order, where two links give first).
    """
    result, tolerance, floor = order_fit(name, pendulum, references)
    order = get_method(name).order
    if get_method(name).variables == "velocity" and pendulum == "simple":
        assert result.slope >= order - tolerance, result
    else:
        assert abs(result.slope - order) <= tolerance, result
    assert result.errors[-1] > floor  # the fit stays above round-off


def test_a_method_declared_with_the_wrong_order_fails_the_order_test(references):
    # negative control: Yoshida's triple jump declared of order 6 is fitted at 4 (same name,
    # so its compiled loop is the one already on disk)
    wrong = dataclasses.replace(get_method("yoshida4"), order=6)
    result, tolerance, _ = order_fit(wrong, "double", references)
    assert abs(result.slope - wrong.order) > tolerance
    assert abs(result.slope - 4) <= tolerance


def test_velocity_leapfrog_is_only_first_order_on_the_double_pendulum(dp_reference):
    # The report's leapfrog on (theta, omega) evaluates a velocity-dependent
    # acceleration at a half-step Euler velocity: it loses an order.
    result = analysis.observed_order(DP, [0.8, 1.2], [0.0, 0.0], t_end=1.0, dts=ORDER_DTS,
                                     method="leapfrog_velocity", reference=dp_reference)
    assert abs(result.slope - 1.0) <= 0.15, result


# ---------------------------------------------------------------- symplecticity
Q0 = np.array([2.0, 2.5])
P0 = DP.momenta(Q0, [0.3, -0.2])


@pytest.mark.parametrize("name", SYMPLECTIC)
def test_symplectic_methods_preserve_the_symplectic_form(name):
    assert analysis.symplecticity_defect(DP, Q0, p0=P0, dt=0.05, method=name) <= 1e-8


@pytest.mark.parametrize("name", NOT_SYMPLECTIC)
def test_non_symplectic_methods_fail_the_same_check(name, method_tested):
    worst_symplectic = max(
        analysis.symplecticity_defect(DP, Q0, p0=P0, dt=0.05, method=m) for m in SYMPLECTIC
        if method_tested(m)
    )
    defect = analysis.symplecticity_defect(DP, Q0, p0=P0, dt=0.05, method=name)
    assert defect >= 100 * max(worst_symplectic, 1e-8)


def test_velocity_methods_are_symplectic_for_the_simple_pendulum():
    # With a constant mass matrix (theta, omega) are canonical up to a factor.
    for name in ("semi_implicit_euler_velocity", "leapfrog_velocity"):
        assert analysis.symplecticity_defect(SP, [2.0], p0=[0.5], dt=0.05, method=name) <= 1e-8


# ---------------------------------------------------------------- reversibility
@pytest.mark.parametrize("name", SYMMETRIC)
def test_symmetric_methods_are_reversible(name):
    assert analysis.reversibility_error(DP, Q0, p0=P0, dt=0.05, method=name) <= 1e-12


@pytest.mark.parametrize("name", NOT_SYMMETRIC)
def test_non_symmetric_methods_are_not_reversible(name):
    assert analysis.reversibility_error(DP, Q0, p0=P0, dt=0.05, method=name) > 1e-8


# ---------------------------------------------------------------- long-run energy
@pytest.fixture(scope="module")
def long_runs():
    return {name: pl.simulate(DP, [2.0, 2.5], [0.0, 0.0], t_end=1000.0, dt=0.01, method=name)
            for name in ("glrk4", "glrk8", "leapfrog", "rk4")}


@pytest.mark.parametrize("name", ["glrk4", "glrk8", "leapfrog"])
def test_symplectic_energy_error_stays_bounded(long_runs, name):
    first, last = analysis.energy_growth(long_runs[name])
    assert last <= 3 * first, (first, last)


def test_rk4_energy_error_grows(long_runs):
    first, last = analysis.energy_growth(long_runs["rk4"])
    assert last > 3 * first, (first, last)


# ---------------------------------------------------------------- against SciPy
@pytest.mark.parametrize("name, dt, tol", [("rk4", 0.001, 1e-8), ("glrk4", 0.002, 1e-8)])
def test_agreement_with_dop853(name, dt, tol):
    theta_ref, omega_ref = analysis.reference_solution(DP, [1.0, 1.5], [0.0, 0.0], t_end=5.0,
                                                      rtol=1e-12)
    traj = pl.simulate(DP, [1.0, 1.5], [0.0, 0.0], t_end=5.0, dt=dt, method=name)
    assert np.max(np.abs(traj.theta[-1] - theta_ref)) < tol
    assert np.max(np.abs(traj.omega[-1] - omega_ref)) < tol * 10


# ---------------------------------------------------------------- implicit solver
def iterate(g, x0, max_sweeps=100):
    """Drive the integrators' stopping rule the way the implicit steps do."""
    x, smallest = np.asarray(x0, float), np.full(np.shape(x0), np.inf)
    for sweep in range(1, max_sweeps + 1):
        x_new = g(x)
        status = fixed_point_status(x_new, x, smallest)
        x = x_new
        if status != 0:
            return x, sweep, status
    return x, max_sweeps, 0


def test_stopping_rule_iterates_to_roundoff():
    x, sweeps, status = iterate(np.cos, [1.0, 0.2])
    assert status == 1 and sweeps < 100
    assert np.max(np.abs(x - 0.7390851332151607)) < 1e-15


def test_stopping_rule_does_not_stop_on_a_small_but_shrinking_increment():
    # x <- x/2 from 1e-9: increments drop below the round-off tolerance after a
    # few sweeps but keep halving. A max-norm tolerance stops there; our rule
    # keeps going while any increment still shrinks.
    halve = lambda x: 0.5 * x  # noqa: E731
    x, sweeps, status = iterate(halve, [1e-9], max_sweeps=30)
    assert status == 0 and x[0] < 1e-17
    tolerance_stop = next(k for k in range(1, 30) if 1e-9 * 0.5**k <= 1e-11)
    assert tolerance_stop < 10


def test_stopping_rule_stops_once_the_rest_is_below_half_an_ulp():
    # x <- c + r (x - c) converges at rate r. With r = 1e-4 the increments are
    # 1e-4, 1e-8, 1e-12, 1e-16: after the fourth the predicted rest is far below
    # an ulp of c, so the rule stops there instead of waiting for a stall.
    c = 0.7390851332151607
    x, sweeps, status = iterate(lambda x: c + 1e-4 * (x - c), [c + 1.0])
    assert status == 1 and sweeps <= 5
    assert abs(x[0] - c) <= np.spacing(c)
    # negative control: at rate 0.5 the rest is never below an ulp before the
    # increments stall, so the rule needs many more sweeps
    _, slow_sweeps, slow_status = iterate(lambda x: c + 0.5 * (x - c), [c + 1.0])
    assert slow_status == 1 and slow_sweeps > 40


def test_stopping_rule_reports_divergence_and_non_finite():
    _, sweeps, status = iterate(lambda x: 2.0 * x + 1.0, [1.0], max_sweeps=50)
    assert status == 0 and sweeps == 50  # never accepted
    with np.errstate(over="ignore"):
        _, _, status = iterate(lambda x: np.exp(x * 1e3), [1.0])
    assert status == -1


def test_stopping_rule_floor_accepts_a_stall_at_the_round_off_of_larger_numbers():
    # Iterates near 1 stalled at 1e-10: far above their own round-off, so the
    # rule keeps going (the iteration may be diverging) ...
    old, new = np.array([1.0]), np.array([1.0 + 1e-10])
    assert fixed_point_status(new, old, np.array([1e-10])) == 0
    # ... unless they are combined with numbers of size 1e5 (the floor), whose
    # last place is 1.5e-11: then 1e-10 is round-off and the stall is accepted.
    assert fixed_point_status(new, old, np.array([1e-10]), 1e5) == 1


@pytest.mark.parametrize("name", ["glrk4", "glrk8"])
def test_gauss_steps_converge_at_angles_of_many_turns(name):
    """Far from theta = 0 a stage's slopes stall at the round-off of the angles.

    The start is (2, 2.5) plus 16000 and 32000 whole turns (about 1e5 and 2e5
    rad, as a long run of a rotating pendulum reaches): the same motion. Before
    the stopping rule judged slopes against the state (its ``floor``), the
    stall was taken for divergence and the run refused with ConvergenceError.
    """
    turns = 2 * np.pi * np.array([16000.0, 32000.0])
    far = pl.simulate(DP, np.array([2.0, 2.5]) + turns, [0.0, 0.0], t_end=2.0, dt=0.01,
                      method=name)
    near = pl.simulate(DP, [2.0, 2.5], [0.0, 0.0], t_end=2.0, dt=0.01, method=name)
    # the same motion, to the round-off of the angles (2e5 * 2.2e-16 = 4e-11 per step)
    difference = np.max(np.abs((far.theta - turns) - near.theta))
    assert difference < 1e-9
    assert difference > 0  # negative control: the large angles do round differently


def test_glrk4_too_large_dt_raises_naming_step_and_time():
    with pytest.raises(pl.ConvergenceError, match=r"at step \d+ \(t = [0-9.]+"):
        pl.simulate(DP, [2.0, 2.5], [0.0, 0.0], t_end=20.0, dt=0.6, method="glrk4")


@pytest.mark.parametrize("name, tableau", [("glrk4", GAUSS4_TABLEAU), ("glrk8", GAUSS8_TABLEAU),
                                          ("glrk12", GAUSS12_TABLEAU),
                                          ("glrk16", GAUSS16_TABLEAU)])
def test_gauss_step_solves_the_collocation_equations(name, tableau):
    """The step equals the one whose stages SciPy solves independently.

    A fast-moving state and a large step, where the stage equations are far
    from their first guess; fsolve (the course report's solver) on the stage
    equations in (theta, p) gives the reference.
    """
    from scipy.optimize import fsolve

    field = hamiltonian_field(DP)
    q, p, h = np.array([0.3, -1.0]), DP.momenta([0.3, -1.0], [4.0, -6.0]), 0.08
    stages = tableau.stages

    def f(y):
        dq, dp = np.empty(2), np.empty(2)
        field.hamilton(0.0, y[:2].copy(), y[2:].copy(), field.params, dq, dp)
        return np.concatenate([dq, dp])

    y = np.concatenate([q, p])

    def residual(flat):
        k = flat.reshape(stages, 4)
        return (k - np.array([f(y + h * tableau.a[i] @ k) for i in range(stages)])).ravel()

    slopes = fsolve(residual, np.tile(f(y), stages), xtol=1e-14)
    assert np.max(np.abs(residual(slopes))) < 1e-11
    expected = y + h * tableau.b @ slopes.reshape(stages, 4)
    q1, p1 = pl.step(DP, q, p0=p, dt=h, method=name)
    assert np.max(np.abs(np.concatenate([q1, p1]) - expected)) < 1e-12
    # negative control: an explicit method of the same order is a different map
    q_rk, p_rk = pl.step(DP, q, p0=p, dt=h, method="rk4")
    assert np.max(np.abs(np.concatenate([q_rk, p_rk]) - expected)) > 1e-6


def test_symplectic_methods_are_explicit_for_the_separable_simple_pendulum():
    for name in ("semi_implicit_euler", "leapfrog"):
        traj = pl.simulate(SP, [1.0], [0.0], t_end=1.0, dt=0.01, method=name)
        assert traj.mean_iterations == 0
    traj = pl.simulate(DP, [1.0, 1.0], [0.0, 0.0], t_end=1.0, dt=0.01, method="leapfrog")
    assert traj.mean_iterations > 2


def test_compensated_summation_keeps_what_rounding_loses():
    """Adding 1e-16 to 1.0 a million times: rounding loses every increment, compensation none."""
    from pendulum_lab.integrators.runge_kutta import compensated_sum

    compensation = np.zeros(1)
    compensated = plain = 1.0
    for _ in range(10**5):
        compensated = compensated_sum(compensated, 1e-16, compensation, 0)
        plain = plain + 1e-16
    assert plain == 1.0  # negative control: the plain sum never moves
    assert abs(compensated + compensation[0] - (1.0 + 1e-11)) < 1e-16


@pytest.mark.parametrize("name, saved", [("glrk4", 0.9), ("glrk8", 0.7), ("glrk12", 0.5),
                                         ("glrk16", 0.5)])
def test_starting_values_save_sweeps_and_change_nothing_but_roundoff(name, saved):
    """A run starts each step from the last one's collocation polynomial; ``pl.step`` from f(y).

    Both iterate the stage equations to round-off, so the states agree to
    round-off, but the run needs fewer sweeps, the more so the more stages
    (the guess is O(h^s) close [HLW VIII.6.1]).
    """
    q, p, h, steps = np.array([2.0, 2.5]), DP.momenta([2.0, 2.5], [0.0, 0.0]), 0.005, 20
    run = pl.simulate(DP, q, p0=p, t_end=steps * h, dt=h, method=name)
    alone = []
    for _ in range(steps):
        alone.append(pl.simulate(DP, q, p0=p, t_end=h, dt=h, method=name).mean_iterations)
        q, p = pl.step(DP, q, p0=p, dt=h, method=name)
    assert np.max(np.abs(run.theta[-1] - q)) < 1e-12
    assert np.max(np.abs(run.p[-1] - p)) < 1e-12
    assert run.mean_iterations * steps < saved * sum(alone)
    # control: a run's first step has nothing to continue and costs what a lone step does
    first = pl.simulate(DP, [2.0, 2.5], [0.0, 0.0], t_end=h, dt=h, method=name)
    assert first.mean_iterations == alone[0]


def test_simple_pendulum_symplectic_euler_is_the_textbook_update():
    q, p, h = np.array([0.7]), np.array([0.3]), 0.1
    q1, p1 = pl.step(SP, q, p0=p, dt=h, method="semi_implicit_euler")
    p_expected = p - h * 9.81 * np.sin(q)
    assert np.allclose(p1, p_expected, rtol=0, atol=1e-15)
    assert np.allclose(q1, q + h * p_expected, rtol=0, atol=1e-15)


def test_stage_iteration_contracts_in_proportion_to_the_step():
    from pendulum_lab.analysis import stage_contraction
    from pendulum_lab.integrators import GAUSS4_TABLEAU, RK4_TABLEAU

    dp = pl.double_pendulum()
    steps = np.geomspace(0.001, 0.05, 7)
    runs = [stage_contraction(dp, [2.0, 2.5], [0.0, 0.0], dt=h) for h in steps]
    measured = np.array([r.contraction for r in runs])
    slope = np.polyfit(np.log(steps), np.log(measured), 1)[0]
    assert 0.85 < slope < 1.15  # the factor per sweep is proportional to h
    # and close to h rho(A) rho(df/dy), rho(A) = sqrt(3)/6 for two-stage Gauss-Legendre
    predicted = np.array([r.predicted for r in runs])
    assert np.all(np.abs(np.log(measured / predicted)) < np.log(1.5))
    rho_a = np.max(np.abs(np.linalg.eigvals(GAUSS4_TABLEAU.a)))
    rho_f = np.max(np.abs(np.linalg.eigvals(dp.jacobian([2.0, 2.5], dp.momenta([2.0, 2.5],
                                                                                [0.0, 0.0])))))
    assert rho_a == pytest.approx(np.sqrt(3) / 6)
    assert runs[0].predicted == pytest.approx(steps[0] * rho_a * rho_f)
    # Negative control: RK4's strictly lower triangular A is nilpotent, so the same iteration
    # ends exactly (increment 0) after at most four sweeps instead of contracting.
    rk4 = stage_contraction(dp, [2.0, 2.5], [0.0, 0.0], dt=0.01, tableau=RK4_TABLEAU)
    assert rk4.predicted == 0.0 and len(rk4.increments) <= 4 and rk4.increments[-1] == 0.0
    assert len(runs[3].increments) > 4
    with pytest.raises(TypeError, match="`tableau`"):
        stage_contraction(dp, [2.0, 2.5], [0.0, 0.0], dt=0.01, tableau="gauss")


def test_generated_modules_are_made_once_per_text():
    """Two cache entries for one kernel module must give the same kernels, or the loops
    compiled with the field's kernels (imported by name) would see other objects."""
    from pendulum_lab import codegen

    first, second = codegen.load_kernels(2), codegen.load_kernels(2, False)
    assert first.hamilton is second.hamilton
    run = pl.simulate(DP, [2.0, 2.5], [0.0, 0.0], t_end=0.1, dt=0.01, method="rk4")
    assert run.completed
    # negative control: another chain is another module
    assert codegen.load_kernels(1).hamilton is not first.hamilton
