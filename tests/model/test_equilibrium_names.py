"""A system's equilibria are named in numbers people read: fractions and multiples of pi
with small denominators, other values as floats (never SymPy's guess at a closed form)."""

import math
import re

import numpy as np
import pytest
import sympy as sp

import pendulum_lab as pl
from pendulum_lab.model.system import readable_number


def values_in(name):
    """The numbers of ``"r = 1.027, theta = pi"``."""
    return [float(sp.sympify(part.split("=")[1])) for part in name.split(",")]


def test_equilibria_at_float_parameters_have_short_names_that_read_back():
    model = pl.elastic_pendulum(mass=1.3, stiffness=41.7)
    names = [eq.name for eq in model.equilibria]
    assert names == ["r = 1.05583, theta = 0", "r = 0.444173, theta = pi"]
    for eq in model.equilibria:
        np.testing.assert_allclose(values_in(eq.name), eq.angles, rtol=1e-5)
        assert not re.search(r"\*\*|\bpi\*\*", eq.name)
    # negative control: the closed form SymPy guesses for the same number is unreadable
    guessed = str(sp.nsimplify(model.equilibria[0].angles[0], [sp.pi], tolerance=1e-12))
    assert len(guessed) > 30 and "**" in guessed


def test_simple_values_keep_their_exact_names():
    assert [eq.name for eq in pl.elastic_pendulum().equilibria] == [
        "r = 1, theta = 0", "r = 1/2, theta = pi"]
    assert readable_number(-math.pi / 2) == "-pi/2"
    assert readable_number(3 * math.pi / 4) == "3*pi/4"
    assert readable_number(-0.0) == "0"
    # negative controls: near a fraction is not a fraction, nor is a large denominator
    assert readable_number(0.5 + 1e-9) == "0.5"
    assert readable_number(1 / 13) == "0.0769231"
    assert readable_number(math.pi / 13) == f"{math.pi / 13:.6g}"


@pytest.mark.parametrize("value", [1e-20, -2.75e7, 123.456789])
def test_any_number_reads_back_to_six_digits(value):
    assert float(readable_number(value)) == pytest.approx(value, rel=5e-6)
