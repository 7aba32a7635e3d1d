"""Models of systems and their runs where a student's input would have given a silently wrong
result: replace() checked as the constructor, the period checked, runs that leave the finite
numbers or the positive mass matrices stopped (not completed) with the reason, a step onto a
coordinate singularity named, a run drawn only with its own system. Each with its negative
control."""

import re
import warnings

import numpy as np
import pytest
import sympy as sp

import pendulum_lab as pl
from pendulum_lab.model import SystemModel

th = sp.Symbol("theta", real=True)
m, l, g = sp.symbols("m l g", positive=True)  # noqa: E741 (the rod's length, as written)


def hanging(**arguments):
    return pl.mechanical_system([th], {m: 1.0, l: 1.0, g: 9.81},
                                points=[(l * sp.sin(th), -l * sp.cos(th))], masses=[m],
                                gravity=g, **arguments)


# ---- the model's arguments ----------------------------------------------------------------
def test_replace_applies_the_constructors_checks(elastic):
    with pytest.raises(ValueError, match="`m` must be positive \\(it is declared positive\\)"):
        elastic.replace(m=0.0)
    with pytest.raises(ValueError, match="`k` must be positive"):
        elastic.replace(k=-1.0)
    # a parameter declared without assumptions: the mass it gives is checked
    plain = sp.Symbol("m")
    loose = pl.mechanical_system([th], {plain: 1.0, l: 1.0}, points=[(l * sp.sin(th), 0)],
                                 masses=[plain])
    with pytest.raises(ValueError, match=r"`masses\[0\]` = m must be non-negative"):
        loose.replace(m=-1.0)
    # negative controls: good values are accepted and used
    assert elastic.replace(m=2.0).parameter_values[m] == 2.0
    assert loose.replace(m=3.0).parameter_values[plain] == 3.0


def test_a_family_checks_every_members_values_against_the_declared_assumptions(elastic):
    with pytest.raises(ValueError, match="`m` must be positive \\(it is declared positive\\), "
                                         "got 0"):
        elastic.family(m=[1.0, 0.0, 2.0])
    assert elastic.family(m=[1.0, 0.5, 2.0]).shape == (3,)  # negative control


@pytest.mark.parametrize("period, error, message", [
    (float("nan"), ValueError, "positive finite number, got nan"),
    (-1, ValueError, "positive finite number, got -1"),
    (0.0, ValueError, "positive finite number, got 0.0"),
    (float("inf"), ValueError, "positive finite number, got inf"),
    ("fast", TypeError, "positive finite number, got 'fast' \\(str\\)"),
    (True, TypeError, "positive finite number, got True"),
])
def test_a_period_that_is_not_a_positive_finite_number_is_refused(period, error, message):
    with pytest.raises(error, match=f"`period` must be a {message}"):
        hanging(period=period)


def test_a_positive_period_is_accepted_from_numpy_as_well():
    assert hanging(period=np.float32(0.5)).drive_period == 0.5
    assert hanging(period=2).drive_period == 2.0


def test_the_factories_accept_numpy_numbers_and_refuse_non_numbers():
    model = pl.elastic_pendulum(mass=np.float32(2.0), stiffness=np.int64(40))
    assert model.parameter_values[m] == 2.0
    with pytest.raises(ValueError, match="`mass` must be a positive finite number"):
        pl.elastic_pendulum(mass=np.float32(-2.0))  # negative control
    with pytest.raises(TypeError, match="`mass` must be a positive finite number, got '2'"):
        pl.elastic_pendulum(mass="2")


# ---- runs that must stop -----------------------------------------------------------------
def test_a_run_whose_energy_overflows_stops_not_completed_with_the_reason():
    model = pl.simple_pendulum()
    with pytest.warns(RuntimeWarning, match="energy is not a finite number"):
        run = pl.simulate(model, [0.5], [1e155], t_end=0.05, dt=0.01, method="rk4")
    assert not run.completed
    assert len(run.t) == 1 and np.all(np.isfinite(run.theta))
    # negative control: a fast but representable spin completes, its energy finite
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fine = pl.simulate(model, [0.5], [1e100], t_end=0.05, dt=0.01, method="rk4")
    assert fine.completed and np.all(np.isfinite(fine.energy))


def test_in_an_ensemble_only_the_overflowing_member_stops():
    with pytest.warns(RuntimeWarning, match="in 1 of 2 trajectories"):
        run = pl.simulate(pl.simple_pendulum(), [[0.5], [0.5]], [[1e155], [1.0]],
                          t_end=0.05, dt=0.01, method="rk4")
    assert not run.completed
    assert np.all(np.isnan(run.energy[1:, 0])) and np.all(np.isfinite(run.energy[:, 1]))


