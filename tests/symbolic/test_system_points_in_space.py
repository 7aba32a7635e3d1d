"""Points in space: the derivation from (x, y, z) positions, the direction of gravity and a
turning frame, each checked against equations written by hand, with negative controls."""

import pytest
import sympy as sp

from pendulum_lab.symbolic.systems import MechanicalSystem

x, y = sp.symbols("x y", real=True)
x_dot, y_dot = sp.symbols("x_dot y_dot", real=True)
m, rod, g = sp.symbols("m l g", positive=True)
spin, lat = sp.symbols("Omega lat", real=True)
VALUES = {m: 1.0, rod: 1.0, g: 9.81}
HEIGHT = -sp.sqrt(rod ** 2 - x ** 2 - y ** 2)


def bob(**extra):
    arguments = dict(points=[(x, y, HEIGHT)], masses=[m], gravity=g) | extra
    values = VALUES | ({spin: 0.01, lat: 0.8} if "frame_rotation" in extra else {})
    return MechanicalSystem([x, y], values, **arguments)


def vanishes(expr) -> bool:
    return sp.simplify(expr) == 0


def test_the_spherical_pendulum_from_its_point_has_the_lagrangian_written_by_hand():
    system = bob()
    z_dot = -(x * x_dot + y * y_dot) / HEIGHT  # d/dt of z = -sqrt(rod^2 - x^2 - y^2)
    by_hand = m * (x_dot ** 2 + y_dot ** 2 + z_dot ** 2) / 2 - m * g * HEIGHT
    assert vanishes(system.lagrangian - by_hand)
    assert system.dimensions == 3 and system.joints == [(-1, 0)]  # a rod from the pivot
    # negative control: the same point without its height is a free particle in a plane
    flat = MechanicalSystem([x, y], VALUES, points=[(x, y)], masses=[m], gravity=g)
    assert flat.dimensions == 2 and not vanishes(flat.lagrangian - by_hand)


def test_gravity_pulls_along_the_direction_given_whatever_its_length():
    down = bob().potential
    assert down == -g * m * sp.sqrt(rod ** 2 - x ** 2 - y ** 2)
    assert bob(gravity_direction=(0, 0, -2)).potential == down  # made a unit vector
    assert bob(gravity_direction=(1, 0, 0)).potential == -g * m * x
    # negative control: another direction gives another potential
    assert bob(gravity_direction=(0, 0, 1)).potential == -down


def test_a_planar_system_is_derived_exactly_as_before():
    th = sp.Symbol("theta", real=True)
    arguments = dict(points=[(rod * sp.sin(th), -rod * sp.cos(th))], masses=[m], gravity=g)
    default = MechanicalSystem([th], VALUES, **arguments)
    assert default.potential == -g * rod * m * sp.cos(th) and default.dimensions == 2
    assert default.frame_rotation is None
    stated = MechanicalSystem([th], VALUES, gravity_direction=(0, -1), **arguments)
    assert stated.lagrangian == default.lagrangian
    # negative control: gravity along +x of the plane is another pendulum
    sideways = MechanicalSystem([th], VALUES, gravity_direction=(1, 0), **arguments)
    assert sideways.potential == -g * rod * m * sp.sin(th)


def test_a_turning_frame_gives_the_coriolis_and_centrifugal_forces_at_the_bottom():
    """At the bottom the bob moves horizontally; in the frame turning at
    Omega (0, cos lat, sin lat) the forces there are -2 m Omega x v (Coriolis) and
    -m Omega x (Omega x r) at r = (0, 0, -rod) (centrifugal), horizontally
    2 m Omega sin(lat) (y', -x') + (0, m Omega^2 rod sin(lat) cos(lat))."""
    turning = bob(frame_rotation=(0, spin * sp.cos(lat), spin * sp.sin(lat)))
    at_bottom = turning.forcing.xreplace({x: 0, y: 0})
    expected = sp.Matrix([2 * m * spin * sp.sin(lat) * y_dot,
                          -2 * m * spin * sp.sin(lat) * x_dot
                          + m * spin ** 2 * rod * sp.sin(lat) * sp.cos(lat)])
    assert all(sp.expand(e) == 0 for e in at_bottom - expected)
    assert turning.mass_matrix == bob().mass_matrix  # the frame adds no inertia
    # T and V as seen in the frame: T + V is p q' - L, the Hamiltonian (Jacobi's integral)
    assert sp.expand(turning.legendre_transform() - turning.kinetic - turning.potential) == 0
    assert sp.expand(turning.lagrangian - turning.kinetic + turning.potential) != 0  # Coriolis
    # negative control: without the frame nothing pushes the bob at the bottom
    assert all(e == 0 for e in bob().forcing.xreplace({x: 0, y: 0}))


@pytest.mark.parametrize("arguments, error, message", [
    (dict(points=[(x, y, HEIGHT), (x, y)], masses=[m, m]), ValueError,
     r"`points\[1\]` has 2 coordinates and `points\[0\]` 3.*not a mixture"),
    (dict(gravity_direction=(0, 0, 0)), ValueError, "`gravity_direction` .* is zero"),
    (dict(gravity_direction=(0, -1)), ValueError, "`gravity_direction` must hold 3 entries"),
    (dict(gravity_direction=(0, 0, float("nan"))), ValueError,
     r"`gravity_direction\[2\]` must be a real finite number"),
    (dict(gravity_direction="down"), TypeError, "`gravity_direction` must be a sequence"),
    (dict(gravity_direction=(0, 0, True)), TypeError, r"`gravity_direction\[2\]` must be a"),
    (dict(gravity_direction=(0, 0, x)), ValueError, "does not change with the motion"),
    (dict(gravity=None, gravity_direction=(0, 0, -1)), TypeError,
     "`gravity_direction` goes with `gravity`"),
    (dict(frame_rotation=(0, 0)), ValueError, "`frame_rotation` must hold 3 entries"),
    (dict(frame_rotation=(0, 0, x)), ValueError, r"`frame_rotation\[2\]` = x must be a number"),
])
def test_bad_descriptions_in_space_are_refused_naming_the_argument(arguments, error, message):
    with pytest.raises(error, match=message):
        MechanicalSystem([x, y], VALUES, **(dict(points=[(x, y, HEIGHT)], masses=[m],
                                                 gravity=g) | arguments))


def test_a_turning_frame_needs_points_in_space():
    th = sp.Symbol("theta", real=True)
    with pytest.raises(ValueError, match="`frame_rotation` needs points in space"):
        MechanicalSystem([th], VALUES, points=[(sp.sin(th), -sp.cos(th))], masses=[m],
                         frame_rotation=(0, 0, 1))
    with pytest.raises(TypeError, match="`gravity_direction` and `frame_rotation` go with"):
        MechanicalSystem([th], {}, lagrangian=sp.Symbol("theta_dot") ** 2 / 2,
                         frame_rotation=(0, 0, 1))
    # negative control: the same frame turns points given in space
    assert bob(frame_rotation=(0, 0, 1)).frame_rotation == [0, 0, 1]
