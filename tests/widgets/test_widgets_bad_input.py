"""Bad input to the widgets' public functions: a message naming the argument, never a crash.

``dt = 0`` used to end in a ZeroDivisionError; it now meets the rule of
:func:`pendulum_lab.step_count` (``dt > 0``), raised when a simulator or an explorer is built,
and
``set_controls`` names a choice control and its options (ipywidgets' ``TraitError`` used to
come through).
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
    lambda dt: widgets.explore(DP, dt=dt),
    lambda dt: widgets.explore_energy(DP, dt=dt),
    lambda dt: widgets.explore_equilibrium(DP, dt=dt),
], ids=["explore", "explore_energy", "explore_equilibrium"])
def test_the_explorers_refuse_dt_zero_naming_it(build):
    with pytest.raises(ValueError, match=DT_RULE):
        build(0)
    # negative control: a valid step builds and runs without that message
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert "`dt`" not in build(0.01).message


@pytest.mark.parametrize("build", [
    lambda: widgets.section_explorer(DP, dt=0),
    lambda: widgets.portrait_explorer(SP, dt=0),
], ids=["section_explorer", "portrait_explorer"])
def test_the_click_explorers_refuse_dt_zero(build):
    with pytest.raises(ValueError, match=DT_RULE):
        build()


def test_set_controls_names_the_control_and_its_choices():
    explorer = widgets.explore(DP, t_end=1.0)
    with pytest.raises(ValueError, match="`method` must be one of .*'rk4'.*got 'foo'"):
        explorer.set_controls({"method": "foo"})
    assert explorer.set_controls({"method": "rk4"})  # negative control: a listed choice runs


def _lagrangian_only():
    import sympy as sp
    q, w = sp.symbols("q w", real=True)
    return pl.mechanical_system([q], {}, lagrangian=w**2 / 2 - q**2 / 2, velocities=[w],
                                name="an oscillator given by its Lagrangian")


@pytest.mark.parametrize("build", [
    lambda model: widgets.live_simulator(model, t_end=1.0),
    lambda model: animation.simulator(model, t_end=1.0),
    lambda model: widgets.explore(model, t_end=1.0, plots=("pendulum",)),
], ids=["live_simulator", "animation.simulator", "explore"])
def test_the_drawings_refuse_a_system_without_points_and_say_so(build):
    # A system given by its Lagrangian has nothing to draw: a TypeError that names it and says
    # how to give points, not an AttributeError from inside; one given by its points builds.
    with pytest.raises(TypeError, match="given by its Lagrangian.*`points`") as refused:
        build(_lagrangian_only())
    assert "an oscillator given by its Lagrangian" in str(refused.value)
    build(pl.elastic_pendulum())


def test_the_section_explorer_refuses_a_system_and_says_so():
    # Its section is the double pendulum's (theta1 = 0): a TypeError naming the system.
    with pytest.raises(TypeError, match="not a chain|a chain of two links") as refused:
        widgets.section_explorer(pl.elastic_pendulum())
    assert "the elastic pendulum" in str(refused.value)
    widgets.section_explorer(pl.double_pendulum(), t_end=1.0)  # the control builds
