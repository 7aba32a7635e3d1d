"""The numbers a chain model accepts: how many links, the range of every parameter, and the
parameters a family may vary; each checked with an error that names the argument."""

from __future__ import annotations

import numpy as np

from .. import validation as check

__all__ = [
    "FAMILY_PARAMETERS",
    "MAX_LINKS",
    "MAX_LINKS_REASON",
    "PARAMETER_RANGE",
    "PARAMETER_RANGE_REASON",
    "check_range",
    "link_count",
    "model_number",
]

#: The longest chain a numeric model accepts, and why (measured on unit chains).
MAX_LINKS = 1000
MAX_LINKS_REASON = (
    "longer chains are untested: the mass matrix's condition number grows like n^2 (1.6e6 at "
    "1000 links, where the linear-time solve already loses 5e-12 against a dense one) and its "
    "fastest normal mode like sqrt(n) (about 200 rad/s at 1000 unit links), so the steps an "
    "integrator needs shrink with n")
#: The range of every number of a model (masses, lengths, and the size of g, the damping and
#: the drive), and why.
PARAMETER_RANGE = (1e-9, 1e9)
PARAMETER_RANGE_REASON = (
    "the compiled kernels divide by products such as m l^2 and l1 l2 m2, which must stay far "
    "inside the range of double precision (length = 1e-300 gives m l^2 = 0, a division by "
    "zero); choose units in which the numbers lie in [1e-9, 1e9]")

#: The parameters a family can vary (one number per member).
FAMILY_PARAMETERS = ("damping", "drive_amplitude", "drive_frequency", "g")


def link_count(n) -> int:
    """The number of links ``n``, checked before anything is built for it."""
    n = check.integer_at_least("n", n, 1)
    if n > MAX_LINKS:
        shown = n if n < 10**6 else format(n, ".3g")
        raise ValueError(f"`n` must be at most {MAX_LINKS} links, got {shown}: "
                         f"{MAX_LINKS_REASON}")
    return n


def check_range(name: str, values, positive: bool) -> np.ndarray:
    """``values`` (a number or an array, validated finite) checked against PARAMETER_RANGE:
    ``low <= value <= high`` if ``positive``, else ``|value| <= high``."""
    low, high = PARAMETER_RANGE
    array = np.asarray(values, dtype=float)
    bad = (array < low) | (array > high) if positive else np.abs(array) > high
    if np.any(bad):
        first = float(array[bad].flat[0]) if array.ndim else float(array)
        accepted = f"in [{low:g}, {high:g}]" if positive else f"of size at most {high:g}"
        raise ValueError(f"`{name}` must be {accepted}, got {first:g}: {PARAMETER_RANGE_REASON}")
    return array


def model_number(name: str, value, positive: bool = True) -> float:
    """A model's number, finite and (positive and) within PARAMETER_RANGE."""
    value = check.positive_number(name, value) if positive else check.real_number(name, value)
    check_range(name, value, positive)
    return value
