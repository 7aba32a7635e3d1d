"""One notation in the package's figures: Unicode symbols, no TeX, units on the axes; and
labels that do not pile up (a bifurcation diagram's doublings)."""

import re
from types import SimpleNamespace as Fake

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.text import Text  # noqa: E402

import pendulum_lab as pl  # noqa: E402
from pendulum_lab import analysis, plotting  # noqa: E402
from pendulum_lab.chaos import PeriodDoubling  # noqa: E402

SP, DP = pl.simple_pendulum(), pl.double_pendulum()
#: Greek letters and TeX commands spelled out in ASCII, as labels had them ("theta1(0)").
SPELLED_OUT = re.compile(r"\b(theta|omega|lambda|rho|alpha|gamma|delta)(_?\d|\b|\()|\\[a-z]+|_\d")
#: Axis labels of dimensionless quantities: no unit to give.
DIMENSIONLESS = {"|E − E(0)| / |E(0)|", "area(t) / area(0)", "growth factor per step",
                 "contraction per sweep", "h ω", "energy above rest / reference's", "K", "φ",
                 "I (mod 2π)", "iterations N", "vector-field evaluations"}


def texts(figure: Figure) -> list[Text]:
    """Every text a reader sees: titles, axis labels, legend entries, annotations."""
    found = []
    for ax in figure.axes:
        found += [ax.title, ax.xaxis.label, ax.yaxis.label, *ax.texts]
        if ax.get_legend() is not None:
            found += ax.get_legend().get_texts()
    return [t for t in found + list(figure.texts) if t.get_text().strip()]


def notation_problems(figure: Figure) -> list[str]:
    problems = []
    for text in texts(figure):
        words = text.get_text()
        if "$" in words:
            problems.append(f"TeX: {words!r}")
        if SPELLED_OUT.search(words):
            problems.append(f"spelled out: {words!r}")
    for ax in figure.axes:
        for label in (ax.get_xlabel(), ax.get_ylabel()):
            if label and label not in DIMENSIONLESS and not re.search(r"\([^()]+\)$", label):
                problems.append(f"no unit: {label!r}")
    return problems


@pytest.fixture(scope="module")
def runs():
    return {
        "simple": pl.simulate(SP, [2.5], [0.0], t_end=3.0, dt=0.01, method="rk4"),
        "double": pl.simulate(DP, [2.0, 2.5], [0.0, 0.0], t_end=3.0, dt=0.01, method="rk4"),
    }


def fake_doublings(*entries):
    return [PeriodDoubling(period, value - 0.001, value) for period, value in entries]


def bifurcation(doublings):
    values = np.linspace(0.9, 1.5, 120)
    return Fake(points=np.zeros((4, len(values), 1)), values=values, link=0,
                theta=np.zeros((4, len(values), 1, 1)), variable="omega",
                parameter="drive_amplitude", doublings=lambda: doublings)


