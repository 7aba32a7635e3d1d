"""The root of the trapezoidal variational step followed in h, through its fold."""

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab.geometric import continuation
from pendulum_lab.integrators import variational_method

UNEVEN = pl.double_pendulum(m1=1.0, m2=1.5, l1=1.0, l2=0.7, g=9.81)
THETA0 = np.array([0.3, -1.0])
P0 = UNEVEN.momenta(THETA0, np.array([4.0, -6.0]))


@pytest.fixture(scope="module")
def branch():
    return continuation.variational_root_branch(UNEVEN, "trapezoid", THETA0, P0, h_stop=0.25)


def test_branch_points_are_roots_and_match_the_registered_step(branch):
    for h in (0.1, 0.2, 0.3):
        (root, *_) = branch.roots_at(h)
        q1, _ = pl.step(UNEVEN, THETA0, p0=P0, dt=h, method="variational_trapezoid")
        assert np.max(np.abs(root - q1)) < 1e-4  # interpolated between branch points


def test_the_branch_folds_where_the_jacobian_is_singular(branch):
    assert branch.folded and 0.33 < branch.fold_h < 0.34
    assert np.all(branch.h <= branch.fold_h + 1e-9)
    assert np.sign(branch.determinant[0]) == -np.sign(branch.determinant[-1])
    # beyond the fold the small-step root is gone: the fixed-point solver gives up
    with pytest.raises(pl.ConvergenceError):
        pl.step(UNEVEN, THETA0, p0=P0, dt=0.4, method="variational_trapezoid")


def test_newtons_root_at_large_step_lies_beyond_the_fold(branch):
    before, beyond = branch.roots_at(0.3)
    newton, _ = pl.step(UNEVEN, THETA0, p0=P0, dt=0.3,
                        method=variational_method("trapezoid", "newton"))
    assert np.max(np.abs(newton - beyond)) < 1e-4
    assert np.max(np.abs(newton - before)) > 0.5  # negative control: not the small-step root


def test_one_link_trapezoid_has_no_fold():
    one = continuation.variational_root_branch(pl.simple_pendulum(), "trapezoid", [0.5], [1.0],
                                               h_max=0.5)
    assert not one.folded and one.h[-1] >= 0.5 and np.isnan(one.fold_h)


def test_bad_input():
    with pytest.raises(ValueError, match="`rule`"):
        continuation.variational_root_branch(UNEVEN, "simpson", THETA0, P0)
    with pytest.raises(ValueError, match="`h_max`"):
        continuation.variational_root_branch(UNEVEN, "trapezoid", THETA0, P0, h_max=0.001)
    with pytest.raises(ValueError, match="conservative"):
        continuation.variational_root_branch(pl.driven_pendulum(), "trapezoid", [0.1], [0.0])
