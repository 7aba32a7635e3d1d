"""Damped and driven pendulums: generalized forces, explicit time, conformal methods.

Each property is paired with a negative control that fails the same check.
"""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import pendulum_lab as pl
from pendulum_lab import codegen
from pendulum_lab.driver.loops import compile_method
from pendulum_lab.driver.simulate import hamiltonian_field
from pendulum_lab.symbolic.mechanics import derive_chain, is_identically_zero

DRIVEN = pl.driven_pendulum()  # Baker and Gollub: q = 2, A = 1.2, Omega = 2/3
# Other parameters, so that no formula can hide behind m = l = g = 1.
HEAVY = pl.driven_pendulum(damping=0.3, drive_amplitude=0.8, drive_frequency=1.3, mass=2.0,
                           length=0.7, g=9.81)
DAMPED = pl.driven_pendulum(damping=0.3, drive_amplitude=0.0, mass=2.0, length=0.7, g=9.81)
UNDAMPED_DRIVEN = pl.driven_pendulum(damping=0.0)
FORCED_DP = pl.double_pendulum(m1=1.0, m2=0.6, l1=1.0, l2=0.8, damping=(0.2, 0.1),
                               drive_amplitude=3.0, drive_frequency=2.0)
DAMPED_DP = pl.double_pendulum(damping=0.2)


def reference(model, theta0, omega0, duration, t0=0.0):
    """``(theta, omega)`` at ``t0 + duration`` from SciPy's DOP853 on ``model.accelerations``."""
    n = model.n

    def rhs(t, y):
        return np.concatenate([y[n:], model.accelerations(y[:n], y[n:], t)])

    sol = solve_ivp(rhs, (t0, t0 + duration), np.concatenate([theta0, omega0]), method="DOP853",
                    rtol=1e-13, atol=1e-13)
    return sol.y[:n, -1], sol.y[n:, -1]


def step_jacobian(model, method, q, p, h, t0, d=1e-3):
    """One step's Jacobian in ``(theta, p)`` for one link, by a fourth-order central difference."""
    z = np.array([q, p], float)
    offsets, weights = np.array([2, 1, -1, -2]) * d, np.array([-1, 8, -8, 1]) / (12 * d)
    columns = []
    for j in range(2):
        zs = np.repeat(z[None], 4, axis=0)
        zs[:, j] += offsets
        q1, p1 = pl.step(model, zs[:, :1], p0=zs[:, 1:], dt=h, method=method, t0=t0)
        columns.append(weights @ np.concatenate([q1, p1], axis=1))
    return np.array(columns).T


# ---------------------------------------------------------------- symbolic layer
def test_forced_simple_pendulum_is_the_textbook_equation():
    chain = derive_chain(1, forced=True)
    (theta,), (omega,), (alpha,) = chain.q, chain.omega, chain.omega_dot
    (m,), (length,), (c,) = chain.masses, chain.lengths, chain.damping
    a, w, g, t = chain.drive_amplitude, chain.drive_frequency, chain.g, chain.t
    lhs, rhs = chain.euler_lagrange.lhs[0] - chain.euler_lagrange.rhs[0], (
        m * length**2 * alpha + c * omega + m * g * length * sp.sin(theta) - a * sp.cos(w * t))
    assert sp.expand(lhs - rhs) == 0
    # negative control: the conservative chain lacks the damping and the drive
    conservative = derive_chain(1).euler_lagrange
    assert sp.expand(conservative.lhs[0] - conservative.rhs[0] - rhs) != 0


@pytest.mark.parametrize("n", [2, 3])
def test_joint_damping_is_tridiagonal_and_dissipates(n):
    chain = derive_chain(n, forced=True)
    c, omega = list(chain.damping), chain.omega
    expected = sp.zeros(n)
    for i in range(n):
        expected[i, i] = c[i] + (c[i + 1] if i + 1 < n else 0)
        if i + 1 < n:
            expected[i, i + 1] = expected[i + 1, i] = -c[i + 1]
    assert chain.damping_matrix == expected
    damping_force = chain.generalized_forces.subs(chain.drive_amplitude, 0)
    assert sp.expand(damping_force + chain.damping_matrix * omega) == sp.zeros(n, 1)
    # the power of the damping forces is -2 R, a sum of squares
    power = sp.expand((omega.T * damping_force)[0, 0])
    assert sp.expand(power + 2 * chain.dissipation) == 0
    relative = sum(ci * (omega[i] - (omega[i - 1] if i else 0)) ** 2 for i, ci in enumerate(c))
    assert sp.expand(power + relative) == 0
    # negative control: damping by absolute angular velocities is a different force
    absolute = sum(ci * omega[i] ** 2 for i, ci in enumerate(c))
    assert sp.expand(power + absolute) != 0


