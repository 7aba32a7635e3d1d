"""Figures of trajectories and models: energies, angles, phase space, the chain itself.

Angles in phase plots are wrapped into ``(-pi, pi]`` and lines are broken
where a rotating link jumps from ``pi`` to ``-pi``.

:data:`PANELS` names the single-axes drawings the explorers in
:mod:`pendulum_lab.widgets` can show; each is a callable
``(ax, trajectory, model) -> None``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from .. import validation as check
from ..analysis import (
    equilibrium_angles,
    exact_period,
    find_equilibrium,
    linearized_solution,
    normal_modes,
)
from ..analysis import spectrum as power_spectrum
from ..driver.simulate import Trajectory
from ..model.pendulum import PendulumModel

if TYPE_CHECKING:  # geometric imports plotting's neighbours; only the type is needed here
    from ..geometric import ModifiedEnergy
from .drawing import VIEWS, drawing_frame, joined_paths, view_reach
from .figures import (
    KINETIC,
    LIBRATION,
    POTENTIAL,
    ROTATION,
    SEPARATRIX,
    TOTAL,
    axis_label,
    broken_at_wraps,
    get_axes,
    link_label,
    new_figure,
    plot_by_time,
    single_trajectory,
    superscript,
    wrap_angle,
)

__all__ = [
    "PANELS",
    "draw_pendulum",
    "plot_angles",
    "plot_energy",
    "plot_energy_error",
    "plot_linear_vs_nonlinear",
    "plot_link_projections",
    "plot_modified_level_sets",
    "plot_normal_modes",
    "plot_period_vs_amplitude",
    "plot_phase",
    "plot_phase_portrait",
    "plot_spectrum",
]


# --------------------------------------------------------------------------- time series
def plot_energy(traj: Trajectory, ax: Axes | None = None) -> Figure:
    """Kinetic, potential and total energy [J] against time.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> traj = pl.simulate(pl.simple_pendulum(), [1.0], [0.0], t_end=1.0, dt=0.01)
    >>> fig = plot_energy(traj)
    >>> [line.get_label() for line in fig.axes[0].lines]
    ['kinetic T', 'potential V', 'total E = T + V']
    """
    traj = single_trajectory(traj)
    ax = get_axes(ax)
    ax.plot(traj.t, traj.kinetic, color=KINETIC, label="kinetic T")
    ax.plot(traj.t, traj.potential, color=POTENTIAL, label="potential V")
    ax.plot(traj.t, traj.energy, color=TOTAL, lw=2, label="total E = T + V")
    ax.set(
        xlabel=axis_label("t"),
        ylabel="energy (J)",
        title=f"Energy ({traj.method.name}, dt = {traj.dt:g} s)",
    )
    ax.legend(loc="upper right", fontsize="small")
    return ax.figure


def plot_energy_error(traj: Trajectory, ax: Axes | None = None, relative: bool = True) -> Figure:
    """``|E(t) - E(0)|`` (relative to ``|E(0)|`` by default) on a log scale.

    Exact zeros (the first sample) are not drawn: a log axis cannot show them.
    """
    traj = single_trajectory(traj)
    ax = get_axes(ax)
    error = np.abs(traj.relative_energy_error if relative else traj.energy_error)
    shown = np.where(error > 0, error, np.nan)
    ax.plot(traj.t, shown, color=TOTAL, lw=1)
    if np.any(np.isfinite(shown)):
        ax.set_yscale("log")
    ylabel = "|E − E(0)| / |E(0)|" if relative else "|E − E(0)| (J)"
    ax.set(xlabel=axis_label("t"), ylabel=ylabel, title=f"Energy error ({traj.method.name})")
    return ax.figure


def plot_angles(traj: Trajectory, ax: Axes | None = None, names=None) -> Figure:
    """Each angle ``theta_i(t)`` [rad] (not wrapped: a full turn adds 2 pi); with ``names``
    (a system's coordinates, :attr:`~pendulum_lab.SystemModel.coordinate_names`), each
    coordinate under its name."""
    traj = single_trajectory(traj)
    ax = get_axes(ax)
    n = traj.theta.shape[1]
    for i in range(n):
        ax.plot(traj.t, traj.theta[:, i],
                label=f"θ{link_label(i, n)}" if names is None else names[i])
    if names is None:
        ax.set(xlabel=axis_label("t"), ylabel="angle (rad)", title="Angles")
    else:
        ax.set(xlabel=axis_label("t"), ylabel="coordinate", title="Coordinates")
        ax.legend(loc="upper right", fontsize="small")
    if n > 1:
        ax.legend(loc="upper right", fontsize="small")
    return ax.figure


# --------------------------------------------------------------------------- phase space
def plot_phase(traj: Trajectory, ax: Axes | None = None, link: int | None = None) -> Figure:
    """Phase-space projections ``(theta_i, omega_i)``, angles wrapped into ``(-pi, pi]``.

    Parameters
    ----------
    traj : Trajectory
    ax : Axes, optional
    link : int, optional
        Draw only this link (0-based); by default all links, overlaid.
    """
    traj = single_trajectory(traj)
    ax = get_axes(ax)
    n = traj.theta.shape[1]
    links = range(n) if link is None else [check.index_below("link", link, n)]
    for i in links:
        x, y = broken_at_wraps(traj.theta[:, i], traj.omega[:, i])
        (line,) = ax.plot(x, y, lw=0.8, label=f"arm {i + 1}")
        ax.plot(x[0], y[0], "o", color=line.get_color(), ms=5)
    single_link = len(links) == 1 and n > 1
    sub = link_label(links[0], n) if len(links) == 1 else "ᵢ"
    ax.set(
        xlabel=axis_label("theta", sub),
        ylabel=axis_label("omega", sub),
        title=f"Arm {links[0] + 1}" if single_link else "Phase space",
        xlim=(-np.pi, np.pi),
    )
    if len(links) > 1:
        ax.legend(loc="upper right", fontsize="small")
    return ax.figure


def plot_link_projections(traj: Trajectory, axes=None) -> Figure:
    """One panel per link: the projection ``(theta_i, omega_i)`` of the trajectory.

    For the double pendulum the motion lives in a 4-dimensional phase space;
    each panel is a shadow of it, so curves may cross themselves.

    Parameters
    ----------
    traj : Trajectory
    axes : sequence of Axes, optional
        ``n`` axes; by default a new row of ``n`` panels.
    """
    traj = single_trajectory(traj)
    n = traj.theta.shape[1]
    if axes is None:
        axes = np.atleast_1d(new_figure(1, n, width=4.0 * n, height=3.6)[1])
    if len(axes) != n:
        raise ValueError(f"`axes` must hold {n} Axes (one per link), got {len(axes)}")
    for i, ax in enumerate(axes):
        plot_phase(traj, ax=ax, link=i)
    return axes[0].figure


def plot_phase_portrait(
    model: PendulumModel,
    ax: Axes | None = None,
    *,
    trajectory: Trajectory | None = None,
    omega_max: float | None = None,
    libration_levels: int = 5,
    rotation_levels: int = 3,
) -> Figure:
    """Phase portrait of the simple pendulum: level sets of ``H(theta, omega)``.

    Librations (closed curves around the bottom, ``E < m g l``) are blue,
    rotations (``E > m g l``) green, and the separatrix ``E = m g l`` through
    the upright saddle red. The center at ``(0, 0)`` and the saddles at
    ``(+-pi, 0)`` are marked. A ``trajectory`` is drawn on top, its angles
    wrapped into ``(-pi, pi]``, coloured by time from dark (its start, marked)
    to light (:func:`~pendulum_lab.plotting.figures.plot_by_time`), so that a
    long orbit winding many times stays readable; the window grows to hold all
    of it. The level sets are those of ``H``: for a model with damping or a
    drive its trajectory crosses them.

    Parameters
    ----------
    model : PendulumModel
        A simple pendulum.
    omega_max : float, optional
        Half-height of the window [rad/s]; default 1.6 times the separatrix's
        top speed ``2 sqrt(g / l)``. If the ``trajectory`` is faster
        somewhere, the window widens to 1.08 times its largest ``|omega|``.
    libration_levels, rotation_levels : int
        How many level sets of each kind to draw.
    """
    if not isinstance(model, PendulumModel) or model.n != 1:
        raise ValueError(
            "`model` must be a simple pendulum (n = 1) for a phase portrait; "
            "for more links use plot_link_projections"
        )
    ax = get_axes(ax)
    mass, length, g = model.masses[0], model.lengths[0], model.g
    top_speed = 2.0 * np.sqrt(abs(g) / length)
    omega_max = 1.6 * top_speed if omega_max is None else float(omega_max)
    traj = None if trajectory is None else single_trajectory(trajectory)
    if traj is not None:
        speeds = np.abs(traj.omega[:, 0])
        speeds = speeds[np.isfinite(speeds)]
        if speeds.size and speeds.max() > omega_max:
            omega_max = 1.08 * float(speeds.max())
    theta = np.linspace(-np.pi, np.pi, 401)
    omega = np.linspace(-omega_max, omega_max, 401)
    big_theta, big_omega = np.meshgrid(theta, omega)
    energy = model.energy(big_theta[..., None], big_omega[..., None])
    e_bottom, e_sep = -mass * g * length, mass * g * length
    e_top = float(energy.max())
    inner = np.linspace(e_bottom, e_sep, libration_levels + 2)[1:-1]
    outer = np.linspace(e_sep, e_top, rotation_levels + 2)[1:-1]
    style = {"linestyles": "solid", "linewidths": 0.9}
    ax.contour(big_theta, big_omega, energy, levels=inner, colors=LIBRATION, **style)
    if len(outer):
        ax.contour(big_theta, big_omega, energy, levels=outer, colors=ROTATION, **style)
    ax.contour(
        big_theta,
        big_omega,
        energy,
        levels=[e_sep],
        colors=SEPARATRIX,
        linestyles="solid",
        linewidths=2,
    )
    ax.plot([0], [0], "o", color="black", ms=6)
    ax.annotate("center", (0, 0), xytext=(4, -12), textcoords="offset points", fontsize="small")
    ax.plot([-np.pi, np.pi], [0, 0], "X", color=SEPARATRIX, ms=9, clip_on=False)
    ax.annotate(
        "saddle",
        (-np.pi, 0),
        xytext=(6, 6),
        textcoords="offset points",
        fontsize="small",
        color=SEPARATRIX,
    )
    ax.plot([], [], color=LIBRATION, label="libration")
    ax.plot([], [], color=ROTATION, label="rotation")
    ax.plot([], [], color=SEPARATRIX, lw=2, label="separatrix")
    if traj is not None:
        plot_by_time(ax, traj.t, traj.theta[:, 0], traj.omega[:, 0],
                     label="trajectory (dark → light: time)")
        ax.plot([wrap_angle(traj.theta[0, 0])], [traj.omega[0, 0]], "o", color="gold", mec="black",
                ms=9, zorder=5)
    ax.set(
        xlabel=axis_label("theta"),
        ylabel=axis_label("omega"),
        xlim=(-np.pi, np.pi),
        ylim=(-omega_max, omega_max),
        title="Phase portrait of the simple pendulum",
    )
    ax.legend(loc="upper right", fontsize="x-small", framealpha=0.9)
    return ax.figure


def plot_modified_level_sets(
    traj: Trajectory, modified: ModifiedEnergy, ax: Axes | None = None
) -> Figure:
    """A numerical orbit on the level set of the modified energy, beside that of ``H``.

    In the canonical plane ``(theta, p)`` of a simple pendulum: the level set
    of ``H`` through the orbit's start (dashed), the level set of the modified
    Hamiltonian ``H~`` at the trajectory's step through the same start
    (solid), and the computed states (dots). A symplectic method's states
    follow the solid curve, not the dashed one.

    Parameters
    ----------
    traj : Trajectory
        One run of the method ``modified`` belongs to, on ``modified.model``.
    modified : ModifiedEnergy
        From :func:`pendulum_lab.geometric.modified_energy`.
    ax : Axes, optional
    """
    traj = single_trajectory(traj)
    if traj.method.name != modified.method:
        raise ValueError(
            f"`traj` was computed with {traj.method.name!r}, but `modified` belongs to "
            f"{modified.method!r}"
        )
    model = modified.model
    ax = get_axes(ax, width=6.0, height=4.6)
    theta, p = traj.theta[:, 0], traj.p[:, 0]
    pad_theta, pad_p = 0.15 * np.ptp(theta) + 0.05, 0.15 * np.ptp(p) + 0.05
    grid_theta, grid_p = np.meshgrid(
        np.linspace(theta.min() - pad_theta, theta.max() + pad_theta, 401),
        np.linspace(p.min() - pad_p, p.max() + pad_p, 401),
    )
    exact = model.hamiltonian_value(grid_theta[..., None], grid_p[..., None])
    tilde = modified(grid_theta[..., None], grid_p[..., None], traj.dt)
    start_exact = float(model.hamiltonian_value(traj.theta[0], traj.p[0]))
    start_tilde = float(modified(traj.theta[0], traj.p[0], traj.dt))
    ax.contour(grid_theta, grid_p, exact, levels=[start_exact], colors="0.45",
               linestyles="dashed", linewidths=1.4)
    ax.contour(grid_theta, grid_p, tilde, levels=[start_tilde], colors="tab:blue",
               linewidths=1.6)
    ax.plot(theta, p, ".", color="tab:red", ms=4, zorder=3)
    ax.plot([], [], "--", color="0.45", label="level set of H")
    ax.plot([], [], color="tab:blue",
            label=f"level set of the modified H (terms to h{superscript(modified.order)})")
    ax.plot([], [], ".", color="tab:red", label=f"{traj.method.name}, h = {traj.dt:g} s")
    ax.set(xlabel="θ (rad)", ylabel="p (kg m²/s)",
           title="The numerical orbit lies on a level set of the modified energy")
    ax.legend(loc="upper right", fontsize="x-small", framealpha=0.9)
    return ax.figure


def plot_normal_modes(model: PendulumModel, amplitude: float = 0.35, axes=None) -> Figure:
    """The shape of each normal mode: the chain at both turning points of the mode.

    One panel per mode, slowest first: the chain at ``+amplitude`` (solid) and
    ``-amplitude`` (dashed) times the mode shape (scaled so that its largest
    angle is ``amplitude`` [rad]), with the hanging chain dotted. The title
    gives the mode's angular frequency and its shape (first link's angle 1).
    """
    frequencies, shapes = normal_modes(model)
    amplitude = check.positive_number("amplitude", amplitude)
    n = model.n
    if axes is None:
        axes = new_figure(1, n, width=3.4 * n, height=3.6)[1]
    axes = np.atleast_1d(axes)
    if len(axes) != n:
        raise ValueError(f"`axes` must hold one axes per mode ({n}), got {len(axes)}")
    reach = 1.1 * sum(model.lengths)
    for k, (ax, omega, shape) in enumerate(zip(axes, frequencies, shapes)):
        angles = amplitude * shape / np.max(np.abs(shape))
        rest_x, rest_y = model.positions(np.zeros(n))
        ax.plot(np.r_[0.0, rest_x], np.r_[0.0, rest_y], ":", color="0.6", lw=1.5)
        for sign, style in ((1.0, "-"), (-1.0, "--")):
            x, y = model.positions(sign * angles)
            ax.plot(np.r_[0.0, x], np.r_[0.0, y], style, color="0.25", lw=2)
            ax.scatter(x, y, s=60, color="tab:red" if sign > 0 else "white",
                       edgecolor="black", zorder=3)
        ax.plot([0], [0], "s", color="black", ms=6, zorder=4)
        written = ", ".join(f"{value:.3g}" for value in shape)
        ax.set(xlim=(-0.75 * reach, 0.75 * reach), ylim=(-reach, 0.15 * reach), aspect="equal",
               xlabel="x (m)", title=f"mode {k + 1}: ω = {omega:.3f} rad/s\nshape ({written})")
    axes[0].set_ylabel("y (m)")
    return axes[0].figure


# --------------------------------------------------------------------------- configuration
def draw_pendulum(model: PendulumModel, theta, ax: Axes | None = None, trail=None, *,
                  t: float | None = None, trail_t=None) -> Figure:
    """The model at coordinates ``theta`` (time ``t``): rods, springs, points (area
    proportional to mass; a massless point, such as a shaken pivot, as a small mark), pivot.

    A system in space (``model.dimensions == 3``) is drawn in two views side by side, from
    above (x, y) and from the side (x, z): into ``ax`` given as a pair of axes, or into two
    halves of a single ``ax`` (its own frame hidden), or into a new figure.

    Parameters
    ----------
    model : PendulumModel
        A chain, or a system given by its points (:attr:`~pendulum_lab.SystemModel.drawing`).
    theta : array_like, shape (n,)
    ax : Axes, optional
        Or, for a system in space, a pair of Axes.
    trail : array_like, shape (N, n), optional
        Earlier coordinates; the path of the last massive point is drawn faintly.
    t, trail_t : float and array_like of shape (N,), optional
        The times of ``theta`` and of ``trail``, for a system whose points move with time.
    """
    theta = np.asarray(theta, dtype=float)
    if theta.shape != (model.n,):
        raise ValueError(f"`theta` must have shape ({model.n},), got {theta.shape}")
    drawing = model.drawing
    views = VIEWS[model.dimensions]
    axes = _view_axes(ax, len(views))
    masses = np.asarray(drawing.masses)
    position = model.positions(theta, t)
    seen = [np.ravel(c) for c in position]
    if trail is not None:
        trail_position = model.positions(np.asarray(trail, dtype=float), trail_t)
        seen += [np.ravel(c) for c in trail_position]
    seen = np.concatenate(seen)
    heavy = masses > 0
    for view_ax, (pair, labels, name) in zip(axes, views):
        x, y = position[pair[0]], position[pair[1]]
        if trail is not None:
            last = np.flatnonzero(heavy)[-1]
            view_ax.plot(trail_position[pair[0]][:, last], trail_position[pair[1]][:, last],
                         color="tab:purple", lw=0.7, alpha=0.5)
        rods, springs = joined_paths(drawing, x, y, view_reach(model, seen, seen))
        view_ax.plot(rods[:, 0], rods[:, 1], color="0.25", lw=2.5, zorder=2)
        view_ax.plot(springs[:, 0], springs[:, 1], color="0.25", lw=1.2, zorder=2)
        view_ax.scatter(x[heavy], y[heavy], s=120 * masses[heavy] / masses.max(),
                        color="tab:red", edgecolor="black", zorder=3)
        view_ax.plot(x[~heavy], y[~heavy], "s", color="black", ms=5, zorder=4)
        drawing_frame(view_ax, model, seen, seen, labels=labels)
        view_ax.set_title("Configuration" if name is None else f"Configuration {name}")
    return axes[0].figure


def _view_axes(ax, count: int) -> list:
    """``count`` axes to draw a model's views into: ``ax`` itself for one view; for two, ``ax``
    as a pair, or two halves of a single ``ax`` (whose own frame is hidden), or a new
    figure's."""
    if count == 1:
        return [get_axes(ax, width=4.0, height=4.0)]
    if ax is None:
        return list(new_figure(1, count, width=4.0 * count, height=4.0)[1])
    if isinstance(ax, Axes):
        ax.set_axis_off()
        return [ax.inset_axes([k / count + 0.06, 0.06, 1 / count - 0.1, 0.8])
                for k in range(count)]
    given = list(np.ravel(np.asarray(ax, dtype=object)))
    if len(given) != count or not all(isinstance(a, Axes) for a in given):
        raise ValueError(f"`ax` must be one matplotlib Axes or {count} of them (one per view "
                         f"of a system in space), got {ax!r}")
    return given


