"""Butcher tableaus as data: the conditions they satisfy and the registry entries made from them.

Each condition is shown to hold where the theory says so and, as the negative
control, to fail where it must.
"""

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab.integrators import METHODS, Method
from pendulum_lab.integrators.tableau import ButcherTableau, gauss_legendre_tableau, rooted_trees

RK4 = METHODS["rk4"].tableau
GAUSS = {s: gauss_legendre_tableau(s) for s in (1, 2, 3, 4, 6)}
# Two tableaus from the literature that no registry entry uses.
THREE_EIGHTHS = ButcherTableau(  # Kutta's 3/8 rule: order 4
    a=[[0, 0, 0, 0], [1 / 3, 0, 0, 0], [-1 / 3, 1, 0, 0], [1, -1, 1, 0]],
    b=[1 / 8, 3 / 8, 3 / 8, 1 / 8],
)
HEUN3 = ButcherTableau(a=[[0, 0, 0], [1 / 3, 0, 0], [0, 2 / 3, 0]], b=[1 / 4, 0, 3 / 4])
TRAPEZOIDAL = ButcherTableau(a=[[0, 0], [0.5, 0.5]], b=[0.5, 0.5])


def test_rooted_tree_counts_are_the_known_sequence():
    # OEIS A000081: the number of rooted trees with k vertices
    assert [len(rooted_trees(k)) for k in range(1, 10)] == [1, 1, 2, 4, 9, 20, 48, 115, 286]
    assert len(set(rooted_trees(6))) == 20  # no tree counted twice


@pytest.mark.parametrize("stages", [1, 2, 3, 4, 6])
def test_gauss_satisfies_symplectic_and_simplifying_conditions(stages):
    tableau = GAUSS[stages]
    for condition in (
        tableau.symplectic_condition(),
        tableau.quadrature_condition(2 * stages),
        tableau.stage_condition(stages),
        tableau.adjoint_stage_condition(stages),
    ):
        assert condition.holds and condition.largest < 1e-14
    assert tableau.symplectic_condition().defect.shape == (stages, stages)
    assert tableau.is_collocation
    # B(2s) is the most a quadrature with s nodes can do
    assert not tableau.quadrature_condition(2 * stages + 1).holds


def test_rk4_fails_the_symplectic_and_collocation_conditions():
    assert not RK4.symplectic_condition().holds
    assert RK4.symplectic_condition().largest > 0.1
    assert not RK4.stage_condition(2).holds and not RK4.is_collocation
    # but it does integrate cubics: B(4), and D(1)
    assert RK4.quadrature_condition(4).holds and not RK4.quadrature_condition(5).holds
    assert RK4.adjoint_stage_condition(1).holds


def test_conditions_equal_their_definitions():
    """The vectorised defects against the sums written out term by term."""
    for tableau in (RK4, GAUSS[3], HEUN3):
        a, b, c, s = tableau.a, tableau.b, tableau.c, tableau.stages
        m = [[b[i] * a[i, j] + b[j] * a[j, i] - b[i] * b[j] for j in range(s)] for i in range(s)]
        assert np.allclose(tableau.symplectic_condition().defect, m, rtol=0, atol=1e-15)
        quad = [sum(b[i] * c[i] ** (k - 1) for i in range(s)) - 1 / k for k in (1, 2, 3)]
        assert np.allclose(tableau.quadrature_condition(3).defect, quad, rtol=0, atol=1e-15)
        stage = [[sum(a[i, j] * c[j] ** (k - 1) for j in range(s)) - c[i] ** k / k
                  for k in (1, 2)] for i in range(s)]
        assert np.allclose(tableau.stage_condition(2).defect, stage, rtol=0, atol=1e-15)
        adjoint = [[sum(b[i] * c[i] ** (k - 1) * a[i, j] for i in range(s))
                    - b[j] * (1 - c[j] ** k) / k for k in (1, 2)] for j in range(s)]
        assert np.allclose(tableau.adjoint_stage_condition(2).defect, adjoint, rtol=0, atol=1e-15)


