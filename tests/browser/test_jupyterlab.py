"""The course notebooks opened in a real JupyterLab in a real browser (Chromium via Playwright).

For every ``notebooks/*.ipynb`` the tests open ``/lab/tree/NAME.ipynb``, wait for the kernel
to be Idle, clear the outputs, run all cells and wait until every non-empty code cell has an
execution count and the kernel is Idle again. Then they check:

* no cell raised (no error output, no "Traceback" in any output; plain stderr such as warnings
  is allowed), and no output reads "Error displaying widget";
* every cell marked ``# NBVAL_CHECK_OUTPUT`` prints what the notebook stores (nbval's rule:
  standard output compared, standard error left out);
* every cell marked as below shows what it promises;
* the first slider with an editable value box moves the figure next to it, the first dropdown
  changes it, and a Play button makes the value it drives advance.

Marker convention for notebook authors
--------------------------------------
A code cell announces what it must show in its metadata, not in its code::

    "metadata": {"pendulum_lab": {"expect": ["figure"]}}

``"figure"``: at least one visible image, canvas or svg in the cell's output; ``"widget"``: at
least one rendered ipywidgets view; both: an explorer (controls plus the figure they redraw).

A figure drawn inside a widget (``interactive_output``) counts for the cell that displays the
widget. Unknown words in ``expect`` fail the test, so a typo cannot switch a check off.

For the interaction tests, put a control and the figure it redraws in the output of the same
cell (for instance ``display(VBox([HBox([slider, dropdown]), out]))``), and a ``Play`` widget
together with the slider it is linked to. Sliders are changed through their value box (click,
select all, type, Enter), so keep ``readout=True`` on the sliders to be tested.

Artifacts (``test-artifacts/`` is git-ignored): ``test-artifacts/browser/screenshots/NAME.png``
(after run-all: the first screen, the whole notebook when the run had problems),
``NAME.slider-before.png`` / ``-after`` and the like for each interaction, and
``test-artifacts/browser/timings.json`` with the run-all wall time per notebook.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import time
from dataclasses import dataclass
from pathlib import Path

import pytest
from lab_harness import SCREENSHOTS, NotebookRun, list_notebooks, notebook_dir
from repository_scripts import load_script

# How checked outputs are stored and compared.
checked_outputs = load_script("tools/refresh_checked_outputs.py")

NOTEBOOKS = list_notebooks()
if not NOTEBOOKS:
    pytest.skip(
        f"no notebooks (*.ipynb) in {notebook_dir()}: nothing to open in the browser",
        allow_module_level=True,
    )

pytestmark = [pytest.mark.browser, pytest.mark.parametrize("notebook", NOTEBOOKS)]


def test_run_all_cells(notebook_runner, notebook):
    run = notebook_runner.get(notebook)
    if not run.ok:
        pytest.fail(run.report(), pytrace=False)
    # The course's check of printed results: the cells marked NBVAL_CHECK_OUTPUT print what
    # the notebook stores (nbval's rule; Binder's environment runs a few notebooks under nbval
    # itself, tests/binder).
    stored = json.loads((notebook_dir() / notebook).read_text(encoding="utf-8"))
    differences = checked_outputs.differences(stored, run.model)
    assert not differences, "\n".join(differences)


# ---------------------------------------------------------------------------------------------
# Interactions
# ---------------------------------------------------------------------------------------------

CHANGE_TIMEOUT = 20.0  # seconds for a figure to change after a control moved


def ran_cleanly(runner, notebook: str) -> NotebookRun:
    run = runner.get(notebook)
    if not run.ok:
        pytest.fail(
            f"run-all of {notebook} did not complete cleanly, so its widgets cannot be "
            f"tested:\n{run.report()}",
            pytrace=False,
        )
    return run


def tag_control(run: NotebookRun, selector: str, editable_readout: bool = False) -> dict | None:
    return run.page.evaluate(
        "([p, s, e]) => window.__plab.tagControl(p, s, e)", [run.name, selector, editable_readout]
    )


@dataclass(frozen=True)
class Shot:
    """A screenshot of the figure next to a control: what was pictured and its digest."""

    kind: str  # "img", "canvas", "svg" or "output-area"
    digest: str

    def differs_from(self, other: Shot | None) -> bool:
        return other is not None and self.kind == other.kind and self.digest != other.digest


def target_shot(run: NotebookRun, label: str) -> Shot | None:
    """Screenshot of the figure nearest to the tagged control, saved under the screenshots
    folder too. The figure is found again every time (a redraw replaces the element) and
    pictured by its box on the page, so a redraw in progress cannot make the picture fail."""
    page = run.page
    box = page.evaluate("(p) => window.__plab.targetBox(p)", run.name)
    if not box or box["width"] < 1 or box["height"] < 1:
        return None
    clip = {key: box[key] for key in ("x", "y", "width", "height")}
    mask = [page.locator("[data-plab-control]")] if box["kind"] == "output-area" else []
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    path = SCREENSHOTS / f"{Path(run.name).stem}.{label}.png"
    png = page.screenshot(path=str(path), clip=clip, mask=mask, animations="disabled")
    return Shot(box["kind"], hashlib.sha256(png).hexdigest())


def busy_count(runner, run: NotebookRun) -> int:
    return runner.state(run).get("busyCount", 0)


def wait_for_new_figure(
    runner, run: NotebookRun, label: str, before: Shot | None, busy_before: int
) -> Shot | None:
    """After a control changed: wait for the kernel to work and go idle, then for the figure
    to differ from ``before``. Returns the last screenshot taken."""
    # No busy phase within 10 s means the change never reached the kernel; then the picture
    # below decides (and a figure that depends on the kernel will not have changed).
    with contextlib.suppress(TimeoutError):
        runner.wait_idle(run, timeout=10, min_busy=busy_before + 1)
    runner.wait_idle(run, timeout=120)
    deadline = time.monotonic() + CHANGE_TIMEOUT
    while True:
        after = target_shot(run, label)
        if (after is not None and after.differs_from(before)) or time.monotonic() > deadline:
            return after
        time.sleep(0.3)


def expect_new_picture(before: Shot | None, after: Shot | None, message: str) -> None:
    """Fail with ``message`` (and where the pictures are) unless ``after`` shows a change."""
    if after is None or not after.differs_from(before):
        pytest.fail(f"{message}\n(pictures: {SCREENSHOTS})", pytrace=False)


def as_number(text: str) -> float:
    return float(text.strip().replace("\u2212", "-"))


def test_slider_changes_figure(notebook_runner, notebook):
    run = ran_cleanly(notebook_runner, notebook)
    found = tag_control(run, ".widget-slider", editable_readout=True)
    if found is None:
        pytest.skip(f"{notebook} has no visible slider with an editable readout")
    page = run.page
    control = page.locator("[data-plab-control]")
    readout = control.locator(".widget-readout")
    handle = control.locator(".noUi-handle").first
    low = float(handle.get_attribute("aria-valuemin"))
    high = float(handle.get_attribute("aria-valuemax"))
    shown = readout.inner_text().strip()
    current = as_number(shown)
    decimals = len(shown.split(".")[1]) if "." in shown else 0
    # Halfway to the farther end of the range, written with the readout's own precision.
    far = high if high - current >= current - low else low
    new_value = round(current + (far - current) / 2, decimals)
    if new_value == current:
        new_value = far
    typed = f"{new_value:.{decimals}f}"
    assert as_number(typed) != current, f"slider in {notebook} has an empty range [{low}, {high}]"

    before = target_shot(run, "slider-before")
    busy = busy_count(notebook_runner, run)
    readout.click()
    page.keyboard.press("ControlOrMeta+a")
    page.keyboard.type(typed)
    page.keyboard.press("Enter")
    after = wait_for_new_figure(notebook_runner, run, "slider-after", before, busy)

    assert as_number(readout.inner_text()) == pytest.approx(as_number(typed)), (
        f"readout of the slider in cell {found['cellIndex']} shows {readout.inner_text()!r} "
        f"after typing {typed!r}"
    )
    assert before is not None, f"nothing to picture next to the slider in {notebook}"
    expect_new_picture(
        before,
        after,
        f"the {found['target']} next to the slider in cell {found['cellIndex']} of {notebook} "
        f"did not change within {CHANGE_TIMEOUT:.0f} s after the slider moved "
        f"{shown} -> {typed}",
    )


def test_dropdown_changes_figure(notebook_runner, notebook):
    run = ran_cleanly(notebook_runner, notebook)
    found = tag_control(run, ".widget-dropdown")
    if found is None:
        pytest.skip(f"{notebook} has no visible dropdown")
    select = run.page.locator("[data-plab-control] select")
    options = [v for v in select.locator("option").evaluate_all("os => os.map(o => o.value)")]
    current = select.input_value()
    others = [v for v in options if v != current]
    if not others:
        pytest.skip(f"the dropdown in {notebook} has a single option")
    new = others[0]

    before = target_shot(run, "dropdown-before")
    busy = busy_count(notebook_runner, run)
    select.select_option(new)
    after = wait_for_new_figure(notebook_runner, run, "dropdown-after", before, busy)

    assert select.input_value() == new
    assert before is not None, f"nothing to picture next to the dropdown in {notebook}"
    expect_new_picture(
        before,
        after,
        f"the {found['target']} next to the dropdown in cell {found['cellIndex']} of "
        f"{notebook} did not change within {CHANGE_TIMEOUT:.0f} s after choosing option "
        f"{new!r} instead of {current!r}",
    )


def test_play_advances(notebook_runner, notebook):
    run = ran_cleanly(notebook_runner, notebook)
    found = tag_control(run, ".widget-play")
    if found is None:
        pytest.skip(f"{notebook} has no Play widget")
    page = run.page
    control = page.locator("[data-plab-control]")
    cell = page.locator(".jp-Notebook .jp-Cell").nth(found["cellIndex"])
    readouts = cell.locator(".widget-readout")
    assert readouts.count() > 0, (
        f"the Play widget in cell {found['cellIndex']} of {notebook} has no slider with a "
        "readout in the same output to show the value it drives"
    )

    def values() -> list[str]:
        return [t.strip() for t in readouts.all_inner_texts()]

    has_figure = found["target"] != "output-area"
    before = target_shot(run, "play-before") if has_figure else None
    start = values()
    control.locator("button:has(.fa-play)").first.click()
    try:
        page.wait_for_timeout(400)
        first = values()
        deadline = time.monotonic() + 5
        second = values()
        while second == first and time.monotonic() < deadline:
            page.wait_for_timeout(300)
            second = values()
        after = None
        if has_figure:
            deadline = time.monotonic() + CHANGE_TIMEOUT
            while time.monotonic() < deadline:
                after = target_shot(run, "play-after")
                if after is not None and after.differs_from(before):
                    break
                page.wait_for_timeout(300)
    finally:
        pause = control.locator("button:has(.fa-pause)")
        if pause.count():
            pause.first.click()
        notebook_runner.wait_idle(run, timeout=120)

    assert second != first, (
        f"the value driven by the Play widget in cell {found['cellIndex']} of {notebook} did "
        f"not advance: {start} before Play, then {first} and {second} (read some hundred ms "
        "apart)"
    )
    if has_figure:
        expect_new_picture(
            before,
            after,
            f"the {found['target']} in cell {found['cellIndex']} of {notebook} showed no new "
            f"frame within {CHANGE_TIMEOUT:.0f} s of pressing Play",
        )
