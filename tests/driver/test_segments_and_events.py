"""The segment driver and the event locator: each checked against a known answer.

Every property has a negative control: a case where the same check must fail.
"""

import copy
import importlib
import itertools

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab import events

DP = pl.double_pendulum()
SP = pl.simple_pendulum()
CHAOTIC = np.array([2.0, 2.5])  # at rest: round-off grows by e^(t / 0.6 s) here


# --------------------------------------------------------------------------- the step-count rule
def test_step_count_forgives_only_round_off():
    assert pl.step_count(0.3, 0.1) == 3  # 0.3 / 0.1 = 2.9999999999999996
    assert pl.step_count(1.0, 0.3) == 3
    assert pl.step_count(30.005, 0.01) == 3000
    # negative control: a genuine shortfall of one part in 1e9 is not forgiven
    assert pl.step_count(0.3 * (1 - 1e-9), 0.1) == 2
    traj = pl.simulate(SP, [1.0], [0.0], t_end=0.3, dt=0.1, method="rk4")
    assert len(traj.t) == pl.step_count(0.3, 0.1) + 1


# --------------------------------------------------------------------------- segments
@pytest.mark.parametrize("method", ["glrk4", "rk4", "leapfrog_velocity"])
def test_a_segmented_run_is_the_same_run_to_the_last_bit(method):
    theta0 = np.stack([CHAOTIC, [0.3, -0.2]])
    whole = pl.simulate(DP, theta0, np.zeros_like(theta0), t_end=20.0, dt=0.01, method=method,
                        save_every=5)
    run = pl.simulate_segments(DP, theta0, np.zeros_like(theta0), t_end=20.0, dt=0.01,
                               method=method, save_every=5, segment_steps=35)
    pieces = list(run)
    assert len(pieces) == 58 and run.done == 2000  # 57 segments of 35 steps, one of 5
    for a, b in zip(pieces[:-1], pieces[1:]):
        assert np.array_equal(a.theta[-1], b.theta[0]) and a.t[-1] == pytest.approx(b.t[0])
    theta = np.concatenate([pieces[0].theta] + [p.theta[1:] for p in pieces[1:]])
    t = np.concatenate([pieces[0].t] + [p.t[1:] for p in pieces[1:]])
    assert np.array_equal(theta, whole.theta)
    assert np.allclose(t, whole.t, rtol=0, atol=1e-12)
    # Negative control: restarting from angular velocities, as the chaotic runs did before,
    # adds a rounding at each restart that the chaotic member amplifies far above round-off.
    q, w, chained = theta0, np.zeros_like(theta0), [theta0]
    for _ in range(40):
        seg = pl.simulate(DP, q, w, t_end=0.5, dt=0.01, method="glrk4")
        q, w = seg.theta[-1], seg.omega[-1]
        chained.append(q)
    exact = pl.simulate(DP, theta0, np.zeros_like(theta0), t_end=20.0, dt=0.01, method="glrk4")
    assert np.max(np.abs(chained[-1][0] - exact.theta[-1][0])) > 1e-9


@pytest.mark.parametrize("model", [pl.driven_pendulum(), pl.kapitza_pendulum()],
                         ids=["driven", "kapitza"])
