"""Build and grade the course's graded assignments with otter-grader, offline and without Docker.

Each master notebook in ``assignments/`` holds the questions, their solutions and their public and
hidden tests (otter-grader's master-notebook format). ``build`` runs ``otter assign`` on each into
``dist/assignments/<name>/``: ``student/<name>.ipynb`` is what students get (no solutions, no
hidden tests), ``autograder/`` holds the solutions notebook and the autograder zip that
``otter run`` and Gradescope take. ``grade`` grades submissions locally with that zip::

    python tools/assignments.py build                     # every assignment (make assignments)
    python tools/assignments.py build 02_integrators_and_orders
    python tools/assignments.py grade 02_integrators_and_orders submissions/*.ipynb -o graded/

A submission is graded in a fresh kernel by ``otter run``. Around it this tool makes sure that a
bad submission is graded, not crashed on: a file that is not a notebook, or is empty, scores zero
with the reason; every cell gets a time limit (``--cell-seconds``: a cell that runs longer raises
``TimeoutError`` and what it should have answered scores zero) and the whole grading a wall-clock
limit (``--total-seconds``: past it the grading is stopped and the submission scores zero, and
the notes end with the grader's log and the stack of each thread of the kernel where it was); a
cell that raises, or graded cells that were deleted, cost only their questions, and the notes say
so. Every submission gets ``<stem>.json`` (Gradescope's results format, the notes added) and the
run a ``grades.csv`` (one row per submission, one column per question) for a gradebook such as
Canvas.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import importlib.util
import json
import os
import pickle
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import nbformat

REPO_ROOT = Path(__file__).resolve().parents[1]
ASSIGNMENTS = REPO_ROOT / "assignments"
DIST = REPO_ROOT / "dist" / "assignments"

#: Seconds one cell of a submission may run. The slowest cell of a solution takes a few
#: seconds once the integrators are compiled; a first compilation of a method takes up to
#: half a minute on a loaded machine.
CELL_SECONDS = 120.0
#: Seconds the grading of one submission may take in all (kernel start, every cell, every test).
TOTAL_SECONDS = 900.0

#: Put first in every graded submission: a per-cell time limit inside the grading kernel. A
#: timer started before each cell and cancelled after it raises TimeoutError in whatever runs
#: too long: an answer cell, or a test calling the student's function (otter then records that
#: test as failed, with the message, and goes on to the next test). The timer fires again every
#: ``seconds`` until the cell ends, so a second test stuck in the same function is stopped too.
#: Otter puts its own set-up cells before this one.
TIME_LIMIT_CELL = """\
# Added by the grader: no later cell may run longer than {seconds:g} s.
def _grader_time_limit(seconds):
    import faulthandler
    import os
    import signal
    import sys

    from IPython import get_ipython

    def stop(signum, frame):
        raise TimeoutError(f"stopped by the grader: this cell ran longer than {{seconds:g}} s")

    signal.signal(signal.SIGALRM, stop)
    # Where the kernel is stuck when the whole grading is stopped: the grader sends SIGUSR1
    # first, and every thread's stack goes to the log (also from inside compiled code).
    faulthandler.register(signal.SIGUSR1, file=sys.__stderr__, all_threads=True)
    with open({pid_file!r}, "w") as handle:
        handle.write(str(os.getpid()))
    events = get_ipython().events
    events.register("pre_run_cell",
                    lambda info: signal.setitimer(signal.ITIMER_REAL, seconds, seconds))
    events.register("post_run_cell", lambda result: signal.setitimer(signal.ITIMER_REAL, 0))


