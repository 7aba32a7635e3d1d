"""What a picture of a system shows and what a drag sets: ``model.drawing``,
``model.place_point`` and ``angle_coordinates``, for chains and systems given by their points."""

import numpy as np
import pytest
import sympy as sp

import pendulum_lab as pl


def test_a_chains_drawing_is_its_bobs_joined_to_the_pivot():
    drawing = pl.n_pendulum(3, lengths=[1.0, 0.5, 0.25]).drawing
    assert drawing.rods == ((-1, 0), (0, 1), (1, 2)) and drawing.springs == ()
    assert drawing.reach == pytest.approx(1.75) and drawing.uses_origin
    assert drawing.movable == (None, None, None)


def test_the_systems_drawings_name_their_parts():
    elastic, kapitza, cart = pl.elastic_pendulum(), pl.kapitza_pendulum(), pl.cart_pendulum()
    assert elastic.drawing.springs == ((-1, 0),) and elastic.drawing.rods == ()
    assert kapitza.drawing.masses == (0.0, 1.0) and kapitza.drawing.rods == ((0, 1),)
    assert not kapitza.drawing.uses_origin  # its pivot is the massless point 0, shaken
    assert cart.drawing.masses == (1.0, 0.5) and cart.drawing.reach is None
    # The shaken pivot cannot be dragged (its motion is prescribed); the bob can.
    assert "does not move with the coordinates" in kapitza.drawing.movable[0]
    assert kapitza.drawing.movable[1] is None


def test_the_kapitza_pivot_moves_with_time_at_its_amplitude():
    kapitza = pl.kapitza_pendulum(amplitude=0.05, frequency=100.0)
    t = np.array([0.0, np.pi / 100, np.pi / 200])
    x, y = kapitza.positions(np.full((3, 1), 0.3), t)
    assert y[:, 0] == pytest.approx([0.05, -0.05, 0.0], abs=1e-15)
    assert y[:, 1] - y[:, 0] == pytest.approx(np.full(3, -np.cos(0.3)))  # the rod's length 1


def test_angle_coordinates_are_those_seen_only_through_sine_and_cosine():
    assert pl.elastic_pendulum().angle_coordinates == (False, True)
    assert pl.cart_pendulum().angle_coordinates == (False, True)
    assert pl.double_pendulum().angle_coordinates == (True, True)
    # Negative control: a torsion spring k theta^2 / 2 makes theta no longer 2 pi-periodic.
    th = sp.Symbol("theta", real=True)
    m, rod, g, k = sp.symbols("m l g k", positive=True)
    spring = pl.mechanical_system([th], {m: 1.0, rod: 1.0, g: 9.81, k: 2.0},
                                  points=[(rod * sp.sin(th), -rod * sp.cos(th))], masses=[m],
                                  gravity=g, potential=k * th**2 / 2, joints=[(-1, 0)])
    assert spring.angle_coordinates == (False,)


def test_dragging_the_elastic_bob_puts_it_exactly_there():
    elastic = pl.elastic_pendulum()
    for target in [(0.5, -1.0), (-0.3, -0.4), (0.9, 0.2)]:
        q = elastic.place_point(0, *target, elastic.start)
        x, y = elastic.positions(q)
        assert (x[0], y[0]) == pytest.approx(target, abs=1e-12)
    # The origin is where polar coordinates fail: refused, not a NaN start.
    with pytest.raises(ValueError, match="mass matrix is singular"):
        elastic.place_point(0, 0.0, 0.0, elastic.start)


def test_dragging_the_cart_moves_only_the_cart_and_the_bob_moves_both():
    cart = pl.cart_pendulum()
    start = np.array([0.2, 0.7])
    q = cart.place_point(0, -0.4, 0.3, start)  # the cart rides its rail: y cannot change
    assert q == pytest.approx([-0.4, 0.7], abs=1e-9)
    q = cart.place_point(1, 0.5, -0.6, start)
    x, y = cart.positions(q)
    assert (x[1], y[1]) == pytest.approx((0.5, -0.6), abs=1e-10)
    assert abs(q[0] - start[0]) > 1e-3 and abs(q[1] - start[1]) > 1e-3  # both coordinates moved


def test_a_bob_out_of_reach_stops_at_the_nearest_place_and_the_pivot_is_refused():
    kapitza = pl.kapitza_pendulum()
    q = kapitza.place_point(1, 10.0, 0.05, kapitza.start)  # far to the right of the pivot
    # The rod points there (up to whole turns), its length kept.
    assert np.angle(np.exp(1j * q[0])) == pytest.approx(np.pi / 2, abs=1e-6)
    with pytest.raises(ValueError, match="prescribed"):
        kapitza.place_point(0, 0.1, 0.1, kapitza.start)


