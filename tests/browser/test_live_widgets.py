"""The browser-drawn widgets of ``pendulum_lab.widgets`` in a real JupyterLab in Chromium.

The demo notebook ``live_demo/live_widgets.ipynb`` shows the live simulator,
the clickable Poincare section and the clickable phase portrait. The harness
of ``lab_harness.py`` serves that folder (``PENDULUM_LAB_NOTEBOOKS``) and runs
all cells; then the tests play, drag, press keys and click as a student
would, and read what the widgets report in their ``data-*`` attributes and
in the ipywidgets sliders (which the kernel sets). Every request the page
makes is recorded: none may leave the local server.
"""

from __future__ import annotations

import json
import math
import os
import re
import time
from pathlib import Path

import pytest
from lab_harness import SCREENSHOTS, VIEWPORT, NotebookRunner

pytestmark = pytest.mark.browser

DEMO = Path(__file__).resolve().parent / "live_demo"
NOTEBOOK = "live_widgets.ipynb"
SIM, CLICK = ".plab-live", ".plab-click"
PIVOT = (170.0, 170.0)  # CSS pixels of the pivot in the simulator's canvas (simulator.js)


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    """One JupyterLab on the demo folder, its page after "run all", and the requests seen."""
    runner = NotebookRunner(lambda: tmp_path_factory.mktemp("live-lab"))
    previous = os.environ.get("PENDULUM_LAB_NOTEBOOKS")
    os.environ["PENDULUM_LAB_NOTEBOOKS"] = str(DEMO)
    requests: list[str] = []
    try:
        runner.start()
        # "Copy as code" writes to the clipboard, and the tests read it back.
        runner.context.grant_permissions(
            ["clipboard-read", "clipboard-write"], origin=runner.server.url
        )
        runner.context.on("request", lambda request: requests.append(request.url))
        run = runner.get(NOTEBOOK)
        yield runner, run, requests
    finally:
        if previous is None:
            os.environ.pop("PENDULUM_LAB_NOTEBOOKS", None)
        else:
            os.environ["PENDULUM_LAB_NOTEBOOKS"] = previous
        runner.close()


@pytest.fixture(scope="module")
def page(lab):
    _, run, _ = lab
    if not run.ok:
        pytest.fail(f"run-all of the demo notebook failed:\n{run.report()}", pytrace=False)
    run.page.wait_for_function(
        f"() => document.querySelector('{SIM}') && document.querySelector('{SIM}').dataset.states"
        " === '6001'",
        timeout=60_000,
    )
    return run.page


def data(page, selector: str, index: int = 0) -> dict:
    return page.evaluate(
        "([s, k]) => ({...document.querySelectorAll(s)[k].dataset})", [selector, index]
    )


def wait_data(page, selector, key, predicate: str, index: int = 0, timeout: float = 30_000):
    """Wait until ``predicate`` (JavaScript over ``v``, the attribute's text) holds."""
    page.wait_for_function(
        f"([s, k, key]) => {{ const el = document.querySelectorAll(s)[k];"
        f" const v = el && el.dataset[key]; return v !== undefined && ({predicate}); }}",
        arg=[selector, index, key],
        timeout=timeout,
    )


def slider_readouts(page, selector: str) -> dict[str, str]:
    """Description -> value box text of the sliders in the cell that shows ``selector`` (with
    ASCII minus signs: the value boxes show U+2212)."""
    readouts = page.evaluate(
        """(s) => {
            const cell = document.querySelector(s).closest('.jp-Cell');
            const out = {};
            for (const slider of cell.querySelectorAll('.widget-slider')) {
                const label = slider.querySelector('.widget-label');
                const readout = slider.querySelector('.widget-readout');
                if (label && readout) out[label.textContent.trim()] = readout.textContent.trim();
            }
            return out;
        }""",
        selector,
    )
    return {label: text.replace("\u2212", "-") for label, text in readouts.items()}


def canvas_origin(page, selector: str, canvas: str) -> tuple[float, float]:
    box = page.locator(f"{selector} {canvas}").first.bounding_box()
    return box["x"], box["y"]


