"""The spherical and Foucault pendulums under the package's tools: the vertical angular
momentum by method, Airy's precession, Foucault's, equilibria, symplecticity, sections,
Lyapunov spectra and bad input, each check with a negative control."""

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab.analysis import symplecticity_defect

G, L = 9.81, 1.0
OMEGA = np.sqrt(G / L)


def vertical_momentum(model, run):
    """``L_z = x p_y - y p_x`` along a run (the canonical form of ``m (x y' - y x')``)."""
    p = model.momenta(run.theta, run.omega)
    return run.theta[:, 0] * p[:, 1] - run.theta[:, 1] * p[:, 0]


def apsis_rate(run) -> float:
    """The mean rate [rad/s] at which the farthest points of the swing turn about the vertical
    (a line of swing is a direction mod pi)."""
    x, y = run.theta[:, 0], run.theta[:, 1]
    r2 = x * x + y * y
    k = np.flatnonzero((r2[1:-1] > r2[:-2]) & (r2[1:-1] >= r2[2:])) + 1
    return float(np.polyfit(run.t[k], np.unwrap(2 * np.arctan2(y[k], x[k])) / 2, 1)[0])


def test_symplectic_methods_keep_the_vertical_angular_momentum_and_rk4_does_not(spherical):
    """L_z is a bilinear invariant q^T C p: symplectic (partitioned) Runge-Kutta methods keep
    it to round-off (Hairer, Lubich, Wanner, Sect. IV.2); RK4 lets it drift."""
    start = ([0.4, 0.0], [0.0, 1.5])
    drifts = {}
    for method in ("leapfrog", "glrk4", "rk4"):
        run = pl.simulate(spherical, *start, t_end=30.0, dt=0.02, method=method)
        assert run.completed
        lz = vertical_momentum(spherical, run)
        drifts[method] = np.abs(lz - lz[0]).max() / abs(lz[0])
    assert drifts["leapfrog"] < 1e-12 and drifts["glrk4"] < 1e-12, drifts
    assert drifts["rk4"] > 1e-9, drifts  # negative control: the check sees a drift


def test_a_nearly_elliptical_orbit_precesses_at_airys_rate(spherical):
    a, b = 0.05 * L, 0.01 * L
    run = pl.simulate(spherical, [a, 0.0], [0.0, b * OMEGA], t_end=40.0, dt=0.01,
                      method="glrk4")
    airy = 3 / 8 * a * b * OMEGA / L ** 2
    assert abs(apsis_rate(run) - airy) < 0.02 * airy
    # negative control: a swing in a plane (b = 0) does not turn
    flat = pl.simulate(spherical, [a, 0.0], [0.0, 0.0], t_end=40.0, dt=0.01, method="glrk4")
    assert abs(apsis_rate(flat)) < 0.01 * airy


def test_the_plane_of_a_foucault_pendulum_turns_at_omega_sin_latitude():
    """A sped-up Earth (Omega = 0.05 rad/s, still 60 times slower than the swing) over a
    quarter of its day, from rest at a tenth of the length: the plane turns clockwise at
    Omega sin(latitude) to within Airy's (3/8)(a/l)^2 of the thin ellipse the Coriolis force
    makes."""
    spin, rates = 0.05, {}
    for latitude in (48.85, -48.85, 0.0):
        model = pl.foucault_pendulum(latitude=latitude, rotation_rate=spin)
        run = pl.simulate(model, [0.1 * L, 0.0], [0.0, 0.0], t_end=0.25 * 2 * np.pi / spin,
                          dt=0.02, method="leapfrog")
        assert np.abs(run.energy - run.energy[0]).max() < 1e-3 * abs(run.energy[0])
        rates[latitude] = apsis_rate(run)
    expected = -spin * np.sin(np.radians(48.85))
    assert abs(rates[48.85] - expected) < 0.01 * abs(expected), rates
    # negative controls: the other hemisphere turns the other way, the equator not at all
    assert abs(rates[-48.85] + expected) < 0.01 * abs(expected), rates
    assert abs(rates[0.0]) < 0.01 * abs(expected), rates


