"""Interactive explorers: ipywidgets controls driving a simulation and a matplotlib figure.

Three explorers share one machinery (:class:`Instrument`): a dict of
controls, a status line, and a figure rendered to PNG into an
``ipywidgets.Image``. Rendering to an image works the same in JupyterLab, in
a notebook run by nbval and in a test without any front end, and needs no
interactive matplotlib backend. Every control has ``continuous_update=False``:
the simulation reruns when a slider is released, not while it moves.

* :func:`explore` -- initial state, step, duration, method and the physical
  parameters of any pendulum; choose the panels with ``plots=``.
* :func:`explore_equilibrium` -- start near one of the ``2**n`` equilibria
  and see the linearised and the nonlinear motion side by side.
* :func:`explore_energy` -- pick the total energy; the chain starts at rest
  on that energy level and each arm's phase-space projection is drawn.

In a notebook cell, ``pl.widgets.explore(model)`` shows the explorer (it
has ``_ipython_display_``). Each explorer keeps what it shows inspectable:
``controls`` (name -> widget), ``trajectory``, ``figure``, ``message`` and
``update()``, so it can be driven without a browser::

    ex = explore(pl.double_pendulum(), t_end=5.0)
    ex.controls["theta1"].value = 0.5      # reruns and redraws
    ex.trajectory.theta[0]                 # array([0.5, 2.5])

Invalid combinations (``t_end < dt``, too many steps, an implicit solver that
does not converge) leave the last trajectory and figure in place and put a
readable sentence in ``message`` instead of raising.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence

import ipywidgets as widgets
import matplotlib as mpl
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from . import analysis, plotting
from ._png import png_bytes
from .integrators import METHODS, ConvergenceError, get_method
from .model import PendulumModel, check_model, double_pendulum, n_pendulum, simple_pendulum
from .simulate import Trajectory, simulate

__all__ = [
    "DT_CHOICES",
    "MAX_STEPS",
    "EnergyExplorer",
    "EquilibriumExplorer",
    "Explorer",
    "Instrument",
    "explore",
    "explore_energy",
    "explore_equilibrium",
]

#: Step sizes offered by the ``dt`` slider [s] (a logarithmic ladder).
DT_CHOICES = (0.0005, 0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5)
#: Largest number of steps one update may take (``t_end / dt``).
MAX_STEPS = 100_000

_SUBSCRIPTS = str.maketrans("0123456789", "₀₁₂₃₄₅₆₇₈₉")
_DESCRIPTION_WIDTH = "88px"
_SLIDER_WIDTH = "310px"
_DPI = 90
_ROW_HEIGHT = 3.4  # inches per row of panels
_WIDTH = 10.5  # inches


# --------------------------------------------------------------------------- controls
def _keys(n: int) -> dict[str, list[str]]:
    """Control names: ``theta``/``omega``/``mass``/``length`` for one link, else indexed."""
    if n == 1:
        return {"theta": ["theta"], "omega": ["omega"], "mass": ["mass"], "length": ["length"]}
    idx = range(1, n + 1)
    return {
        "theta": [f"theta{i}" for i in idx],
        "omega": [f"omega{i}" for i in idx],
        "mass": [f"m{i}" for i in idx],
        "length": [f"l{i}" for i in idx],
    }


def _symbol(base: str, i: int, n: int) -> str:
    return base if n == 1 else base + str(i + 1).translate(_SUBSCRIPTS)


def _slider(
    value: float, low: float, high: float, step: float, description: str, fmt: str = ".2f"
) -> widgets.FloatSlider:
    """A float slider whose range always contains ``value``; the unit is in the description."""
    return widgets.FloatSlider(
        value=value,
        min=min(low, value),
        max=max(high, value),
        step=step,
        description=description,
        readout_format=fmt,
        continuous_update=False,
        style={"description_width": _DESCRIPTION_WIDTH},
        layout=widgets.Layout(width=_SLIDER_WIDTH),
    )


def _state_controls(
    n: int,
    theta0,
    omega0,
    *,
    angle_range=(-np.pi, np.pi),
    speed_range=(-10, 10),
    angle_step=0.01,
    speed_step=0.05,
    prefix: str = "",
) -> dict:
    """Sliders ``theta*`` [rad] and ``omega*`` [rad/s] for the initial state (or its offsets)."""
    keys = _keys(n)
    controls = {}
    for i, key in enumerate(keys["theta"]):
        controls[key] = _slider(
            float(theta0[i]), *angle_range, angle_step, f"{prefix}{_symbol('θ', i, n)} (rad)", ".3f"
        )
    for i, key in enumerate(keys["omega"]):
        controls[key] = _slider(
            float(omega0[i]),
            *speed_range,
            speed_step,
            f"{prefix}{_symbol('ω', i, n)} (rad/s)",
            ".2f",
        )
    return controls


def _parameter_controls(model: PendulumModel) -> dict:
    """Sliders for masses [kg], lengths [m] and g [m/s^2], starting at the model's values."""
    n, keys = model.n, _keys(model.n)
    controls = {}
    for i, key in enumerate(keys["mass"]):
        controls[key] = _slider(model.masses[i], 0.1, 5.0, 0.05, f"{_symbol('m', i, n)} (kg)")
    for i, key in enumerate(keys["length"]):
        controls[key] = _slider(model.lengths[i], 0.1, 3.0, 0.05, f"{_symbol('l', i, n)} (m)")
    controls["g"] = _slider(model.g, 0.5, 25.0, 0.01, "g (m/s²)")
    return controls


