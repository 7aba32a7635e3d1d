"""pytest wiring of the browser tests: the ``browser`` marker, the skip/fail policy, test
ordering, and the session fixture (one JupyterLab, one Chromium, one page per notebook).

The machinery itself lives in ``lab_harness.py``; see ``README.md`` beside this file.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from lab_harness import NotebookRunner, browser_unavailable_reason, in_ci

HERE = Path(__file__).resolve().parent
#: The session's runner, once the fixture has made it (for the teardown hook below).
_RUNNERS: list[NotebookRunner] = []


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
def notebook_runner(tmp_path_factory, notebooks_run_in_jupyterlab):
    """One JupyterLab (on a temporary copy of the notebooks) and one Chromium for the session,
    started by the first test that opens a notebook; one page per notebook. Each clean run-all
    is kept in ``notebooks_run_in_jupyterlab`` (for the website's build). See
    ``lab_harness.NotebookRunner``."""
    runner = NotebookRunner(lambda: tmp_path_factory.mktemp("jupyterlab"),
                            notebooks_run_in_jupyterlab)
    _RUNNERS.append(runner)
    try:
        yield runner
    finally:
        runner.close()


def pytest_runtest_teardown(item, nextitem):
    """Stop JupyterLab and Chromium once the last test of this folder has run, not at the end
    of the session: the website and Binder tests that follow in the same shard would share the
    cores with the last notebook's page and kernel (half a core for the rest of the shard)."""
    if nextitem is None or HERE not in Path(nextitem.path).resolve().parents:
        for runner in _RUNNERS:
            runner.close()
