"""Click to launch, headlessly: the section and portrait explorers of pendulum_lab.widgets."""

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab import chaos, plotting
from pendulum_lab.widgets.clickable import (
    COLOURS,
    portrait_explorer,
    section_explorer,
    section_reach,
)

DP = pl.double_pendulum()
SP = pl.simple_pendulum()


@pytest.fixture
def section():
    return section_explorer(DP, energy=-15.0, t_end=30.0)


@pytest.fixture
def portrait():
    return portrait_explorer(SP, t_end=5.0)


def sent_points(plot, k):
    return np.frombuffer(plot.orbits[k]["xy"], dtype="<f4").reshape(-1, 2)


# --------------------------------------------------------------------------- the section
@pytest.mark.parametrize("energy", [-25.0, -15.0, 0.0])
@pytest.mark.parametrize("theta2", [-0.5, 0.0, 0.7])
def test_the_reachable_region_is_where_a_momentum_solves_the_energy(energy, theta2):
    reach = float(section_reach(DP, energy, theta2))
    assert reach > 0
    # Just inside, section_states finds p1 with H = E; just outside it finds none.
    theta0, omega0 = chaos.section_states(DP, energy, [[theta2]], [[0.999999 * reach]])
    assert DP.energy(theta0, omega0)[0] == pytest.approx(energy, abs=1e-9)
    with pytest.raises(ValueError, match="no point reaches"):
        chaos.section_states(DP, energy, [[theta2]], [[1.000001 * reach]])


def test_nothing_is_reachable_where_the_potential_exceeds_the_energy():
    # V(0, pi) = -g (2 - 1) = -9.81 J: at -15 J the second arm cannot point up.
    assert np.isnan(section_reach(DP, -15.0, np.pi))
    assert section_reach(DP, -5.0, np.pi) == pytest.approx(np.sqrt(2 * (-5.0 + 9.81)))


def test_a_click_launches_the_orbit_through_that_point(section):
    assert section.click(0.5, 0.0)
    (orbit,) = section.orbits
    assert orbit.points[0].tolist() == [0.5, 0.0]  # the clicked point first
    # The same public calls by hand give the same crossings.
    theta0, omega0 = chaos.section_states(DP, -15.0, [[0.5]], [[0.0]])
    by_hand = chaos.poincare_section(DP, theta0, omega0, t_end=30.0, dt=0.01, method="glrk4")
    np.testing.assert_array_equal(orbit.points[1:], np.column_stack(by_hand.coordinates()))
    # Energy is conserved, so every crossing lies in the reachable region.
    x, y = orbit.points[:, 0], orbit.points[:, 1]
    assert len(x) > 5 and np.all(np.abs(y) <= section_reach(DP, -15.0, x) + 1e-6)
    np.testing.assert_array_equal(sent_points(section.plot, 0), orbit.points.astype(np.float32))
    assert "crossings" in section.message and section.plot.message_kind == "info"


def test_each_orbit_gets_a_new_colour_and_undo_and_clear_remove_them(section):
    assert section.click(0.5, 0.0) and section.click(-0.3, 2.0) and section.click(0.0, -3.0)
    colours = [o.colour for o in section.orbits]
    assert colours == list(COLOURS[:3]) and len(set(colours)) == 3
    assert [o["colour"] for o in section.plot.orbits] == colours
    assert section.undo()
    assert len(section.orbits) == len(section.plot.orbits) == 2
    section.clear()
    assert section.orbits == [] and section.plot.orbits == []
    assert not section.undo() and section.message == "Nothing to undo."


def test_a_click_where_no_orbit_exists_keeps_the_picture(section):
    assert section.click(0.5, 0.0)
    before = list(section.plot.orbits)
    assert not section.click(3.0, 5.0)  # beyond the boundary of E = -15 J
    assert section.plot.orbits == before and len(section.orbits) == 1
    assert section.plot.message_kind == "error"
    assert "grey region" in section.message and "θ₂ = 3.000 rad" in section.message
    assert not section.click(float("nan"), 0.0)
    assert "`x` must be finite" in section.message and len(section.orbits) == 1


def test_the_browser_click_message_gets_an_answer(section, monkeypatch):
    sent = []
    monkeypatch.setattr(section.plot, "send", lambda content, buffers=None: sent.append(content))
    section.plot._dispatch(section.plot, {"type": "click", "x": 0.5, "y": 0.0}, [])
    section.plot._dispatch(section.plot, {"type": "click", "x": None, "y": 0.0}, [])
    assert sent == [{"type": "launched", "ok": True}, {"type": "launched", "ok": False}]
    section.plot._dispatch(section.plot, {"type": "undo"}, [])
    assert section.orbits == []


def test_a_new_energy_redraws_the_surface_and_clears_the_orbits(section):
    assert section.click(0.5, 0.0)
    picture, frame = section.plot.background, dict(section.plot.frame)
    section.controls["energy"].value = -5.0
    assert section.orbits == [] and section.plot.orbits == []
    assert section.plot.background != picture
    assert section.plot.frame["ylim"][1] > frame["ylim"][1]  # more energy, more momentum
    assert section.plot.background[:8] == b"\x89PNG\r\n\x1a\n"
    assert section.click(3.0, 0.5)  # outside at -15 J, inside at -5 J


