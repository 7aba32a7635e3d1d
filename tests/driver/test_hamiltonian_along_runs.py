"""``traj.energy`` is T + V; ``traj.hamiltonian`` is H(q, p, t), the function the run's
equations come from. They differ where the pivot moves: on the Kapitza pendulum H obeys
dH/dt = dH/dt|_(q, p) along the motion, and T + V obeys nothing of the kind."""

import numpy as np
import pytest

import pendulum_lab as pl

DT = 1e-4


@pytest.fixture(scope="module")
def shaken_run(kapitza):
    return pl.simulate(kapitza, [np.pi - 0.3], [0.0], t_end=0.2, dt=DT, method="rk4",
                       progress=False)


def partial_t(model, theta, p, t, h=1e-6):
    return (model.hamiltonian_value(theta, p, t + h)
            - model.hamiltonian_value(theta, p, t - h)) / (2 * h)


def test_the_kapitza_hamiltonian_changes_at_the_rate_of_its_explicit_time_dependence(
        kapitza, shaken_run):
    run = shaken_run
    assert not kapitza.hamiltonian_is_energy
    rate = (run.hamiltonian[2:] - run.hamiltonian[:-2]) / (2 * DT)
    explicit = partial_t(kapitza, run.theta[1:-1], run.p[1:-1], run.t[1:-1])
    scale = np.max(np.abs(explicit))
    assert scale > 100  # the shaking pumps H in and out at a high rate
    assert np.max(np.abs(rate - explicit)) < 1e-3 * scale
    # negative control: T + V is neither conserved nor changing at that rate
    energy_rate = (run.energy[2:] - run.energy[:-2]) / (2 * DT)
    assert np.max(np.abs(energy_rate - explicit)) > 0.5 * scale
    assert np.ptp(run.energy) > 1.0
    # H = T + V - b q' - 2 T_0: they differ by joules here
    assert np.max(np.abs(run.hamiltonian - run.energy)) > 1.0


def test_the_hamiltonian_is_the_energy_where_nothing_moves_the_points(elastic):
    run = pl.simulate(elastic, [1.1, 0.4], [0.0, 0.0], t_end=0.1, dt=0.01, method="rk4",
                      progress=False)
    assert elastic.hamiltonian_is_energy and run.hamiltonian is run.energy
    chain = pl.simulate(pl.double_pendulum(), [1.0, 0.5], [0.0, 0.0], t_end=0.1, dt=0.01,
                        method="rk4", progress=False)
    assert chain.hamiltonian is chain.energy
    # and it is the same H the model evaluates (negative control: the Kapitza pendulum's is not)
    np.testing.assert_allclose(elastic.hamiltonian_value(run.theta, run.p, run.t[:, None]),
                               run.energy, rtol=1e-13)


def test_a_familys_run_holds_one_hamiltonian_per_member(kapitza):
    family = kapitza.family(a=[0.03, 0.05])
    run = pl.simulate(family, [[np.pi - 0.3]] * 2, [[0.0]] * 2, t_end=0.01, dt=1e-3,
                      method="rk4", progress=False)
    assert run.hamiltonian.shape == run.energy.shape == (11, 2)
    for k in range(2):
        member = family.member(k)
        np.testing.assert_allclose(
            run.hamiltonian[:, k],
            member.hamiltonian_value(run.theta[:, k], run.p[:, k], run.t), rtol=1e-12)
