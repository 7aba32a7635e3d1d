"""Redraw only what changed in a figure of several panels (blitting, per axes).

Most of an explorer's redraw is text: tick labels, axis labels, titles. While
a slider moves, the frame around a panel's data (its axes, ticks and labels)
often stays as it was, or only one of its axes changes. :class:`BackgroundCache`
draws each axes' frame alone over the empty figure, piece by piece (patch,
x axis, y axis, titles), keeping the picture after each piece, and draws a
piece again only when its :func:`piece_key` changes, over the picture of the
pieces before it. A render pastes the frames into the empty figure and paints
every panel's data over them in the order of a full draw. While the frames'
rectangles do not touch, the picture is the same pixel for pixel as a full
draw (the tests compare them); when they do, or for a figure this scheme
does not cover (overlapping axes, figure-level artists, a layout engine),
the figure is drawn in full.
"""

from __future__ import annotations

import math
from operator import attrgetter

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg, RendererAgg
from matplotlib.figure import Figure

__all__ = ["BackgroundCache", "data_artists", "draw_order", "piece_key", "split"]


def data_artists(ax: Axes) -> list:
    """What a panel draws into ``ax``: lines, collections, patches, texts, images, legend."""
    artists = [*ax.lines, *ax.collections, *ax.patches, *ax.texts, *ax.images]
    if ax.get_legend() is not None:
        artists.append(ax.get_legend())
    return artists


def draw_order(ax: Axes) -> list:
    """The artists :meth:`Axes.draw` draws for ``ax``, in its order.

    The patch first (if the axes and its frame are on), then the children by
    z-order (a stable sort); no spines without the frame, no axis objects
    with the axes off, no animated artists.
    """
    framed = ax.axison and ax.get_frame_on()
    skipped = {ax.patch}
    if not framed:
        skipped.update(ax.spines.values())
    if not ax.axison:
        skipped.update((ax.xaxis, ax.yaxis))
    artists = [a for a in ax.get_children() if a not in skipped and not a.get_animated()]
    artists.sort(key=attrgetter("zorder"))
    return [ax.patch, *artists] if framed else artists


def split(ax: Axes) -> tuple[list, list]:
    """``(frame, foreground)``: the artists of ``ax`` cached as pixels and those drawn each time.

    The foreground is the data and everything :func:`draw_order` draws at or
    above the data's lowest z-order: the spines, for instance, are drawn
    over the lines, and the axis objects (ticks, grid and tick labels) over
    data drawn below them. The frame is the rest (by default the patch and
    the axis objects); the patch (drawn first whatever its z-order) and the
    titles (outside the data's clip box) are always in it.
    Both lists keep :func:`draw_order`'s order; both are empty for a hidden axes.
    """
    if not ax.get_visible():
        return [], []
    order = draw_order(ax)
    data = data_artists(ax)
    if not data:
        return order, []
    lowest = min(artist.get_zorder() for artist in data)
    always_frame = {ax.patch, ax.title, ax._left_title, ax._right_title}  # first; outside
    front = [a for a in order if a.get_zorder() >= lowest and a not in always_frame]
    shown = set(front)
    return [a for a in order if a not in shown], front


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


