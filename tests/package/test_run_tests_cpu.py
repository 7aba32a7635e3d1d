"""The suite runner (tools/run_tests.py) reports each job's CPU minutes where the operating
system counts them: the POSIX branch for real, Windows (no ``resource`` module) by emulation."""

from __future__ import annotations

import importlib.util
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