def press(page, selector: str, *keys: str) -> None:
    page.evaluate("(s) => document.querySelector(s).focus()", selector)
    for key in keys:
        page.keyboard.press(key)


def kernel_output(page, code: str) -> str:
    """What ``code`` prints, run in the demo's kernel (beside the cells, not in one)."""
    return page.evaluate(
        """async ([path, code]) => {
            const kernel = window.__plab.panel(path).sessionContext.session.kernel;
            const future = kernel.requestExecute({ code, store_history: false });
            let out = "";
            future.onIOPub = (msg) => {
                if (msg.header.msg_type === "stream") out += msg.content.text;
                if (msg.header.msg_type === "error") out += "ERROR " + msg.content.evalue;
            };
            await future.done;
            return out;
        }""",
        [NOTEBOOK, code],
    )


def description(page) -> str:
    return page.locator(f"{SIM} .plab-description").first.text_content()


def numbers_in(text: str, *names: str) -> list[float]:
    """The values of ``name = value`` pairs in a description (U+2212 read as a minus)."""
    text = text.replace("\u2212", "-")
    return [float(re.search(rf"{re.escape(name.replace(chr(0x2212), '-'))} = (-?[0-9.e+-]+)",
                            text).group(1).rstrip(".")) for name in names]


def test_the_demo_runs_cleanly(lab, page):
    _, run, _ = lab
    assert page.locator(SIM).count() == 4 and page.locator(CLICK).count() == 2
    # 60 s at 10 ms: 6001 states, sent in two chunks of at most 4096.
    assert data(page, SIM)["chunks"] == "2"
    page.locator(SIM).first.scroll_into_view_if_needed()
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    page.locator(SIM).first.screenshot(path=str(SCREENSHOTS / "live_simulator.png"))
    assert not run.console_errors, run.console_errors


def test_play_advances_frames_at_the_playback_speed(page):
    press(page, SIM, "Home")  # paused at t = 0, far from the end of the 60 s run
    frames_at_home = int(data(page, SIM)["frames"])
    press(page, SIM, "Space")
    wait_data(page, SIM, "playing", "v === '1'")
    # The first frame after play only takes the display's clock (it has no previous frame to
    # measure from); until a later frame has moved the time, `clock` may be a paused frame's.
    page.wait_for_function(
        "([s, n]) => { const d = document.querySelector(s).dataset;"
        " return Number(d.frames) > n && Number(d.time) > 0; }",
        arg=[SIM, frames_at_home],
    )
    first = data(page, SIM)
    page.wait_for_timeout(1500)
    second = data(page, SIM)
    frames = int(second["frames"]) - int(first["frames"])
    seconds = (float(second["clock"]) - float(first["clock"])) / 1000
    advanced = float(second["time"]) - float(first["time"])
    print(f"{frames} frames in {seconds:.3f} s: {frames / seconds:.1f} frames per second")
    assert frames > 10, "the animation did not advance"
    # Playback maps the display's clock to simulated time at `speed` (1x here) ...
    assert advanced == pytest.approx(seconds, abs=2e-3)
    # ... and at 2x twice as fast (negative control of the check above).
    press(page, SIM, "ArrowUp")
    wait_data(page, SIM, "time", "true")
    page.wait_for_timeout(200)
    first = data(page, SIM)
    page.wait_for_timeout(1000)
    second = data(page, SIM)
    seconds = (float(second["clock"]) - float(first["clock"])) / 1000
    advanced = float(second["time"]) - float(first["time"])
    assert advanced == pytest.approx(2 * seconds, abs=4e-3)
    assert advanced != pytest.approx(seconds, abs=0.1)
    press(page, SIM, "ArrowDown")


