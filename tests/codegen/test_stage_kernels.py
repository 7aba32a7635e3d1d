"""The fields' ``stages`` kernels: every stage of an implicit step in one call.

For one or two links the kernel is vectorized and computes sines and cosines
with :mod:`pendulum_lab.codegen.lowlevel`'s instead of the C library's; elsewhere it
calls ``hamilton`` column by column. Both must give ``hamilton``'s values.
"""

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab import codegen
from pendulum_lab.codegen import lowlevel
from pendulum_lab.driver.simulate import hamiltonian_field
from pendulum_lab.integrators.runge_kutta import stage_lanes


def _columns(n, lanes, size=3.0):
    """Random times, and random states (q, p) as the columns of a (2 n, lanes) array; the same
    for the same arguments, whichever tests ran before in this process (the negative controls
    below need states whose last bits differ, which a given draw is checked to have)."""
    rng = np.random.default_rng([20261130, n, lanes])
    return rng.uniform(0.0, 50.0, lanes), rng.uniform(-size, size, (2 * n, lanes))


def _hamilton_by_column(field, ts, y, hamilton=None):
    """``field.hamilton`` (or the kernel ``hamilton``) called at each column of ``y``."""
    n = y.shape[0] // 2
    out = np.empty_like(y)
    for k in range(y.shape[1]):
        dq, dp = np.empty(n), np.empty(n)
        (hamilton or field.hamilton)(ts[k], y[:n, k].copy(), y[n:, k].copy(), field.params, dq,
                                     dp)
        out[:n, k], out[n:, k] = dq, dp
    return out


def _stages(field, ts, y):
    dy = np.empty_like(y)
    field.stages(ts, y, field.params, dy, np.empty(2 * y.shape[0]))
    return dy


MODELS = {
    "simple": pl.simple_pendulum(mass=1.3, length=0.7, g=9.81),
    "double": pl.double_pendulum(m1=1.0, m2=2.0, l1=1.5, l2=0.5, g=9.81),
    "driven double": pl.n_pendulum(2, masses=(1.0, 2.0), lengths=(1.5, 0.5), damping=0.3,
                                   drive_amplitude=1.2, drive_frequency=0.7),
}


@pytest.mark.parametrize("name", list(MODELS))
def test_vectorized_stages_give_hamilton_at_every_column(name):
    field = hamiltonian_field(MODELS[name])
    n = MODELS[name].n
    for lanes in (1, 2, 8, 16, 13):  # shorter than a pass, whole passes, and a remainder
        ts, y = _columns(n, lanes)
        expected = _hamilton_by_column(field, ts, y)
        got = _stages(field, ts, y)
        # the sines differ from the C library's by an ulp or two: a few ulps of the result
        scale = np.max(np.abs(expected), axis=1, keepdims=True)
        assert np.max(np.abs(got - expected) / scale) < 1e-14
        if lanes > 1:  # negative control: the columns must not be interchangeable
            assert np.max(np.abs(got[:, ::-1] - expected) / scale) > 1e-3


@pytest.mark.parametrize("name", list(MODELS))
def test_angles_beyond_the_lane_functions_range_are_computed_by_the_c_library(name):
    field = hamiltonian_field(MODELS[name])
    n = MODELS[name].n
    ts, y = _columns(n, 8 * lowlevel.LANE_GROUP)  # enough that some last bit differs below
    y[0, 3] += 2 * np.pi * 40_000  # about 2.5e5 rad in one column, beyond LIMIT
    assert abs(y[0, 3]) > lowlevel.LIMIT
    # every column then comes from hamilton itself, to the last bit
    np.testing.assert_array_equal(_stages(field, ts, y), _hamilton_by_column(field, ts, y))
    # negative control: within range, the vectorized functions differ in some last bits
    y[0, 3] -= 2 * np.pi * 40_000
    assert not np.array_equal(_stages(field, ts, y), _hamilton_by_column(field, ts, y))