def test_a_segmented_driven_run_is_the_same_run_to_the_last_bit(model):
    # The chaotic driven pendulum over 60 drive periods, the Kapitza pendulum over 60
    # shakes; t0 = 0.3 s so that the clock is not a plain multiple of the step.
    period = model.drive_period
    dt, t0 = period / 50, 0.3
    start = (np.array([np.pi - 0.3]), np.array([0.2]))
    whole = pl.simulate(model, *start, t_end=60 * period, dt=dt, method="rk4", t0=t0,
                        save_every=2, progress=False)
    pieces = list(pl.simulate_segments(model, *start, t_end=60 * period, dt=dt, method="rk4",
                                       t0=t0, save_every=2, segment_steps=70, progress=False))
    assert len(pieces) > 40
    for name in ("t", "theta", "p", "energy", "hamiltonian"):
        joined = np.concatenate([getattr(pieces[0], name)]
                                + [getattr(piece, name)[1:] for piece in pieces[1:]])
        assert np.array_equal(joined.reshape(getattr(whole, name).shape),
                              getattr(whole, name)), name
    # Negative control: segments that count their step times from their own start (the
    # clock before) leave the long run in the last bits, and the drive makes it grow.
    from pendulum_lab.driver.loops import compile_method
    from pendulum_lab.driver.simulate import hamiltonian_field, integrate, to_method_variables
    method = pl.get_method("rk4")
    compiled = compile_method(method, hamiltonian_field(model), model.n)
    q = start[0].reshape(1, 1).copy()
    y = to_method_variables(model, method, q, start[1].reshape(1, 1), False, t=t0)
    memory, done, last = compiled.new_memory(1), 0, None
    while done < len(whole.t) * 2 - 2:
        steps = min(70, 2 * (len(whole.t) - 1) - done)
        last = integrate(model, compiled, q, y, (1,), t_end=steps * dt, dt=dt, n_steps=steps,
                         save_every=2, t0=t0 + done * dt, progress=False, memory=memory)
        done += steps
    assert not np.array_equal(last.theta[-1, 0], whole.theta[-1])


def test_segments_carry_the_start_time():
    run = pl.simulate_segments(SP, [1.0], [0.0], t_end=1.0, dt=0.1, method="rk4", t0=5.0,
                               segment_steps=4)
    starts = [float(seg.t[0]) for seg in run]
    assert np.allclose(starts, [5.0, 5.4, 5.8]) and run.time == pytest.approx(6.0)
    # the start time shifts the clock, not the motion (the pendulum is autonomous)
    late = pl.simulate(SP, [1.0], [0.0], t_end=1.0, dt=0.1, method="rk4", t0=5.0)
    early = pl.simulate(SP, [1.0], [0.0], t_end=1.0, dt=0.1, method="rk4")
    assert np.array_equal(late.theta, early.theta)
    assert np.allclose(late.t - early.t, 5.0) and not np.allclose(late.t, early.t)
    with pytest.raises(ValueError, match="`t0`"):
        pl.simulate(SP, [1.0], [0.0], t0=float("nan"))


def test_members_can_leave_and_move_between_segments():
    theta0 = np.array([[0.1, 0.0], [0.2, 0.0], [0.3, 0.0]])
    run = pl.simulate_segments(DP, theta0, np.zeros_like(theta0), t_end=1.0, dt=0.01,
                               method="rk4", segment_steps=50)
    seen = []
    for _segment in run:
        seen.append(run.members.tolist())
        if len(seen) == 1:
            run.keep(np.array([True, False, True]))
    assert seen == [[0, 1, 2], [0, 2]]
    # restart moves only the chosen members; the others go on untouched
    run = pl.simulate_segments(DP, theta0, np.zeros_like(theta0), t_end=1.0, dt=0.01,
                               method="rk4", segment_steps=50)
    first = next(iter(run))
    run.restart([[0.0, 0.0]], [[0.0, 0.0]], where=[False, True, False])
    second = next(iter(run))
    assert np.array_equal(second.theta[0, 1], [0.0, 0.0]) and np.all(second.theta[:, 1] == 0)
    assert np.array_equal(second.theta[0, [0, 2]], first.theta[-1, [0, 2]])
    with pytest.raises(ValueError, match="`where`"):
        run.restart([[0.0, 0.0]], [[0.0, 0.0]], where=[True, False])
    with pytest.raises(ValueError, match="`segment_steps`"):
        pl.simulate_segments(SP, [1.0], [0.0], t_end=1.0, save_every=3, segment_steps=10)