def test_keyboard_steps_and_changes_speed(page):
    active_cell = "() => window.jupyterapp.shell.currentWidget.content.activeCellIndex"
    cell_before = page.evaluate(active_cell)
    press(page, SIM, "Home")
    wait_data(page, SIM, "playing", "v === '0'")
    wait_data(page, SIM, "time", "Number(v) === 0")
    press(page, SIM, "ArrowRight", "ArrowRight", "ArrowRight")
    wait_data(page, SIM, "time", "Math.abs(Number(v) - 0.03) < 1e-6")
    press(page, SIM, "ArrowLeft")
    wait_data(page, SIM, "time", "Math.abs(Number(v) - 0.02) < 1e-6")
    speed = page.locator(f"{SIM} .plab-speed").first
    assert speed.input_value() == "1"
    press(page, SIM, "ArrowUp")
    assert speed.input_value() == "2"
    press(page, SIM, "ArrowDown", "ArrowDown")
    assert speed.input_value() == "0.5"
    press(page, SIM, "ArrowUp")
    press(page, SIM, "End")
    wait_data(page, SIM, "time", "Math.abs(Number(v) - 60) < 1e-6")
    press(page, SIM, "k")
    wait_data(page, SIM, "playing", "v === '1'")  # from the end, play starts again at 0
    press(page, SIM, "k")
    wait_data(page, SIM, "playing", "v === '0'")
    # The keys went to the widget, not to JupyterLab ("k" selects the cell above).
    assert page.evaluate(active_cell) == cell_before


def test_the_live_region_describes_the_state_shown(page):
    region = page.locator(f"{SIM} .plab-description").first
    assert region.get_attribute("aria-live") == "polite"
    press(page, SIM, "Home")
    wait_data(page, SIM, "playing", "v === '0'")
    page.wait_for_function(
        "(s) => document.querySelector(s + ' .plab-description').textContent"
        ".startsWith('Paused at t = 0.00 s')", arg=SIM)
    press(page, SIM, "ArrowRight", "ArrowRight")
    page.wait_for_function(
        "(s) => document.querySelector(s + ' .plab-description').textContent"
        ".startsWith('Paused at t = 0.02 s')", arg=SIM)
    text = description(page)
    assert "of 60.0 s (glrk4, Δt = 0.01 s)" in text and "energy error E − E(0)" in text
    kinetic, potential, total, error = numbers_in(
        text, "Kinetic energy T", "potential energy V", "total E", "E − E(0)")
    # The kernel's run at the state shown (step 2: saved states are 10 ms apart).
    truth = json.loads(kernel_output(page, (
        "import json; tr = sim.trajectory\n"
        "print(json.dumps([float(tr.kinetic[2]), float(tr.potential[2]), float(tr.energy[2]),"
        " float(tr.energy_error[2])]))")))
    assert [kinetic, potential, total] == pytest.approx(truth[:3], abs=1.5e-3)
    assert error == pytest.approx(truth[3], rel=2e-2, abs=1e-12)
    # Playing is announced once, not frame by frame; pausing describes the new moment.
    press(page, SIM, "Space")
    page.wait_for_function(
        "(s) => document.querySelector(s + ' .plab-description').textContent"
        ".startsWith('Playing at 1× speed')", arg=SIM)
    page.wait_for_timeout(600)
    assert description(page).startswith("Playing at 1× speed from t = 0.02 s")
    press(page, SIM, "Space")
    page.wait_for_function(
        "(s) => { const t = document.querySelector(s + ' .plab-description').textContent;"
        " return t.startsWith('Paused at') && !t.startsWith('Paused at t = 0.02 s'); }",
        arg=SIM)


def test_copy_as_code_puts_the_runs_simulate_call_on_the_clipboard(page):
    import numpy as np

    cell = page.locator(SIM).first.locator("xpath=ancestor::div[contains(@class,'jp-Cell')]")
    line = cell.locator(".plab-statusline").first
    assert line.get_attribute("data-code") == "1"
    line.locator("button", has_text="Copy as code").click()
    page.wait_for_function(
        "(c) => c.dataset.copied === '1'", arg=line.element_handle(), timeout=10_000)
    code = page.evaluate("() => navigator.clipboard.readText()")
    assert "pl.simulate(model, " in code and "method='glrk4'" in code
    # The copied code, run here, computes the kernel's run number for number.
    namespace: dict = {}
    exec(compile(code, "<clipboard>", "exec"), namespace)  # noqa: S102 - the code under test
    ours = namespace["traj"]
    theirs = json.loads(kernel_output(page, (
        "import json; tr = sim.trajectory\n"
        "print(json.dumps([tr.theta[-1].tolist(), tr.omega[-1].tolist(), len(tr.t)]))")))
    assert ours.theta[-1].tolist() == theirs[0] and ours.omega[-1].tolist() == theirs[1]
    assert len(ours.t) == theirs[2] == 6001
    # And it is the run the canvas plays: its first state.
    press(page, SIM, "Home")
    wait_data(page, SIM, "time", "Number(v) === 0")
    shown = [float(v) for v in data(page, SIM)["theta"].split(",")]
    np.testing.assert_allclose(shown, ours.theta[0], atol=1e-5)


