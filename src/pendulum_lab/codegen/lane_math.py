"""Sine and cosine that the compiler can vectorize, for the fields' stage kernels.

An implicit Runge-Kutta step evaluates the field at all its stages at once
(the ``stages`` kernels of :mod:`pendulum_lab.codegen.kernels`), in a loop over
stages that LLVM turns into SIMD instructions, 8 stages per pass. A call to
the C library's ``sin`` stops that: LLVM cannot vectorize an opaque call
(Numba's LLVM has no vector math library). These functions compute the same
values from additions and multiplications alone, without branches, so the
loop vectorizes: the double pendulum's field at 8 stages costs about two
calls of ``hamilton`` (measured).

How: ``x = k pi/2 + r`` with ``|r| <= pi/4`` (Cody and Waite's reduction, with
``pi/2`` split into three parts whose first two have 33 significant bits, so
that ``k`` times them is exact for ``|k| < 2^20``), then the Taylor series of
sine and cosine on ``[-pi/4, pi/4]``, kept up to the degree where the next
term is below a few hundredths of a unit in the last place, and the quadrant
``k mod 4`` to pick and sign the results. The cosine adds ``1 - r^2/2`` in
two parts, so that the rounding of that sum is not lost (as fdlibm's
``__kernel_cos`` does). Both agree with the C library to two units in the
last place for ``|x| <= LIMIT`` (``tests/codegen/test_stage_kernels.py``); larger
arguments lose accuracy, and the stage kernels recompute such stages with
the C library.
"""

from __future__ import annotations

import math

import numba

#: The stages of an implicit step are evaluated in groups of this many
#: (unused ones at the step's start): a ``stages`` kernel's loop is vectorized
#: 8 iterations at a time, whatever the SIMD width (2, 4 or 8 doubles,
#: interleaved), and a shorter loop stays scalar.
LANE_GROUP = 8

#: Arguments up to this size are reduced exactly enough (``k < 2^20``, with margin).
LIMIT = 1.0e5

TWO_OVER_PI = 0.6366197723675814
# pi/2 = HALF_PI_1 + HALF_PI_2 + HALF_PI_3 to 1e-37; the first two have 33 significant bits.
HALF_PI_1 = 1.5707963267341256  # 0x1.921fb544p+0
HALF_PI_2 = 6.077100506303966e-11  # 0x1.0b4611a6p-34
HALF_PI_3 = 2.0222662487959506e-21  # 0x1.3198a2e037073p-69
# Adding and subtracting 1.5 * 2^52 rounds a float below 2^51 to an integer (round to even).
ROUNDING = 6755399441055744.0

# 1/k! for the Taylor series; sine: k = 3, 5, ..., 17; cosine: k = 4, 6, ..., 16.
_S = tuple((-1.0) ** j / math.factorial(2 * j + 1) for j in range(1, 9))
_C = tuple((-1.0) ** j / math.factorial(2 * j) for j in range(2, 9))
S3, S5, S7, S9, S11, S13, S15, S17 = _S
C4, C6, C8, C10, C12, C14, C16 = _C


@numba.njit(inline="always")
def _reduced(x):
    """``(r, k)``: ``x = k pi/2 + r``, ``|r| <= pi/4``, ``k`` a whole number (as a float)."""
    k = (x * TWO_OVER_PI + ROUNDING) - ROUNDING
    return ((x - k * HALF_PI_1) - k * HALF_PI_2) - k * HALF_PI_3, k


@numba.njit(inline="always")
def _sine_cosine_near_zero(r):
    """``(sin r, cos r)`` for ``|r| <= pi/4``."""
    z = r * r
    sine_tail = S5 + z * (S7 + z * (S9 + z * (S11 + z * (S13 + z * (S15 + z * S17)))))
    sine = r + r * z * (S3 + z * sine_tail)
    cosine_tail = z * z * (C4 + z * (C6 + z * (C8 + z * (C10 + z * (C12 + z * (C14 + z * C16))))))
    half = 0.5 * z
    w = 1.0 - half
    cosine = w + (((1.0 - w) - half) + cosine_tail)
    return sine, cosine


@numba.njit(inline="always")
def lane_sincos(x):
    """``(sin x, cos x)``, vectorizable (module docstring); accurate for ``|x| <= LIMIT``."""
    r, k = _reduced(x)
    s, c = _sine_cosine_near_zero(r)
    quarter = k * 0.25
    quadrant = k - 4.0 * math.floor(quarter)  # k mod 4, as 0.0, 1.0, 2.0 or 3.0
    odd = (quadrant == 1.0) | (quadrant == 3.0)
    sine = c if odd else s
    cosine = s if odd else c
    sine = -sine if quadrant >= 2.0 else sine
    cosine = -cosine if (quadrant == 1.0) | (quadrant == 2.0) else cosine
    return sine, cosine


@numba.njit(inline="always")
def lane_sin(x):
    """``sin x``, vectorizable; accurate for ``|x| <= LIMIT``."""
    return lane_sincos(x)[0]


@numba.njit(inline="always")
def lane_cos(x):
    """``cos x``, vectorizable; accurate for ``|x| <= LIMIT``."""
    return lane_sincos(x)[1]