_grader_time_limit({seconds!r})
del _grader_time_limit
"""
#: Lines of the grader's log kept in the notes of a grading stopped by the total limit.
LOG_LINES = 60
TIME_LIMIT_MARK = "# Added by the grader: no later cell may run longer than"

_CHECK_CALL = re.compile(r"""\.check\(\s*["']([^"']+)["']\s*\)""")
_POINTS = re.compile(r"^points\s*=\s*([0-9.]+)\s*$", re.MULTILINE)


# ------------------------------------------------------------------------------ building
def masters(names: list[str] | None = None) -> list[Path]:
    """The master notebooks in ``assignments/``, or those named (file stems)."""
    found = {path.stem: path for path in sorted(ASSIGNMENTS.glob("*.ipynb"))}
    if not names:
        return list(found.values())
    unknown = [name for name in names if name not in found]
    if unknown:
        raise ValueError(f"no assignment named {unknown}; the assignments are {sorted(found)}")
    return [found[name] for name in names]


def build(master: Path, dist: Path = DIST) -> Path:
    """Run ``otter assign`` on ``master`` into ``dist/<name>/`` (replaced); return that folder.

    No PDFs are made and nothing is fetched. otter's own run of the tests on the solutions is
    left out (``--no-run-tests``): grading the solutions with the autograder zip, as ``build``
    on the command line (unless ``--no-check``) and the test suite do next, runs the same
    tests. Raises ``RuntimeError`` with otter's output if the build fails or does not produce
    the student notebook, the solutions and the autograder zip.
    """
    out = dist / master.stem
    if out.exists():
        shutil.rmtree(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    command = [sys.executable, "-m", "otter", "assign", "--no-pdfs", "--no-run-tests",
               master.name, str(out)]
    completed = subprocess.run(command, cwd=master.parent, capture_output=True, text=True,
                               env={**os.environ, "PYTHONWARNINGS": "ignore"}, check=False)
    log = completed.stdout + completed.stderr
    expected = [out / "student" / master.name, out / "autograder" / master.name]
    if completed.returncode != 0 or not all(path.exists() for path in expected):
        raise RuntimeError(f"otter assign failed on {master.name}:\n{log}")
    add_package(autograder_zip(out))  # exactly one zip, then the course's package in it
    return out


#: Where the package's wheel goes inside the autograder zip, and how its requirements name it:
#: relative to the folder the zip is unpacked in (Gradescope's /autograder/source), which is
#: where conda runs the pip part of environment.yml, and where requirements.txt lies.
WHEEL_FOLDER = "files"
_WHEEL: dict[str, bytes] = {}  # file name -> contents: built once per process


def package_wheel() -> tuple[str, bytes]:
    """The course's package as a wheel: its file name and its bytes (built once per process)."""
    if not _WHEEL:
        with tempfile.TemporaryDirectory(prefix="wheel-") as folder:
            # With the build backend at hand (the assignments extra) nothing is downloaded.
            isolation = ([] if importlib.util.find_spec("hatchling") is None
                         else ["--no-build-isolation"])
            completed = subprocess.run(
                [sys.executable, "-m", "pip", "wheel", "--no-deps", "--quiet", *isolation,
                 "-w", folder, str(REPO_ROOT)], capture_output=True, text=True, check=False)
            wheels = sorted(Path(folder).glob("pendulum_lab-*.whl"))
            if completed.returncode != 0 or len(wheels) != 1:
                raise RuntimeError(f"building the package's wheel failed:\n{completed.stderr}")
            _WHEEL[wheels[0].name] = wheels[0].read_bytes()
    return next(iter(_WHEEL.items()))


def add_package(zip_path: Path) -> None:
    """Put the course's package into an autograder zip, as Gradescope needs it.

    The hidden tests import ``pendulum_lab``, which no public index serves: its wheel goes into
    the zip (``files/``), ``requirements.txt`` names it, and so does the pip part of the zip's
    ``environment.yml`` (what Gradescope's image installs), beside otter-grader; the wheel's
    own requirements bring NumPy, SciPy, SymPy and Numba.
    """
    import yaml  # otter-grader's dependency

    name, contents = package_wheel()
    requirement = f"./{WHEEL_FOLDER}/{name}"
    with zipfile.ZipFile(zip_path) as archive:
        entries = {entry: archive.read(entry) for entry in archive.namelist()}
    environment = yaml.safe_load(entries["environment.yml"])
    pip = next(item["pip"] for item in environment["dependencies"] if isinstance(item, dict))
    pip.append(requirement)
    entries["environment.yml"] = yaml.safe_dump(environment, sort_keys=False).encode("utf-8")
    entries["requirements.txt"] = f"{requirement}\n".encode()
    entries[f"{WHEEL_FOLDER}/{name}"] = contents
    rebuilt = zip_path.with_suffix(".tmp")
    with zipfile.ZipFile(rebuilt, "w", zipfile.ZIP_DEFLATED) as archive:
        for entry, data in entries.items():
            archive.writestr(entry, data)
    rebuilt.replace(zip_path)


