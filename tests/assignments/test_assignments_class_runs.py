"""An instructor's run of ``grade``: paths, names, an accumulating CSV, re-runs, interruptions,
and the branches for the OSes without a sandbox (emulated).

Most cases grade files that are not notebooks (scored zero without starting a kernel), so the
run's bookkeeping is tested without the cost of gradings; one real grading checks a relative
``--dist``, one real grading is interrupted.
"""

from __future__ import annotations

import csv
import os
import shutil
import signal
import subprocess
import sys
import time

import psutil
import pytest
from assignment_harness import REPO_ROOT, tool

A1 = "01_derivations_and_fixed_points"
TOOL = REPO_ROOT / "tools" / "assignments.py"


def _rows(out) -> dict[str, float]:
    with open(out / "grades.csv", newline="") as handle:
        return {row["submission"]: float(row["total"]) for row in csv.DictReader(handle)}


def _seeded(kit, out):
    """An output folder whose sandbox cache is the session's (no compile of its own)."""
    shutil.copytree(kit.cache, out / ".kernel-cache")
    (out / ".kernel-cache" / "ready").write_text("")
    return out


def test_same_file_names_in_two_folders_stay_apart_and_the_csv_accumulates(kit, tmp_path,
                                                                           monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    for name in ("alice", "bob", "carol"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "hw.ipynb").write_text("")
    args = ["--dist", str(kit.dist), "grade", A1, "-o", "graded", "--jobs", "2"]
    assert tool.main([*args, "alice/hw.ipynb", "bob/hw.ipynb"]) == 0
    assert set(_rows(tmp_path / "graded")) == {"alice/hw.ipynb", "bob/hw.ipynb"}
    assert (tmp_path / "graded" / "alice" / "hw.json").exists()
    assert (tmp_path / "graded" / "bob" / "hw.json").exists()
    # A late submission: its row joins the others.
    assert tool.main([*args, "carol/hw.ipynb"]) == 0
    assert set(_rows(tmp_path / "graded")) == {"alice/hw.ipynb", "bob/hw.ipynb",
                                               "carol/hw.ipynb"}
    # A re-run grades only what changed.
    stamp = (tmp_path / "graded" / "bob" / "hw.json").stat().st_mtime_ns
    (tmp_path / "alice" / "hw.ipynb").write_text("not JSON")
    capsys.readouterr()
    assert tool.main([*args, "alice/hw.ipynb", "bob/hw.ipynb", "carol/hw.ipynb"]) == 0
    printed = capsys.readouterr().out
    assert "2 submissions unchanged" in printed
    assert "alice/hw.ipynb: 0/12" in printed and "bob/hw.ipynb:" not in printed
    assert (tmp_path / "graded" / "bob" / "hw.json").stat().st_mtime_ns == stamp
    assert "not a readable notebook" in (tmp_path / "graded" / "alice" / "hw.json").read_text()
    # Negative control: --regrade grades them all again.
    capsys.readouterr()
    assert tool.main([*args, "--regrade", "alice/hw.ipynb", "bob/hw.ipynb"]) == 0
    assert "bob/hw.ipynb: 0/12" in capsys.readouterr().out


def test_a_submission_outside_the_root_is_refused_with_the_reason(kit, tmp_path, capsys):
    (tmp_path / "hw.ipynb").write_text("")
    code = tool.main(["--dist", str(kit.dist), "grade", A1, str(tmp_path / "hw.ipynb"),
                      "--root", str(tmp_path / "elsewhere"), "-o", str(tmp_path / "out")])
    assert code == 2
    assert "is not under --root" in capsys.readouterr().err


def test_a_relative_dist_grades_like_an_absolute_one(kit, tmp_path, monkeypatch):
    monkeypatch.chdir(kit.dist.parent)
    submission = tmp_path / "solutions.ipynb"
    shutil.copy(kit.folders[A1] / "autograder" / f"{A1}.ipynb", submission)
    out = _seeded(kit, tmp_path / "graded")
    assert tool.main(["--dist", os.path.relpath(kit.dist), "grade", A1, str(submission),
                      "--root", str(tmp_path), "-o", str(out)]) == 0
    assert _rows(out) == {"solutions.ipynb": kit.solutions(A1).max_score}


def test_an_interrupted_run_ends_every_child_and_keeps_what_was_graded(kit, tmp_path):
    (tmp_path / "early.ipynb").write_text("")
    slow = kit.notebook(A1, "autograder")
    slow.cells[-1].source = "import time\ntime.sleep(3600)"
    slow.cells[-1].cell_type = "code"
    slow.cells[-1].outputs, slow.cells[-1].execution_count = [], None
    import nbformat

    nbformat.write(slow, tmp_path / "slow.ipynb")
    out = _seeded(kit, tmp_path / "graded")
    run = subprocess.Popen([sys.executable, str(TOOL), "--dist", str(kit.dist), "grade", A1,
                            "early.ipynb", "slow.ipynb", "-o", str(out), "--jobs", "2",
                            "--cell-seconds", "3000"], cwd=tmp_path,
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 300
    seen = []
    while time.time() < deadline and run.poll() is None:
        seen = psutil.Process(run.pid).children(recursive=True)
        if any("ipykernel" in " ".join(proc.cmdline()) for proc in seen
               if proc.is_running()):
            break
        time.sleep(1.0)
    assert run.poll() is None, run.communicate()
    time.sleep(3.0)
    seen = psutil.Process(run.pid).children(recursive=True)
    run.send_signal(signal.SIGTERM)
    _, err = run.communicate(timeout=120)
    assert run.returncode == 130, err
    assert "interrupted" in err
    assert _rows(out) == {"early.ipynb": 0.0}
    _, alive = psutil.wait_procs(seen, timeout=10)
    assert seen and alive == []


# ------------------------------------------------------------------------ OS branches, emulated
@pytest.mark.parametrize("platform", ["darwin", "win32"])
def test_without_linux_grading_is_refused_unless_asked_by_name(kit, tmp_path, monkeypatch,
                                                                 capsys, platform):
    monkeypatch.setattr(sys, "platform", platform)
    assert "exists on Linux only" in tool.sandbox_problem()
    submission = tmp_path / "hw.ipynb"
    shutil.copy(kit.folders[A1] / "autograder" / f"{A1}.ipynb", submission)
    with pytest.raises(tool.SandboxUnavailable, match=tool.NO_SANDBOX_FLAG):
        tool.grade(kit.folders[A1], submission)
    code = tool.main(["--dist", str(kit.dist), "grade", A1, str(submission), "--root",
                      str(tmp_path), "-o", str(tmp_path / "out")])
    assert code == 2 and tool.NO_SANDBOX_FLAG in capsys.readouterr().err
    assert not (tmp_path / "out" / "grades.csv").exists()


def test_a_linux_without_bubblewrap_is_told_how_to_install_it(monkeypatch):
    monkeypatch.setattr(sys, "platform", "linux")
    monkeypatch.setattr(shutil, "which", lambda name: None)
    assert "apt-get install bubblewrap" in tool.sandbox_problem()
    monkeypatch.undo()
    if shutil.which("bwrap"):  # negative control: here there is one
        assert tool.sandbox_problem() is None


def test_windows_branches_limits_groups_and_environment(monkeypatch):
    monkeypatch.setitem(sys.modules, "resource", None)  # Windows has no resource module
    assert tool._limit_resources(1024, 64) == [
        "memory and process count: not limited (no rlimits on Windows)"]
    monkeypatch.setattr(sys, "platform", "win32")
    assert "creationflags" in tool._new_group()
    monkeypatch.setenv("SYSTEMROOT", r"C:\Windows")
    env = tool._sandbox_env(r"C:\work", r"C:\cache")
    assert env["SYSTEMROOT"] == r"C:\Windows" and env["TEMP"].startswith(r"C:\work")
    monkeypatch.undo()
    assert tool._new_group() == {"start_new_session": True}  # negative control: POSIX


def test_a_process_tree_is_ended_whole_on_every_os():
    """psutil's walk of the tree (the branch Windows and macOS use, where there is no sandbox)
    ends a grandchild that Popen.kill alone leaves running."""
    code = ("import subprocess, sys, time\n"
            "subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(600)'])\n"
            "time.sleep(600)")

    def family():
        parent = subprocess.Popen([sys.executable, "-c", code])
        for _ in range(100):
            kids = psutil.Process(parent.pid).children(recursive=True)
            if kids:
                return parent, kids
            time.sleep(0.1)
        raise AssertionError("the grandchild did not start")

    parent, kids = family()
    parent.kill()
    parent.wait()
    _, alive = psutil.wait_procs(kids, timeout=2)
    assert alive, "negative control: Popen.kill leaves the grandchild"
    for proc in alive:
        proc.kill()
    parent, kids = family()
    tool.end_process_tree(parent)
    _, alive = psutil.wait_procs(kids, timeout=5)
    assert alive == [] and parent.poll() is not None


def test_srepr_text_is_parsed_never_evaluated():
    import sympy as sp

    g, l = sp.symbols("g l", positive=True)  # noqa: E741
    answer = 2 / sp.sqrt((2 + sp.sqrt(2)) * g / l)
    assert tool.decode_answer(tool.encode_answer(answer)) == answer
    matrix = sp.Matrix([[0, 1], [-g / l, 0]])
    assert tool.decode_answer(tool.encode_answer(matrix)) == matrix
    for attack in ["__import__('os').system('true')", "Symbol('x').__class__",
                   "open('/etc/passwd')", "Integer(1) + Integer(2)", "[c for c in ()]"]:
        with pytest.raises(ValueError):
            tool.parse_srepr(attack)
