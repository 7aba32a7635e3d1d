"""Phase-space area: Liouville, symplecticity, Poincare's integral invariant.

Every conservation check has a non-symplectic method (or a volume-preserving but
non-symplectic matrix) as its negative control.
"""

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab import analysis
from pendulum_lab.geometric import phase_space as ps

SP = pl.simple_pendulum(mass=1.0, length=1.0, g=9.81)
DP = pl.double_pendulum(m1=1.0, m2=1.0, l1=1.0, l2=1.0, g=9.81)
DISC = [[0.15, 0.0], [0.0, 0.3]]
# A loop in the double pendulum's 4-d phase space mixing both planes (theta1, theta2, p1, p2).
LOOP_4D = 0.1 * np.array([[1.0, 0.5, 0.0, 0.3], [0.2, 0.0, 1.0, 0.8]])


def test_polygon_area_of_a_circle_converges_like_n_squared_and_extrapolates():
    areas = []
    for n in (32, 64):
        loop = ps.ellipse_loop([0.0, 0.0], [[1.0, 0.0], [0.0, 1.0]], n)
        areas.append(float(ps.polygon_area(loop[:, 0], loop[:, 1])))
    errors = np.pi - np.array(areas)
    assert 3.9 < errors[0] / errors[1] < 4.1
    assert abs((4 * areas[1] - areas[0]) / 3 - np.pi) < 1e-5 < errors[1]
    # orientation: clockwise is negative
    assert ps.polygon_area(loop[::-1, 0], loop[::-1, 1]) < 0


@pytest.mark.parametrize("method", ["semi_implicit_euler", "leapfrog", "glrk4"])
def test_symplectic_methods_keep_the_area_of_a_blob(method):
    result = ps.carried_loop_areas(SP, method, [1.0, 0.0], DISC, t_end=4.0, dt=0.05,
                                   save_every=20, tol=1e-10)
    assert np.max(np.abs(result.ratio - 1)) < 1e-9
    assert result.error < 1e-9


def test_non_symplectic_methods_change_the_area():
    euler = ps.carried_loop_areas(SP, "explicit_euler", [1.0, 0.0], DISC, t_end=4.0, dt=0.05,
                                  save_every=20, tol=1e-10)
    rk4 = ps.carried_loop_areas(SP, "rk4", [1.0, 0.0], DISC, t_end=4.0, dt=0.05, save_every=20,
                                tol=1e-10)
    assert euler.ratio[-1] > 1.5  # small swing: cos(theta) > 0 mostly, the area grows
    assert 1e-7 < abs(rk4.ratio[-1] - 1) < 1e-3


@pytest.mark.parametrize("center", [[2.6, 0.0], [0.0, 6.6]], ids=["large libration", "rotation"])
def test_explicit_euler_shrinks_blobs_near_the_top_while_the_energy_grows(center):
    result = ps.carried_loop_areas(SP, "explicit_euler", center, DISC, t_end=3.0, dt=0.02,
                                   save_every=50, tol=1e-9)
    energy = SP.hamiltonian_value(result.loops[..., :1], result.loops[..., 1:]).mean(axis=1)
    assert result.ratio[-1] < 0.9
    assert energy[-1] - energy[0] > 0.5
    # negative control: the exact flow (GL8 at a small step) keeps both
    exact = ps.carried_loop_areas(SP, "glrk8", center, DISC, t_end=3.0, dt=0.05, save_every=20,
                                  tol=1e-9)
    assert abs(exact.ratio[-1] - 1) < 1e-8


@pytest.mark.parametrize("theta", [0.0, 1.0, 2.5, np.pi])
def test_explicit_euler_determinant_formula(theta):
    h = 0.1
    det, defect = ps.jacobian_properties(SP, "explicit_euler", [theta], [0.7], h)
    assert abs(det - (1 + h**2 * SP.g / SP.lengths[0] * np.cos(theta))) < 1e-8
    det_se, defect_se = ps.jacobian_properties(SP, "semi_implicit_euler", [theta], [0.7], h)
    assert abs(det_se - 1) < 1e-8 and defect_se < 1e-8


def test_unit_determinant_is_not_enough_for_two_links():
    stretch = np.diag([2.0, 1.0, 1.0, 0.5])
    assert abs(np.linalg.det(stretch) - 1) < 1e-15
    assert analysis.symplectic_form_defect(stretch) == pytest.approx(1.0)
    rotation = np.array([[np.cos(0.3), np.sin(0.3)], [-np.sin(0.3), np.cos(0.3)]])
    assert analysis.symplectic_form_defect(rotation) < 1e-15
    for method in ("leapfrog", "glrk4"):
        det, defect = ps.jacobian_properties(DP, method, [0.5, 0.8], [0.3, 0.1], 0.05)
        assert abs(det - 1) < 1e-8 and defect < 1e-8
    det, defect = ps.jacobian_properties(DP, "leapfrog_velocity", [0.5, 0.8], [0.3, 0.1], 0.05)
    assert defect > 1e-4


@pytest.fixture(scope="module")
def loops_4d():
    return {
        method: ps.carried_loop_areas(DP, method, [0.5, 0.8, 0.0, 0.0], LOOP_4D, t_end=4.0,
                                      dt=0.05, save_every=20, tol=1e-9)
        for method in ("glrk8", "leapfrog", "leapfrog_velocity", "semi_implicit_euler_velocity")
    }


def test_poincare_integral_invariant_is_kept_by_symplectic_methods(loops_4d):
    for method in ("glrk8", "leapfrog"):
        result = loops_4d[method]
        assert np.max(np.abs(result.ratio - 1)) < 1e-8
        # a single projection is not invariant
        assert np.max(np.abs(result.canonical[:, 0] / result.canonical[0, 0] - 1)) > 0.1


def test_velocity_variants_break_the_invariant(loops_4d):
    for method in ("leapfrog_velocity", "semi_implicit_euler_velocity"):
        assert np.max(np.abs(loops_4d[method].ratio - 1)) > 1e-3


def test_area_in_theta_omega_is_not_invariant_even_for_the_exact_flow(loops_4d):
    exact = loops_4d["glrk8"]
    velocity_sum = exact.velocity.sum(axis=1)
    assert np.max(np.abs(velocity_sum / velocity_sum[0] - 1)) > 0.05


def test_bad_loops_are_refused():
    with pytest.raises(ValueError, match="`center`"):
        ps.carried_loop_areas(SP, "leapfrog", [1.0, 0.0, 0.0], DISC, t_end=1.0, dt=0.1)
    with pytest.raises(ValueError, match="4 entries"):
        ps.carried_loop_areas(DP, "leapfrog", [1.0, 0.0], DISC, t_end=1.0, dt=0.1)
    with pytest.raises(ValueError, match="`matrix`"):
        analysis.symplectic_form_defect(np.eye(3))
