"""What a run refuses or warns about before it starts, and what it does at the edges of floats.

* the work budget (steps times trajectories), with ``allow_long_run`` as the way past it;
* the memory a run needs, all of it (kept states, conversions, each method's working
  memory), checked before any start-up work;
* a clock that stands still (``t0 + dt == t0``) and a driven model's rounded step times;
* huge initial angles, reduced by whole turns (every model is 2 pi-periodic in each angle),
  with the saved angles continued from those given;
* one rule for a state that becomes non-finite, in ``simulate`` and in ``step``;
* ``save_every`` longer than the run, and ``step_count``'s own arguments.

Each property comes with a negative control: the check, switched off or fed the other
case, fails.
"""

from __future__ import annotations

import contextlib
import importlib
import tracemalloc
import warnings

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

import pendulum_lab as pl
from pendulum_lab import validation
from pendulum_lab.driver import arguments, segments, trajectory
from pendulum_lab.integrators import get_method
from pendulum_lab.model import reduce_turns

# the module (the package's `simulate` is the function of the same name)
driver = importlib.import_module("pendulum_lab.driver.simulate")

DP = pl.double_pendulum()
SP = pl.simple_pendulum()
DRIVEN = pl.driven_pendulum()


# --------------------------------------------------------------------------- the work budget
@pytest.mark.parametrize("kwargs, steps", [
    (dict(t_end=1.0, dt=1e-12, keep="final"), "1e+12 steps"),
    (dict(t_end=1e12, dt=0.01, save_every=10**9), "1e+14 steps"),
])
def test_runs_beyond_the_budget_are_refused_at_once_with_the_count(kwargs, steps,
                                                                    before_any_work):
    with before_any_work(), pytest.raises(ValueError) as info:
        pl.simulate(DP, [1.0, 0.5], [0.0, 0.0], method="rk4", **kwargs)
    message = str(info.value)
    assert steps in message and "budget of 1e+10" in message and "allow_long_run=True" in message


def test_the_budget_counts_trajectories_and_allow_long_run_lifts_it(monkeypatch):
    monkeypatch.setattr(arguments, "WORK_BUDGET", 1000)
    theta0 = np.full((4, 2), 0.5)
    # 300 steps of one trajectory fit; of four (1,200 updates) they do not ...
    pl.simulate(DP, theta0[0], np.zeros(2), t_end=3.0, dt=0.01, method="rk4")
    with pytest.raises(ValueError, match="x 4 trajectories = 1.2e\\+03 state updates"):
        pl.simulate(DP, theta0, np.zeros_like(theta0), t_end=3.0, dt=0.01, method="rk4")
    with pytest.raises(ValueError, match="budget"):
        pl.simulate_segments(DP, theta0, np.zeros_like(theta0), t_end=3.0, dt=0.01,
                             method="rk4")
    # ... unless asked for (negative control: the same run goes through)
    traj = pl.simulate(DP, theta0, np.zeros_like(theta0), t_end=3.0, dt=0.01, method="rk4",
                       allow_long_run=True)
    assert traj.theta.shape == (301, 4, 2)
    run = pl.simulate_segments(DP, theta0, np.zeros_like(theta0), t_end=3.0, dt=0.01,
                               method="rk4", allow_long_run=True)
    assert sum(len(segment.t) - 1 for segment in run) == 300
    with pytest.raises(TypeError, match="`allow_long_run`"):
        pl.simulate(DP, theta0, np.zeros_like(theta0), t_end=3.0, dt=0.01, allow_long_run="y")


def test_the_chaos_measurements_meet_the_budget_before_they_allocate(before_any_work):
    for run in (lambda: pl.chaos.lyapunov_benettin(DP, [1.0, 0.5], [0.0, 0.0], t_end=1e12),
                lambda: pl.chaos.lyapunov_variational(DP, [1.0, 0.5], [0.0, 0.0], t_end=1e12),
                lambda: pl.chaos.poincare_section(DP, [1.0, 0.5], [0.0, 0.0], t_end=1e12),
                lambda: pl.chaos.stroboscopic_section(DRIVEN, [0.2], [0.0],
                                                      n_periods=10**12)):
        with before_any_work(), pytest.raises(ValueError, match="budget"):
            run()


