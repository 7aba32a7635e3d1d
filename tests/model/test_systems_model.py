"""Models of any mechanical system under simulate and step: the elastic, Kapitza and cart
pendulums, each property with a negative control."""

import pickle

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import pendulum_lab as pl
from pendulum_lab.analysis import reversibility_error, symplecticity_defect


def test_elastic_energy_bounded_over_1000_periods_with_glrk4_and_drifts_with_rk4(elastic):
    r_star = 0.75 + 9.81 / elastic.parameter_values[sp.Symbol("k", positive=True)]
    period = 2 * np.pi / np.sqrt(9.81 / r_star)  # the slower (swinging) mode
    t_end, dt = 1000 * period, 0.04
    start = ([r_star + 0.05, 0.4], [0.0, 0.0])
    gauss = pl.simulate(elastic, *start, t_end=t_end, dt=dt, method="glrk4", save_every=10)
    error = np.abs(gauss.energy - gauss.energy[0])
    tenth = len(error) // 10
    assert error.max() < 1e-5
    assert error[-tenth:].max() < 2 * error[:tenth].max()  # bounded: no growth
    rk4 = pl.simulate(elastic, *start, t_end=t_end, dt=dt, method="rk4", save_every=10)
    drift = np.abs(rk4.energy - rk4.energy[0])
    assert drift[-tenth:].max() > 5 * drift[:tenth].max()  # negative control: it drifts


def test_elastic_step_is_symplectic_with_gauss_and_not_with_rk4(elastic):
    state = dict(theta0=[1.1, 0.5], omega0=[0.3, -0.2], dt=0.1)
    assert symplecticity_defect(elastic, **state, method="glrk4") < 1e-8
    assert symplecticity_defect(elastic, **state, method="leapfrog") < 1e-8
    assert symplecticity_defect(elastic, **state, method="rk4") > 1e-6
    assert reversibility_error(elastic, **state, method="glrk4") < 1e-12
    assert reversibility_error(elastic, **state, method="rk4") > 1e-8


def test_step_equals_one_step_of_simulate(elastic):
    run = pl.simulate(elastic, [1.0, 0.2], [0.1, 0.0], t_end=0.05, dt=0.05, method="glrk4")
    q, p = pl.step(elastic, [1.0, 0.2], [0.1, 0.0], dt=0.05, method="glrk4")
    assert np.allclose(q, run.theta[-1], rtol=0, atol=1e-14)
    assert np.allclose(p, run.p[-1], rtol=0, atol=1e-14)


def hamilton_ode(model):
    """The same Hamilton equations as a SciPy right-hand side (the model's NumPy functions)."""
    n = model.n

    def rhs(t, y):
        dq, dp = model.vector_field(y[:n], y[n:], t=t)
        return np.concatenate([dq, dp])

    return rhs


@pytest.mark.parametrize("method", ["glrk4", "rk4", "leapfrog"])
def test_kapitza_agrees_with_dop853_of_the_same_hamilton_equations(kapitza, method):
    theta0, omega0, t_end = [2.9], [0.0], 1.0
    run = pl.simulate(kapitza, theta0, omega0, t_end=t_end, dt=2e-4, method=method)
    p0 = kapitza.momenta(theta0, omega0, t=0.0)
    ref = solve_ivp(hamilton_ode(kapitza), (0, t_end), [*theta0, *p0], method="DOP853",
                    rtol=1e-12, atol=1e-12, t_eval=run.t[::500])
    assert np.max(np.abs(run.theta[::500, 0] - ref.y[0])) < 1e-6
    assert np.max(np.abs(run.p[::500, 0] - ref.y[1])) < 1e-5
    # negative control: the same run with the pivot standing still is far away
    still = pl.simulate(kapitza.replace(a=1e-9), theta0, omega0, t_end=t_end, dt=2e-4,
                        method=method)
    assert np.max(np.abs(still.theta[::500, 0] - ref.y[0])) > 0.1


def test_kapitza_energy_is_not_conserved_and_the_inverted_position_is_stable(kapitza):
    run = pl.simulate(kapitza, [np.pi - 0.1], [0.0], t_end=5.0, dt=2e-4, method="glrk4")
    assert np.ptp(run.energy) > 0.1  # the shaking pivot does work
    assert np.all(np.abs(run.theta[:, 0] - np.pi) < 0.2)  # a^2 w^2 = 25 > 2 g l = 19.6
    slow = kapitza.replace(w=80.0)  # a^2 w^2 = 16 < 19.6: it falls
    fallen = pl.simulate(slow, [np.pi - 0.1], [0.0], t_end=5.0, dt=2e-4, method="glrk4")
    assert np.max(np.abs(fallen.theta[:, 0] - np.pi)) > 1.0


