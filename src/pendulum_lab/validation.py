"""Checks of user input at the public boundary; each error names the argument.

Every public function of the package validates its arguments with these
helpers, so that a wrong value gives a ``TypeError`` or ``ValueError`` that
says which argument was wrong and what is accepted, before any work starts.
"""

from __future__ import annotations

import ctypes
import numbers
import os
import sys
from pathlib import Path

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
        raise ValueError(f"`{name}` must be a positive number (> 0), got {value}")
    return value


def non_negative_number(name: str, value) -> float:
    """``value`` as a finite float >= 0."""
    value = real_number(name, value)
    if value < 0:
        raise ValueError(f"`{name}` must be a number >= 0, got {value}")
    return value


def number_in(name: str, value, low: float, high: float, unit: str = "",
              open_low: bool = False) -> float:
    """``value`` as a float in ``[low, high]`` (``(low, high]`` with ``open_low``)."""
    value = real_number(name, value)
    if value > high or value < low or (open_low and value == low):
        bracket = "(" if open_low else "["
        unit = f" {unit}" if unit else ""
        raise ValueError(f"`{name}` must be in {bracket}{low:.6g}, {high:.6g}]{unit}, got {value}")
    return value


def integer_at_least(name: str, value, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"`{name}` must be an integer >= {minimum}, got {value!r}")
    if value < minimum:
        raise ValueError(f"`{name}` must be an integer >= {minimum}, got {value}")
    return int(value)


def seed(name: str, value) -> int | None:
    """A seed of NumPy's random generator as the package takes it: None or an integer >= 0."""
    if value is None:
        return None
    accepted = f"`{name}` must be an integer >= 0 or None (a fresh random choice), got {value!r}"
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(accepted)
    if value < 0:
        raise ValueError(accepted)
    return int(value)


def index_below(name: str, value, size: int) -> int:
    """An integer in ``[0, size - 1]`` (a 0-based link number)."""
    value = integer_at_least(name, value, 0)
    if value >= size:
        raise ValueError(f"`{name}` must be in [0, {size - 1}], got {value}")
    return value


def choice(name: str, value, allowed):
    """``value`` itself if it is one of ``allowed``."""
    allowed = list(allowed)
    if isinstance(value, bool) or value not in allowed:
        options = (" or ".join(map(repr, allowed)) if len(allowed) == 2
                   else f"one of {allowed}")
        raise ValueError(f"`{name}` must be {options}, got {value!r}")
    return value


def choices(name: str, values, allowed) -> tuple:
    """A non-empty selection from ``allowed`` (a string counts as one item), repeats dropped."""
    if isinstance(values, str):
        values = [values]
    values = tuple(dict.fromkeys(values))  # drop repeats, keep order
    if not values:
        raise ValueError(f"`{name}` must name at least one of {list(allowed)}")
    for value in values:
        if value not in allowed:
            raise ValueError(f"`{name}` must be among {list(allowed)}, got {value!r}")
    return values


def _entries(name: str, values, n: int, kind: str) -> list:
    """The ``n`` entries of a sequence, or an error naming ``name`` and what it must hold."""
    try:
        items = list(values)
    except TypeError:
        raise TypeError(f"`{name}` must be a sequence of {n} {kind}") from None
    if len(items) != n:
        raise ValueError(f"`{name}` must have {n} entries (one per link), got {len(items)}")
    return items


def real_array(name: str, values) -> np.ndarray:
    """``values`` as a non-empty array of finite floats (any shape)."""
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"`{name}` must hold real numbers") from None
    if array.size == 0:
        raise ValueError(f"`{name}` must hold at least one value")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"`{name}` must be finite, got {array[~np.isfinite(array)][0]}")
    return array


def real_sequence(name: str, values) -> np.ndarray:
    """``values`` as a 1-d array of finite floats, at least one."""
    array = real_array(name, values)
    if array.ndim != 1:
        raise ValueError(f"`{name}` must be a 1-d sequence of numbers, got shape {array.shape}")
    return array


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
            f"`{name}` must have shape (..., {n}), "
            f"got shape {arr.shape}"
        )
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"All components of `{name}` must be finite.")
    return arr


