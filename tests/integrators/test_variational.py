"""Variational integrators as methods of pl.simulate (notebook 15).

Each property is checked with a negative control: a method that must fail the
same check. The coincidences are checked to round-off, and the one that does
not hold (trapezoid against the generalized leapfrog when M varies) is shown
to fail at O(h^3) per step, with its cause.
"""

import numpy as np
import pytest
import sympy as sp

import pendulum_lab as pl
from pendulum_lab import analysis, codegen
from pendulum_lab import discrete_mechanics as dm
from pendulum_lab.integrators import (
    VARIATIONAL_METHODS,
    Method,
    gauss_legendre_tableau,
    variational_method,
)
from pendulum_lab.integrators.source import method_source

SP = pl.simple_pendulum(mass=0.8, length=1.2, g=9.81)
DP = pl.double_pendulum(m1=1.0, m2=1.5, l1=1.0, l2=0.7, g=9.81)
NAMES = ("variational_midpoint", "variational_trapezoid")
Q0 = np.array([2.0, 2.5])
P0 = DP.momenta(Q0, [0.3, -0.2])
# The implicit midpoint rule: the one-stage Gauss-Legendre method.
IMPLICIT_MIDPOINT = Method.from_tableau("implicit_midpoint", gauss_legendre_tableau(1),
                                        "implicit midpoint rule")


def distance(a, b):
    """Max-norm distance of two states ``(theta, p)``."""
    return float(np.max(np.abs(np.concatenate([a[0] - b[0], a[1] - b[1]]))))


def steps(model, method, theta, p, dt, count):
    for _ in range(count):
        theta, p = pl.step(model, theta, p0=p, dt=dt, method=method)
    return theta, p


# ---------------------------------------------------------------- registry
def test_registered_with_their_properties_apart_from_the_course_table():
    assert set(VARIATIONAL_METHODS) == set(NAMES)
    for name in NAMES:
        method = pl.get_method(name)
        assert method is VARIATIONAL_METHODS[name]
        assert (method.order, method.symplectic, method.implicit) == (2, True, True)
        assert method.variables == "canonical" and method.rule == name.split("_")[1]
        assert name not in pl.METHODS and name not in pl.CONFORMAL_METHODS
    shown = method_source("variational_midpoint")
    assert "def variational(" in shown and "rule='midpoint'" in shown


def test_generated_kernels_print_the_discrete_legendre_transforms():
    kernels = codegen.load_discrete_kernels(2, "trapezoid")
    for name in ("fixed_point_update", "newton_update", "impulse"):
        assert f"def {name}(" in kernels.source
    assert kernels.path.exists() and kernels.path.read_text() == kernels.source


# ---------------------------------------------------------------- against the reference solver
@pytest.mark.parametrize("rule", dm.RULES)
@pytest.mark.parametrize("solver", ["newton", "fixed_point"])
@pytest.mark.parametrize("model, theta, p", [(SP, [2.0], [0.5]), (DP, [1.0, 1.5], [0.3, -0.2]),
                                             (pl.n_pendulum(3), [0.4, -0.3, 0.8],
                                              [0.2, -0.1, 0.3])])
def test_compiled_step_solves_the_same_equations_as_the_reference(rule, solver, model, theta, p):
    """The slow SymPy/Newton reference and the generated kernels give the same step."""
    expected = dm.reference_step(model.n, rule, model.parameter_values, theta, p, 0.05)
    got = pl.step(model, theta, p0=p, dt=0.05, method=variational_method(rule, solver))
    assert distance(got, expected) < 1e-12
    # negative control: the other rule is another map
    other = dm.RULES[1 - dm.RULES.index(rule)]
    assert distance(dm.reference_step(model.n, other, model.parameter_values, theta, p, 0.05),
                    expected) > 1e-7


# ---------------------------------------------------------------- order
@pytest.fixture(scope="module")
def references():
    return {1: analysis.reference_solution(SP, [1.2], [0.0], t_end=1.0),
            2: analysis.reference_solution(DP, [0.8, 1.2], [0.0, 0.0], t_end=1.0)}


ORDER_DTS = (0.01, 0.005, 0.0025, 0.00125)