def test_kapitza_momentum_depends_on_time_and_needs_it(kapitza):
    p_a = kapitza.momenta([1.0], [0.0], t=0.0)
    p_b = kapitza.momenta([1.0], [0.0], t=0.01)
    assert not np.allclose(p_a, p_b)
    with pytest.raises(ValueError, match="`t` is required"):
        kapitza.momenta([1.0], [0.0])


def test_one_set_of_model_methods_serves_chains_and_systems(kapitza):
    """A chain's compiled functions take the time and ignore it, so a system overrides none of
    the numeric methods only to pass the time; where the time enters, it is used."""
    from pendulum_lab.model import SystemModel
    from pendulum_lab.model.functions import ModelFunctions

    shared = {"mass_matrix_at", "accelerations", "generalized_forces", "vector_field", "momenta",
              "velocities", "kinetic_energy", "potential_energy", "dH_dq", "hamiltonian_value"}
    assert shared <= set(vars(ModelFunctions)) and not shared & set(vars(SystemModel))
    assert "jacobian" in vars(SystemModel)  # negative control: an override is seen
    driven, theta, p = pl.driven_pendulum(), np.array([0.4]), np.array([0.2])
    for name in ("mass_matrix_at", "hamiltonian_value", "dH_dq"):
        args = (theta,) if name == "mass_matrix_at" else (theta, p)
        assert np.array_equal(getattr(driven, name)(*args, t=3.0), getattr(driven, name)(*args))
    # negative controls: the drive and a shaken pivot depend on the time
    assert not np.array_equal(driven.vector_field(theta, p, t=0.0)[1],
                              driven.vector_field(theta, p, t=3.0)[1])
    assert not np.array_equal(kapitza.hamiltonian_value([1.0], [0.5], t=0.0),
                              kapitza.hamiltonian_value([1.0], [0.5], t=0.01))


def test_cart_conserves_horizontal_momentum():
    cart = pl.cart_pendulum()
    run = pl.simulate(cart, [0.0, 2.0], [0.3, 0.0], t_end=20.0, dt=0.01, method="glrk4")
    assert np.ptp(run.p[:, 0]) < 1e-12
    assert np.ptp(run.p[:, 1]) > 0.1  # negative control: the angle's momentum is not
    assert np.max(np.abs(run.energy - run.energy[0])) < 1e-6


def test_jacobian_matches_finite_differences(kapitza, elastic):
    for model, t in ((kapitza, 0.013), (elastic, None)):
        n = model.n
        z = np.array([1.1, 0.4, 0.3, -0.2][: 2 * n]) if n == 2 else np.array([1.1, 0.3])
        exact = model.jacobian(z[:n], z[n:], t=t)
        eps, columns = 1e-6, []
        for j in range(2 * n):
            dz = np.zeros(2 * n)
            dz[j] = eps
            plus = np.concatenate(model.vector_field((z + dz)[:n], (z + dz)[n:], t=t))
            minus = np.concatenate(model.vector_field((z - dz)[:n], (z - dz)[n:], t=t))
            columns.append((plus - minus) / (2 * eps))
        assert np.allclose(exact, np.array(columns).T, rtol=1e-6, atol=1e-6)


def test_chain_kernels_unchanged_and_a_system_chain_runs_like_the_chain():
    """The one generator: a chain's described by its points gives the chain's motion."""
    from pendulum_lab.model.system import SystemModel
    from pendulum_lab.symbolic.systems import chain_system

    general = SystemModel(chain_system(2))
    dp = pl.double_pendulum()
    a = pl.simulate(general, [1.0, 2.0], [0.0, 0.0], t_end=2.0, dt=0.01, method="glrk4")
    b = pl.simulate(dp, [1.0, 2.0], [0.0, 0.0], t_end=2.0, dt=0.01, method="glrk4")
    assert np.max(np.abs(a.theta - b.theta)) < 1e-10


