"""The browser harness stops what it started on any system (no browser needed).

JupyterLab starts kernels in sessions of their own, so stopping the server's process group
leaves them running; ``lab_harness.stop_process_tree`` finds the descendants first and kills
them last. Here a real tree (a parent that starts a child in a new session, which sleeps) is
stopped three ways: as on Linux, without ``/proc`` and ``os.killpg`` (Windows, by emulation:
psutil finds the descendants, ``Popen.terminate`` ends the parent), and, as the negative
control, with descendants not looked for, which leaves the child running.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time

import lab_harness
import pytest

psutil = pytest.importorskip("psutil")  # installed with IPython, as the lab extra has it

PARENT = """
import subprocess, sys, time
child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(120)"],
                         start_new_session=True)
print(child.pid, flush=True)
time.sleep(120)
"""


def start_tree():
    """A parent in a group of its own and its child in another session: (Popen, child pid)."""
    parent = subprocess.Popen([sys.executable, "-c", PARENT], stdout=subprocess.PIPE,
                              text=True, **lab_harness.new_process_group())
    child = int(parent.stdout.readline())
    return parent, child


def running(pid: int) -> bool:
    try:
        return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


def gone_within(pid: int, seconds: float = 10) -> bool:
    deadline = time.monotonic() + seconds
    while running(pid):
        if time.monotonic() > deadline:
            return False
        time.sleep(0.05)
    return True


def test_the_tree_is_stopped_as_on_linux():
    parent, child = start_tree()
    polite = []
    lab_harness.stop_process_tree(parent, lambda: polite.append(1), waits=(0.2, 5, 5))
    assert polite == [1] and parent.returncode is not None
    assert gone_within(child)


def test_the_tree_is_stopped_without_proc_or_killpg(monkeypatch):
    parent, child = start_tree()
    monkeypatch.delattr(os, "killpg")
    monkeypatch.setattr(lab_harness, "Path", lambda *a: pytest.fail("/proc was read"))
    assert lab_harness._descendants(parent.pid) == [child]
    lab_harness.stop_process_tree(parent, waits=(0.2, 5, 5))
    assert parent.returncode is not None and gone_within(child)


def test_without_psutil_linux_finds_the_descendants_in_proc(monkeypatch):
    if not os.path.isdir("/proc/self"):
        pytest.skip("this system has no /proc (the branch used where psutil is missing)")
    parent, child = start_tree()
    monkeypatch.setitem(sys.modules, "psutil", None)  # import psutil raises ImportError
    try:
        assert lab_harness._descendants(parent.pid) == [child]
    finally:
        monkeypatch.undo()
        lab_harness.stop_process_tree(parent, waits=(0.2, 5, 5))
    assert gone_within(child)


def test_a_child_in_its_own_session_outlives_its_group_if_not_looked_for(monkeypatch):
    # negative control: without the descendants, stopping the group leaves the child running
    parent, child = start_tree()
    monkeypatch.setattr(lab_harness, "_descendants", lambda pid: [])
    try:
        lab_harness.stop_process_tree(parent, waits=(0.2, 5, 5))
        assert parent.returncode is not None
        assert running(child)
    finally:
        psutil.Process(child).kill()
    assert gone_within(child)
