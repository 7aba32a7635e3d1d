"""Redraw only what changed in a figure of several panels (blitting, per axes).

Most of an explorer's redraw is text: tick labels, axis labels, titles. While
a slider moves, the frame around a panel's data (its axes, ticks and labels)
often stays as it was. :class:`BackgroundCache` draws each axes' frame alone
over the empty figure, keeps the rectangle of pixels it changed, and draws it
again only when its :func:`axes_key` changes; a render pastes the frames into
the empty figure and paints every panel's data over them in the order a full
draw would. While the frames' rectangles do not touch, the picture is the
same pixel for pixel as a full draw (the tests compare them); when they do,
or for a figure this scheme does not cover (overlapping axes, figure-level
artists, a layout engine), the figure is drawn in full.
"""

from __future__ import annotations

import math
from operator import attrgetter

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg, RendererAgg
from matplotlib.figure import Figure

__all__ = ["BackgroundCache", "axes_key", "data_artists", "foreground"]


def data_artists(ax: Axes) -> list:
    """What a panel draws into ``ax``: lines, collections, patches, texts, images, legend."""
    artists = [*ax.lines, *ax.collections, *ax.patches, *ax.texts, *ax.images]
    if ax.get_legend() is not None:
        artists.append(ax.get_legend())
    return artists


def foreground(ax: Axes) -> list:
    """The artists of ``ax`` drawn over its cached frame, in the order a full draw uses.

    The data and every child of the axes at or above the data's lowest
    z-order: the spines, for instance, are drawn over the lines, and the
    axis objects (ticks, grid and tick labels) over data drawn below them.
    The axes patch and the titles (outside the data's clip box) are always
    in the frame; by default the axis objects are too, below the data.
    """
    data = data_artists(ax)
    if not data:
        return []
    lowest = min(artist.get_zorder() for artist in data)
    frame = {ax.patch, ax.title, ax._left_title, ax._right_title}
    children = [a for a in ax.get_children() if a not in frame and a.get_zorder() >= lowest]
    return sorted(children, key=attrgetter("zorder"))  # a stable sort, as Axes.draw's


def _text_key(text) -> tuple:
    return (text.get_text(), text.get_color(), text.get_fontsize(), text.get_visible())


def _axis_key(axis) -> tuple:
    locations = axis.get_majorticklocs()
    labels = axis.major.formatter.format_ticks(locations)
    grid = bool(axis.majorTicks) and axis.majorTicks[0].gridline.get_visible()
    return (
        axis.get_scale(),
        tuple(float(v) for v in locations),
        tuple(labels),
        grid,
        _text_key(axis.label),
        axis.get_visible(),
    )


def axes_key(ax: Axes) -> tuple:
    """What the pixels of the frame of ``ax`` depend on, as comparable values.

    Its position, view limits, facecolor, both axes' scale, tick locations
    and labels, grid and label, and its titles. A panel that changes anything
    else about a frame between updates (tick parameters, say) should not be
    drawn through the cache.
    """
    ax.apply_aspect()
    return (
        tuple(ax.get_position().bounds),
        tuple(float(v) for v in (*ax.get_xlim(), *ax.get_ylim())),
        ax.get_facecolor(),
        ax.axison,
        ax.get_visible(),
        _axis_key(ax.xaxis),
        _axis_key(ax.yaxis),
        tuple(_text_key(t) for t in (ax.title, ax._left_title, ax._right_title)),
    )


def _axes_overlap(figure: Figure) -> bool:
    boxes = [ax.get_position() for ax in figure.axes]
    return any(
        a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1
        for k, a in enumerate(boxes)
        for b in boxes[k + 1 :]
    )


def _figure_key(figure: Figure) -> tuple:
    return (
        tuple(figure.bbox.bounds),
        figure.dpi,
        figure.get_facecolor(),
        tuple(tuple(ax.get_position().bounds) for ax in figure.axes),
    )


def _cacheable(figure: Figure) -> bool:
    """Axes that do not overlap, nothing else on the figure, and no layout engine."""
    extras = [*figure.lines, *figure.patches, *figure.texts, *figure.images, *figure.legends]
    return (
        not extras
        and not figure.subfigs
        and figure.get_layout_engine() is None
        and not _axes_overlap(figure)
    )


def _changed_box(pixels: np.ndarray, blank: np.ndarray) -> tuple[slice, slice]:
    """The smallest rectangle (row and column slices) holding every pixel that differs."""
    changed = pixels.view(np.uint32)[..., 0] != blank.view(np.uint32)[..., 0]
    rows, columns = np.flatnonzero(changed.any(axis=1)), np.flatnonzero(changed.any(axis=0))
    if rows.size == 0:
        return slice(0, 0), slice(0, 0)
    return slice(rows[0], rows[-1] + 1), slice(columns[0], columns[-1] + 1)


