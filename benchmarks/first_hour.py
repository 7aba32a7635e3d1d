"""A student's first hour, measured from empty caches: notebook 00 up to its first figure, and
the wait for each method's first run on the double pendulum.

Beside the suite rather than an item of it: every measurement starts from empty kernel and Numba
caches, so it compiles everything it uses (minutes of CPU), and it can measure another source
tree (``--src``, for instance an export of an older commit) for a before-and-after comparison.

Usage (from the repository root)::

    .venv/bin/python benchmarks/first_hour.py                     # this checkout
    .venv/bin/python benchmarks/first_hour.py --src /tmp/old-tree --label before
    .venv/bin/python benchmarks/first_hour.py --only methods --methods rk4 glrk4

What it measures, each in a fresh process with new, empty ``PENDULUM_LAB_CACHE`` and
``NUMBA_CACHE_DIR`` folders:

* **first figure**: notebook 00 of the tree executed cell by cell in a new kernel (nbclient),
  as a student runs it after a fresh clone; the time from the start of the first cell to the
  end of the first cell that shows a figure, and each cell's time on the way. The kernel's
  start is reported apart.
* **methods**: the double pendulum's field loaded first (as an explorer showing its first
  picture has), then for each method the explorer's run (2000 steps of 0.01 s from (2.0, 2.5)
  at rest) twice: the first call's wall and CPU time minus the second's is the wait that
  switching an explorer to the method costs. Where the tree reports it, the run's own
  ``compile_time`` is given too.

Results are printed as Markdown and written to ``benchmarks/results/first_hour_LABEL.json`` and
``.md`` (``--out`` for another stem).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent

METHODS_SCRIPT = r"""
import json, sys, time
import pendulum_lab as pl

def clock():
    return time.perf_counter(), time.process_time()

dp = pl.double_pendulum()
start = clock()
pl.hamiltonian_field(dp)
end = clock()
rows = {"field": {"wall": end[0] - start[0], "cpu": end[1] - start[1]}}
for name in sys.argv[1:]:
    timings = []
    for _ in range(2):
        start = clock()
        traj = pl.simulate(dp, [2.0, 2.5], [0.0, 0.0], t_end=20.0, dt=0.01, method=name)
        end = clock()
        timings.append((end[0] - start[0], end[1] - start[1],
                        getattr(traj, "compile_time", None), traj.wall_time))
    (wall1, cpu1, compile1, run1), (wall2, cpu2, _, _) = timings
    rows[name] = {"first_wall": wall1, "first_cpu": cpu1, "second_wall": wall2,
                  "second_cpu": cpu2, "wait_wall": wall1 - wall2, "wait_cpu": cpu1 - cpu2,
                  "compile_time": compile1, "first_wall_time": run1}
