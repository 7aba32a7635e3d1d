"""The stopping rule of every implicit solve: its vectorized round-off test against exact
arithmetic, the bit casts it takes its maxima over, and a component moving off zero."""

import math
from fractions import Fraction

import numba
import numpy as np

from pendulum_lab.codegen.lowlevel import bits_float, float_bits
from pendulum_lab.integrators.stopping import EPSILON, roundoff_status

RNG = np.random.default_rng(20261201)


def reference_roundoff_status(new, old, smallest):
    """The rule of ``_roundoff_status`` in exact rational arithmetic (a plain-Python oracle)."""
    rate, worst, measured, first = Fraction(0), Fraction(0), False, False
    updated = smallest.copy()
    for x, y, previous in zip(new, old, smallest):
        delta, size = abs(x - y), abs(x)
        unknown = math.isinf(previous)
        first |= unknown
        if not unknown and previous > 256.0 * EPSILON * size:
            measured = True
            rate = max(rate, Fraction(delta) / Fraction(previous))
        if delta < previous and delta > 0.0:
            worst = max(worst, Fraction(delta) / Fraction(size) if size else math.inf)
    for i, (x, y) in enumerate(zip(new, old)):
        updated[i] = min(abs(x - y), smallest[i])
    if worst == 0:
        return 1, updated
    # an infinite relative increment (a component of size 0 still moving) is never done
    done = (measured and not first and rate < 1 and worst != math.inf
            and rate * worst <= Fraction(EPSILON) / 2 * (1 - rate))
    return (1 if done else 0), updated


def test_vectorized_stopping_rule_decides_as_the_exact_rule():
    decisions = {0: 0, 1: 0}
    for _ in range(3000):
        new = RNG.uniform(-3, 3, 24)
        scale = RNG.choice([1e-18, 1e-17, 1e-16, 1e-15, 1e-14, 1e-13], 24)
        old = new * (1 + scale * RNG.choice([-1.0, 1.0], 24))
        smallest = RNG.choice([np.inf, 1e-13, 1e-14, 1e-15, 3e-16, 1e-16, 0.0], 24)
        got_smallest = smallest.copy()
        got = roundoff_status(new, old, got_smallest)
        expected, expected_smallest = reference_roundoff_status(new, old, smallest)
        assert got == expected
        np.testing.assert_array_equal(got_smallest, expected_smallest)
        decisions[got] += 1
    # both outcomes occur, so the comparison covers both
    assert min(decisions.values()) > 20


@numba.njit
def _bits_and_back(xs):
    bits = np.empty(xs.size, np.int64)
    back = np.empty_like(xs)
    for i in range(xs.size):
        bits[i] = float_bits(xs[i])
        back[i] = bits_float(bits[i])
    return bits, back


def test_the_stopping_rule_takes_maxima_over_bits_that_order_as_the_numbers():
    # roundoff_status takes its maxima over the bits of non-negative floats as integers
    xs = np.concatenate([[0.0, 5e-324, 1e-300, EPSILON, 1.0, 1e300, np.inf],
                         RNG.uniform(0.0, 10.0, 2000) * 10.0 ** RNG.integers(-300, 300, 2000)])
    bits, back = _bits_and_back(xs)
    np.testing.assert_array_equal(back, xs)
    np.testing.assert_array_equal(np.argsort(bits, kind="stable"), np.argsort(xs, kind="stable"))
    # negative control: for negative numbers the order of the bits is not theirs
    bits, _ = _bits_and_back(-xs)
    assert not np.array_equal(np.argsort(bits, kind="stable"), np.argsort(-xs, kind="stable"))


def test_stopping_rule_takes_a_component_moving_off_zero_as_not_done():
    # a slope that is exactly 0 now and was not before has an infinite relative
    # increment: not done (and no ZeroDivisionError, which a 20-link chain from
    # rest met through the momenta of its first sweeps)
    new, old = np.array([0.0, 1.0]), np.array([1e-17, 1.0])
    assert roundoff_status(new, old, np.array([1e-15, 0.0])) == 0
    assert reference_roundoff_status(new, old, np.array([1e-15, 0.0]))[0] == 0
    # negative control: once it stays at 0 (no increment), it is done
    assert roundoff_status(new, new.copy(), np.array([1e-15, 0.0])) == 1