@pytest.mark.parametrize("n", [1, 2])
def test_the_conservative_chain_is_the_forced_one_without_forces(n):
    forced, conservative = derive_chain(n, forced=True), derive_chain(n)
    zero_forces = {s: 0 for s in forced.damping} | {forced.drive_amplitude: 0}
    for i in range(n):
        assert is_identically_zero(forced.forcing[i].subs(zero_forces) - conservative.forcing[i])
    assert conservative.parameters == forced.parameters[: 2 * n + 1]
    assert conservative.generalized_forces == sp.zeros(n, 1) and not conservative.forced
    with pytest.raises(ValueError, match="equilibria"):
        _ = forced.equilibria


def test_conservative_kernels_have_no_time_or_force_terms():
    for n in (1, 2, 3):
        body = codegen.kernel_source(derive_chain(n)).split("def hamilton")[1]
        assert f"params[{2 * n + 1}]" not in body and "*t)" not in body
    # negative control: the forced kernels read the force parameters and the time
    forced = codegen.kernel_source(derive_chain(1, forced=True)).split("def hamilton")[1]
    assert "params[5]" in forced and "*t)" in forced


# ---------------------------------------------------------------- numeric model
def test_driven_pendulum_defaults_and_attributes():
    assert DRIVEN.damping == (0.5,) and DRIVEN.drive_amplitude == 1.2
    assert DRIVEN.drive_frequency == pytest.approx(2 / 3, rel=1e-15)
    assert DRIVEN.drive_period == pytest.approx(3 * np.pi, rel=1e-15)
    assert not DRIVEN.is_conservative and not DRIVEN.is_autonomous and DRIVEN.forced
    assert HEAVY.conformal_damping_rate == pytest.approx(0.3 / (2.0 * 0.7**2), rel=1e-15)
    assert DAMPED.is_autonomous and not DAMPED.is_conservative
    assert UNDAMPED_DRIVEN.is_conservative and UNDAMPED_DRIVEN.conformal_damping_rate == 0.0
    assert DAMPED_DP.conformal_damping_rate is None  # joint damping of two links
    sp_ = pl.simple_pendulum()
    assert not sp_.forced and sp_.drive_period is None and sp_.chain is derive_chain(1)
    assert pl.driven_pendulum(damping=0.0, drive_amplitude=0.0).chain is derive_chain(1)


def test_driven_pendulum_accelerations_are_the_equation():
    rng = np.random.default_rng(3)
    theta, omega, t = rng.normal(size=(3, 20))
    m, length, g, c = 2.0, 0.7, 9.81, 0.3
    torque = 0.8 * np.cos(1.3 * t) - c * omega - m * g * length * np.sin(theta)
    expected = torque / (m * length**2)
    got = HEAVY.accelerations(theta[:, None], omega[:, None], t)[:, 0]
    assert np.allclose(got, expected, rtol=1e-13, atol=1e-13)
    # negative control: the drive at another time
    assert not np.allclose(HEAVY.accelerations(theta[:, None], omega[:, None], t + 1)[:, 0],
                           expected, rtol=1e-6, atol=1e-6)
    with pytest.raises(ValueError, match="`t`"):
        HEAVY.accelerations([0.1], [0.0])
    assert DAMPED.accelerations([0.1], [0.2]).shape == (1,)  # no drive: t not needed


