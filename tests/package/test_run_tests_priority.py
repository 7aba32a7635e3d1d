"""The suite runner's background job (tools/run_tests.py): the floors start at the lowest
scheduling priority, so that they take only the cores the queued jobs leave idle. The POSIX
branch is run for real; the Windows branch by emulation (``os.name``)."""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest

TOOL = Path(__file__).resolve().parents[2] / "tools" / "run_tests.py"


@pytest.fixture(scope="module")
def run_tests():
    spec = importlib.util.spec_from_file_location("run_tests_tool", TOOL)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _niceness_of_a_child(**popen) -> int:
    child = subprocess.run([sys.executable, "-c", "import os; print(os.nice(0))"],
                           capture_output=True, text=True, check=True, **popen)
    return int(child.stdout)


@pytest.mark.skipif(os.name == "nt", reason="niceness is POSIX")
def test_a_background_job_runs_at_the_lowest_priority_and_a_queued_one_does_not(run_tests):
    assert _niceness_of_a_child(**run_tests.lowest_priority()) == 19
    assert _niceness_of_a_child() == os.nice(0)  # the control: a queued job's priority


def test_on_windows_a_background_job_gets_the_idle_priority_class(run_tests, monkeypatch):
    monkeypatch.setattr(run_tests.os, "name", "nt")
    assert run_tests.lowest_priority() == {"creationflags": 0x40}  # IDLE_PRIORITY_CLASS
    monkeypatch.setattr(run_tests.os, "name", "posix")
    assert "creationflags" not in run_tests.lowest_priority()
