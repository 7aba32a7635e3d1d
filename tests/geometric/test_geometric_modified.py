"""Backward error analysis: the symbolic modified equations and Hamiltonians, checked numerically.

Each property is paired with a negative control: H itself (not H~) shrinks only like h^order,
explicit Euler's modified field has no Hamiltonian, a symplectic method has no dissipative term.
"""

import numpy as np
import pytest
import sympy as sp

import pendulum_lab as pl
from pendulum_lab import step
from pendulum_lab.geometric import backward_error as be
from pendulum_lab.geometric import long_time
from pendulum_lab.geometric import modified_equations as me

SP = pl.simple_pendulum(mass=0.8, length=1.2, g=9.81)
DP = pl.double_pendulum(m1=1.0, m2=1.0, l1=1.0, l2=1.0, g=9.81)


def series_step(method, model, q0, p0, h, order):
    """The truncated Taylor series of one step, evaluated numerically."""
    chain = model.chain
    series = me.step_series(method, chain.hamiltonian, list(chain.q), list(chain.p), order)
    subs = model.parameter_values | dict(zip(chain.q, q0)) | dict(zip(chain.p, p0))
    return np.array([float(sum(c.xreplace(subs) * h**k for k, c in enumerate(s)))
                     for s in series])


@pytest.mark.parametrize("method", ["explicit_euler", "semi_implicit_euler", "leapfrog", "rk4",
                                    "glrk4"])
def test_step_series_is_the_taylor_expansion_of_the_compiled_step(method):
    q0, p0, order = [1.1], [0.4], 3
    misses = []
    for h in (0.04, 0.02):
        exact = np.concatenate(step(SP, np.array(q0), p0=np.array(p0), dt=h, method=method))
        misses.append(np.max(np.abs(series_step(method, SP, q0, p0, h, order) - exact)))
    # the first omitted term is h^(order+1): halving h divides the miss by about 16, unless the
    # step is a polynomial of degree <= 3 in h (explicit Euler; symplectic Euler for separable H)
    assert misses[0] < 1e-14 or 12 < misses[0] / misses[1] < 20, misses
    # negative control: the series of another method misses by O(h^2) at least
    other = "leapfrog" if method != "leapfrog" else "semi_implicit_euler"
    wrong = np.concatenate(step(SP, np.array(q0), p0=np.array(p0), dt=0.02, method=other))
    if method in ("rk4", "glrk4", "leapfrog") and other == "leapfrog":
        assert np.max(np.abs(series_step(method, SP, q0, p0, 0.02, order) - wrong)) > 1e-6
    else:
        assert np.max(np.abs(series_step(method, SP, q0, p0, 0.02, order) - wrong)) > 1e-5


def test_general_formulas_match_hairer_lubich_wanner():
    q, p = sp.Symbol("q"), sp.Symbol("p")
    h = be.STEP_SIZE
    hf = sp.Function("H")(q, p)
    d = sp.diff
    expected = (hf - h / 2 * d(hf, p) * d(hf, q)
                + h**2 / 12 * (d(hf, p, 2) * d(hf, q) ** 2 + d(hf, q, 2) * d(hf, p) ** 2
                               + 4 * d(hf, p, q) * d(hf, p) * d(hf, q)))
    got = be.generic_modified_hamiltonian("semi_implicit_euler", 2)
    assert sp.expand(got - expected) == 0
    t, u = sp.Function("T")(p), sp.Function("U")(q)
    verlet = t + u + h**2 * (d(t, p) ** 2 * d(u, q, 2) / 12 - d(t, p, 2) * d(u, q) ** 2 / 24)
    assert sp.expand(be.generic_modified_hamiltonian("leapfrog", 2, separable=True) - verlet) == 0
    # negative control: a wrong coefficient is seen
    assert sp.expand(got - expected.subs(sp.Rational(1, 12), sp.Rational(1, 6))) != 0


def test_explicit_euler_field_has_no_hamiltonian():
    q, p, hf = me.abstract_problem(1, False)
    fields = me.modified_fields(me.step_series("explicit_euler", hf, q, p, 2), (*q, *p))
    with pytest.raises(ValueError, match="not Hamiltonian"):
        me.hamiltonian_of_field(fields[1], hf, q, p, 2)
    sym = me.modified_fields(me.step_series("semi_implicit_euler", hf, q, p, 2), (*q, *p))
    assert me.hamiltonian_of_field(sym[1], hf, q, p, 2) != 0


def test_modified_hamiltonian_symbols_and_top_level():
    h_tilde = pl.modified_hamiltonian(SP, "leapfrog", 2)
    assert h_tilde.free_symbols <= SP.hamiltonian.free_symbols | {be.STEP_SIZE}
    assert be.STEP_SIZE in h_tilde.free_symbols
    assert sp.expand(h_tilde.subs(be.STEP_SIZE, 0) - SP.hamiltonian) == 0
    # symmetric: no odd powers
    assert sp.expand(h_tilde).coeff(be.STEP_SIZE, 1) == 0
    # the velocity version is the same map for one link
    assert sp.expand(pl.modified_hamiltonian(SP, "leapfrog_velocity", 2) - h_tilde) == 0


def test_glrk4_first_correction_is_h4():
    h_tilde = sp.expand(pl.modified_hamiltonian(SP, "glrk4", 4))
    powers = [h_tilde.coeff(be.STEP_SIZE, j) for j in range(1, 5)]
    assert powers[:3] == [0, 0, 0] and powers[3] != 0