@pytest.mark.parametrize(
    "tableau, order",
    [(METHODS["explicit_euler"].tableau, 1), (HEUN3, 3), (RK4, 4), (THREE_EIGHTHS, 4),
     (TRAPEZOIDAL, 2), (GAUSS[1], 2), (GAUSS[2], 4), (GAUSS[3], 6), (GAUSS[4], 8),
     (GAUSS[6], 12)],
)
def test_order_is_derived_from_the_order_conditions(tableau, order):
    assert tableau.order == order
    assert all(tableau.order_condition(k).holds for k in range(1, order + 1))


def test_a_perturbed_tableau_loses_its_order():
    # negative control: move one coefficient of RK4 (keeping c the row sums)
    a = RK4.a.copy()
    a[3, 2], a[3, 1] = 0.9, 0.1
    assert ButcherTableau(a=a, b=RK4.b).order == 3
    a = RK4.a.copy()
    a[2, 1], a[2, 0] = 0.4, 0.1
    assert ButcherTableau(a=a, b=RK4.b).order == 2


def test_trapezoidal_rule_is_not_symplectic_but_the_midpoint_rule_is():
    assert not TRAPEZOIDAL.symplectic_condition().holds
    assert TRAPEZOIDAL.symplectic_condition().largest == pytest.approx(0.25, abs=1e-16)
    assert GAUSS[1].symplectic_condition().holds  # the midpoint rule


def test_bad_tableaus_and_arguments_are_rejected():
    with pytest.raises(ValueError, match="sum to 1"):
        ButcherTableau(a=[[0, 0], [0.5, 0]], b=[0.5, 0.6])
    with pytest.raises(ValueError, match="row sums"):
        ButcherTableau(a=[[0, 0], [0.4, 0]], b=[0, 1], c=[0, 0.5])
    with pytest.raises(ValueError, match="shapes"):
        ButcherTableau(a=[[0, 0], [0.5, 0]], b=[1.0])
    with pytest.raises(ValueError, match="`p`"):
        RK4.quadrature_condition(0)
    with pytest.raises(ValueError, match="`stages`"):
        gauss_legendre_tableau(0)


@pytest.mark.parametrize("name", ["explicit_euler", "rk4", "glrk4", "glrk8", "glrk12", "glrk16"])
def test_registry_entries_are_derived_from_their_tableaus(name):
    method = METHODS[name]
    tableau = method.tableau
    assert method.order == tableau.order
    assert method.implicit == (not tableau.explicit)
    assert method.symplectic == tableau.symplectic_condition().holds
    assert method.variables == "canonical"


def test_simplified_order_is_a_lower_bound_reached_by_gauss():
    # Gauss: B(2s), C(s), D(s) give min(2s, 2s + 1, 2s + 2) = 2s, the full order
    for stages in (1, 2, 3, 6):
        assert GAUSS[stages].simplified_order() == 2 * stages == GAUSS[stages].order
    # negative control: RK4 satisfies only C(1), so the simplifying conditions promise less
    # than its order 4, which the rooted trees then establish
    assert RK4.simplified_order() < RK4.order == 4


@pytest.mark.parametrize("stages", [2, 4, 6])
def test_extrapolation_continues_polynomials_of_degree_below_s(stages):
    """``E`` maps a polynomial's values at the nodes ``c`` to those at ``1 + c`` [HLW VIII.6]."""
    tableau = GAUSS[stages]
    c, extrapolation = tableau.c, tableau.extrapolation
    rng = np.random.default_rng(stages)
    exact = np.polynomial.Polynomial(rng.normal(size=stages))  # degree s - 1
    assert np.max(np.abs(extrapolation @ exact(c) - exact(1 + c))) < 1e-10
    # negative control: one degree more is not continued exactly
    higher = np.polynomial.Polynomial(np.append(rng.normal(size=stages), 1.0))
    assert np.max(np.abs(extrapolation @ higher(c) - higher(1 + c))) > 1e-3
    # coinciding nodes have no interpolating polynomial
    assert TRAPEZOIDAL.extrapolation is not None and RK4.extrapolation is None


