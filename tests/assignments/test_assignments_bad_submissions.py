"""Bad submissions are graded, never crashed on: a zero for what could not run, and the reason.

Also: grading needs no network and no Docker (the grading command run in a network namespace with
only the loopback device, and with a ``docker`` on the PATH that records any call).
"""

from __future__ import annotations

import csv
import os
import shlex
import shutil
import subprocess
import sys
import textwrap

import pytest
from assignment_harness import REPO_ROOT, replace_cell

A1 = "01_derivations_and_fixed_points"
A2 = "02_integrators_and_orders"


@pytest.mark.parametrize("content, suffix, reason", [
    ("A short essay about pendulums.\n", ".txt", "is not a notebook"),
    ("{this is not JSON", ".ipynb", "is not a readable notebook"),
    ('{"cells": 3}', ".ipynb", "is not a readable notebook"),
    ("", ".ipynb", "is empty"),
    ("  \n", ".ipynb", "is empty"),
], ids=["text file", "not JSON", "not a notebook's JSON", "empty", "blank"])
def test_a_file_that_is_not_a_notebook_scores_zero_with_the_reason(kit, tmp_path, content,
                                                                    suffix, reason):
    submission = tmp_path / f"submission{suffix}"
    submission.write_text(content)
    graded = kit.grade(A1, submission, "not-a-notebook")
    assert graded.score == 0 and set(graded.scores) == set(graded.possible)
    assert any(reason in note for note in graded.notes)
    assert all(reason in output for output in graded.outputs.values())
    assert graded.results["score"] == 0 and len(graded.results["tests"]) == len(graded.possible)


@pytest.fixture(scope="module")
def broken_cells(kit):
    """Assignment 1's solutions with three kinds of damage, each to its own question."""
    solutions = kit.notebook(A1, "autograder")
    damaged = replace_cell(solutions, "amplitude_10_percent = brentq",
                           'raise RuntimeError("the root finder is broken")')        # q6
    damaged = replace_cell(damaged, "period_2rad = float", "while True:\n    pass")    # q5
    deleted = [cell for cell in damaged.cells
               if "jacobian_up" in cell.source or "Question 3 (" in cell.source]     # q3
    assert len(deleted) == 3  # the question, its answer cell and its check cell
    damaged.cells = [cell for cell in damaged.cells if cell not in deleted]
    return kit.grade(A1, damaged, "broken-cells", cell_seconds=10.0, total_seconds=300.0)


def _full_except(graded, lost: set[str]) -> bool:
    return all(graded.scores[q] == (0 if q in lost else graded.possible[q]) for q in graded.scores)


def test_broken_cells_cost_only_their_questions(broken_cells):
    lost = {"q3_jacobian_up", "q5_period_from_simulation", "q6_ten_percent_amplitude"}
    assert _full_except(broken_cells, lost), broken_cells.scores


def test_a_cell_that_raises_is_named(broken_cells):
    """The raising cell comes after the looping one: with nbclient's output reader of a
    timed-out cell left running (interrupt_on_timeout off), the outputs of the cells after it
    were swallowed at random and this note went missing."""
    assert any("RuntimeError: the root finder is broken" in note for note in broken_cells.notes)


def test_a_cell_that_loops_forever_is_stopped_by_the_cell_time_limit(broken_cells):
    assert any("TimeoutError" in note and "longer than 10 s" in note
               for note in broken_cells.notes)
    assert broken_cells.seconds < 300.0  # stopped by the cell's limit, not the total one


def test_deleted_graded_cells_are_named(broken_cells):
    assert any("check cell of q3_jacobian_up is missing" in note for note in broken_cells.notes)
    assert "is not answered yet" in broken_cells.outputs["q3_jacobian_up"]


def test_a_step_function_that_never_returns_fails_only_its_tests(kit):
    """The tests call the student's function: its first call is stopped at the cell's time
    limit and fails; it is not called again, so its later tests fail at once and the grading
    ends well within its total time (before, each of its hundreds of calls waited out the
    limit and the total time ran out, losing every question)."""
    hanging = textwrap.dedent('''\
        def leapfrog_step(theta, p, h):
            """A step that never returns."""
            while True:
                pass
        ''')
    submission = replace_cell(kit.notebook(A2, "autograder"), "def leapfrog_step", hanging)
    graded = kit.grade(A2, submission, "hanging-step", cell_seconds=6.0, total_seconds=300.0)
    assert _full_except(graded, {"q2_leapfrog"}), graded.scores
    assert "TimeoutError: stopped by the grader" in graded.outputs["q2_leapfrog"]
    assert "not called again" in graded.outputs["q2_leapfrog"]
    assert not any("stopped after" in note for note in graded.notes)  # not the total limit


