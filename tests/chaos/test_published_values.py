"""The library against published values of its classic problems.

Each test names its source, the published value, and why its tolerance is what it is; each
has a negative control showing the same check fails where it should. The whole module runs in
a few seconds.
"""

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab import chaos
from pendulum_lab.geometric.standard_map import residue_crossing

DRIVEN = pl.driven_pendulum()  # q = 2, Omega = 2/3: Baker and Gollub's pendulum
T = DRIVEN.drive_period

#: Greene (1979), refined by MacKay (1983): the last invariant circle of the standard map.
GREENE_K_C = 0.971635
#: Feigenbaum (1978): the ratio of successive gaps between period doublings.
FEIGENBAUM_DELTA = 4.669201609


def golden_approximants(count):
    """``(F_(j-1), F_j)`` for the last ``count`` Fibonacci pairs up to q = 610."""
    pairs = [(1, 2)]
    while pairs[-1][1] < 610:
        p, q = pairs[-1]
        pairs.append((q, p + q))
    return pairs[-count:]


def test_greene_critical_k_from_the_residues_of_the_golden_approximants():
    """J. M. Greene, J. Math. Phys. 20 (1979) 1183; R. S. MacKay, Physica D 7 (1983) 283.

    Published: K_c = 0.971635 (MacKay: 0.971635406). The ``K`` where the residue of the orbit
    of rotation number F_(j-1)/F_j reaches 1/4 tends to K_c from alternate sides, the steps
    shrinking geometrically; the tolerance is the last step (q = 377 to 610), which the
    distance of the last value from the limit cannot exceed once the steps shrink.
    """
    estimates = [residue_crossing(p, q) for p, q in golden_approximants(4)]  # q = 144 .. 610
    steps = np.diff(estimates)
    assert np.all(np.abs(steps[1:]) < np.abs(steps[:-1]))  # converging
    tolerance = abs(steps[-1])
    assert tolerance < 1e-5
    assert abs(estimates[-1] - GREENE_K_C) < tolerance
    # negative control: the silver mean's approximants (sqrt 2 - 1) converge elsewhere
    silver = [residue_crossing(p, q, bracket=(0.5, 1.1)) for p, q in [(29, 70), (70, 169)]]
    assert abs(silver[-1] - GREENE_K_C) > 100 * tolerance


def test_the_double_pendulums_spectrum_pairs_like_a_hamiltonian_systems():
    """Benettin, Galgani, Giorgilli, Strelcyn, Meccanica 15 (1980) 21: for a Hamiltonian flow
    the exponents pair, lambda_i + lambda_(2n+1-i) = 0, and two vanish (along the flow and
    across the energy surface).

    Published: 0 (a theorem). Finite-time estimates of both converge like 1/t; the tolerances
    are c / t with c = 5 s for the pairs and 10 s for the near-zero exponents, from the run
    of 200 s (measured: 0.010 and 0.03 to 0.04 1/s against lambda_1 = 1.49 1/s).
    """
    t_end = 200.0
    spectrum = chaos.lyapunov_spectrum(pl.double_pendulum(), [2.0, 2.5], [0.0, 0.0],
                                       t_end=t_end, dt=0.01, method="glrk4", save_every=10)
    lam = spectrum.exponents
    assert lam[0] > 1.0  # chaotic
    assert abs(lam[0] + lam[3]) < 5.0 / t_end and abs(lam[1] + lam[2]) < 5.0 / t_end
    assert abs(lam[1]) < 10.0 / t_end and abs(lam[2]) < 10.0 / t_end
    # negative control: joint damping breaks the pairing
    damped = chaos.lyapunov_spectrum(pl.double_pendulum(damping=0.1), [2.0, 2.5], [0.0, 0.0],
                                     t_end=100.0, dt=0.01, method="glrk4", save_every=10)
    assert abs(damped.exponents[0] + damped.exponents[3]) > 5.0 / 100.0


