"""The line data of a model's picture (plotting.drawing) and the scene drawn from it."""

import numpy as np
import pytest
from matplotlib.figure import Figure

import pendulum_lab as pl
from pendulum_lab.animation import PendulumScene
from pendulum_lab.plotting.drawing import joined_paths, rod_chains, spring_path


def test_rods_joined_end_to_end():
    assert rod_chains([(-1, 0), (0, 1), (1, 2)]) == [[-1, 0, 1, 2]]
    assert rod_chains([(0, 1), (-1, 2)]) == [[0, 1], [-1, 2]]


def test_a_spring_runs_from_end_to_end_within_its_width():
    path = spring_path((0.0, 0.0), (0.0, -2.0), width=0.1)
    assert path[0] == pytest.approx([0, 0]) and path[-1] == pytest.approx([0, -2])
    assert np.abs(path[:, 0]).max() == pytest.approx(0.1)  # the zigzag's half-width
    assert np.all(np.diff(path[:, 1]) <= 0)  # it advances along the spring


def test_the_chains_rods_are_one_path_from_the_pivot():
    dp = pl.double_pendulum()
    x, y = dp.positions([0.3, -1.2])
    rods, springs = joined_paths(dp.drawing, x, y, reach=2.0)
    assert rods == pytest.approx(np.column_stack([np.r_[0.0, x], np.r_[0.0, y]]))
    assert springs.shape == (0, 2)


def test_the_scene_draws_the_kapitza_pendulum_with_its_pivot_shaking():
    kapitza = pl.kapitza_pendulum()
    traj = pl.simulate(kapitza, [3.0], [0.0], t_end=0.1, dt=0.001, method="rk4",
                       progress=False)
    scene = PendulumScene(Figure(figsize=(9, 3.6)), kapitza, traj, animated=False)
    x, y = kapitza.positions(traj.theta, traj.t)
    for index in (0, 15, 31):
        scene.show(index)
        pivot_x, pivot_y = scene.parts[0][1].get_data()
        assert (pivot_x[0], pivot_y[0]) == pytest.approx((x[index, 0], y[index, 0]))
        bob_x, bob_y = scene.bobs.get_data()
        assert (bob_x[0], bob_y[0]) == pytest.approx((x[index, 1], y[index, 1]))
    # The pivot went up and down by the amplitude over the run.
    assert y[:, 0].max() - y[:, 0].min() == pytest.approx(0.1, rel=1e-3)


def test_the_elastic_pendulums_spring_ends_at_its_bob():
    elastic = pl.elastic_pendulum()
    traj = pl.simulate(elastic, elastic.start, [0.0, 0.0], t_end=0.5, dt=0.01, method="rk4",
                       progress=False)
    scene = PendulumScene(Figure(figsize=(9, 3.6)), elastic, traj, animated=False)
    scene.show(len(traj.t) - 1)
    spring_x, spring_y = scene.parts[0][0].get_data()
    x, y = elastic.positions(traj.theta[-1])
    assert (spring_x[0], spring_y[0]) == (0.0, 0.0)  # hung from the pivot
    assert (spring_x[-1], spring_y[-1]) == pytest.approx((x[0], y[0]))
    assert len(scene.rods.get_data()[0]) == 0  # no rod: a spring only
