"""The kernel-free simulator's mathematics in Chromium: generated models and methods against
the kernel.

The ES modules of ``pendulum_lab/widgets/static/browser`` (the models' equations printed by
``pendulum_lab.codegen.browser``, the methods written after ``integrators.reference``) are
imported into a Chromium page served from the package's own folder, and compared with the
Python package:

* the generated field, momenta, energies and positions against the model's Python functions
  at random states;
* one browser step of every shipped model and method against ``pl.step`` (the compiled step);
* the energy error of a 20 s run of the browser's engine against ``pl.simulate``'s, to one
  pixel of the simulator's energy-error trace;
* negative controls: a wrong sign in one generated term, a wrong weight in a method.

Tolerances (derived, stated in ``field_tolerance`` and ``step_tolerance``): two evaluations of
one expression in a different order of at most ``N`` rounded operations differ by at most
``N eps M``, ``M`` bounding the magnitudes met (here ``1 +`` the largest input or output). A
step adds ``h`` times a weighted mean of ``s`` field values (weights summing to one, the
implicit ones solved to round-off, where the two stopping points differ by a few ulps), so
it differs by at most ``8 eps (1 + |y|) + s |h| N eps M``.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from browser_engine import FIELD, RUN, STEPS, engine_page, shipped_model_url, shipped_models

import pendulum_lab as pl
from pendulum_lab.integrators.registry import MAIN_METHODS

pytestmark = pytest.mark.browser

EPS = np.finfo(float).eps
MODELS = shipped_models()
#: The simulator's energy-error trace spans +-error_max over (304 - 150) / 2 = 77 pixels
#: (``drawError`` in simulator.js): "plotting precision" is one of them.
TRACE_HALF_HEIGHT_PX = 77
#: Field evaluations per step (stages; the symplectic methods evaluate twice per update).
EVALUATIONS = {"explicit_euler": 1, "semi_implicit_euler": 2, "leapfrog": 4, "rk4": 4, "glrk4": 2}
H = 0.01


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    with engine_page(tmp=tmp_path_factory.mktemp("chromium")) as opened:
        yield opened


def operations(model) -> int:
    """``N``: the arithmetic operations in the printed expressions of the field."""
    system = model.chain
    exprs = [*system.mass_matrix, *system.dlagrangian_dq, *system.generalized_forces,
             *system.momentum_offset, system.kinetic, system.potential]
    return int(sp.count_ops(exprs))


def field_tolerance(model, *values) -> float:
    size = max(float(np.max(np.abs(np.concatenate([np.ravel(v) for v in values])))), 0.0)
    return operations(model) * EPS * (1.0 + size)


def step_tolerance(model, method, y, f) -> float:
    y, f = np.abs(y).max(), np.abs(f).max()
    return 8 * EPS * (1 + y) + EVALUATIONS[method] * H * field_tolerance(model, [y], [f])


def random_states(model, count=6, seed=7):
    """``[t, q, p, omega]`` at random: angles in (-2, 2), a spring's length near its rest, a
    bob in space's horizontal place within 0.8 of its rod's reach."""
    rng = np.random.default_rng(seed)
    n = model.n
    if model.is_chain:
        qs = rng.uniform(-2, 2, (count, n))
    elif model.dimensions == 3:
        qs = rng.uniform(-0.55, 0.55, (count, n))
    else:
        qs = np.column_stack([rng.uniform(0.7, 1.5, count), rng.uniform(-1, 1, count)])
    ws = rng.uniform(-2, 2, (count, n))
    ts = rng.uniform(0, 10, count)
    ps = np.array([model.momenta(q, w, t) for q, w, t in zip(qs, ws, ts)])
    return [[float(t), q.tolist(), p.tolist(), w.tolist()] for t, q, p, w in zip(ts, qs, ps, ws)]


def params_of(model) -> list[float]:
    return [float(v) for v in model.parameter_values.values()]


def field_misfit(page_, model, module) -> float:
    """The largest ratio of a generated function's difference from Python's to its tolerance."""
    page, base, _ = page_
    states = random_states(model)
    out = page.evaluate(FIELD, dict(model=module, methods=f"{base}/browser/methods/index.js",
                                    params=params_of(model), states=states))
    worst = 0.0
    for (t, q, p, w), (dq, dp, momenta, energies, places) in zip(states, out):
        q, p, w = map(np.array, (q, p, w))
        rates = model.vector_field(q, p, t)
        expected = [*rates, p, [model.kinetic_energy(q, w, t), model.potential_energy(q, t)],
                    np.ravel(np.column_stack(model.positions(q, t)))]
        for got, want in zip((dq, dp, momenta, energies, places), expected):
            tolerance = field_tolerance(model, q, p, w, want)
            worst = max(worst, np.max(np.abs(np.array(got) - np.asarray(want))) / tolerance)
    return worst


def step_misfit(page_, model, module, method, tableau=None) -> float:
    """The largest ratio of a browser step's difference from ``pl.step``'s to its tolerance."""
    page, base, _ = page_
    states = [s[:3] for s in random_states(model, count=4, seed=11)]
    steps = page.evaluate(STEPS, dict(model=module, methods=f"{base}/browser/methods/index.js",
                                      method=method, params=params_of(model), states=states,
                                      h=H, tableau=tableau))
    worst = 0.0
    for (t, q, p), (q1, p1) in zip(states, steps):
        want = pl.step(model, np.array(q), p0=np.array(p), dt=H, method=method, t0=t)
        y = np.concatenate([q, p])
        f = np.concatenate(model.vector_field(np.array(q), np.array(p), t))
        difference = np.max(np.abs(np.concatenate([q1, p1]) - np.concatenate(want)))
        worst = max(worst, difference / step_tolerance(model, method, y, f))
    return worst


def start_of(model) -> list[float]:
    """A start in the regular part of phase space: round-off does not grow into the trace
    within 20 s (a chaotic start would separate the two runs by itself)."""
    return [0.5, 0.3, 0.1][: model.n] if model.is_chain else list(model.start)


def energy_error_misfit(page_, model, module, method, tableau=None) -> tuple[float, float]:
    """The browser's 20 s energy error against the kernel's: (largest difference, one pixel)."""
    page, base, _ = page_
    start = start_of(model)
    run = page.evaluate(RUN, dict(engine=f"{base}/browser/engine.js", model=module,
                                  params=params_of(model), method=method, theta0=start,
                                  omega0=[0.0] * model.n, tEnd=20.0, dt=0.01, tableau=tableau))
    kernel = pl.simulate(model, start, np.zeros(model.n), t_end=20.0, dt=0.01, method=method)
    energy = np.array(run["energy"])
    assert len(energy) == len(kernel.t) == 2001
    pixel = np.max(np.abs(kernel.energy_error)) / TRACE_HALF_HEIGHT_PX
    return float(np.max(np.abs((energy - energy[0]) - kernel.energy_error))), float(pixel)


def refused_in_the_browser(model) -> dict:
    """The methods the browser's page refuses for ``model``, with the reason it shows."""
    from pendulum_lab.widgets.browser import browser_config

    return browser_config(model, method="rk4")["refused"]