def test_segments_handed_out_are_never_overwritten():
    theta0 = np.stack([CHAOTIC, [0.3, -0.2], [1.0, 1.5]])
    run = pl.simulate_segments(DP, theta0, np.zeros_like(theta0), t_end=1.0, dt=0.01,
                               method="rk4", segment_steps=20)
    handed, snapshots = [], []
    for segment in run:
        handed.append(segment)
        snapshots.append(copy.deepcopy(segment))
        if len(handed) == 2:
            run.keep(np.array([True, False, True]))
        if len(handed) == 3:
            run.restart([[0.5, 0.5]], [[0.0, 0.0]], where=[False, True])
    assert len(handed) == 5
    arrays = ("t", "theta", "omega", "p", "kinetic", "potential", "energy")
    for segment, snapshot in zip(handed, snapshots):
        for name in arrays:
            assert np.array_equal(getattr(segment, name), getattr(snapshot, name))
    for a, b in itertools.combinations(handed, 2):
        assert not any(np.shares_memory(getattr(a, x), getattr(b, y))
                       for x in arrays for y in arrays)
    # Negative control: the run goes on from a view into the last segment handed out,
    # so a run that stepped its state in place would overwrite that segment.
    assert np.shares_memory(run._theta, handed[-1].theta)


# --------------------------------------------------------------------------- bad input
def test_a_run_too_large_for_memory_is_refused_with_the_numbers():
    with pytest.raises(ValueError) as info:
        pl.simulate(DP, [1.0, 1.0], [0.0, 0.0], t_end=1e9, dt=1e-6, allow_long_run=True)
    message = str(info.value)
    for name in ("`t_end`", "`dt`", "`save_every`"):
        assert name in message
    assert "1e+15 steps" in message and " PB of memory" in message


def test_the_memory_check_counts_the_kept_states(monkeypatch):
    from pendulum_lab import validation

    monkeypatch.setattr(validation, "available_memory", lambda: 1_000_000)
    monkeypatch.setattr(importlib.import_module("pendulum_lab.driver.arguments"), "SMALL_RUN", 0)
    # 100,001 states x (9 * 2 + 3) floats x 8 bytes = 16.8 MB > 1 MB: refused ...
    with pytest.raises(ValueError, match="needs about 16.8 MB"):
        pl.simulate(DP, [1.0, 1.0], [0.0, 0.0], t_end=10.0, dt=1e-4, method="rk4")
    # ... keeping every 100th state (10 kB) is not (negative control)
    traj = pl.simulate(DP, [1.0, 1.0], [0.0, 0.0], t_end=10.0, dt=1e-4, method="rk4",
                       save_every=100)
    assert traj.theta.shape == (1001, 2)


def test_step_takes_velocities_or_momenta_and_returns_momenta():
    theta0, omega0 = np.array([1.0, 0.5]), np.array([0.3, -0.2])
    p0 = DP.momenta(theta0, omega0)
    by_omega = pl.step(DP, theta0, omega0, dt=0.01, method="glrk4")
    by_p = pl.step(DP, theta0, p0=p0, dt=0.01, method="glrk4")
    assert np.allclose(by_omega[0], by_p[0], rtol=0, atol=1e-15)
    assert np.allclose(by_omega[1], by_p[1], rtol=0, atol=1e-14)
    # negative control: the velocities read as momenta are another state
    wrong = pl.step(DP, theta0, p0=omega0, dt=0.01, method="glrk4")
    assert np.max(np.abs(wrong[1] - by_p[1])) > 1e-3
    with pytest.raises(TypeError, match="exactly one"):
        pl.step(DP, theta0, omega0, p0=p0, dt=0.01)


def test_chain_equilibrium_by_name():
    chain = pl.derive_chain(2)
    assert [float(a) for a in chain.equilibrium("down-up").angles] == [0.0, np.pi]
    assert chain.equilibrium("up-down") is chain.equilibria[2]
    with pytest.raises(ValueError, match="must be one of"):
        chain.equilibrium("sideways")