def autograder_zip(folder: Path) -> Path:
    """The autograder zip of a built assignment folder (otter names it with a time stamp)."""
    zips = sorted((folder / "autograder").glob("*-autograder_*.zip"))
    if len(zips) != 1:
        raise FileNotFoundError(f"expected one autograder zip in {folder / 'autograder'}, "
                                f"found {len(zips)}: build the assignment first")
    return zips[0]


def question_points(folder: Path) -> dict[str, float]:
    """Question name -> points, in the order of the autograder's test files."""
    points = {}
    with zipfile.ZipFile(autograder_zip(folder)) as archive:
        for name in sorted(archive.namelist()):
            if name.startswith("tests/") and name.endswith(".py"):
                match = _POINTS.search(archive.read(name).decode("utf-8"))
                points[Path(name).stem] = float(match.group(1)) if match else 1.0
    return points


# ------------------------------------------------------------------------------ grading
@dataclass
class Grade:
    """The grading of one submission.

    Attributes
    ----------
    submission : Path
    scores, possible : dict of str -> float
        Points earned and points possible per question.
    notes : list of str
        What went wrong with the submission as a whole (not a notebook, empty, cells that
        raised or ran out of time, graded cells missing, grading stopped), in words.
    outputs : dict of str -> str
        Otter's output per question (which test failed and why).
    results : dict
        The results file, in Gradescope's format (``tests``, ``score``), with the notes added.
    executed : nbformat.NotebookNode or None
        The submission as the grader ran it, when it ran.
    seconds : float
        Wall time of the grading.
    """

    submission: Path
    scores: dict[str, float]
    possible: dict[str, float]
    notes: list[str] = field(default_factory=list)
    outputs: dict[str, str] = field(default_factory=dict)
    results: dict = field(default_factory=dict)
    executed: object = None
    seconds: float = 0.0

    @property
    def score(self) -> float:
        return sum(self.scores.values())

    @property
    def max_score(self) -> float:
        return sum(self.possible.values())


def _zero(submission: Path, possible: dict[str, float], reason: str, seconds: float,
          details: tuple[str, ...] = ()) -> Grade:
    """A zero on every question, each test saying why; ``details`` (for the instructor) follow
    the reason in the notes."""
    tests = [{"name": name, "score": 0.0, "max_score": points, "output": reason}
             for name, points in possible.items()]
    notes = [reason, *details]
    results = {"score": 0.0, "tests": tests, "notes": list(notes)}
    return Grade(submission, dict.fromkeys(possible, 0.0), dict(possible), notes,
                 dict.fromkeys(possible, reason), results, None, seconds)


def read_submission(path: Path) -> tuple[nbformat.NotebookNode | None, str | None]:
    """The submission as a notebook, or ``None`` and why it cannot be graded."""
    if not path.is_file():
        return None, f"not graded: {path.name} is not a file"
    if path.suffix != ".ipynb":
        return None, f"not graded: {path.name} is not a notebook (a .ipynb file is expected)"
    text = path.read_text(encoding="utf-8", errors="replace")
    if not text.strip():
        return None, f"not graded: {path.name} is empty"
    try:
        notebook = nbformat.reads(text, as_version=4)
        nbformat.validate(notebook)
    except Exception as err:  # nbformat raises several kinds (JSON, schema, version)
        first_line = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        return None, f"not graded: {path.name} is not a readable notebook ({first_line[:200]})"
    return notebook, None


def missing_checks(notebook: nbformat.NotebookNode, questions) -> list[str]:
    """The questions whose check cell (``grader.check("name")``) is not in the notebook."""
    present = set()
    for cell in notebook.cells:
        if cell.cell_type == "code":
            present.update(_CHECK_CALL.findall(cell.source))
    return [name for name in questions if name not in present]


