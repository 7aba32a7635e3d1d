"""Figures (Agg, no pyplot) and the analysis they draw: periods, spectra, linearisation."""

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

import pendulum_lab as pl  # noqa: E402
from pendulum_lab import analysis, plotting  # noqa: E402

SP = pl.simple_pendulum(mass=1.0, length=1.0, g=9.81)
DP = pl.double_pendulum()


@pytest.fixture(scope="module")
def dp_traj():
    return pl.simulate(DP, [1.0, 1.5], [0.0, 0.0], t_end=2.0, dt=0.01)


@pytest.fixture(scope="module")
def rotating():
    return pl.simulate(SP, [0.0], [8.0], t_end=3.0, dt=0.01)  # above the separatrix speed 6.26


# --------------------------------------------------------------------------- plots
def test_energy_plot_draws_the_trajectory_energies(dp_traj):
    fig = plotting.plot_energy(dp_traj)
    assert isinstance(fig, Figure)
    kinetic, potential, total = fig.axes[0].lines
    np.testing.assert_array_equal(kinetic.get_ydata(), dp_traj.kinetic)
    np.testing.assert_array_equal(potential.get_ydata(), dp_traj.potential)
    np.testing.assert_array_equal(total.get_ydata(), dp_traj.energy)
    np.testing.assert_array_equal(total.get_xdata(), dp_traj.t)


def test_plots_draw_into_a_given_axes(dp_traj):
    fig, axes = plotting.new_figure(1, 3)
    assert plotting.plot_angles(dp_traj, ax=axes[0]) is fig
    assert plotting.plot_energy_error(dp_traj, ax=axes[1]) is fig
    assert plotting.plot_phase(dp_traj, ax=axes[2]) is fig
    assert len(axes[0].lines) == 2 and axes[1].get_yscale() == "log"
    with pytest.raises(TypeError, match="ax"):
        plotting.plot_angles(dp_traj, ax="left")


def test_energy_error_is_relative_by_default(dp_traj):
    fig = plotting.plot_energy_error(dp_traj)
    shown = np.array(fig.axes[0].lines[0].get_ydata(), dtype=float)
    expected = np.abs(dp_traj.relative_energy_error)
    np.testing.assert_allclose(shown[1:], np.where(expected[1:] > 0, expected[1:], np.nan))
    absolute = plotting.plot_energy_error(dp_traj, relative=False).axes[0].lines[0].get_ydata()
    assert not np.allclose(np.asarray(absolute, float)[1:], shown[1:])  # E(0) != +-1 here


def test_wrap_angle():
    np.testing.assert_allclose(
        plotting.wrap_angle([0.0, np.pi, -np.pi, 3 * np.pi, 4.0]),
        [0.0, np.pi, np.pi, np.pi, 4.0 - 2 * np.pi],
    )


def test_phase_plot_wraps_and_breaks_rotations(rotating):
    x = np.asarray(plotting.plot_phase(rotating).axes[0].lines[0].get_xdata(), dtype=float)
    finite = x[np.isfinite(x)]
    assert np.all(np.abs(finite) <= np.pi)
    assert np.isnan(x).sum() >= 2  # about three turns, one break per turn
    assert np.all(np.abs(np.diff(x)[np.isfinite(np.diff(x))]) < 1.0)
    # Negative control: a libration is never broken.
    swing = pl.simulate(SP, [1.0], [0.0], t_end=3.0, dt=0.01)
    x = np.asarray(plotting.plot_phase(swing).axes[0].lines[0].get_xdata(), dtype=float)
    assert not np.isnan(x).any()


def test_arm_projections_one_panel_per_arm(dp_traj):
    fig = plotting.plot_link_projections(dp_traj)
    assert len(fig.axes) == 2
    for i, ax in enumerate(fig.axes):
        np.testing.assert_allclose(ax.lines[0].get_ydata(), dp_traj.omega[:, i])
    with pytest.raises(ValueError, match="axes"):
        plotting.plot_link_projections(dp_traj, axes=[fig.axes[0]])