@pytest.mark.parametrize("angle", [1e17, 1e300])
def test_a_system_coordinate_no_step_can_move_stops_the_run_at_its_start(elastic, angle):
    starts = re.escape(f"a coordinate starts at {angle:.3g}, where floats are ")
    with pytest.warns(RuntimeWarning, match=starts + ".* apart, so the steps cannot move it"):
        run = pl.simulate(elastic, [1.0, angle], [0.0, 0.0], t_end=0.1, dt=0.01)
    assert not run.completed and len(run.t) == 1
    # negative control: a coordinate a thousand turns out still moves, and the run completes
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        far = pl.simulate(elastic, [1.0, 2000 * np.pi + 0.5], [0.0, 0.0], t_end=0.1, dt=0.01)
    assert far.completed and far.theta[-1, 1] != far.theta[0, 1]


@pytest.fixture(scope="module")
def softening():
    """A particle whose mass 1 - t^2/2000 passes zero at t = 44.7 s: positive wherever the
    search looks (|t| <= 30), not proved by SymPy."""
    x, x_dot = sp.symbols("x x_dot", real=True)
    t = sp.Symbol("t", real=True)
    return pl.mechanical_system([x], {}, lagrangian=(1 - t**2 / 2000) * x_dot**2 / 2,
                                name="a softening particle")


def test_a_run_into_an_indefinite_mass_matrix_stops_there(softening):
    assert not softening.positivity_proved
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # the velocity's growth near 44.7 s
        with pytest.warns(RuntimeWarning, match="mass matrix is not positive definite"):
            run = pl.simulate(softening, [0.0], [1.0], t_end=60.0, dt=0.01, method="rk4")
    assert not run.completed and run.t[-1] < np.sqrt(2000)
    # the part kept is a motion of a positive mass
    assert np.all(softening.mass_matrix_at(run.theta, run.t[:, None]) > 0)


def test_without_the_check_the_run_goes_on_with_a_negative_kinetic_energy(softening,
                                                                         monkeypatch):
    # negative control: the same run completes, reaching negative kinetic energies
    monkeypatch.setattr(SystemModel, "positivity_proved", True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        run = pl.simulate(softening, [0.0], [1.0], t_end=60.0, dt=0.01, method="rk4")
    assert run.completed and run.kinetic.min() < 0


def test_a_step_onto_a_coordinate_singularity_is_a_clear_error(elastic):
    # the elastic pendulum in polar coordinates: at r = 0 the angle is not defined
    with pytest.raises(ValueError, match="divided by zero: the state reached a place where "
                                         "its equations are not defined"):
        pl.step(elastic, [0.0, 0.3], [0.0, 0.0], dt=0.01, method="rk4")
    theta, _ = pl.step(elastic, [1.0, 0.3], [0.0, 0.0], dt=0.01, method="rk4")
    assert np.all(np.isfinite(theta))  # negative control


# ---- a run drawn with its own system ---------------------------------------------------------
def test_a_run_is_drawn_only_with_the_system_it_came_from(elastic, cart):
    from pendulum_lab import animation

    run = pl.simulate(elastic, [1.0, 0.3], [0.0, 0.0], t_end=0.05, dt=0.01)
    assert run.model is elastic
    with pytest.raises(ValueError, match="`traj` is a run of the elastic pendulum, and "
                                         "`model` is the pendulum on a cart"):
        animation.still_frame(run, cart, dpi=40)
    # negative controls: the same system built again, or with other values, draws the run
    for same in (pl.elastic_pendulum(), elastic.replace(k=30.0)):
        assert animation.still_frame(run, same, dpi=40)[:4] == b"\x89PNG"


def test_explore_energy_refuses_a_system_consistently_with_the_other_messages(elastic):
    widgets = pytest.importorskip("pendulum_lab.widgets")
    with pytest.raises(TypeError, match="`model` must be a chain: explore_energy .* "
                                        "explore\\(model\\) shows its motion"):
        widgets.explore_energy(elastic)
    with pytest.raises(TypeError, match="explore, explore_equilibrium, the simulators and "
                                        "the drawings accept it.*explore_energy among them"):
        _ = elastic.lengths


def test_a_start_beyond_the_rods_reach_is_refused_naming_theta0():
    # The spherical pendulum's (x, y) beyond its 1 m rod have no height: refused before the
    # run, not started from NaN energies (it failed at its first step with "use a smaller dt").
    model = pl.spherical_pendulum()
    with pytest.raises(ValueError, match=r"`theta0` = \[2\.0, 0\.0\] is not a place"):
        pl.simulate(model, [2.0, 0.0], [0.0, 0.0], t_end=0.1, dt=0.01)
    with pytest.raises(ValueError, match=r"ensemble member \(1,\)"):
        pl.simulate(model, [[0.1, 0.0], [0.2, 1.5]], [[0.0, 0.0], [0.0, 0.0]], t_end=0.1,
                    dt=0.01)
    # the tools that take a start check it the same way (they share the driver's validation)
    with pytest.raises(ValueError, match=r"`theta0` = \[2\.0, 0\.0\] is not a place"):
        pl.step(model, [2.0, 0.0], [0.0, 0.0], dt=0.01)
    # negative control: inside the reach the same call runs
    assert pl.simulate(model, [0.5, 0.0], [0.0, 0.3], t_end=0.1, dt=0.01).completed
