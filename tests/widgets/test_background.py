"""The explorers' frame cache draws what a full draw draws; round limits keep frames still."""

import math

import matplotlib as mpl
import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

import pendulum_lab as pl
from pendulum_lab import widgets
from pendulum_lab.widgets import background
from pendulum_lab.widgets.explorers import LIMIT_GRID, LOG_LIMIT_GRID, round_limits

UNHINTED = {"text.hinting": "none"}  # as the instruments render


def cached_and_full(figure, canvas, cache):
    """The pixels the cache renders and those of a full draw of the same figure."""
    with mpl.rc_context(UNHINTED):
        cache.render()
        cached = np.array(canvas.buffer_rgba())
        canvas.draw()
    return cached, np.array(canvas.buffer_rgba())


@pytest.mark.parametrize("n, plots", [
    (2, ("energy", "angles")),
    (2, ("phase", "pendulum", "energy_error")),
    (1, ("portrait", "energy")),
    (3, ("energy", "angles", "phase", "energy_error")),
])
def test_cached_frames_draw_what_a_full_draw_draws(n, plots):
    ex = widgets.explore(pl.n_pendulum(n), method="rk4", t_end=3.0, plots=plots)
    angle = ex.controls["theta1" if n > 1 else "theta"]
    for step in (0.01, 0.01, -0.3, 0.01, 0.02, -0.01):  # small changes and a large one
        angle.value = round(angle.value + step, 2)
        cached, full = cached_and_full(ex.figure, ex._canvas, ex.background)
        assert np.array_equal(cached, full)
    cache = ex.background
    # The comparison covered both reused and redrawn frames, and no full draws.
    assert cache.hits > 0 and cache.misses > len(plots) and cache.full == 0


def test_a_stale_frame_would_be_seen(monkeypatch):
    # Negative control of the comparison above: with a key that ignores the frames' limits, a
    # frame whose ticks no longer fit the data is reused, and the pixels differ from a full draw.
    ex = widgets.explore(pl.double_pendulum(), method="rk4", t_end=3.0)
    cache = background.BackgroundCache(ex.figure, ex._canvas)
    monkeypatch.setattr(background, "piece_key", lambda ax, artist: ("the same every time",))
    cached, full = cached_and_full(ex.figure, ex._canvas, cache)
    assert np.array_equal(cached, full) and cache.misses == 2
    ex.controls["theta1"].value = 0.3  # a much smaller swing: new limits and ticks
    cached, full = cached_and_full(ex.figure, ex._canvas, cache)
    assert cache.hits == 2
    assert not np.array_equal(cached, full)


def test_figures_it_does_not_cover_are_drawn_in_full():
    figure = Figure(figsize=(6, 3), dpi=50)
    canvas = FigureCanvasAgg(figure)
    ax = figure.add_subplot(121)
    ax.plot([0, 1], [0, 1])
    figure.add_subplot(122).plot([0, 1], [1, 0])
    cache = background.BackgroundCache(figure, canvas)
    cached, full = cached_and_full(figure, canvas, cache)
    assert np.array_equal(cached, full) and cache.full == 0 and cache.misses == 2
    ax.set_visible(False)  # covered: a hidden axes has an empty frame
    cached, full = cached_and_full(figure, canvas, cache)
    assert np.array_equal(cached, full) and cache.full == 0
    ax.set_visible(True)
    figure.suptitle("a figure-level text is drawn over the axes")
    cached, full = cached_and_full(figure, canvas, cache)
    assert np.array_equal(cached, full) and cache.full == 1
    figure.texts.clear()
    figure.add_axes([0.3, 0.3, 0.3, 0.3]).plot([0, 1], [0.5, 0.5])  # an inset overlaps
    cached, full = cached_and_full(figure, canvas, cache)
    assert np.array_equal(cached, full) and cache.full == 2


def test_data_below_the_ticks_and_grid_is_drawn_under_them(monkeypatch):
    figure = Figure(figsize=(6, 3), dpi=50)
    canvas = FigureCanvasAgg(figure)
    ax = figure.add_subplot()
    ax.grid(True)
    ax.tick_params(direction="in", length=12)
    ax.axhspan(0.2, 0.8, color="tab:orange", zorder=1)  # below the axis objects (1.5)
    ax.plot([0, 1], [0, 1])
    cache = background.BackgroundCache(figure, canvas)
    assert ax.xaxis in background.split(ax)[1]
    cached, full = cached_and_full(figure, canvas, cache)
    assert np.array_equal(cached, full) and cache.full == 0
    # Control: with the axis objects in the frame, the band would cover the grid and ticks.
    frame, front = background.split(ax)
    moved = ([*frame[:1], ax.xaxis, ax.yaxis, *frame[1:]],
             [a for a in front if a not in (ax.xaxis, ax.yaxis)])
    cache = background.BackgroundCache(figure, canvas)
    monkeypatch.setattr(background, "split", lambda axes: moved)
    cached, full = cached_and_full(figure, canvas, cache)
    assert not np.array_equal(cached, full)