# --------------------------------------------------------------------------- analyses
def plot_linear_vs_nonlinear(
    model: PendulumModel, equilibrium, traj: Trajectory, axes=None, clip: float = np.pi
) -> Figure:
    """Linearised (left) and nonlinear (right) motion near an equilibrium, side by side.

    Both panels show the offsets ``theta_i(t) - theta_i*`` with the same axes.
    The linear solution :func:`~pendulum_lab.analysis.linearized_solution`
    starts from the trajectory's initial state; it is cut where an offset
    exceeds ``clip`` (near a saddle it grows exponentially and would otherwise
    flatten the nonlinear curve).
    """
    traj = single_trajectory(traj)
    eq = find_equilibrium(model, equilibrium)
    if axes is None:
        axes = new_figure(1, 2, width=10.0, height=3.6, sharey=True)[1]
    angles = equilibrium_angles(model, eq)
    linear, _ = linearized_solution(model, traj.theta[0], traj.omega[0], t=traj.t,
                                    equilibrium=eq)
    linear = linear - angles
    linear[np.maximum.accumulate(np.any(np.abs(linear) > clip, axis=1))] = np.nan
    offsets = traj.theta - angles
    n = model.n
    names = ([f"θ{link_label(i, n)}" for i in range(n)] if model.is_chain
             else model.coordinate_names)
    for ax, data, title in zip(axes, (linear, offsets), ("linearised", "nonlinear")):
        for i in range(n):
            ax.plot(traj.t, data[:, i], color=f"C{i}", label=f"{names[i]} − {names[i]}*")
        ax.set(xlabel=axis_label("t"), title=f"{title} near {eq.name}")
        ax.legend(loc="upper left", fontsize="small")
    axes[0].set_ylabel("offset from equilibrium" + (" (rad)" if model.is_chain else ""))
    return axes[0].figure