def test_the_explorer_is_keyboard_operable_and_announces_each_run(page):
    explorer = page.locator(".jp-Cell").filter(has=page.locator(".widget-image")).last
    explorer.scroll_into_view_if_needed()
    status = explorer.locator(".plab-statusline .plab-status-text").first
    assert status.get_attribute("role") == "status"
    before = status.text_content()
    active_cell = "() => window.jupyterapp.shell.currentWidget.content.activeCellIndex"
    handle = explorer.locator(".widget-slider").first.locator(".noUi-handle").first
    handle.focus()  # (focus inside a cell makes it JupyterLab's active cell)
    cell_before = page.evaluate(active_cell)
    # θ₁ one step (0.01 rad) up, from the keyboard alone; in JupyterLab's command mode the
    # same key would select the cell above.
    page.keyboard.press("ArrowUp")
    readout = explorer.locator(".widget-slider").first.locator(".widget-readout").first
    page.wait_for_function("(r) => r.textContent.trim() === '2.010'", arg=readout.element_handle())
    page.wait_for_function(
        "([s, b]) => s.textContent !== b && !s.closest('.plab-statusline').dataset.kind"
        ".startsWith('busy')", arg=[status.element_handle(), before], timeout=30_000)
    text = status.text_content()
    assert text.startswith("500 steps of rk4") and "max |E − E(0)|" in text
    reported = json.loads(kernel_output(page, "import json; print(json.dumps(float("
                                              "ex.trajectory.theta[0, 0])))"))
    assert reported == pytest.approx(2.01, abs=1e-12)
    assert page.evaluate(active_cell) == cell_before  # the key stayed with the slider


def test_a_step_typed_into_the_box_reruns_the_explorer(page):
    explorer = page.locator(".jp-Cell").filter(has=page.locator(".widget-image")).last
    explorer.scroll_into_view_if_needed()
    status = explorer.locator(".plab-statusline .plab-status-text").first
    box = explorer.locator(".plab-step-box input").first
    before = status.text_content()
    assert "dt = 0.01 s" in before
    box.click()
    page.keyboard.press("ControlOrMeta+a")
    page.keyboard.type("0.005")
    page.keyboard.press("Enter")
    page.wait_for_function(
        "([s, b]) => s.textContent !== b && !s.closest('.plab-statusline').dataset.kind"
        ".startsWith('busy')", arg=[status.element_handle(), before], timeout=30_000)
    text = status.text_content()
    assert "dt = 0.005 s" in text and "steps of rk4" in text, text
    assert float(box.input_value()) == 0.005  # the box shows the step that ran
    ran = json.loads(kernel_output(page, "import json; print(json.dumps(ex.trajectory.dt))"))
    assert ran == 0.005
    # negative control: a step typed but not committed (no Enter, no blur) runs nothing
    box.click()
    page.keyboard.press("ControlOrMeta+a")
    page.keyboard.type("0.02")
    page.wait_for_timeout(1500)
    assert json.loads(kernel_output(page, "import json; print(json.dumps(ex.trajectory.dt))")
                      ) == 0.005
    page.keyboard.press("Enter")
    page.wait_for_function("(s) => s.textContent.includes('dt = 0.02 s')",
                           arg=status.element_handle(), timeout=30_000)