def test_the_stroboscopic_maps_exponents_are_the_drive_period_times_the_flows():
    """Baker and Gollub, Chaotic Dynamics, 2nd ed. (1996), ch. 5: sampled once per drive
    period, the motion is a map whose exponents are T times the flow's.

    Here the map's exponents come from shooting (the Floquet multipliers mu of the period-1
    orbit at A = 1.06, log |mu| per drive period) and the flow's from QR re-orthonormalisation
    along the orbit (1/s): independent algorithms. The flow's estimate converges like 1/t;
    the tolerance is twice its own convergence measure (the change over the second half).
    """
    model = DRIVEN.replace(drive_amplitude=1.06)
    orbit = chaos.periodic_orbit(model, [-0.25], [1.97])
    spectrum = chaos.lyapunov_spectrum(model, orbit.theta[0], p0=orbit.p[0], t_end=200 * T,
                                       dt=T / 200, save_every=200, method="rk4")
    per_period = np.log(np.abs(orbit.multipliers))
    tolerance = 2 * spectrum.half_run_difference * T
    assert np.all(np.abs(spectrum.exponents * T - per_period) < tolerance)
    assert np.all(tolerance < 0.01)
    # negative control: the flow's exponents are not themselves the map's
    assert np.all(np.abs(spectrum.exponents - per_period) > 10 * tolerance)


@pytest.mark.parametrize("amplitude, period", [(0.90, 1), (1.07, 2), (1.15, 0), (1.35, 1),
                                               (1.45, 2), (1.47, 4), (1.50, 0)])
def test_the_period_doubling_route_of_baker_and_gollub(amplitude, period):
    """Baker and Gollub, Chaotic Dynamics, 2nd ed. (1996), ch. 3: at q = 2, Omega = 2/3 the
    pendulum released at rest has period 1 at g = 0.9, 2 at 1.07, is chaotic at 1.15, has
    period 1 at 1.35 (a rotation), 2 at 1.45, 4 at 1.47, and is chaotic at 1.50.

    Each period is checked twice: from the stroboscopic samples after a transient, and by
    shooting, which must close a stable orbit of exactly that period (the orbit of half the
    period is then not closed). Chaos: lambda_1 > 0 with its convergence measure below
    lambda_1 / 2.
    """
    model = DRIVEN.replace(drive_amplitude=amplitude)
    section = chaos.stroboscopic_section(model, [0.0], [0.0], n_periods=64,
                                         transient_periods=500, steps_per_period=200)
    assert int(section.periods()) == period
    if period:
        orbit = chaos.periodic_orbit(model, section.theta[-1], p0=section.p[-1],
                                     t0=section.t[-1] % T, periods=period)
        assert orbit.stable
        if period > 1:
            assert orbit.closing_gap(period // 2) > 0.1
    else:
        spectrum = chaos.lyapunov_spectrum(model, section.theta[-1], p0=section.p[-1],
                                           t0=section.t[-1], t_end=200 * T, dt=T / 200,
                                           save_every=200, method="rk4")
        assert spectrum.largest > 0.05
        assert spectrum.half_run_difference[0] < spectrum.largest / 2


def test_feigenbaums_delta_from_the_first_doublings_located_precisely():
    """M. J. Feigenbaum, J. Stat. Phys. 19 (1978) 25: delta = 4.669201609...

    The period map contracts areas by exp(-gamma T) = 0.009 per period, so near the cascade
    it acts as a one-dimensional map and the gaps between doublings shrink by delta. Our first
    two ratios carry stated errors below 1e-4 (the doublings located with 400 and 800 steps
    per period); what separates them from delta is the cascade's own convergence, which for
    the first ratios of a one-dimensional map is of order 1 % (the logistic map's are 4.75
    and 4.66). Tolerance: 0.01, about 0.2 %.
    """
    cascade = chaos.period_doubling_cascade(DRIVEN, "drive_amplitude", (1.06, 1.09), [0.0],
                                            [0.0], doublings=4)
    assert cascade.periods.tolist() == [1, 2, 4, 8]
    assert np.all(cascade.ratio_errors < 1e-4)
    assert np.all(np.abs(cascade.gap_ratios - FEIGENBAUM_DELTA) < 0.01)
    # negative control: the doublings as a grid of short runs sees them (critical slowing
    # down moves each one early by a different amount) give a ratio far from delta
    grid = chaos.bifurcation_diagram(DRIVEN, "drive_amplitude", np.linspace(1.06, 1.09, 61),
                                     theta0=[[0.0], [-1.0]], omega0=[[0.0]] * 2, n_periods=64,
                                     transient_periods=300, steps_per_period=60)
    onsets = np.array([d.value for d in grid.doublings()])
    gaps = np.diff(onsets)
    assert np.any(np.abs(gaps[:-1] / gaps[1:] - FEIGENBAUM_DELTA) > 0.01)
