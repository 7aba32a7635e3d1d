"""Argument checks shared by the modules of :mod:`pendulum_lab.geometric`."""

from __future__ import annotations

from ..model import require_model
from ..model.pendulum import PendulumModel


def conservative_model(model, links=None) -> PendulumModel:
    """``model`` if it is an unforced chain with a number of links in ``links`` (any if None).

    Modified Hamiltonians, exact librations, the standard map and the
    adaptive geometric methods are statements about Hamiltonian motion: a
    damped or driven model gets a ``ValueError`` naming what it has, not a
    silently wrong answer.
    """
    model = require_model(model)
    if model.forced:
        raise ValueError(
            "`model` must be conservative and autonomous (no damping, no drive): this is about "
            f"Hamiltonian motion; got damping {model.damping} and drive amplitude "
            f"{model.drive_amplitude}"
        )
    if links is not None and model.n not in links:
        links = tuple(sorted(links))
        accepted = {(1,): "a simple pendulum (n = 1)",
                    (1, 2): "a simple or a double pendulum (1 or 2 links)"}.get(
            links, f"a chain of {' or '.join(map(str, links))} links")
        raise ValueError(f"`model` must be {accepted} here, got n = {model.n}")
    return model


def simple_pendulum_model(model) -> PendulumModel:
    """``model`` if it is an unforced simple pendulum, else a ``TypeError``/``ValueError``."""
    return conservative_model(model, (1,))
