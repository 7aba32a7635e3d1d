"""The run behind an instrument's picture, as a value and as code ("copy as code").

An instrument prepares a :class:`SimulateCall` from its controls (the
model, the initial state, ``t_end``, ``dt`` and the method), runs it, and
offers its :meth:`~SimulateCall.code`: the ``pl.simulate(...)`` call that a
student pastes into a cell to get the same trajectory, number for number
(every float is written with ``repr``, which reads back exactly), followed by the
plotting call that draws it as the instrument does (:func:`panels_code` for panels), the
figure as the cell's last value so that the pasted cell shows it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..driver.simulate import Trajectory, simulate
from ..model import PendulumModel

__all__ = ["SimulateCall", "model_code", "numbers", "panels_code"]


def numbers(values) -> str:
    """A list of floats as Python source that reads back exactly.

    >>> numbers([2.0, 0.1 + 0.2])
    '[2.0, 0.30000000000000004]'
    """
    return "[" + ", ".join(repr(float(v)) for v in np.ravel(values)) + "]"


def model_code(model: PendulumModel) -> str:
    """The ``pl.<factory>(...)`` call that builds ``model`` again, parameters included.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> model_code(pl.double_pendulum(m2=0.5))
    'pl.double_pendulum(m1=1.0, m2=0.5, l1=1.0, l2=1.0, g=9.81)'
    >>> model_code(pl.driven_pendulum(drive_amplitude=1.5))
    'pl.driven_pendulum(damping=0.5, drive_amplitude=1.5, drive_frequency=0.6666666666666666, \
mass=1.0, length=1.0, g=1.0)'

    A system is built again by its factory (or, for one a student built with
    ``pl.mechanical_system``, from the variable ``model`` holding it) with its parameters
    replaced by name:

    >>> model_code(pl.cart_pendulum(mass=0.25))
    "pl.cart_pendulum().replace(**{'M': 1.0, 'm': 0.25, 'l': 1.0, 'g': 9.81})"
    """
    if not model.is_chain:
        values = model.in_factory_units({str(s): float(v)
                                         for s, v in model.parameter_values.items()})
        return f"{model.factory or 'model'}.replace(**{values!r})"
    masses, lengths = [float(m) for m in model.masses], [float(v) for v in model.lengths]
    g = float(model.g)
    forces = []
    if not model.is_conservative:
        damping = {float(c) for c in model.damping}
        forces.append(f"damping={damping.pop()!r}" if len(damping) == 1
                      else f"damping={numbers(model.damping)}")
    if not model.is_autonomous:
        forces.append(f"drive_amplitude={float(model.drive_amplitude)!r}")
    if model.drive_frequency is not None:
        forces.append(f"drive_frequency={float(model.drive_frequency)!r}")
    if model.n == 1:
        if not forces:
            return f"pl.simple_pendulum(mass={masses[0]!r}, length={lengths[0]!r}, g={g!r})"
        damping = float(model.damping[0])
        drive = float(model.drive_amplitude)
        frequency = None if model.drive_frequency is None else float(model.drive_frequency)
        return (f"pl.driven_pendulum(damping={damping!r}, drive_amplitude={drive!r}, "
                f"drive_frequency={frequency!r}, mass={masses[0]!r}, length={lengths[0]!r}, "
                f"g={g!r})")
    extra = "".join(", " + part for part in forces)
    if model.n == 2:
        return (f"pl.double_pendulum(m1={masses[0]!r}, m2={masses[1]!r}, l1={lengths[0]!r}, "
                f"l2={lengths[1]!r}, g={g!r}{extra})")
    return (f"pl.n_pendulum({model.n}, masses={numbers(masses)}, lengths={numbers(lengths)}, "
            f"g={g!r}{extra})")


def panels_code(panels, columns: int | None = None) -> str:
    """Source that draws ``traj`` of ``model`` in the explorers' panels, one axes each, in
    ``columns`` columns (all in one row by default); the figure is its last line's value.

    ``panels``: names of :data:`pendulum_lab.plotting.PANELS` or functions
    ``(ax, traj, model)`` (written by their name, as the student defined them).

    Examples
    --------
    >>> print(panels_code(["pendulum", "energy"]))
    # The picture: each panel drawn into its axes
    fig, axes = pl.plotting.new_figure(1, 2, width=12.0)
    panels = [pl.plotting.PANELS['pendulum'], pl.plotting.PANELS['energy']]
    for ax, panel in zip(fig.axes, panels):
        panel(ax, traj, model)
    fig
    <BLANKLINE>
    """
    drawers = [f"pl.plotting.PANELS[{panel!r}]" if isinstance(panel, str)
               else getattr(panel, "__name__", "my_panel") for panel in panels]
    columns = columns or len(drawers)
    rows = -(-len(drawers) // columns)
    spare = ("for ax in fig.axes[len(panels):]:\n    ax.remove()  # a grid cell left empty\n"
             if rows * columns > len(drawers) else "")
    return ("# The picture: each panel drawn into its axes\n"
            f"fig, axes = pl.plotting.new_figure({rows}, {columns}, width=12.0)\n"
            f"panels = [{', '.join(drawers)}]\n"
            "for ax, panel in zip(fig.axes, panels):\n"
            "    panel(ax, traj, model)\n"
            f"{spare}fig\n")


@dataclass(frozen=True)
class SimulateCall:
    """One :func:`pendulum_lab.simulate` call: what an instrument runs and what it copies.

    Attributes
    ----------
    model : PendulumModel
    theta0, omega0 : ndarray, shape (n,)
        Initial angles [rad] and angular velocities [rad/s].
    t_end, dt : float
        Duration and step [s].
    method : str
        A method's name.
    """

    model: PendulumModel
    theta0: np.ndarray
    omega0: np.ndarray
    t_end: float
    dt: float
    method: str

    def run(self) -> Trajectory:
        """The trajectory (no progress bar: an instrument reports in its status line)."""
        return simulate(self.model, self.theta0, self.omega0, t_end=self.t_end, dt=self.dt,
                        method=self.method, progress=False)

    def arguments(self) -> str:
        """The call's arguments after ``model``, as source."""
        return (f"{numbers(self.theta0)}, {numbers(self.omega0)}, t_end={float(self.t_end)!r}, "
                f"dt={float(self.dt)!r}, method={self.method!r}")

    def code(self, drawing: str = "") -> str:
        """Source that computes the same trajectory, as ``traj``, then ``drawing`` (source
        that draws it, such as :func:`panels_code`), after an empty line.

        Examples
        --------
        >>> import numpy as np, pendulum_lab as pl
        >>> call = SimulateCall(pl.simple_pendulum(), np.array([1.0]), np.array([0.0]),
        ...                     t_end=2.0, dt=0.01, method="rk4")
        >>> print(call.code())
        import pendulum_lab as pl
        <BLANKLINE>
        model = pl.simple_pendulum(mass=1.0, length=1.0, g=9.81)
        traj = pl.simulate(model, [1.0], [0.0], t_end=2.0, dt=0.01, method='rk4')
        <BLANKLINE>
        """
        return (
            "import pendulum_lab as pl\n\n"
            f"model = {model_code(self.model)}\n"
            f"traj = pl.simulate(model, {self.arguments()})\n"
        ) + ("\n" + drawing if drawing else "")
