"""The package's operating-system branches, each run here by emulation (``docs/portability.md``).

Students run the course on Windows, macOS and Linux. Every place where the package asks the
operating system something has a branch for each; these tests take each branch on this machine
by faking what differs (``sys.platform``, ``/proc`` missing, ``os.sysconf`` missing, a fake
``ctypes.windll``), and check what a student on that system gets. The sine and cosine's C
library is in ``tests/codegen/test_sincos_platforms.py``.
"""

from __future__ import annotations

import ast
import ctypes
import os
import sys
import types
from pathlib import Path

import pytest

from pendulum_lab import validation

REPO = Path(__file__).resolve().parents[2]
GIB = 2**30


# ---------------------------------------------------------------- memory (validation.py)
def fake_windll(total: int, available: int, succeeds: bool = True):
    """A ``ctypes.windll`` whose ``GlobalMemoryStatusEx`` fills in the given figures."""
    calls = []

    def global_memory_status_ex(reference):
        status = reference._obj
        calls.append(status.dwLength)
        if succeeds:
            status.ullTotalPhys, status.ullAvailPhys = total, available
        return int(succeeds)

    kernel32 = types.SimpleNamespace(GlobalMemoryStatusEx=global_memory_status_ex)
    return types.SimpleNamespace(kernel32=kernel32), calls


def without_sysconf(monkeypatch):
    monkeypatch.delattr(os, "sysconf", raising=False)


def test_windows_memory_comes_from_global_memory_status(monkeypatch):
    windll, calls = fake_windll(16 * GIB, 5 * GIB)
    monkeypatch.setattr(sys, "platform", "win32")
    monkeypatch.setattr(ctypes, "windll", windll, raising=False)
    without_sysconf(monkeypatch)  # Windows has no os.sysconf
    assert validation.physical_memory() == 16 * GIB
    assert validation.available_memory() == 5 * GIB
    # the structure's size is passed in, as the Windows API requires (64 bytes)
    assert calls == [64, 64]


def test_windows_without_an_answer_says_none(monkeypatch):
    monkeypatch.setattr(sys, "platform", "win32")
    without_sysconf(monkeypatch)
    monkeypatch.setattr(ctypes, "windll", fake_windll(0, 0, succeeds=False)[0], raising=False)
    assert validation.physical_memory() is None and validation.available_memory() is None
    monkeypatch.delattr(ctypes, "windll", raising=False)  # no windll at all
    assert validation.physical_memory() is None and validation.available_memory() is None


def test_macos_takes_the_physical_memory_from_sysconf_and_reads_no_proc(monkeypatch):
    monkeypatch.setattr(sys, "platform", "darwin")
    pages = {"SC_PAGE_SIZE": 16384, "SC_PHYS_PAGES": 2**20}
    monkeypatch.setattr(os, "sysconf", pages.__getitem__)
    monkeypatch.setattr(validation, "MEMINFO", "/proc/meminfo-must-not-be-read")
    opened = []
    real_open = open
    monkeypatch.setattr("builtins.open", lambda path, *a, **k: opened.append(path)
                        or real_open(path, *a, **k))
    assert validation.physical_memory() == 16 * GIB
    assert validation.available_memory() == 16 * GIB
    assert opened == []


def test_linux_reads_mem_available_and_falls_back_without_proc(monkeypatch, tmp_path):
    monkeypatch.setattr(sys, "platform", "linux")
    meminfo = tmp_path / "meminfo"
    meminfo.write_text("MemTotal:       16000000 kB\nMemAvailable:    3000000 kB\n",
                       encoding="ascii")
    monkeypatch.setattr(validation, "MEMINFO", str(meminfo))
    assert validation.available_memory() == 3_000_000 * 1024
    # no /proc (a sandbox): the physical memory from sysconf
    monkeypatch.setattr(validation, "MEMINFO", str(tmp_path / "absent"))
    monkeypatch.setattr(os, "sysconf", {"SC_PAGE_SIZE": 4096, "SC_PHYS_PAGES": 2**21}.__getitem__)
    assert validation.available_memory() == 8 * GIB
    # neither: None, never an exception
    without_sysconf(monkeypatch)
    assert validation.available_memory() is None and validation.physical_memory() is None


def test_this_machine_reports_its_memory():
    total, available = validation.physical_memory(), validation.available_memory()
    assert total is not None and total > 2**28  # more than 256 MB
    assert available is not None and 0 < available <= total
