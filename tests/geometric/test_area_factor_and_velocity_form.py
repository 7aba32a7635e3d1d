"""One step's area factor in high precision; the invariant 2-form written in (theta, omega)."""

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab import analysis
from pendulum_lab.geometric import phase_space as ps

SP = pl.simple_pendulum(mass=1.0, length=1.0, g=9.81)
DP = pl.double_pendulum(m1=1.0, m2=1.0, l1=1.0, l2=1.0, g=9.81)


def test_explicit_euler_area_change_is_the_textbook_formula():
    angles = np.linspace(-3.0, 3.0, 13)[:, None]
    change = ps.one_step_area_change(SP, "explicit_euler", angles, np.full_like(angles, 0.7),
                                     0.1)
    np.testing.assert_allclose(change, 0.01 * 9.81 * np.cos(angles[:, 0]), rtol=0, atol=1e-15)


def test_rk4_at_the_bottom_is_its_stability_function():
    # At the equilibrium the step is the linear map R(hA): det = |R(i w h)|^2.
    for h in (0.05, 0.1, 0.2):
        x2 = 9.81 * h**2
        expected = -(x2**3) / 72 + x2**4 / 576
        change = float(ps.one_step_area_change(SP, "rk4", [0.0], [0.0], h))
        assert change == pytest.approx(expected, rel=1e-12)
        # negative control: explicit Euler's factor at the same point is far off
        assert float(ps.one_step_area_change(SP, "explicit_euler", [0.0], [0.0], h)) > 0


def test_rk4_area_change_changes_sign_with_the_state():
    low, high = ps.one_step_area_change(SP, "rk4", [[0.0], [3.0]], [[0.0], [0.0]], 0.05)
    assert low == pytest.approx(-2.04e-7, rel=1e-2) and high == pytest.approx(2.0e-7, rel=3e-2)


def test_high_precision_agrees_with_finite_differences_where_these_resolve_it():
    for model, theta, p in ((SP, [1.0], [0.3]), (DP, [0.5, 0.8], [0.3, 0.1])):
        exact = float(ps.one_step_area_change(model, "rk4", theta, p, 0.1))
        det, _ = ps.jacobian_properties(model, "rk4", theta, p, 0.1)
        assert abs(exact - (det - 1)) < 1e-8 < abs(exact)
    # the double precision answer is stable in the number of digits
    a = ps.one_step_area_change(SP, "rk4", [2.0], [0.1], 0.05, digits=30)
    b = ps.one_step_area_change(SP, "rk4", [2.0], [0.1], 0.05, digits=60)
    assert float(a) == float(b)


def test_area_change_refuses_methods_without_explicit_tableau():
    for name in ("leapfrog", "glrk4"):
        with pytest.raises(ValueError, match="explicit Butcher tableau"):
            ps.one_step_area_change(SP, name, [0.0], [0.0], 0.1)
    with pytest.raises(ValueError, match="unforced"):
        ps.one_step_area_change(pl.driven_pendulum(), "rk4", [0.0], [0.0], 0.1)
    with pytest.raises(ValueError, match="`theta` and `p`"):
        ps.one_step_area_change(SP, "rk4", [[0.0], [1.0]], [0.0], 0.1)


@pytest.mark.parametrize("name", ["glrk8", "variational_midpoint", "leapfrog"])
def test_symplectic_steps_keep_the_velocity_form_but_not_the_constant_one(name):
    theta, omega = [1.0, 1.5], [0.3, -0.2]
    assert ps.velocity_form_defect(DP, name, theta, omega, 0.05) < 1e-8
    # negative control: the constant form d theta ^ d omega is not kept for two links
    constant = analysis.symplecticity_defect(DP, theta, omega, dt=0.05, method=name,
                                             variables="velocity")
    assert constant > 0.1


def test_velocity_form_fails_for_the_reports_leapfrog_and_rk4():
    theta, omega = [1.0, 1.5], [0.3, -0.2]
    assert ps.velocity_form_defect(DP, "leapfrog_velocity", theta, omega, 0.05) > 1e-3
    assert ps.velocity_form_defect(DP, "rk4", theta, omega, 0.05) > 1e-7
    # one link: the two versions are one map, which keeps m l^2 d theta ^ d omega
    assert ps.velocity_form_defect(SP, "leapfrog_velocity", [2.0], [0.5], 0.05) < 1e-8