CASES = [(stem, method) for stem in MODELS for method in MAIN_METHODS
         if method not in refused_in_the_browser(MODELS[stem])]


@pytest.mark.parametrize("stem", list(MODELS))
def test_the_generated_field_equals_the_python_field_at_random_states(page, stem):
    _, base, _ = page
    assert field_misfit(page, MODELS[stem], shipped_model_url(base, stem)) <= 1.0


def test_a_model_in_space_prints_its_positions_with_their_height(page):
    from pendulum_lab.widgets.browser import model_module

    spherical = pl.spherical_pendulum()
    source = model_module(spherical).source
    assert "export const DIMENSIONS = 3;" in source
    assert field_misfit(page, spherical, source) <= 1.0
    # negative control: the bob drawn above the pivot instead of below it is caught
    wrong = source.replace("out[2] = -Math.sqrt", "out[2] = Math.sqrt")
    assert wrong != source and field_misfit(page, spherical, wrong) > 1.0


@pytest.mark.parametrize(("stem", "method"), CASES)
def test_one_browser_step_agrees_with_pl_step(page, stem, method):
    _, base, _ = page
    assert step_misfit(page, MODELS[stem], shipped_model_url(base, stem), method) <= 1.0


@pytest.mark.parametrize(("stem", "method"), CASES)
def test_the_energy_error_over_20_s_matches_the_kernels_to_a_pixel(page, stem, method):
    _, base, _ = page
    difference, pixel = energy_error_misfit(page, MODELS[stem], shipped_model_url(base, stem),
                                            method)
    assert difference <= pixel