def _run_controls(method, t_end: float, dt: float, t_end_range=(0.1, 100.0)) -> dict:
    """The method dropdown, a ``dt`` ladder slider [s] and a ``t_end`` slider [s]."""
    name = get_method(method).name
    choices = sorted(set(DT_CHOICES) | {float(dt)})
    return {
        "method": widgets.Dropdown(
            options=list(METHODS),
            value=name,
            description="method",
            style={"description_width": _DESCRIPTION_WIDTH},
            layout=widgets.Layout(width=_SLIDER_WIDTH),
        ),
        "dt": widgets.SelectionSlider(
            options=[(f"{v:g}", v) for v in choices],
            value=float(dt),
            description="Δt (s)",
            continuous_update=False,
            style={"description_width": _DESCRIPTION_WIDTH},
            layout=widgets.Layout(width=_SLIDER_WIDTH),
        ),
        "t_end": _slider(float(t_end), *t_end_range, 0.1, "t_end (s)", ".1f"),
    }


def _model_from(n: int, controls: dict) -> PendulumModel:
    """Build the model the parameter controls describe (cheap: compiled code is shared per n)."""
    keys = _keys(n)
    masses = [controls[k].value for k in keys["mass"]]
    lengths = [controls[k].value for k in keys["length"]]
    g = controls["g"].value
    if n == 1:
        return simple_pendulum(mass=masses[0], length=lengths[0], g=g)
    if n == 2:
        return double_pendulum(m1=masses[0], m2=masses[1], l1=lengths[0], l2=lengths[1], g=g)
    return n_pendulum(n, masses=masses, lengths=lengths, g=g)


def _initial_state(n: int, controls: dict) -> tuple[np.ndarray, np.ndarray]:
    keys = _keys(n)
    return (
        np.array([controls[k].value for k in keys["theta"]], dtype=float),
        np.array([controls[k].value for k in keys["omega"]], dtype=float),
    )


def _check_steps(t_end: float, dt: float) -> int:
    steps = math.floor(t_end / dt * (1 + 1e-12))
    if steps > MAX_STEPS:
        raise ValueError(
            f"t_end / dt = {t_end:g} s / {dt:g} s = {steps} steps, more than the explorer's "
            f"limit of {MAX_STEPS}; choose a larger dt or a shorter t_end"
        )
    return steps


def _column(title: str, controls: Sequence[widgets.Widget]) -> widgets.VBox:
    return widgets.VBox([widgets.HTML(f"<b>{title}</b>"), *controls])


def _state_vector(name: str, value, default, n: int) -> np.ndarray:
    if value is None:
        return np.asarray(default, dtype=float)
    arr = np.asarray(value, dtype=float).reshape(-1)
    if arr.shape != (n,) or not np.all(np.isfinite(arr)):
        raise ValueError(f"`{name}` must be {n} finite number(s), got {value!r}")
    return arr


