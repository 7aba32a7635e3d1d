"""Checks of user input at the public boundary; each error names the argument."""

from __future__ import annotations

import numbers

import numpy as np


def real_number(name: str, value) -> float:
    """``value`` as a finite float, or a ``TypeError``/``ValueError`` naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"`{name}` must be a real number, got {type(value).__name__}")
    value = float(value)
    if not np.isfinite(value):
        raise ValueError(f"`{name}` must be finite, got {value}")
    return value


def positive_number(name: str, value) -> float:
    """``value`` as a finite float > 0."""
    value = real_number(name, value)
    if value <= 0:
        raise ValueError(f"`{name}` must be positive (> 0), got {value}")
    return value


def integer_at_least(name: str, value, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"`{name}` must be an integer >= {minimum}, got {value!r}")
    if value < minimum:
        raise ValueError(f"`{name}` must be an integer >= {minimum}, got {value}")
    return int(value)


def _entries(name: str, values, n: int, kind: str) -> list:
    """The ``n`` entries of a sequence, or an error naming ``name`` and what it must hold."""
    try:
        items = list(values)
    except TypeError:
        raise TypeError(f"`{name}` must be a sequence of {n} {kind}") from None
    if len(items) != n:
        raise ValueError(f"`{name}` must have {n} entries (one per link), got {len(items)}")
    return items


def positive_vector(name: str, values, n: int) -> tuple[float, ...]:
    """A sequence of ``n`` finite positive numbers."""
    items = _entries(name, values, n, "positive numbers")
    return tuple(positive_number(f"{name}[{i}]", v) for i, v in enumerate(items))


def state_array(name: str, value, n: int) -> np.ndarray:
    """An array of shape ``(..., n)`` of finite floats (angles, velocities, momenta)."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"`{name}` must be an array of real numbers of shape (..., {n})") from None
    if arr.ndim == 0 and n == 1:
        arr = arr.reshape(1)
    if arr.ndim == 0 or arr.shape[-1] != n:
        raise ValueError(
            f"`{name}` must have shape (..., {n}) for a model with {n} link(s), "
            f"got shape {arr.shape}"
        )
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"All components of `{name}` must be finite.")
    return arr


def nonnegative_number(name: str, value) -> float:
    """``value`` as a finite float >= 0."""
    value = real_number(name, value)
    if value < 0:
        raise ValueError(f"`{name}` must be non-negative (>= 0), got {value}")
    return value


def nonnegative_vector(name: str, values, n: int) -> tuple[float, ...]:
    """One finite number >= 0 (then the same for all ``n`` entries) or a sequence of ``n``."""
    if isinstance(values, numbers.Real) and not isinstance(values, bool):
        return (nonnegative_number(name, values),) * n
    if isinstance(values, str):
        raise TypeError(f"`{name}` must be a number or a sequence of {n} numbers >= 0")
    items = _entries(name, values, n, "numbers >= 0")
    return tuple(nonnegative_number(f"{name}[{i}]", v) for i, v in enumerate(items))