def test_only_the_pieces_from_the_first_change_on_are_drawn_again():
    figure = Figure(figsize=(6, 3), dpi=50)
    canvas = FigureCanvasAgg(figure)
    ax = figure.add_subplot()
    ax.set_title("a title")
    (line,) = ax.plot([0, 1], [0, 1])
    cache = background.BackgroundCache(figure, canvas)
    frame, _ = background.split(ax)
    assert frame[:3] == [ax.patch, ax.xaxis, ax.yaxis] and len(frame) == 6  # and 3 titles
    cached, full = cached_and_full(figure, canvas, cache)
    assert np.array_equal(cached, full) and cache.pieces_drawn == 6
    line.set_ydata([0, 3])  # new y limits and ticks; x unchanged
    ax.relim()
    ax.autoscale_view()
    cached, full = cached_and_full(figure, canvas, cache)
    assert np.array_equal(cached, full) and cache.pieces_drawn == 6 + 4  # y axis and titles
    line.set_xdata([0, 2])  # now x as well: from the x axis on
    ax.relim()
    ax.autoscale_view()
    cached, full = cached_and_full(figure, canvas, cache)
    assert np.array_equal(cached, full) and cache.pieces_drawn == 10 + 5
    cached, full = cached_and_full(figure, canvas, cache)  # nothing changed
    assert np.array_equal(cached, full) and cache.pieces_drawn == 15 and cache.hits == 1


def test_only_the_frames_that_changed_are_drawn_again():
    figure = Figure(figsize=(6, 3), dpi=50)
    canvas = FigureCanvasAgg(figure)
    left, right = figure.subplots(1, 2)
    figure.subplots_adjust(wspace=0.5)
    left.set_title("a title")
    (line,) = left.plot([0, 1], [0, 1])
    right.plot([0, 1], [1, 0])
    cache = background.BackgroundCache(figure, canvas)
    frame, _ = background.split(left)
    assert frame[:3] == [left.patch, left.xaxis, left.yaxis] and len(frame) == 6  # and 3 titles
    cached, full = cached_and_full(figure, canvas, cache)
    assert np.array_equal(cached, full) and (cache.misses, cache.hits) == (2, 0)
    line.set_ydata([0, 3])  # new y limits and ticks on the left; the right unchanged
    left.relim()
    left.autoscale_view()
    cached, full = cached_and_full(figure, canvas, cache)
    assert np.array_equal(cached, full) and (cache.misses, cache.hits) == (3, 1)
    left.set_title("another title")  # a title is a piece of its frame too
    cached, full = cached_and_full(figure, canvas, cache)
    assert np.array_equal(cached, full) and (cache.misses, cache.hits) == (4, 2)
    cached, full = cached_and_full(figure, canvas, cache)  # nothing changed
    assert np.array_equal(cached, full) and (cache.misses, cache.hits) == (4, 4)
    cache.clear()
    cached, full = cached_and_full(figure, canvas, cache)
    assert np.array_equal(cached, full) and (cache.misses, cache.hits) == (6, 4)


def test_titles_are_placed_as_a_full_draw_places_them():
    # With the x ticks on top, matplotlib lifts an automatically placed title above their
    # labels when it draws the axes; the cached frame must show it there too.
    def figure_with_title(**title):
        figure = Figure(figsize=(4, 3), dpi=50)
        canvas = FigureCanvasAgg(figure)
        ax = figure.add_axes([0.15, 0.1, 0.7, 0.6])
        ax.xaxis.tick_top()
        ax.set_title("above the ticks", **title)
        ax.plot([0, 1], [0, 1])
        return figure, canvas

    figure, canvas = figure_with_title()
    cache = background.BackgroundCache(figure, canvas)
    for _ in range(2):  # drawn anew, then reused
        cached, full = cached_and_full(figure, canvas, cache)
        assert np.array_equal(cached, full)
    assert cache.misses >= 1 and cache.hits >= 1 and cache.full == 0
    # Control: the same title left where it was set (y = 1) is drawn elsewhere, so the
    # comparison above sees where the title goes.
    figure, canvas = figure_with_title(y=1.0)
    with mpl.rc_context(UNHINTED):
        canvas.draw()
    assert not np.array_equal(np.array(canvas.buffer_rgba()), full)


