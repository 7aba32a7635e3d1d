"""The explorers driven headlessly: set a control, check the recomputed trajectory and figure."""

import base64
import io

import numpy as np
import pytest
from PIL import Image

import pendulum_lab as pl
from pendulum_lab import analysis, widgets

SHORT = {"t_end": 2.0, "dt": 0.01}


def line_data(explorer, axes_index=0, line_index=-1):
    """A copy of one line's y-data in the explorer's figure."""
    return np.array(explorer.figure.axes[axes_index].lines[line_index].get_ydata(), dtype=float)


@pytest.fixture
def dp_explorer():
    return widgets.explore(pl.double_pendulum(), **SHORT)


def test_controls_of_the_double_pendulum(dp_explorer):
    expected = {
        "theta1",
        "theta2",
        "omega1",
        "omega2",
        "m1",
        "m2",
        "l1",
        "l2",
        "g",
        "dt",
        "t_end",
        "method",
    }
    assert set(dp_explorer.controls) == expected
    assert all(
        getattr(c, "continuous_update", False) is False
        for k, c in dp_explorer.controls.items()
        if k != "method"
    )
    assert list(dp_explorer.controls["method"].options) == list(pl.METHODS)
    # The start matches the documented default (2.0, 2.5) at rest.
    np.testing.assert_array_equal(dp_explorer.trajectory.theta[0], [2.0, 2.5])
    assert dp_explorer.trajectory.t[-1] == pytest.approx(2.0)


def test_controls_of_the_simple_pendulum_use_unindexed_names():
    ex = widgets.explore(pl.simple_pendulum(length=2.0), **SHORT)
    assert {"theta", "omega", "mass", "length", "g"} <= set(ex.controls)
    assert "theta1" not in ex.controls
    assert ex.controls["length"].value == 2.0


def test_angle_slider_recomputes_and_redraws(dp_explorer):
    ex = dp_explorer
    before_traj, before_line = ex.trajectory, line_data(ex)
    before_png = ex.widget.children[-1].value
    ex.controls["theta1"].value = 0.5
    assert ex.trajectory is not before_traj
    assert ex.trajectory.theta[0, 0] == 0.5
    assert ex.trajectory.theta[0, 1] == before_traj.theta[0, 1]  # the other arm is untouched
    assert not np.array_equal(line_data(ex), before_line)
    np.testing.assert_allclose(line_data(ex), ex.trajectory.energy)  # total energy line
    assert ex.widget.children[-1].value != before_png


def test_set_controls_changes_several_and_recomputes_once(dp_explorer, monkeypatch):
    ex = dp_explorer
    computed = []
    prepare = ex.prepare
    monkeypatch.setattr(ex, "prepare", lambda: computed.append(1) or prepare())
    assert ex.set_controls({"theta1": 0.4, "theta2": -0.3, "omega1": 1.0})
    assert len(computed) == 1
    np.testing.assert_array_equal(ex.trajectory.theta[0], [0.4, -0.3])
    assert ex.trajectory.omega[0, 0] == pytest.approx(1.0)
    # Negative control: one control at a time recomputes each time.
    ex.controls["theta1"].value = 0.1
    ex.controls["theta2"].value = 0.2
    assert len(computed) == 3
    # An unknown name changes nothing.
    with pytest.raises(ValueError, match="no control named"):
        ex.set_controls({"theta1": 0.9, "theta9": 1.0})
    assert ex.controls["theta1"].value == 0.1 and len(computed) == 3


def test_velocity_slider_sets_the_initial_velocity(dp_explorer):
    dp_explorer.controls["omega2"].value = 1.5
    np.testing.assert_array_equal(dp_explorer.trajectory.omega[0], [0.0, 1.5])


def test_method_dropdown_switches_the_integrator(dp_explorer):
    assert dp_explorer.trajectory.method.name == "glrk4"
    before = line_data(dp_explorer)
    dp_explorer.controls["method"].value = "explicit_euler"
    assert dp_explorer.trajectory.method.name == "explicit_euler"
    assert not np.allclose(line_data(dp_explorer), before)


