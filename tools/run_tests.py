"""Run the whole test suite (``make test``) as two pytest processes, one per core.

The suite's time goes mostly to running notebooks: nbval runs them, the browser tests run them in
JupyterLab, the website build and the Binder environment run them again. Each of these is one
process waiting on a kernel, so on a machine with two cores one pytest leaves a core idle. This
script splits the suite into two shards of about the same length, runs them side by side, prints
each shard's output when it ends and fails if either fails:

* ``browser``: the browser tests, the website, the Binder environment and the installs from a
  fresh clone, the sdist and the wheel (tests that start their own servers and environments,
  kept together so they never compete for a port or a folder);
* ``core``: everything else: doctests, unit, property and symbolic tests, and the graded
  assignments. The notebooks run under nbval in the Binder test, in Binder's environment.

``--floors PYTHON`` adds a third job: the unit suite (what ``make check`` runs) under another
interpreter, the one of the environment with the oldest supported versions pinned
(``make test-floors``). It starts when the first shard ends, on the core that shard leaves, with
its own kernel caches (compiled code differs between library versions).

With one core (or ``--serial``) it runs a single pytest over everything, then the floors;
``--floors-only`` runs the floors job alone, under the interpreter running this script. Any
other arguments go to pytest unchanged (``python tools/run_tests.py -x -k order``).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BROWSER_SHARD = ["tests/browser", "tests/site", "tests/binder", "tests/install"]
# The notebooks' nbval run is the Binder test's (tests/binder): it runs them in the environment
# Binder builds, so they are not run a fourth time here.
CORE_SHARD = ["src", "tests"] + [f"--ignore={path}" for path in BROWSER_SHARD]
#: What ``make check`` runs: the unit suite, without notebooks, browser, website or Binder.
UNIT_SUITE = ["src", "tests"] + [f"--ignore={path}" for path in [*BROWSER_SHARD,
                                                                  "tests/assignments"]]


def floors_job(python: str, extra: list[str]) -> tuple[list[str], dict]:
    """The command and environment of the unit suite in the floor environment."""
    caches = ROOT / ".venv-floors-caches"
    env = {**os.environ, "PENDULUM_LAB_CACHE": str(caches / "kernels"),
           "NUMBA_CACHE_DIR": str(caches / "numba")}
    # The benchmark items' smoke runs check the benchmark harness, which the main environment
    # tests; at the floors they would repeat the library's runs that the unit tests make.
    command = [python, "-m", "pytest", "-o", "cache_dir=.pytest_cache/floors", *UNIT_SUITE,
               "--ignore=tests/benchmarks", *extra]
    return command, env


def run_serial(extra: list[str], floors: str | None) -> int:
    code = subprocess.call([sys.executable, "-m", "pytest", *extra], cwd=ROOT)
    if floors is not None:
        command, env = floors_job(floors, extra)
        code = max(code, subprocess.call(command, cwd=ROOT, env=env))
    return code


def run_sharded(extra: list[str], floors: str | None) -> int:
    jobs = {"core": ([sys.executable, "-m", "pytest", "-o", "cache_dir=.pytest_cache/core",
                      *CORE_SHARD, *extra], None),
            "browser": ([sys.executable, "-m", "pytest", "-o", "cache_dir=.pytest_cache/browser",
                         *BROWSER_SHARD, *extra], None)}
    waiting = {"floors": floors_job(floors, extra)} if floors is not None else {}
    started = time.perf_counter()
    with tempfile.TemporaryDirectory() as logs:
        running, codes, minutes = {}, {}, {}

        def start(name, command, env):
            log = open(Path(logs) / f"{name}.log", "w+", encoding="utf-8")  # noqa: SIM115 (closed below)
            running[name] = (subprocess.Popen(command, cwd=ROOT, stdout=log, env=env,
                                              stderr=subprocess.STDOUT), log,
                             time.perf_counter())
            print(f"{name}: {' '.join(command[1:])}", flush=True)

        for name, (command, env) in jobs.items():
            start(name, command, env)
        while running:
            time.sleep(1.0)
            for name, (process, log, since) in list(running.items()):
                if process.poll() is None:
                    continue
                codes[name] = process.returncode
                minutes[name] = (time.perf_counter() - since) / 60
                log.seek(0)
                print(f"\n{'=' * 30} {name} (exit {codes[name]}, {minutes[name]:.1f} min) "
                      f"{'=' * 30}", flush=True)
                sys.stdout.write(log.read())
                log.close()
                del running[name]
                if waiting:  # the core this job leaves goes to the floors
                    waiting_name, (command, env) = waiting.popitem()
                    start(waiting_name, command, env)
    total = (time.perf_counter() - started) / 60
    summary = ", ".join(f"{name} exit {code} ({minutes[name]:.1f} min)"
                        for name, code in codes.items())
    print(f"\nwhole suite: {total:.1f} min wall ({summary})", flush=True)
    # pytest's exit code 5 (no tests collected) is a failure here too: a shard must test something.
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
    return run_sharded(extra, floors)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
