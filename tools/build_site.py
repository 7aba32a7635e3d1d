"""Build the course website (``make docs``): Sphinx + MyST-NB into ``docs/_build/html``.

Every build reads all pages afresh (``-E``) with warnings as errors (``-W --keep-going``), so a
warning is reported on every build, not only on the build after the page changed; the notebooks'
execution cache (``docs/_build/.jupyter_cache``) is what keeps a rebuild fast: a notebook whose
code did not change, under an unchanged package, is not run again. While it runs, each notebook
says when it starts (``[3/20] notebooks/03_phase_portraits: executing ...``) and how it ended.

Usage::

    .venv/bin/python tools/build_site.py                  # the site, into docs/_build/html
    .venv/bin/python tools/build_site.py -D course_repository_url=https://github.com/OWNER/REPO

The site tests import :func:`build` and build throwaway sites with the same configuration.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import nbformat
from jupyter_cache import get_cache
from jupyter_cache.base import CacheBundleIn
from jupyter_cache.cache.db import create_db

REPO_ROOT = Path(__file__).resolve().parents[1]
DOCS = REPO_ROOT / "docs"
OUTPUT = DOCS / "_build" / "html"
MATHJAX = DOCS / "_vendor" / "mathjax" / "tex-mml-chtml.js"
MATHJAX_HINT = "make mathjax (make docs and make test do it)"


@dataclass
class BuildResult:
    returncode: int
    seconds: float
    log: str
    output: Path

    @property
    def ok(self) -> bool:
        return self.returncode == 0

    def warnings(self) -> list[str]:
        return [line for line in self.log.splitlines() if "WARNING:" in line or "ERROR:" in line]


def missing_mathjax() -> str | None:
    """Why the site cannot be built here, or None."""
    if not MATHJAX.exists():
        return f"the local MathJax copy {MATHJAX.relative_to(REPO_ROOT)} is missing: {MATHJAX_HINT}"
    return None


#: nbclient's message for a kernel that did not answer its start-up call in time.
KERNEL_START_FAILURE = "Kernel didn't respond in"


def execution_cache(output: Path = OUTPUT) -> Path:
    """MyST-NB's execution cache of the build into ``output`` (``output/../.jupyter_cache``),
    created with its database if it is missing.

    With an empty cache both parallel readers of a build would create it; jupyter_cache checks,
    then creates, and the second reader failed with FileExistsError (seen in CI).
    """
    folder = output.parent / ".jupyter_cache"
    folder.mkdir(parents=True, exist_ok=True)
    create_db(folder).dispose()
    return folder


def seed_execution_cache(executed: dict[Path, tuple[dict, float]],
                         output: Path = OUTPUT) -> list[str]:
    """Store notebooks executed elsewhere under the current package in the execution cache
    of the build into ``output``, so that the build shows their outputs instead of running
    them again (the tests' JupyterLab run of the course feeds the tests' build this way).

    Parameters
    ----------
    executed : dict of Path -> (dict, float)
        Per notebook as the build reads it (``docs/notebooks/NAME.ipynb``): the executed
        notebook (nbformat JSON) and its run time in seconds.
    output : Path
        The build's HTML folder, as given to :func:`build`.

    Returns
    -------
    list of str
        The names of the notebooks stored. An execution is stored only when its code cells
        are the source's, in order, every one of them ran, and nothing went to standard error
        (a warning the build, which runs with warnings off, would not show). What is stored
        is the source notebook (its cells, metadata and kernel) with the execution's outputs,
        counts, language and widget state, so that the cache finds it under the key the build
        computes.
    """
    sys.path.insert(0, str(DOCS / "_ext"))
    try:
        import course_site
    finally:
        sys.path.remove(str(DOCS / "_ext"))
    folder = execution_cache(output)
    # The executions ran under the package as it is now: a cache of an older package goes.
    course_site.empty_cache_if_package_changed(output.parent, folder)
    cache = get_cache(folder)
    stored = []
    for path, (notebook, seconds) in sorted(executed.items()):
        source = nbformat.read(path, as_version=4)
        ran = nbformat.from_dict(notebook)
        mine = [cell for cell in source.cells if cell.cell_type == "code"]
        theirs = [cell for cell in ran.cells if cell.cell_type == "code"]
        if ([cell.source for cell in mine] != [cell.source for cell in theirs]
                or any(cell.execution_count is None for cell in theirs if cell.source.strip())
                or any(out.get("name") == "stderr" for cell in theirs for out in cell.outputs)):
            continue
        for cell, result in zip(mine, theirs, strict=True):
            cell.outputs, cell.execution_count = result.outputs, result.execution_count
        # What an execution records beside the outputs: the kernel's language (the pages'
        # code highlighting) and the widgets' state (which views are progress bars).
        for key in ("language_info", "widgets"):
            if key in ran.metadata:
                source.metadata[key] = ran.metadata[key]
        cache.cache_notebook_bundle(
            CacheBundleIn(source, str(path), data={"execution_seconds": seconds}),
            check_validity=False, overwrite=True)
        stored.append(path.stem)
    return stored


def build(
    source: Path = DOCS,
    output: Path = OUTPUT,
    overrides: dict[str, str] | None = None,
    jobs: int = 2,
    warnings_are_errors: bool = True,
    echo: bool = False,
) -> BuildResult:
    """Build the HTML site of ``source`` with the course configuration (``docs/conf.py``).

    Parameters
    ----------
    source : Path
        Folder of the pages (``docs/`` for the course; a throwaway folder in the tests).
    output : Path
        Where the HTML goes; the execution cache goes next to it (``output/../.jupyter_cache``).
    overrides : dict of str -> str, optional
        Configuration values for this build (``sphinx-build -D name=value``).
    jobs : int
        Parallel processes for reading (notebooks run in parallel, one kernel each).
    warnings_are_errors : bool
        ``-W --keep-going`` (the default, as ``make docs``); False only for the tests'
        negative controls, which need the pages of a site that has problems.
    echo : bool
        Print the build's messages as they come (``make docs``): each notebook says when it
        starts and how it ended, with a count (``docs/_ext/course_site.py``).

    Returns
    -------
    BuildResult
        Exit code, wall time in seconds, the combined log and the output folder.
    """
    reason = missing_mathjax()
    if reason:
        raise FileNotFoundError(reason)
    execution_cache(output)
    command = [
        sys.executable, "-m", "sphinx",
        "-b", "html", "-E", "-q", "-j", str(jobs),
        *(["-W", "--keep-going"] if warnings_are_errors else []),
        "-c", str(DOCS),
        str(source), str(output),
    ]  # fmt: skip
    for name, value in (overrides or {}).items():
        command += ["-D", f"{name}={value}"]
    # The kernels' "running over TCP without encryption" notice is noise in a local build; the
    # notes of first-use compilations describe the build machine, not the course.
    env = {**os.environ, "PYTHONWARNINGS": "ignore", "PENDULUM_LAB_COMPILE_NOTES": "off"}
    start = time.perf_counter()
    lines = []
    for attempt in (1, 2):
        with subprocess.Popen(command, cwd=REPO_ROOT, env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True, encoding="utf-8",
                              errors="replace", bufsize=1) as process:
            for line in process.stdout:
                lines.append(line)
                if echo and "IPKernelApp" not in line:
                    print(line, end="", flush=True)
        # A kernel that does not answer nbclient's start-up call within its fixed 60 s (MyST-NB
        # offers no setting for it) means a loaded machine, not a broken notebook: build once
        # more; the notebooks that ran are in the execution cache, so only the failed ones run.
        if process.returncode == 0 or KERNEL_START_FAILURE not in "".join(lines) or attempt == 2:
            break
        lines.append(f"{KERNEL_START_FAILURE}: building once more\n")
    seconds = time.perf_counter() - start
    return BuildResult(process.returncode, seconds, "".join(lines), output)


def report(result: BuildResult) -> dict:
    """Wall time, exit code, and which notebooks this build ran or took from the cache."""
    execution = result.output.parent / "execution.json"
    notebooks = json.loads(execution.read_text(encoding="utf-8")) if execution.exists() else {}
    ran = sorted(name for name, row in notebooks.items() if row["ran_in_this_build"])
    return {
        "seconds": round(result.seconds, 1),
        "returncode": result.returncode,
        "notebooks": len(notebooks),
        "notebooks_run": ran,
        "notebook_seconds_run": round(sum(notebooks[n]["seconds"] or 0 for n in ran), 1),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "-D",
        dest="overrides",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="override a configuration value for this build",
    )
    parser.add_argument("-j", dest="jobs", type=int, default=2, help="parallel readers (2)")
    args = parser.parse_args(argv)
    overrides = dict(item.split("=", 1) for item in args.overrides)
    try:
        result = build(overrides=overrides, jobs=args.jobs, echo=True)
    except FileNotFoundError as err:
        print(f"build_site: {err}", file=sys.stderr)
        return 2
    facts = report(result)
    (OUTPUT.parent / "build.json").write_text(json.dumps(facts, indent=1) + "\n",
                                              encoding="utf-8")
    verdict = "built" if result.ok else "FAILED (warnings are errors)"
    print(
        f"site {verdict} in {result.seconds:.1f} s ({len(facts['notebooks_run'])} of "
        f"{facts['notebooks']} notebooks run, the others from the cache): "
        f"{result.output.relative_to(REPO_ROOT)}"
    )
    return result.returncode


if __name__ == "__main__":
    sys.exit(main())