def test_bad_joints_and_springs_are_refused_by_name():
    th = sp.Symbol("theta", real=True)
    point = [(sp.sin(th), -sp.cos(th))]
    with pytest.raises(ValueError, match="`springs` pair \\(0, 3\\)"):
        pl.mechanical_system([th], {}, points=point, masses=[1], springs=[(0, 3)])
    with pytest.raises(TypeError, match="`joints` must hold pairs"):
        pl.mechanical_system([th], {}, points=point, masses=[1], joints=[(0,)])
    assert pl.mechanical_system([th], {}, points=point, masses=[1], joints=[(-1, 0)])  # control


def test_a_system_given_by_its_lagrangian_has_no_drawing_and_says_why():
    q, w = sp.symbols("q w", real=True)
    model = pl.mechanical_system([q], {}, lagrangian=w**2 / 2 - q**2 / 2, velocities=[w],
                                 name="the oscillator")
    with pytest.raises(TypeError, match="the oscillator was given by its Lagrangian"):
        model.drawing  # noqa: B018


# ---- the suspension read from the points, when no joints or springs are declared ----------
def sideways_pendulum(**options):
    th, t = sp.Symbol("theta", real=True), sp.Symbol("t", real=True)
    a, w, m, length, g = sp.symbols("a w m l g", positive=True)
    return pl.mechanical_system(
        [th], {a: 0.1, w: 20.0, m: 1.0, length: 0.8, g: 9.81},
        points=[(a * sp.cos(w * t) + length * sp.sin(th), -length * sp.cos(th))], masses=[m],
        gravity=g, name="a pendulum shaken sideways", **options)


def test_a_pendulum_shaken_sideways_is_drawn_with_its_rod_and_moving_pivot():
    from pendulum_lab.widgets.channel import figure_message

    model = sideways_pendulum()
    drawing = model.drawing
    assert drawing.masses == (1.0, 0.0) and drawing.rods == ((1, 0),)
    assert drawing.movable[0] is None and drawing.movable[1] is not None  # the pivot is led
    run = pl.simulate(model, [0.5], [0.0], t_end=0.5, dt=0.005, method="rk4", progress=False)
    xs, ys = model.positions(run.theta, run.t)
    np.testing.assert_allclose(xs[:, 1], 0.1 * np.cos(20.0 * run.t), atol=1e-15)
    np.testing.assert_allclose(ys[:, 1], 0.0, atol=0)
    # the rod keeps its length while the pivot moves
    np.testing.assert_allclose(np.hypot(xs[:, 0] - xs[:, 1], ys[:, 0] - ys[:, 1]), 0.8,
                               rtol=1e-13)
    assert np.ptp(xs[:, 1]) > 0.1  # and the pivot does move
    message = figure_message(model, np.stack([xs, ys], axis=-1))
    assert message["rods"] == [[1, 0]] and message["masses"] == [1.0, 0.0]
    assert message["trailed"] == 0  # the trail follows the bob, not the pivot
    # The added massless point changes nothing in the motion: the same run as with the
    # joint declared by hand (which draws a lone disc without it).
    bare = sideways_pendulum(joints=[])
    assert bare.drawing.rods == () and bare.drawing.masses == (1.0,)  # negative control
    same = pl.simulate(bare, [0.5], [0.0], t_end=0.5, dt=0.005, method="rk4", progress=False)
    np.testing.assert_array_equal(same.theta, run.theta)


def test_rods_are_read_from_fixed_distances_only():
    t1, t2, r = sp.symbols("theta1 theta2 r", real=True)
    m, length, g, k = sp.symbols("m l g k", positive=True)
    values = {m: 1.0, length: 1.0, g: 9.81}
    bob1 = (length * sp.sin(t1), -length * sp.cos(t1))
    bob2 = (bob1[0] + length * sp.sin(t2), bob1[1] - length * sp.cos(t2))
    double = pl.mechanical_system([t1, t2], values, points=[bob1, bob2], masses=[m, m],
                                  gravity=g)
    assert double.drawing.rods == ((-1, 0), (0, 1))
    # negative control: a spring's length changes, so no rod is drawn for it
    spring = pl.mechanical_system([r, t1], values | {k: 40.0},
                                  points=[(r * sp.sin(t1), -r * sp.cos(t1))], masses=[m],
                                  gravity=g, potential=k * (r - 1) ** 2 / 2)
    assert spring.drawing.rods == () and len(spring.drawing.masses) == 1