def test_the_guard_of_the_refusals_fails_on_work_done(before_any_work, monkeypatch):
    # negative controls of the fixture the refusals above use: a run that steps (even one
    # whose error is caught), a figure drawn, a large array held each fail it
    with pytest.raises(AssertionError, match="a trajectory stepped"), before_any_work():
        pl.simulate(DP, [1.0, 0.5], [0.0, 0.0], t_end=0.1, dt=0.01, method="rk4")
    with pytest.raises(AssertionError, match="a trajectory stepped"), before_any_work():
        with contextlib.suppress(AssertionError):
            pl.simulate(DP, [1.0, 0.5], [0.0, 0.0], t_end=0.1, dt=0.01, method="rk4")
    with monkeypatch.context() as patch:  # the budget's refusal switched off: it steps
        patch.setattr(arguments, "WORK_BUDGET", 1e30)
        with pytest.raises(AssertionError, match="a trajectory stepped"), before_any_work():
            pl.simulate(DP, [1.0, 0.5], [0.0, 0.0], method="rk4", t_end=1e12, dt=0.01,
                        save_every=10**9)
    with pytest.raises(AssertionError, match="a state stepped"), before_any_work():
        pl.step(DP, [1.0, 0.5], [0.0, 0.0], dt=0.01, method="rk4")
    figure = Figure()
    figure.add_subplot().plot([0, 1])
    with pytest.raises(AssertionError, match="a figure drawn"), before_any_work():
        FigureCanvasAgg(figure).draw()
    with pytest.raises(AssertionError, match="MiB held before the refusal"), before_any_work():
        np.ones(2**26).sum()  # 512 MiB
    with before_any_work():  # and a few MiB pass (the checks are of work, not of any memory)
        np.ones(2**20).sum()


# --------------------------------------------------------------------------- memory
def _peak_bytes(model, method, members, t_end):
    theta0 = np.full((members, model.n), 0.3)
    pl.simulate(model, theta0[:1], np.zeros((1, model.n)), t_end=0.01, dt=0.01, method=method)
    tracemalloc.start()
    try:
        traj = pl.simulate(model, theta0, np.zeros_like(theta0), t_end=t_end, dt=0.01,
                           method=method)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    return peak, len(traj.t)


@pytest.mark.parametrize("n, method, members, t_end", [
    (1, "rk4", 4000, 0.01), (1, "glrk8", 4000, 0.01), (2, "rk4", 4000, 0.01),
    (2, "glrk8", 4000, 0.01), (2, "leapfrog", 4000, 0.01), (2, "rk4", 2, 40.0),
    (3, "glrk4", 2000, 0.02), (3, "rk4", 2, 40.0),
])
def test_the_memory_estimate_covers_what_a_run_really_holds(n, method, members, t_end):
    model = pl.n_pendulum(n)
    peak, saved = _peak_bytes(model, method, members, t_end)
    estimate = driver.memory_needed(n, get_method(method), members, saved)
    assert peak <= estimate <= 2 * peak + 1e5
    # negative control: the count used before (kept states only, 5 n + 3 floats each)
    # misses the method's working memory and the conversions
    assert 8.0 * members * saved * (5 * n + 3) < peak


def test_memory_is_checked_before_any_start_up_work(monkeypatch):
    monkeypatch.setattr(validation, "available_memory", lambda: 10**6)
    monkeypatch.setattr(arguments, "SMALL_RUN", 0)  # ask about every run

    def no_start_up(*args, **kwargs):
        raise AssertionError("the start-up work ran before the memory check")

    monkeypatch.setattr(driver, "hamiltonian_field", no_start_up)
    monkeypatch.setattr(segments, "hamiltonian_field", no_start_up)
    big = np.zeros((20000, 2))
    with pytest.raises(ValueError, match="needs about .* more than the 1 MB"):
        pl.simulate(DP, big, big, t_end=0.01, dt=0.01, method="rk4")
    with pytest.raises(ValueError, match="one step of 20000 states needs about"):
        pl.step(DP, big, big, dt=0.01, method="rk4")
    with pytest.raises(ValueError, match="`segment_steps`"):
        pl.simulate_segments(DP, [1.0, 0.5], [0.0, 0.0], t_end=1000.0, dt=0.01,
                             segment_steps=10**5, method="rk4")
    # negative control: a run that fits gets as far as the start-up work
    with pytest.raises(AssertionError, match="start-up work"):
        pl.simulate(DP, [1.0, 0.5], [0.0, 0.0], t_end=0.01, dt=0.01, method="rk4")