@pytest.mark.parametrize("name", [*NAMES, "semi_implicit_euler"])
@pytest.mark.parametrize("model, theta0", [(SP, [1.2]), (DP, [0.8, 1.2])])
def test_observed_order_is_two(name, model, theta0, references):
    result = analysis.observed_order(model, theta0, np.zeros(model.n), t_end=1.0, dts=ORDER_DTS,
                                     method=name, reference=references[model.n])
    if name in NAMES:
        assert abs(result.slope - 2) <= 0.15, result
    else:  # negative control: a first-order method fails the same check
        assert abs(result.slope - 2) > 0.8, result


# ---------------------------------------------------------------- structure
@pytest.mark.parametrize("name", NAMES)
def test_symplectic_in_canonical_variables(name):
    defects = [analysis.symplecticity_defect(DP, Q0, p0=P0, dt=0.05, method=name),
               analysis.symplecticity_defect(SP, [2.0], p0=[0.5], dt=0.05, method=name)]
    assert max(defects) <= 1e-8, defects
    # negative control: RK4, same field and step, is not symplectic
    control = analysis.symplecticity_defect(DP, Q0, p0=P0, dt=0.05, method="rk4")
    assert control >= 100 * max(max(defects), 1e-8)


@pytest.mark.parametrize("name", NAMES)
def test_symmetric_hence_reversible(name):
    assert analysis.reversibility_error(DP, Q0, p0=P0, dt=0.05, method=name) <= 1e-12
    # negative control: symplectic Euler is symplectic but not symmetric
    assert analysis.reversibility_error(DP, Q0, p0=P0, dt=0.05,
                                        method="semi_implicit_euler") > 1e-8


@pytest.fixture(scope="module")
def long_runs():
    return {name: pl.simulate(DP, [2.0, 2.5], [0.0, 0.0], t_end=1000.0, dt=0.01, method=name)
            for name in (*NAMES, "rk4")}


@pytest.mark.parametrize("name", NAMES)
def test_energy_error_stays_bounded_over_1000_s(long_runs, name):
    first, last = analysis.energy_growth(long_runs[name])
    assert last <= 3 * first, (first, last)
    # negative control: RK4's error drifts on the same run
    rk4_first, rk4_last = analysis.energy_growth(long_runs["rk4"])
    assert rk4_last > 3 * rk4_first, (rk4_first, rk4_last)


# ---------------------------------------------------------------- coincidences
@pytest.mark.parametrize("model, theta, p", [(SP, [2.0], [0.5]), (DP, [1.0, 1.5], [0.3, -0.2])])
def test_midpoint_rule_is_the_implicit_midpoint_rule(model, theta, p):
    """For any L = T - V: p_k and p_(k+1) average to M(q_mid) v and differ by h L_q there."""
    theta, p = np.array(theta), np.array(p)
    variational = steps(model, "variational_midpoint", theta, p, 0.1, 50)
    assert distance(variational, steps(model, IMPLICIT_MIDPOINT, theta, p, 0.1, 50)) < 1e-12
    # negative control: the trapezoid rule is not the implicit midpoint rule
    assert distance(steps(model, "variational_trapezoid", theta, p, 0.1, 50),
                    variational) > 1e-4


def test_trapezoid_is_the_leapfrog_for_one_link():
    theta, p = np.array([2.0]), np.array([0.5])
    trapezoid = steps(SP, "variational_trapezoid", theta, p, 0.1, 50)
    assert distance(trapezoid, steps(SP, "leapfrog", theta, p, 0.1, 50)) < 1e-12


def test_trapezoid_differs_from_the_leapfrog_by_h3_when_the_mass_matrix_varies():
    theta, p = np.array([1.0, 1.5]), np.array([0.3, -0.2])
    misses = [distance(pl.step(DP, theta, p0=p, dt=h, method="variational_trapezoid"),
                       pl.step(DP, theta, p0=p, dt=h, method="leapfrog"))
              for h in (0.04, 0.02, 0.01)]
    assert misses[-1] > 1e-7  # far above round-off: two methods
    ratios = np.array(misses[:-1]) / np.array(misses[1:])
    assert np.all((6.5 < ratios) & (ratios < 9.5)), ratios  # O(h^3) per step


