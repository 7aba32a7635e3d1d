"""Fixtures of the assignment tests: every assignment built once per session, its solutions graded.

The solutions are graded first: that grading also compiles the integrators that the later
gradings reuse (about 10 s per grading here once compiled, on an idle machine). Without
otter-grader (the ``assignments`` extra) the tests are skipped with the reason, and fail instead
when ``CI=true``.
"""

from __future__ import annotations

import importlib.util
import json
import os
from pathlib import Path

import pytest
from assignment_harness import ARTIFACTS, NAMES, Kit


def pytest_collection_modifyitems(config, items):
    here = Path(__file__).parent
    ours = [item for item in items if here in Path(str(item.fspath)).parents]
    if not ours or importlib.util.find_spec("otter") is not None:
        return
    reason = "otter-grader is not installed (pip install -e '.[assignments]')"
    if os.environ.get("CI") == "true":
        raise pytest.UsageError(f"CI: {reason}")
    for item in ours:
        item.add_marker(pytest.mark.skip(reason=reason))


@pytest.fixture(scope="session")
def kit(tmp_path_factory):
    work = tmp_path_factory.mktemp("assignments")
    built = Kit(work / "dist", work)
    for name in NAMES:  # first, so that every later grading finds the integrators compiled
        built.solutions(name)
    yield built
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    (ARTIFACTS / "grading_seconds.json").write_text(json.dumps(built.seconds, indent=1) + "\n")
