"""The exported animations' text stays legible at their resolution."""

import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

import pendulum_lab as pl
from pendulum_lab.plotting import scene as export

DP = pl.double_pendulum()
RUN = pl.simulate(DP, [2.0, 2.5], [0.0, 0.0], t_end=1.0, dt=0.01)


def text_heights(figure, dpi) -> dict[str, float]:
    """Pixels of each text of ``figure`` (its size in points at ``dpi``)."""
    FigureCanvasAgg(figure).draw()
    sizes = {}
    for ax in figure.axes:
        for tick in ax.get_xticklabels() + ax.get_yticklabels():
            sizes[f"tick {tick.get_text()}"] = tick.get_fontsize()
        sizes["x label"] = ax.xaxis.label.get_fontsize()
        if ax.get_legend() is not None:
            sizes.update({f"legend {t.get_text()}": t.get_fontsize()
                          for t in ax.get_legend().get_texts()})
        if ax.get_title():
            sizes[f"title {ax.get_title()}"] = ax.title.get_fontsize()
    sizes.update({f"text {t.get_text()}": t.get_fontsize() for t in figure.texts})
    return {name: points * dpi / 72 for name, points in sizes.items()}


@pytest.mark.parametrize("dpi", [56, 64, 80])
def test_the_export_scene_writes_every_text_at_least_eleven_pixels_high(dpi):
    figure, scene = export.export_scene([RUN, RUN], DP, 1.0, dpi, labels=["a", "b"])
    heights = text_heights(figure, dpi)
    assert len(heights) > 10
    small = {name: round(px, 1) for name, px in heights.items()
             if px < 0.85 * export.MIN_TEXT_PIXELS}  # legend and ticks are 0.85-0.9 of it
    assert small == {}
    assert scene.readout.get_fontsize() * dpi / 72 >= export.MIN_TEXT_PIXELS


def test_without_the_floor_a_low_resolution_header_is_tiny():
    # Negative control: matplotlib's default sizes at the exports' 64 dpi give the legend
    # above the panel some 7 pixels.
    figure = Figure(figsize=export.EXPORT_SIZE, dpi=64)
    export.PendulumScene(figure, DP, RUN, 1.0)
    heights = text_heights(figure, 64)
    legend = [px for name, px in heights.items() if name.startswith("legend")]
    assert legend and max(legend) < 9