OVERFLOW_JS = """(cell) => {
    // How far (CSS pixels) any control of the cell's widget output reaches past the output's
    // right edge (0: everything inside).
    const area = cell.querySelector('.jp-OutputArea-output');
    const right = area.getBoundingClientRect().right;
    let worst = 0;
    for (const el of cell.querySelectorAll('.plab-controls .widget-readout, '
                                          + '.plab-controls select, .plab-controls input')) {
        const box = el.getBoundingClientRect();
        if (box.width > 0) worst = Math.max(worst, box.right - right);
    }
    return worst;
}"""


def test_a_system_with_five_parameters_keeps_its_controls_inside_the_cell(page):
    # The Kapitza pendulum (a, w, m, l, g) in the live simulator, in a window as narrow as a
    # laptop's half screen.
    page.set_viewport_size({"width": 1000, "height": 900})
    try:
        cell = page.locator(SIM).nth(KAPITZA).locator(
            "xpath=ancestor::div[contains(@class,'jp-CodeCell')]")
        cell.scroll_into_view_if_needed()
        page.wait_for_timeout(500)
        SCREENSHOTS.mkdir(parents=True, exist_ok=True)
        cell.screenshot(path=str(SCREENSHOTS / "kapitza-live-controls.png"))
        assert page.locator(".plab-controls").count() >= 1
        assert cell.evaluate(OVERFLOW_JS) <= 0.5
        text = cell.locator(".plab-statusline .plab-status-text").first.text_content()
        assert "besides the potential" not in text and "the forces' work" not in text, text
        assert "the work of the moving point" in text, text
        # negative control: without the wrapping the columns run past the right edge
        cell.evaluate("(c) => { c.querySelector('.plab-controls').style.flexWrap = 'nowrap'; }")
        page.wait_for_timeout(300)
        overflow = cell.evaluate(OVERFLOW_JS)
        cell.screenshot(path=str(SCREENSHOTS / "kapitza-live-controls-nowrap.png"))
        cell.evaluate("(c) => { c.querySelector('.plab-controls').style.flexWrap = ''; }")
        assert overflow > 20
    finally:
        page.set_viewport_size(VIEWPORT)


def drag_between(page, start, to) -> None:
    """Drag the mouse from page pixel ``start`` to ``to`` in five moves, as a hand would."""
    page.mouse.move(*start)
    page.mouse.down()
    for k in range(1, 6):
        f = k / 5
        page.mouse.move(start[0] + f * (to[0] - start[0]), start[1] + f * (to[1] - start[1]))
    page.mouse.up()


def drag_bob(page, bob: int, to: tuple[float, float]) -> float:
    """Drag bob ``bob`` (0-based) of the paused simulator to canvas pixel ``to``; return the
    angle from the arm's joint to the release point the widget reported (``data-release``, in
    metres, y up), which must lie under the pointer."""
    state = data(page, SIM)
    scale = float(state["scale"])
    theta = [float(v) for v in state["theta"].split(",")]
    x0, y0 = canvas_origin(page, SIM, "canvas")
    joint = [0.0, 0.0]  # metres, y up
    for j in range(bob):
        joint = [joint[0] + math.sin(theta[j]), joint[1] - math.cos(theta[j])]
    bob_at = (joint[0] + math.sin(theta[bob]), joint[1] - math.cos(theta[bob]))
    start = (PIVOT[0] + scale * bob_at[0], PIVOT[1] - scale * bob_at[1])
    drag_between(page, (x0 + start[0], y0 + start[1]), (x0 + to[0], y0 + to[1]))
    wait_data(page, SIM, "release", "true")
    x, y = (float(v) for v in data(page, SIM)["release"].split(","))
    pointer = (PIVOT[0] + scale * x, PIVOT[1] - scale * y)
    assert math.dist(pointer, to) < 1.0, (pointer, to)  # the widget read the pointer right
    return math.atan2(x - joint[0], -(y - joint[1]))


