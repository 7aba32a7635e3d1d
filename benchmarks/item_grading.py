"""A class graded: copies of a realistic submission to assignment 02, in parallel against serial.

The submission is the solutions with two slips a student makes (explicit Euler handed in as the
leapfrog, the sign of a SymPy answer lost): it earns 10 of 16 points, and its gradings run
every kind of hidden test (step functions called by the checker, numbers, SymPy text). The
class run is ``tools/assignments.py``'s own ``grade_class`` (sandboxed, as an instructor runs
it), with ``--jobs`` = the cores; the serial run is the same with one job, on fewer copies when
asked (its per-submission time then extrapolates to the class), and plain ``otter run`` (the
grading before the sandbox, one after another) on as many copies as the serial run.

Run alone (it is not in the suite's list, as it takes minutes per dozen submissions)::

    python benchmarks/item_grading.py --copies 200 --serial 10

Prints a Markdown row and the details; the numbers depend on the machine's load (printed).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import nbformat

ROOT = Path(__file__).resolve().parents[1]
A2 = "02_integrators_and_orders"
SLIPS = [  # (answer cell marker, right text, wrong text)
    ("def leapfrog_step", "p_half = p - 0.5 * h * G * np.sin(theta)\n"
     "    theta_new = theta + h * p_half\n"
     "    return theta_new, p_half - 0.5 * h * G * np.sin(theta_new)",
     "return theta + h * p, p - h * G * np.sin(theta)"),
    ("leapfrog_limit = 2 /", "leapfrog_limit = 2 /", "leapfrog_limit = -2 /"),
]


def _tool():
    spec = importlib.util.spec_from_file_location("assignment_tool",
                                                  ROOT / "tools" / "assignments.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def realistic_submission(folder: Path) -> nbformat.NotebookNode:
    notebook = nbformat.read(folder / "autograder" / f"{A2}.ipynb", as_version=4)
    for marker, right, wrong in SLIPS:
        cell = next(c for c in notebook.cells if c.cell_type == "code" and marker in c.source)
        assert right in cell.source, marker
        cell.source = cell.source.replace(right, wrong)
    return notebook


def _copies(notebook, where: Path, count: int) -> dict[str, Path]:
    paths = {}
    for index in range(count):
        path = where / f"student{index:03d}" / f"{A2}.ipynb"
        path.parent.mkdir(parents=True)
        nbformat.write(notebook, path)
        paths[path.relative_to(where).as_posix()] = path
    return paths


def bench_grading(copies: int, serial: int, jobs: int, otter_copies: int) -> dict:
    tool = _tool()
    with tempfile.TemporaryDirectory(prefix="grading_bench_") as tmp:
        tmp = Path(tmp)
        folder = tool.build(tool.ASSIGNMENTS / f"{A2}.ipynb", tmp / "dist")
        cache = tmp / "cache"
        warm = tool.warm_cache(folder, cache)
        submission = realistic_submission(folder)
        load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
        result = {"copies": copies, "jobs": jobs, "serial copies": serial,
                  "load at start": round(load, 1), "warm (solutions) s": round(warm.seconds, 1)}
        for label, count, workers in [("class", copies, jobs), ("serial", serial, 1)]:
            paths = _copies(submission, tmp / label, count)
            start = time.perf_counter()
            grades = tool.grade_class(folder, paths, tmp / f"out-{label}", jobs=workers,
                                      progress=sys.stderr.isatty(), cache=cache)
            wall = time.perf_counter() - start
            scores = sorted({graded.score for graded in grades.values()})
            result[f"{label} wall s"] = round(wall, 1)
            result[f"{label} s per submission"] = round(wall / count, 2)
            result[f"{label} s per submission per core"] = round(wall * workers / count, 2)
            result[f"{label} scores"] = scores
            print(json.dumps({k: v for k, v in result.items() if k.startswith(label)}),
                  flush=True)
        if otter_copies:
            path = tmp / "otter" / f"{A2}.ipynb"
            path.parent.mkdir()
            nbformat.write(submission, path)
            start = time.perf_counter()
            for _ in range(otter_copies):
                subprocess.run([sys.executable, "-m", "otter", "run", "-a",
                                str(tool.autograder_zip(folder)), "-o", str(path.parent),
                                "--no-logo", str(path)], cwd=path.parent, capture_output=True,
                               check=False)
            result["plain otter run s per submission"] = round(
                (time.perf_counter() - start) / otter_copies, 2)
            results = (path.parent / "results.json").read_text(encoding="utf-8")
            tests = json.loads(results).get("tests", [])
            result["plain otter score"] = sum(test.get("score", 0) for test in tests)
        result["load at end"] = round(os.getloadavg()[0], 1) if hasattr(os, "getloadavg") \
            else float("nan")
        result["class of 200, extrapolated from the class run, min"] = round(
            result["class s per submission"] * 200 / 60, 1)
        result["class of 200, serial, extrapolated, min"] = round(
            result["serial s per submission"] * 200 / 60, 1)
        shutil.rmtree(tmp / "dist", ignore_errors=True)
    return result


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--copies", type=int, default=200)
    parser.add_argument("--serial", type=int, default=10)
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--otter", type=int, default=2,
                        help="copies graded by plain otter run (0: none)")
    args = parser.parse_args()
    result = bench_grading(args.copies, args.serial, args.jobs, args.otter)
    print(json.dumps(result, indent=1))
    print(f"| grading | {args.copies} copies of a 10/16 submission, --jobs {args.jobs} | "
          f"{result['class wall s']} s | {result['class s per submission per core']} s per "
          f"submission per core | serial {result['serial s per submission']} s per submission "
          f"| {result['serial s per submission'] / result['class s per submission']:.2f}x |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