def test_lengths_are_never_reduced_by_whole_turns(elastic):
    """A chain's large angles are reduced by 2 pi turns; a spring's length must not be."""
    r0, dt = 9000.0, 1e-3
    q, _ = pl.step(elastic, [r0, 0.0], [0.0, 0.0], dt=dt, method="rk4")
    acceleration = elastic.accelerations([r0, 0.0], [0.0, 0.0])[0]
    assert abs(q[0] - (r0 + acceleration * dt**2 / 2)) < 1e-6
    run = pl.simulate(elastic, [r0, 0.0], [0.0, 0.0], t_end=dt, dt=dt, method="rk4")
    assert abs(run.theta[-1, 0] - q[0]) < 1e-9


# ---- bad input ------------------------------------------------------------------------------
def test_methods_that_do_not_apply_are_refused_naming_those_that_do(elastic, kapitza):
    with pytest.raises(ValueError, match="variational_midpoint.*Methods that can: .*glrk4"):
        pl.simulate(kapitza, [3.0], [0.0], t_end=1.0, dt=0.01, method="variational_midpoint")
    th, m, c = sp.symbols("theta m c", real=True)
    damped = pl.mechanical_system([th], {m: 1.0, c: 0.2}, points=[(sp.sin(th), -sp.cos(th))],
                                  masses=[m], gravity=9.81,
                                  dissipation=c * sp.Symbol("theta_dot", real=True) ** 2 / 2)
    for method in ("leapfrog", "conformal_euler"):
        with pytest.raises(ValueError, match=f"{method}.*Methods that can: .*rk4"):
            pl.simulate(damped, [1.0], [0.0], t_end=1.0, dt=0.01, method=method)
    run = pl.simulate(damped, [1.0], [0.0], t_end=10.0, dt=0.01, method="glrk4")
    assert run.energy[-1] < 0.5 * (run.energy[0] + 9.81) - 9.81  # it loses energy


def test_bad_input_is_refused_naming_the_argument(elastic):
    with pytest.raises(ValueError, match="`theta0` must have shape"):
        pl.simulate(elastic, [1.0], [0.0], t_end=1.0, dt=0.01)
    with pytest.raises(ValueError, match=r"`values` names \['q'\].*parameters are"):
        elastic.replace(q=1.0)
    with pytest.raises(ValueError, match="`amplitude` must be a positive finite number"):
        pl.kapitza_pendulum(amplitude=-1.0)
    with pytest.raises(ValueError, match=r"`parameters\[k\]` must be finite"):
        elastic.replace(k=float("nan"))
    with pytest.raises(ValueError, match=r"`values` must be one of \['m', 'k', 'l_0', 'g'\]"):
        elastic.family(q=[9.81, 1.62])
    x = sp.Symbol("x", real=True)
    with pytest.raises(ValueError, match="`points\\[0\\]` uses c, which is neither"):
        pl.mechanical_system([x], {"m": 1.0}, points=[(x + sp.Symbol("c"), 0)],
                             masses=[sp.Symbol("m")])


def kapitza_reference(kapitza, theta0, t_end):
    p0 = kapitza.momenta(theta0, [0.0], t=0.0)
    ref = solve_ivp(hamilton_ode(kapitza), (0, t_end), [*theta0, *p0], method="DOP853",
                    rtol=1e-13, atol=1e-13)
    return ref.y[0, -1]


@pytest.mark.parametrize("method", ["explicit_euler", "semi_implicit_euler", "leapfrog", "rk4",
                                    "glrk4", "semi_implicit_euler_velocity", "leapfrog_velocity",
                                    "conformal_euler", "conformal_leapfrog"])
def test_every_method_that_applies_to_kapitza_converges_at_its_order(kapitza, method):
    """The time-dependent field through every method's own handling of t: the error against
    DOP853 falls by 2**order when the step is halved (negative control: a method that froze
    the drive at t = 0 would converge to another motion, and its error would not fall)."""
    theta0, t_end = [2.9], 0.2
    exact = kapitza_reference(kapitza, theta0, t_end)
    errors = [abs(pl.simulate(kapitza, theta0, [0.0], t_end=t_end, dt=dt, method=method,
                              keep="final").theta[-1, 0] - exact) for dt in (1e-3, 5e-4)]
    observed = np.log2(errors[0] / errors[1])
    assert observed > pl.get_method(method).order - 0.3, (errors, observed)