def test_dragging_a_bob_restarts_the_motion_from_there(page):
    press(page, SIM, "Home")
    wait_data(page, SIM, "playing", "v === '0'")
    run_before = int(data(page, SIM)["run"])
    before = slider_readouts(page, SIM)
    # The first bob to the right of the pivot and a little up.
    expected = drag_bob(page, 0, (PIVOT[0] + 60.0, PIVOT[1] - 20.0))
    assert expected == pytest.approx(math.atan2(60, -20), abs=0.02)  # from the downward vertical
    wait_data(page, SIM, "run", f"Number(v) === {run_before + 1}")
    wait_data(page, SIM, "states", "v === '6001'")
    after = slider_readouts(page, SIM)
    assert after["θ₁ (rad)"] != before["θ₁ (rad)"]
    assert after["θ₁ (rad)"] == f"{expected:.3f}"
    assert float(after["ω₁ (rad/s)"]) == 0.0 and float(after["ω₂ (rad/s)"]) == 0.0
    # The new run starts where the bob was released, the second arm unchanged.
    press(page, SIM, "Home")
    wait_data(page, SIM, "time", "Number(v) === 0")
    theta = [float(v) for v in data(page, SIM)["theta"].split(",")]
    assert theta[0] == pytest.approx(expected, abs=1e-5)
    assert after["θ₂ (rad)"] == before["θ₂ (rad)"]


def test_a_drag_beyond_the_chain_is_clamped(page):
    press(page, SIM, "Home")
    wait_data(page, SIM, "playing", "v === '0'")
    run_before = int(data(page, SIM)["run"])
    x0, _ = canvas_origin(page, SIM, "canvas")
    # Far outside the canvas to the left: the second arm points that way; no error.
    expected = drag_bob(page, 1, (-x0 + 5.0, PIVOT[1] + 40.0))
    wait_data(page, SIM, "run", f"Number(v) === {run_before + 1}")
    after = slider_readouts(page, SIM)
    assert after["θ₂ (rad)"] == f"{expected:.3f}"
    status = page.locator(f"{SIM} .plab-status").first
    assert status.get_attribute("data-kind") != "error", status.text_content()


ELASTIC, KAPITZA = 1, 2  # the live simulators of the systems given by their points


def paused_at_start(page, index: int) -> dict:
    """Pause simulator ``index`` at its first state once its run is in; its data attributes."""
    page.locator(SIM).nth(index).scroll_into_view_if_needed()
    page.evaluate("(k) => document.querySelectorAll('.plab-live')[k].focus()", index)
    page.keyboard.press("Home")
    wait_data(page, SIM, "playing", "v === '0'", index)
    wait_data(page, SIM, "time", "Number(v) === 0", index)
    return data(page, SIM, index)


def drawn_points(state: dict) -> list[tuple[float, float]]:
    return [tuple(float(c) for c in pair.split()) for pair in state["points"].split(",")]


def kernel_positions(page, name: str) -> list[list[float]]:
    """The points of simulator ``name``'s model at its run's first state, from the kernel."""
    return json.loads(kernel_output(page, (
        f"import json, numpy as np; m = {name}.model; q = {name}.trajectory.theta[0]; "
        "print(json.dumps(np.stack(m.positions(q, 0.0), -1).tolist()))")))


def point_pixel(page, index: int, state: dict, point: int) -> tuple[float, float]:
    x0, y0 = (page.locator(f"{SIM} canvas").nth(index).bounding_box()[k] for k in ("x", "y"))
    x, y = drawn_points(state)[point]
    scale = float(state["scale"])
    return x0 + PIVOT[0] + scale * x, y0 + PIVOT[1] - scale * y


def test_a_system_is_drawn_at_the_points_the_kernel_computes(page):
    wait_data(page, SIM, "states", "v === '1001'", ELASTIC)
    state = paused_at_start(page, ELASTIC)
    drawn = drawn_points(state)
    expected = kernel_positions(page, "elastic")
    assert len(drawn) == len(expected) == 1
    assert drawn[0] == pytest.approx(expected[0], abs=1e-4)  # float32 on the way
    # Control: the drawing is not the chain's (a unit rod at the first coordinate's angle).
    theta = [float(v) for v in state["theta"].split(",")]
    assert math.dist(drawn[0], (math.sin(theta[0]), -math.cos(theta[0]))) > 0.1