@pytest.mark.parametrize("stem", list(MODELS))
def test_the_browser_refuses_exactly_the_methods_the_kernel_refuses(stem):
    model, refused = MODELS[stem], refused_in_the_browser(MODELS[stem])
    for method in MAIN_METHODS:
        try:
            pl.step(model, np.full(model.n, 0.1), np.zeros(model.n), dt=H, method=method)
        except ValueError as err:
            assert method in refused and refused[method].split(": ", 1)[1] in str(err)
        else:
            assert method not in refused
    # the damped, driven pendulum: the two symplectic methods (the kernel says why)
    assert bool(refused) == (stem == "driven_pendulum")


# ---- negative controls: each check fails on a defect of the kind it is there for -----------
def wrong_sign_module(base) -> str:
    """The double pendulum's module with the sign of one term of dp[1] flipped."""
    from pendulum_lab.widgets.browser import BROWSER_FOLDER

    text = (BROWSER_FOLDER / "models" / "double_pendulum.js").read_text()
    line = next(x for x in text.splitlines() if x.strip().startswith("dp[1] ="))
    flipped = line.replace(" + ", " - ", 1) if " + " in line else line.replace(" - ", " + ", 1)
    assert flipped != line
    return text.replace(line, flipped)


def test_a_wrong_sign_in_one_generated_term_fails_both_checks(page):
    _, base, _ = page
    model = MODELS["double_pendulum"]
    module = wrong_sign_module(base)
    assert field_misfit(page, model, module) > 1e6
    assert step_misfit(page, model, module, "rk4") > 1e3


def test_a_wrong_weight_fails_the_step_and_the_energy_checks(page):
    _, base, _ = page
    model, module = MODELS["double_pendulum"], shipped_model_url(base, "double_pendulum")
    rk4 = {"a": [[0, 0, 0, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 1, 0]],
           "b": [1 / 6, 1 / 3, 1 / 6, 1 / 3], "c": [0, 0.5, 0.5, 1]}
    assert step_misfit(page, model, module, "rk4", tableau=rk4) > 1e3
    difference, pixel = energy_error_misfit(page, model, module, "rk4", tableau=rk4)
    assert difference > 10 * pixel
    root = np.sqrt(3) / 6
    gauss = {"a": [[0.25, 0.25 - root], [0.25 + root, 0.25]], "b": [0.6, 0.4],
             "c": [0.5 - root, 0.5 + root]}
    assert step_misfit(page, model, module, "glrk4", tableau=gauss) > 1e3


def test_nothing_was_fetched_from_another_host(page):
    p, base, requests = page
    assert requests and all(u.startswith(base) or u.startswith("data:") for u in requests)
    assert p.errors == []


# ---- the simulator without a kernel, mounted in a page as the website mounts it -------------
@pytest.fixture(scope="module")
def mounted(page):
    """A page holding two kernel-free simulators (the double and the driven pendulum), as
    ``simulator_html`` writes them for the website."""
    from pendulum_lab.widgets.browser import browser_config, simulator_html

    p, base, _ = page
    body = "".join(simulator_html(browser_config(model, method=method, t_end=10.0),
                                  "/browser/engine.js",
                                  fallback_html='<p class="still">the still picture</p>')
                   for model, method in ((MODELS["double_pendulum"], "glrk4"),
                                         (MODELS["driven_pendulum"], "rk4")))
    html = f'<!doctype html><html><head><link rel="stylesheet" href="/live.css"></head>' \
           f"<body>{body}</body></html>"
    p.route(f"{base}/trial.html", lambda route: route.fulfill(body=html, content_type="text/html"))
    p.goto(f"{base}/trial.html")
    p.wait_for_function(
        "() => document.querySelectorAll('.plab-live[data-run=\"1\"]').length === 2")
    return p


