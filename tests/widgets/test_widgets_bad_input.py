"""Bad input to the widgets' public functions: a message naming the argument, never a crash.

``dt = 0`` used to end in a ZeroDivisionError; it now meets the rule of
:func:`pendulum_lab.step_count` (``dt > 0``), raised by the simulators and shown by the
explorers in their message line. The cases marked ``xfail`` are refusals still to be made
inside the widgets themselves (a click explorer accepts ``dt = 0`` until a click, and
``set_controls`` passes ipywidgets' ``TraitError`` through); they fail strictly once fixed,
so that the marker goes with the fix.
"""

import warnings

import pytest

import pendulum_lab as pl

widgets = pytest.importorskip("pendulum_lab.widgets")
animation = pytest.importorskip("pendulum_lab.animation")

SP = pl.simple_pendulum()
DP = pl.double_pendulum()
DT_RULE = r"`dt` must be a positive number \(> 0\), got 0"


@pytest.mark.parametrize("build", [
    lambda: widgets.live_simulator(DP, dt=0.0),
    lambda: animation.simulator(DP, dt=0.0),
], ids=["live_simulator", "animation.simulator"])
def test_the_simulators_refuse_dt_zero_naming_it(build):
    with pytest.raises(ValueError, match=DT_RULE):
        build()


@pytest.mark.parametrize("build", [
    lambda: widgets.explore(DP, dt=0),
    lambda: widgets.explore_energy(DP, dt=0),
    lambda: widgets.explore_equilibrium(DP, dt=0),
], ids=["explore", "explore_energy", "explore_equilibrium"])
def test_the_explorers_say_what_dt_must_be(build):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        explorer = build()
    assert "`dt` must be a positive number (> 0), got 0" in explorer.message
    # negative control: a valid step runs without that message
    explorer.set_controls({"dt": 0.01})
    assert "`dt`" not in explorer.message


@pytest.mark.xfail(strict=True, reason="a refusal to be made in widgets/clickable.py (its owner)")
@pytest.mark.parametrize("build", [
    lambda: widgets.section_explorer(DP, dt=0),
    lambda: widgets.portrait_explorer(SP, dt=0),
], ids=["section_explorer", "portrait_explorer"])
def test_the_click_explorers_refuse_dt_zero(build):
    with pytest.raises(ValueError, match=DT_RULE):
        build()


@pytest.mark.xfail(strict=True, reason="a refusal to be made in widgets/instrument.py "
                   "(set_controls, its owner)")
def test_set_controls_names_the_control_and_its_choices():
    explorer = widgets.explore(DP, t_end=1.0)
    with pytest.raises(ValueError, match="`method` must be one of"):
        explorer.set_controls({"method": "foo"})
