"""A class on a hub at 9:00: what the image's shared kernel cache saves, and what one student's
kernel needs (the figures behind docs/hub.md's sizing).

* **First figure, N students at once.** N fresh processes, started together, each running
  notebook 00's cells up to its first figure (the import, the double pendulum, its glrk4 run,
  the energy plot rendered to PNG), as N kernels on one hub node do when a class presses Run
  together. *Shared*: every process reads an image's cache (``pendulum-lab warmup --cache``,
  made once beforehand, its time reported apart) as ``PENDULUM_LAB_SHARED_CACHE``, with an
  empty cache of its own. *Cold*: each process has only its own empty kernel and Numba caches
  (a hub without the image's cache). Reported: the time until the last student's figure and
  the median student's, from the common start. The hub itself is left out (tests/hub runs the
  same cells through a real one); its servers' start is a fixed cost per student either way.
* **One kernel per notebook.** Each notebook run top to bottom (nbclient) in a fresh kernel
  reading a warm cache: the kernel's peak resident memory (``ru_maxrss``) and its CPU seconds,
  read by a last cell appended to the notebook.

Run alone (it is not in the suite's list: it takes minutes)::

    python benchmarks/item_classroom.py --students 5 10 --notebooks 00 04 11 17

Prints JSON lines and a Markdown table; the numbers depend on the machine and its load
(printed with them).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = ROOT / "notebooks"
# notebook 00's cells up to its first figure, found by what they hold
FIRST_FIGURE_CELLS = ("import pendulum_lab as pl", "pl.double_pendulum(", "pl.simulate(",
                      "plotting.plot_energy(")
MEASURE_CELL = (
    "import json as _json, resource as _resource\n"
    "_usage = _resource.getrusage(_resource.RUSAGE_SELF)\n"
    "print('KERNEL_USAGE', _json.dumps({'peak_rss_mb': _usage.ru_maxrss / 1024, "
    "'cpu_s': _usage.ru_utime + _usage.ru_stime}))\n"
)


def _load() -> float:
    return round(os.getloadavg()[0], 1) if hasattr(os, "getloadavg") else float("nan")


def first_figure_code() -> str:
    """A script of notebook 00's cells up to its first figure, the figure saved as PNG."""
    notebook = json.loads((NOTEBOOKS / "00_start_here.ipynb").read_text(encoding="utf-8"))
    sources = ["".join(cell["source"]) for cell in notebook["cells"]
               if cell["cell_type"] == "code"]
    chosen = [next(source for source in sources if marker in source)
              for marker in FIRST_FIGURE_CELLS]
    lines = [line for line in "\n".join(chosen).splitlines() if not line.startswith("%")]
    *body, last = lines  # the figure is the last line's value, as in the notebook
    return ("import io, matplotlib\nmatplotlib.use('agg')\n" + "\n".join(body)
            + f"\n_figure = {last}\n_buffer = io.BytesIO()\n"
            "getattr(_figure, 'figure', _figure).savefig(_buffer, format='png')\n"
            "assert _buffer.getvalue()[:4] == b'\\x89PNG'\nprint('FIGURE')\n")


def _student_env(home: Path, shared: Path | None) -> dict:
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("PENDULUM_LAB", "NUMBA_CACHE"))}
    env |= {"PENDULUM_LAB_CACHE": str(home / "kernels"), "NUMBA_CACHE_DIR": str(home / "numba"),
            "PENDULUM_LAB_COMPILE_NOTES": "off", "MPLCONFIGDIR": str(home / "mpl"),
            "PYTHONPATH": str(ROOT / "src")}
    if shared is not None:
        env["PENDULUM_LAB_SHARED_CACHE"] = str(shared)
    return env