def live_data(p, index=0) -> dict:
    return p.evaluate("k => ({...document.querySelectorAll('.plab-live')[k].dataset})", index)


def test_the_kernel_free_simulator_plays_a_run_computed_in_the_browser(mounted):
    p = mounted
    first = live_data(p)
    assert int(first["states"]) < 1001 and first["playing"] == "1"  # integrated as it plays
    p.wait_for_timeout(600)
    later = live_data(p)
    assert int(later["frames"]) > int(first["frames"]) + 10
    assert float(later["time"]) > float(first["time"]) + 0.3
    assert int(later["states"]) > int(first["states"]) + 30
    status = p.locator(".plab-engine-status").first
    # on a loaded machine it may be falling behind, and say so
    assert "1000 steps of glrk4 (Δt = 0.01 s) computed in the browser as the motion plays" \
        in status.text_content() or status.get_attribute("data-kind") == "behind"
    assert p.locator(".plab-still").count() == 2  # the still picture stays for print


def test_method_and_step_boxes_recompute_and_a_refused_method_says_why(mounted):
    p = mounted
    p.locator("select[aria-label=method]").first.select_option("leapfrog")
    p.wait_for_function("() => document.querySelector('.plab-live').dataset.run === '2'")
    p.locator("select[aria-label='time step']").first.select_option("0.02")
    p.wait_for_function("() => document.querySelector('.plab-live').dataset.run === '3'")
    text = p.locator(".plab-engine-status").first.text_content()
    assert "500 steps of leapfrog (Δt = 0.02 s)" in text \
        or "steps of leapfrog (Δt = 0.02 s) this frame called for" in text  # loaded: behind
    driven = p.locator(".plab-browser-sim").nth(1)
    driven.locator("select[aria-label=method]").select_option("leapfrog")
    status = driven.locator(".plab-engine-status")
    assert "leapfrog cannot integrate this model" in status.text_content()
    assert status.get_attribute("data-kind") == "error"
    assert live_data(p, 1)["run"] == "1"  # the previous motion goes on
    assert driven.locator("select[aria-label=method]").input_value() == "rk4"


def test_dragging_a_bob_restarts_the_motion_from_there_in_the_browser(mounted):
    p = mounted
    before = live_data(p)["run"]
    canvas = p.locator(".plab-live-canvas").first
    box = canvas.bounding_box()
    s = float(live_data(p)["scale"])
    # pause at the start, then drag the upper bob to the right of the pivot
    p.evaluate("() => { const el = document.querySelector('.plab-live'); el.focus(); }")
    p.keyboard.press("Home")
    p.wait_for_function("() => document.querySelector('.plab-live').dataset.time === '0.0000'")
    p.wait_for_timeout(100)  # a frame drawn at t = 0
    theta = [float(a) for a in live_data(p)["theta"].split(",")]
    assert theta == pytest.approx([2.0, 2.5], abs=1e-5)
    x0 = box["x"] + 170 + s * np.sin(theta[0])
    y0 = box["y"] + 170 + s * np.cos(theta[0])
    p.mouse.move(x0, y0)
    p.mouse.down()
    p.mouse.move(box["x"] + 170 + 60, box["y"] + 170, steps=4)
    p.mouse.up()
    p.wait_for_function(f"() => document.querySelector('.plab-live').dataset.run !== '{before}'")
    p.keyboard.press("Home")
    p.wait_for_timeout(100)
    angles = [float(a) for a in live_data(p)["theta"].split(",")]
    assert angles[0] == pytest.approx(np.pi / 2, abs=0.02)
    assert angles[1] == pytest.approx(theta[1], abs=1e-4)
    assert p.errors == []