# --------------------------------------------------------------------------- the machinery
class Instrument:
    """Controls, a status line and a figure that :meth:`update` recomputes and redraws.

    Subclasses implement ``_compute()`` (build the model and the trajectory
    from the controls; raise ``ValueError`` for an invalid combination) and
    ``_draw(figure)``. Everything else -- observing the controls, catching
    errors, rendering the figure, the message -- lives here once.

    Attributes
    ----------
    controls : dict of str -> ipywidgets.ValueWidget
    model : PendulumModel
        The model of the latest successful update.
    trajectory : Trajectory
        The latest successful trajectory.
    figure : matplotlib.figure.Figure
        The figure shown (redrawn in place).
    widget : ipywidgets.VBox
        Controls, status line and figure; display this.
    """

    #: Exceptions that mean "this combination of inputs cannot be simulated".
    _EXPECTED = (ValueError, TypeError, ConvergenceError, FloatingPointError, OverflowError)

    def __init__(
        self,
        model: PendulumModel,
        controls: dict,
        columns: list[tuple[str, list[str]]],
        rows: int = 1,
    ):
        self.model = model
        self.controls = controls
        self.trajectory: Trajectory | None = None
        self._message = ""
        self.figure = Figure(figsize=(_WIDTH, _ROW_HEIGHT * rows), dpi=_DPI)
        self._canvas = FigureCanvasAgg(self.figure)
        self._status = widgets.HTML(layout=widgets.Layout(min_height="1.6em"))
        self._image = widgets.Image(format="png")
        boxes = [_column(title, [controls[k] for k in keys]) for title, keys in columns if keys]
        self.widget = widgets.VBox([widgets.HBox(boxes), self._status, self._image])
        for control in controls.values():
            control.observe(self._on_change, names="value")

    # ---- what subclasses provide ------------------------------------------------------------
    def _compute(self) -> tuple[PendulumModel, Trajectory]:
        raise NotImplementedError

    def _draw(self, figure: Figure) -> None:
        raise NotImplementedError

    def _summary(self) -> str:
        traj = self.trajectory
        err = float(np.max(np.abs(traj.energy_error)))
        return (
            f"{len(traj.t) - 1} steps of {traj.method.name} (dt = {traj.dt:g} s) in "
            f"{traj.wall_time:.2f} s; E(0) = {traj.energy[0]:.4f} J, "
            f"max |E − E(0)| = {err:.2e} J"
        )

    # ---- the shared machinery ----------------------------------------------------------------
    @property
    def message(self) -> str:
        """The text of the status line: a summary of the run, a warning or an error."""
        return self._message

    def _set_message(self, text: str, kind: str = "info") -> None:
        self._message = text
        colour = {"info": "#333", "warning": "#9a6700", "error": "#b00020"}[kind]
        escaped = text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
        self._status.value = f'<span style="color:{colour}">{escaped}</span>'

    def _on_change(self, change) -> None:
        self.update()

    def update(self) -> bool:
        """Recompute from the controls and redraw; return whether it succeeded.

        On an invalid combination the previous trajectory and figure stay and
        ``message`` says what is wrong. A run that blew up (non-finite state)
        is drawn up to where it stopped, with the warning in ``message``.
        """
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", RuntimeWarning)
                model, trajectory = self._compute()
        except self._EXPECTED as err:
            what = (
                "The solver did not converge"
                if isinstance(err, ConvergenceError)
                else ("Cannot run this combination")
            )
            self._set_message(f"{what}: {err}. The figure still shows the previous run.", "error")
            return False
        self.model, self.trajectory = model, trajectory
        try:
            self._redraw()
        except self._EXPECTED as err:
            self._set_message(f"Could not draw the figure: {err}", "error")
            return False
        self._render()
        # The driver's own warning (a blow-up) says what happened; NumPy's
        # "overflow encountered in ..." that may follow it adds nothing.
        notes = list(
            dict.fromkeys(
                str(w.message)
                for w in caught
                if issubclass(w.category, RuntimeWarning) and "encountered in" not in str(w.message)
            )
        )
        if notes:
            self._set_message(" ".join([*notes[:2], self._summary()]), "warning")
        else:
            self._set_message(self._summary())
        return True

    def _redraw(self) -> None:
        """Draw the current trajectory into an emptied figure."""
        self.figure.clear()
        self._draw(self.figure)

    def _render(self) -> None:
        # FreeType's hinting of every glyph is a fifth of a redraw; unhinted
        # text looks the same at this size and resolution.
        with mpl.rc_context({"text.hinting": "none"}):
            self._canvas.draw()
        self._image.value = png_bytes(np.asarray(self._canvas.buffer_rgba()))

    def _ipython_display_(self) -> None:
        from IPython.display import display

        display(self.widget)

    def _repr_mimebundle_(self, **kwargs):
        return self.widget._repr_mimebundle_(**kwargs)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.model!r})"


