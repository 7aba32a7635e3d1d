"""The controls the explorers and the simulators share: sliders, dropdowns, their model.

A public internal module: the explorers of :mod:`pendulum_lab.widgets`, the
matplotlib simulator of :mod:`pendulum_lab.animation` and the browser-drawn
instruments of :mod:`pendulum_lab.widgets.live` and
:mod:`pendulum_lab.widgets.clickable` build their panels from these pieces,
and a new instrument should too. Control names are fixed: ``theta1``, ...,
``omega1``, ..., ``m1``, ..., ``l1``, ..., ``g``, ``method``, ``dt``,
``t_end`` (``theta``, ``omega``, ``mass``, ``length`` for one link).

An instrument runs exactly the model it is given: the sliders change its
masses, lengths and ``g``, and its damping and drive stay as they are
(:func:`model_from_controls`). The method dropdown offers the methods
:func:`pendulum_lab.simulate` accepts for that model
(:func:`pendulum_lab.integrators.suitable_methods`, the rule the driver
applies), and a method it refuses is refused here by the driver's own check,
with its reason (:func:`check_method`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import ipywidgets as widgets
import numpy as np
import traitlets
from sympy import pretty

from .. import validation as check
from ..driver.simulate import Trajectory, check_method_fits, hamiltonian_field, step_count
from ..integrators import METHODS, get_method, suitable_methods
from ..model import require_model
from ..model.pendulum import PendulumModel
from ..plotting import link_label
from .calls import SimulateCall

__all__ = [
    "DT_CHOICES",
    "MAX_STEPS",
    "SIMULATOR_T_END",
    "SPEEDS",
    "StepControl",
    "build_simulator",
    "call_from_controls",
    "check_method",
    "check_steps",
    "column",
    "control_names",
    "energy_changers",
    "energy_is_conserved",
    "forces_text",
    "methods_for",
    "model_from_controls",
    "parameter_controls",
    "pendulum_controls",
    "run_controls",
    "simulate_controls",
    "parameter_key",
    "slider",
    "start_state",
    "state_controls",
    "system_state_controls",
    "state_from_controls",
]

#: Step sizes offered by the ``dt`` slider [s] (a logarithmic ladder).
DT_CHOICES = (0.0005, 0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5)
#: Largest number of steps one update may take (``t_end / dt``).
MAX_STEPS = 100_000
#: Playback speeds the simulators offer: simulated seconds per real second.
SPEEDS = (0.25, 0.5, 1.0, 2.0, 4.0)
#: The range of a simulator's run length ``t_end`` [s].
SIMULATOR_T_END = (1.0, 60.0)

DESCRIPTION_WIDTH = "88px"
SLIDER_WIDTH = "310px"


#: The smallest and largest step the ``dt`` box takes [s] (a typed value is clamped).
DT_LIMITS = (1e-5, 1.0)


class StepControl(widgets.HBox):
    """The step ``dt`` [s]: a ladder slider (:data:`DT_CHOICES`, for dragging) and, at its
    right end where a slider shows its value, a box where any step can be typed.

    ``value`` is the step of record: a drag sets it to a rung, a value typed into the box
    (committed by Enter) sets it as typed (clamped to :data:`DT_LIMITS`), and setting it from
    code moves both. Off the ladder, the slider rests on the nearest rung (on a log scale)
    while the box shows the value. (A ``SelectionSlider``'s own value box lets one type but
    does nothing with it: the run was not redone and the box kept the typed text.)
    """

    value = traitlets.Float()

    def __init__(self, value: float, choices=DT_CHOICES, description: str = "Δt (s)"):
        value = float(value)
        self._choices = tuple(sorted({float(c) for c in choices}))
        self.ladder = widgets.SelectionSlider(
            options=[(f"{v:g}", v) for v in self._choices],
            value=self._nearest(value),
            description=description,
            readout=False,
            continuous_update=False,
            style={"description_width": DESCRIPTION_WIDTH},
            layout=widgets.Layout(flex="1 1 auto", width="auto"),
        )
        low, high = DT_LIMITS
        self.box = widgets.BoundedFloatText(
            value=value, min=min(low, value), max=max(high, value), step=None,
            continuous_update=False, layout=widgets.Layout(width="70px"),
        )
        self.box.add_class("plab-step-box")
        super().__init__([self.ladder, self.box], layout=widgets.Layout(width=SLIDER_WIDTH))
        self.add_class("plab-step-control")
        self.value = value
        self._syncing = False
        self.ladder.observe(self._from_ladder, names="value")
        self.box.observe(self._from_box, names="value")
        self.observe(self._to_parts, names="value")

    def _nearest(self, value: float) -> float:
        return min(self._choices, key=lambda rung: abs(math.log(rung / value)))

    def _from_ladder(self, change) -> None:
        if not self._syncing:
            self.value = float(change["new"])

    def _from_box(self, change) -> None:
        if not self._syncing:
            self.value = float(change["new"])

    def _to_parts(self, change) -> None:
        value = float(change["new"])
        self._syncing = True
        try:
            self.box.value = value
            self.ladder.value = self._nearest(value)
        finally:
            self._syncing = False

    @property
    def description(self) -> str:
        return self.ladder.description


def control_names(n: int) -> dict[str, list[str]]:
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


def slider(
    value: float, low: float, high: float, step: float, description: str, fmt: str = ".2f"
) -> widgets.FloatSlider:
    """A float slider whose range always contains ``value``; the unit is in the description.

    The range's ends are rounded inward to whole steps: the browser's slider
    counts its steps from ``min``, so that a step from the keyboard or the
    mouse lands on round values (2.00, 2.01, ...), as its readout shows them,
    not on ``-pi + k step``.
    """
    low = math.ceil(low / step - 1e-9) * step
    high = math.floor(high / step + 1e-9) * step
    return widgets.FloatSlider(
        value=value,
        min=min(low, value),
        max=max(high, value),
        step=step,
        description=description,
        readout_format=fmt,
        continuous_update=False,
        style={"description_width": DESCRIPTION_WIDTH},
        layout=widgets.Layout(width=SLIDER_WIDTH),
    )


def state_controls(
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
    keys = control_names(n)
    controls = {}
    for i, key in enumerate(keys["theta"]):
        controls[key] = slider(
            float(theta0[i]), *angle_range, angle_step, f"{prefix}θ{link_label(i, n)} (rad)", ".3f"
        )
    for i, key in enumerate(keys["omega"]):
        controls[key] = slider(
            float(omega0[i]),
            *speed_range,
            speed_step,
            f"{prefix}ω{link_label(i, n)} (rad/s)",
            ".2f",
        )
    return controls


def system_state_controls(model: PendulumModel, theta0, omega0) -> dict:
    """A system's initial-state sliders, under the keys of :func:`control_names`: an angle
    coordinate in ``[-pi, pi]`` rad, another within two of its scale of the start value
    (``max(1, |q0|)``), each velocity in ``[-10, 10]`` per second."""
    keys = control_names(model.n)
    controls = {}
    for i, (key, name, angle) in enumerate(zip(keys["theta"], model.coordinate_names,
                                               model.angle_coordinates)):
        value = float(theta0[i])
        if angle:
            low, high, unit = -np.pi, np.pi, " (rad)"
        else:
            scale = max(1.0, abs(value))
            low, high, unit = value - 2 * scale, value + 2 * scale, ""
        controls[key] = slider(value, low, high, 0.01, f"{name}{unit}", ".3f")
    for i, (key, name, angle) in enumerate(zip(keys["omega"], model.coordinate_names,
                                               model.angle_coordinates)):
        unit = " (rad/s)" if angle else " (/s)"
        controls[key] = slider(float(omega0[i]), -10, 10, 0.05, f"d{name}/dt{unit}", ".2f")
    return controls


def parameter_key(model: PendulumModel, name: str) -> str:
    """The control name of a system's parameter: its own name, unless a fixed control
    already has it (then ``param_<name>``)."""
    fixed = {"method", "dt", "t_end", *(k for keys in control_names(model.n).values()
                                          for k in keys)}
    return f"param_{name}" if name in fixed else name


def parameter_controls(model: PendulumModel) -> dict:
    """Sliders for masses [kg], lengths [m] and g [m/s^2], starting at the model's values;
    for a system, one slider per parameter, from a tenth to three times its value (a
    parameter at 0 from -1 to 1), named as the system names it."""
    if not model.is_chain:
        controls = {}
        for symbol, value in model.parameter_values.items():
            name = str(symbol)
            if value == 0:
                low, high, step = -1.0, 1.0, 0.01
            else:
                low, high = sorted((0.1 * value, 3.0 * value))
                step = 10.0 ** math.floor(math.log10(abs(value))) / 100
            digits = max(0, -math.floor(math.log10(step)))
            controls[parameter_key(model, name)] = slider(
                value, low, high, step, pretty(symbol, use_unicode=True), f".{digits}f")
        return controls
    n, keys = model.n, control_names(model.n)
    controls = {}
    for i, key in enumerate(keys["mass"]):
        controls[key] = slider(model.masses[i], 0.1, 5.0, 0.05, f"m{link_label(i, n)} (kg)")
    for i, key in enumerate(keys["length"]):
        controls[key] = slider(model.lengths[i], 0.1, 3.0, 0.05, f"l{link_label(i, n)} (m)")
    controls["g"] = slider(model.g, 0.5, 25.0, 0.01, "g (m/s²)")
    return controls


def methods_for(model: PendulumModel) -> list[str]:
    """Names of the methods :func:`pendulum_lab.simulate` accepts for ``model``, in the
    registry's order (every one for a conservative chain; fewer with damping or a drive)."""
    return suitable_methods(hamiltonian_field(model))