@pytest.mark.parametrize("model", [FORCED_DP, HEAVY])
def test_compiled_kernels_agree_with_the_lambdified_model(model):
    """Two code paths from one set of expressions: generated Numba source and lambdify."""
    field = hamiltonian_field(model)
    rng = np.random.default_rng(5)
    n = model.n
    for _ in range(5):
        theta, omega, t = rng.normal(size=n), rng.normal(size=n), float(rng.normal() * 10)
        p = model.momenta(theta, omega)
        dq, dp, acc = np.empty(n), np.empty(n), np.empty(n)
        field.hamilton(t, theta, p, field.params, dq, dp)
        field.acceleration(t, theta, omega, field.params, acc)
        expected_dq, expected_dp = model.vector_field(theta, p, t)
        assert np.allclose(dq, expected_dq, rtol=1e-12, atol=1e-12)
        assert np.allclose(dp, expected_dp, rtol=1e-12, atol=1e-12)
        assert np.allclose(acc, model.accelerations(theta, omega, t), rtol=1e-12, atol=1e-12)
        # negative control: the Hamiltonian part alone misses the forces
        assert not np.allclose(dp, -model.dH_dq(theta, p), rtol=1e-6, atol=1e-6)


def test_jacobian_of_the_damped_field_matches_finite_differences():
    theta, p, t, eps = np.array([0.7, -0.4]), np.array([0.3, 0.5]), 1.1, 1e-6
    z = np.concatenate([theta, p])

    def field(z):
        return np.concatenate(FORCED_DP.vector_field(z[:2], z[2:], t))

    fd = np.column_stack([(field(z + eps * e) - field(z - eps * e)) / (2 * eps) for e in np.eye(4)])
    assert np.allclose(FORCED_DP.jacobian(theta, p, t), fd, rtol=1e-7, atol=1e-7)
    # negative control: the conservative model's Jacobian misses -C in the momentum rows
    conservative = FORCED_DP.replace(damping=0.0, drive_amplitude=0.0)
    assert not np.allclose(conservative.jacobian(theta, p), fd, rtol=1e-4, atol=1e-4)


@pytest.mark.parametrize("kwargs, error, argument", [
    (dict(damping=-0.1), ValueError, "damping"),
    (dict(damping=float("nan")), ValueError, "damping"),
    (dict(damping="a"), TypeError, "damping"),
    (dict(drive_amplitude=float("inf")), ValueError, "drive_amplitude"),
    (dict(drive_amplitude=float("nan")), ValueError, "drive_amplitude"),
    (dict(drive_frequency=0.0), ValueError, "drive_frequency"),
    (dict(drive_frequency=-1.0), ValueError, "drive_frequency"),
    (dict(drive_frequency=float("inf")), ValueError, "drive_frequency"),
])
def test_bad_forces_are_refused_naming_the_argument(kwargs, error, argument):
    with pytest.raises(error, match=f"`{argument}`"):
        pl.driven_pendulum(**kwargs)


def test_bad_forces_on_chains_are_refused():
    with pytest.raises(ValueError, match="`drive_frequency`"):
        pl.double_pendulum(drive_amplitude=1.0)  # a drive needs a frequency
    with pytest.raises(ValueError, match=r"`damping\[1\]`"):
        pl.double_pendulum(damping=(0.1, -0.1))
    with pytest.raises(ValueError, match="`damping`"):
        pl.n_pendulum(3, damping=(0.1, 0.1))
    with pytest.raises(ValueError, match="cannot replace"):
        DRIVEN.replace(friction=1.0)


# ---------------------------------------------------------------- simulate
def test_time_starts_at_t0_and_a_restart_continues_the_run():
    whole = pl.simulate(DRIVEN, [0.2], [0.0], t_end=10.0, dt=0.01, method="rk4")
    first = pl.simulate(DRIVEN, [0.2], [0.0], t_end=5.0, dt=0.01, method="rk4")
    second = pl.simulate(DRIVEN, first.theta[-1], p0=first.p[-1], t_end=5.0, dt=0.01,
                         method="rk4", t0=5.0)
    assert second.t[0] == 5.0 and second.t[-1] == pytest.approx(10.0, rel=1e-14)
    assert len(second.t) == len(first.t) == 501
    assert np.allclose(second.theta[-1], whole.theta[-1], rtol=0, atol=1e-11)
    with pytest.raises(ValueError, match="`t0`"):
        pl.simulate(DRIVEN, [0.2], [0.0], t_end=5.0, dt=0.01, t0=float("nan"))
    with pytest.raises(TypeError, match="`t0`"):
        pl.step(DRIVEN, [0.2], [0.0], dt=0.01, method="rk4", t0="now")
    # negative control: restarting the clock at 0 meets another drive phase
    reset = pl.simulate(DRIVEN, first.theta[-1], p0=first.p[-1], t_end=5.0, dt=0.01,
                        method="rk4")
    assert np.max(np.abs(reset.theta[-1] - whole.theta[-1])) > 1e-2