@pytest.mark.parametrize("method", ["glrk8", "glrk12", "glrk16"])
def test_high_order_gauss_methods_match_dop853_on_kapitza(kapitza, method):
    exact = kapitza_reference(kapitza, [2.9], 0.2)
    run = pl.simulate(kapitza, [2.9], [0.0], t_end=0.2, dt=1e-3, method=method, keep="final")
    assert abs(run.theta[-1, 0] - exact) < 1e-10


@pytest.mark.parametrize("factory", ["elastic_pendulum", "kapitza_pendulum", "cart_pendulum"])
def test_generated_kernels_equal_the_numpy_vector_field(factory):
    model = getattr(pl, factory)()
    kernels, params = model.kernels(), np.array(list(model.parameter_values.values()))
    rng = np.random.default_rng(3)
    for _ in range(5):
        q, p = rng.uniform(0.5, 1.5, (2, model.n))
        t = float(rng.uniform(0, 1))
        dq, dp = np.empty(model.n), np.empty(model.n)
        kernels.hamilton(t, q, p, params, dq, dp)
        want_dq, want_dp = model.vector_field(q, p, t=t)
        assert np.allclose(dq, want_dq, rtol=1e-12, atol=1e-12)
        assert np.allclose(dp, want_dp, rtol=1e-12, atol=1e-12)
        out = np.empty(model.n)
        kernels.acceleration(t, q, want_dq, params, out)
        assert np.allclose(out, model.accelerations(q, want_dq, t=t), rtol=1e-12, atol=1e-12)


# ---- families of a system -----------------------------------------------------------------
def test_a_family_runs_each_member_as_the_member_runs_alone(elastic):
    springs = elastic.family(k=[20.0, 39.24, 60.0])
    assert springs.shape == (3,) and len(springs) == 3
    start = np.broadcast_to(elastic.start, (3, 2))
    together = pl.simulate(springs, start, np.zeros((3, 2)), t_end=2.0, dt=0.01, method="rk4")
    for i in range(3):
        alone = pl.simulate(springs.member(i), elastic.start, [0.0, 0.0], t_end=2.0, dt=0.01,
                            method="rk4")
        assert np.array_equal(alone.theta, together.theta[:, i])
        assert np.array_equal(alone.energy, together.energy[:, i])
    # negative control: the members are different systems
    assert np.max(np.abs(together.theta[-1, 0] - together.theta[-1, 2])) > 0.1
    assert pickle.loads(pickle.dumps(springs)).values["k"].tolist() == [20.0, 39.24, 60.0]
    assert springs.select([0, 2]).member(1).parameter_values == springs.member(2).parameter_values


def test_a_family_refuses_what_it_cannot_vary_or_answer(elastic, kapitza):
    with pytest.raises(ValueError, match="`values` 'w' sets how the Kapitza pendulum depends "
                                         "on the time.*can vary are \\['a', 'm', 'l', 'g'\\]"):
        kapitza.family(w=[90.0, 100.0])
    springs = elastic.family(k=[20.0, 60.0])
    with pytest.raises(TypeError, match="one set of equilibria per member"):
        _ = springs.equilibria
    with pytest.raises(TypeError, match="already a family"):
        springs.family(m=[1.0, 2.0])
    with pytest.raises(ValueError, match="must broadcast together"):
        elastic.family(k=[20.0, 60.0], m=[1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="name at least one parameter"):
        elastic.family()
    # negative control: the shaking amplitude does not set the period, so it can vary
    assert kapitza.family(a=[0.03, 0.06]).drive_period == kapitza.drive_period


def test_a_drive_given_as_a_force_sets_the_clock_a_family_cannot_vary():
    th = sp.Symbol("theta", real=True)
    m, length, g, f, drive = sp.symbols("m l g f Omega", positive=True)
    t = sp.Symbol("t", real=True)
    driven = pl.mechanical_system([th], {m: 1.0, length: 1.0, g: 9.81, f: 0.5, drive: 2.0},
                                  points=[(length * sp.sin(th), -length * sp.cos(th))],
                                  masses=[m], gravity=g, forces=[f * sp.cos(drive * t)],
                                  period=2 * np.pi / 2.0, name="a driven pendulum")
    with pytest.raises(ValueError, match="'Omega' sets how a driven pendulum depends on the "
                                         "time"):
        driven.family(Omega=[1.5, 2.5])
    # negative control: the drive's strength does not set the period, so it can vary
    assert len(driven.family(f=[0.2, 0.8])) == 2
