"""The explorers: a pendulum's sliders driving live figures.

* :func:`explore` -- initial state, step, duration, method and the physical
  parameters of any pendulum; choose the panels with ``plots=``.
* :func:`explore_equilibrium` -- start near one of the ``2**n`` equilibria
  and see the linearised and the nonlinear motion side by side.
* :func:`explore_energy` -- pick the total energy; the chain starts at rest
  on that energy level and each link's phase-space projection is drawn.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import ipywidgets as widgets
import numpy as np
from matplotlib.ticker import MaxNLocator

from .. import plotting
from .. import validation as check
from ..analysis import equilibrium_angles, find_equilibrium, rest_state_at_energy
from ..model import require_model
from ..model.pendulum import PendulumModel
from .background import BackgroundCache
from .calls import SimulateCall, panels_code
from .controls import (
    DESCRIPTION_WIDTH,
    SLIDER_WIDTH,
    call_from_controls,
    check_steps,
    control_names,
    energy_is_conserved,
    forces_text,
    parameter_controls,
    parameter_key,
    pendulum_controls,
    run_controls,
    slider,
    start_state,
    state_controls,
)
from .instrument import Instrument

__all__ = [
    "EnergyExplorer",
    "EquilibriumExplorer",
    "Explorer",
    "cheap_to_redraw",
    "explore",
    "explore_energy",
    "explore_equilibrium",
    "panel_grid",
    "remove_data",
    "resolve_panels",
    "round_limits",
]

#: The explorers round a linear axis's autoscaled limits outward to this fraction of its tick
#: spacing, and a log axis's to this many decades (:func:`round_limits`).
LIMIT_GRID = 0.2
LOG_LIMIT_GRID = 0.25


def panel_grid(count: int) -> tuple[int, int]:
    cols = 1 if count == 1 else 2 if count in (2, 4) else 3
    return math.ceil(count / cols), cols


# --------------------------------------------------------------------------- explore
Panel = Callable[..., None]


class Explorer(Instrument):
    """Initial state, parameters, method, ``dt``, ``t_end`` of a pendulum; see :func:`explore`."""

    def __init__(
        self, model: PendulumModel, method, t_end: float, dt: float, theta0, omega0, plots: Sequence
    ):
        self.panels = resolve_panels(plots, model.n)
        controls, columns = pendulum_controls(
            model, theta0, omega0, t_end=t_end, dt=dt, method=method
        )
        self._rows, self._cols = panel_grid(len(self.panels))
        super().__init__(model, controls, columns, rows=self._rows)
        #: The pixels of the panels' frames, reused while they hold still (its ``hits``,
        #: ``misses`` and ``pieces_drawn`` count what was reused and what drawn anew).
        self.background = BackgroundCache(self.figure, self._canvas)

    def prepare(self) -> SimulateCall:
        return call_from_controls(self.model, self.controls)

    def _repr_mimebundle_(self, **kwargs):
        """The widget and its still picture; where the browser can run the first run (one
        model, a method the browser has), also its settings, with which a page without a
        kernel (the course website) shows that run live above the picture."""
        from .browser import run_settings, with_run_settings  # browser imports the widgets

        bundle = super()._repr_mimebundle_(**kwargs)
        settings = run_settings(self.model, self.trajectory)
        return bundle if "refusal" in settings else with_run_settings(bundle, settings)

    def drawing_code(self) -> str:
        return panels_code([name if plotting.PANELS.get(name) is function else function
                            for name, function in self.panels], self._cols)

    def redraw(self) -> None:
        # Building axes and their ticks is most of a redraw: on an update, keep
        # the axes and replace only what the panels draw (half the latency).
        axes = self.figure.axes
        if len(axes) != len(self.panels):
            self.background.clear()
            super().redraw()
            return
        for ax in axes:
            remove_data(ax)
        for ax, (_, panel) in zip(axes, self.panels):
            panel(ax, self.trajectory, self.model)
            cheap_to_redraw(ax)
            round_limits(ax)

    def rasterise(self) -> None:
        self.background.render()

    def draw(self, figure):
        for k, (_, panel) in enumerate(self.panels):
            ax = figure.add_subplot(self._rows, self._cols, k + 1)
            panel(ax, self.trajectory, self.model)
            cheap_to_redraw(ax)
            round_limits(ax)
        figure.subplots_adjust(
            left=0.07,
            right=0.985,
            bottom=0.16 / self._rows,
            top=1 - 0.1 / self._rows,
            wspace=0.28,
            hspace=0.45,
        )


def cheap_to_redraw(ax) -> None:
    """At most about five ticks on each linear axis of a live panel, and a fixed title height.

    Text is most of the cost of a redraw, and tick labels are most of the
    text (docs/design/explorer-redraw.md). Log axes keep their own ticks. A
    title with an explicit height skips matplotlib's search for a place above
    the tick labels; the explorers' titles are short, so nothing collides.
    """
    for axis in (ax.xaxis, ax.yaxis):
        if axis.get_scale() == "linear":
            axis.set_major_locator(MaxNLocator(5, steps=[1, 2, 2.5, 5, 10]))
    ax.set_title(ax.get_title(), y=1.0)


def round_limits(ax) -> None:
    """Round the limits of each autoscaled axis of ``ax`` outward to a coarse grid.

    The grid is a fifth of the tick spacing on a linear axis and a quarter of
    a decade on a log axis (:data:`LIMIT_GRID`, :data:`LOG_LIMIT_GRID`), so
    the frame moves only when the data cross a grid line, not on every small
    change of a slider: the frame holds still, which makes the change easier
    to see and lets the explorer reuse the frame's pixels. The limits depend
    only on the data, so an updated explorer and a fresh one draw the same
    picture.
    """
    for axis, autoscales, get, set_limits in (
        (ax.xaxis, ax.get_autoscalex_on(), ax.get_xlim, ax.set_xlim),
        (ax.yaxis, ax.get_autoscaley_on(), ax.get_ylim, ax.set_ylim),
    ):
        low, high = get()
        if not autoscales or not (math.isfinite(low) and math.isfinite(high)) or low == high:
            continue
        flipped = low > high
        low, high = sorted((low, high))
        if axis.get_scale() == "log":
            if low <= 0:
                continue
            grid = LOG_LIMIT_GRID
            low, high = math.log10(low), math.log10(high)
        elif axis.get_scale() == "linear":
            ticks = axis.get_major_locator().tick_values(low, high)
            if len(ticks) < 2:
                continue
            grid = float(ticks[1] - ticks[0]) * LIMIT_GRID
        else:
            continue
        low, high = math.floor(low / grid) * grid, math.ceil(high / grid) * grid
        if axis.get_scale() == "log":
            low, high = 10.0**low, 10.0**high
        set_limits((high, low) if flipped else (low, high))


def remove_data(ax) -> None:
    """Empty ``ax`` of what a panel drew, leaving it as a fresh axes would draw again.

    Removes the data artists and the legend, forgets the data limits, turns
    autoscaling back on and restarts the colour cycle; ticks, spines and
    layout stay (they are what is expensive to build).
    """
    for artist in [*ax.lines, *ax.collections, *ax.patches, *ax.texts, *ax.images]:
        artist.remove()
    if ax.get_legend() is not None:
        ax.get_legend().remove()
    ax.ignore_existing_data_limits = True
    ax.set_autoscale_on(True)
    ax.set_prop_cycle(None)


def resolve_panels(plots, n: int) -> list[tuple[str, Panel]]:
    if isinstance(plots, str) or callable(plots):
        plots = (plots,)
    if not plots:
        raise ValueError("`plots` must name at least one panel")
    panels = []
    for item in plots:
        if callable(item):
            panels.append((getattr(item, "__name__", "custom"), item))
        elif item in plotting.PANELS:
            if item == "portrait" and n != 1:
                raise ValueError(
                    "the 'portrait' panel is for the simple pendulum only; "
                    "use 'phase' for more links"
                )
            panels.append((item, plotting.PANELS[item]))
        else:
            raise ValueError(
                f"`plots` entries must be one of {list(plotting.PANELS)} or "
                f"callables (ax, trajectory, model) -> None, got {item!r}"
            )
    return panels


def explore(
    model: PendulumModel,
    theta0=None,
    omega0=None,
    *,
    t_end: float = 20.0,
    dt: float = 0.01,
    method="glrk4",
    plots=("energy", "angles"),
) -> Explorer:
    """An explorer of one pendulum: sliders, a method dropdown and live figures.

    Parameters
    ----------
    model : PendulumModel
        Any chain; its masses, lengths and ``g`` are the sliders' start values,
        and its damping and drive stay as they are (noted beside the sliders).
    theta0, omega0 : array_like, shape (n,), optional
        Initial angles [rad] in ``[-pi, pi]`` and angular velocities [rad/s];
        default 1 rad for one link, ``(2.0, 2.5)`` for two (a chaotic start),
        and at rest.
    t_end, dt : float
        Duration and step [s]. ``dt`` is offered on a ladder of values
        (:data:`DT_CHOICES`, plus the given one).
    method : str
        A method :func:`pendulum_lab.simulate` accepts for ``model`` (the
        dropdown's start value; the dropdown offers the others of
        :data:`pendulum_lab.METHODS` it accepts); another raises
        ``ValueError`` with the driver's reason.
    plots : sequence of str or callable
        Panels, by name from :data:`pendulum_lab.plotting.PANELS`
        (``"energy"``, ``"energy_error"``, ``"angles"``, ``"phase"``,
        ``"portrait"``, ``"pendulum"``) or callables
        ``(ax, trajectory, model) -> None`` that draw into ``ax``.

    Returns
    -------
    Explorer
        ``widget`` to display (a bare ``ex`` at the end of a cell shows it),
        ``controls`` (``"theta1"``, ..., ``"omega1"``, ..., ``"m1"``, ...,
        ``"l1"``, ..., ``"g"``, ``"dt"``, ``"t_end"``, ``"method"``; for one
        link ``"theta"``, ``"omega"``, ``"mass"``, ``"length"``),
        ``trajectory``, ``figure``, ``message``, ``model``, ``code()`` (the
        ``pl.simulate`` call of the run shown) and ``update()``.
        An update redraws only the data of a panel whose axes, ticks and
        labels are unchanged (``background`` counts them); to that end each
        autoscaled axis's limits are rounded out a little (:func:`round_limits`).

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> ex = explore(pl.simple_pendulum(), t_end=2.0, dt=0.01, plots=("portrait",))
    >>> ex.controls["theta"].value = 0.5
    >>> float(ex.trajectory.theta[0, 0])
    0.5
    """
    model = require_model(model)
    theta0, omega0 = start_state(model, theta0, omega0)
    if "pendulum" in plots:
        model.drawing  # noqa: B018 (a model with nothing to draw is refused here, a TypeError)
    ex = Explorer(model, method, t_end, dt, theta0, omega0, plots)
    ex.update()
    return ex


# --------------------------------------------------------------------------- equilibria
class EquilibriumExplorer(Instrument):
    """Linearised and nonlinear motion near an equilibrium; see :func:`explore_equilibrium`."""

    def __init__(
        self,
        model: PendulumModel,
        equilibrium: str,
        t_end: float,
        dt: float,
        method,
        offset: np.ndarray,
    ):
        n = model.n
        names = [eq.name for eq in model.equilibria]
        controls = {
            "equilibrium": widgets.Dropdown(
                options=names,
                value=equilibrium,
                description="equilibrium",
                style={"description_width": DESCRIPTION_WIDTH},
                layout=widgets.Layout(width=SLIDER_WIDTH),
            ),
            **state_controls(
                n,
                offset,
                np.zeros(n),
                angle_range=(-0.5, 0.5),
                speed_range=(-1.0, 1.0),
                angle_step=0.005,
                speed_step=0.01,
                prefix="δ",
            ),
            **parameter_controls(model),
            **run_controls(model, method, t_end, dt, t_end_range=(0.1, 30.0)),
        }
        keys = control_names(n)
        columns = [
            ("Start near", ["equilibrium", *keys["theta"], *keys["omega"]]),
            ("Parameters", keys["mass"] + keys["length"] + ["g"] if model.is_chain
             else [parameter_key(model, str(s)) for s in model.parameter_values]),
            ("Integration", ["method", "dt", "t_end"]),
        ]
        super().__init__(model, controls, columns)

    def _selected(self, model):
        """The equilibrium of ``model`` the dropdown selects."""
        dropdown = self.controls["equilibrium"]
        if model.is_chain:
            return find_equilibrium(model, dropdown.value)
        # A system's equilibria move with its parameters (and so do their names): take the
        # one in the same place of the list, ordered by potential energy.
        return model.equilibria[dropdown.index]

    @property
    def equilibrium(self):
        """The selected :class:`~pendulum_lab.symbolic.mechanics.Equilibrium`."""
        return self._selected(self.model)

    def prepare(self) -> SimulateCall:
        def origin(model):
            return equilibrium_angles(model, self._selected(model))

        return call_from_controls(self.model, self.controls, origin=origin)

    def drawing_code(self) -> str:
        return ("# The picture: the linearised and the nonlinear motion side by side\n"
                "pl.plotting.plot_linear_vs_nonlinear(model, "
                f"{self.equilibrium.name!r}, traj)\n")

    def draw(self, figure):
        left = figure.add_subplot(1, 2, 1)
        right = figure.add_subplot(1, 2, 2, sharey=left)
        plotting.plot_linear_vs_nonlinear(self.model, self.equilibrium, self.trajectory,
                                          axes=(left, right))
        figure.subplots_adjust(left=0.07, right=0.985, bottom=0.16, top=0.9, wspace=0.12)

    def summary(self) -> str:
        eq = self.equilibrium
        try:
            kind = eq.classify(self.model.parameter_values)
        except ValueError:  # an eigenvalue 0: a coordinate left free (the cart's position)
            kind = "degenerate (a coordinate moves freely)"
        jac = np.array(eq.jacobian.subs(self.model.parameter_values), dtype=float)
        pairs = []
        for z in np.linalg.eigvals(jac):
            real = abs(z.imag) <= 1e-9 * max(1.0, abs(z))
            text = f"±{abs(z.real):.3f}" if real else f"±{abs(z.imag):.3f}i"
            if text not in pairs:
                pairs.append(text)
        return (
            f"{eq.name}: {kind}; Jacobian eigenvalues {', '.join(sorted(pairs))} (1/s). "
            + super().summary()
        )


def explore_equilibrium(
    model: PendulumModel,
    equilibrium: str | None = None,
    *,
    t_end: float = 10.0,
    dt: float = 0.01,
    method="glrk4",
    offset=None,
) -> EquilibriumExplorer:
    """Start near an equilibrium and compare the linearised with the nonlinear motion.

    Parameters
    ----------
    model : PendulumModel
    equilibrium : str, optional
        A name from ``[eq.name for eq in model.chain.equilibria]`` (``"down"``,
        ``"up"`` for one link; ``"down-down"``, ``"down-up"``, ``"up-down"``,
        ``"up-up"`` for two); default all down. For a system that is not a
        chain, a name from ``[eq.name for eq in model.equilibria]``; default its
        equilibrium of least potential energy.
    t_end, dt : float
        Duration and step [s].
    method : str
    offset : array_like, shape (n,), optional
        Initial angle offsets from the equilibrium [rad], each in
        ``[-0.5, 0.5]``; default 0.05 rad on the first link.

    Returns
    -------
    EquilibriumExplorer
        Controls ``"equilibrium"`` (dropdown), ``"theta1"``, ... (angle
        offsets), ``"omega1"``, ... (angular velocities), the parameters,
        ``"method"``, ``"dt"``, ``"t_end"``; the left panel shows the
        linearised motion ``exp(A t) x0``, the right the simulation.

    Raises
    ------
    ValueError
        For a model with damping or a drive (its linearisation is not the
        conservative chain's), with the reason.
    """
    model = require_model(model)
    if not energy_is_conserved(model):
        raise ValueError(
            "`model` must have no damping and no drive: explore_equilibrium compares the motion "
            "with its linearisation about an equilibrium of the conservative chain, and this "
            f"model has {forces_text(model)}; explore(model) shows its motion"
        )
    n = model.n
    equilibrium = find_equilibrium(model, equilibrium).name
    offset = check.state_vector("offset", [0.05] + [0.0] * (n - 1) if offset is None else offset,
                                n, 0.5, "rad")
    ex = EquilibriumExplorer(model, equilibrium, t_end, dt, method, offset)
    ex.update()
    return ex


# --------------------------------------------------------------------------- energy levels
class EnergyExplorer(Instrument):
    """Per-link phase projections on a chosen energy level; see :func:`explore_energy`."""

    def __init__(self, model: PendulumModel, energy: float, t_end: float, dt: float, method):
        depth = -float(model.potential_energy(np.zeros(model.n)))
        step = 10 ** math.floor(math.log10(depth / 200))
        controls = {
            "energy": slider(
                energy,
                -depth + step,
                depth,
                step,
                "E (J)",
                f".{max(0, -math.floor(math.log10(step)))}f",
            ),
            **run_controls(model, method, t_end, dt, t_end_range=(1.0, 200.0)),
        }
        columns = [("Energy", ["energy"]), ("Integration", ["method", "dt", "t_end"])]
        self._cols = model.n
        super().__init__(model, controls, columns)

    def prepare(self) -> SimulateCall:
        c = self.controls
        check_steps(c["t_end"].value, c["dt"].value)
        theta0 = rest_state_at_energy(self.model, c["energy"].value)
        return SimulateCall(self.model, theta0, np.zeros(self.model.n), t_end=c["t_end"].value,
                            dt=c["dt"].value, method=c["method"].value)

    def drawing_code(self) -> str:
        if self.model.n == 1:
            return ("# The picture: the run on the phase portrait\n"
                    "pl.plotting.plot_phase_portrait(model, trajectory=traj)\n")
        return ("# The picture: each link's projection (theta_i, omega_i)\n"
                "pl.plotting.plot_link_projections(traj)\n")

    def draw(self, figure):
        axes = [figure.add_subplot(1, self._cols, k + 1) for k in range(self._cols)]
        if self.model.n == 1:
            plotting.plot_phase_portrait(self.model, ax=axes[0], trajectory=self.trajectory)
        else:
            plotting.plot_link_projections(self.trajectory, axes=axes)
        figure.subplots_adjust(left=0.07, right=0.985, bottom=0.16, top=0.9, wspace=0.25)

    def summary(self) -> str:
        phi = float(self.trajectory.theta[0, 0])
        return (
            f"Start at rest with every angle = {phi:.4f} rad "
            f"({np.degrees(phi):.1f}°). " + super().summary()
        )


def explore_energy(
    model: PendulumModel,
    energy: float | None = None,
    *,
    t_end: float = 60.0,
    dt: float = 0.01,
    method="glrk4",
) -> EnergyExplorer:
    """Choose the total energy; see each link's ``(theta_i, omega_i)`` projection.

    The chain starts at rest with all angles equal
    (:func:`pendulum_lab.analysis.rest_state_at_energy`), so the slider runs
    from just above the bottom (everything hanging down) to everything
    pointing up. For the double pendulum, low energies give regular, nearly
    periodic projections and high energies tangled, chaotic ones.

    Parameters
    ----------
    model : PendulumModel
    energy : float, optional
        Total energy [J]; default a quarter of the way up from the bottom.
    t_end, dt : float
    method : str

    Returns
    -------
    EnergyExplorer
        Controls ``"energy"``, ``"method"``, ``"dt"``, ``"t_end"``.

    Raises
    ------
    ValueError
        For a model with damping or a drive (its energy does not stay on a
        level), with the reason.
    """
    model = require_model(model)
    if not model.is_chain:
        raise TypeError(
            f"`model` must be a chain: explore_energy measures its energy levels from the "
            f"hanging chain's depth below the pivot, which {model.name} (a system given by its "
            "points or its Lagrangian) does not have; explore(model) shows its motion and its "
            "energy")
    if not energy_is_conserved(model):
        raise ValueError(
            "`model` must have no damping and no drive: explore_energy follows the chain on one "
            f"level of its energy, and this model has {forces_text(model)}, which carry it off "
            "that level; explore(model) shows its motion and its energy"
        )
    depth = -float(model.potential_energy(np.zeros(model.n)))
    if depth <= 0:
        raise ValueError(f"the model's `g` must be positive, got {model.g}")
    energy = -0.5 * depth if energy is None else check.number_in(
        "energy", energy, -depth, depth, "J", open_low=True)
    ex = EnergyExplorer(model, energy, t_end, dt, method)
    ex.update()
    return ex
