"""The systems the course names, each built by :func:`~pendulum_lab.mechanical_system`:
:func:`elastic_pendulum`, :func:`kapitza_pendulum` and :func:`cart_pendulum`, the classics of a
mechanics course in a plane, :func:`spherical_pendulum` and :func:`foucault_pendulum`, two in
space."""

from __future__ import annotations

import math
import numbers

import numpy as np
import sympy as sp

from .system import SystemModel, mechanical_system, positive_finite

__all__ = [
    "EARTH_ROTATION",
    "cart_pendulum",
    "elastic_pendulum",
    "foucault_pendulum",
    "kapitza_pendulum",
    "spherical_pendulum",
]

#: The Earth's rate of rotation relative to the stars [rad/s] (one turn per sidereal day).
EARTH_ROTATION = 7.2921e-5


def elastic_pendulum(mass: float = 1.0, stiffness: float = 4 * 9.81,
                     rest_length: float = 0.75, g: float = 9.81) -> SystemModel:
    """A mass on a spring that swings in a plane: coordinates ``(r, theta)``.

    ``r`` is the spring's length, ``theta`` its angle from the downward vertical; the
    spring's potential is ``k (r - l_0)^2 / 2``. At rest ``r* = l_0 + m g / k``; the
    stretching mode has ``omega_r^2 = k / m``, the swinging mode ``omega_theta^2 = g / r*``.
    The defaults put them in 2:1 resonance (``omega_r = 2 omega_theta``: ``k r* = 4 m g``
    with ``r* = 1``), where energy swings between the two modes.
    """
    r, th = sp.symbols("r theta", real=True)
    m, k, l0, grav = sp.symbols("m k l_0 g", positive=True)
    values = {m: positive_finite("mass", mass), k: positive_finite("stiffness", stiffness),
              l0: positive_finite("rest_length", rest_length), grav: positive_finite("g", g)}
    model = mechanical_system([r, th], values, points=[(r * sp.sin(th), -r * sp.cos(th))],
                              masses=[m], gravity=grav, potential=k * (r - l0) ** 2 / 2,
                              springs=[(-1, 0)], name="the elastic pendulum")
    rest = values[l0] + values[m] * values[grav] / values[k]
    return _made_by(model, "elastic_pendulum", start=[1.2 * rest, 0.6])


def _made_by(model: SystemModel, factory: str, start) -> SystemModel:
    """``model`` with the simulators' start and the call that builds it named."""
    model.start = np.asarray(start, dtype=float)
    model.factory = f"pl.{factory}()"
    return model


def kapitza_pendulum(amplitude: float = 0.05, frequency: float = 100.0, mass: float = 1.0,
                     length: float = 1.0, g: float = 9.81) -> SystemModel:
    """A pendulum whose pivot is shaken vertically: pivot at ``(0, a cos(w t))``.

    ``theta`` from the downward vertical. The inverted position ``theta = pi`` is stable
    (Kapitza) when ``a^2 w^2 > 2 g l``; averaged over the fast shaking the motion sees the
    potential ``-m g l cos(theta) + m a^2 w^2 sin(theta)^2 / 4``.
    """
    th = sp.Symbol("theta", real=True)
    a, w, m, rod, grav = sp.symbols("a w m l g", positive=True)
    t = sp.Symbol("t", real=True)
    values = {a: positive_finite("amplitude", amplitude),
              w: positive_finite("frequency", frequency), m: positive_finite("mass", mass),
              rod: positive_finite("length", length), grav: positive_finite("g", g)}
    pivot_y = a * sp.cos(w * t)
    bob = (rod * sp.sin(th), pivot_y - rod * sp.cos(th))
    # The pivot is a massless point, so that the drawings show it shaking.
    model = mechanical_system([th], values, points=[(sp.Integer(0), pivot_y), bob],
                              masses=[0, m], gravity=grav, joints=[(0, 1)],
                              name="the Kapitza pendulum", period=2 * sp.pi / w)
    return _made_by(model, "kapitza_pendulum", start=[math.pi - 0.3])


def cart_pendulum(cart_mass: float = 1.0, mass: float = 0.5, length: float = 1.0,
                  g: float = 9.81) -> SystemModel:
    """A pendulum hanging from a cart that rolls freely on a horizontal rail.

    Coordinates ``(x, theta)``: the cart's position and the rod's angle from the downward
    vertical. Two points: the cart at ``(x, 0)`` and the bob at
    ``(x + l sin(theta), -l cos(theta))``.
    """
    x, th = sp.symbols("x theta", real=True)
    big_m, m, rod, grav = sp.symbols("M m l g", positive=True)
    values = {big_m: positive_finite("cart_mass", cart_mass), m: positive_finite("mass", mass),
              rod: positive_finite("length", length), grav: positive_finite("g", g)}
    bob = (x + rod * sp.sin(th), -rod * sp.cos(th))
    model = mechanical_system([x, th], values, points=[(x, sp.Integer(0)), bob],
                              masses=[big_m, m], gravity=grav, joints=[(0, 1)],
                              name="the pendulum on a cart")
    return _made_by(model, "cart_pendulum", start=[0.0, 1.0])


def _bob_in_space(length_symbol) -> tuple:
    """``(x, y)`` of a bob on a rod of length ``l`` from the origin, and its position
    ``(x, y, z)`` below the pivot (``z = -sqrt(l^2 - x^2 - y^2)``)."""
    x, y = sp.symbols("x y", real=True)
    return x, y, (x, y, -sp.sqrt(length_symbol ** 2 - x ** 2 - y ** 2))


