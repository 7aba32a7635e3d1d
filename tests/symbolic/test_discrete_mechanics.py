"""Discrete Lagrangians of the chain, discrete Euler-Lagrange equations, Legendre transforms."""

import numpy as np
import pytest
import sympy as sp

import pendulum_lab as pl
from pendulum_lab import discrete_mechanics as dm
from pendulum_lab import step

SP = pl.simple_pendulum(mass=0.8, length=1.2, g=9.81)
DP = pl.double_pendulum(m1=1.0, m2=1.5, l1=1.0, l2=0.7, g=9.81)


def test_trapezoid_is_stormer_verlet_for_one_link():
    q, p = np.array([2.0]), np.array([0.5])
    a, b = q.copy(), p.copy()
    for _ in range(50):
        q, p = dm.reference_step(1, "trapezoid", SP.parameter_values, q, p, 0.1)
        a, b = step(SP, a, p0=b, dt=0.1, method="leapfrog")
    assert np.max(np.abs(q - a)) < 1e-12 and np.max(np.abs(p - b)) < 1e-12
    # negative control: the midpoint rule is another method (implicit midpoint)
    qm, pm = dm.reference_step(1, "midpoint", SP.parameter_values, [2.0], [0.5], 0.1)
    qv, pv = step(SP, np.array([2.0]), p0=np.array([0.5]), dt=0.1, method="leapfrog")
    assert np.max(np.abs(np.r_[qm - qv, pm - pv])) > 1e-5


def test_midpoint_rule_gives_the_implicit_midpoint_rule_for_one_link():
    dl = dm.discrete_lagrangian(1, "midpoint")
    chain = dl.chain
    (m,), (l_,), g = chain.masses, chain.lengths, chain.g
    a, b = dl.q[0], dl.q_next[0]
    p0, p1 = dl.momentum_minus[0], dl.momentum_plus[0]
    # p0 + p1 = 2 m l^2 (b - a) / h  and  p1 - p0 = -h m g l sin((a + b) / 2)
    assert sp.simplify(p0 + p1 - 2 * m * l_**2 * (b - a) / dl.h) == 0
    assert sp.simplify(p1 - p0 + dl.h * m * g * l_ * sp.sin((a + b) / 2)) == 0


@pytest.mark.parametrize("rule", dm.RULES)
def test_discrete_legendre_transform_gives_the_canonical_momentum(rule):
    dl = dm.discrete_lagrangian(2, rule)
    chain = dl.chain
    omega = sp.Matrix(chain.omega)
    at_q = dict(zip(chain.q, dl.q))
    moving = dict(zip(dl.q_next, dl.q + dl.h * omega))
    limit = sp.Matrix([sp.limit(e.xreplace(moving), dl.h, 0) for e in dl.momentum_minus])
    canonical = chain.mass_matrix.xreplace(at_q) * omega
    assert sp.simplify(limit - canonical) == sp.zeros(2, 1)
    # negative control: the momentum is not the velocity (M is not the identity)
    assert sp.simplify(limit - omega) != sp.zeros(2, 1)


@pytest.mark.parametrize("rule", dm.RULES)
def test_discrete_euler_lagrange_residual_on_the_exact_motion_is_third_order(rule):
    dl = dm.discrete_lagrangian(2, rule)
    args = (*dl.q_prev, *dl.q, *dl.q_next, dl.h, *dl.chain.parameters)
    residual = sp.lambdify(args, list(dl.euler_lagrange), cse=True, dummify=True)
    params = [DP.parameter_values[s] for s in dl.chain.parameters]

    def worst(model_params, h):
        run = pl.simulate(DP, [1.0, 1.5], [0.2, -0.3], t_end=2.0, dt=h / 8, method="glrk8")
        theta = run.theta[::8]
        return max(np.max(np.abs(residual(*theta[k - 1], *theta[k], *theta[k + 1], h,
                                          *model_params)))
                   for k in range(1, len(theta) - 1))

    errors = [worst(params, h) for h in (0.04, 0.02)]
    assert 6 < errors[0] / errors[1] < 10  # O(h^3): the scheme is second order
    # negative control: a wrong g leaves a residual of order h (the equations are not met)
    wrong = params[:-1] + [params[-1] * 1.2]
    wrong_errors = [worst(wrong, h) for h in (0.04, 0.02)]
    assert 1.5 < wrong_errors[0] / wrong_errors[1] < 2.5


def test_trapezoid_is_not_stormer_verlet_when_the_mass_matrix_varies():
    misses = []
    for h in (0.05, 0.025):
        q, p = dm.reference_step(2, "trapezoid", DP.parameter_values, [1.0, 1.5], [0.3, -0.2], h)
        a, b = step(DP, np.array([1.0, 1.5]), p0=np.array([0.3, -0.2]), dt=h, method="leapfrog")
        misses.append(np.max(np.abs(np.r_[q - a, p - b])))
    assert misses[1] > 1e-8  # not round-off: two different methods
    assert 6 < misses[0] / misses[1] < 10  # they agree to O(h^3) per step (both second order)


def test_three_links_derive_cheaply_and_bad_input():
    dl = dm.discrete_lagrangian(3, "trapezoid")
    assert dl.euler_lagrange.shape == (3, 1)
    with pytest.raises(ValueError, match="`rule`"):
        dm.discrete_lagrangian(2, "simpson")
    with pytest.raises(TypeError, match="`n`"):
        dm.discrete_lagrangian(2.0, "midpoint")
    with pytest.raises(ValueError, match="`n`"):
        dm.discrete_lagrangian(0, "midpoint")
    with pytest.raises(ValueError, match="`parameters`"):
        dm.reference_step(1, "midpoint", {}, [0.1], [0.0], 0.1)


def test_discrete_momenta_bad_input():
    with pytest.raises(ValueError, match="`q0` and `q1`"):
        dm.discrete_momenta(2, "midpoint", DP.parameter_values, [0.1, 0.2], [0.1], 0.1)
    with pytest.raises(ValueError, match="`h`"):
        dm.discrete_momenta(1, "midpoint", SP.parameter_values, [0.1], [0.2], 0.0)
    with pytest.raises(TypeError, match="`parameters`"):
        dm.discrete_momenta(1, "midpoint", [1.0, 1.0, 9.81], [0.1], [0.2], 0.1)
    # negative control: a batch of steps is fine
    start, end = dm.discrete_momenta(1, "midpoint", SP.parameter_values, np.zeros((4, 1)),
                                     np.full((4, 1), 0.1), 0.1)
    assert start.shape == end.shape == (4, 1)