def test_dragging_a_systems_point_places_its_coordinates_there(page):
    state = paused_at_start(page, ELASTIC)
    run_before = int(state["run"])
    start = point_pixel(page, ELASTIC, state, 0)
    drag_between(page, start, (start[0] + 45.0, start[1] + 30.0))
    wait_data(page, SIM, "run", f"Number(v) === {run_before + 1}", ELASTIC)
    x, y = (float(v) for v in data(page, SIM, ELASTIC)["release"].split(","))
    # The kernel's new start puts the bob where it was released, at rest.
    assert kernel_positions(page, "elastic")[0] == pytest.approx([x, y], abs=1e-7)
    assert json.loads(kernel_output(page, "print(elastic.trajectory.omega[0].tolist())")) == [
        0.0, 0.0]


def test_dragging_a_shaken_pivot_is_refused_with_a_sentence(page):
    wait_data(page, SIM, "states", "v === '501'", KAPITZA)
    state = paused_at_start(page, KAPITZA)
    run_before = int(state["run"])
    pivot = point_pixel(page, KAPITZA, state, 0)
    page.mouse.move(*pivot)
    page.mouse.down()
    page.mouse.up()
    wait_data(page, SIM, "refused", "v === '0'", KAPITZA)
    status = page.locator(f"{SIM} .plab-status").nth(KAPITZA)
    assert "does not move with the coordinates" in status.text_content()
    assert int(data(page, SIM, KAPITZA)["run"]) == run_before  # nothing was recomputed
    # Control: the bob of the same simulator can be dragged.
    bob = point_pixel(page, KAPITZA, state, 1)
    page.mouse.move(*bob)
    page.mouse.down()
    page.mouse.move(bob[0] + 30.0, bob[1])
    page.mouse.up()
    wait_data(page, SIM, "run", f"Number(v) === {run_before + 1}", KAPITZA)


SPHERICAL = 3  # the live simulator of the spherical pendulum, a system in space


def test_a_drag_from_above_sets_the_kernels_start_of_a_system_in_space(page):
    """The kernel's engine: seen from above, a dragged bob starts where it is released; seen at
    an angle, the same drag turns the view (negative control)."""
    wait_data(page, SIM, "states", "v === '201'", SPHERICAL)
    state = paused_at_start(page, SPHERICAL)
    run_before = int(state["run"])
    box = page.locator(f"{SIM} canvas").nth(SPHERICAL).bounding_box()
    x0, y0 = box["x"], box["y"]
    scale = float(state["scale"])
    (x, y, z), = drawn_points(state)
    assert x * x + y * y + z * z == pytest.approx(1.0, abs=1e-5)  # the rod's length, z sent
    turn, tilt = (float(v) for v in state["view"].split(","))
    pivot = [float(v) for v in state["pivot"].split(",")]
    across = x * math.cos(turn) + y * math.sin(turn)
    up = (-x * math.sin(turn) + y * math.cos(turn)) * math.sin(tilt) + z * math.cos(tilt)
    target = (x0 + PIVOT[0] + 0.3 * scale, y0 + PIVOT[1] + 0.2 * scale)
    drag_between(page, (x0 + pivot[0] + scale * across, y0 + pivot[1] - scale * up), target)
    wait_data(page, SIM, "view", f"v !== '{state['view']}'", SPHERICAL)
    assert int(data(page, SIM, SPHERICAL)["run"]) == run_before
    status = page.locator(f"{SIM} .plab-status").nth(SPHERICAL)
    assert "press “top”" in status.text_content()
    page.locator(SIM).nth(SPHERICAL).get_by_role("button", name="top").click()
    wait_data(page, SIM, "view", "v.endsWith(',1.57080')", SPHERICAL)
    drag_between(page, (x0 + PIVOT[0] + scale * x, y0 + PIVOT[1] - scale * y), target)
    wait_data(page, SIM, "run", f"Number(v) === {run_before + 1}", SPHERICAL)
    start = json.loads(kernel_output(page, "print(spherical.trajectory.theta[0].tolist())"))
    assert start == pytest.approx([0.3, -0.2], abs=1 / scale)  # one pixel's worth of metres


