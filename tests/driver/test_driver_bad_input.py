"""Bad input to the driver (simulate, step, step_count, simulate_segments, a Dask client).

Each case was met by probing the public functions as a careless or curious student would;
each now raises a ``TypeError`` or ``ValueError`` whose message names the argument (or what
is wrong) and what is accepted, before any work starts. The last tests show that the valid
neighbours of these inputs are accepted, so that the checks do not refuse everything.
"""

import numpy as np
import pytest

import pendulum_lab as pl

SP = pl.simple_pendulum()
DP = pl.double_pendulum()
DRIVEN = pl.driven_pendulum()


def run(**changes):
    """``pl.simulate`` of the double pendulum with some arguments changed."""
    arguments = dict(theta0=[1.0, 0.5], omega0=[0.0, 0.0], t_end=1.0, dt=0.01,
                     method="rk4") | changes
    return pl.simulate(DP, **arguments)


def _closed_client():
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                       dashboard_address=None)
    client = distributed.Client(cluster)
    client.close()
    cluster.close()
    return client


CASES = {
    "dt = 1e-320 (t_end / dt overflows)": (lambda: run(dt=1e-320), ValueError,
                                           r"`t_end` / `dt` = 1 / 9.99989e-321 overflows"),
    "save_every = 10**30": (lambda: run(save_every=10**30), ValueError,
                            "`save_every` = 1000000000000000000000000000000 is more than"),
    "an empty ensemble": (lambda: run(theta0=np.zeros((0, 2)), omega0=np.zeros((0, 2))),
                          ValueError, r"`theta0` must hold at least one state, got shape \(0, 2\)"),
    "t_end = 1, dt = 1e-12": (lambda: run(dt=1e-12, keep="final"), ValueError,
                              "1e\\+12 steps, more than the budget"),
    "t_end = 1e12, save_every = 1e9": (lambda: run(t_end=1e12, save_every=10**9), ValueError,
                                       "1e\\+14 steps, more than the budget"),
    "t0 = 1e15 on a driven model": (lambda: pl.simulate(DRIVEN, [0.2], [0.0], t0=1e15),
                                    ValueError, "`t0` = 1e\\+15 s"),
    "t0 = 1e308": (lambda: pl.simulate(DRIVEN, [0.5], [0.0], t_end=1, dt=0.1, t0=1e308),
                   ValueError, "`t0` = 1e\\+308 s"),
    "save_every longer than the run": (lambda: run(t_end=1.0, dt=0.1, save_every=100),
                                       ValueError, "`save_every` = 100 is more than the run's"),
    "progress = 'yes'": (lambda: run(progress="yes"), TypeError,
                         "`progress` must be True, False or None"),
    "allow_long_run = 'yes'": (lambda: run(allow_long_run="yes"), TypeError,
                               "`allow_long_run` must be True or False"),
    "step_count(1.0, -0.1)": (lambda: pl.step_count(1.0, -0.1), ValueError,
                              r"`dt` must be a positive number \(> 0\), got -0.1"),
    "step_count(1, 0)": (lambda: pl.step_count(1, 0), ValueError,
                         r"`dt` must be a positive number \(> 0\), got 0"),
    "step_count(nan, 0.1)": (lambda: pl.step_count(float("nan"), 0.1), ValueError,
                             "`t_end` must be finite"),
    "step, t0 = 1e300": (lambda: pl.step(DRIVEN, [0.2], [0.0], dt=0.01, t0=1e300),
                         ValueError, "`t0` = 1e\\+300 s"),
    "step, an empty ensemble": (lambda: pl.step(DP, np.zeros((0, 2)), np.zeros((0, 2)),
                                                dt=0.01), ValueError, "at least one state"),
    "segments, segment_steps = 10**12": (
        lambda: pl.simulate_segments(DP, [1.0, 0.5], [0.0, 0.0], t_end=1e7, dt=0.01,
                                     method="rk4", segment_steps=10**12), ValueError,
        "a segment of 1e\\+09 steps .* Choose a smaller `segment_steps`"),
    "segments, label = 5": (
        lambda: pl.simulate_segments(DP, [1.0, 0.5], [0.0, 0.0], t_end=10.0, progress=True,
                                     label=5), TypeError, "`label` must be a string"),
    "segments, progress = 'no'": (
        lambda: pl.simulate_segments(DP, [1.0, 0.5], [0.0, 0.0], t_end=10.0, progress="no"),
        TypeError, "`progress` must be True, False or None"),
    "segments, t_end = 1e12": (
        lambda: pl.simulate_segments(DP, [1.0, 0.5], [0.0, 0.0], t_end=1e12), ValueError,
        "more than the budget"),
    "a closed Dask client": (
        lambda: pl.chaos.lyapunov_benettin(DP, [[1.0, 0.5], [1.0, 0.6]], [[0, 0], [0, 0]],
                                           t_end=1.0, method="rk4", client=_closed_client()),
        ValueError, "`client` must be a running dask.distributed.Client, but this one is"),
}


@pytest.mark.parametrize("case", CASES)
def test_bad_input_is_refused_with_a_message_naming_the_argument(case):
    call, error, message = CASES[case]
    with pytest.raises(error, match=message):
        call()


def test_the_valid_neighbours_are_accepted():
    assert run(dt=0.5, t_end=1.0).t.tolist() == [0.0, 0.5, 1.0]
    assert len(run(t_end=1.0, dt=0.1, save_every=10).t) == 2
    assert run(theta0=np.zeros((1, 2)), omega0=np.zeros((1, 2))).theta.shape == (101, 1, 2)
    assert run(progress=False).completed and run(allow_long_run=True).completed
    assert pl.simulate(DRIVEN, [0.2], [0.0], t_end=1.0, t0=1e3, method="rk4").t[0] == 1e3
    assert pl.step_count(1.0, 0.1) == 10 and pl.step_count(0, 0.1) == 0
    run_ = pl.simulate_segments(DP, [1.0, 0.5], [0.0, 0.0], t_end=1.0, method="rk4",
                                label="mine", segment_steps=10**12, progress=False)
    assert [len(segment.t) for segment in run_] == [101]
