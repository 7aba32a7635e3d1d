"""The ES modules printed for the browser (``codegen.browser``), without a browser: the shipped
files are what the generator makes now, keys follow the kernels' rules, and a function
JavaScript lacks is refused by name. Their numbers are checked in Chromium
(tests/browser/test_browser_engine.py)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
import sympy as sp

import pendulum_lab as pl
from pendulum_lab.codegen.browser import (
    BrowserPrinter,
    browser_module_source,
    unprintable_functions,
)
from pendulum_lab.codegen.cache import text_key
from pendulum_lab.widgets import browser


def test_the_shipped_modules_equal_what_the_generator_makes_now():
    assert browser.stale_shipped() == [], (
        "regenerate them: python -m pendulum_lab.widgets.browser")


def test_a_drifted_shipped_module_is_found(tmp_path):
    written = browser.write_shipped(tmp_path)
    assert browser.stale_shipped(tmp_path) == []
    text = written[1].read_text()
    written[1].write_text(text.replace("Math.sin", "Math.cos", 1))
    written[3].unlink()
    assert browser.stale_shipped(tmp_path) == [written[1].name, written[3].name]


def test_the_key_is_of_the_text_and_the_generator():
    source = browser_module_source(pl.double_pendulum().chain)
    first, body = source.split("\n", 1)
    assert first.endswith(f"(key {text_key(body, 'pendulum_lab.codegen.browser')}).")
    assert text_key(body + " ", "pendulum_lab.codegen.browser") not in first


def test_small_integer_powers_are_products():
    x = sp.Symbol("x", real=True)
    printer = BrowserPrinter()
    assert printer.doprint(x**2) == "(x*x)"
    assert printer.doprint(sp.sin(x) ** -2) == "1/(Math.sin(x)*Math.sin(x))"
    assert printer.doprint(x**7) == "Math.pow(x, 7)"
    assert printer.doprint(sp.sqrt(x)) == "Math.sqrt(x)"


def test_a_function_javascript_lacks_is_named():
    x, m = sp.symbols("x m", real=True)
    assert unprintable_functions([sp.besselj(0, x) + sp.erf(x) + sp.sin(x)]) == ["besselj", "erf"]
    assert unprintable_functions([sp.sin(x) * sp.atan2(x, m)]) == []
    system = SimpleNamespace(
        n=1, q=sp.Matrix([x]), omega=sp.Matrix([sp.Symbol("v", real=True)]), parameters=(m,),
        mass_matrix=sp.Matrix([[m]]), momentum_offset=sp.Matrix([0]),
        dlagrangian_dq=sp.Matrix([-m * sp.besselj(1, x)]), forced=False,
        generalized_forces=sp.Matrix([0]), kinetic=m / 2, potential=m * sp.besselj(0, x),
        points=[(x, sp.Integer(0))], name="a Bessel potential")
    with pytest.raises(ValueError, match="use besselj, which JavaScript's Math does not have"):
        browser_module_source(system)


def test_models_the_browser_cannot_run_are_refused_with_the_reason():
    assert browser.browser_refusal(pl.double_pendulum()) is None
    assert "beyond what a browser" in browser.browser_refusal(pl.n_pendulum(7))
    assert "family" in browser.browser_refusal(pl.double_pendulum().family(g=[9.81, 1.62]))
    config = browser.browser_config(pl.driven_pendulum(), method="rk4")
    assert set(config["refused"]) == {"semi_implicit_euler", "leapfrog"}
    assert "damping" in config["refused"]["leapfrog"]
    with pytest.raises(ValueError, match="leapfrog cannot integrate this model"):
        browser.browser_config(pl.driven_pendulum(), method="leapfrog")
    with pytest.raises(ValueError, match="`method` must be one of"):
        browser.browser_config(pl.double_pendulum(), method="glrk8")


def test_a_new_model_gets_its_module_on_demand():
    made = browser.model_module(pl.n_pendulum(4))
    assert made.stem == "chain4" and made.name == f"chain4_{made.key}.js"
    assert "export function hamilton" in made.source and "solveSymmetric" in made.source
    assert browser.model_module(pl.double_pendulum(m1=2.0)).stem == "double_pendulum"


def test_a_live_simulators_display_carries_its_settings_for_the_browser():
    from pendulum_lab.widgets import live_simulator
    from pendulum_lab.widgets.live import BROWSER_SETTINGS

    view = "application/vnd.jupyter.widget-view+json"
    sim = live_simulator(pl.double_pendulum(), t_end=2.0, dt=0.02, method="rk4")
    settings = sim._repr_mimebundle_()[view][BROWSER_SETTINGS]
    assert settings == browser.browser_config(pl.double_pendulum(), [2.0, 2.5], [0.0, 0.0],
                                              t_end=2.0, dt=0.02, method="rk4")
    sim.drag(0, 1.0, 0.0)
    moved = sim._repr_mimebundle_()[view][BROWSER_SETTINGS]
    assert moved["theta0"][0] == pytest.approx(np.pi / 2) and moved["theta0"][1] == 2.5
    chain = live_simulator(pl.n_pendulum(7), t_end=1.0, dt=0.05, method="rk4")
    assert "beyond what a browser" in chain._repr_mimebundle_()[view][BROWSER_SETTINGS]["refusal"]