def _grid(count: int) -> tuple[int, int]:
    cols = 1 if count == 1 else 2 if count in (2, 4) else 3
    return math.ceil(count / cols), cols


# --------------------------------------------------------------------------- explore
Panel = Callable[..., None]


class Explorer(Instrument):
    """Initial state, parameters, method, ``dt``, ``t_end`` of a pendulum; see :func:`explore`."""

    def __init__(
        self, model: PendulumModel, method, t_end: float, dt: float, theta0, omega0, plots: Sequence
    ):
        n = model.n
        self.panels = _panels(plots, n)
        controls = {
            **_state_controls(n, theta0, omega0),
            **_parameter_controls(model),
            **_run_controls(method, t_end, dt),
        }
        keys = _keys(n)
        columns = [
            ("Initial state", keys["theta"] + keys["omega"]),
            ("Parameters", keys["mass"] + keys["length"] + ["g"]),
            ("Integration", ["method", "dt", "t_end"]),
        ]
        self._rows, self._cols = _grid(len(self.panels))
        super().__init__(model, controls, columns, rows=self._rows)

    def _compute(self):
        return simulate_controls(self.model.n, self.controls)

    def _redraw(self) -> None:
        # Building axes and their ticks is most of a redraw: on an update, keep
        # the axes and replace only what the panels draw (half the latency).
        axes = self.figure.axes
        if len(axes) != len(self.panels):
            super()._redraw()
            return
        for ax in axes:
            _remove_data(ax)
        for ax, (_, panel) in zip(axes, self.panels):
            panel(ax, self.trajectory, self.model)
            _cheap_to_redraw(ax)

    def _draw(self, figure):
        for k, (_, panel) in enumerate(self.panels):
            ax = figure.add_subplot(self._rows, self._cols, k + 1)
            panel(ax, self.trajectory, self.model)
            _cheap_to_redraw(ax)
        figure.subplots_adjust(
            left=0.07,
            right=0.985,
            bottom=0.16 / self._rows,
            top=1 - 0.1 / self._rows,
            wspace=0.28,
            hspace=0.45,
        )


def start_state(n: int, theta0=None, omega0=None) -> tuple[np.ndarray, np.ndarray]:
    """The explorers' starting state: the given one checked, or the default.

    The default is at rest from 1 rad (one link) or from angles spread over
    2.0-2.5 rad (a lively, chaotic release). Angles must lie in [-pi, pi] and
    velocities in [-10, 10] rad/s, the range of the sliders.
    """
    default = [1.0] if n == 1 else np.linspace(2.0, 2.5, n)
    theta0 = _state_vector("theta0", theta0, default, n)
    omega0 = _state_vector("omega0", omega0, np.zeros(n), n)
    if np.any(np.abs(theta0) > np.pi):
        raise ValueError(f"`theta0` entries must lie in [-pi, pi], got {theta0}")
    if np.any(np.abs(omega0) > 10):
        raise ValueError(f"`omega0` entries must lie in [-10, 10] rad/s, got {omega0}")
    return theta0, omega0


def simulate_controls(n: int, controls: dict, origin=None) -> tuple[PendulumModel, Trajectory]:
    """The model and the trajectory that a set of explorer controls describes.

    Parameters
    ----------
    n : int
        Number of links.
    controls : dict
        Name -> widget, with the initial-state, parameter, ``dt``, ``t_end``
        and ``method`` controls of :func:`explore`.
    origin : callable ``model -> angles``, optional
        If given, the angle controls are offsets from these angles.
    """
    c = controls
    _check_steps(c["t_end"].value, c["dt"].value)
    model = _model_from(n, c)
    theta0, omega0 = _initial_state(n, c)
    if origin is not None:
        theta0 = theta0 + origin(model)
    traj = simulate(model, theta0, omega0, t_end=c["t_end"].value, dt=c["dt"].value,
                    method=c["method"].value, progress=False)
    return model, traj


