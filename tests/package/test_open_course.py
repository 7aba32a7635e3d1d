"""The student's way in (``open_course.py``) and the Makefile's choice of Python
(``tools/find_python.py``), on every OS's branch; the real run from a fresh clone is in
``tests/install``."""

from __future__ import annotations

import os
import subprocess
import sys
import sysconfig
import types
from pathlib import Path

import pytest
from repository_scripts import load_script

REPO_ROOT = Path(__file__).resolve().parents[2]


open_course = load_script("open_course.py")
find_python = load_script("tools/find_python.py")


# --------------------------------------------------------------------------- open_course.py
def test_the_venv_interpreter_is_where_venv_puts_it_on_this_os(tmp_path):
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True,
                   timeout=300)
    here = open_course.venv_python(venv)
    assert here.is_file()
    # Negative control: the other OS's layout is not there.
    assert not open_course.venv_python(venv, windows=os.name != "nt").exists()


def test_the_windows_layout_is_cpythons_own():
    venv = Path("C:/course/.venv")
    # CPython's scheme for virtual environments on Windows (sysconfig, Python 3.11+).
    scripts = sysconfig.get_path("scripts", "nt_venv", vars={"base": str(venv)}, expand=True)
    assert Path(scripts) == open_course.venv_python(venv, windows=True).parent
    posix = sysconfig.get_path("scripts", "posix_venv", vars={"base": str(venv)}, expand=True)
    assert Path(posix) == open_course.venv_python(venv, windows=False).parent
    assert open_course.venv_python(venv, windows=True).name == "python.exe"


def test_installs_only_when_pyproject_changed(tmp_path):
    pyproject = tmp_path / "pyproject.toml"
    stamp = tmp_path / ".installed-lab"
    pyproject.write_text("")
    assert open_course.needs_install(stamp, pyproject)  # never installed
    stamp.touch()
    os.utime(pyproject, (1_000_000, 1_000_000))
    assert not open_course.needs_install(stamp, pyproject)
    os.utime(pyproject, (4_000_000_000, 4_000_000_000))
    assert open_course.needs_install(stamp, pyproject)  # changed since


@pytest.fixture
def course(tmp_path, monkeypatch):
    """``open_course`` pointed at an empty folder, with every command recorded, none run."""
    venv = tmp_path / ".venv"
    (tmp_path / "pyproject.toml").write_text("")
    monkeypatch.setattr(open_course, "ROOT", tmp_path)
    monkeypatch.setattr(open_course, "VENV", venv)
    monkeypatch.setattr(open_course, "STAMP", venv / ".installed-lab")
    ran = []

    def record(command, cwd=None):
        ran.append(command)
        if command[1:3] == ["-m", "venv"]:
            open_course.venv_python(venv).parent.mkdir(parents=True)
            open_course.venv_python(venv).touch()
        return 0

    monkeypatch.setattr(open_course.subprocess, "call", record)
    return types.SimpleNamespace(venv=venv, ran=ran)


class Exec(Exception):
    """os.execv does not return: the fake one raises this instead."""


def test_the_first_run_creates_installs_then_starts(course, monkeypatch):
    started = []

    def execv(path, args):
        started.append(args)
        raise Exec

    monkeypatch.setattr(open_course.os, "execv", execv)

    def launch(argv):  # the launch as this OS makes it: exec on POSIX, a child elsewhere
        try:
            open_course.main(argv)
        except Exec:
            pass
        return started.pop() if os.name == "posix" else course.ran.pop()

    python = str(open_course.venv_python(course.venv))
    assert launch(["--no-browser"]) == [python, "-m", "pendulum_lab", "--no-browser"]
    assert course.ran == [
        [sys.executable, "-m", "venv", str(course.venv)],
        [python, "-m", "pip", "install", "--upgrade", "pip"],
        [python, "-m", "pip", "install", "-e", ".[lab]"],
    ]
    assert (course.venv / ".installed-lab").is_file()
    # The second run installs nothing.
    course.ran.clear()
    assert launch([]) == [python, "-m", "pendulum_lab"]
    assert course.ran == []


def test_on_windows_the_launcher_runs_as_a_child(course, monkeypatch):
    def no_exec(*args):
        raise AssertionError("no exec on Windows")

    monkeypatch.setattr(open_course, "os", types.SimpleNamespace(name="nt", execv=no_exec))
    assert open_course.main(["--help"]) == 0
    python = str(course.venv / "Scripts" / "python.exe")
    assert course.ran[-1] == [python, "-m", "pendulum_lab", "--help"]


def test_a_failed_step_says_what_to_do(course, monkeypatch):
    monkeypatch.setattr(open_course.subprocess, "call", lambda command, cwd=None: 1)
    with pytest.raises(SystemExit, match=r"creating the virtual environment failed.*Delete"):
        open_course.main([])


def test_too_old_a_python_is_refused_with_the_reason(course, monkeypatch, capsys):
    monkeypatch.setattr(open_course, "OLDEST_PYTHON", (99, 0))
    assert open_course.main([]) == 1
    assert "needs Python 99.0 or newer" in capsys.readouterr().err
    assert course.ran == []  # nothing created


# --------------------------------------------------------------------------- find_python.py
def test_supported_versions_are_the_classifiers(tmp_path):
    assert find_python.supported_versions() == [(3, 11), (3, 12), (3, 13)]
    listed = tmp_path / "pyproject.toml"
    listed.write_text('[project]\nclassifiers = ["Programming Language :: Python :: 3.12",\n'
                      '"Programming Language :: Python :: 3.9", "Topic :: Education"]\n')
    assert find_python.supported_versions(listed) == [(3, 9), (3, 12)]
    listed.write_text('[project]\nclassifiers = ["Topic :: Education"]\n')
    with pytest.raises(SystemExit, match="no 'Programming Language"):
        find_python.supported_versions(listed)


def test_an_interpreter_counts_only_if_it_runs_as_the_version_named(tmp_path):
    mine = sys.version_info[:2]
    assert find_python.probe([sys.executable], mine)
    assert find_python.probe([sys.executable], (mine[0], mine[1] + 1)) is None
    assert find_python.probe([str(tmp_path / "python3.99")], (3, 99)) is None  # not there


@pytest.mark.parametrize(("which", "expected"), [("newest", "/py/3.12"), ("oldest", "/py/3.11")])
def test_newest_and_oldest_are_the_ends_of_what_is_found(which, expected, monkeypatch, capsys):
    found = {(3, 11): "/py/3.11", (3, 12): "/py/3.12"}  # no 3.13 on this imagined machine
    monkeypatch.setattr(find_python, "find", found.get)
    assert find_python.main([which]) == 0
    assert capsys.readouterr().out.strip() == expected
    monkeypatch.setattr(find_python, "find", lambda version: None)
    assert find_python.main([which]) == 1
