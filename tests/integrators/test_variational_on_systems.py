"""Variational integrators on systems given by their points: the elastic and the cart
pendulum, whose L = T - V is all of their dynamics. The discrete Lagrangian is derived from
the system's own Lagrangian, so the runs solve the system's discrete Euler-Lagrange
equations; a chain written as a system gets the chain's discrete Lagrangian back. Each check
has a negative control."""

import numpy as np
import pytest
import sympy as sp

import pendulum_lab as pl
from pendulum_lab import analysis
from pendulum_lab import discrete_mechanics as dm
from pendulum_lab.symbolic.systems import chain_system

NAMES = ("variational_midpoint", "variational_trapezoid")
RULES = {"variational_midpoint": "midpoint", "variational_trapezoid": "trapezoid"}


@pytest.fixture(scope="module", params=["elastic", "cart"])
def system(request):
    return request.getfixturevalue(request.param)


@pytest.mark.parametrize("rule", dm.RULES)
def test_a_chain_written_as_a_system_has_the_chains_discrete_lagrangian(rule):
    chain, written = dm.discrete_lagrangian(2, rule), dm.discrete_lagrangian(chain_system(2),
                                                                            rule)
    rename = (dict(zip(written.q, chain.q)) | dict(zip(written.q_next, chain.q_next))
              | dict(zip(written.chain.parameters, chain.chain.parameters)))

    def difference(ours, theirs):  # cos(a - b) against cos(a) cos(b) + sin(a) sin(b)
        return (ours.xreplace(rename) - theirs).applyfunc(
            lambda e: sp.expand(sp.expand_trig(e)))

    for ours, theirs in [(written.momentum_minus, chain.momentum_minus),
                         (written.momentum_plus, chain.momentum_plus)]:
        assert difference(ours, theirs) == sp.zeros(2, 1)
    # negative control: the other rule's transforms differ
    other = dm.discrete_lagrangian(2, "trapezoid" if rule == "midpoint" else "midpoint")
    assert difference(written.momentum_minus, other.momentum_minus) != sp.zeros(2, 1)


@pytest.mark.parametrize("name", NAMES)
def test_the_runs_solve_the_systems_discrete_euler_lagrange_equations(system, name):
    run = pl.simulate(system, system.start, [0.3, -0.2], t_end=2.0, dt=0.02, method=name)
    rule, values = RULES[name], system.parameter_values
    start, end = dm.discrete_momenta(system.system, rule, values, run.theta[:-1],
                                     run.theta[1:], run.dt)
    assert np.max(np.abs(end[:-1] - start[1:])) < 1e-11  # D2 L_d + D1 L_d = 0
    assert np.max(np.abs(start - run.p[:-1])) < 1e-11  # and p is the discrete momentum
    assert np.allclose(run.p[0], system.momenta(system.start, [0.3, -0.2]), atol=1e-12)
    # negative control: the leapfrog's configurations do not solve them
    leapfrog = pl.simulate(system, system.start, [0.3, -0.2], t_end=2.0, dt=0.02,
                           method="leapfrog")
    start, end = dm.discrete_momenta(system.system, rule, values, leapfrog.theta[:-1],
                                     leapfrog.theta[1:], leapfrog.dt)
    assert np.max(np.abs(end[:-1] - start[1:])) > 1e-7


@pytest.mark.parametrize("name", NAMES)
def test_symplectic_and_symmetric_on_a_system(system, name):
    theta, p = system.start, system.momenta(system.start, [0.3, -0.2])
    defect = analysis.symplecticity_defect(system, theta, p0=p, dt=0.05, method=name)
    assert defect <= 1e-9  # the finite differences' accuracy
    assert analysis.reversibility_error(system, theta, p0=p, dt=0.05, method=name) <= 1e-12
    # negative controls: RK4 is not symplectic, symplectic Euler not symmetric
    control = analysis.symplecticity_defect(system, theta, p0=p, dt=0.05, method="rk4")
    assert control >= 1e-7 and control >= 100 * defect
    assert analysis.reversibility_error(system, theta, p0=p, dt=0.05,
                                        method="semi_implicit_euler") > 1e-8


