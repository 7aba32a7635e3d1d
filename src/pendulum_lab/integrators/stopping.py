"""The stopping rule of every implicit equation the integrators solve: iterate to round-off.

A tolerance would stop on a small but still shrinking increment, and an implicit
Runge-Kutta method whose stage equations are not solved to round-off drifts in energy
[HMR]_. The rule here stops when no component's increment decreases any more (it only
jitters at round-off), or when the observed contraction predicts that the remaining
corrections are below half a unit in the last place.

References
----------
.. [HMR] E. Hairer, R. I. McLachlan, A. Razakarivony, "Achieving Brouwer's law with
   implicit Runge-Kutta methods", BIT 48 (2008) 231-243.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ..codegen.lowlevel import bits_float, float_bits, inline_into_callers

__all__ = [
    "EPSILON",
    "MAX_SWEEPS",
    "ROUNDOFF_TOLERANCE",
    "fixed_point_status",
    "roundoff_status",
]

MAX_SWEEPS = 100
# A stalled iteration counts as converged only if its last increment is this
# small relative to the unknowns (or to the floor the caller gives, see
# fixed_point_status): stalling far from round-off means divergence.
ROUNDOFF_TOLERANCE = 1e-11
EPSILON = np.finfo(np.float64).eps


@numba.njit
def fixed_point_status(new, old, smallest, floor=0.0):
    """The stopping rule of every implicit solve here, applied per component.

    ``new`` and ``old`` are successive iterates (1-d arrays) and ``smallest``
    holds each component's smallest increment so far (updated in place).
    ``floor`` is added to every component's size where "tiny" is judged
    (below): unknowns whose round-off is set by larger numbers they are
    combined with, as the slopes of :func:`implicit_rk`, need it. A
    component is done when its increment did not fall below its smallest
    earlier one (it only jitters at round-off now), or when the iteration's
    observed contraction predicts that all its further corrections together
    stay below half a unit in its last place. Returns ``1`` when every component is done
    and all increments are tiny, ``0`` to continue, and ``-1`` if an iterate is
    not finite. Unlike a tolerance, this cannot stop on a small but still
    shrinking increment and needs no tuning to the problem; the prediction
    saves the sweeps a plain stall test would spend at round-off.
    """
    # Most sweeps are far from round-off: a first pass finds that out (and
    # whether all is finite) and records the smallest increments; the full
    # test runs only on the last few sweeps. The loops are written without
    # branches (`&`, `|`, conditional expressions): this rule runs once per
    # sweep and, with data-dependent branches, cost as much as a stage.
    inline_into_callers()
    small, finite = True, True
    for i in range(new.size):
        x = new[i]
        finite &= math.isfinite(x)
        small &= abs(x - old[i]) <= ROUNDOFF_TOLERANCE * (1.0 + floor + abs(x))
    if not finite:
        return -1
    if not small:
        for i in range(new.size):
            smallest[i] = min(smallest[i], abs(new[i] - old[i]))
        return 0
    return roundoff_status(new, old, smallest)


@numba.njit(error_model="numpy")  # x / 0 is inf, as intended below, not ZeroDivisionError
def roundoff_status(new, old, smallest):
    """:func:`fixed_point_status` once every increment is tiny: stalled, or predicted done?"""
    # rate: the largest ratio of an increment to the one before it, over the
    # components whose previous increment was well above round-off (below
    # that, ratios are noise); unknown on the first sweep or if none qualifies.
    # worst: the largest relative increment among components still improving.
    # Every quantity is computed for every component and then selected, with
    # no branch and no running comparison between components, so that the
    # loop vectorizes (a chain of selects from one component to the next,
    # as an earlier version had, does not; docs/design/stage-iteration.md). Both
    # maxima are taken over the quantities' bits as integers: they are never
    # negative, so their bits order as they do, and LLVM vectorizes an
    # integer maximum but not a floating-point one, whose NaN rules forbid
    # reordering it (codegen.lowlevel says what it buys).
    inline_into_callers()
    rate_bits, worst_bits = 0, 0
    measured, first = False, False
    for i in range(new.size):
        x = new[i]
        delta, previous, size = abs(x - old[i]), smallest[i], abs(x)
        unknown = math.isinf(previous)
        counts = (not unknown) & (previous > 256.0 * EPSILON * size)
        first |= unknown
        measured |= counts
        # the divisors are replaced where the quotient is not used (no 0 / 0)
        ratio = delta / (previous if counts else 1.0)
        rate_bits = max(rate_bits, float_bits(ratio if counts else 0.0))
        improving = delta < previous
        smallest[i] = delta if improving else previous
        grows = improving & (delta > 0.0)  # size 0: an infinite relative increment
        relative = delta / (size if grows else 1.0)
        worst_bits = max(worst_bits, float_bits(relative if grows else 0.0))
    rate, worst = bits_float(rate_bits), bits_float(worst_bits)
    if worst == 0.0:  # every component stalled or exactly unchanged
        return 1
    # the improving ones are done if rate / (1 - rate) * worst < half an ulp
    done = (measured and not first and rate < 1.0
            and rate * worst <= 0.5 * EPSILON * (1.0 - rate))
    return 1 if done else 0