def piece_key(ax: Axes, artist) -> tuple:
    """What the pixels of ``artist``, a piece of the frame of ``ax``, depend on, as values.

    The axes' position and, for the patch its colours, for an axis object its
    view limits, scale, tick locations and labels, grid and label, for a
    title its text. Any other artist gets a key equal to no other (its
    pixels cannot be told from its properties here), so it and the pieces
    after it are drawn anew on every render.
    """
    position = tuple(ax.get_position().bounds)
    if artist is ax.patch:
        colours = (artist.get_facecolor(), artist.get_edgecolor(), artist.get_linewidth())
        return ("patch", position, colours)
    if artist is ax.xaxis:
        return ("x", position, tuple(map(float, ax.get_xlim())), _axis_key(artist))
    if artist is ax.yaxis:
        return ("y", position, tuple(map(float, ax.get_ylim())), _axis_key(artist))
    if artist in (ax.title, ax._left_title, ax._right_title):
        return ("title", position, _text_key(artist), tuple(artist.get_position()))
    return ("artist", object())


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
    """Render ``figure`` on ``canvas``, reusing the pieces of each axes' frame that hold.

    A frame is drawn piece by piece (:func:`split`, :func:`piece_key`) over
    the blank, keeping the picture after each piece; when a piece changes,
    the picture before it is taken up again and the rest drawn over it, in
    the order of a full draw. ``hits`` counts the frames reused whole,
    ``misses`` those with a piece drawn anew (one of the two per axes and
    render), ``pieces_drawn`` the pieces drawn, ``full`` the renders drawn in
    full.
    """

    def __init__(self, figure: Figure, canvas: FigureCanvasAgg):
        self.figure, self.canvas = figure, canvas
        self.hits = self.misses = self.pieces_drawn = self.full = 0
        self._figure_key = self._blank = self._scratch = None  # set up by the first render
        self._pieces, self._frames = [], []

    def clear(self) -> None:
        """Forget every frame (the next render draws them anew)."""
        self._pieces = [[(None, picture) for _, picture in pieces] for pieces in self._pieces]

    def render(self) -> None:
        """Draw the figure into the canvas's pixels (call inside any ``rc_context`` needed)."""
        figure = self.figure
        if not _cacheable(figure):
            self._figure_key = None
            self._draw_in_full()
            return
        if _figure_key(figure) != self._figure_key:
            self._start()
        layers = []
        for k, ax in enumerate(figure.axes):
            # What Axes.draw does before it draws: autoscale, aspect, the titles' place.
            ax._unstale_viewLim()
            ax.apply_aspect()
            ax._update_title_position(self._scratch)
            frame, front = split(ax)
            layers.append((ax, front))
            keys = [piece_key(ax, artist) for artist in frame]
            cached = self._pieces[k]
            same = 0
            while same < min(len(keys), len(cached)) and cached[same][0] == keys[same]:
                same += 1
            if same == len(keys) == len(cached) and self._frames[k] is not None:
                self.hits += 1
            else:
                self.misses += 1
                self._frames[k] = self._draw_frame(k, ax, frame, keys, same)
        if not _disjoint([(rows, columns) for rows, columns, _ in self._frames]):
            self._draw_in_full()  # frames that touch: a full draw puts one over the other
            return
        pixels = np.asarray(self.canvas.get_renderer().buffer_rgba())
        pixels[...] = self._blank
        for rows, columns, frame in self._frames:
            pixels[rows, columns] = frame
        for ax, artists in layers:
            for artist in artists:
                ax.draw_artist(artist)

    def _draw_in_full(self) -> None:
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
        self._pieces = [[] for _ in figure.axes]
        self._frames = [None] * len(figure.axes)
        self._figure_key = _figure_key(figure)

    def _draw_frame(self, k: int, ax: Axes, frame: list, keys: list, same: int):
        """Draw the pieces of the frame of axes ``k`` from ``same`` on over the picture of
        those before; return where the frame differs from the blank, and its pixels."""
        scratch = np.asarray(self._scratch.buffer_rgba())
        pieces = self._pieces[k]
        scratch[...] = pieces[same - 1][1] if same else self._blank
        for j in range(same, len(frame)):
            frame[j].draw(self._scratch)
            self.pieces_drawn += 1
            if j < len(pieces):  # reuse the picture's memory: fresh pages cost more than a copy
                np.copyto(pieces[j][1], scratch)
                pieces[j] = (keys[j], pieces[j][1])
            else:
                pieces.append((keys[j], scratch.copy()))
        del pieces[len(frame) :]
        picture = pieces[-1][1] if pieces else self._blank
        rows, columns = _frame_box(ax, _changed_box(picture, self._blank), picture.shape)
        return rows, columns, picture[rows, columns]
