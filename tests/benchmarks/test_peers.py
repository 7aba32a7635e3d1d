"""Our integrators against an independent truth: heyoka's Taylor method at tolerance 1e-16.

heyoka (``pip install -e ".[bench]"``, installed by ``make test``) integrates
the same SymPy equations by a different method (Taylor series of order 20
and more, LLVM-compiled); at tol 1e-16 its states are exact to round-off over
a few seconds of motion. ``glrk8`` and ``rk4`` must agree with them to their
own truncation error. Skipped, with the reason, where heyoka is absent.
"""

from pathlib import Path

import numpy as np
import pytest

import pendulum_lab as pl

BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"
pytestmark = pytest.mark.peers


@pytest.fixture(scope="module")
def peers():
    with pytest.MonkeyPatch.context() as mp:
        mp.syspath_prepend(str(BENCHMARKS))
        import peers as module
    hy, reason = module.heyoka_or_reason()
    if hy is None:
        pytest.skip(reason)
    return module


DP = pl.double_pendulum(m1=1.0, m2=1.0, l1=1.0, l2=1.0, g=9.81)
TRIPLE = pl.n_pendulum(3)
T = 5.0

# (model, start, method, dt, tolerance on theta and omega at T). The tolerances
# are the methods' measured truncation errors with a margin of a few: glrk8
# at dt = 0.005 is within 1e-11 of the truth, rk4 at dt = 5e-4 within 1e-7.
CASES = [
    (DP, [2.0, 2.5], "glrk8", 0.005, 1e-10),
    (DP, [2.0, 2.5], "rk4", 5e-4, 1e-7),
    (TRIPLE, [1.0, 1.5, 2.0], "glrk8", 0.005, 1e-10),
    (TRIPLE, [1.0, 1.5, 2.0], "rk4", 5e-4, 1e-7),
]


@pytest.mark.parametrize("model, theta0, method, dt, tolerance", CASES,
                         ids=[f"n{c[0].n}-{c[2]}" for c in CASES])
def test_agrees_with_heyoka_at_tolerance_1e16(peers, model, theta0, method, dt, tolerance):
    omega0 = np.zeros(model.n)
    times = np.array([1.0, 2.5, T])
    theta_true, omega_true = peers.heyoka_states(model, theta0, omega0, times)
    run = pl.simulate(model, theta0, omega0, t_end=T, dt=dt, method=method,
                      save_every=round(0.5 / dt))
    at = [int(round(t / 0.5)) for t in times]
    gap = max(np.max(np.abs(run.theta[at] - theta_true)),
              np.max(np.abs(run.omega[at] - omega_true)))
    assert gap < tolerance, gap
    # negative control: the same run of a model with g ten parts per million
    # larger is told apart by far more than the tolerance
    other = model.replace(g=9.81 * (1 + 1e-5))
    moved = pl.simulate(other, theta0, omega0, t_end=T, dt=dt, method=method,
                        save_every=round(0.5 / dt))
    assert np.max(np.abs(moved.theta[at] - theta_true)) > 100 * tolerance
