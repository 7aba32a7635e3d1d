"""Bad input to the accuracy measurements: a slope needs two different step sizes."""

import pytest

import pendulum_lab as pl
from pendulum_lab import analysis

SP = pl.simple_pendulum()

CASES = {
    "one step size": (dict(dts=[0.1]), ValueError,
                      "`dts` must hold at least two different step sizes"),
    "one step size twice": (dict(dts=[0.1, 0.1]), ValueError, "at least two different"),
    "no step size": (dict(dts=[]), ValueError, "`dts` must hold at least one value"),
    "a negative step": (dict(dts=[0.1, -0.1]), ValueError, "`dts` must be a positive number"),
    "a run beyond the budget": (dict(dts=[1e-12, 2e-12]), ValueError, "budget"),
    "not numbers": (dict(dts=["a", "b"]), TypeError, "`dts` must hold real numbers"),
    "t_end = 0": (dict(t_end=0.0), ValueError, "`t_end` must be a positive number"),
}


@pytest.mark.parametrize("case", CASES)
def test_bad_input_is_refused_with_a_message_naming_the_argument(case):
    changes, error, message = CASES[case]
    with pytest.raises(error, match=message):
        analysis.observed_order(SP, [0.5], [0.0], method="rk4", **changes)


def test_two_step_sizes_give_the_methods_order():
    # the valid neighbour: two different steps suffice, and the slope is RK4's order
    result = analysis.observed_order(SP, [0.5], [0.0], dts=[0.02, 0.01], method="rk4")
    assert abs(result.slope - 4) < 0.2
