"""The suite runner (tools/run_tests.py): each job's CPU minutes are reported where the operating
system counts them, and the floors job starts at the lowest scheduling priority, so that it takes
only the cores the queued jobs leave idle. The POSIX branches run for real; the Windows branches
by emulation (no ``resource`` module; ``os.name``)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
from repository_scripts import load_script


@pytest.fixture(scope="module")
def run_tests():
    return load_script("tools/run_tests.py", "run_tests_tool")


@pytest.mark.skipif(sys.platform == "win32", reason="the resource module is POSIX")
def test_a_reaped_child_s_cpu_time_is_counted(run_tests):
    before = run_tests.children_cpu_seconds()
    subprocess.run([sys.executable, "-c", "sum(i * i for i in range(3_000_000))"], check=True)
    assert run_tests.children_cpu_seconds() - before > 0.05
    # the control: nothing reaped, nothing counted
    again = run_tests.children_cpu_seconds()
    assert run_tests.children_cpu_seconds() == again


def test_without_the_resource_module_no_cpu_time_is_claimed(run_tests, monkeypatch):
    monkeypatch.setitem(sys.modules, "resource", None)  # import resource raises ImportError
    assert run_tests.children_cpu_seconds() is None


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
