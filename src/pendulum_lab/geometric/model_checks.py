"""Argument checks shared by the modules of :mod:`pendulum_lab.geometric`."""

from __future__ import annotations

from ..model import require_chain, require_model
from ..model.pendulum import PendulumModel


def conservative_model(model, links=None, *, chain: bool = False) -> PendulumModel:
    """``model`` if it is conservative and autonomous, with a number of links in ``links``.

    Modified Hamiltonians, exact librations, the standard map and the
    adaptive geometric methods are statements about Hamiltonian motion with
    a Hamiltonian that does not depend on the time: a damped, driven or
    shaken model gets a ``ValueError`` naming what it has, not a silently
    wrong answer. ``links`` (any number if None) limits the number of
    coordinates; with ``chain`` (the formulas of a chain's rods), a system
    that is not a chain gets a ``TypeError``.
    """
    model = require_model(model)
    if model.forced or not model.is_autonomous:
        has = (f"damping {model.damping} and drive amplitude {model.drive_amplitude}"
               if model.is_chain else
               f"forces {model.damping}, and equations that "
               f"{'do not ' if model.is_autonomous else ''}depend on the time")
        raise ValueError(
            "`model` must be conservative and autonomous (no damping, no drive, no moving "
            f"pivot): this is about Hamiltonian motion with a constant H; got {has}"
        )
    if chain:
        require_chain(model, "the formulas used here are those of a chain's rods")
    if links is not None and model.n not in links:
        links = tuple(sorted(links))
        accepted = {(1,): "a simple pendulum (n = 1)",
                    (1, 2): "a simple or a double pendulum (1 or 2 links)"}.get(
            links, f"a chain of {' or '.join(map(str, links))} links")
        raise ValueError(f"`model` must be {accepted} here, got n = {model.n}")
    return model


def simple_pendulum_model(model) -> PendulumModel:
    """``model`` if it is an unforced simple pendulum, else a ``TypeError``/``ValueError``."""
    return conservative_model(model, (1,), chain=True)