def check_method(model: PendulumModel, method) -> str:
    """The name of ``method`` if :func:`pendulum_lab.simulate` accepts it for ``model``.

    Raises
    ------
    ValueError
        For an unknown name, or a method the driver refuses for this model
        (damping that a symplectic or variational method cannot take, a drive
        that a variational method cannot take), with the driver's reason and
        the methods that can.
    """
    method = get_method(method)
    check_method_fits(model, method, hamiltonian_field(model))  # the driver's own check
    return method.name


def energy_is_conserved(model: PendulumModel) -> bool:
    """Whether the exact motion of ``model`` keeps its energy: no damping and no drive."""
    return model.is_conservative and model.is_autonomous


def _system_time_dependence(model) -> tuple[bool, bool]:
    """Whether a system's points move with the time (its Lagrangian reads ``t``), and
    whether its generalized forces read ``t`` (a drive)."""
    system, t = model.system, model.system.t
    return (t in system.lagrangian.free_symbols,
            any(t in force.free_symbols for force in system.generalized_forces))


def energy_changers(model: PendulumModel) -> str:
    """What changes the model's energy, in words (``"the damping and the drive"``, ``"the
    moving point"``: a point the time moves, such as a shaken pivot), or ``""`` for a model
    that conserves it.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> energy_changers(pl.driven_pendulum()), energy_changers(pl.kapitza_pendulum())
    ('the damping and the drive', 'the moving point')
    >>> energy_changers(pl.double_pendulum())
    ''
    """
    if model.is_chain:
        parts = [name for name, present in (("the damping", not model.is_conservative),
                                             ("the drive", not model.is_autonomous)) if present]
    else:
        moving, driven = _system_time_dependence(model)
        parts = [name for name, present in (
            ("the moving point", moving),
            ("the time-dependent forces" if driven else "the forces Q", not model.is_conservative),
        ) if present]
    return " and ".join(parts)