def test_phase_portrait_separatrix_is_the_saddle_level():
    fig = plotting.plot_phase_portrait(SP)
    ax = fig.axes[0]
    red = [
        c
        for c in ax.collections
        if np.allclose(c.get_edgecolor()[0][:3], matplotlib.colors.to_rgb("tab:red"))
    ]
    assert len(red) == 1
    separatrix = red[0]
    assert list(separatrix.levels) == pytest.approx([SP.masses[0] * SP.g * SP.lengths[0]])
    points = np.concatenate([p.vertices for p in separatrix.get_paths()])
    energy = SP.energy(points[:, :1], points[:, 1:])
    assert np.max(np.abs(energy - SP.g)) < 0.05  # on the grid's contour to its resolution
    # Negative control: the librations lie strictly below it.
    blue = [c for c in ax.collections if c is not separatrix and max(c.levels) < SP.g]
    assert blue


def test_phase_portrait_overlays_a_trajectory_and_rejects_chains(rotating):
    fig = plotting.plot_phase_portrait(SP, trajectory=rotating)
    traj_line = [ln for ln in fig.axes[0].lines if ln.get_label() == "trajectory"][0]
    y = np.asarray(traj_line.get_ydata(), dtype=float)
    np.testing.assert_allclose(y[np.isfinite(y)], rotating.omega[:, 0])
    with pytest.raises(ValueError, match="simple pendulum"):
        plotting.plot_phase_portrait(DP)


def test_draw_pendulum_puts_bobs_at_the_model_positions():
    theta = np.array([0.3, -1.2])
    fig = plotting.draw_pendulum(DP, theta)
    rods = fig.axes[0].lines[0]
    x, y = DP.positions(theta)
    np.testing.assert_allclose(rods.get_xdata(), [0.0, *x])
    np.testing.assert_allclose(rods.get_ydata(), [0.0, *y])
    with pytest.raises(ValueError, match="theta"):
        plotting.draw_pendulum(DP, [0.3])


def test_linear_vs_nonlinear_panels(dp_traj):
    small = pl.simulate(DP, [np.pi + 1e-3, np.pi], [0.0, 0.0], t_end=5.0, dt=0.01)
    fig = plotting.plot_linear_vs_nonlinear(DP, "up-up", small)
    linear_ax, nonlinear_ax = fig.axes
    lin = np.asarray(linear_ax.lines[0].get_ydata(), dtype=float)
    # The saddle's linear solution grows like exp(5.79 t): cut once it passes pi.
    assert np.isnan(lin[-1]) and np.isfinite(lin[0])
    assert np.nanmax(np.abs(lin)) <= np.pi
    np.testing.assert_allclose(nonlinear_ax.lines[0].get_ydata(), small.theta[:, 0] - np.pi)


def test_period_and_spectrum_plots():
    fig = plotting.plot_period_vs_amplitude(SP, [0.5, 1.0], [2.04, 2.14])
    assert [ln.get_label() for ln in fig.axes[0].lines][-1] == "measured (simulation)"
    traj = pl.simulate(DP, [0.02, 0.0], [0.0, 0.0], t_end=20.0, dt=0.02)
    fig = plotting.plot_spectrum(traj, marks=analysis.normal_mode_frequencies(DP))
    assert len(fig.axes[0].lines) == 3


def test_panels_registry(dp_traj):
    fig, axes = plotting.new_figure(1, len(plotting.PANELS))
    sp_traj = pl.simulate(SP, [1.0], [0.0], t_end=1.0, dt=0.01)
    for ax, (name, panel) in zip(axes, plotting.PANELS.items()):
        panel(ax, sp_traj, SP)
        assert ax.has_data(), name


def test_ensembles_are_refused():
    ens = pl.simulate(SP, [[0.1], [0.2]], [[0.0], [0.0]], t_end=0.1, dt=0.01)
    with pytest.raises(ValueError, match="single trajectory"):
        plotting.plot_energy(ens)


# --------------------------------------------------------------------------- analysis used above
def test_exact_period_limits():
    small = 2 * np.pi * np.sqrt(SP.lengths[0] / SP.g)
    assert analysis.exact_period(SP, 1e-9) == pytest.approx(small, rel=1e-14)
    assert analysis.exact_period(SP, 3.14) > 5 * small  # diverges at the top
    long = pl.simple_pendulum(length=4.0)
    assert analysis.exact_period(long, 1.0) == pytest.approx(2 * analysis.exact_period(SP, 1.0))
    with pytest.raises(ValueError, match="amplitude"):
        analysis.exact_period(SP, np.pi)
    with pytest.raises(ValueError, match="simple pendulum"):
        analysis.exact_period(DP, 1.0)