def plot_period_vs_amplitude(
    model: PendulumModel, amplitudes, measured, ax: Axes | None = None
) -> Figure:
    """Measured periods (markers) against the exact elliptic-integral period (line).

    The dashed line is the small-angle period ``2 pi sqrt(l / g)``.
    """
    ax = get_axes(ax)
    dense = np.linspace(0.0, 0.995 * np.pi, 400)
    ax.plot(
        dense,
        exact_period(model, dense),
        color="black",
        label="exact 4 √(l/g) K(sin²(θ₀/2))",
    )
    ax.axhline(
        2 * np.pi * np.sqrt(model.lengths[0] / model.g),
        color="0.5",
        ls="--",
        label="small angle 2π √(l/g)",
    )
    ax.plot(amplitudes, measured, "o", color="tab:red", label="measured (simulation)")
    upper = 1.3 * float(np.max(measured))
    ax.set(
        xlabel="amplitude θ₀ (rad)",
        ylabel="period (s)",
        ylim=(0, upper),
        title="Period against amplitude",
    )
    ax.legend(loc="upper left", fontsize="small")
    return ax.figure


def plot_spectrum(
    traj: Trajectory,
    ax: Axes | None = None,
    marks=(),
    link: int | None = None,
    omega_max: float | None = None,
) -> Figure:
    """Power spectrum of the angles (log scale) with vertical lines at ``marks`` [rad/s]."""
    traj = single_trajectory(traj)
    ax = get_axes(ax)
    omega, power = power_spectrum(traj, link=link)
    ax.semilogy(omega, np.maximum(power, 1e-16), color="black", lw=1)
    for k, mark in enumerate(marks):
        ax.axvline(mark, color="tab:red", ls="--", lw=1, label="predicted" if k == 0 else None)
    top = 2.0 * max(marks) if len(marks) else omega[-1]
    ax.set(
        xlabel="angular frequency ω (rad/s)",
        ylabel="power (normalised)",
        xlim=(0, top if omega_max is None else omega_max),
        ylim=(1e-8, 2),
        title="Spectrum",
    )
    if len(marks):
        ax.legend(loc="upper right", fontsize="small")
    return ax.figure