def test_equilibrium_symplecticity_and_the_tools_that_apply(spherical):
    (bottom,) = spherical.equilibria
    assert bottom.angles == (0.0, 0.0) and bottom.classify({}) == "center"
    assert np.allclose(sorted(abs(complex(e).imag) for e in bottom.eigenvalues()),
                       [OMEGA] * 4)
    state = ([0.3, 0.1], [0.2, -0.5])
    assert symplecticity_defect(spherical, *state, dt=0.1, method="glrk4") < 1e-8
    assert symplecticity_defect(spherical, *state, dt=0.1, method="rk4") > 1e-6  # control
    section = pl.chaos.poincare_section(spherical, *state, t_end=20.0, dt=0.02)
    assert len(section.theta) > 5 and np.allclose(section.theta[..., 0], 0.0, atol=1e-9)
    largest = {}
    for t_end in (10.0, 640.0):
        spectrum = pl.chaos.lyapunov_spectrum(spherical, *state, t_end=t_end, dt=0.02)
        exponents = np.sort(np.asarray(spectrum.exponents))[::-1]
        assert exponents.shape == (4,)
        assert np.abs(exponents + exponents[::-1]).max() < 0.01  # in pairs
        largest[t_end] = exponents[0]
    # integrable (energy and L_z): the largest exponent falls towards 0 as the run grows,
    # where a chaotic orbit's would settle at a positive value
    assert largest[640.0] < 0.02 and largest[640.0] < 0.2 * largest[10.0], largest


@pytest.mark.parametrize("latitude, error", [
    (90.5, ValueError), (-91, ValueError), (float("nan"), ValueError),
    (float("inf"), ValueError), ("48.85", TypeError), (True, TypeError), (None, TypeError),
])
def test_a_latitude_outside_the_globe_is_refused_naming_it(latitude, error):
    with pytest.raises(error, match="`latitude` must be a number of degrees in \\[-90, 90\\]"):
        pl.foucault_pendulum(latitude=latitude)


def test_the_poles_and_numpy_numbers_are_latitudes_and_other_arguments_are_checked():
    # negative control of the refusals above: the ends of the range are accepted
    for latitude in (90, -90, np.float32(45.0)):
        assert pl.foucault_pendulum(latitude=latitude).factory.startswith(
            "pl.foucault_pendulum(latitude=")
    with pytest.raises(ValueError, match="`length` must be a positive finite number"):
        pl.foucault_pendulum(length=0.0)
    with pytest.raises(ValueError, match="`rotation_rate` must be finite"):
        pl.foucault_pendulum(rotation_rate=float("inf"))
    with pytest.raises(ValueError, match="`mass` must be a positive finite number"):
        pl.spherical_pendulum(mass=-1.0)


def test_a_point_in_space_is_placed_by_its_horizontal_position_within_reach(spherical):
    """What a drag seen from above sets: the bob's (x, y); its height follows from the rod."""
    placed = spherical.place_point(0, 0.3, -0.4, [0.1, 0.2])
    assert placed == pytest.approx([0.3, -0.4], abs=1e-9)
    assert spherical.positions(placed)[2][0] == pytest.approx(-np.sqrt(1 - 0.25))
    # negative control: beyond the rod's reach there is no height, and no silent NaN run
    with pytest.raises(ValueError, match="point 0 of the spherical pendulum cannot be at "
                                         "\\(1.2, 0\\) m: its rods do not reach there"):
        spherical.place_point(0, 1.2, 0.0, [0.1, 0.2])