def _cell_problems(executed) -> list[str]:
    """One note per cell of the graded run that raised (a timeout included)."""
    notes, number = [], 0
    for cell in executed.cells:
        if cell.cell_type != "code" or TIME_LIMIT_MARK in cell.source:
            continue
        number += 1
        for output in cell.get("outputs", []):
            if output.get("output_type") == "error":
                first = cell.source.strip().splitlines()[0][:60] if cell.source.strip() else ""
                notes.append(f"a cell raised {output.get('ename')}: "
                             f"{str(output.get('evalue'))[:200]} (cell starting {first!r})")
    return notes


def _stop(process: subprocess.Popen, kernel_pid: Path) -> str:
    """End the grading process and its kernel, after asking the kernel for its threads' stacks;
    the log of the grading, with those stacks at its end.

    The kernel runs in a session of its own (jupyter_client starts it so), so it is signalled by
    the process id it wrote, once that is seen to be a child of the grading process: a kernel
    stuck in compiled code would not notice its parent's end."""
    kernel = _child_pid(kernel_pid, process.pid)
    if kernel is not None:
        os.kill(kernel, signal.SIGUSR1)
        time.sleep(1.0)  # faulthandler writes from the signal handler, at once
    with contextlib.suppress(ProcessLookupError):
        os.killpg(process.pid, signal.SIGKILL)
    if kernel is not None:
        with contextlib.suppress(ProcessLookupError):
            os.kill(kernel, signal.SIGKILL)
    log, _ = process.communicate()
    return log or ""


def _child_pid(pid_file: Path, parent: int) -> int | None:
    """The process id in ``pid_file`` if that process is a child of ``parent`` (read from
    Linux's ``/proc``; None elsewhere, and when the file or the process is gone)."""
    try:
        pid = int(pid_file.read_text())
        stat = Path(f"/proc/{pid}/stat").read_text()
    except (OSError, ValueError):
        return None
    # The fields after the command name, which is in parentheses: state, then the parent's id.
    return pid if int(stat.rsplit(")", 1)[1].split()[1]) == parent else None


def _tail(log: str, lines: int) -> str:
    return "\n".join(log.strip().splitlines()[-lines:])


def grade(folder: Path, submission: Path, *, cell_seconds: float = CELL_SECONDS,
          total_seconds: float = TOTAL_SECONDS) -> Grade:
    """Grade one submission with the autograder of the built assignment ``folder``.

    Parameters
    ----------
    folder : Path
        ``dist/assignments/<name>`` as made by :func:`build`.
    submission : Path
        The student's notebook.
    cell_seconds : float
        Time limit of each cell (and of the tests run by each check cell) [s].
    total_seconds : float
        Time limit of the whole grading [s].

    Returns
    -------
    Grade
        Never raises for a bad submission: it scores zero where it could not be graded, and
        ``notes`` and ``outputs`` say why.
    """
    if cell_seconds <= 0 or total_seconds <= 0:
        raise ValueError("`cell_seconds` and `total_seconds` must be positive")
    started = time.perf_counter()
    submission = Path(submission)
    possible = question_points(folder)
    notebook, problem = read_submission(submission)
    if notebook is None:
        return _zero(submission, possible, problem, time.perf_counter() - started)
    notes = []
    if not any(cell.cell_type == "code" for cell in notebook.cells):
        notes.append("the notebook has no code cells")
    notes += [f"the check cell of {name} is missing (were the graded cells deleted?)"
              for name in missing_checks(notebook, possible)]
    with tempfile.TemporaryDirectory(prefix="grade-") as work:
        work = Path(work)
        kernel_pid = work / "kernel.pid"
        notebook.cells.insert(0, nbformat.v4.new_code_cell(
            TIME_LIMIT_CELL.format(seconds=float(cell_seconds), pid_file=str(kernel_pid))))
        # Under the name it was handed out with: its first cell opens the notebook by name.
        copy = work / f"{folder.name}.ipynb"
        nbformat.write(notebook, copy)
        command = [sys.executable, "-m", "otter", "run", "-a", str(autograder_zip(folder)),
                   "-o", str(work), "--no-logo", "-p", str(copy)]
        env = {**os.environ, "PYTHONWARNINGS": "ignore"}
        process = subprocess.Popen(command, cwd=work, env=env, stdout=subprocess.PIPE,
                                   stderr=subprocess.STDOUT, text=True, start_new_session=True)
        try:
            log, _ = process.communicate(timeout=total_seconds)
        except subprocess.TimeoutExpired:
            log = _stop(process, kernel_pid)
            reason = (f"not graded: the grading was stopped after {total_seconds:g} s "
                      "(a cell that never ends and outlasts the per-cell limit?)")
            stacks = ("the end of the grader's log, with the kernel's stacks:\n"
                      + _tail(log, LOG_LINES))
            return _zero(submission, possible, reason, time.perf_counter() - started, (stacks,))
        results_file = work / "results.json"
        if not results_file.exists():
            tail = _tail(log, 5)
            reason = f"not graded: the autograder stopped with an error:\n{tail}"
            return _zero(submission, possible, reason, time.perf_counter() - started)
        results = json.loads(results_file.read_text())
        executed = None
        if (work / "results.pkl").exists():
            with open(work / "results.pkl", "rb") as handle:
                executed = getattr(pickle.load(handle), "notebook", None)
    if executed is not None:
        notes += _cell_problems(executed)
    scores, outputs = dict.fromkeys(possible, 0.0), {}
    for test in results.get("tests", []):
        if test.get("name") in possible:
            scores[test["name"]] = float(test.get("score") or 0.0)
            outputs[test["name"]] = test.get("output", "")
    results["notes"] = notes
    return Grade(submission, scores, dict(possible), notes, outputs, results, executed,
                 time.perf_counter() - started)