@pytest.mark.parametrize("name", NAMES)
def test_observed_order_two_on_the_elastic_pendulum(elastic, name):
    result = analysis.observed_order(elastic, elastic.start, [0.0, 0.0], t_end=1.0,
                                     dts=(0.02, 0.01, 0.005), method=name)
    assert abs(result.slope - 2) <= 0.15, result
    # negative control: a first-order method fails the same check
    euler = analysis.observed_order(elastic, elastic.start, [0.0, 0.0], t_end=1.0,
                                    dts=(0.02, 0.01, 0.005), method="semi_implicit_euler")
    assert abs(euler.slope - 2) > 0.8, euler


def test_energy_bounded_over_1000_swings_of_the_elastic_pendulum(elastic):
    swing = 2 * np.pi / analysis.normal_modes(elastic)[0][0]
    runs = {name: pl.simulate(elastic, elastic.start, [0.0, 0.0], t_end=1000 * swing, dt=0.05,
                              method=name, save_every=10, progress=False)
            for name in (*NAMES, "rk4")}
    for name in NAMES:
        first, last = analysis.energy_growth(runs[name])
        assert last <= 3 * first, (name, first, last)
    # negative control: RK4's error drifts on the same run
    first, last = analysis.energy_growth(runs["rk4"])
    assert last > 3 * first, (first, last)


def test_refused_where_the_lagrangian_is_not_all_of_the_dynamics(kapitza):
    with pytest.raises(ValueError, match="depends on the time"):
        dm.discrete_lagrangian(kapitza.system, "midpoint")
    th, c = sp.symbols("theta c", real=True)
    damped = pl.mechanical_system([th], {c: 0.2}, lagrangian=sp.Symbol("theta_dot",
                                                                       real=True) ** 2 / 2
                                  + sp.cos(th), dissipation=c * sp.Symbol("theta_dot",
                                                                          real=True) ** 2 / 2)
    with pytest.raises(ValueError, match="generalized forces"):
        dm.discrete_lagrangian(damped.system, "trapezoid")
    for model in (kapitza, damped):
        with pytest.raises(ValueError, match="cannot integrate.*Methods that can"):
            pl.step(model, [0.1], [0.0], dt=0.01, method="variational_midpoint")
    # negative control: the same system without damping is accepted
    undamped = pl.mechanical_system([th], {}, lagrangian=sp.Symbol("theta_dot",
                                                                   real=True) ** 2 / 2
                                    + sp.cos(th))
    assert pl.step(undamped, [0.1], [0.0], dt=0.01,
                   method="variational_midpoint")[0].shape == (1,)


def test_a_velocity_linear_term_in_the_lagrangian_is_kept():
    """A charge in a magnetic field and a trap: L has the term B (x y' - y x') / 2, so
    p = m v + b(q). The variational steps converge to the motion at order two."""
    x, y, xd, yd = sp.symbols("x y x_dot y_dot", real=True)
    m, big_b, k = sp.symbols("m B k", positive=True)
    charge = pl.mechanical_system(
        [x, y], {m: 1.0, big_b: 2.0, k: 3.0}, velocities=[xd, yd],
        lagrangian=m * (xd**2 + yd**2) / 2 + big_b * (x * yd - y * xd) / 2
        - k * (x**2 + y**2) / 2, name="a charge in a magnetic trap")
    assert np.allclose(charge.momenta([1.0, 0.0], [0.0, 0.0]), [0.0, 1.0])  # b = B x / 2
    for name in NAMES:
        result = analysis.observed_order(charge, [1.0, 0.0], [0.0, 0.5], t_end=2.0,
                                         dts=(0.02, 0.01, 0.005), method=name)
        assert abs(result.slope - 2) <= 0.15, (name, result)
        assert result.errors[-1] < 1e-3
    # negative control: leaving b out (p = m v) starts another motion
    wrong = pl.simulate(charge, [1.0, 0.0], None, t_end=2.0, dt=0.005, method=NAMES[0],
                        p0=[0.0, 0.5])
    right = pl.simulate(charge, [1.0, 0.0], [0.0, 0.5], t_end=2.0, dt=0.005, method=NAMES[0])
    assert np.max(np.abs(wrong.theta[-1] - right.theta[-1])) > 0.1