def test_the_foucault_pendulums_equilibrium_and_its_two_frequencies():
    """Found numerically (Newton) within a second: pushed north by the centrifugal force,
    Omega^2 l sin(lat) cos(lat) / g, and the swing's two frequencies split by 2 Omega sin(lat)
    (the plane turns at half the difference)."""
    spin, latitude = 0.01, 45.0
    turning = pl.foucault_pendulum(latitude=latitude, rotation_rate=spin)
    (bottom,) = turning.equilibria
    lat = np.radians(latitude)
    assert bottom.angles[0] == pytest.approx(0.0, abs=1e-12)
    assert bottom.angles[1] == pytest.approx(spin ** 2 * L * np.sin(lat) * np.cos(lat) / G,
                                             rel=1e-3)
    frequencies = np.sort(np.abs(np.linalg.eigvals(np.array(bottom.jacobian, dtype=float))
                                 .imag))[::2]
    assert frequencies[1] - frequencies[0] == pytest.approx(2 * spin * np.sin(lat), rel=1e-3)
    # negative control: a frame that does not turn leaves the bob at the bottom, one frequency
    (still,) = pl.foucault_pendulum(latitude=latitude, rotation_rate=0.0).equilibria
    assert still.angles == (0.0, 0.0)
    still_frequencies = np.abs(np.linalg.eigvals(np.array(still.jacobian, dtype=float)).imag)
    assert np.ptp(still_frequencies) < 1e-9


def test_a_bead_on_a_turning_hoop_rises_to_the_angle_the_centrifugal_force_sets():
    """A bead on a hoop of radius R turning at W about its vertical diameter, written in the
    hoop's frame: above W^2 R = g it rests at cos(theta) = g / (R W^2), on either side."""
    import sympy as sp

    th = sp.Symbol("theta", real=True)
    m, radius, g, spin = sp.symbols("m R g W", positive=True)

    def hoop(rate):
        return pl.mechanical_system(
            [th], {m: 1.0, radius: 0.5, g: G, spin: rate},
            points=[(radius * sp.sin(th), 0, -radius * sp.cos(th))], masses=[m], gravity=g,
            frame_rotation=(0, 0, spin), name="a bead on a turning hoop")

    fast = sorted(eq.angles[0] for eq in hoop(6.0).equilibria)
    side = np.arccos(G / (0.5 * 6.0 ** 2))
    assert fast == pytest.approx([-side, 0.0, side], abs=1e-9)
    # negative control: below the threshold only the bottom
    assert [eq.angles for eq in hoop(4.0).equilibria] == [(0.0,)]


@pytest.fixture(scope="module")
def paris():
    return pl.foucault_pendulum(latitude=48.85)


@pytest.mark.parametrize(("latitude", "error"), [(100, ValueError), (float("nan"), ValueError),
                                                 ("north", TypeError), (True, TypeError)])
def test_replace_takes_the_latitude_as_the_factory_does(paris, latitude, error):
    """In degrees, in [-90, 90], refused with the factory's own sentence."""
    with pytest.raises(error) as by_factory:
        pl.foucault_pendulum(latitude=latitude)
    with pytest.raises(error) as by_replace:
        paris.replace(lat=latitude)
    assert str(by_replace.value) == str(by_factory.value)


def test_replace_family_and_copied_code_keep_the_latitude_in_degrees(paris):
    equator = pl.foucault_pendulum(latitude=45)
    moved = paris.replace(lat=45)
    assert list(moved.parameter_values.values()) == list(equator.parameter_values.values())
    assert paris.family(lat=[0.0, 45.0]).member(1).parameter_values == moved.parameter_values
    with pytest.raises(ValueError, match="`latitude` must be a number of degrees in "):
        paris.family(lat=[45.0, 100.0])
    from pendulum_lab.widgets.calls import model_code

    copied = eval(model_code(moved), {"pl": pl})  # the code an instrument copies
    assert copied.parameter_values == pytest.approx(moved.parameter_values)
    # negative control: a number of radians is read as degrees (pi/4 is not 45 degrees)
    radians = paris.replace(lat=np.pi / 4)
    assert radians.parameter_values != equator.parameter_values
    assert list(radians.parameter_values.values())[-1] == pytest.approx(np.radians(np.pi / 4))