def test_evaluation_counts_come_from_the_stages(method_tested):
    dp = pl.double_pendulum()
    for name in ("explicit_euler", "rk4"):
        run = pl.simulate(dp, [1.0, 1.5], [0.0, 0.0], t_end=1.0, dt=0.01, method=name)
        assert run.evaluations == 100 * METHODS[name].tableau.stages
    for name in filter(method_tested, ("glrk4", "glrk8", "glrk12", "glrk16")):
        run = pl.simulate(dp, [1.0, 1.5], [0.0, 0.0], t_end=1.0, dt=0.01, method=name)
        sweeps = run.mean_iterations * 100
        # the first step evaluates its guess f(y); every later step starts from
        # the previous step's collocation polynomial (no evaluation); s per sweep
        expected = 1 + METHODS[name].tableau.stages * sweeps
        assert run.evaluations == pytest.approx(expected, abs=1e-9)


def test_a_new_tableau_method_is_one_line():
    """Kutta's 3/8 rule, made from its tableau alone, runs with order 4 and 4 evaluations a step."""
    from pendulum_lab import analysis

    method = Method.from_tableau("three_eighths", THREE_EIGHTHS, "Kutta's 3/8 rule")
    assert (method.order, method.implicit, method.symplectic) == (4, False, False)
    sp = pl.simple_pendulum()
    dts = (0.01, 0.005, 0.0025, 0.00125)
    result = analysis.observed_order(sp, [1.2], [0.0], t_end=1.0, dts=dts, method=method)
    assert abs(result.slope - 4) <= 0.15, result
    run = pl.simulate(sp, [1.2], [0.0], t_end=1.0, dt=0.01, method=method)
    assert run.evaluations == 400
    # negative control: Heun's third-order tableau gives a slope of 3
    heun = Method.from_tableau("heun3", HEUN3, "Heun's third-order method")
    result = analysis.observed_order(sp, [1.2], [0.0], t_end=1.0, dts=dts, method=heun)
    assert abs(result.slope - 3) <= 0.15, result


def test_an_implicit_tableau_with_more_stages_than_the_stack_buffer_is_refused():
    # the stage sums run in a stack buffer of MAX_STAGE_LANES columns
    from pendulum_lab.integrators.runge_kutta import MAX_STAGE_LANES

    def averaging(stages):  # implicit, every stage the mean of all: consistent, order 1
        return ButcherTableau(a=np.full((stages, stages), 1.0 / stages),
                              b=np.full(stages, 1.0 / stages))

    with pytest.raises(ValueError, match=f"at most {MAX_STAGE_LANES}"):
        Method.from_tableau("too_many", averaging(MAX_STAGE_LANES + 1), "too many stages")
    # negative control: the largest allowed number is taken
    assert Method.from_tableau("as_many", averaging(MAX_STAGE_LANES), "as many").implicit


def test_symmetry_is_derived_from_the_coefficients():
    """``b`` reversed equals ``b`` and ``a_(s+1-i, s+1-j) + a_ij = b_j`` [HLW, Thm V.2.3]."""
    assert gauss_legendre_tableau(2).symmetric and gauss_legendre_tableau(3).symmetric
    trapezoidal = ButcherTableau(a=[[0, 0], [0.5, 0.5]], b=[0.5, 0.5])
    assert trapezoidal.symmetric
    # negative controls: explicit methods are never symmetric, RK4 among them
    assert not ButcherTableau(a=[[0.0]], b=[1.0]).symmetric
    assert not ButcherTableau(a=[[0, 0, 0, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 1, 0]],
                              b=[1 / 6, 1 / 3, 1 / 3, 1 / 6]).symmetric
