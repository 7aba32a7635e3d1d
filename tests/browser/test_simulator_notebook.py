"""Notebook 10 (the pendulum simulator) as a student meets it in JupyterLab in Chromium.

The harness of ``lab_harness.py`` serves a copy of the notebook alone and runs all its cells
once; then:

- ``test_the_simulator_opens_without_an_error``: after "run all", no widget shows an error:
  the refused drag the notebook demonstrates reports in its own cell's output, the live
  simulator's canvas and every status line stay clean. A refused release sent as the browser
  sends one then shows its error in the widget (the negative control: the check can see one).
- ``test_a_reopened_notebook_shows_the_hint_in_place_of_the_error``: the notebook is saved with
  its outputs (no widget state, as JupyterLab saves by default), its kernel shut down and the
  page reloaded: every instrument's output shows the one-line hint to run its cell, and no
  "Error displaying widget" is visible; while the widgets lived, the hints were hidden.
"""

from __future__ import annotations

import os
import shutil
import time
from pathlib import Path
from urllib.parse import quote

import pytest
from lab_harness import SCREENSHOTS, NotebookRunner, notebook_dir

pytestmark = pytest.mark.browser

NOTEBOOK = "10_pendulum_simulator.ipynb"
SIM = ".plab-live"
HINT = ".plab-reopen-hint"
INSTRUMENTS = 3  # the live simulator and two matplotlib simulators


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    folder = tmp_path_factory.mktemp("notebook-10")
    shutil.copy(notebook_dir() / NOTEBOOK, folder / NOTEBOOK)
    runner = NotebookRunner(lambda: tmp_path_factory.mktemp("notebook-10-lab"))
    previous = os.environ.get("PENDULUM_LAB_NOTEBOOKS")
    os.environ["PENDULUM_LAB_NOTEBOOKS"] = str(folder)
    try:
        run = runner.get(NOTEBOOK)
        yield runner, run
    finally:
        if previous is None:
            os.environ.pop("PENDULUM_LAB_NOTEBOOKS", None)
        else:
            os.environ["PENDULUM_LAB_NOTEBOOKS"] = previous
        runner.close()


def kernel_run(page, code: str) -> str:
    """Run ``code`` in the notebook's kernel (beside its cells); return what it prints."""
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


def test_the_simulator_opens_without_an_error(lab):
    runner, run = lab
    if not run.ok:
        pytest.fail(f"run-all of notebook 10 failed:\n{run.report()}", pytrace=False)
    page = run.page
    page.wait_for_function(f"() => document.querySelector('{SIM}')?.dataset.states > 0")
    canvas_status = page.locator(f"{SIM} .plab-status").first
    assert canvas_status.text_content() == "", canvas_status.text_content()
    assert canvas_status.get_attribute("data-kind") != "error"
    kinds = page.eval_on_selector_all(".plab-statusline", "els => els.map(e => e.dataset.kind)")
    assert len(kinds) == INSTRUMENTS and "error" not in kinds, kinds
    # The demonstration of a refused drag answered in its own cell.
    outputs = "\n".join(cell.get("outputText", "") for cell in run.cells)
    assert "refused: `x` must be finite, got nan" in outputs
    assert "Cannot start from that drag" not in page.locator(SIM).first.text_content()
    # While the widgets live, the reopen hints stay hidden.
    assert page.locator(HINT).count() == INSTRUMENTS
    assert not any(page.locator(HINT).nth(k).is_visible() for k in range(INSTRUMENTS))
    # Negative control: a release the browser sends with NaN (JavaScript's NaN arrives as null)
    # shows its error in the widget, where the check above looks.
    kernel_run(page, "live_sim.view._dispatch(live_sim.view, {'type': 'release', 'bob': 0, "
                     "'x': None, 'y': 0.0}, [])")
    page.wait_for_function(
        "(s) => document.querySelector(s + ' .plab-status').dataset.kind === 'error'", arg=SIM)
    assert "Cannot start from that drag" in canvas_status.text_content()


def test_a_reopened_notebook_shows_the_hint_in_place_of_the_error(lab):
    runner, run = lab
    page = run.page
    page.evaluate("() => window.jupyterapp.commands.execute('docmanager:save')")
    page.wait_for_function(
        "(p) => { const w = window.__plab.panel(p); return w && !w.context.model.dirty; }",
        arg=NOTEBOOK, timeout=30_000)
    saved = (runner.server.root / NOTEBOOK).read_text(encoding="utf-8")
    assert "plab-reopen-hint" in saved and "application/vnd.jupyter.widget-state+json" not in saved
    runner.server.shutdown_kernels_of(NOTEBOOK)
    time.sleep(1.0)
    page.goto(f"{runner.server.url}/lab/tree/{quote(NOTEBOOK)}")
    page.wait_for_function("() => window.jupyterapp && window.jupyterapp.shell", timeout=90_000)
    runner.wait_idle(run, timeout=120)
    failed = page.locator(".jp-OutputArea-output.jupyter-widgets")  # JupyterLab's failed views
    page.wait_for_function(
        "(n) => document.querySelectorAll('.jp-OutputArea-output.jupyter-widgets').length >= n",
        arg=INSTRUMENTS, timeout=60_000)
    assert "model not found" in failed.first.text_content()  # what the hint stands in for
    hints = page.locator(HINT)
    assert hints.count() == INSTRUMENTS
    for k in range(INSTRUMENTS):
        hints.nth(k).scroll_into_view_if_needed()
        assert hints.nth(k).is_visible()
        assert "run this cell to bring it back" in hints.nth(k).text_content()
    assert not any(failed.nth(k).is_visible() for k in range(failed.count()))
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    hints.first.locator("xpath=ancestor::div[contains(@class,'jp-CodeCell')]").screenshot(
        path=str(SCREENSHOTS / Path(NOTEBOOK).with_suffix(".reopened.png").name))