def _cheap_to_redraw(ax) -> None:
    """At most about five ticks on each linear axis of a live panel, and a fixed title height.

    Text is most of the cost of a redraw, and tick labels are most of the
    text: with matplotlib's default density an explorer update took a third
    longer. Log axes keep their own ticks. A title with an explicit height
    skips matplotlib's search for a place above the tick labels (4 ms per
    update); the explorers' titles are short, so nothing collides.
    """
    for axis in (ax.xaxis, ax.yaxis):
        if axis.get_scale() == "linear":
            axis.set_major_locator(MaxNLocator(5, steps=[1, 2, 2.5, 5, 10]))
    ax.set_title(ax.get_title(), y=1.0)


def _remove_data(ax) -> None:
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


def _panels(plots, n: int) -> list[tuple[str, Panel]]:
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
                    "use 'phase' for more arms"
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
    method="glrk4",
    t_end: float = 20.0,
    dt: float = 0.01,
    theta0=None,
    omega0=None,
    plots=("energy", "angles"),
) -> Explorer:
    """An explorer of one pendulum: sliders, a method dropdown and live figures.

    Parameters
    ----------
    model : PendulumModel
        Any chain; its masses, lengths and ``g`` are the sliders' start values.
    method : str
        A key of :data:`pendulum_lab.METHODS` (the dropdown's start value).
    t_end, dt : float
        Duration and step [s]. ``dt`` is offered on a ladder of values
        (:data:`DT_CHOICES`, plus the given one).
    theta0, omega0 : array_like, shape (n,), optional
        Initial angles [rad] in ``[-pi, pi]`` and angular velocities [rad/s];
        default 1 rad for one link, ``(2.0, 2.5)`` for two (a chaotic start),
        and at rest.
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
        ``trajectory``, ``figure``, ``message``, ``model`` and ``update()``.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> ex = explore(pl.simple_pendulum(), t_end=2.0, dt=0.01, plots=("portrait",))
    >>> ex.controls["theta"].value = 0.5
    >>> float(ex.trajectory.theta[0, 0])
    0.5
    """
    model = check_model(model)
    theta0, omega0 = start_state(model.n, theta0, omega0)
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
        names = [eq.name for eq in model.chain.equilibria]
        controls = {
            "equilibrium": widgets.Dropdown(
                options=names,
                value=equilibrium,
                description="equilibrium",
                style={"description_width": _DESCRIPTION_WIDTH},
                layout=widgets.Layout(width=_SLIDER_WIDTH),
            ),
            **_state_controls(
                n,
                offset,
                np.zeros(n),
                angle_range=(-0.5, 0.5),
                speed_range=(-1.0, 1.0),
                angle_step=0.005,
                speed_step=0.01,
                prefix="δ",
            ),
            **_parameter_controls(model),
            **_run_controls(method, t_end, dt, t_end_range=(0.1, 30.0)),
        }
        keys = _keys(n)
        columns = [
            ("Start near", ["equilibrium", *keys["theta"], *keys["omega"]]),
            ("Parameters", keys["mass"] + keys["length"] + ["g"]),
            ("Integration", ["method", "dt", "t_end"]),
        ]
        super().__init__(model, controls, columns)

    @property
    def equilibrium(self):
        """The selected :class:`~pendulum_lab.mechanics.Equilibrium`."""
        return analysis._equilibrium(self.model, self.controls["equilibrium"].value)

    def _compute(self):
        def equilibrium_angles(model):
            eq = analysis._equilibrium(model, self.controls["equilibrium"].value)
            return np.array([float(a) for a in eq.angles])

        return simulate_controls(self.model.n, self.controls, origin=equilibrium_angles)

    def _draw(self, figure):
        left = figure.add_subplot(1, 2, 1)
        right = figure.add_subplot(1, 2, 2, sharey=left)
        plotting.plot_linear_vs_nonlinear(
            self.model, self.controls["equilibrium"].value, self.trajectory, axes=(left, right)
        )
        figure.subplots_adjust(left=0.07, right=0.985, bottom=0.16, top=0.9, wspace=0.12)

    def _summary(self) -> str:
        eq = self.equilibrium
        kind = eq.classify(self.model.parameter_values)
        jac = np.array(eq.jacobian.subs(self.model.parameter_values), dtype=float)
        pairs = []
        for z in np.linalg.eigvals(jac):
            real = abs(z.imag) <= 1e-9 * max(1.0, abs(z))
            text = f"±{abs(z.real):.3f}" if real else f"±{abs(z.imag):.3f}i"
            if text not in pairs:
                pairs.append(text)
        return (
            f"{eq.name}: {kind}; Jacobian eigenvalues {', '.join(sorted(pairs))} (1/s). "
            + super()._summary()
        )


