"""pytest wiring of the browser tests: the ``browser`` marker, the skip/fail policy, test
ordering, and the session fixtures (one JupyterLab, one Chromium, one page per notebook).

The machinery itself lives in ``lab_harness.py``; see ``README.md`` beside this file.
"""

from __future__ import annotations

import pytest
from lab_harness import (
    CHROMIUM_ARGS,
    PAGE_HELPERS,
    VIEWPORT,
    NotebookRunner,
    browser_unavailable_reason,
    chromium_path,
    in_ci,
    notebook_dir,
    skip_or_fail,
    start_lab,
)


def pytest_configure(config):
    config.addinivalue_line(
        "markers",
        "browser: runs notebooks in JupyterLab in Chromium via Playwright "
        "(skipped without Chromium/Playwright, failing instead when CI=true)",
    )


def pytest_collection_modifyitems(config, items):
    slots = [i for i, item in enumerate(items) if item.get_closest_marker("browser") is not None]
    if not slots:
        return

    # Keep each notebook's tests together so that one page (and one kernel) per notebook is
    # enough; the order of the test functions within a notebook is kept (the sort is stable).
    def notebook_of(item) -> str:
        callspec = getattr(item, "callspec", None)
        return str(callspec.params.get("notebook", "")) if callspec else ""

    ordered = sorted((items[i] for i in slots), key=notebook_of)
    for slot, item in zip(slots, ordered, strict=True):
        items[slot] = item

    reason = browser_unavailable_reason()
    if reason is not None and not in_ci():
        for slot in slots:
            items[slot].add_marker(pytest.mark.skip(reason=reason))


@pytest.fixture(scope="session")
def jupyterlab(tmp_path_factory):
    """A JupyterLab server on a temporary copy of the notebooks (one per session)."""
    reason = browser_unavailable_reason()
    if reason is not None:
        skip_or_fail(reason)
    server = start_lab(tmp_path_factory.mktemp("jupyterlab"), notebook_dir())
    try:
        yield server
    finally:
        server.stop()


@pytest.fixture(scope="session")
def chromium():
    """Debian's Chromium driven by Playwright (one per session, never downloaded)."""
    reason = browser_unavailable_reason()
    if reason is not None:
        skip_or_fail(reason)
    from playwright.sync_api import sync_playwright

    manager = sync_playwright().start()
    try:
        browser = manager.chromium.launch(executable_path=chromium_path(), args=CHROMIUM_ARGS)
        try:
            yield browser
        finally:
            browser.close()
    finally:
        manager.stop()


@pytest.fixture(scope="session")
def notebook_runner(jupyterlab, chromium):
    """Opens each notebook in a new page and runs all its cells once; see NotebookRunner."""
    context = chromium.new_context(viewport=VIEWPORT, device_scale_factor=1)
    context.set_default_timeout(30_000)
    context.add_init_script(PAGE_HELPERS)
    runner = NotebookRunner(jupyterlab, context)
    try:
        yield runner
    finally:
        runner.close_current()
        context.close()