# --------------------------------------------------------------------------- explorer panels
def _panel_energy(ax, traj, model):
    plot_energy(traj, ax=ax)


def _panel_energy_error(ax, traj, model):
    plot_energy_error(traj, ax=ax)
    if not (model.is_conservative and model.is_autonomous):
        # The model's forces change its energy: the curve is their work, not an error alone.
        ax.set_title(f"Energy change ({traj.method.name}; not conserved)")


def _panel_angles(ax, traj, model):
    plot_angles(traj, ax=ax, names=None if model.is_chain else model.coordinate_names)


def _panel_phase(ax, traj, model):
    if model.is_chain:
        plot_phase(traj, ax=ax)
        return
    # A system's coordinates need not be angles: drawn as they are, not wrapped.
    for i, name in enumerate(model.coordinate_names):
        (line,) = ax.plot(traj.theta[:, i], traj.omega[:, i], lw=0.8, label=name)
        ax.plot(traj.theta[0, i], traj.omega[0, i], "o", color=line.get_color(), ms=5)
    ax.set(xlabel="coordinate q", ylabel="velocity dq/dt", title="Phase space")
    ax.legend(loc="upper right", fontsize="small")


def _panel_portrait(ax, traj, model):
    plot_phase_portrait(model, ax=ax, trajectory=traj)


def _panel_pendulum(ax, traj, model):
    draw_pendulum(model, traj.theta[-1], ax=ax, trail=traj.theta, t=traj.t[-1],
                  trail_t=traj.t)
    ax.set_title(f"Configuration at t = {traj.t[-1]:.2f} s")


PANELS: dict[str, Callable[[Axes, Trajectory, PendulumModel], None]] = {
    "energy": _panel_energy,
    "energy_error": _panel_energy_error,
    "angles": _panel_angles,
    "phase": _panel_phase,
    "portrait": _panel_portrait,
    "pendulum": _panel_pendulum,
}
"""Single-axes drawings by name, each ``(ax, trajectory, model) -> None``:

``energy`` (kinetic, potential, total), ``energy_error`` (relative, log
scale), ``angles`` (a system's coordinates by name), ``phase`` (all links
overlaid; a system's coordinates unwrapped), ``portrait`` (simple pendulum
only: level sets of H with the trajectory), ``pendulum`` (final configuration
with the last massive point's path; any model with a drawing).
"""