def state_vector(name: str, value, n: int, bound: float | None = None, unit: str = ""):
    """One state: shape ``(n,)``, finite, and with ``|x| <= bound`` if a bound is given."""
    arr = state_array(name, value, n)
    if arr.shape != (n,):
        raise ValueError(f"`{name}` must be {n} finite number(s) (one state), got shape "
                         f"{arr.shape}")
    if bound is not None and np.any(np.abs(arr) > bound):
        unit = f" {unit}" if unit else ""
        raise ValueError(f"`{name}` entries must lie in [-{bound:g}, {bound:g}]{unit}, got {arr}")
    return arr


def same_shape(name_a: str, a: np.ndarray, name_b: str, b: np.ndarray) -> None:
    if a.shape != b.shape:
        raise ValueError(
            f"`{name_a}` and `{name_b}` must have the same shape, got {a.shape} and {b.shape}"
        )


def output_folder(name: str, value) -> Path:
    """A folder that exists (created with its parents if missing) and can be written to."""
    try:
        path = Path(value)
    except TypeError:
        raise TypeError(f"`{name}` must be a path, got {type(value).__name__}") from None
    if path.exists() and not path.is_dir():
        raise ValueError(f"`{name}` must be a folder, but {str(path)!r} is a file")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise ValueError(
            f"`{name}` must be a folder that can be created, but {str(path)!r} cannot be "
            f"({err.strerror or err})"
        ) from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise ValueError(f"`{name}` must be a folder you can write to, but {str(path)!r} is not")
    return path


def physical_memory() -> int | None:
    """Bytes of RAM of this machine, or None where the system does not say.

    Windows: ``GlobalMemoryStatusEx``; Linux and macOS: ``sysconf`` (pages times page size).
    """
    if sys.platform == "win32":
        status = _windows_memory_status()
        return None if status is None else status[0]
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        return None


def available_memory() -> int | None:
    """Bytes of memory available to a new computation now, else :func:`physical_memory`.

    Linux: ``MemAvailable`` of ``/proc/meminfo`` (free memory plus the caches the system can
    drop); Windows: ``GlobalMemoryStatusEx``'s available physical memory; macOS, and Linux
    without ``/proc`` (some sandboxes): the physical memory, which at least bounds it.
    """
    if sys.platform == "win32":
        status = _windows_memory_status()
        if status is not None:
            return status[1]
    elif sys.platform.startswith("linux"):
        try:
            with open(MEMINFO, encoding="ascii") as info:
                for line in info:
                    if line.startswith("MemAvailable:"):
                        return int(line.split()[1]) * 1024
        except (OSError, ValueError, IndexError):
            pass
    return physical_memory()


#: Linux's memory figures (absent on macOS and Windows, and in some sandboxes).
MEMINFO = "/proc/meminfo"


class _MemoryStatus(ctypes.Structure):
    """Windows' ``MEMORYSTATUSEX``, filled by ``GlobalMemoryStatusEx``."""

    _fields_ = [("dwLength", ctypes.c_uint32), ("dwMemoryLoad", ctypes.c_uint32),
                *((name, ctypes.c_uint64) for name in (
                    "ullTotalPhys", "ullAvailPhys", "ullTotalPageFile", "ullAvailPageFile",
                    "ullTotalVirtual", "ullAvailVirtual", "ullAvailExtendedVirtual"))]


def _windows_memory_status() -> tuple[int, int] | None:
    """``(total, available)`` bytes of physical memory on Windows, or None if it fails."""
    status = _MemoryStatus()
    status.dwLength = ctypes.sizeof(_MemoryStatus)
    try:
        filled = ctypes.windll.kernel32.GlobalMemoryStatusEx(ctypes.byref(status))
    except (AttributeError, OSError):
        return None
    if not filled or status.ullTotalPhys == 0:
        return None
    return int(status.ullTotalPhys), int(status.ullAvailPhys)


def bytes_text(size: float) -> str:
    """``"3.2 GB"``: a byte count for a message."""
    units = ("bytes", "kB", "MB", "GB", "TB", "PB", "EB", "ZB", "YB")
    for unit in units:
        if size < 1000 or unit == units[-1]:
            break
        size /= 1000
    return f"{size:.3g} {unit}"


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
