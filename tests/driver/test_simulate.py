"""The numeric model, the simulate driver, and errors on bad input."""

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import pendulum_lab as pl

DP = pl.double_pendulum()
SP = pl.simple_pendulum()
angles = st.floats(-np.pi, np.pi)
speeds = st.floats(-5.0, 5.0)


def test_public_contract_names():
    ch = pl.n_pendulum(3, masses=(1.0, 1.0, 1.0), lengths=(1.0, 1.0, 1.0), g=9.81)
    for model, n in ((SP, 1), (DP, 2), (ch, 3)):
        assert model.n == n
        assert model.mass_matrix.shape == (n, n) and model.forcing.shape == (n, 1)
        assert model.lagrangian.free_symbols and model.hamiltonian.free_symbols
    traj = pl.simulate(DP, [1.0, 0.5], [0.0, 0.0], t_end=1.0, dt=0.01, method="glrk4")
    assert traj.t.shape == (101,)
    for name in ("theta", "omega", "p"):
        assert getattr(traj, name).shape == (101, 2)
    for name in ("kinetic", "potential", "energy"):
        assert getattr(traj, name).shape == (101,)


@settings(max_examples=30, deadline=None)
@given(st.lists(angles, min_size=2, max_size=2), st.lists(speeds, min_size=2, max_size=2))
def test_momenta_and_velocities_are_inverse(theta, omega):
    p = DP.momenta(theta, omega)
    assert np.allclose(DP.velocities(theta, p), omega, rtol=1e-12, atol=1e-12)


@settings(max_examples=30, deadline=None)
@given(st.lists(angles, min_size=2, max_size=2), st.lists(speeds, min_size=2, max_size=2))
def test_hamiltonian_value_equals_energy(theta, omega):
    p = DP.momenta(theta, omega)
    assert np.isclose(DP.hamiltonian_value(theta, p), DP.energy(theta, omega), rtol=1e-12,
                      atol=1e-12)


@settings(max_examples=20, deadline=None)
@given(st.lists(angles, min_size=2, max_size=2), st.lists(speeds, min_size=2, max_size=2))
def test_jacobian_matches_finite_differences(theta, omega):
    theta = np.asarray(theta)
    p = DP.momenta(theta, omega)
    z = np.concatenate([theta, p])

    def rhs(z):
        return np.concatenate([DP.dH_dp(z[:2], z[2:]), -DP.dH_dq(z[:2], z[2:])])

    eps = 1e-6
    fd = np.column_stack([(rhs(z + eps * e) - rhs(z - eps * e)) / (2 * eps) for e in np.eye(4)])
    assert np.allclose(DP.jacobian(theta, p), fd, rtol=1e-6, atol=1e-6)


def test_simple_pendulum_numbers():
    model = pl.simple_pendulum(mass=2.0, length=0.5, g=9.81)
    assert np.isclose(model.accelerations([0.3], [1.0])[0], -9.81 / 0.5 * np.sin(0.3))
    assert np.isclose(model.potential_energy([0.0]), -2.0 * 9.81 * 0.5)
    assert np.isclose(model.kinetic_energy([0.0], [2.0]), 0.5 * 2.0 * 0.25 * 4.0)


def test_batches_give_the_same_numbers_as_single_states():
    rng = np.random.default_rng(1)
    theta, omega = rng.uniform(-3, 3, (5, 3, 2)), rng.uniform(-2, 2, (5, 3, 2))
    batch = DP.accelerations(theta, omega)
    assert batch.shape == (5, 3, 2)
    single = DP.accelerations(theta[2, 1], omega[2, 1])
    assert np.array_equal(batch[2, 1], single)
    for method in ("rk4", "glrk4", "leapfrog"):
        ens = pl.simulate(DP, theta[:, 0], omega[:, 0], t_end=0.5, dt=0.01, method=method)
        one = pl.simulate(DP, theta[3, 0], omega[3, 0], t_end=0.5, dt=0.01, method=method)
        assert ens.theta.shape == (51, 5, 2)
        assert np.allclose(ens.theta[:, 3], one.theta, rtol=0, atol=1e-12)


@pytest.mark.parametrize("n", [3, 4, 5])
@pytest.mark.parametrize(
    "method, dts, bounds",
    # halving dt divides the energy error by about 2**order: 16 and 256
    [("glrk4", (0.01, 0.005), (12, 20)), ("glrk8", (0.02, 0.01), (180, 400))],
)
def test_n_pendulum_gauss_energy_error_has_the_methods_order(n, method, dts, bounds):
    theta0 = np.linspace(1.0, -0.5, n)
    errors = [np.max(np.abs(pl.simulate(pl.n_pendulum(n), theta0, np.zeros(n), t_end=2.0, dt=dt,
                                        method=method).energy_error))
              for dt in dts]
    assert bounds[0] < errors[0] / errors[1] < bounds[1], errors


def test_inputs_are_not_modified():
    theta0, omega0 = np.array([1.0, 0.5]), np.array([0.0, 0.2])
    p0 = DP.momenta(theta0, omega0)
    before = (theta0.copy(), omega0.copy(), p0.copy())
    pl.simulate(DP, theta0, omega0, t_end=0.1, dt=0.01, method="glrk4")
    pl.step(DP, theta0, p0=p0, dt=0.01, method="glrk4")
    pl.step(DP, theta0, p0=p0, dt=0.01, method="leapfrog_velocity")
    for a, b in zip((theta0, omega0, p0), before):
        assert np.array_equal(a, b)