def _children_cpu() -> float:
    """CPU seconds of the finished children (POSIX); NaN where the system does not count
    them (Windows)."""
    try:
        import resource
    except ImportError:
        return float("nan")
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def class_at_once(students: int, shared: Path | None, work: Path) -> dict:
    """Start ``students`` first-figure processes together; seconds to each one's figure, and
    the CPU seconds each one used (their mean)."""
    code = first_figure_code()
    cpu = _children_cpu()
    processes = []
    start = time.perf_counter()
    for index in range(students):
        home = work / f"student{index:02d}"
        home.mkdir(parents=True)
        processes.append(subprocess.Popen([sys.executable, "-c", code],
                                          env=_student_env(home, shared),
                                          stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                          text=True, encoding="utf-8"))
    ends = [None] * students
    while any(end is None for end in ends):
        for index, process in enumerate(processes):
            if ends[index] is None and process.poll() is not None:
                ends[index] = time.perf_counter() - start
                out, err = process.communicate()
                if process.returncode != 0 or "FIGURE" not in out:
                    raise RuntimeError(f"student {index}: {err[-2000:]}")
        time.sleep(0.05)
    return {"last s": round(max(ends), 1), "median s": round(statistics.median(ends), 1),
            "CPU s per student": round((_children_cpu() - cpu) / students, 1)}


def kernel_usage(notebook: str, timeout: float) -> dict:
    """Peak RSS and CPU of a fresh kernel that runs ``notebook`` top to bottom."""
    import nbclient
    import nbformat

    path = next(NOTEBOOKS.glob(f"{notebook}_*.ipynb"))
    nb = nbformat.read(path, as_version=4)
    nb.cells.append(nbformat.v4.new_code_cell(MEASURE_CELL))
    env = {k: v for k, v in os.environ.items() if k != "PENDULUM_LAB_COMPILE_NOTES"}
    env |= {"PENDULUM_LAB_COMPILE_NOTES": "off", "PYTHONPATH": str(ROOT / "src")}
    start = time.perf_counter()
    client = nbclient.NotebookClient(nb, timeout=timeout, kernel_name="python3",
                                     resources={"metadata": {"path": str(NOTEBOOKS)}})
    client.km_kwargs = {}
    old = dict(os.environ)
    os.environ.update(env)
    try:
        client.execute()
    finally:
        os.environ.clear()
        os.environ.update(old)
    wall = time.perf_counter() - start
    text = "".join(output.get("text", "") for output in nb.cells[-1].outputs)
    usage = json.loads(text.split("KERNEL_USAGE", 1)[1])
    return {"notebook": path.name, "peak RSS MB": round(usage["peak_rss_mb"]),
            "kernel CPU s": round(usage["cpu_s"], 1), "wall s": round(wall, 1)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--students", type=int, nargs="*", default=[5, 10])
    parser.add_argument("--notebooks", nargs="*", default=["00", "04", "11", "17"])
    parser.add_argument("--timeout", type=float, default=1800.0,
                        help="seconds per cell for the notebook runs")
    args = parser.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory(prefix="classroom_bench_") as tmp:
        tmp = Path(tmp)
        if args.students:
            image = tmp / "image"
            start = time.perf_counter()
            subprocess.run([sys.executable, "-m", "pendulum_lab", "warmup", "--cache", str(image),
                            "--n", "2", "--methods", "glrk4", "--progress", "none"],
                           env=_student_env(tmp / "builder", None), check=True,
                           capture_output=True)
            built = time.perf_counter() - start
            print(json.dumps({"image (glrk4, double pendulum) built in s": round(built, 1),
                              "load": _load()}), flush=True)
        for students in args.students:
            for label, shared in (("shared", tmp / "image"), ("cold", None)):
                load = _load()
                result = class_at_once(students, shared, tmp / f"{label}{students}")
                row = {"students": students, "caches": label, **result, "load at start": load}
                print(json.dumps(row), flush=True)
                rows.append(row)
        usages = []
        for notebook in args.notebooks:
            usage = {**kernel_usage(notebook, args.timeout), "load": _load()}
            print(json.dumps(usage), flush=True)
            usages.append(usage)
    if rows:
        print("\n| students | caches | last figure (s) | median figure (s) | CPU per student (s) "
              "| load at start |")
        print("|---|---|---|---|---|---|")
        for row in rows:
            print(f"| {row['students']} | {row['caches']} | {row['last s']} | "
                  f"{row['median s']} | {row['CPU s per student']} | {row['load at start']} |")
    if usages:
        print("\n| notebook | peak RSS (MB) | kernel CPU (s) | wall (s) |")
        print("|---|---|---|---|")
        for usage in usages:
            print(f"| {usage['notebook']} | {usage['peak RSS MB']} | {usage['kernel CPU s']} | "
                  f"{usage['wall s']} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