ORDER_CASES = [
    # model, method, steps, expected order
    (HEAVY, "explicit_euler", (0.004, 0.002, 0.001, 0.0005), 1),
    (HEAVY, "rk4", (0.02, 0.01, 0.005, 0.0025), 4),
    (HEAVY, "glrk4", (0.02, 0.01, 0.005, 0.0025), 4),
    (HEAVY, "glrk8", (0.125, 0.1, 0.0625, 0.05), 8),
    (HEAVY, "conformal_euler", (0.004, 0.002, 0.001, 0.0005), 1),
    (HEAVY, "conformal_leapfrog", (0.04, 0.02, 0.01, 0.005), 2),
    (DRIVEN, "conformal_leapfrog", (0.04, 0.02, 0.01, 0.005), 2),
    (UNDAMPED_DRIVEN, "semi_implicit_euler", (0.004, 0.002, 0.001, 0.0005), 1),
    (UNDAMPED_DRIVEN, "leapfrog", (0.04, 0.02, 0.01, 0.005), 2),
    (FORCED_DP, "rk4", (0.02, 0.01, 0.005, 0.0025), 4),
    (FORCED_DP, "glrk4", (0.02, 0.01, 0.005, 0.0025), 4),
    (FORCED_DP, "glrk8", (0.125, 0.1, 0.0625, 0.05), 8),
]
ORDER_T0, ORDER_T_END = 0.7, 1.0


def order_start(model):
    """A start in the asymptotic regime of these steps (gentler for two links)."""
    return ([1.0], [0.5]) if model.n == 1 else ([0.5, 0.6], [0.0, 0.0])


@pytest.fixture(scope="module")
def references():
    return {id(model): np.concatenate(reference(model, *order_start(model), ORDER_T_END,
                                                t0=ORDER_T0))
            for model in (HEAVY, DRIVEN, UNDAMPED_DRIVEN, FORCED_DP)}


@pytest.mark.parametrize("model, name, dts, order", ORDER_CASES)
def test_observed_order_on_forced_models(model, name, dts, order, references):
    """Each stage or kick must see its own time: a wrong time costs the order."""
    errors = []
    for dt in dts:
        run = pl.simulate(model, *order_start(model), t_end=ORDER_T_END, dt=dt, method=name,
                          t0=ORDER_T0)
        final = np.concatenate([run.theta[-1], run.omega[-1]])
        errors.append(np.max(np.abs(final - references[id(model)])))
    slope = np.polyfit(np.log(dts), np.log(errors), 1)[0]
    assert abs(slope - order) <= (0.3 if order == 8 else 0.15), (slope, errors)
    assert errors[-1] > 1e-12  # above round-off and the reference's error


def test_observed_order_negative_control(references):
    # RK4 stepped with the clock stuck at the start time (a t-blind driver) does not converge
    dts, errors = (0.04, 0.02, 0.01, 0.005), []
    for dt in dts:
        q, p = np.array([1.0]), HEAVY.momenta([1.0], [0.5])
        for _ in range(int(round(ORDER_T_END / dt))):
            q, p = pl.step(HEAVY, q, p0=p, dt=dt, method="rk4", t0=ORDER_T0)
        final = np.concatenate([q, HEAVY.velocities(q, p)])
        errors.append(np.max(np.abs(final - references[id(HEAVY)])))
    assert np.polyfit(np.log(dts), np.log(errors), 1)[0] < 0.5


@pytest.mark.parametrize("model", [HEAVY, DRIVEN, DAMPED])
@pytest.mark.parametrize("h", [0.05, 0.3])
def test_conformal_step_contracts_area_by_exactly_exp_minus_gamma_h(model, h):
    gamma = model.conformal_damping_rate
    for name in ("conformal_leapfrog", "conformal_euler"):
        for q, p, t0 in ((0.3, 0.2, 0.0), (2.5, -1.0, 1.7), (-1.0, 2.0, 5.0)):
            det = np.linalg.det(step_jacobian(model, name, q, p, h, t0))
            assert abs(det / np.exp(-gamma * h) - 1) < 1e-11, (name, det)
    # negative control: RK4's one-step determinant is not exp(-gamma h)
    det = np.linalg.det(step_jacobian(model, "rk4", 2.5, -1.0, 0.3, 1.7))
    assert abs(det / np.exp(-gamma * 0.3) - 1) > 1e-6


