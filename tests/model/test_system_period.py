"""A system's period follows its parameters: derived from the time dependence (SymPy's
periodicity of each function of t, their least common multiple), so that
``replace(w=...)`` moves it and what samples once per period samples at the right times."""

import pickle

import numpy as np
import pytest
import sympy as sp

import pendulum_lab as pl
from pendulum_lab import widgets
from pendulum_lab.symbolic.systems import MechanicalSystem

TH = sp.Symbol("theta", real=True)
T = sp.Symbol("t", real=True)
W, L = sp.symbols("w l", positive=True)


def shaken(pivot_y):
    return MechanicalSystem([TH], {W: 10.0, L: 1.0}, masses=[1], gravity=9.81,
                            points=[(L * sp.sin(TH), pivot_y - L * sp.cos(TH))])


def test_the_period_is_the_common_period_of_the_time_dependence():
    assert sp.simplify(shaken(sp.cos(W * T)).period - 2 * sp.pi / W) == 0
    assert sp.simplify(shaken(sp.cos(W * T) + sp.sin(3 * W * T / 2)).period
                       - 4 * sp.pi / W) == 0
    assert sp.simplify(shaken(sp.cos(W * T) ** 2).period - 2 * sp.pi / W) == 0
    # negative controls: no common period, t outside a function, no time at all
    assert shaken(sp.cos(W * T) + sp.cos(sp.sqrt(2) * W * T)).period is None
    assert shaken(sp.cos(W * T) + T / 10).period is None
    assert shaken(sp.Integer(0)).period is None


def test_replace_moves_the_kapitza_period_with_the_frequency(kapitza):
    slow = kapitza.replace(w=50.0)
    assert slow.drive_period == pytest.approx(2 * np.pi / 50.0, rel=1e-15)
    assert pl.kapitza_pendulum(frequency=50.0).drive_period == slow.drive_period
    assert kapitza.drive_period == pytest.approx(2 * np.pi / 100.0, rel=1e-15)
    # negative control: the amplitude is no clock parameter, the period stays
    assert kapitza.replace(a=0.08).drive_period == kapitza.drive_period
    # The equations repeat after the new period and not after the old one (half of it now:
    # the pivot is at the opposite end of its stroke).
    theta, p, t = np.array([2.8]), np.array([0.4]), 0.013
    field = np.concatenate(slow.vector_field(theta, p, t))
    later = np.concatenate(slow.vector_field(theta, p, t + slow.drive_period))
    np.testing.assert_allclose(later, field, rtol=1e-12)
    old = np.concatenate(slow.vector_field(theta, p, t + kapitza.drive_period))
    assert np.max(np.abs(old - field)) > 1e-2


def test_a_given_period_is_a_multiple_of_the_systems_own_and_follows_it(kapitza):
    twice = pl.SystemModel(kapitza.system, period=2 * kapitza.drive_period)
    assert twice.replace(w=40.0).drive_period == pytest.approx(2 * 2 * np.pi / 40.0, rel=1e-14)
    # a family and a pickle keep it
    assert twice.family(a=[0.03, 0.06]).drive_period == twice.drive_period
    assert pickle.loads(pickle.dumps(twice.replace(w=40.0))).drive_period == \
        twice.replace(w=40.0).drive_period


def test_a_numeric_period_of_a_system_without_a_found_period_refuses_a_clock_change():
    model = pl.SystemModel(shaken(sp.cos(W * T) + T / 10), period=0.5)
    assert model.drive_period == 0.5
    with pytest.raises(ValueError, match=r"\['w'\] sets how .* period was given as the number "
                                         r"0.5 s.*2\*sp.pi/w"):
        model.replace(w=20.0)
    # negative control: a parameter the time dependence does not read changes freely
    assert model.replace(l=2.0).drive_period == 0.5
    with pytest.raises(ValueError, match="`period` uses \\['k'\\]"):
        pl.SystemModel(shaken(sp.cos(W * T)), period=2 * sp.pi / sp.Symbol("k"))


def test_the_explorers_w_slider_runs_the_new_period(kapitza):
    ex = widgets.explore(kapitza, t_end=0.2, dt=0.002, method="rk4")
    assert "w" in ex.controls
    assert ex.set_controls({"w": 60.0})
    assert ex.prepare().model.drive_period == pytest.approx(2 * np.pi / 60.0, rel=1e-15)
    # the run is the new model's own
    run = pl.simulate(kapitza.replace(w=60.0), kapitza.start, [0.0], t_end=0.2, dt=0.002,
                      method="rk4", progress=False)
    np.testing.assert_array_equal(ex.trajectory.theta, run.theta)