def test_the_memory_check_counts_each_methods_working_memory(monkeypatch):
    # 10,000 trajectories, one step: glrk8 carries 154 floats each, rk4 24
    members, n = 10_000, 2
    needed = {m: driver.memory_needed(n, get_method(m), members, 2) for m in ("rk4", "glrk8")}
    monkeypatch.setattr(validation, "available_memory", lambda: int(sum(needed.values()) / 2))
    monkeypatch.setattr(arguments, "SMALL_RUN", 0)
    theta0 = np.full((members, n), 0.3)
    pl.simulate(DP, theta0, np.zeros_like(theta0), t_end=0.01, dt=0.01, method="rk4")
    with pytest.raises(ValueError, match="needs about"):
        pl.simulate(DP, theta0, np.zeros_like(theta0), t_end=0.01, dt=0.01, method="glrk8")


# --------------------------------------------------------------------------- the clock
def test_a_clock_that_would_stand_still_is_refused():
    with pytest.raises(ValueError, match=r"`t0` = 1e\+15 s.*t \+ dt == t.*t0 % 9.42478"):
        pl.simulate(DRIVEN, [0.2], [0.0], t_end=1.0, dt=0.01, method="rk4", t0=1e15)
    with pytest.raises(ValueError, match="does not depend on the time"):
        pl.simulate(SP, [0.2], [0.0], t_end=1.0, dt=0.01, method="rk4", t0=1e18)
    with pytest.raises(ValueError, match="t \\+ dt == t"):
        pl.step(DRIVEN, [0.2], [0.0], dt=0.01, method="rk4", t0=1e308)
    with pytest.raises(ValueError, match="t \\+ dt == t"):
        pl.simulate_segments(DRIVEN, [0.2], [0.0], t_end=1.0, dt=0.01, t0=1e15)


def test_rounded_step_times_of_a_driven_model_warn_and_small_ones_do_not():
    with pytest.warns(RuntimeWarning, match="drive is evaluated at times rounded"):
        traj = pl.simulate(DRIVEN, [0.2], [0.0], t_end=1.0, dt=0.01, method="rk4", t0=1e9)
    assert len(np.unique(traj.t)) == len(traj.t)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # negative controls: an ordinary t0, a model without t
        pl.simulate(DRIVEN, [0.2], [0.0], t_end=1.0, dt=0.01, method="rk4", t0=1e3)
        pl.simulate(SP, [0.2], [0.0], t_end=1.0, dt=0.01, method="rk4", t0=1e9)


# --------------------------------------------------------------------------- huge angles
def test_whole_turns_are_taken_off_exactly():
    rng = np.random.default_rng(1)
    angles = np.concatenate([10.0 ** rng.uniform(3, 300, 40), -(10.0 ** rng.uniform(3, 20, 10)),
                             [1e15, 2.0**60, np.pi, -np.pi, 0.0, 7.0]])
    reduced = reduce_turns(angles)
    assert np.all(np.abs(reduced) <= np.pi)
    # the same point of the circle: libm reduces its argument exactly too
    # (up to the rounding of the reduced angle: an ulp of pi, 4.4e-16)
    assert np.allclose(np.sin(reduced), np.sin(angles), rtol=0, atol=4.5e-16)
    assert np.allclose(np.cos(reduced), np.cos(angles), rtol=0, atol=4.5e-16)
    # negative control: dividing by the float nearest to 2 pi misses by 0.02 rad at 1e15
    naive = np.mod(1e15 + np.pi, 2 * np.pi) - np.pi
    assert abs(naive - reduce_turns(1e15)) > 0.01


