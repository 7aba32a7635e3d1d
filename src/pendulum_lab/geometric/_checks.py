"""Argument checks shared by the modules of :mod:`pendulum_lab.geometric`."""

from __future__ import annotations

from .._validation import pendulum_model as check_model
from ..model import PendulumModel


def simple_pendulum_model(model) -> PendulumModel:
    """``model`` if it is a simple pendulum, else a ``TypeError``/``ValueError`` naming it."""
    model = check_model(model)
    if model.n != 1:
        raise ValueError(f"`model` must be a simple pendulum (n = 1), got n = {model.n}")
    return model