# ------------------------------------------------------------------------------ commands
def _build_command(args) -> int:
    for master in masters(args.names):
        start = time.perf_counter()
        folder = build(master, Path(args.dist))
        points = question_points(folder)
        line = (f"{master.stem}: {len(points)} questions, {sum(points.values()):g} points "
                f"({', '.join(f'{q} {p:g}' for q, p in points.items())}); built in "
                f"{time.perf_counter() - start:.1f} s")
        if args.check:
            solutions = grade(folder, folder / "autograder" / master.name)
            line += (f"; solutions score {solutions.score:g}/{solutions.max_score:g} "
                     f"(graded in {solutions.seconds:.1f} s)")
            if solutions.score != solutions.max_score:
                print(line)
                for name, text in solutions.outputs.items():
                    if solutions.scores[name] != solutions.possible[name]:
                        print(f"--- {name}\n{text}")
                return 1
        print(line, flush=True)
    return 0


def _grade_command(args) -> int:
    folder = Path(args.dist) / args.name
    autograder_zip(folder)
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for submission in map(Path, args.submissions):
        result = grade(folder, submission, cell_seconds=args.cell_seconds,
                       total_seconds=args.total_seconds)
        (out / f"{submission.stem}.json").write_text(json.dumps(result.results, indent=1))
        print(f"{submission}: {result.score:g}/{result.max_score:g} in {result.seconds:.1f} s")
        for note in result.notes:
            print(f"    note: {note}")
        rows.append({"submission": submission.name, **result.scores, "total": result.score})
    with open(out / "grades.csv", "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]) if rows else ["submission"])
        writer.writeheader()
        writer.writerows(rows)
    print(f"grades: {out / 'grades.csv'}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--dist", default=str(DIST), help="built assignments (dist/assignments)")
    commands = parser.add_subparsers(dest="command", required=True)
    build_parser = commands.add_parser("build", help="otter assign every (or each named) master")
    build_parser.add_argument("names", nargs="*", help="assignment names (default: all)")
    build_parser.add_argument("--no-check", dest="check", action="store_false",
                              help="do not grade the solutions after building")
    grade_parser = commands.add_parser("grade", help="grade submissions of one assignment")
    grade_parser.add_argument("name", help="the assignment (e.g. 01_derivations_and_fixed_points)")
    grade_parser.add_argument("submissions", nargs="+", help="submitted notebooks")
    grade_parser.add_argument("-o", "--output", default="graded", help="results folder (graded)")
    grade_parser.add_argument("--cell-seconds", type=float, default=CELL_SECONDS)
    grade_parser.add_argument("--total-seconds", type=float, default=TOTAL_SECONDS)
    args = parser.parse_args(argv)
    try:
        return _build_command(args) if args.command == "build" else _grade_command(args)
    except (ValueError, FileNotFoundError, RuntimeError) as err:
        print(f"assignments: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