def test_why_the_trapezoid_is_not_the_leapfrog():
    """The trapezoid averages M over the step, the leapfrog M^-1: equal only if M is constant.

    Trapezoid: v = Mbar^-1 pbar with Mbar = (M(q0) + M(q1)) / 2 (symbolic check
    on the discrete Lagrangian); leapfrog: v = (M(q0)^-1 + M(q1)^-1) / 2 p_half.
    The two averages differ by O(|M(q1) - M(q0)|^2) = O(h^2), hence q1 by O(h^3).
    """
    for n in (1, 2):
        dl = dm.discrete_lagrangian(n, "trapezoid")
        ends = [dl.chain.mass_matrix.xreplace(dict(zip(dl.chain.q, q)))
                for q in (dl.q, dl.q_next)]
        assert sp.simplify(dl.mean_mass - (ends[0] + ends[1]) / 2) == sp.zeros(n, n)
    gaps = []
    for model, theta, omega in ((SP, [1.0], [2.0]), (DP, [1.0, 1.5], [2.0, -3.0])):
        theta, omega = np.array(theta), np.array(omega)
        for h in (0.02, 0.01):
            a, b = model.mass_matrix_at(theta), model.mass_matrix_at(theta + h * omega)
            harmonic = np.linalg.inv((np.linalg.inv(a) + np.linalg.inv(b)) / 2)
            gaps.append(np.max(np.abs((a + b) / 2 - harmonic)))
    assert max(gaps[:2]) < 1e-14  # one link: M is constant, the averages agree
    assert gaps[2] > 1e-6 and 3.5 < gaps[2] / gaps[3] < 4.5  # two links: O(h^2)


# ---------------------------------------------------------------- the solver
@pytest.mark.parametrize("rule", dm.RULES)
def test_fixed_point_and_newton_solve_to_the_same_roundoff(rule):
    theta, p = np.array([0.3, -1.0]), DP.momenta([0.3, -1.0], [4.0, -6.0])
    for h in (0.01, 0.05, 0.1):
        newton = pl.step(DP, theta, p0=p, dt=h, method=variational_method(rule, "newton"))
        fixed = pl.step(DP, theta, p0=p, dt=h, method=variational_method(rule, "fixed_point"))
        assert distance(newton, fixed) < 1e-13
    # Newton needs fewer iterations per step
    runs = {solver: pl.simulate(DP, [2.0, 2.5], [0.0, 0.0], t_end=2.0, dt=0.02,
                                method=variational_method(rule, solver))
            for solver in ("newton", "fixed_point")}
    assert runs["newton"].mean_iterations < runs["fixed_point"].mean_iterations


def test_newton_can_leave_the_branch_where_fixed_point_iteration_stays_or_stops():
    """Why the registry iterates to a fixed point: robustness at large steps.

    Trapezoid rule, a fast state of the double pendulum. At h = 0.3 the
    discrete equations have two nearby roots (the step is near a fold, beyond
    which the small-step solution stops existing). Fixed-point iteration finds
    the one that continues the small-step solution; Newton's method from the
    same start finds the other; beyond the fold (h = 0.4) fixed-point iteration
    raises, while Newton's method converges again for larger steps, to roots
    on other branches.
    """
    theta, omega = np.array([0.3, -1.0]), np.array([4.0, -6.0])
    p = DP.momenta(theta, omega)
    newton, fixed = (variational_method("trapezoid", s) for s in ("newton", "fixed_point"))
    branch = [pl.step(DP, theta, p0=p, dt=h, method=fixed)[0] for h in (0.2, 0.25, 0.3)]
    jump = np.max(np.abs(branch[2] - branch[1]))
    assert jump < 2.0 * np.max(np.abs(branch[1] - branch[0]))  # a smooth continuation
    root = pl.step(DP, theta, p0=p, dt=0.3, method=newton)[0]
    assert np.max(np.abs(root - branch[2])) > 0.1
    # both are roots: each is a fixed point of the other solver's update
    kernels = codegen.load_discrete_kernels(2, "trapezoid")
    params = np.array(list(DP.parameter_values.values()))
    for q1 in (root, branch[2]):
        out = np.empty(2)
        kernels.fixed_point_update(0.3, theta, np.array(q1), params, p, out)
        assert np.max(np.abs(out - q1)) < 1e-12
    with pytest.raises(pl.ConvergenceError, match="variational_trapezoid"):
        pl.step(DP, theta, p0=p, dt=0.4, method=fixed)
    assert np.all(np.isfinite(pl.step(DP, theta, p0=p, dt=0.6, method=newton)[0]))
    # negative control: at small steps the two solvers agree (previous test)