def _frame_box(ax: Axes, changed: tuple[slice, slice], shape) -> tuple[slice, slice]:
    """``changed`` widened to the whole rectangle of ``ax``, which its patch paints even where
    that leaves the blank's colour (rows count from the top, display coordinates from the
    bottom); ``shape`` is the picture's."""
    height, width = shape[:2]
    rows, columns = changed
    top, bottom = height - math.ceil(ax.bbox.y1), height - math.floor(ax.bbox.y0)
    left, right = math.floor(ax.bbox.x0), math.ceil(ax.bbox.x1)
    if rows.stop > rows.start:
        top, bottom = min(top, rows.start), max(bottom, rows.stop)
        left, right = min(left, columns.start), max(right, columns.stop)
    return slice(max(top, 0), min(bottom, height)), slice(max(left, 0), min(right, width))


def _disjoint(boxes: list[tuple[slice, slice]]) -> bool:
    def meet(a: slice, b: slice) -> bool:
        return a.start < b.stop and b.start < a.stop

    return not any(
        meet(a[0], b[0]) and meet(a[1], b[1]) for k, a in enumerate(boxes) for b in boxes[k + 1 :]
    )


class BackgroundCache:
    """Render ``figure`` on ``canvas``, reusing each axes' frame while its :func:`axes_key` holds.

    ``hits`` counts the frames reused, ``misses`` those drawn anew (one of
    each per axes and render), ``full`` the renders drawn in full.
    """

    def __init__(self, figure: Figure, canvas: FigureCanvasAgg):
        self.figure, self.canvas = figure, canvas
        self.hits = self.misses = self.full = 0
        self.clear()

    def clear(self) -> None:
        """Forget every frame (the next render draws them anew)."""
        self._figure_key = self._blank = self._scratch = None
        self._keys, self._frames = [], []

    def render(self) -> None:
        """Draw the figure into the canvas's pixels (call inside any ``rc_context`` needed)."""
        figure = self.figure
        if not _cacheable(figure):
            self._draw_in_full()
            return
        if _figure_key(figure) != self._figure_key:
            self._start()
        layers = [(ax, foreground(ax)) for ax in figure.axes]
        for k, (ax, artists) in enumerate(layers):
            key = axes_key(ax)
            if key == self._keys[k]:
                self.hits += 1
            else:
                self._frames[k] = self._draw_frame(ax, artists)
                self._keys[k] = key
                self.misses += 1
        if not _disjoint([(rows, columns) for rows, columns, _ in self._frames]):
            self.full += 1  # frames that touch: a full draw puts one over the other
            self.canvas.draw()
            return
        pixels = np.asarray(self.canvas.get_renderer().buffer_rgba())
        pixels[...] = self._blank
        for rows, columns, frame in self._frames:
            pixels[rows, columns] = frame
        for ax, artists in layers:
            for artist in artists:
                ax.draw_artist(artist)

    def _draw_in_full(self) -> None:
        self.clear()
        self.full += 1
        self.canvas.draw()

    def _start(self) -> None:
        """Draw the figure without its axes (the blank every frame is drawn over)."""
        figure = self.figure
        visible = [ax for ax in figure.axes if ax.get_visible()]
        for ax in visible:
            ax.set_visible(False)
        try:
            self.canvas.draw()
        finally:
            for ax in visible:
                ax.set_visible(True)
        self._blank = np.array(self.canvas.get_renderer().buffer_rgba())
        height, width = self._blank.shape[:2]
        self._scratch = RendererAgg(width, height, figure.dpi)
        self._keys = [None] * len(figure.axes)
        self._frames = [None] * len(figure.axes)
        self._figure_key = _figure_key(figure)

    def _draw_frame(self, ax: Axes, artists: list) -> tuple[slice, slice, np.ndarray]:
        """The frame of ``ax`` drawn alone over the blank: where it differs, and those pixels."""
        scratch = np.asarray(self._scratch.buffer_rgba())
        scratch[...] = self._blank
        shown = [a for a in artists if a.get_visible()]
        for artist in shown:
            artist.set_visible(False)
        try:
            ax.draw(self._scratch)
        finally:
            for artist in shown:
                artist.set_visible(True)
        rows, columns = _frame_box(ax, _changed_box(scratch, self._blank), scratch.shape)
        return rows, columns, scratch[rows, columns].copy()