def forces_text(model: PendulumModel) -> str:
    """The model's damping and drive in words, with units (``"no damping, no drive"``).

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> forces_text(pl.driven_pendulum())
    'damping 0.5 N m s/rad, drive 1.2 cos(0.6667 t) N m'
    >>> forces_text(pl.kapitza_pendulum())
    'no damping or applied forces, a point moved with the time (period 0.06283 s)'
    >>> forces_text(pl.elastic_pendulum())
    'no damping or applied forces'
    """
    if not model.is_chain:
        moving, driven = _system_time_dependence(model)
        parts = ["no damping or applied forces" if model.is_conservative
                 else f"forces {model.damping}"]
        period = model.drive_period
        every = "" if period is None else f" (period {period:.4g} s)"
        if moving:
            parts.append("a point moved with the time" + every)
        elif driven:
            parts.append("forces that depend on t" + every)
        return ", ".join(parts)
    coefficients = {float(c) for c in model.damping}
    if model.is_conservative:
        parts = ["no damping"]
    elif len(coefficients) == 1:  # the same at every joint
        parts = [f"damping {coefficients.pop():g} N m s/rad"]
    else:
        parts = ["damping " + ", ".join(f"{float(c):g}" for c in model.damping) + " N m s/rad"]
    if model.is_autonomous:
        parts.append("no drive")
    else:
        parts.append(
            f"drive {float(model.drive_amplitude):g} cos({float(model.drive_frequency):.4g} t) N m"
        )
    return ", ".join(parts)