# ---------------------------------------------------------------- bad input
def test_unforced_chains_only():
    damped = pl.driven_pendulum()
    for name in NAMES:
        with pytest.raises(ValueError, match="assumes a Hamiltonian vector field"):
            pl.simulate(damped, [0.1], [0.0], t_end=1.0, dt=0.1, method=name)
        with pytest.raises(ValueError, match="a drive, damping or a shaken pivot is not part"):
            pl.step(damped.replace(damping=0.0), [0.1], [0.0], dt=0.1, method=name)
    # negative control: the conservative pendulum is accepted
    assert pl.step(SP, [0.1], [0.0], dt=0.1, method=NAMES[0])[0].shape == (1,)


def test_unknown_rule_or_solver():
    with pytest.raises(ValueError, match="`rule` must be 'midpoint' or 'trapezoid'"):
        variational_method("simpson", "newton")
    with pytest.raises(ValueError, match="`solver` must be 'fixed_point' or 'newton'"):
        variational_method("midpoint", "secant")
    with pytest.raises(ValueError, match="variational_midpoint"):
        pl.get_method("variational_simpson")  # the message lists the registered names


# ---------------------------------------------------------------- momentum, not velocity
def test_the_discrete_momentum_is_handed_from_step_to_step_and_is_the_runs_p():
    run = pl.simulate(DP, [1.0, 1.5], [0.3, -0.2], t_end=1.0, dt=0.01,
                      method="variational_trapezoid")
    start, end = dm.discrete_momenta(2, "trapezoid", DP.parameter_values, run.theta[:-1],
                                     run.theta[1:], run.dt)
    assert np.max(np.abs(end[:-1] - start[1:])) < 1e-12  # the discrete Euler-Lagrange equation
    assert np.max(np.abs(start - run.p[:-1])) < 1e-12
    assert np.max(np.abs(end - run.p[1:])) < 1e-12
    # negative control: the step velocities on both sides of a configuration differ
    velocities = np.diff(run.theta, axis=0) / run.dt
    assert np.max(np.abs(np.diff(velocities, axis=0))) > 1e-2
    # and the transforms of the other rule do not match this run
    other, _ = dm.discrete_momenta(2, "midpoint", DP.parameter_values, run.theta[:-1],
                                   run.theta[1:], run.dt)
    assert np.max(np.abs(other - run.p[:-1])) > 1e-6


@pytest.mark.parametrize("name", ["variational_midpoint", "glrk8"])
def test_theta_omega_are_canonical_for_one_link_only(name):
    """A symplectic step stays symplectic in (theta, omega) when M is constant, not otherwise."""
    one = analysis.symplecticity_defect(SP, [2.0], [0.5], dt=0.05, method=name,
                                        variables="velocity")
    assert one <= 1e-8
    two = [analysis.symplecticity_defect(DP, [1.0, 1.5], [0.3, -0.2], dt=h, method=name,
                                         variables="velocity") for h in (0.05, 0.025)]
    assert two[1] > 1e-2 and 1.7 < two[0] / two[1] < 2.3  # O(h): the coordinates, not the method
    # negative control: the same steps in (theta, p)
    assert analysis.symplecticity_defect(DP, [1.0, 1.5], [0.3, -0.2], dt=0.05,
                                         method=name) <= 1e-8
    with pytest.raises(ValueError, match="`variables`"):
        analysis.symplecticity_defect(SP, [2.0], [0.5], dt=0.05, method=name, variables="omega")


def test_finite_difference_jacobian_of_a_linear_map_is_its_matrix():
    matrix = np.array([[1.0, 2.0, 0.0], [0.5, -1.0, 3.0]])
    jac = analysis.finite_difference_jacobian(lambda z: matrix @ z, [0.3, -0.2, 1.0])
    assert jac.shape == (2, 3) and np.max(np.abs(jac - matrix)) < 1e-9
    # negative control: a nonlinear map's Jacobian depends on the point
    square = analysis.finite_difference_jacobian(lambda z: z**2, [1.0, 2.0])
    assert np.max(np.abs(square - np.diag([2.0, 4.0]))) < 1e-8
    with pytest.raises(ValueError, match="`z`"):
        analysis.finite_difference_jacobian(lambda z: z, [[1.0]])