def test_measured_periods_match_the_elliptic_integral():
    amplitudes = np.array([0.3, 1.5, 2.8])
    traj = pl.simulate(SP, amplitudes[:, None].copy(), np.zeros((3, 1)), t_end=25.0, dt=0.01)
    measured = analysis.oscillation_period(traj)
    assert measured.shape == (3,)
    np.testing.assert_allclose(measured, analysis.exact_period(SP, amplitudes), rtol=1e-6)
    # Negative control: the small-angle period is wrong by far more at these amplitudes.
    small = 2 * np.pi * np.sqrt(SP.lengths[0] / SP.g)
    assert np.all(np.abs(measured[1:] / small - 1) > 0.1)


def test_period_of_a_rotation_is_refused(rotating):
    with pytest.raises(ValueError, match="crossing"):
        analysis.oscillation_period(rotating)


def test_fft_frequencies_match_the_normal_modes():
    modes = analysis.normal_mode_frequencies(DP)
    np.testing.assert_allclose(
        modes**2, 9.81 * np.array([2 - np.sqrt(2), 2 + np.sqrt(2)]), rtol=1e-12
    )
    small = pl.simulate(DP, [0.01, 0.0], [0.0, 0.0], t_end=100.0, dt=0.02)
    np.testing.assert_allclose(analysis.dominant_frequencies(small), modes, rtol=2e-4)
    # Negative control: at a large amplitude the frequencies have moved away.
    large = pl.simulate(DP, [0.8, 0.0], [0.0, 0.0], t_end=100.0, dt=0.02)
    assert np.max(np.abs(analysis.dominant_frequencies(large) / modes - 1)) > 5e-3


def test_linearized_solution_matches_small_motion_and_fails_for_large():
    t = np.arange(0, 201) * 0.01
    for eq, start in (("down-down", [1e-3, -1e-3]), ("down-up", [1e-5, np.pi])):
        angles = np.array([0.0, 0.0 if eq == "down-down" else np.pi])
        traj = pl.simulate(DP, np.array(start), np.zeros(2), t_end=2.0, dt=0.01)
        theta, omega = analysis.linearized_solution(DP, traj.theta[0], traj.omega[0], t=t,
                                                    equilibrium=eq)
        size = np.max(np.abs(traj.theta - angles))  # how far the motion goes
        assert np.max(np.abs(theta - traj.theta)) < 1e-3 * size
        assert omega.shape == (201, 2)
    big = pl.simulate(DP, np.array([0.8, 0.0]), np.zeros(2), t_end=2.0, dt=0.01)
    theta, _ = analysis.linearized_solution(DP, big.theta[0], big.omega[0], t=t,
                                          equilibrium="down-down")
    assert np.max(np.abs(theta - big.theta)) > 0.05
    with pytest.raises(ValueError, match="equilibrium"):
        analysis.linearized_solution(DP, [0, 0], [0, 0], t=t, equilibrium="down")


def test_rest_state_at_energy():
    for energy in (-25.0, 0.0, 29.0):
        theta = analysis.rest_state_at_energy(DP, energy)
        assert theta[0] == theta[1]
        assert float(DP.potential_energy(theta)) == pytest.approx(energy, abs=1e-10)
    with pytest.raises(ValueError, match="energy"):
        analysis.rest_state_at_energy(DP, 30.0)