def frame_pixel(page, index: int, x: float, y: float) -> tuple[float, float]:
    """Page pixel of the data point ``(x, y)`` of clickable plot ``index``."""
    frame = json.loads(data(page, CLICK, index)["frame"])
    (left, top, right, bottom), (w, h) = frame["box"], frame["size"]
    u = (x - frame["xlim"][0]) / (frame["xlim"][1] - frame["xlim"][0])
    v = (y - frame["ylim"][0]) / (frame["ylim"][1] - frame["ylim"][0])
    page.locator(CLICK).nth(index).scroll_into_view_if_needed()
    box = page.locator(f"{CLICK} canvas").nth(index).bounding_box()
    return box["x"] + (left + u * (right - left)) * w, box["y"] + (bottom - v * (bottom - top)) * h


def test_clicking_the_section_launches_an_orbit(page):
    section = 0
    assert data(page, CLICK, section)["orbits"] == "0"
    page.mouse.click(*frame_pixel(page, section, 0.5, 0.0))
    wait_data(page, CLICK, "orbits", "v === '1'", section)
    wait_data(page, CLICK, "pending", "v === '0'", section)
    points = int(data(page, CLICK, section)["points"])
    assert points > 5  # the clicked point and its crossings
    page.mouse.click(*frame_pixel(page, section, -0.3, 2.0))
    wait_data(page, CLICK, "orbits", "v === '2'", section)
    assert int(data(page, CLICK, section)["points"]) > points
    page.locator(CLICK).nth(section).screenshot(path=str(SCREENSHOTS / "live_section.png"))
    # In the grey region no orbit of this energy exists: a message, the picture unchanged.
    before = data(page, CLICK, section)
    page.mouse.click(*frame_pixel(page, section, 3.0, 5.0))
    wait_data(page, CLICK, "pending", "v === '0'", section)
    status = page.locator(f"{CLICK} .plab-status").nth(section)
    status_text = status.text_content()
    assert "No orbit launched" in status_text and "grey region" in status_text
    assert status.get_attribute("data-kind") == "error"
    assert data(page, CLICK, section)["points"] == before["points"]
    # Undo from the keyboard, then the Undo button of the controls.
    press_in(page, section, "u")
    wait_data(page, CLICK, "orbits", "v === '1'", section)
    cell = (
        page.locator(CLICK).nth(section).locator("xpath=ancestor::div[contains(@class,'jp-Cell')]")
    )
    cell.locator("button", has_text="Undo").click()
    wait_data(page, CLICK, "orbits", "v === '0'", section)


def press_in(page, index: int, key: str) -> None:
    page.evaluate("(k) => document.querySelectorAll('.plab-click')[k].focus()", index)
    page.keyboard.press(key)


def test_clicking_the_portrait_launches_an_orbit_and_widens_the_window(page):
    portrait = 1
    ylim = json.loads(data(page, CLICK, portrait)["frame"])["ylim"]
    page.mouse.click(*frame_pixel(page, portrait, -3.0, -9.0))
    wait_data(page, CLICK, "orbits", "v === '1'", portrait)
    wait_data(page, CLICK, "pending", "v === '0'", portrait)
    widened = json.loads(data(page, CLICK, portrait)["frame"])["ylim"]
    # A rotation from (-3, -9) reaches |omega| = sqrt(81 + 2 g (1 - cos 3)) = 10.96 rad/s at
    # the bottom, beyond the first window (+-10.02 rad/s): the window grew to hold it.
    assert ylim[1] == pytest.approx(10.02, abs=0.01)
    assert widened[1] > 11.0
    # The keyboard launches too: Enter at the cross-hair (the centre at first).
    press_in(page, portrait, "ArrowRight")
    page.keyboard.press("Enter")
    wait_data(page, CLICK, "orbits", "v === '2'", portrait)
    page.locator(CLICK).nth(portrait).screenshot(path=str(SCREENSHOTS / "live_portrait.png"))


def test_no_console_errors_and_no_request_outside_the_local_server(lab, page):
    runner, run, requests = lab
    time.sleep(0.5)
    assert requests, "no request was recorded: the check would prove nothing"
    local = runner.server.url
    outside = [u for u in requests if not u.startswith((local, "blob:", "data:"))]
    assert not outside, outside[:10]
    assert not run.console_errors, run.console_errors