def run_controls(
    model: PendulumModel, method, t_end: float, dt: float, t_end_range=(0.1, 100.0)
) -> dict:
    """The method dropdown, a ``dt`` ladder slider [s] and a ``t_end`` slider [s].

    The dropdown offers the course's methods (:data:`pendulum_lab.METHODS`)
    that :func:`pendulum_lab.simulate` accepts for ``model``
    (:func:`methods_for`), and ``method`` if it is another one it accepts
    (a conformal or variational method); a ``method`` it refuses raises
    :func:`check_method`'s ``ValueError``.
    """
    name = check_method(model, method)
    dt = check.positive_number("dt", dt)
    choices = sorted(set(DT_CHOICES) | {float(dt)})
    offered = [m for m in methods_for(model) if m in METHODS or m == name]
    return {
        "method": widgets.Dropdown(
            options=offered,
            value=name,
            description="method",
            style={"description_width": DESCRIPTION_WIDTH},
            layout=widgets.Layout(width=SLIDER_WIDTH),
        ),
        "dt": StepControl(float(dt), choices),
        "t_end": slider(float(t_end), *t_end_range, 0.1, "t_end (s)", ".1f"),
    }


def model_from_controls(model: PendulumModel, controls: dict) -> PendulumModel:
    """``model`` with the masses, lengths and ``g`` the parameter controls hold; its damping
    and drive unchanged (cheap: compiled code is shared per number of links). A system's
    parameters are its own sliders' values (its compiled code takes them as arguments)."""
    if not model.is_chain:
        return model.replace(**model.in_factory_units({
            str(s): controls[parameter_key(model, str(s))].value for s in model.parameter_values}))
    keys = control_names(model.n)
    return model.replace(
        masses=tuple(controls[k].value for k in keys["mass"]),
        lengths=tuple(controls[k].value for k in keys["length"]),
        g=controls["g"].value,
    )


def state_from_controls(n: int, controls: dict) -> tuple[np.ndarray, np.ndarray]:
    """The initial angles [rad] and angular velocities [rad/s] the state controls hold.

    Returns
    -------
    theta0, omega0 : ndarray, shape (n,)
    """
    keys = control_names(n)
    return (
        np.array([controls[k].value for k in keys["theta"]], dtype=float),
        np.array([controls[k].value for k in keys["omega"]], dtype=float),
    )


def check_steps(t_end: float, dt: float) -> int:
    """The steps a run of the controls takes, at most :data:`MAX_STEPS`."""
    steps = step_count(t_end, dt)
    if steps > MAX_STEPS:
        raise ValueError(
            f"t_end / dt = {t_end:g} s / {dt:g} s = {steps} steps, more than the explorer's "
            f"limit of {MAX_STEPS}; choose a larger dt or a shorter t_end"
        )
    return steps


def column(title: str, controls: Sequence[widgets.Widget]) -> widgets.VBox:
    """A column of controls under a bold title (one group of an instrument's panel)."""
    return widgets.VBox([widgets.HTML(f"<b>{title}</b>"), *controls])


def start_state(model: PendulumModel, theta0=None, omega0=None) -> tuple[np.ndarray, np.ndarray]:
    """The explorers' starting state: the given one checked, or the default.

    The default is at rest from 1 rad (one link) or from angles spread over
    2.0-2.5 rad (a lively, chaotic release); a system's from its ``start``. Angles must
    lie in [-pi, pi] (a system's other coordinates need only be finite) and velocities in
    [-10, 10] per second, the range of the sliders.
    """
    n = model.n
    if model.is_chain:
        default = [1.0] if n == 1 else np.linspace(2.0, 2.5, n)
        theta0 = check.state_vector("theta0", default if theta0 is None else theta0, n, np.pi,
                                    "rad")
    else:
        theta0 = check.state_vector("theta0", model.start if theta0 is None else theta0, n)
        for i, angle in enumerate(model.angle_coordinates):
            if angle and abs(theta0[i]) > np.pi:
                raise ValueError(f"`theta0[{i}]` ({model.coordinate_names[i]}, an angle) must "
                                 f"lie in [-pi, pi] rad, the sliders' range; got {theta0[i]:g}")
    omega0 = check.state_vector("omega0", np.zeros(n) if omega0 is None else omega0, n, 10.0,
                                "rad/s")
    return theta0, omega0


