"""What a picture of a model shows (:class:`Drawing`), the same for chains and systems, and
where a chain's bobs are (:class:`ChainDrawing`): their positions, the chain's picture, the
angles after a bob is dragged."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import validation as check

__all__ = ["ChainDrawing", "Drawing"]


@dataclass(frozen=True)
class Drawing:
    """What a picture of a model shows: its points, and which of them are joined.

    The drawings, the animations and the live simulator read this, and the points'
    positions from ``model.positions(theta, t)``; a chain and a system given by its points
    are drawn by the same code.

    Attributes
    ----------
    masses : tuple of float
        One per point [kg]; a point of mass 0 (a moving pivot) is drawn as a small mark.
    rods, springs : tuple of (int, int)
        Pairs of points joined by a rod or by a spring; ``-1`` is the fixed origin.
    movable : tuple of (str or None)
        One per point: None where dragging the point places the coordinates
        (:meth:`PendulumModel.place_point`), else the sentence that says why it cannot.
    reach : float or None
        Half the width of a square view that holds every configuration [m] (a chain's
        length); None where only the motion tells (the view is fitted to it).
    """

    masses: tuple
    rods: tuple
    springs: tuple = ()
    movable: tuple = ()
    reach: float | None = None

    @property
    def uses_origin(self) -> bool:
        """Whether a rod or a spring hangs from the fixed origin (drawn as the pivot)."""
        return any(-1 in pair for pair in (*self.rods, *self.springs))


class ChainDrawing:
    """A chain's bobs in the plane (a base of :class:`~pendulum_lab.PendulumModel`).

    A subclass has ``n``, ``masses``, ``lengths`` and ``_states`` (the states checked).
    """

    #: A chain swings in a plane: its positions are ``(x, y)``.
    dimensions = 2

    def positions(self, theta, t=None) -> tuple[np.ndarray, np.ndarray]:
        """Cartesian bob positions ``(x, y)``, each shape ``(..., n)``, pivot at the origin
        (``t`` is accepted for the protocol a :class:`~pendulum_lab.model.SystemModel`
        shares; a chain's pivot does not move)."""
        theta = self._states("theta", theta)
        lengths = np.stack(np.broadcast_arrays(*self.lengths), axis=-1)
        return (np.cumsum(lengths * np.sin(theta), axis=-1),
                -np.cumsum(lengths * np.cos(theta), axis=-1))

    @property
    def angle_coordinates(self) -> tuple[bool, ...]:
        """For each coordinate, whether it is an angle (every one of a chain's)."""
        return (True,) * self.n

    @property
    def drawing(self) -> Drawing:
        """The chain's picture: the bobs joined by rods, the first to the pivot."""
        n = self.n
        return Drawing(masses=tuple(float(m) for m in self.masses),
                       rods=tuple((i - 1, i) for i in range(n)), movable=(None,) * n,
                       reach=float(sum(self.lengths)))

    def place_point(self, point: int, x: float, y: float, theta, t: float = 0.0) -> np.ndarray:
        """The angles after bob ``point`` (0-based) is dragged to ``(x, y)`` [m].

        The bob moves on its circle around the joint before it, to the point of the circle
        in the direction of ``(x, y)`` (a rod does not stretch: a point beyond reach is
        clamped onto the circle); the other arms keep their angles ``theta``.

        Raises
        ------
        ValueError
            If ``(x, y)`` is the joint itself (it gives the arm no direction).
        """
        theta = self._states("theta", theta)
        point = check.index_below("point", point, self.n)
        x, y = check.real_number("x", x), check.real_number("y", y)
        joint_x, joint_y = 0.0, 0.0
        if point > 0:
            xs, ys = self.positions(theta)
            joint_x, joint_y = float(xs[point - 1]), float(ys[point - 1])
        dx, dy = x - joint_x, y - joint_y
        if math.hypot(dx, dy) <= 1e-9 * sum(self.lengths):
            raise ValueError(f"the release point ({x:.3g}, {y:.3g}) m is the joint of arm "
                             f"{point + 1}: it gives the arm no direction")
        angles = np.array(theta, dtype=float)
        # theta is measured from the downward vertical: (x, y) = l (sin theta, -cos theta).
        angles[point] = math.atan2(dx, -dy)
        return angles