def test_frames_that_touch_are_drawn_in_full():
    figure = Figure(figsize=(6, 3), dpi=50)
    canvas = FigureCanvasAgg(figure)
    left, right = figure.subplots(1, 2)
    figure.subplots_adjust(wspace=0.0)  # the right axes' tick labels reach into the left one
    left.plot([0, 1], [0, 1])
    right.plot([0, 1], [0, 1000])
    cache = background.BackgroundCache(figure, canvas)
    cached, full = cached_and_full(figure, canvas, cache)
    assert np.array_equal(cached, full) and cache.full == 1
    # Control: with room between them, the same axes are drawn from their frames.
    figure.subplots_adjust(wspace=0.5)
    cached, full = cached_and_full(figure, canvas, cache)
    assert np.array_equal(cached, full) and cache.full == 1


def test_changed_box_is_the_smallest_rectangle_of_changes():
    blank = np.zeros((20, 30, 4), np.uint8)
    pixels = blank.copy()
    pixels[3, 7, 2] = 1
    pixels[11, 4, 3] = 255
    rows, columns = background._changed_box(pixels, blank)
    assert (rows, columns) == (slice(3, 12), slice(4, 8))
    assert background._changed_box(blank, blank) == (slice(0, 0), slice(0, 0))


def test_a_frame_owns_its_whole_axes_rectangle():
    # The axes patch paints its rectangle white over a white figure: no pixel changes there,
    # yet a full draw would cover whatever lay below it, so the frame's box includes it.
    figure = Figure(figsize=(4, 3), dpi=50)
    ax = figure.add_axes([0.25, 0.25, 0.5, 0.5])
    shape = (150, 200, 4)
    rows, columns = background._frame_box(ax, (slice(0, 0), slice(0, 0)), shape)
    assert (rows, columns) == (slice(37, 113), slice(50, 150))
    rows, columns = background._frame_box(ax, (slice(10, 40), slice(5, 60)), shape)
    assert (rows, columns) == (slice(10, 113), slice(5, 150))


def test_round_limits_lands_on_the_grid_and_holds_through_small_changes():
    figure = Figure()
    ax = figure.add_subplot()
    ax.plot([0.0, 10.0], [-3.3, 47.1])
    round_limits(ax)
    low, high = ax.get_ylim()
    ticks = ax.yaxis.get_major_locator().tick_values(low, high)
    grid = (ticks[1] - ticks[0]) * LIMIT_GRID
    margin = 0.05 * (47.1 + 3.3)  # matplotlib's, before rounding
    assert -3.3 - margin - grid <= low <= -3.3 - margin
    assert 47.1 + margin <= high <= 47.1 + margin + grid
    for value in (low, high):
        assert value / grid == pytest.approx(round(value / grid), abs=1e-9)
    # A slightly different curve gets the same limits: the frame holds still.
    ax.lines[0].remove()
    ax.relim()
    ax.set_autoscale_on(True)
    ax.plot([0.0, 10.0], [-3.4, 47.3])
    round_limits(ax)
    assert ax.get_ylim() == (low, high)
    # Control: a larger change moves them.
    ax.lines[0].remove()
    ax.relim()
    ax.set_autoscale_on(True)
    ax.plot([0.0, 10.0], [-3.4, 80.0])
    round_limits(ax)
    assert ax.get_ylim()[1] > high


def test_round_limits_on_a_log_axis_and_explicit_limits():
    figure = Figure()
    ax = figure.add_subplot()
    ax.semilogy([0.0, 1.0], [3e-12, 2e-7])
    round_limits(ax)
    for value in ax.get_ylim():
        quarters = math.log10(value) / LOG_LIMIT_GRID
        assert quarters == pytest.approx(round(quarters), abs=1e-9)
    assert ax.get_ylim()[0] <= 3e-12 and ax.get_ylim()[1] >= 2e-7
    ax.set_xlim(0.123, 0.877)  # set by the panel: not touched
    round_limits(ax)
    assert ax.get_xlim() == (0.123, 0.877)
