"""Redraw only what changed in a figure of several panels (blitting, per axes).

Most of an explorer's redraw is text: tick labels, axis labels, titles. While
a slider moves, the frame around a panel's data (its axes, ticks and labels)
often stays as it was. :class:`BackgroundCache` keeps each axes' frame as
pixels and draws it again only from the first of its pieces (patch, x axis,
y axis, titles) whose :func:`piece_key` changed. It uses matplotlib's
documented blitting API (see matplotlib's guide "Faster rendering by using
blitting"): each piece is drawn by :meth:`Axes.draw <matplotlib.axes.Axes.draw>`
over the picture of the pieces before it, with the rest of the axes marked
animated (:meth:`~matplotlib.artist.Artist.set_animated`) and the patch
hidden; pictures are kept with ``canvas.copy_from_bbox`` and pasted back
with ``canvas.restore_region``; the data are then painted over the frames
with :meth:`~matplotlib.axes.Axes.draw_artist`, in the order of a full draw. While
the frames' rectangles do not touch, the picture is the same pixel for pixel
as a full draw (the tests compare them); when they do, or for a figure this
scheme does not cover (overlapping axes, figure-level artists, a layout
engine), the figure is drawn in full.
"""

from __future__ import annotations

import math
from contextlib import contextmanager
from operator import attrgetter

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.text import Text
from matplotlib.transforms import Bbox

__all__ = ["BackgroundCache", "data_artists", "draw_order", "piece_key", "split", "titles"]


def data_artists(ax: Axes) -> list:
    """What a panel draws into ``ax``: lines, collections, patches, texts, images, legend."""
    artists = [*ax.lines, *ax.collections, *ax.patches, *ax.texts, *ax.images]
    if ax.get_legend() is not None:
        artists.append(ax.get_legend())
    return artists


def titles(ax: Axes) -> list[Text]:
    """The three titles of ``ax`` (centre, left, right): its texts that are not ``ax.texts``."""
    return [a for a in ax.get_children() if isinstance(a, Text) and a not in ax.texts]


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
    always_frame = {ax.patch, *titles(ax)}  # first; outside the clip box
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
    title its text and place. Any other artist gets a key equal to no other
    (its pixels cannot be told from its properties here), so a frame holding
    it is drawn anew on every render.
    """
    position = tuple(ax.get_position().bounds)
    if artist is ax.patch:
        colours = (artist.get_facecolor(), artist.get_edgecolor(), artist.get_linewidth())
        return ("patch", position, colours)
    if artist is ax.xaxis:
        return ("x", position, tuple(map(float, ax.get_xlim())), _axis_key(artist))
    if artist is ax.yaxis:
        return ("y", position, tuple(map(float, ax.get_ylim())), _axis_key(artist))
    if artist in titles(ax):
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


def _display_box(rows: slice, columns: slice, height: int) -> Bbox:
    """The pixel rectangle ``rows`` x ``columns`` (rows from the top) in display coordinates."""
    return Bbox.from_extents(columns.start, height - rows.stop, columns.stop, height - rows.start)


def _disjoint(boxes: list[tuple[slice, slice]]) -> bool:
    def meet(a: slice, b: slice) -> bool:
        return a.start < b.stop and b.start < a.stop

    return not any(
        meet(a[0], b[0]) and meet(a[1], b[1]) for k, a in enumerate(boxes) for b in boxes[k + 1 :]
    )


@contextmanager
def _alone(ax: Axes, piece, others: list):
    """Leave everything of ``ax`` but ``piece`` out of a draw of ``ax``.

    The ``others`` are marked animated (a draw of their axes skips them), and
    the patch, which :meth:`Axes.draw` draws first whatever its state, hidden
    unless it is the piece. Both are set back afterwards.
    """
    patch_shown = ax.patch.get_visible()
    marked = [a for a in others if a is not piece and a is not ax.patch]
    for artist in marked:
        artist.set_animated(True)
    if piece is not ax.patch:
        ax.patch.set_visible(False)
    try:
        yield
    finally:
        ax.patch.set_visible(patch_shown)
        for artist in marked:
            artist.set_animated(False)


class BackgroundCache:
    """Render ``figure`` on ``canvas``, reusing the pieces of each axes' frame that hold.

    A frame is drawn piece by piece (:func:`split`, :func:`piece_key`) over
    the blank, keeping the picture after each piece: each piece is drawn by
    :meth:`Axes.draw` with the rest of its axes left out (marked animated, as
    matplotlib's blitting guide does), so it lands where a full draw puts it
    (a title above top tick labels, say). When a piece changes, the picture
    before it is taken up again and the rest drawn over it, in the order of a
    full draw. A render pastes the frames into the blank and draws every
    foreground over them. ``hits`` counts the frames reused whole, ``misses``
    those with a piece drawn anew (one of the two per axes and render),
    ``pieces_drawn`` the pieces drawn, ``full`` the renders drawn in full.
    """

    def __init__(self, figure: Figure, canvas: FigureCanvasAgg):
        self.figure, self.canvas = figure, canvas
        self.hits = self.misses = self.pieces_drawn = self.full = 0
        self._figure_key = self._blank = self._blank_pixels = None  # set up by the first render
        self._pieces, self._frames = [], []

    def clear(self) -> None:
        """Forget every frame (the next render draws them anew)."""
        self._pieces = [[] for _ in self._pieces]

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
            # Where Axes.draw would put the axes (an aspect may move it); its limits settle
            # on first reading, as in a draw.
            ax.apply_aspect()
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
                self._frames[k] = self._draw_frame(k, ax, frame, front, same)
        if not _disjoint([box for box, _ in self._frames]):
            self._draw_in_full()  # frames that touch: a full draw puts one over the other
            return
        canvas = self.canvas
        canvas.restore_region(self._blank)
        for _, frame in self._frames:
            canvas.restore_region(frame)
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
        self._blank = self.canvas.copy_from_bbox(figure.bbox)
        self._blank_pixels = np.array(self.canvas.buffer_rgba())
        self._pieces = [[] for _ in figure.axes]
        self._frames = [None] * len(figure.axes)
        self._figure_key = _figure_key(figure)

    def _draw_frame(self, k: int, ax: Axes, frame: list, front: list, same: int):
        """Draw the pieces of the frame of axes ``k`` from ``same`` on over the picture of
        those before; return where the frame lies (row and column slices) and its pixels
        there (a region for ``restore_region``)."""
        canvas, pieces = self.canvas, self._pieces[k]
        del pieces[same:]
        canvas.restore_region(pieces[-1][1] if pieces else self._blank)
        everything = [*frame, *front]
        for piece in frame[same:]:
            with _alone(ax, piece, everything):
                self.figure.draw_artist(ax)
            self.pieces_drawn += 1
            # The key after the draw: drawing places the titles.
            pieces.append((piece_key(ax, piece), canvas.copy_from_bbox(self.figure.bbox)))
        pixels = np.asarray(canvas.buffer_rgba())
        rows, columns = _frame_box(ax, _changed_box(pixels, self._blank_pixels), pixels.shape)
        region = canvas.copy_from_bbox(_display_box(rows, columns, pixels.shape[0]))
        return (rows, columns), region
