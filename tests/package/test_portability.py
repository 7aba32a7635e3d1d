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
import subprocess
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


# ---------------------------------------------------------------- text files (every module)
#: Calls that read or write text in the locale's encoding unless told otherwise (cp1252 on
#: most Windows machines: a UTF-8 file with a "μ" or an "→" fails to read there).
PROCESS_CALLS = {"run", "Popen", "check_output"}
#: Modules that other work is changing at the moment; their text calls are listed in
#: docs/portability.md and must be given an encoding there.
ELSEWHERE: set[str] = set()


#: Owners whose ``open`` is not a text file (images, archives, browsers, file descriptors).
NOT_TEXT_OPEN = {"Image", "webbrowser", "tarfile", "zipfile", "os", "gzip"}


def _binary_mode(call: ast.Call, position: int) -> bool:
    modes = [kw.value for kw in call.keywords if kw.arg == "mode"]
    if len(call.args) > position:
        modes.append(call.args[position])
    return any(isinstance(m, ast.Constant) and isinstance(m.value, str) and "b" in m.value
               for m in modes)


def _reads_or_writes_text(call: ast.Call) -> bool:
    func = call.func
    if isinstance(func, ast.Name):
        name, owner = func.id, None
    elif isinstance(func, ast.Attribute):
        name, owner = func.attr, func.value
    else:
        return False
    if name in {"read_text", "write_text", "TextIOWrapper"}:
        return True
    if name == "open":
        if isinstance(owner, ast.Name) and owner.id in NOT_TEXT_OPEN:
            return False
        return not _binary_mode(call, 1 if owner is None else 0)  # open(path, mode), p.open(mode)
    if name == "fdopen":
        return not _binary_mode(call, 1)
    if name in PROCESS_CALLS:
        keywords = {kw.arg: kw.value for kw in call.keywords}
        return any(isinstance(keywords.get(flag), ast.Constant) and keywords[flag].value is True
                   for flag in ("text", "universal_newlines"))
    return False


def text_calls_without_encoding(source: str) -> list[int]:
    """Line numbers of calls that read or write text without naming an encoding: ``open``,
    ``Path.open``/``read_text``/``write_text``, ``os.fdopen`` in text mode, and ``subprocess``
    calls with ``text=True`` or ``universal_newlines=True``."""
    return sorted(
        node.lineno for node in ast.walk(ast.parse(source))
        if isinstance(node, ast.Call) and _reads_or_writes_text(node)
        # an encoding named, or passed on in **kwargs
        and not any(kw.arg in ("encoding", None) for kw in node.keywords))


def test_every_text_file_and_pipe_names_its_encoding():
    found = {}
    for folder in ("src", "tools", "benchmarks", "docs"):
        for path in sorted((REPO / folder).rglob("*.py")):
            relative = path.relative_to(REPO).as_posix()
            if relative in ELSEWHERE:
                continue
            lines = text_calls_without_encoding(path.read_text(encoding="utf-8"))
            if lines:
                found[relative] = lines
    assert found == {}, f"pass encoding='utf-8' (or open in binary mode) at {found}"


def test_the_encoding_scan_finds_what_it_looks_for():
    # negative controls for the test above: each form it must find, and the forms it passes
    unnamed = """
import subprocess
from pathlib import Path
open("a.txt")
open("a.txt", "w")
Path("a").read_text()
Path("a").open("a")
folder.write_text("x")
subprocess.run(["x"], text=True)
subprocess.Popen(["x"], universal_newlines=True)
os.fdopen(fd, "w")
"""
    assert text_calls_without_encoding(unnamed) == [4, 5, 6, 7, 8, 9, 10, 11]
    named = """
open("a.txt", encoding="utf-8")
open("a.bin", "rb")
Path("a").open("wb")
Path("a").read_text(encoding="ascii")
subprocess.run(["x"], text=True, encoding="utf-8")
subprocess.run(["x"], capture_output=True)
os.fdopen(fd, "wb")
Image.open(gif)
"""
    assert text_calls_without_encoding(named) == []


# ---------------------------------------------------------------- the launcher (app/cli.py)
def test_the_launcher_becomes_jupyterlab_on_posix_and_runs_it_as_a_child_on_windows(
        monkeypatch):
    from pendulum_lab.app import cli

    calls = []
    monkeypatch.setattr(os, "execv", lambda path, args: calls.append(("execv", args)))
    monkeypatch.setattr(cli.subprocess, "call", lambda args: calls.append(("call", args)) or 3)
    monkeypatch.setattr(os, "name", "nt")
    assert cli._run(["python", "-m", "jupyterlab"]) == 3
    assert calls == [("call", ["python", "-m", "jupyterlab"])]
    # control: on POSIX the process is replaced (execv), no child is started
    calls.clear()
    monkeypatch.setattr(os, "name", "posix")
    cli._run(["python", "-m", "jupyterlab"])
    assert calls[0] == ("execv", ["python", "-m", "jupyterlab"])


def test_the_launcher_asks_for_allow_root_only_where_there_is_a_root(monkeypatch):
    from pendulum_lab.app import cli

    monkeypatch.delattr(os, "geteuid", raising=False)  # Windows has no user ids
    assert "--allow-root" not in cli.lab_command(REPO, no_browser=True)
    monkeypatch.setattr(os, "geteuid", lambda: 0, raising=False)
    assert "--allow-root" in cli.lab_command(REPO, no_browser=True)


def test_the_install_hint_works_in_every_shell(monkeypatch, capsys):
    # single quotes are not quotes in Windows' cmd: the hint uses double quotes
    from pendulum_lab.app import cli

    monkeypatch.setattr(cli.importlib.util, "find_spec", lambda name: None)
    assert cli.run_lab(types.SimpleNamespace()) == 1
    hint = capsys.readouterr().err
    assert 'python -m pip install "pendulum_lab[lab]"' in hint and "'" not in hint


# ---------------------------------------------------------------- tools/emulate_c_library.py
@pytest.mark.parametrize("kind", ["without-sincos", "other-library"])
def test_the_c_library_emulations_take_effect_and_only_with_their_sitecustomize(kind,
                                                                               tmp_path):
    sys.path.insert(0, str(REPO / "tools"))
    try:
        import emulate_c_library as emulation
    finally:
        sys.path.remove(str(REPO / "tools"))
    reason = emulation.prepare(kind, tmp_path)
    if reason is not None and kind == "other-library":
        pytest.skip(reason)  # no C compiler
    assert reason is None
    env = os.environ | {"NUMBA_CACHE_DIR": str(tmp_path / "numba"),
                        "PENDULUM_LAB_CACHE": str(tmp_path / "kernels")}

    def in_effect(path: str) -> bool:
        return subprocess.run([sys.executable, "-c", emulation.IN_EFFECT[kind]], cwd=REPO,
                              env=env | {"PYTHONPATH": path}, capture_output=True,
                              check=False).returncode == 0

    assert in_effect(os.pathsep.join([str(tmp_path), str(REPO / "src")]))
    assert not in_effect(str(REPO / "src"))  # control: this machine's own C library