def spherical_pendulum(mass: float = 1.0, length: float = 1.0, g: float = 9.81) -> SystemModel:
    """A bob on a rod that turns freely in every direction about a fixed pivot.

    Coordinates ``(x, y)``: the bob's horizontal position [m], ``z = -sqrt(l^2 - x^2 - y^2)``
    below the pivot (``z`` up, gravity along ``-z``). These are regular wherever the bob is
    below the pivot's level, bottom included, where the course runs it (small and moderate
    swings, the nearly elliptical orbits of Airy's precession); they fail only at the level of
    the pivot (``x^2 + y^2 = l^2``, where ``z`` turns). The usual angles ``(theta, phi)`` fail
    at the bottom instead: there ``phi`` is undefined, and an orbit that passes near the
    bottom turns ``phi`` by nearly pi in a moment.

    The vertical angular momentum ``L_z = m (x y' - y x')``, which is ``x p_y - y p_x`` in
    the canonical momenta, is conserved (gravity and the rod exert no torque about the
    vertical axis).
    """
    m, rod, grav = sp.symbols("m l g", positive=True)
    values = {m: positive_finite("mass", mass), rod: positive_finite("length", length),
              grav: positive_finite("g", g)}
    x, y, bob = _bob_in_space(rod)
    model = mechanical_system([x, y], values, points=[bob], masses=[m], gravity=grav,
                              name="the spherical pendulum")
    return _made_by(model, "spherical_pendulum", start=[0.5 * values[rod], 0.0])


def _latitude(latitude) -> float:
    """``latitude`` in degrees as a float, if it is a real number in [-90, 90]."""
    if isinstance(latitude, (bool, np.bool_)) or not isinstance(latitude, numbers.Real):
        raise TypeError(f"`latitude` must be a number of degrees in [-90, 90], got "
                        f"{latitude!r} ({type(latitude).__name__})")
    if not (math.isfinite(latitude) and -90 <= latitude <= 90):
        raise ValueError(f"`latitude` must be a number of degrees in [-90, 90] (north "
                         f"positive), got {latitude!r}")
    return float(latitude)


def foucault_pendulum(latitude: float = 48.85, length: float = 1.0, mass: float = 1.0,
                      g: float = 9.81, rotation_rate: float = EARTH_ROTATION) -> SystemModel:
    """A spherical pendulum in a laboratory on the turning Earth, at ``latitude`` degrees.

    The points are written in the laboratory's frame (``x`` east, ``y`` north, ``z`` up,
    pivot at the origin), which turns with the Earth at ``Omega = rotation_rate`` about the
    Earth's axis: in those axes ``Omega (0, cos(lat), sin(lat))``. The Lagrangian is built
    from the bob's inertial velocity ``r' + Omega x r`` (``frame_rotation`` of
    :func:`mechanical_system`), so the Coriolis and centrifugal forces come out of the
    derivation. ``g`` is the local gravity a plumb line shows: the centrifugal acceleration of
    the laboratory's distance from the Earth's axis is constant in the laboratory and is part
    of it, so the frame turns about an axis through the pivot.

    Coordinates ``(x, y)``, the bob's horizontal position, as for :func:`spherical_pendulum`
    and for the same reason: a Foucault pendulum swings through the bottom, where angles
    ``(theta, phi)`` fail, while ``(x, y)`` fail only at the pivot's level. Its plane of swing
    turns clockwise (seen from above) at ``Omega sin(lat)`` in the northern hemisphere.

    Parameters
    ----------
    latitude : float
        Degrees in [-90, 90], north positive (the default is Paris, the Panthéon's
        pendulum). The model's parameter ``lat`` holds it in radians; ``replace(lat=...)`` and
        ``family(lat=[...])`` take degrees, as here, checked the same way.
    length, mass, g : float
        The rod's length [m], the bob's mass [kg], the local gravity [m/s^2].
    rotation_rate : float
        ``Omega`` [rad/s], the Earth's by default; a larger one speeds the turning up for a
        short simulation (the Coriolis force stays small beside gravity while ``Omega`` is
        far below the swing's ``sqrt(g / l)``).
    """
    lat_degrees = _latitude(latitude)
    if isinstance(rotation_rate, (bool, np.bool_)) or not isinstance(rotation_rate,
                                                                     numbers.Real):
        raise TypeError(f"`rotation_rate` must be a real number of rad/s, got "
                        f"{rotation_rate!r} ({type(rotation_rate).__name__})")
    if not math.isfinite(rotation_rate):
        raise ValueError(f"`rotation_rate` must be finite, got {rotation_rate!r}")
    m, rod, grav = sp.symbols("m l g", positive=True)
    spin, lat = sp.symbols("Omega lat", real=True)
    values = {m: positive_finite("mass", mass), rod: positive_finite("length", length),
              grav: positive_finite("g", g), spin: float(rotation_rate),
              lat: math.radians(lat_degrees)}
    x, y, bob = _bob_in_space(rod)
    model = mechanical_system(
        [x, y], values, points=[bob], masses=[m], gravity=grav,
        frame_rotation=(0, spin * sp.cos(lat), spin * sp.sin(lat)),
        name="the Foucault pendulum")
    model = _made_by(model, "foucault_pendulum", start=[0.1 * values[rod], 0.0])
    model.factory = f"pl.foucault_pendulum(latitude={lat_degrees:g})"
    model.factory_units = {"lat": (_latitude_radians, math.degrees)}
    return model


def _latitude_radians(latitude) -> float:
    """A latitude in degrees, checked as :func:`foucault_pendulum` checks it, in radians (the
    unit of the model's ``lat``)."""
    return math.radians(_latitude(latitude))