# --------------------------------------------------------------------------- events
def test_crossings_of_a_sine_in_each_direction():
    t = np.linspace(0.0, 4 * np.pi, 401)
    up = events.find_crossings(np.sin(t - 0.3), direction=1)
    down = events.find_crossings(np.sin(t - 0.3), direction=-1)
    both = events.find_crossings(np.sin(t - 0.3), direction=0)
    located = t[up.step] + up.fraction() * (t[1] - t[0])
    assert np.allclose(located, [0.3, 2 * np.pi + 0.3], atol=1e-4)
    falling = t[down.step] + down.fraction() * (t[1] - t[0])
    assert np.allclose(falling, [np.pi + 0.3, 3 * np.pi + 0.3], atol=1e-4)
    assert len(both) == len(up) + len(down) == 4
    with pytest.raises(ValueError, match="`direction`"):
        events.find_crossings(np.sin(t), direction=2)


def test_periodic_levels_count_every_turn():
    angle = np.linspace(0.0, 4.5 * np.pi, 200)  # a rotating angle passes pi, 3 pi
    hits = events.find_crossings(angle, direction=1, level=np.pi, period=2 * np.pi)
    assert np.allclose(hits.level, [np.pi, 3 * np.pi])
    # negative control: without the period only the first level is crossed
    assert len(events.find_crossings(angle, direction=1, level=np.pi)) == 1


def test_hermite_root_is_fourth_order_and_linear_is_second():
    # g = cos(t) - 0.2 crosses zero at arccos(0.2); sample it at steps h and 2h.
    root, steps = np.arccos(0.2), np.array([0.4, 0.2, 0.1, 0.05, 0.025])
    cubic, linear = [], []
    for h in steps:
        t = np.arange(0.0, 2.0, h)
        hits = events.find_crossings(np.cos(t) - 0.2, direction=-1)
        k = hits.step
        rate = -h * np.sin(t)
        cubic.append(abs(t[k[0]] + hits.fraction(rate[k], rate[k + 1])[0] * h - root))
        linear.append(abs(t[k[0]] + hits.fraction()[0] * h - root))
    cubic_order = np.polyfit(np.log(steps), np.log(cubic), 1)[0]
    linear_order = np.polyfit(np.log(steps), np.log(linear), 1)[0]
    assert cubic_order > 3.5 and cubic[-1] < 1e-9
    assert 1.5 < linear_order < 2.5 and linear[-1] > 1e-6  # negative control


def test_first_keeps_one_crossing_per_member():
    values = np.array([[-1.0, 1.0], [1.0, -1.0], [-1.0, 1.0], [1.0, -1.0]])
    hits = events.find_crossings(values, direction=1)
    assert sorted(zip(hits.member.tolist(), hits.step.tolist())) == [(0, 0), (0, 2), (1, 1)]
    first = hits.first()
    assert sorted(zip(first.member.tolist(), first.step.tolist())) == [(0, 0), (1, 1)]


def test_land_puts_a_step_of_the_integrator_on_the_surface():
    # Land the simple pendulum on theta = 0.3, from the state a step before.
    q0, p0, dt = np.array([0.25]), np.array([1.0]), 0.1

    def advance(tau):
        return (q0, p0) if tau == 0.0 else pl.step(SP, q0, p0=p0, dt=tau, method="glrk4")

    miss, (q, p), tau, steps = events.land(
        advance, lambda s: s[0][0] - 0.3, lambda s: SP.dH_dp(*s)[0], 0.05, (-dt, 2 * dt),
        scale=0.3,
    )
    assert miss < 1e-15 and abs(q[0] - 0.3) < 1e-15 and 0 < tau < dt and 1 < steps < 12
    # the landed state is one step of the method from the saved state, not an interpolation
    direct = pl.step(SP, q0, p0=p0, dt=tau, method="glrk4")
    assert np.array_equal(direct[0], q) and np.array_equal(direct[1], p)
    # negative control: without iterating, the first guess is off the surface
    assert abs(advance(0.05)[0][0] - 0.3) > 1e-4