def test_the_frame_maps_data_to_the_picture(section):
    frame = section.plot.frame
    left, top, right, bottom = frame["box"]
    assert 0 < left < right < 1 and 0 < top < bottom < 1
    assert frame["xlim"] == pytest.approx([-np.pi, np.pi])
    assert frame["size"] == [600, 440] and frame["style"] == "points"
    assert frame["labels"] == ["θ₂ (rad)", "p₂ (kg m²/s)"]


def test_display_carries_the_picture_clicks_land_on(section):
    import base64

    bundle = section._repr_mimebundle_()
    assert "application/vnd.jupyter.widget-view+json" in bundle
    assert base64.b64decode(bundle["image/png"]) == section.plot.background
    section.controls["energy"].value = -5.0  # a new surface, a new picture
    assert base64.b64decode(section._repr_mimebundle_()["image/png"]) == section.plot.background
    assert base64.b64decode(bundle["image/png"]) != section.plot.background


def test_section_explorer_refuses_other_models_and_energies():
    with pytest.raises(ValueError, match="double pendulum"):
        section_explorer(SP)
    with pytest.raises(ValueError, match="`energy` must be in"):
        section_explorer(DP, energy=-40.0)


# --------------------------------------------------------------------------- the portrait
def test_a_click_on_the_portrait_launches_the_simulated_orbit(portrait):
    assert portrait.click(1.0, 0.0)
    (orbit,) = portrait.orbits
    run = pl.simulate(SP, [1.0], [0.0], t_end=5.0, dt=0.01, method="glrk4")
    np.testing.assert_array_equal(orbit.points[:, 0], plotting.wrap_angle(run.theta[:, 0]))
    np.testing.assert_array_equal(orbit.points[:, 1], run.omega[:, 0])
    assert portrait.plot.frame["style"] == "line"


def test_the_portrait_wraps_angles_and_widens_to_hold_the_orbit(portrait):
    limit = portrait.plot.frame["ylim"][1]
    assert limit == pytest.approx(1.6 * 2 * np.sqrt(9.81))
    # From the top at -10 rad/s: a rotation, fastest at the bottom, beyond the window.
    assert portrait.click(-np.pi, -10.0)
    theta, omega = portrait.orbits[0].points.T
    assert np.all((theta > -np.pi) & (theta <= np.pi))
    assert np.max(np.abs(omega)) == pytest.approx(np.sqrt(100 + 4 * 9.81), rel=1e-3)
    assert portrait.plot.frame["ylim"][1] >= np.max(np.abs(omega))
    assert portrait.omega_max > limit
    # A small orbit afterwards does not shrink the window.
    widened = portrait.plot.frame["ylim"][1]
    assert portrait.click(0.2, 0.0) and portrait.plot.frame["ylim"][1] == widened
    assert len(portrait.plot.orbits) == 2


def test_explicit_euler_orbits_spiral_out(portrait):
    portrait.controls["method"].value = "explicit_euler"
    assert portrait.click(0.5, 0.0)
    theta, omega = portrait.orbits[0].points.T
    energy = SP.energy(theta[:, None], omega[:, None])
    assert energy[-1] > energy[0] + 0.1
    assert "max |E − E(0)|" in portrait.message
    # Negative control: the symplectic, symmetric GLRK4 stays on its level set.
    portrait.controls["method"].value = "glrk4"
    assert portrait.click(0.5, 0.0)
    theta, omega = portrait.orbits[1].points.T
    energy = SP.energy(theta[:, None], omega[:, None])
    assert np.ptp(energy) < 1e-6


def test_portrait_explorer_refuses_other_models():
    with pytest.raises(ValueError, match="simple pendulum"):
        portrait_explorer(DP)


def test_the_explorers_portrait_panel_holds_a_fast_trajectory():
    """Notebook 04's explorer from theta = -pi, omega = -10 rad/s with explicit Euler: the
    energy grows, the rotation speeds up beyond the default window (+-10.02 rad/s)."""
    from pendulum_lab import widgets

    ex = widgets.explore(
        SP, method="explicit_euler", t_end=20.0, dt=0.01, theta0=[1.0], plots=("portrait",)
    )
    ex.controls["theta"].value = -np.pi
    ex.controls["omega"].value = -10.0
    (ax,) = ex.figure.axes
    fastest = np.max(np.abs(ex.trajectory.omega))
    assert fastest > 12.0  # faster than the default window allows
    low, high = ax.get_ylim()
    assert low <= -fastest and high >= fastest
    x, y = ax.lines[-2].get_data()  # the trajectory (the start marker is last)
    inside = np.isnan(x) | ((x > -np.pi) & (x <= np.pi) & (y >= low) & (y <= high))
    assert np.all(inside)
    # Negative control: a slow libration keeps the default window.
    ex.controls["omega"].value = 0.0
    ex.controls["theta"].value = 0.5
    assert ax.get_ylim()[1] == pytest.approx(1.6 * 2 * np.sqrt(9.81))