def test_lyapunov_energy_and_landing_error_figures():
    import dataclasses

    from pendulum_lab import chaos

    scan = chaos.lyapunov_by_energy(DP, [-20.0, 16.0], orbits=2, t_end=20.0, method="rk4",
                                    threshold=0.3)
    ax = plotting.plot_lyapunov_energy(scan).axes[0]
    from matplotlib.collections import PathCollection

    dots = [c for c in ax.collections if isinstance(c, PathCollection)]
    assert sum(len(c.get_offsets()) for c in dots) == 4  # every orbit drawn once
    means = ax.lines[0].get_ydata()
    assert np.isnan(means[0]) and means[1] == pytest.approx(scan.exponent[2:].mean())
    # Negative control: with every orbit regular there is no mean to draw.
    regular = plotting.plot_lyapunov_energy(dataclasses.replace(scan, threshold=10.0)).axes[0]
    assert np.all(np.isnan(regular.lines[0].get_ydata()))
    theta, omega = chaos.section_spread(DP, -5.0, orbits=4)
    errors = chaos.landing_errors(DP, theta, omega, dt=0.01, method="rk4", landing="henon")
    line = errors.plot().axes[0].lines[0]
    assert np.array_equal(np.sort(line.get_xdata()), np.sort(errors.speed))
    assert set(line.get_ydata()) == set(errors.state_error)


# --------------------------------------------------------------------------- geometric figures
def test_geometric_figures_draw_their_results_into_given_axes():
    from pendulum_lab.geometric import standard_map

    fig, axes = plotting.new_figure(1, 3)
    crossings = standard_map.crossing_times([0.6, 1.0], orbits=16, max_iterations=10**5)
    assert plotting.plot_crossing_times(crossings, ax=axes[0]) is fig
    medians, halves = axes[0].lines[0], axes[0].lines[1:3]
    np.testing.assert_array_equal(medians.get_xdata(), crossings.excess)
    np.testing.assert_array_equal(medians.get_ydata(), crossings.median)
    np.testing.assert_array_equal(halves[1].get_ydata(), crossings.half_medians[:, 1])
    slope_line = axes[0].lines[-1]
    fitted = np.polyfit(np.log(slope_line.get_xdata()), np.log(slope_line.get_ydata()), 1)[0]
    assert fitted == pytest.approx(-standard_map.FLUX_EXPONENT)
    scipy = analysis.scipy_run(SP, [1.0], [0.0], t_end=5.0, rtol=1e-6)
    fixed = pl.simulate(SP, [1.0], [0.0], t_end=5.0, dt=0.05, method="leapfrog")
    assert plotting.plot_adaptive_energy([scipy, fixed], ax=axes[1]) is fig
    labels = [t.get_text() for t in axes[1].get_legend().get_texts()]
    assert labels == ["DOP853, rtol 1e-06", "leapfrog, dt = 0.05"]
    np.testing.assert_array_equal(axes[1].lines[0].get_ydata(), scipy.energy_error)
    assert plotting.plot_level_sets(SP.hamiltonian_value, (-3, 3), (-8, 8), ax=axes[2]) is fig
    assert axes[2].get_xlabel() == "θ (rad)" and axes[2].get_ylabel() == "p (kg m²/s)"
    with pytest.raises(TypeError, match="`ax`"):
        plotting.plot_crossing_times(crossings, ax="left")


def test_transport_threshold_figure_draws_its_thresholds():
    from pendulum_lab.geometric import standard_map

    threshold = standard_map.transport_threshold((10, 100), ks=np.linspace(1.5, 2.5, 5), orbits=4)
    ax = plotting.plot_transport_threshold(threshold).axes[0]
    np.testing.assert_array_equal(ax.lines[0].get_xdata(), threshold.iterations)
    np.testing.assert_array_equal(ax.lines[0].get_ydata(), threshold.thresholds)
    with pytest.raises(TypeError, match="`ax`"):
        plotting.plot_transport_threshold(threshold, ax="left")


def test_carried_loops_share_limits_and_show_the_area_ratio():
    from pendulum_lab.geometric import phase_space

    runs = [phase_space.carried_loop_areas(SP, name, [1.0, 0.0], [[0.3, 0.0], [0.0, 0.6]],
                                           t_end=2.0, dt=0.1, save_every=10, tol=1e-8)
            for name in ("explicit_euler", "leapfrog")]
    fig = plotting.plot_carried_loops(SP, runs, frames=[0, 2], ncols=2)
    euler, leapfrog = fig.axes[:2]
    assert euler.get_xlim() == leapfrog.get_xlim() and euler.get_ylim() == leapfrog.get_ylim()
    assert euler.get_aspect() == 1.0
    assert f"area ratio {runs[0].ratio[2]:.6f}" in euler.get_title()
    assert "area ratio 1.000000" in leapfrog.get_title()
    # negative control: fitted to their own loops, the swollen Euler blob needs other limits
    own = plotting.plot_carried_loops(SP, runs, frames=[0, 2], ncols=2, shared=False)
    assert own.axes[0].get_xlim() != own.axes[1].get_xlim()
    rows = plotting.plot_carried_loops(SP, runs, frames=[0, 2], ncols=1, shared="row")
    assert rows.axes[0].get_xlim() != rows.axes[1].get_xlim()  # one panel per row
    with pytest.raises(ValueError, match="`shared`"):
        plotting.plot_carried_loops(SP, runs, frames=[0, 2], shared="column")