print(json.dumps(rows))
"""


def empty_caches() -> tuple[tempfile.TemporaryDirectory, dict]:
    """New empty cache folders and the environment that points the package at them."""
    folder = tempfile.TemporaryDirectory(prefix="first_hour_")
    env = {"PENDULUM_LAB_CACHE": os.path.join(folder.name, "kernels"),
           "NUMBA_CACHE_DIR": os.path.join(folder.name, "numba")}
    return folder, env


def environment(src: Path, caches: dict) -> dict:
    env = {**os.environ, **caches, "PYTHONPATH": str(src / "src"), "PYTHONWARNINGS": "ignore"}
    env.pop("PENDULUM_LAB_COMPILE_NOTES", None)  # a student sees the notes
    env.pop("PENDULUM_LAB_SHARED_CACHE", None)  # a first hour reads no image's kernels
    return env


def shows_figure(cell) -> bool:
    return any("image/png" in output.get("data", {}) for output in cell.get("outputs", []))


def first_figure(src: Path) -> dict:
    """Notebook 00 cell by cell in a fresh kernel with empty caches, up to its first figure."""
    import nbformat
    from nbclient import NotebookClient

    path = src / "notebooks" / "00_start_here.ipynb"
    notebook = nbformat.read(path, as_version=4)
    folder, caches = empty_caches()
    saved = dict(os.environ)
    os.environ.clear()
    os.environ.update(environment(src, caches))
    try:
        client = NotebookClient(notebook, timeout=1800, kernel_name="python3",
                                resources={"metadata": {"path": str(path.parent)}})
        cells, started = [], time.perf_counter()
        with client.setup_kernel():
            kernel_start = time.perf_counter() - started
            first = time.perf_counter()
            for index, cell in enumerate(notebook.cells):
                if cell.cell_type != "code":
                    continue
                begin = time.perf_counter()
                client.execute_cell(cell, index)
                text = "".join(o.get("text", "") for o in cell.outputs
                               if o.output_type == "stream")
                notes = [o["data"]["text/plain"] for o in cell.outputs
                         if o.output_type == "display_data" and "text/plain" in o.get("data", {})
                         and "once per machine" in o["data"]["text/plain"]]
                cells.append({"cell": cell.get("id"), "seconds": time.perf_counter() - begin,
                              "first_line": cell.source.splitlines()[0][:70].replace("|", "\\|"),
                              "notes": notes, "stdout": text[-300:]})
                if shows_figure(cell):
                    break
            to_figure = time.perf_counter() - first
    finally:
        os.environ.clear()
        os.environ.update(saved)
        folder.cleanup()
    return {"kernel_start": kernel_start, "to_first_figure": to_figure, "cells": cells}


def method_waits(src: Path, methods: list[str]) -> dict:
    folder, caches = empty_caches()
    try:
        done = subprocess.run([sys.executable, "-c", METHODS_SCRIPT, *methods],
                              env=environment(src, caches), capture_output=True, text=True,
                              encoding="utf-8", errors="replace", timeout=7200, check=False)
    finally:
        folder.cleanup()
    if done.returncode != 0:
        raise RuntimeError(done.stderr[-2000:])
    return json.loads(done.stdout.strip().splitlines()[-1])


def load_average() -> tuple[float, float, float] | None:
    """The 1, 5 and 15 minute load averages, or None where there are none (Windows)."""
    try:
        return os.getloadavg()
    except (AttributeError, OSError):
        return None


def markdown(label: str, src: Path, results: dict) -> str:
    load = " / ".join(f"{x:.2f}" for x in load_average() or ()) or "unknown"
    lines = [f"# First hour ({label}: {src})", "",
             f"{time.strftime('%Y-%m-%d %H:%M')}, {os.cpu_count()} cores, load average "
             f"{load}; empty kernel and Numba caches.", ""]
    if "first_figure" in results:
        figure = results["first_figure"]
        lines += ["## Notebook 00 to its first figure", "",
                  f"Kernel start {figure['kernel_start']:.1f} s; first cell to the first figure "
                  f"{figure['to_first_figure']:.1f} s.", "",
                  "| cell | first line | seconds | compile notes shown |", "|---|---|---|---|"]
        for cell in figure["cells"]:
            notes = "; ".join(note.splitlines()[0] for note in cell["notes"]) or "-"
            lines.append(f"| {cell['cell']} | `{cell['first_line']}` | {cell['seconds']:.1f} | "
                         f"{notes} |")
        lines.append("")
    if "methods" in results:
        rows = results["methods"]
        lines += ["## The wait for each method's first run (double pendulum, 2000 steps)", "",
                  f"Loading the field first: {rows['field']['wall']:.1f} s wall, "
                  f"{rows['field']['cpu']:.1f} s CPU.", "",
                  "| method | wait, wall (s) | wait, CPU (s) | run's compile_time (s) | "
                  "run's wall_time, first call (s) |", "|---|---|---|---|---|"]
        for name, row in rows.items():
            if name == "field":
                continue
            compile_time = ("-" if row["compile_time"] is None
                            else f"{row['compile_time']:.1f}")
            lines.append(f"| {name} | {row['wait_wall']:.1f} | {row['wait_cpu']:.1f} | "
                         f"{compile_time} | {row['first_wall_time']:.2f} |")
        lines.append("")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--src", type=Path, default=REPO,
                        help="the source tree to measure (its src/ and notebooks/)")
    parser.add_argument("--label", default="after", help="name of the results (after)")
    parser.add_argument("--only", choices=("figure", "methods"), action="append",
                        help="one of the two measurements (both by default)")
    parser.add_argument("--methods", nargs="+", default=None,
                        help="methods to time (default: every method of pl.METHODS)")
    parser.add_argument("--out", type=Path, default=None, help="results stem")
    args = parser.parse_args(argv)
    src = args.src.resolve()
    wanted = set(args.only or ("figure", "methods"))
    methods = args.methods
    if methods is None:
        sys.path.insert(0, str(src / "src"))
        import pendulum_lab as pl

        methods = list(pl.METHODS)
    results = {"label": args.label, "src": str(src), "load_start": load_average()}
    if "figure" in wanted:
        results["first_figure"] = first_figure(src)
    if "methods" in wanted:
        results["methods"] = method_waits(src, methods)
    results["load_end"] = load_average()
    stem = args.out or HERE / "results" / f"first_hour_{args.label}"
    text = markdown(args.label, src, results)
    Path(f"{stem}.json").write_text(json.dumps(results, indent=1) + "\n", encoding="utf-8")
    Path(f"{stem}.md").write_text(text + "\n", encoding="utf-8")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