def test_starting_from_momenta_matches_starting_from_velocities():
    theta0, omega0 = np.array([1.0, 0.5]), np.array([0.3, -0.2])
    p0 = DP.momenta(theta0, omega0)
    for method in ("glrk4", "leapfrog_velocity"):
        a = pl.simulate(DP, theta0, omega0, t_end=1.0, dt=0.01, method=method)
        b = pl.simulate(DP, theta0, p0=p0, t_end=1.0, dt=0.01, method=method)
        assert np.allclose(a.theta, b.theta, rtol=0, atol=1e-13)
    with pytest.raises(TypeError, match="exactly one"):
        pl.simulate(DP, theta0, omega0, p0=p0)
    with pytest.raises(TypeError, match="exactly one"):
        pl.simulate(DP, theta0)


def test_save_every_thins_the_output():
    full = pl.simulate(DP, [1.0, 1.0], [0.0, 0.0], t_end=1.0, dt=0.01, method="rk4")
    thin = pl.simulate(DP, [1.0, 1.0], [0.0, 0.0], t_end=1.0, dt=0.01, method="rk4", save_every=10)
    assert thin.t.shape == (11,)
    assert np.array_equal(thin.theta, full.theta[::10])


def test_explicit_euler_blow_up_stops_with_a_warning():
    with pytest.warns(RuntimeWarning, match="non-finite at step"):
        traj = pl.simulate(DP, [3.0, -3.0], [20.0, -20.0], t_end=200.0, dt=0.5,
                           method="explicit_euler")
    assert not traj.completed
    assert traj.t.size < 401 and np.all(np.isfinite(traj.theta))


def test_a_normal_run_does_not_warn():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        traj = pl.simulate(DP, [1.0, 1.0], [0.0, 0.0], t_end=1.0, dt=0.01, method="explicit_euler")
    assert traj.completed


# ---------------------------------------------------------------- bad input
@pytest.mark.parametrize("kwargs, error, argument", [
    (dict(m1=0.0), ValueError, "m1"),
    (dict(m2=-1.0), ValueError, "m2"),
    (dict(l1=float("nan")), ValueError, "l1"),
    (dict(l2=float("inf")), ValueError, "l2"),
    (dict(g=float("nan")), ValueError, "g"),
    (dict(m1="1"), TypeError, "m1"),
])
def test_bad_double_pendulum_parameters(kwargs, error, argument):
    with pytest.raises(error, match=f"`{argument}`"):
        pl.double_pendulum(**kwargs)


def test_bad_simple_and_n_pendulum_parameters():
    with pytest.raises(ValueError, match="`mass`"):
        pl.simple_pendulum(mass=-1)
    with pytest.raises(ValueError, match="`length`"):
        pl.simple_pendulum(length=0)
    with pytest.raises(ValueError, match="`n`"):
        pl.n_pendulum(0)
    with pytest.raises(TypeError, match="`n`"):
        pl.n_pendulum(2.5)
    with pytest.raises(ValueError, match="`masses`"):
        pl.n_pendulum(3, masses=(1.0, 1.0))
    with pytest.raises(ValueError, match=r"`lengths\[1\]`"):
        pl.n_pendulum(2, lengths=(1.0, -1.0))


@pytest.mark.parametrize("kwargs, error, argument", [
    (dict(dt=0.0), ValueError, "dt"),
    (dict(dt=-0.1), ValueError, "dt"),
    (dict(dt=float("nan")), ValueError, "dt"),
    (dict(t_end=0.0), ValueError, "t_end"),
    (dict(t_end=0.001, dt=0.01), ValueError, "t_end"),
    (dict(theta0=[1.0]), ValueError, "theta0"),
    (dict(theta0=[1.0, float("nan")]), ValueError, "theta0"),
    (dict(omega0=[0.0, 0.0, 0.0]), ValueError, "omega0"),
    (dict(omega0=["a", "b"]), TypeError, "omega0"),
    (dict(method="rk5"), ValueError, "method"),
    (dict(method=4), TypeError, "method"),
    (dict(save_every=0), ValueError, "save_every"),
])
def test_bad_simulate_arguments(kwargs, error, argument):
    args = dict(theta0=[1.0, 1.0], omega0=[0.0, 0.0], t_end=1.0, dt=0.01, method="rk4") | kwargs
    with pytest.raises(error, match=f"`{argument}`"):
        pl.simulate(DP, **args)


def test_unknown_method_lists_the_valid_ones():
    with pytest.raises(ValueError) as info:
        pl.simulate(DP, [1.0, 1.0], [0.0, 0.0], method="verlet")
    for name in pl.METHODS:
        assert name in str(info.value)


def test_model_argument_is_checked():
    with pytest.raises(TypeError, match="`model`"):
        pl.simulate("double", [1.0, 1.0], [0.0, 0.0])
    with pytest.raises(ValueError, match="`dt`"):
        pl.step(DP, [1.0, 1.0], p0=[0.0, 0.0], dt=0.0, method="rk4")