def _before_the_surface(states, distance):
    """States on theta_1 = 0 (from the section) moved back in time by ``distance`` (glrk8)."""
    theta, omega = states
    p = DP.momenta(theta, omega)
    back_theta, back_p = theta, p
    for _ in range(8):
        back_theta, back_p = pl.step(DP, back_theta, p0=back_p, dt=-distance / 8,
                                     method="glrk8")
    return theta, p, back_theta, back_p


@pytest.mark.parametrize(
    ("method", "order"),
    [("rk4", 4), ("glrk4", 4), ("leapfrog", 2), ("semi_implicit_euler", 1)],
)
def test_henon_step_lands_on_the_surface_with_the_local_error_of_the_method(method, order):
    states = pl.chaos.section_spread(DP, -8.0, orbits=6)
    errors = []
    for distance in (0.01, 0.005):
        theta, p, back_theta, back_p = _before_the_surface(states, distance)
        theta1, p1, elapsed = pl.henon_step(DP, back_theta, p0=back_p, link=0, level=0.0,
                                            method=method)
        assert elapsed.shape == (6,)
        assert np.max(np.abs(theta1[:, 0])) < 1e-16  # on the surface, up to one rounding
        errors.append(max(np.max(np.abs(theta1 - theta)), np.max(np.abs(p1 - p)),
                          np.max(np.abs(elapsed - distance))))
    # A step's local error falls at least like h^(order + 1) when the step halves (on the
    # symmetric states theta = 0 of the section, one order faster for the momenta).
    assert 0.6 * 2 ** (order + 1) < errors[0] / errors[1] < 2 ** (order + 3)
    # Negative control: the nearest saved step (the start) is off the surface by far more.
    assert np.min(np.abs(back_theta[:, 0])) > 1e-3


def test_henon_step_arguments():
    theta, p = np.array([[-0.01, 0.3], [-0.02, 0.1]]), np.array([[1.0, 0.0], [1.0, 0.2]])
    theta1, _, elapsed = pl.henon_step(DP, theta, p0=p, link=0, level=[0.0, 2 * np.pi],
                                       method="rk4")
    assert theta1[1, 0] == pytest.approx(2 * np.pi, abs=4e-15) and elapsed[1] > elapsed[0]
    with pytest.raises(ValueError, match="canonical variables"):
        pl.henon_step(DP, theta, p0=p, link=0, level=0.0, method="leapfrog_velocity")
    with pytest.raises(ValueError, match="`level` must be a number or have shape"):
        pl.henon_step(DP, theta, p0=p, link=0, level=[0.0, 0.0, 0.0], method="rk4")
    with pytest.raises(ValueError, match="`link`"):
        pl.henon_step(DP, theta, p0=p, link=2, level=0.0, method="rk4")
    # at rest, theta_1 does not move: it cannot be the independent variable
    with pytest.raises(FloatingPointError, match="vanishes"):
        pl.henon_step(DP, [0.5, 0.0], [0.0, 0.0], link=0, level=0.0, method="rk4")


def test_newton_and_henon_landings_find_the_same_crossings():
    theta0, omega0 = pl.chaos.section_spread(DP, -12.0, orbits=4)
    kwargs = dict(t_end=30.0, dt=0.01, method="rk4")
    newton = pl.chaos.poincare_section(DP, theta0, omega0, landing="newton", **kwargs)
    henon = pl.chaos.poincare_section(DP, theta0, omega0, landing="henon", **kwargs)
    assert len(newton.t) == len(henon.t) > 40 and np.array_equal(newton.orbit, henon.orbit)
    assert np.max(henon.residual) < 1e-14 and np.max(newton.residual) < 1e-14
    # both land from the same saved steps: they differ by a local error, not a global one
    # (largest at the slowest crossings, where Henon's rescaled field varies fastest)
    assert np.median(np.abs(newton.p - henon.p)) < 1e-8
    assert np.max(np.abs(newton.p - henon.p)) < 1e-4
    assert np.median(np.abs(newton.t - henon.t)) < 1e-9
    assert set(henon.landing_steps.tolist()) == {1} and newton.landing_steps.mean() > 1.5
    # Negative control: the nearest saved step is far from both.
    nearest = pl.chaos.poincare_section(DP, theta0, omega0, landing="nearest", **kwargs)
    assert np.median(np.abs(nearest.p - henon.p)) > 1e-4
    with pytest.raises(ValueError, match="`landing`"):
        pl.chaos.poincare_section(DP, theta0, omega0, landing="bisect", **kwargs)
    with pytest.raises(ValueError, match="canonical variables"):
        pl.chaos.poincare_section(DP, theta0, omega0, t_end=1.0, landing="henon",
                                  method="semi_implicit_euler_velocity")


