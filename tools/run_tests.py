"""Run the whole test suite (``make test``) as two pytest processes, one per core.

The suite's time goes mostly to running notebooks: nbval runs them, the browser tests run them in
JupyterLab, the website build and the Binder environment run them again. Each of these is one
process waiting on a kernel, so on a machine with two cores one pytest leaves a core idle. This
script splits the suite into two shards of about the same length, runs them side by side, prints
each shard's output when it ends and fails if either fails:

* ``browser``: the browser tests, the website and the Binder environment (tests that start their
  own servers and environments, kept together so they never compete for a port or a folder);
* ``core``: everything else: doctests, unit, property and symbolic tests, and the notebooks.

With one core (or ``--serial``) it runs a single pytest over everything. Any other arguments go
to pytest unchanged (``python tools/run_tests.py -x -k order``).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BROWSER_SHARD = ["tests/browser", "tests/site", "tests/binder"]
CORE_SHARD = ["src", "tests", "notebooks"] + [f"--ignore={path}" for path in BROWSER_SHARD]


def run_serial(extra: list[str]) -> int:
    return subprocess.call([sys.executable, "-m", "pytest", *extra], cwd=ROOT)


def run_sharded(extra: list[str]) -> int:
    shards = {"core": CORE_SHARD, "browser": BROWSER_SHARD}
    started = time.perf_counter()
    with tempfile.TemporaryDirectory() as logs:
        running = {}
        for name, paths in shards.items():
            log = open(Path(logs) / f"{name}.log", "w+")  # noqa: SIM115 (closed below)
            # Separate pytest cache folders: the two shards must not write the same files.
            command = [sys.executable, "-m", "pytest", "-o", f"cache_dir=.pytest_cache/{name}",
                       *paths, *extra]
            running[name] = (subprocess.Popen(command, cwd=ROOT, stdout=log,
                                              stderr=subprocess.STDOUT), log)
            print(f"shard {name}: {' '.join(paths)}", flush=True)
        codes = {}
        for name, (process, log) in running.items():
            codes[name] = process.wait()
            log.seek(0)
            print(f"\n{'=' * 30} shard {name} (exit {codes[name]}) {'=' * 30}", flush=True)
            sys.stdout.write(log.read())
            log.close()
    minutes = (time.perf_counter() - started) / 60
    summary = ", ".join(f"{name} exit {code}" for name, code in codes.items())
    print(f"\nwhole suite: {minutes:.1f} min wall ({summary})", flush=True)
    # pytest's exit code 5 (no tests collected) is a failure here too: a shard must test something.
    return max(codes.values())


def main(argv: list[str]) -> int:
    serial = "--serial" in argv
    extra = [arg for arg in argv if arg != "--serial"]
    if serial or (os.cpu_count() or 1) < 2:
        return run_serial(extra)
    return run_sharded(extra)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