def explore_equilibrium(
    model: PendulumModel,
    equilibrium: str | None = None,
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
        ``"up-up"`` for two); default all down.
    t_end, dt : float
        Duration and step [s].
    method : str
    offset : array_like, shape (n,), optional
        Initial angle offsets from the equilibrium [rad], each in
        ``[-0.5, 0.5]``; default 0.05 rad on the first arm.

    Returns
    -------
    EquilibriumExplorer
        Controls ``"equilibrium"`` (dropdown), ``"theta1"``, ... (angle
        offsets), ``"omega1"``, ... (angular velocities), the parameters,
        ``"method"``, ``"dt"``, ``"t_end"``; the left panel shows the
        linearised motion ``exp(A t) x0``, the right the simulation.
    """
    model = check_model(model)
    n = model.n
    names = [eq.name for eq in model.chain.equilibria]
    equilibrium = names[0] if equilibrium is None else equilibrium
    if equilibrium not in names:
        raise ValueError(f"`equilibrium` must be one of {names}, got {equilibrium!r}")
    offset = _state_vector("offset", offset, [0.05] + [0.0] * (n - 1), n)
    if np.any(np.abs(offset) > 0.5):
        raise ValueError(f"`offset` entries must lie in [-0.5, 0.5] rad, got {offset}")
    ex = EquilibriumExplorer(model, equilibrium, t_end, dt, method, offset)
    ex.update()
    return ex


# --------------------------------------------------------------------------- energy levels
class EnergyExplorer(Instrument):
    """Per-arm phase projections on a chosen energy level; see :func:`explore_energy`."""

    def __init__(self, model: PendulumModel, energy: float, t_end: float, dt: float, method):
        depth = -float(model.potential_energy(np.zeros(model.n)))
        step = 10 ** math.floor(math.log10(depth / 200))
        controls = {
            "energy": _slider(
                energy,
                -depth + step,
                depth,
                step,
                "E (J)",
                f".{max(0, -math.floor(math.log10(step)))}f",
            ),
            **_run_controls(method, t_end, dt, t_end_range=(1.0, 200.0)),
        }
        columns = [("Energy", ["energy"]), ("Integration", ["method", "dt", "t_end"])]
        self._cols = model.n
        super().__init__(model, controls, columns)

    def _compute(self):
        c = self.controls
        _check_steps(c["t_end"].value, c["dt"].value)
        theta0 = analysis.rest_state_at_energy(self.model, c["energy"].value)
        traj = simulate(
            self.model,
            theta0,
            np.zeros(self.model.n),
            t_end=c["t_end"].value,
            dt=c["dt"].value,
            method=c["method"].value,
            progress=False,
        )
        return self.model, traj

    def _draw(self, figure):
        axes = [figure.add_subplot(1, self._cols, k + 1) for k in range(self._cols)]
        if self.model.n == 1:
            plotting.plot_phase_portrait(self.model, ax=axes[0], trajectory=self.trajectory)
        else:
            plotting.plot_arm_projections(self.trajectory, axes=axes)
        figure.subplots_adjust(left=0.07, right=0.985, bottom=0.16, top=0.9, wspace=0.25)

    def _summary(self) -> str:
        phi = float(self.trajectory.theta[0, 0])
        return (
            f"Start at rest with every angle = {phi:.4f} rad "
            f"({np.degrees(phi):.1f}°). " + super()._summary()
        )


def explore_energy(
    model: PendulumModel,
    energy: float | None = None,
    t_end: float = 60.0,
    dt: float = 0.01,
    method="glrk4",
) -> EnergyExplorer:
    """Choose the total energy; see each arm's ``(theta_i, omega_i)`` projection.

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
    """
    model = check_model(model)
    depth = -float(model.potential_energy(np.zeros(model.n)))
    if depth <= 0:
        raise ValueError(f"the model's `g` must be positive, got {model.g}")
    energy = -0.5 * depth if energy is None else float(energy)
    if not -depth < energy <= depth:
        raise ValueError(f"`energy` must lie in ({-depth:.6g}, {depth:.6g}] J, got {energy}")
    ex = EnergyExplorer(model, energy, t_end, dt, method)
    ex.update()
    return ex