def test_landing_errors_are_local_errors_of_the_method():
    theta, omega = pl.chaos.section_spread(DP, -5.0, orbits=8)
    for landing in ("newton", "henon"):
        coarse = pl.chaos.landing_errors(DP, theta, omega, dt=0.02, method="rk4", landing=landing)
        fine = pl.chaos.landing_errors(DP, theta, omega, dt=0.01, method="rk4", landing=landing)
        ratio = coarse.state_error.max() / fine.state_error.max()
        assert 19 < ratio < 128  # at least 2^5: RK4's local error (2^6 on symmetric states)
        assert fine.time_error.max() < 1e-8
    # Negative control: symplectic Euler is first order, its local error falls 2^2.
    coarse = pl.chaos.landing_errors(DP, theta, omega, dt=0.02, method="semi_implicit_euler",
                                     landing="henon")
    fine = pl.chaos.landing_errors(DP, theta, omega, dt=0.01, method="semi_implicit_euler",
                                   landing="henon")
    assert 3 < coarse.state_error.max() / fine.state_error.max() < 6
    with pytest.raises(ValueError, match="must lie on the surface"):
        pl.chaos.landing_errors(DP, theta + 0.1, omega, dt=0.01)


def test_henon_loses_accuracy_at_slow_crossings_and_newton_does_not():
    # On p_2 = 0, theta_2 near the largest angle E = -12 J reaches: theta_1' falls towards 0.
    theta, omega = pl.chaos.section_states(DP, -12.0, [[1.0], [2.44], [2.455]], [[0.0]] * 3)
    henon = pl.chaos.landing_errors(DP, theta, omega, dt=0.01, method="rk4", landing="henon")
    newton = pl.chaos.landing_errors(DP, theta, omega, dt=0.01, method="rk4", landing="newton")
    assert np.array_equal(henon.speed, newton.speed) and henon.speed[2] < 0.25
    assert henon.state_error[2] > 100 * newton.state_error[2]
    # Negative control: at the brisk crossing the two are alike.
    assert 0.2 < henon.state_error[0] / newton.state_error[0] < 5


def test_henon_step_carries_the_time_of_a_driven_model():
    driven = pl.driven_pendulum()  # damped and driven: the field depends on t
    start, p_start, t0 = np.array([-0.02]), np.array([1.5]), 1.3
    theta1, p1, elapsed = pl.henon_step(driven, start, p0=p_start, link=0, level=0.0,
                                        method="rk4", t0=t0)
    assert abs(theta1[0]) < 1e-16 and 0 < elapsed < 0.02
    # one step of the same method in time, of the length found, lands at the same state
    in_time = pl.step(driven, start, p0=p_start, dt=elapsed, method="rk4", t0=t0)
    assert np.max(np.abs(np.r_[theta1 - in_time[0], p1 - in_time[1]])) < 1e-10
    # Negative control: the drive's phase matters; starting the clock at 0 lands elsewhere.
    _, p_wrong, _ = pl.henon_step(driven, start, p0=p_start, link=0, level=0.0, method="rk4")
    assert abs(p_wrong[0] - p1[0]) > 1e-6