def figures(runs):
    simple, double = runs["simple"], runs["double"]
    order = analysis.OrderResult(np.array([0.02, 0.01]), np.array([1e-4, 6e-6]), 4.0, "rk4", SP)
    yield "energy", plotting.plot_energy(double)
    yield "energy_error", plotting.plot_energy_error(double)
    yield "energy_error absolute", plotting.plot_energy_error(double, relative=False)
    yield "angles", plotting.plot_angles(double)
    yield "phase", plotting.plot_phase(double)
    yield "portrait", plotting.plot_phase_portrait(SP, trajectory=simple)
    yield "period", plotting.plot_period_vs_amplitude(SP, [0.5, 1.0], [2.05, 2.15])
    yield "order", plotting.plot_order(order)
    yield "error growth", plotting.plot_energy_error_growth([simple])
    yield "comparison", plotting.plot_energy_comparison(Fake(trajectories={"rk4": simple}))
    yield "stroboscopic", plotting.plot_stroboscopic(
        Fake(theta=np.zeros((5, 1)), omega=np.zeros((5, 1)), t=np.arange(5.0)))
    yield "bifurcation", plotting.plot_bifurcation(
        bifurcation(fake_doublings((1, 1.0), (2, 1.066))),
        lyapunov=Fake(largest=np.zeros(120), exponent=None))
    yield "basins", plotting.plot_basins(Fake(
        attractors=[np.array([[0.0, 1.0]])], theta0=np.linspace(-3, 3, 4),
        omega0=np.linspace(-2, 2, 3), label=np.zeros((3, 4), int), turns=[0.0],
        fractions=[1.0]))
    yield "lyapunov", plotting.plot_lyapunov(
        Fake(t=np.array([1.0, 2.0]), running=np.array([0.5, 0.4]), approach="tangent",
             method="glrk4"))
    yield "spectrum", plotting.plot_lyapunov_spectrum(
        Fake(t=np.array([1.0, 2.0]), running=np.zeros((2, 4))))
    yield "small angle", plotting.plot_small_angle(
        Fake(t=np.arange(3.0), theta_full=np.zeros((3, 2)), theta_linear=np.zeros((3, 2)),
             parting_time=np.array(1.0)))
    yield "landing", plotting.plot_landing_errors(
        Fake(speed=np.array([1.0, 2.0]), state_error=np.array([1e-6, 1e-7]), landing="cubic",
             method="rk4", dt=0.01))
    yield "contraction", plotting.plot_stage_contraction(
        [Fake(dt=0.01, contraction=0.1, predicted=0.12), Fake(dt=0.02, contraction=0.2,
                                                              predicted=0.24)])
    yield "work", plotting.plot_work_precision(
        [Fake(method="rk4", completed=True, wall_time=0.1, energy_error=1e-6,
              state_error=1e-5)])
    yield "separation", plotting.plot_separation(
        Fake(t=np.arange(3.0), distance=np.array([1e-8, 1e-6, 1e-4])))
    yield "drift", plotting.plot_energy_drift(
        Fake(dts=np.array([0.01, 0.02]), measured=np.array([1e-6, 4e-6]),
             predicted=np.array([1e-6, 4e-6]), power=2, method="rk4", amplitude=1.0))
    yield "modified orders", plotting.plot_modified_energy_orders(
        Fake(orders=[0, 2], errors=[np.array([1e-3, 4e-3]), np.array([1e-7, 1e-6])],
             slopes=[2.0, 4.0], expected=[2, 4], dts=np.array([0.01, 0.02]), method="leapfrog"))


def test_every_figure_uses_unicode_symbols_and_gives_units(runs):
    problems = {name: notation_problems(fig) for name, fig in figures(runs)}
    assert len(problems) >= 20
    assert {name: found for name, found in problems.items() if found} == {}


def test_the_notation_check_finds_tex_and_spelled_out_names():
    # Negative control: labels as some figures had them are caught.
    figure = Figure()
    ax = figure.add_subplot()
    ax.set(xlabel="theta1(0) (rad)", ylabel=r"amplitude $\theta_0$", title="lambda_1")
    ax.plot([0, 1], [0, 1], label="E thick, T thin")
    ax.legend()
    problems = notation_problems(figure)
    assert any("TeX" in p for p in problems) and any("no unit" in p for p in problems)
    assert sum("spelled out" in p for p in problems) == 3  # theta1, \theta, lambda_1


def label_boxes(figure: Figure):
    renderer = figure.canvas.get_renderer() if hasattr(figure.canvas, "get_renderer") else None
    if renderer is None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        renderer = FigureCanvasAgg(figure).get_renderer()
    figure.draw_without_rendering()
    ax = figure.axes[0]
    return [t.get_window_extent(renderer) for t in ax.texts]


def overlapping(boxes) -> int:
    return sum(a.overlaps(b) for k, a in enumerate(boxes) for b in boxes[k + 1:])


def test_close_doublings_share_a_label_that_does_not_pile_up():
    # As near A = 1.07 in notebook 17: 2 -> 4 -> 8 -> 16 within a hundredth of the range.
    cascade = fake_doublings((1, 1.0), (2, 1.066), (4, 1.0785), (8, 1.081), (16, 1.0815))
    figure = plotting.plot_bifurcation(bifurcation(cascade))
    ax = figure.axes[0]
    assert [t.get_text() for t in ax.texts] == ["1→2", "2→4→8→16→32"]
    assert overlapping(label_boxes(figure)) == 0
    assert len(ax.lines) == len(cascade)  # every doubling still has its dashed line
    # Negative control: one label per doubling, as before, piles up.
    texts_before = [(d.value, f"{d.period}→{2 * d.period}") for d in cascade]
    crowded = plotting.plot_bifurcation(bifurcation([]))
    for k, (value, text) in enumerate(texts_before):
        crowded.axes[0].annotate(text, (value, 1.0), xycoords=("data", "axes fraction"),
                                 xytext=(2, -10 - 9 * (k % 3)), textcoords="offset points",
                                 fontsize="x-small")
    assert overlapping(label_boxes(crowded)) > 0


def test_doublings_that_do_not_cascade_are_listed():
    labels = plotting.driven.doubling_labels(fake_doublings((1, 1.0), (4, 1.01)), room=0.05)
    assert labels == [(1.0, "1→2, 4→8")]