def call_from_controls(model: PendulumModel, controls: dict, origin=None) -> SimulateCall:
    """The :func:`pendulum_lab.simulate` call that a set of explorer controls describes.

    Parameters
    ----------
    model : PendulumModel
        The instrument's model: its number of links, damping and drive (the
        controls give the rest).
    controls : dict
        Name -> widget, with the initial-state, parameter, ``dt``, ``t_end``
        and ``method`` controls of :func:`explore`.
    origin : callable ``model -> angles``, optional
        If given, the angle controls are offsets from these angles.

    Raises
    ------
    ValueError
        If the run would take more than :data:`MAX_STEPS` steps.
    """
    c = controls
    check_steps(c["t_end"].value, c["dt"].value)
    model = model_from_controls(model, c)
    theta0, omega0 = state_from_controls(model.n, c)
    if origin is not None:
        theta0 = theta0 + origin(model)
    return SimulateCall(model, theta0, omega0, t_end=c["t_end"].value, dt=c["dt"].value,
                        method=c["method"].value)


def simulate_controls(
    model: PendulumModel, controls: dict, origin=None
) -> tuple[PendulumModel, Trajectory]:
    """The model and the trajectory of :func:`call_from_controls` (the same arguments)."""
    call = call_from_controls(model, controls, origin)
    return call.model, call.run()


def pendulum_controls(
    model: PendulumModel,
    theta0,
    omega0,
    *,
    t_end: float,
    dt: float,
    method,
    t_end_range=(0.1, 100.0),
) -> tuple[dict, list[tuple[str, list[str]]]]:
    """The controls of a whole pendulum run and their columns, as :func:`explore` shows them.

    Initial state (:func:`state_controls`), parameters
    (:func:`parameter_controls`) and integration (:func:`run_controls`, with
    ``t_end`` in ``t_end_range`` [s]): the panel of the explorer and of both
    simulators (which pass :data:`SIMULATOR_T_END`).

    Returns
    -------
    controls : dict of str -> ipywidgets widget
    columns : list of (title, list of control names or widgets)
        For :class:`~pendulum_lab.widgets.Instrument`; a model with damping
        or a drive gets a note of them under its parameters.
    """
    n, keys = model.n, control_names(model.n)
    states = (state_controls(n, theta0, omega0) if model.is_chain
              else system_state_controls(model, theta0, omega0))
    controls = {
        **states,
        **parameter_controls(model),
        **run_controls(model, method, t_end, dt, t_end_range=t_end_range),
    }
    parameters = (keys["mass"] + keys["length"] + ["g"] if model.is_chain
                  else [parameter_key(model, str(s)) for s in model.parameter_values])
    if not energy_is_conserved(model):
        # The model's damping and drive are part of it: say so beside the sliders.
        parameters.append(widgets.HTML(f"<i>and fixed: {forces_text(model)}</i>"))
    columns = [
        ("Initial state", keys["theta"] + keys["omega"]),
        ("Parameters", parameters),
        ("Integration", ["method", "dt", "t_end"]),
    ]
    return controls, columns


def build_simulator(
    simulator_class, model, theta0, omega0, *, t_end, dt, method, speed, trail
):
    """Check a simulator's arguments, build it and compute its first run.

    The one entry of both simulators (:func:`pendulum_lab.animation.simulator`
    and :func:`pendulum_lab.widgets.live_simulator`).

    Parameters
    ----------
    simulator_class : type
        Called as ``simulator_class(model, method, t_end, dt, theta0, omega0,
        speed, trail)``; an :class:`~pendulum_lab.widgets.Instrument`.
    model : PendulumModel
    theta0, omega0 : array_like, shape (n,), or None
        As for :func:`start_state` (the default start when None).
    t_end, dt : float
        ``t_end`` in :data:`SIMULATOR_T_END` [s].
    method : str
    speed : float
        One of :data:`SPEEDS`.
    trail : float
        Trail length [s], ``>= 0``.

    Returns
    -------
    Instrument
        The simulator, its first run computed.

    Raises
    ------
    ValueError
        For an argument out of range, or a first run that cannot be computed
        (the simulator's message).
    """
    model = require_model(model)
    model.drawing  # noqa: B018 (a model with nothing to draw is refused here, a TypeError)
    theta0, omega0 = start_state(model, theta0, omega0)
    speed = check.choice("speed", speed, SPEEDS)
    trail = check.non_negative_number("trail", trail)
    t_end = check.number_in("t_end", t_end, *SIMULATOR_T_END, "s")
    sim = simulator_class(model, method, t_end, dt, theta0, omega0, speed, trail)
    if not sim.update():
        raise ValueError(sim.message)
    return sim