def test_dt_and_t_end_controls(dp_explorer):
    dp_explorer.controls["dt"].value = 0.02
    dp_explorer.controls["t_end"].value = 1.0
    assert dp_explorer.trajectory.dt == 0.02
    assert len(dp_explorer.trajectory.t) == 51
    assert 0.02 in widgets.DT_CHOICES


def test_invalid_combination_shows_message_and_keeps_the_figure():
    ex = widgets.explore(pl.double_pendulum(), method="rk4", **SHORT)
    ex.controls["dt"].value = 0.5  # still valid: t_end = 2 >= dt
    assert "must be" not in ex.message
    traj, line, png = ex.trajectory, line_data(ex), ex.widget.children[-1].value
    ex.controls["t_end"].value = 0.2  # now t_end < dt
    assert "`t_end` must be at least `dt`" in ex.message
    assert "Traceback" not in ex.message
    assert ex.trajectory is traj
    np.testing.assert_array_equal(line_data(ex), line)
    assert ex.widget.children[-1].value == png
    assert ex.update() is False
    # Negative control: a valid value clears the error and redraws.
    ex.controls["t_end"].value = 1.0
    assert "must be" not in ex.message and ex.trajectory is not traj
    assert ex.update() is True


def test_too_many_steps_is_refused_with_a_message():
    ex = widgets.explore(pl.simple_pendulum(), **SHORT)
    ex.controls["dt"].value = min(widgets.DT_CHOICES)  # 2 s / 0.0005 s: allowed
    traj = ex.trajectory
    assert traj.dt == min(widgets.DT_CHOICES)
    ex.controls["t_end"].value = 100.0
    assert widgets.MAX_STEPS < 100.0 / min(widgets.DT_CHOICES)
    assert "limit" in ex.message and ex.trajectory is traj


def test_convergence_failure_is_a_message_not_an_exception(dp_explorer):
    traj = dp_explorer.trajectory
    dp_explorer.controls["dt"].value = 0.5  # GLRK4's stage equations fail at the first step
    assert dp_explorer.trajectory is traj
    assert "did not converge" in dp_explorer.message


def test_blow_up_is_drawn_up_to_where_it_stopped_with_a_warning():
    ex = widgets.explore(pl.double_pendulum(), method="explicit_euler", t_end=20.0, dt=0.5)
    assert ex.trajectory.completed is False
    assert "non-finite" in ex.message
    # Negative control: a small step completes without a warning.
    ex.controls["dt"].value = 0.01
    assert ex.trajectory.completed and "non-finite" not in ex.message


def test_length_slider_rebuilds_the_model(dp_explorer):
    ex = dp_explorer
    v_before = ex.trajectory.potential[0]
    ex.controls["l1"].value = 2.0
    assert ex.model.lengths == (2.0, 1.0)
    expected = pl.double_pendulum(l1=2.0).potential_energy(ex.trajectory.theta[0])
    assert ex.trajectory.potential[0] == pytest.approx(float(expected), rel=1e-12)
    assert ex.trajectory.potential[0] != pytest.approx(v_before)
    # Negative control: the mass slider leaves the lengths alone.
    ex.controls["m2"].value = 3.0
    assert ex.model.lengths == (2.0, 1.0) and ex.model.masses == (1.0, 3.0)


def test_g_slider_changes_the_period():
    ex = widgets.explore(pl.simple_pendulum(), t_end=10.0, dt=0.01, theta0=[0.1])
    period = analysis.oscillation_period(ex.trajectory)
    ex.controls["g"].value = 2 * 9.81
    assert ex.controls["g"].value == 2 * 9.81  # inside the slider's range, not clipped
    assert analysis.oscillation_period(ex.trajectory) == pytest.approx(
        period / np.sqrt(2), rel=1e-4
    )


