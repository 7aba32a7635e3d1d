"""Run the whole test suite (``make test``) as a queue of pytest jobs, two at a time.

The suite's time goes mostly to running notebooks and building environments: the browser tests
run every notebook in JupyterLab (the website's build shows those runs' outputs), the Binder
test builds Binder's environment and runs a few of them there under nbval, the install tests
build a student's environment, the floors run the unit suite under the oldest supported
versions. On a machine with two cores the jobs run two at a time, in the order below, and each
core that a job leaves takes the next job of the queue. Much of a job's time is spent waiting
on a kernel, a browser, an installer or a grader's time limit, so the floors job is not
queued: it starts at once at the lowest scheduling priority, spread over two processes, and
takes the cores whenever the queued jobs leave them idle (and all of them once those are done).
Each job's output is printed when it ends; the run fails if any job fails.

* ``browser``: the notebooks in JupyterLab in Chromium, and the website (``tests/browser``,
  ``tests/site``);
* ``core``: everything else in the main environment: doctests, unit, property and symbolic
  tests, and the graded assignments;
* ``environments``: the tests that build environments of their own and start servers in them
  (``tests/binder``: Binder's environment, where three notebooks run under nbval;
  ``tests/install``: a student's, from a fresh clone, the sdist and the wheel; ``tests/hub``: a
  class on a JupyterHub), and the benchmark items' smoke runs (``tests/benchmarks``: fresh
  interpreters with empty caches, a Dask cluster), which balance the two cores;
* ``floors`` (with ``--floors PYTHON``): the unit suite (what ``make check`` runs) under the
  interpreter of the environment with the oldest supported versions pinned (``make
  test-floors``), with its own kernel caches (compiled code differs between library versions).
  It runs in the background from the start, at the lowest priority, its tests spread over as
  many processes as the queue has workers (pytest-xdist): its many small tests are the work
  that can fill the cores whenever the other jobs wait, and both at the end.

Servers pick free ports and environments live in folders of their own, so jobs never compete
for a port or a folder. With one core (or ``--serial``) it runs a single pytest over everything,
then the floors; ``--floors-only`` runs the floors job alone, under the interpreter running this
script. Any other arguments go to pytest unchanged (``python tools/run_tests.py -x -k order``).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: The jobs in the main environment, by the folders they test (``core`` takes what is left).
#: The benchmark items' smoke runs go with the environments: the core job is the longest, and
#: the browser job and the environments together were about four minutes shorter.
FOLDERS = {"browser": ["tests/browser", "tests/site"],
           "environments": ["tests/binder", "tests/install", "tests/hub", "tests/benchmarks"]}
ELSEWHERE = [folder for folders in FOLDERS.values() for folder in folders]
CORE = ["src", "tests"] + [f"--ignore={path}" for path in ELSEWHERE]
#: What ``make check`` runs: the unit suite, without notebooks, browser, website, Binder,
#: installs, the hub or the graded assignments.
UNIT_SUITE = ["src", "tests"] + [
    f"--ignore={path}" for path in ["tests/browser", "tests/site", "tests/binder",
                                    "tests/install", "tests/hub", "tests/assignments"]]
#: The order the queue's jobs start in: the longest first (measured on a clean clone, see
#: docs/testing.md). The floors are not queued: they start at once in the background.
ORDER = ["browser", "core", "environments"]


def floors_job(python: str, extra: list[str], processes: int = 1) -> tuple[list[str], dict]:
    """The command and environment of the unit suite in the floor environment, its tests
    spread over ``processes`` (more than one: pytest-xdist, the test extra's)."""
    caches = ROOT / ".venv-floors-caches"
    env = {**os.environ, "PENDULUM_LAB_CACHE": str(caches / "kernels"),
           "NUMBA_CACHE_DIR": str(caches / "numba")}
    # The benchmark items' smoke runs check the benchmark harness, which the main environment
    # tests; at the floors they would repeat the library's runs that the unit tests make. So
    # would the tests marked `plumbing` (the command line's warm-up, the report).
    spread = ["-n", str(processes)] if processes > 1 else []
    # Of the methods whose kernels are one code with other coefficients (the composition
    # methods, the Gauss-Legendre methods), the floors test the first of each family.
    command = [python, "-m", "pytest", "-o", "cache_dir=.pytest_cache/floors", *UNIT_SUITE,
               "--ignore=tests/benchmarks", "-m", "not plumbing", "--one-method-per-family",
               *spread, *extra]
    return command, env


def run_serial(extra: list[str], floors: str | None) -> int:
    code = subprocess.call([sys.executable, "-m", "pytest", *extra], cwd=ROOT)
    if floors is not None:
        command, env = floors_job(floors, extra)
        code = max(code, subprocess.call(command, cwd=ROOT, env=env))
    return code


def pytest_job(name: str, paths: list[str], extra: list[str]) -> tuple[list[str], None]:
    # One process: the core job's module-scoped fixtures (the graded attack arena, the report)
    # would be built again by each pytest-xdist process that gets one of their tests.
    return ([sys.executable, "-m", "pytest", "-o", f"cache_dir=.pytest_cache/{name}", *paths,
             *extra], None)


def children_cpu_seconds() -> float | None:
    """User and system CPU seconds of the reaped child processes and their reaped descendants
    so far (POSIX), or None where the ``resource`` module does not exist (Windows)."""
    try:
        import resource
    except ImportError:
        return None
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def lowest_priority() -> dict:
    """Popen arguments that start a process at the lowest scheduling priority: it runs when
    the cores would otherwise idle (POSIX: nice 19, which its children inherit; Windows: the
    idle priority class)."""
    if os.name == "nt":
        return {"creationflags": getattr(subprocess, "IDLE_PRIORITY_CLASS", 0x40)}
    return {"preexec_fn": lambda: os.nice(19)}


def run_queue(extra: list[str], floors: str | None, workers: int = 2) -> int:
    jobs = {"core": pytest_job("core", CORE, extra)}
    jobs.update({name: pytest_job(name, folders, extra) for name, folders in FOLDERS.items()})
    waiting = [(name, *jobs[name]) for name in ORDER if name in jobs]
    started = time.perf_counter()
    with tempfile.TemporaryDirectory() as logs:
        running, codes, minutes = {}, {}, {}

        def start(name, command, env, background=False):
            log = open(Path(logs) / f"{name}.log", "w+", encoding="utf-8")  # noqa: SIM115 (closed below)
            process = subprocess.Popen(command, cwd=ROOT, stdout=log, env=env,
                                       stderr=subprocess.STDOUT,
                                       **(lowest_priority() if background else {}))
            running[name] = (process, log, time.perf_counter(), background)
            print(f"{name}{' (in the background)' if background else ''}: "
                  f"{' '.join(command[1:])}", flush=True)

        if floors is not None:
            start("floors", *floors_job(floors, extra, processes=workers), background=True)
        while waiting or running:
            queued = sum(not background for *_, background in running.values())
            while waiting and queued < workers:
                start(*waiting.pop(0))
                queued += 1
            time.sleep(1.0)
            for name, (process, log, since, _) in list(running.items()):
                before = children_cpu_seconds()
                if process.poll() is None:
                    continue
                codes[name] = process.returncode
                minutes[name] = (time.perf_counter() - since) / 60
                # The job's processes' CPU time, counted when the job is reaped (None on Windows).
                cpu = children_cpu_seconds()
                spent = "" if cpu is None else f", {(cpu - before) / 60:.1f} min CPU"
                log.seek(0)
                print(f"\n{'=' * 30} {name} (exit {codes[name]}, {minutes[name]:.1f} min"
                      f"{spent}) {'=' * 30}", flush=True)
                sys.stdout.write(log.read())
                log.close()
                del running[name]
    total = (time.perf_counter() - started) / 60
    cpu = children_cpu_seconds()
    if cpu is not None:
        print(f"\nall jobs: {cpu / 60:.1f} min CPU in {total:.1f} min wall on "
              f"{os.cpu_count()} cores", flush=True)
    summary = ", ".join(f"{name} exit {code} ({minutes[name]:.1f} min)"
                        for name, code in codes.items())
    print(f"\nwhole suite: {total:.1f} min wall ({summary})", flush=True)
    # pytest's exit code 5 (no tests collected) is a failure here too: a job must test something.
    return max(codes.values())


def main(argv: list[str]) -> int:
    serial = "--serial" in argv
    extra = [arg for arg in argv if arg not in ("--serial", "--floors-only")]
    if "--floors-only" in argv:
        command, env = floors_job(sys.executable, extra)
        return subprocess.call(command, cwd=ROOT, env=env)
    floors = None
    if "--floors" in extra:
        at = extra.index("--floors")
        floors = extra[at + 1]
        del extra[at : at + 2]
    if serial or (os.cpu_count() or 1) < 2:
        return run_serial(extra, floors)
    return run_queue(extra, floors)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