@pytest.mark.parametrize(
    "model, method, orders, start, dts, t_end",
    [
        (SP, "semi_implicit_euler", (0, 1, 2), ([1.5], [0.0]), (0.1, 0.05, 0.025), 10.0),
        (SP, "leapfrog", (0, 2), ([1.5], [0.0]), (0.1, 0.05, 0.025), 10.0),
        (SP, "glrk4", (0, 4), ([1.5], [0.0]), (0.2, 0.1, 0.05), 10.0),
        (DP, "semi_implicit_euler", (0, 1, 2), ([1.0, 1.2], [0.0, 0.0]), (0.02, 0.01, 0.005),
         4.0),
        (DP, "leapfrog", (0, 2), ([1.0, 1.2], [0.0, 0.0]), (0.02, 0.01, 0.005), 4.0),
    ],
)
def test_error_of_truncated_modified_hamiltonian_shrinks_like_first_omitted_power(
        model, method, orders, start, dts, t_end):
    result = be.modified_energy_orders(model, method, *start, dts=dts, orders=orders,
                                       t_end=t_end)
    assert np.all(np.abs(result.slopes - result.expected) < 0.2), (result.slopes, result.expected)
    # negative control: H itself (k = 0) is worse than every H~ by orders of magnitude
    assert np.all(result.errors[0, -1] > 10 * result.errors[1:, -1])


@pytest.mark.parametrize(
    "model, method, message",
    [
        (SP, "explicit_euler", "not symplectic"),
        (SP, "rk4", "not symplectic"),
        (DP, "leapfrog_velocity", "n >= 2"),
        (DP, "semi_implicit_euler_velocity", "n >= 2"),
        (SP, "glrk8", "must be one of"),
        (SP, "no_such_method", "must be one of"),
    ],
)
def test_methods_without_modified_hamiltonian_raise(model, method, message):
    with pytest.raises(ValueError, match=message):
        pl.modified_hamiltonian(model, method, 1)


def test_bad_orders_and_models():
    with pytest.raises(ValueError, match=r"`order` must be in \[0, 2\]"):
        pl.modified_hamiltonian(DP, "leapfrog", 3)
    with pytest.raises(ValueError, match="`order`"):
        pl.modified_hamiltonian(SP, "leapfrog", -1)
    with pytest.raises(TypeError, match="`order`"):
        pl.modified_hamiltonian(SP, "leapfrog", 1.5)
    with pytest.raises(TypeError, match="`model`"):
        pl.modified_hamiltonian("pendulum", "leapfrog", 1)
    with pytest.raises(ValueError, match="1 or 2 link"):
        pl.modified_hamiltonian(pl.n_pendulum(3), "leapfrog", 1)
    with pytest.raises(TypeError, match="`method`"):
        pl.modified_hamiltonian(SP, 3, 1)


def test_rk4_first_dissipative_term_is_h5_with_harmonic_limit():
    term = be.first_dissipative_term(SP, "rk4")
    assert term.power == 5 and 4 in term.divergence_free_powers
    theta, p = SP.chain.q[0], SP.chain.p[0]
    g, l_ = SP.chain.g, SP.chain.lengths[0]
    # small oscillations: RK4 damps the harmonic oscillator at rate omega^6 h^5 / 72
    assert sp.simplify(term.divergence.subs({theta: 0, p: 0}) + g**3 / (72 * l_**3)) == 0
    # negative control: a symplectic method has no dissipative term
    with pytest.raises(ValueError, match="divergence-free"):
        be.first_dissipative_term(SP, "leapfrog", max_power=4)


def test_rk4_energy_drift_is_predicted_by_its_modified_equation():
    result = be.energy_drift(SP, "rk4", 1.5, dts=(0.06, 0.04, 0.03), t_end=400.0)
    assert np.all(np.abs(result.measured / result.predicted - 1) < 0.1), result.measured
    assert abs(result.measured_exponent - 5) < 0.3
    assert np.all(result.measured < 0)  # RK4 loses energy


def test_exact_libration_matches_a_precise_run():
    run = pl.simulate(SP, [2.0], [0.0], t_end=5.0, dt=0.005, method="glrk8")
    theta, p = long_time.exact_libration(SP, 2.0, run.t)
    assert np.max(np.abs(theta - run.theta)) < 1e-11
    assert np.max(np.abs(p - run.p)) < 1e-10


def test_global_error_linear_for_symplectic_quadratic_for_rk4():
    leapfrog = long_time.global_error_growth(SP, "leapfrog", 1.0, dt=0.01, t_end=1000.0)
    assert abs(leapfrog.late_exponent - 1) < 0.1 and abs(leapfrog.early_exponent - 1) < 0.15
    assert abs(leapfrog.quadratic) * leapfrog.t_end < 0.01 * abs(leapfrog.linear)
    coarse = long_time.global_error_growth(SP, "rk4", 1.0, dt=0.025, t_end=2000.0)
    fine = long_time.global_error_growth(SP, "rk4", 1.0, dt=0.0125, t_end=4000.0)
    assert max(coarse.error.max(), fine.error.max()) < 0.1  # far from saturation
    assert abs(coarse.late_exponent - 2) < 0.2
    assert 13 < coarse.linear / fine.linear < 19  # c1 ~ h^4
    assert 27 < coarse.quadratic / fine.quadratic < 37  # c2 ~ h^5
    assert 1.7 < fine.crossover / coarse.crossover < 2.3  # crossover ~ 1/h
