"""A compilation's note in a real JupyterLab in Chromium (``pendulum_lab.codegen.compile_status``).

The demo notebook ``compile_demo/compile_note.ipynb`` announces a block of 3 s as a compilation
and another of 0.05 s. While the long one runs, its cell must show one line that says what is
compiled and counts the seconds, updated in place; when it is done, the line says how long it
took; the short one shows nothing. Then an explorer's run compiles first: while it does, the
explorer's status line says what is compiled and its figure is marked stale; afterwards the
status line reports the run, with the compile time apart, and the figure is fresh again.
"""

from __future__ import annotations

import os
import re
import time
from pathlib import Path

import pytest
from lab_harness import NotebookRunner

pytestmark = pytest.mark.browser

DEMO = Path(__file__).resolve().parent / "compile_demo"
NOTEBOOK = "compile_note.ipynb"
RUNNING = re.compile(r"compiling a demonstration kernel, once per machine… (\d+) s")


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    runner = NotebookRunner(lambda: tmp_path_factory.mktemp("compile-lab"))
    previous = os.environ.get("PENDULUM_LAB_NOTEBOOKS")
    os.environ["PENDULUM_LAB_NOTEBOOKS"] = str(DEMO)
    try:
        runner.start()
        yield runner, runner.get(NOTEBOOK)
    finally:
        if previous is None:
            os.environ.pop("PENDULUM_LAB_NOTEBOOKS", None)
        else:
            os.environ["PENDULUM_LAB_NOTEBOOKS"] = previous
        runner.close()


def outputs(runner, run) -> list[str]:
    return [cell.get("outputText", "") for cell in runner.cells(run)]


def test_the_note_ends_with_the_time_taken_and_a_quick_one_says_nothing(lab):
    runner, run = lab
    if not run.ok:
        pytest.fail(run.report(), pytrace=False)
    text = "\n".join(outputs(runner, run))
    assert re.search(r"compiled a demonstration kernel in 3\.\d s", text), text
    assert not RUNNING.search(text)  # the line was replaced, not followed by another
    assert text.count("a demonstration kernel") == 1
    assert "the quick one is done" in text and "a quick kernel" not in text


def test_while_it_compiles_the_cell_counts_the_seconds_in_one_line(lab):
    runner, run = lab
    busy_before = runner.state(run).get("busyCount", 0)
    run.page.evaluate("() => { window.jupyterapp.commands.execute('notebook:run-all-cells'); }")
    seen, deadline = [], time.monotonic() + 60
    while time.monotonic() < deadline:
        text = "\n".join(outputs(runner, run))
        seen += [int(s) for s in RUNNING.findall(text)]
        assert len(RUNNING.findall(text)) <= 1, text
        if "the slow one is done" in text and seen:
            break
        time.sleep(0.2)
    runner.wait_idle(run, timeout=60, min_busy=busy_before + 1)
    assert len(set(seen)) >= 2, f"the elapsed seconds never moved: {seen}"
    assert seen == sorted(seen)


EXPLORER_STATE = """() => {
  const lines = [...document.querySelectorAll('.plab-statusline')];
  const line = lines[lines.length - 1];
  const stale = [...document.querySelectorAll('.plab-stale')].length;
  return {text: line ? line.querySelector('.plab-status-text').textContent : null,
          kind: line ? line.dataset.kind : null, stale};
}"""


def test_an_explorer_says_it_compiles_and_marks_its_figure_stale_meanwhile(lab):
    runner, run = lab
    busy_before = runner.state(run).get("busyCount", 0)
    run.page.evaluate("() => { window.jupyterapp.commands.execute('notebook:run-all-cells'); }")
    states, deadline = [], time.monotonic() + 120
    while time.monotonic() < deadline:
        states.append(run.page.evaluate(EXPLORER_STATE))
        if any("the explorer is updated" in text for text in outputs(runner, run)):
            break
        time.sleep(0.1)
    runner.wait_idle(run, timeout=60, min_busy=busy_before + 1)
    said = "compiling rk4 for the double pendulum"
    compiling = [s for s in states if s["text"] and said in s["text"]]
    assert compiling, f"the status line never said it compiles: {states[-5:]}"
    assert all(s["kind"] == "busy" and s["stale"] >= 1 for s in compiling)
    final = run.page.evaluate(EXPLORER_STATE)
    # after the run: its summary with the compile time apart, and no stale figure
    assert final["kind"] == "info" and "after compiling for 3." in final["text"], final
    assert final["stale"] == 0
