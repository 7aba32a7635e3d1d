"""The report's argument slips (errata), the modified energy of symplectic Euler, linear stability.

Each check has a negative control: the printed form must fail where the corrected one passes, a
non-Hamiltonian field must be refused, a non-symplectic quantity must not be conserved.
"""

import math

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
import sympy as sp  # noqa: E402

import pendulum_lab as pl  # noqa: E402
from pendulum_lab import analysis, errata, plotting, timing  # noqa: E402
from pendulum_lab.geometric import STEP_SIZE, modified_energy  # noqa: E402
from pendulum_lab.symbolic.mechanics import derive_chain, is_identically_zero  # noqa: E402

SP = pl.simple_pendulum(mass=1.0, length=1.0, g=9.81)
UNIT = pl.simple_pendulum(mass=1.0, length=1.0, g=1.0)  # omega_0 = 1: a step is h omega
DP = pl.double_pendulum()


def verdicts(checks):
    return [check.agrees for check in checks]


# --------------------------------------------------------------------------- errata
def test_eigenvalue_slip_is_g_over_l_set_to_one():
    checks = errata.simple_pendulum_eigenvalue_checks()
    assert verdicts(checks) == [True, False, True, False]
    chain = derive_chain(1)
    g, length = chain.g, chain.lengths[0]
    # The printed polynomials differ from the derived ones by exactly +-(g/l - 1).
    assert is_identically_zero(checks[1].difference - (g / length - 1))
    assert is_identically_zero(checks[1].difference.subs(g, length))


def test_small_angle_lagrangian_sign_and_equations():
    checks = errata.small_angle_lagrangian_checks()
    assert verdicts(checks) == [False, True, True, True, False]
    chain = derive_chain(2)
    (t1, t2), (m1, m2), (l1, l2), g = chain.q, chain.masses, chain.lengths, chain.g
    expected = -g * ((m1 + m2) * l1 * t1**2 + m2 * l2 * t2**2)
    assert is_identically_zero(checks[0].difference - expected)


def test_small_angle_orders():
    t1, t2 = derive_chain(2).q
    assert errata.small_angle_order(t1**2 + t2**2) == 2
    assert errata.small_angle_order(sp.cos(t1) - 1 + t1**2 / 2) == 4  # negative control: not 2
    assert errata.small_angle_order(sp.sin(t1)) == 1
    orders = errata.small_angle_argument_checks()
    assert list(orders.values()) == [2, 2, 2, 4, 2]
    with pytest.raises(ValueError, match="vanishes"):
        errata.small_angle_order(sp.Integer(0))


def test_energy_rate_line_of_section_3_3():
    checks = errata.energy_rate_checks()
    assert verdicts(checks) == [True, False, True, False, True, False]
    p, q = sp.symbols("p q", real=True)
    assert is_identically_zero(checks[3].difference - (p * q - sp.sin(p) ** 2))


def test_leapfrog_limit_symbolic_agrees_with_the_library_method():
    limit = errata.leapfrog_stability_limit()
    y = sp.Symbol("y", positive=True)
    assert sp.simplify(limit.trace - (2 - y**2)) == 0 and limit.determinant == 1
    value = limit.limit_value(length=1.0, g=9.81)
    assert value == pytest.approx(2 / analysis.normal_mode_frequencies(DP)[1], rel=1e-12)
    measured = analysis.stability_limit(DP, method="leapfrog", dt_max=0.6)
    assert measured == pytest.approx(value, rel=1e-5)
    # Negative control: RK4's limit is 2 sqrt(2) / omega_fast, not the leapfrog's.
    rk4 = analysis.stability_limit(DP, method="rk4", dt_max=0.6)
    assert rk4 == pytest.approx(math.sqrt(2) * value, rel=1e-4)


# --------------------------------------------------------------------------- modified energy
def test_modified_hamiltonian_terms_are_the_textbook_ones():
    modified = modified_energy(SP, "semi_implicit_euler", 2)
    chain = SP.chain
    q, p, h = chain.q[0], chain.p[0], STEP_SIZE
    hq, hp = chain.hamiltonian.diff(q), chain.hamiltonian.diff(p)
    hqq, hpp, hpq = (chain.hamiltonian.diff(*v) for v in ((q, q), (p, p), (p, q)))
    assert is_identically_zero(modified.terms[1] + hp * hq / 2)
    second = (hpp * hq**2 + hqq * hp**2 + 4 * hpq * hp * hq) / 12
    assert is_identically_zero(modified.terms[2] - second)
    assert modified.order == 2 and modified.expression.has(h)