def test_projected_areas_split_by_unit_with_legends_outside():
    from pendulum_lab.geometric import phase_space

    surface = phase_space.carried_loop_areas(
        DP, "leapfrog", [0.5, 0.8, 0.0, 0.0], 0.1 * np.array([[1.0, 0.5, 0.0, 0.3],
                                                            [0.2, 0.0, 1.0, 0.8]]),
        t_end=1.0, dt=0.05, save_every=5, tol=1e-8)
    fig = plotting.plot_projected_areas(surface)
    upper, lower = fig.axes
    assert "J s" in upper.get_ylabel() and "rad²/s" in lower.get_ylabel()
    np.testing.assert_allclose(upper.lines[-1].get_ydata(), surface.invariant)
    np.testing.assert_allclose(lower.lines[0].get_ydata(), surface.velocity.sum(axis=1))
    for ax in (upper, lower):  # anchored right of the panel, clear of every curve
        assert ax.get_legend().get_bbox_to_anchor().x0 > ax.get_window_extent().x1 - 1
    assert not plotting.plot_projected_areas(surface, legend=False).axes[0].get_legend()


def test_root_branch_figure_marks_the_fold_and_both_roots():
    from pendulum_lab.geometric import continuation

    uneven = pl.double_pendulum(m1=1.0, m2=1.5, l1=1.0, l2=0.7, g=9.81)
    theta0 = np.array([0.3, -1.0])
    branch = continuation.variational_root_branch(
        uneven, "trapezoid", theta0, uneven.momenta(theta0, np.array([4.0, -6.0])), h_stop=0.25)
    ax = plotting.plot_root_branch(branch, steps=[0.3]).axes[0]
    first, second, fold, *marks = ax.lines
    np.testing.assert_array_equal(first.get_xdata(), branch.h)
    np.testing.assert_array_equal(second.get_ydata(), branch.q_next[:, 1])
    assert fold.get_xdata()[0] == branch.fold_h
    assert [len(mark.get_ydata()) for mark in marks] == [2, 2]  # before and beyond the fold
    unfolded = continuation.variational_root_branch(pl.simple_pendulum(), "trapezoid", [0.5],
                                                    [1.0], h_max=0.2)
    assert len(plotting.plot_root_branch(unfolded).axes[0].lines) == 1  # no fold to mark


def test_geometric_panels_use_the_grid_helper():
    from pendulum_lab.geometric import standard_map

    portraits = {k: standard_map.iterate([np.pi], [0.5], k, 50) for k in (0.5, 1.2)}
    fig = plotting.plot_standard_map(portraits, ncols=2)
    assert len(fig.axes) == 2
    assert [ax.get_title() for ax in fig.axes] == ["K = 0.5", "K = 1.2 (> K_c)"]
    _, axes = plotting.new_figure(1, 2)
    assert plotting.plot_standard_map(portraits, axes=axes) is axes[0].figure
    with pytest.raises(ValueError, match="at least 2 matplotlib Axes"):
        plotting.plot_standard_map(portraits, axes=axes[:1])


def test_axis_labels_come_from_one_table():
    assert plotting.axis_label("theta", plotting.link_label(1, 2)) == "θ₂ (rad)"
    assert plotting.axis_label("p") == "p (kg m²/s)"
    assert set(plotting.QUANTITIES) >= {"t", "theta", "omega", "p"}
    with pytest.raises(ValueError, match="`quantity` must be one of"):
        plotting.axis_label("speed")