@pytest.mark.parametrize("model, method, theta0", [
    (DP, "rk4", [1e15, 0.0]), (DP, "glrk4", [3e4, -2e5]), (SP, "leapfrog", [1e15]),
    (DP, "leapfrog_velocity", [1e12, 0.5]), (DRIVEN, "rk4", [1e13]),
])
def test_a_run_from_huge_angles_is_the_run_from_the_reduced_ones(model, method, theta0):
    theta0 = np.array(theta0)
    omega0 = np.full_like(theta0, 0.3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # the saved angles' rounding
        traj = pl.simulate(model, theta0, omega0, t_end=10.0, dt=0.01, method=method)
    reduced = np.where(np.abs(theta0) > trajectory.REDUCE_ANGLES_BEYOND, reduce_turns(theta0),
                       theta0)
    plain = pl.simulate(model, reduced, omega0, t_end=10.0, dt=0.01, method=method)
    # the motion is computed on the reduced angles: energies and momenta to the last bit ...
    assert np.array_equal(traj.energy, plain.energy) and np.array_equal(traj.p, plain.p)
    # ... and the saved angles start where they were given and go on continuously from there
    assert np.array_equal(traj.theta[0], theta0)
    spacing = np.spacing(np.abs(theta0))
    assert np.all(np.abs(traj.theta - (theta0 + (plain.theta - reduced))) <= spacing)
    assert np.all(np.abs(np.diff(traj.theta, axis=0) - np.diff(plain.theta, axis=0))
                  <= 2 * spacing)


def test_without_the_reduction_huge_angles_ruin_the_run(monkeypatch):
    with pytest.warns(RuntimeWarning, match="0.125 rad apart"):
        reduced = pl.simulate(DP, [1e15, 0.0], [0.0, 0.0], t_end=10.0, dt=0.01, method="rk4")
    assert np.max(np.abs(reduced.relative_energy_error)) < 1e-2
    # negative control: stepping the huge angles themselves (as before) gives a relative energy
    # error of order 1e3
    monkeypatch.setattr(trajectory, "REDUCE_ANGLES_BEYOND", np.inf)
    plain = pl.simulate(DP, [1e15, 0.0], [0.0, 0.0], t_end=10.0, dt=0.01, method="rk4")
    assert np.max(np.abs(plain.relative_energy_error)) > 1


def test_angles_below_the_threshold_are_left_alone():
    # a few turns out (a student's theta0 = 7): nothing reduced, the run is the run as given
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        traj = pl.simulate(DP, [7.0, -20.0], [0.0, 0.0], t_end=1.0, dt=0.01, method="rk4")
    assert traj.theta[0].tolist() == [7.0, -20.0]
    assert driver.AngleReduction.of(np.array([[7.0, -20.0]])) is None
    assert driver.AngleReduction.of(np.array([[1e5, 0.0]])) is not None


def test_a_segmented_run_from_huge_angles_is_the_long_run_to_the_last_bit():
    theta0 = np.array([[1e14, 0.3], [0.2, 0.1]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        whole = pl.simulate(DP, theta0, np.zeros_like(theta0), t_end=2.0, dt=0.01, method="rk4")
        pieces = list(pl.simulate_segments(DP, theta0, np.zeros_like(theta0), t_end=2.0,
                                           dt=0.01, method="rk4", segment_steps=30))
    joined = np.concatenate([pieces[0].theta] + [piece.theta[1:] for piece in pieces[1:]])
    assert np.array_equal(joined, whole.theta)
    assert np.array_equal(pieces[-1].energy[-1], whole.energy[-1])


def test_a_step_from_a_huge_angle_is_the_step_from_the_reduced_one():
    theta1, p1 = pl.step(DP, [1e6, 0.5], [0.1, 0.0], dt=0.01, method="glrk4")
    reduced = reduce_turns(1e6)
    plain_theta, plain_p = pl.step(DP, [reduced, 0.5], [0.1, 0.0], dt=0.01, method="glrk4")
    assert np.array_equal(p1, plain_p)
    assert theta1[0] == 1e6 + (plain_theta[0] - reduced) and theta1[1] == plain_theta[1]


# --------------------------------------------------------------------------- non-finite states
def test_step_and_simulate_warn_alike_of_a_non_finite_state():
    with pytest.warns(RuntimeWarning, match="rk4: the state became non-finite at step 1"):
        theta1, p1 = pl.step(DP, [1.0, 0.5], [0.0, 0.0], dt=1e300, method="rk4")
    assert not np.all(np.isfinite(np.concatenate([theta1, p1])))
    with pytest.warns(RuntimeWarning, match="explicit_euler: the state became non-finite"):
        pl.step(DP, [[1.0, 0.5], [0.1, 0.1]], [[1e10, 0.0], [0.0, 0.0]], dt=1e300,
                method="explicit_euler")
    with pytest.warns(RuntimeWarning, match="the state became non-finite at step"):
        pl.simulate(DP, [3.0, -3.0], [20.0, -20.0], t_end=200.0, dt=0.5,
                    method="explicit_euler")
    with warnings.catch_warnings():  # negative control: an ordinary step is silent
        warnings.simplefilter("error")
        theta1, _ = pl.step(DP, [1.0, 0.5], [0.0, 0.0], dt=0.01, method="rk4")
    assert np.all(np.isfinite(theta1))


# --------------------------------------------------------------------------- save_every, counts
def test_save_every_longer_than_the_run_is_refused():
    with pytest.raises(ValueError, match="`save_every` = 100 is more than the run's 10 steps"):
        pl.simulate(SP, [0.5], [0.0], t_end=1.0, dt=0.1, save_every=100)
    with pytest.raises(ValueError, match="`save_every` = 10000000000"):
        pl.simulate(SP, [0.5], [0.0], t_end=1.0, dt=0.1, save_every=10**10)
    # negative control: the whole run as one saved step keeps both ends
    traj = pl.simulate(SP, [0.5], [0.0], t_end=1.0, dt=0.1, save_every=10, method="rk4")
    assert traj.t.tolist() == [0.0, 1.0]


@pytest.mark.parametrize("t_end, dt, error, argument", [
    (1.0, -0.1, ValueError, "dt"), (1, 0, ValueError, "dt"), (float("nan"), 0.1, ValueError,
                                                              "t_end"),
    (-1.0, 0.1, ValueError, "t_end"), (1.0, 1e-320, ValueError, "overflows"),
    ("1", 0.1, TypeError, "t_end"),
])
def test_step_count_validates_its_arguments(t_end, dt, error, argument):
    with pytest.raises(error, match=argument):
        pl.step_count(t_end, dt)


def test_step_count_of_valid_arguments():
    assert pl.step_count(0.0, 0.1) == 0 and pl.step_count(1, 0.25) == 4
    assert pl.step_count(np.float64(0.3), np.float64(0.1)) == 3


def _restarted_at_a_huge_angle():
    theta0 = np.array([[0.1, 0.2], [0.3, 0.4]])
    run = pl.simulate_segments(DP, theta0, np.zeros_like(theta0), t_end=1.0, dt=0.01,
                               method="rk4", segment_steps=50)
    segments = iter(run)
    next(segments)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # the saved angles' rounding
        run.restart([[1e12, 0.2]], [[0.0, 0.0]], where=[True, False])
    return next(segments)


def test_a_segmented_run_restarted_at_huge_angles_reduces_them_too(monkeypatch):
    after = _restarted_at_a_huge_angle()
    assert after.theta[0, 0].tolist() == [1e12, 0.2]
    fresh = pl.simulate(DP, [reduce_turns(1e12), 0.2], p0=[0.0, 0.0], t_end=0.5, dt=0.01,
                        method="rk4")
    assert np.array_equal(after.energy[:, 0], fresh.energy)
    # negative control: without the reduction the restarted member steps at 1e12 rad, where
    # floats are 1.2e-4 rad apart, and its energy is not the fresh run's
    monkeypatch.setattr(trajectory, "REDUCE_ANGLES_BEYOND", np.inf)
    unreduced = _restarted_at_a_huge_angle()
    assert np.max(np.abs(unreduced.energy[:, 0] - fresh.energy)) > 1e-6