def test_extra_panels_by_name_and_by_callable():
    seen = []

    def custom(ax, trajectory, model):
        seen.append((trajectory, model))
        ax.plot(trajectory.t, trajectory.omega[:, 0])

    ex = widgets.explore(pl.simple_pendulum(), plots=("energy_error", "portrait", custom), **SHORT)
    assert len(ex.figure.axes) == 3
    assert seen[-1] == (ex.trajectory, ex.model)
    assert ex.figure.axes[0].get_yscale() == "log"
    ex.controls["omega"].value = 2.0
    assert len(seen) == 2 and seen[-1][0] is ex.trajectory


@pytest.mark.parametrize(
    ("plots", "match"),
    [(("energy", "nonsense"), "must be one of"), ((), "at least one"), (("portrait",), "simple")],
)
def test_bad_plots_are_rejected(plots, match):
    with pytest.raises(ValueError, match=match):
        widgets.explore(pl.double_pendulum(), plots=plots, **SHORT)


def test_bad_arguments_are_rejected():
    with pytest.raises(TypeError, match="model"):
        widgets.explore("double", **SHORT)
    with pytest.raises(ValueError, match="theta0"):
        widgets.explore(pl.double_pendulum(), theta0=[0.1], **SHORT)
    with pytest.raises(ValueError, match="theta0"):
        widgets.explore(pl.double_pendulum(), theta0=[4.0, 0.0], **SHORT)
    with pytest.raises(ValueError, match="method"):
        widgets.explore(pl.double_pendulum(), method="euler-ish", **SHORT)


def test_explorer_displays_as_its_widget(dp_explorer):
    bundle = dp_explorer._repr_mimebundle_()
    assert "application/vnd.jupyter.widget-view+json" in bundle
    assert bundle["application/vnd.jupyter.widget-view+json"]["model_id"] == (
        dp_explorer.widget.model_id
    )


def test_display_carries_the_current_figure_as_a_picture(dp_explorer):
    """Where no kernel runs (the course website), the PNG in the display stands in for the
    widget: it must be the figure as drawn now, at the figure's size."""

    def picture(explorer):
        data = base64.b64decode(explorer._repr_mimebundle_()["image/png"])
        return data, Image.open(io.BytesIO(data))

    before, image = picture(dp_explorer)
    width, height = dp_explorer.figure.get_size_inches() * dp_explorer.figure.dpi
    assert image.size == (round(width), round(height))
    dp_explorer.controls["theta1"].value = 0.3
    after, _ = picture(dp_explorer)
    # Negative control: a picture taken once, at creation, would fail here.
    assert after != before


def test_three_link_chain():
    ex = widgets.explore(pl.n_pendulum(3), t_end=0.5, dt=0.01)
    assert {"theta3", "omega3", "m3", "l3"} <= set(ex.controls)
    ex.controls["theta3"].value = -1.0
    assert ex.trajectory.theta[0, 2] == -1.0


# --------------------------------------------------------------------------- equilibria
def test_equilibrium_explorer_starts_near_the_chosen_equilibrium():
    ex = widgets.explore_equilibrium(pl.double_pendulum(), "down-down", offset=[0.01, 0.0], **SHORT)
    assert list(ex.controls["equilibrium"].options) == ["down-down", "down-up", "up-down", "up-up"]
    np.testing.assert_allclose(ex.trajectory.theta[0], [0.01, 0.0])
    assert "center" in ex.message
    ex.controls["equilibrium"].value = "up-up"
    np.testing.assert_allclose(ex.trajectory.theta[0], [np.pi + 0.01, np.pi])
    assert "up-up: saddle" in ex.message
    ex.controls["theta2"].value = -0.02
    np.testing.assert_allclose(ex.trajectory.theta[0], [np.pi + 0.01, np.pi - 0.02])


