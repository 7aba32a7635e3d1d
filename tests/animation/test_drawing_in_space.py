"""A system in space drawn still: from above (x, y) and from the side (x, z), each with the
bob's trail. (The live simulator draws it in a projection the student turns:
tests/widgets/test_live_in_space.py and tests/browser/test_simulator_in_space.py.)"""

import io

import numpy as np
import pytest
from matplotlib.figure import Figure
from PIL import Image

import pendulum_lab as pl
from pendulum_lab.animation import PendulumScene, still_frame
from pendulum_lab.plotting import draw_pendulum


@pytest.fixture(scope="module")
def orbit(spherical):
    """An orbit round the vertical: from above a loop, from the side a nearly level line."""
    return pl.simulate(spherical, [0.5, 0.0], [0.0, 1.5], t_end=3.0, dt=0.01, method="rk4",
                       progress=False)


def test_the_scene_draws_two_views_each_with_the_bob_and_its_trail(spherical, orbit):
    scene = PendulumScene(Figure(figsize=(9, 3.6)), spherical, orbit, trail=1.0,
                          animated=False)
    x, y, z = spherical.positions(orbit.theta)
    index = len(orbit.t) - 1
    scene.show(index)
    above, side = scene.views
    assert [v.ax.get_ylabel() for v in scene.views] == ["y (m)", "z (m)"]
    for view, vertical in ((above, y), (side, z)):
        rods, bobs, trail = view.chains[0]
        assert np.allclose(bobs.get_data(), ([x[index, 0]], [vertical[index, 0]]))
        assert np.allclose(rods.get_data(), ([0.0, x[index, 0]], [0.0, vertical[index, 0]]))
        trail_x, trail_v = trail.get_data()
        assert len(trail_x) == 101 and np.allclose(trail_v, vertical[index - 100:, 0])
    # negative control: the two views differ (z is not y), and a plane has one view
    assert not np.allclose(above.chains[0][1].get_data()[1], side.chains[0][1].get_data()[1])
    elastic = pl.elastic_pendulum()
    flat = pl.simulate(elastic, elastic.start, [0.0, 0.0], t_end=0.2, dt=0.01, method="rk4",
                       progress=False)
    assert len(PendulumScene(Figure(figsize=(9, 3.6)), elastic, flat,
                             animated=False).views) == 1


def test_a_still_frame_of_a_run_in_space_is_a_picture_and_names_the_wrong_model(spherical,
                                                                                orbit):
    image = Image.open(io.BytesIO(still_frame(orbit, spherical, dpi=40)))
    assert image.size == (360, 144)
    pixels = np.asarray(image.convert("RGB"), dtype=int)
    red = np.flatnonzero((np.abs(pixels - [214, 39, 40]).sum(axis=-1) < 60).any(axis=0))
    # the bob drawn twice on the left (from above, from the side), never in the energy panel
    assert red.size and red.max() < 0.55 * image.size[0]
    assert red.max() - red.min() > 0.15 * image.size[0]
    # negative control: the Foucault pendulum has the same points, not the same motion
    with pytest.raises(ValueError, match="`traj` is a run of the spherical pendulum"):
        still_frame(orbit, pl.foucault_pendulum())


def test_draw_pendulum_draws_both_views_into_a_figure_a_pair_or_one_axes(spherical, orbit):
    x, y, z = spherical.positions(orbit.theta[-1])
    figure = draw_pendulum(spherical, orbit.theta[-1], trail=orbit.theta)
    views = figure.axes
    assert [ax.get_ylabel() for ax in views] == ["y (m)", "z (m)"]
    for ax, vertical in zip(views, (y, z)):
        offsets = ax.collections[0].get_offsets()  # the bob
        assert np.allclose(offsets, [[x[0], vertical[0]]])
    single = Figure().add_subplot()
    draw_pendulum(spherical, orbit.theta[-1], ax=single)
    assert len(single.child_axes) == 2 and not single.axison
    # negative control: three axes are not two views
    with pytest.raises(ValueError, match="`ax` must be one matplotlib Axes or 2 of them"):
        draw_pendulum(spherical, orbit.theta[-1], ax=Figure().subplots(1, 3))
