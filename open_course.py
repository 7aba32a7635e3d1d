"""Open the course from this folder, on Windows, macOS or Linux: ``python open_course.py``.

The one command a student needs, the same in PowerShell, cmd and a POSIX shell (only the name of
the interpreter differs: ``py`` or ``python`` on Windows, ``python3`` on macOS and Linux). It
uses nothing but the standard library, so it runs before anything is installed:

1. the first time, it creates a virtual environment in ``.venv`` next to this file (the same
   one ``make lab`` uses), so nothing is installed into the system's Python, which Debian,
   Ubuntu and Homebrew refuse anyway (PEP 668);
2. it installs the package with JupyterLab into it (``pip install -e ".[lab]"``), again only
   when ``pyproject.toml`` changed since (the stamp ``.venv/.installed-lab``, as ``make lab``);
3. it runs ``python -m pendulum_lab`` in that environment, with this command's arguments:
   ``python open_course.py --help``, ``python open_course.py --no-browser``.

Activating the environment is never needed: each OS puts the environment's interpreter in its
own folder (``.venv\\Scripts`` on Windows, ``.venv/bin`` elsewhere), and this script knows
both. PowerShell's execution policy, which often blocks ``Activate.ps1`` on school laptops, does
not apply to it either.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

OLDEST_PYTHON = (3, 11)
ROOT = Path(__file__).resolve().parent
VENV = ROOT / ".venv"
STAMP = VENV / ".installed-lab"


def venv_python(venv: Path | None = None, windows: bool | None = None) -> Path:
    """The interpreter of the virtual environment ``venv`` (default ``.venv``) on this OS.

    ``windows`` (default: whether this is Windows) chooses the layout, so that the tests see
    both: ``Scripts\\python.exe`` on Windows, ``bin/python`` on macOS and Linux.
    """
    venv = VENV if venv is None else venv
    windows = os.name == "nt" if windows is None else windows
    return venv / "Scripts" / "python.exe" if windows else venv / "bin" / "python"


def needs_install(stamp: Path | None = None, pyproject: Path | None = None) -> bool:
    """True unless the package was installed after ``pyproject.toml`` last changed."""
    stamp = STAMP if stamp is None else stamp
    pyproject = ROOT / "pyproject.toml" if pyproject is None else pyproject
    return not stamp.exists() or stamp.stat().st_mtime < pyproject.stat().st_mtime


def run(command: list[str], what: str) -> None:
    """Run ``command``; on failure, say what failed and stop."""
    print(f"open_course: {what}: {' '.join(command)}", flush=True)
    if subprocess.call(command, cwd=ROOT) != 0:
        raise SystemExit(f"open_course: {what} failed (the messages above say why). Delete the "
                         f"folder {VENV} and run this command again to start afresh.")


def prepare(python: Path) -> None:
    """Create the environment and install the package, each only when needed."""
    if not python.exists():
        print(f"open_course: creating the virtual environment {VENV} (once)", flush=True)
        run([sys.executable, "-m", "venv", str(VENV)], "creating the virtual environment")
        # A new environment's pip is the one bundled with this Python, possibly years old.
        run([str(python), "-m", "pip", "install", "--upgrade", "pip"], "updating pip")
    if needs_install():
        print("open_course: installing pendulum_lab and JupyterLab (a few minutes the first "
              "time; pip shows its progress)", flush=True)
        run([str(python), "-m", "pip", "install", "-e", ".[lab]"], "installing")
        STAMP.touch()


def main(argv: list[str]) -> int:
    if sys.version_info < OLDEST_PYTHON:
        print(f"open_course: the course needs Python {'.'.join(map(str, OLDEST_PYTHON))} or "
              f"newer; this is {sys.version.split()[0]} ({sys.executable}). Install a newer "
              "Python from python.org and run this command with it.", file=sys.stderr)
        return 1
    python = venv_python()
    prepare(python)
    command = [str(python), "-m", "pendulum_lab", *argv]
    sys.stdout.flush()
    if os.name == "posix":  # become the launcher: Ctrl-C and signals reach JupyterLab directly
        os.execv(command[0], command)
    try:
        return subprocess.call(command)
    except KeyboardInterrupt:
        return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