def test_equilibrium_explorer_shows_linear_and_nonlinear_side_by_side():
    ex = widgets.explore_equilibrium(pl.simple_pendulum(), "down", offset=[0.01], t_end=3.0)
    linear_ax, nonlinear_ax = ex.figure.axes
    lin, _ = analysis.linearized_solution(
        ex.model, ex.trajectory.theta[0], ex.trajectory.omega[0], t=ex.trajectory.t,
        equilibrium="down",
    )
    np.testing.assert_allclose(linear_ax.lines[0].get_ydata(), lin[:, 0])
    np.testing.assert_allclose(nonlinear_ax.lines[0].get_ydata(), ex.trajectory.theta[:, 0])
    # Small offset: the two agree closely ...
    assert np.max(np.abs(lin[:, 0] - ex.trajectory.theta[:, 0])) < 1e-5
    # ... a large one near the bottom does not (the period grows with amplitude).
    ex.controls["theta"].value = 0.5
    lin, _ = analysis.linearized_solution(
        ex.model, ex.trajectory.theta[0], ex.trajectory.omega[0], t=ex.trajectory.t,
        equilibrium="down",
    )
    assert np.max(np.abs(lin[:, 0] - ex.trajectory.theta[:, 0])) > 1e-2


def test_equilibrium_explorer_rejects_unknown_names():
    with pytest.raises(ValueError, match="equilibrium"):
        widgets.explore_equilibrium(pl.double_pendulum(), "sideways")
    with pytest.raises(ValueError, match="offset"):
        widgets.explore_equilibrium(pl.double_pendulum(), offset=[1.0, 0.0])


# --------------------------------------------------------------------------- energy levels
def test_energy_slider_sets_the_total_energy():
    dp = pl.double_pendulum()
    ex = widgets.explore_energy(dp, energy=-20.0, t_end=2.0)
    assert set(ex.controls) == {"energy", "method", "dt", "t_end"}
    assert ex.trajectory.energy[0] == pytest.approx(-20.0, abs=1e-9)
    assert len(ex.figure.axes) == 2  # one projection per arm
    before = np.array(ex.figure.axes[1].lines[0].get_ydata(), dtype=float)
    ex.controls["energy"].value = 10.0
    assert ex.trajectory.energy[0] == pytest.approx(10.0, abs=1e-9)
    assert np.all(ex.trajectory.omega[0] == 0)
    after = np.array(ex.figure.axes[1].lines[0].get_ydata(), dtype=float)
    assert before.shape != after.shape or not np.allclose(before, after, equal_nan=True)


def test_energy_explorer_range():
    dp = pl.double_pendulum()
    depth = -float(dp.potential_energy([0.0, 0.0]))
    with pytest.raises(ValueError, match="energy"):
        widgets.explore_energy(dp, energy=depth + 1.0)
    ex = widgets.explore_energy(dp, t_end=1.0)
    energy = ex.controls["energy"]
    # The range's ends are whole steps, as close to the upright and hanging chain as that
    # allows (so that every value the slider takes reads as it is).
    assert depth - energy.step < energy.max <= depth
    assert -depth < energy.min <= -depth + 2 * energy.step
    assert (energy.min / energy.step) == pytest.approx(round(energy.min / energy.step))


def _pixels(explorer) -> np.ndarray:
    import io

    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(explorer.widget.children[-1].value)))


@pytest.mark.parametrize("n, plots", [
    (2, ("energy", "angles")),
    (2, ("phase", "pendulum", "energy_error")),
    (1, ("portrait", "energy")),
])
def test_an_update_draws_exactly_what_a_fresh_explorer_draws(n, plots):
    # Updates reuse the axes (for speed); the picture must not depend on it.
    model = pl.n_pendulum(n)
    ex = widgets.explore(model, method="rk4", t_end=3.0, plots=plots)
    before = _pixels(ex)
    ex.controls["theta1" if n == 2 else "theta"].value = 0.7
    fresh = widgets.explore(model, method="rk4", t_end=3.0, plots=plots,
                            theta0=ex.trajectory.theta[0], omega0=ex.trajectory.omega[0])
    assert np.array_equal(_pixels(ex), _pixels(fresh))
    assert not np.array_equal(_pixels(ex), before)  # negative control: a new state is drawn