def test_numerical_orbit_conserves_the_modified_energy_to_the_next_order():
    first = modified_energy(SP, "semi_implicit_euler", 1)
    second = modified_energy(SP, "semi_implicit_euler", 2)
    spreads = []
    for h in (0.02, 0.01):
        run = pl.simulate(SP, [2.0], [0.0], t_end=10.0, dt=h, method="semi_implicit_euler")
        spreads.append([np.ptp(run.energy), np.ptp(first(run.theta, run.p, h)),
                        np.ptp(second(run.theta, run.p, h))])
    slopes = np.log2(np.array(spreads[0]) / np.array(spreads[1]))
    assert slopes[0] == pytest.approx(1.0, abs=0.1)  # negative control: H itself, first order
    assert slopes[1] == pytest.approx(2.0, abs=0.1)
    assert slopes[2] == pytest.approx(3.0, abs=0.2)


def test_modified_energy_refuses_what_it_cannot_derive():
    with pytest.raises(ValueError, match="rk4"):
        modified_energy(SP, "rk4", 1)  # not symplectic: no modified Hamiltonian
    with pytest.raises(ValueError, match="order"):
        modified_energy(DP, "semi_implicit_euler", 3)
    with pytest.raises(TypeError):
        modified_energy("pendulum", "semi_implicit_euler", 1)


# --------------------------------------------------------------------------- linear stability
def test_amplification_matches_the_stability_functions():
    y = np.array([0.5, 1.5, 2.5])
    np.testing.assert_allclose(analysis.amplification(UNIT, y, method="explicit_euler"),
                               np.sqrt(1 + y**2), rtol=1e-6)
    rk4 = np.sqrt(1 - y**6 / 72 + y**8 / 576)  # |R(iy)| of RK4
    np.testing.assert_allclose(analysis.amplification(UNIT, y, method="rk4"), rk4, rtol=1e-6)
    np.testing.assert_allclose(analysis.amplification(UNIT, y, method="leapfrog")[:2], 1.0,
                               atol=1e-6)
    assert analysis.amplification(UNIT, [2.1], method="leapfrog")[0] > 1.5  # beyond y = 2


def test_stability_limits_of_each_method():
    limits = {name: analysis.stability_limit(UNIT, method=name, dt_max=2.5 if "gl" in name else 3.4)
              for name in ("explicit_euler", "semi_implicit_euler", "leapfrog", "rk4", "glrk4")}
    assert limits["explicit_euler"] == 0.0
    assert limits["semi_implicit_euler"] == pytest.approx(2.0, rel=1e-6)
    assert limits["leapfrog"] == pytest.approx(2.0, rel=1e-6)
    assert limits["rk4"] == pytest.approx(2 * math.sqrt(2), rel=1e-5)
    assert limits["glrk4"] == math.inf
    with pytest.raises(ValueError, match="dt_max"):
        analysis.stability_limit(UNIT, method="rk4", dt_max=-1.0)


def test_normal_mode_shapes_are_eigenvectors():
    model = pl.double_pendulum(m1=2.0, m2=0.5, l1=1.0, l2=0.7)
    frequencies, shapes = analysis.normal_modes(model)
    ratio = np.array(model.chain.equilibria[0].stiffness_ratio.subs(model.parameter_values),
                     dtype=float)
    for omega, shape in zip(frequencies, shapes):
        np.testing.assert_allclose(ratio @ shape, -omega**2 * shape, rtol=1e-10)
        assert shape[0] == 1.0
    np.testing.assert_allclose(analysis.normal_modes(DP)[1], [[1, np.sqrt(2)], [1, -np.sqrt(2)]])
    assert frequencies[0] < frequencies[1]


# --------------------------------------------------------------------------- figures, timing
def test_new_figures_draw_what_they_say():
    fig = plotting.plot_normal_modes(DP, amplitude=0.2)
    assert len(fig.axes) == 2 and "mode 2" in fig.axes[1].get_title()
    solid = fig.axes[1].lines[1]  # the chain at +amplitude times the fast mode
    x, y = DP.positions(0.2 * np.array([1, -np.sqrt(2)]) / np.sqrt(2))
    np.testing.assert_allclose(solid.get_xdata()[1:], x)
    run = pl.simulate(SP, [2.0], [0.0], t_end=5.0, dt=0.2, method="semi_implicit_euler")
    modified = modified_energy(SP, "semi_implicit_euler", 1)
    fig = plotting.plot_modified_level_sets(run, modified)
    np.testing.assert_array_equal(fig.axes[0].lines[0].get_ydata(), run.p[:, 0])
    other = pl.simulate(SP, [2.0], [0.0], t_end=1.0, dt=0.2, method="leapfrog")
    with pytest.raises(ValueError, match="semi_implicit_euler"):
        plotting.plot_modified_level_sets(other, modified)
    y = np.linspace(0.1, 1.0, 4)
    fig = plotting.plot_amplification(y, {"rk4": np.ones(4)}, {"rk4": 0.5})
    assert len(fig.axes[0].lines) == 3  # the curve, its limit, the line at 1
    with pytest.raises(ValueError, match="shape"):
        plotting.plot_amplification(y, {"rk4": np.ones(3)})


def test_first_use_cost_checks_its_arguments():
    with pytest.raises(ValueError, match="n"):
        timing.first_use_cost(n=0)
    with pytest.raises(ValueError, match="method"):
        timing.first_use_cost(method="euler")
