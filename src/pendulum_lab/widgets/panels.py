"""Extra panels for :func:`pendulum_lab.widgets.explore`: callables ``(ax, trajectory, model)``.

The basic panels (energy, angles, phase space, ...) are
:data:`pendulum_lab.plotting.PANELS`; the ones here run a computation of
their own from the explorer's trajectory.
"""

from __future__ import annotations

from ..chaos import separation
from ..driver.simulate import Trajectory
from ..model.pendulum import PendulumModel

__all__ = ["separation_panel"]


def separation_panel(ax, trajectory: Trajectory, model: PendulumModel) -> None:
    """The separation from the trajectory's start (:func:`pendulum_lab.chaos.separation`).

    Runs from the trajectory's initial state, with its method, step and
    duration, and draws the distance on a log scale with a dashed line at the
    initial distance.
    """
    sep = separation(
        model,
        trajectory.theta[0],
        p0=trajectory.p[0],
        t_end=trajectory.t[-1] - trajectory.t[0],
        dt=trajectory.dt,
        method=trajectory.method,
        progress=False,
    )
    sep.plot(ax=ax, color="tab:red", lw=1)
    ax.axhline(sep.delta, color="0.6", lw=0.8, ls="--")
    ax.set_title(f"Separation from a start {sep.delta:g} away")