def test_conformal_methods_are_the_symplectic_ones_without_damping():
    dp = pl.double_pendulum()
    q, p = np.array([2.0, 2.5]), dp.momenta([2.0, 2.5], [0.3, -0.2])
    for conformal, plain in (("conformal_leapfrog", "leapfrog"),
                             ("conformal_euler", "semi_implicit_euler")):
        assert np.array_equal(np.concatenate(pl.step(dp, q, p0=p, dt=0.05, method=conformal)),
                              np.concatenate(pl.step(dp, q, p0=p, dt=0.05, method=plain)))


@pytest.mark.parametrize("model", [DAMPED, DAMPED_DP])
def test_damped_energy_decays(model):
    n = model.n
    run = pl.simulate(model, [2.0] * n, [0.0] * n, t_end=30.0, dt=0.01, method="glrk4")
    assert np.max(np.diff(run.energy)) <= 1e-12  # dE/dt = -omega C omega <= 0
    assert run.energy[-1] < run.energy[0] - 0.5 * (run.energy[0] - run.potential.min())
    # negative control: without damping the energy stays
    free = model.replace(damping=0.0)
    run = pl.simulate(free, [2.0] * n, [0.0] * n, t_end=30.0, dt=0.01, method="glrk4")
    assert np.max(np.abs(run.energy - run.energy[0])) < 1e-3


@pytest.mark.parametrize("name", ["semi_implicit_euler", "leapfrog"])
@pytest.mark.parametrize("model", [DAMPED, DAMPED_DP])
def test_hamiltonian_methods_refuse_damping(model, name):
    with pytest.raises(ValueError, match=f"'{name}'.*Hamiltonian"):
        pl.simulate(model, [1.0] * model.n, [0.0] * model.n, t_end=1.0, dt=0.01, method=name)
    with pytest.raises(ValueError, match=f"'{name}'"):
        pl.step(model, [1.0] * model.n, [0.0] * model.n, dt=0.01, method=name)
    # negative control: with a drive but no damping they apply (time-dependent H)
    pl.simulate(UNDAMPED_DRIVEN, [1.0], [0.0], t_end=1.0, dt=0.01, method=name)


@pytest.mark.parametrize("name", ["conformal_leapfrog", "conformal_euler"])
def test_conformal_methods_refuse_joint_damping_of_a_chain(name):
    with pytest.raises(ValueError, match=r"not conformal.*C M\(theta\)\^-1 p|C M\(theta\)\^-1 p"):
        pl.simulate(DAMPED_DP, [1.0, 1.0], [0.0, 0.0], t_end=1.0, dt=0.01, method=name)
    # negative control: a conservative chain is fine (gamma = 0)
    pl.simulate(pl.double_pendulum(), [1.0, 1.0], [0.0, 0.0], t_end=0.1, dt=0.01, method=name)


def test_one_loop_call_runs_members_with_their_own_parameters():
    """Rows of ``params`` per member give the same numbers as separate runs."""
    models = [DRIVEN.replace(drive_amplitude=a) for a in (1.0, 1.2, 1.5)]
    fields = [hamiltonian_field(m) for m in models]
    method = pl.get_method("conformal_leapfrog")
    batch = type(fields[0])(fields[0].hamilton, fields[0].acceleration,
                            np.stack([f.params for f in fields]), fields[0].separable,
                            np.array([f.damping_rate for f in fields]))
    q, p = np.full((3, 1), 0.2), np.zeros((3, 1))
    saved = np.full((3, 2, 1), np.nan)
    stats = np.zeros((3, 4), dtype=np.int64)
    compiled = compile_method(method, batch, 1)
    compiled.advance(q, p, 0.01, 500, 0, 500, saved, saved.copy(), stats, compiled.new_memory(3),
                     t0=0.3)
    for k, model in enumerate(models):
        run = pl.simulate(model, [0.2], p0=[0.0], t_end=5.0, dt=0.01, method=method, t0=0.3)
        assert np.array_equal(q[k], run.theta[-1]) and np.array_equal(p[k], run.p[-1])
    assert abs(q[0, 0] - q[2, 0]) > 1e-3  # negative control: the members differ