def test_a_cell_that_ignores_the_interrupt_is_skipped_in_a_new_kernel(kit):
    """A loop that catches the interrupt sent at the end of its time: its kernel is stopped and
    the notebook run again without that cell, so that only its question is lost."""
    stubborn = textwrap.dedent("""\
        while True:
            try:
                while True:
                    pass
            except BaseException:
                pass
        """)
    submission = replace_cell(kit.notebook(A1, "autograder"), "period_2rad = float", stubborn)
    graded = kit.grade(A1, submission, "stubborn", cell_seconds=8.0, total_seconds=400.0)
    assert _full_except(graded, {"q5_period_from_simulation"}), graded.scores
    assert any("ignored the interrupt" in note for note in graded.notes), graded.notes
    assert any("GraderSkipped" in note for note in graded.notes)


def test_the_total_limit_ends_the_grading_and_every_process_of_it(kit):
    """Past ``total_seconds`` the checker, the runner, the kernel and whatever the kernel
    started are ended, and the submission scores zero with the reason."""
    import psutil

    sleeper = "import subprocess, time\nsubprocess.Popen(['sleep', '4321'])\ntime.sleep(3600)"
    submission = replace_cell(kit.notebook(A1, "autograder"), "period_2rad = float", sleeper)
    graded = kit.grade(A1, submission, "total-limit", cell_seconds=600.0, total_seconds=30.0)
    assert graded.score == 0
    assert any("stopped after 30 s" in note for note in graded.notes)
    assert graded.seconds < 120
    time_left = [proc for proc in psutil.process_iter(["cmdline"])
                 if proc.info["cmdline"] and proc.info["cmdline"][:2] == ["sleep", "4321"]]
    assert time_left == []


def _offline(tmp_path, args):
    """``args`` run in a new network namespace (loopback only) with a recording ``docker``."""
    fake_bin = tmp_path / "bin"
    fake_bin.mkdir(exist_ok=True)
    record = tmp_path / "docker-called"
    docker = fake_bin / "docker"
    docker.write_text(f"#!/bin/sh\necho \"$@\" >> {record}\nexit 1\n")
    docker.chmod(0o755)
    inner = "ip link set lo up && exec " + " ".join(shlex.quote(str(arg)) for arg in args)
    env = {**os.environ, "PATH": f"{fake_bin}:{os.environ.get('PATH', '')}",
           "DOCKER_HOST": "unix:///nonexistent/docker.sock"}
    completed = subprocess.run(["unshare", "--net", "sh", "-c", inner], env=env,
                               capture_output=True, text=True, timeout=600, check=False)
    return completed, record


def _isolation_problem() -> str | None:
    if shutil.which("unshare") is None or shutil.which("ip") is None:
        return "unshare or ip is missing"
    probe = subprocess.run(["unshare", "--net", "sh", "-c", "ip link set lo up"],
                           capture_output=True, text=True, check=False)
    return None if probe.returncode == 0 else f"no network namespace here: {probe.stderr.strip()}"


def test_grading_command_works_offline_without_docker_and_reports_every_submission(kit,
                                                                                  tmp_path):
    problem = _isolation_problem()
    if problem and os.environ.get("CI") != "true":
        pytest.skip(problem)
    assert problem is None, problem
    good = tmp_path / "good.ipynb"
    shutil.copy(kit.folders[A1] / "autograder" / f"{A1}.ipynb", good)
    bad = tmp_path / "bad.ipynb"
    bad.write_text("")
    out = tmp_path / "graded"
    shutil.copytree(kit.cache, out / ".kernel-cache")  # the solutions' compiled kernels
    (out / ".kernel-cache" / "ready").write_text("")
    completed, record = _offline(tmp_path, [sys.executable, REPO_ROOT / "tools" / "assignments.py",
                                            "--dist", kit.dist, "grade", A1, bad, good,
                                            "-o", out, "--root", tmp_path])
    assert completed.returncode == 0, completed.stdout + completed.stderr
    assert "note: not graded: bad.ipynb is empty" in completed.stdout
    with open(out / "grades.csv") as handle:
        rows = {row["submission"]: float(row["total"]) for row in csv.DictReader(handle)}
    assert rows == {"bad.ipynb": 0.0, "good.ipynb": kit.solutions(A1).max_score}
    assert (out / "bad.json").exists() and (out / "good.json").exists()
    assert not record.exists(), record.read_text()
    # Negative control: inside the namespace nothing beyond the loopback device answers.
    probe, _ = _offline(tmp_path, [sys.executable, "-c",
                                   "import socket; s = socket.socket(); s.settimeout(3); "
                                   "raise SystemExit(s.connect_ex(('192.0.2.1', 80)))"])
    assert probe.returncode != 0