@pytest.mark.parametrize("name", list(MODELS))
def test_fewer_columns_than_a_vector_pass_are_computed_by_the_c_library(name):
    # as scalar code the lane functions cost more than the C library (glrk4's two stages)
    field = hamiltonian_field(MODELS[name])
    n = MODELS[name].n
    for lanes in range(1, lowlevel.LANE_GROUP):
        ts, y = _columns(n, lanes)
        np.testing.assert_array_equal(_stages(field, ts, y), _hamilton_by_column(field, ts, y))
    # negative control: whole passes go through the lane functions (some last bits differ)
    ts, y = _columns(n, 8 * lowlevel.LANE_GROUP)
    assert not np.array_equal(_stages(field, ts, y), _hamilton_by_column(field, ts, y))


def test_the_vectorized_stages_kernel_aligns_its_stack_and_is_inlined_into_the_loops():
    source = codegen.kernel_source(pl.double_pendulum().chain)
    stages = source.split("def stages(")[1]
    for call in ("align_stack()", "inline_into_callers()"):
        assert source.count(call) == 1 and call in stages  # in stages, not in hamilton


@pytest.mark.parametrize("n, looped", [(3, False), (3, True), (6, True)])
def test_column_by_column_stages_of_longer_chains_are_hamilton_exactly(n, looped):
    kernels = codegen.load_kernels(n, looped=looped)
    field = hamiltonian_field(pl.n_pendulum(n))
    if looped:  # what a model of this length uses
        assert field.stages is kernels.stages
    ts, y = _columns(n, 8, size=1.0)
    dy = np.empty_like(y)
    kernels.stages(ts, y, field.params, dy, np.empty(4 * n))
    expected = _hamilton_by_column(field, ts, y, kernels.hamilton)
    np.testing.assert_array_equal(dy, expected)
    assert not np.array_equal(dy[:, ::-1], expected)  # negative control: columns matter


def test_stage_kernel_of_a_field_made_elsewhere_calls_its_hamilton():
    # the kernel generated around any hamilton kernel (Henon's rescaled field uses it)
    field = hamiltonian_field(MODELS["double"])
    stages = codegen.stage_kernel(field.hamilton)
    ts, y = _columns(2, 5)
    dy = np.empty_like(y)
    stages(ts, y, field.params, dy, np.empty(8))
    np.testing.assert_array_equal(dy, _hamilton_by_column(field, ts, y))
    assert codegen.stage_kernel(field.hamilton) is stages  # generated once


def test_implicit_steps_pad_the_stages_to_whole_passes():
    assert [stage_lanes(s) for s in (1, 2, 3, 4, 6, 8, 9)] == [1, 2, 8, 8, 8, 8, 16]


def _observed_order(method):
    """log2 of the error ratio at t = 1 of the double pendulum between dt = 1/8 and 1/16."""
    model, start = MODELS["double"], ([1.0, 1.5], [0.0, 0.0])
    # the truth: glrk12 at a step far below those compared
    truth = pl.simulate(model, *start, t_end=1.0, dt=1 / 256, method="glrk12").theta[-1]
    errors = [np.max(np.abs(pl.simulate(model, *start, t_end=1.0, dt=dt,
                                        method=method).theta[-1] - truth))
              for dt in (1 / 8, 1 / 16)]
    return np.log2(errors[0] / errors[1])


@pytest.mark.parametrize("method", ["glrk8", "glrk12"])
def test_gauss_steps_through_the_stage_kernel_keep_their_order(method):
    expected = pl.get_method(method).order
    assert expected - 1.0 < _observed_order(method) < expected + 1.5


def test_observed_order_tells_the_methods_apart():
    # negative control: the four-stage method's band excludes the two-stage method's order
    assert not 7.0 < _observed_order("glrk4") < 9.5


# ------------------------------------------------------------- the stopping rule, vectorized
def test_a_twenty_link_chain_from_rest_takes_gauss_steps():
    # the chain of benchmark item 13: its momenta start at exactly 0
    trajectory = pl.simulate(pl.n_pendulum(20), np.full(20, 0.5), np.zeros(20), t_end=0.2,
                             dt=0.01, method="glrk4")
    assert trajectory.completed and np.all(np.isfinite(trajectory.theta))
    assert np.max(np.abs(trajectory.relative_energy_error)) < 1e-6
