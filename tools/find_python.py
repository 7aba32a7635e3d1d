"""Print the newest (or oldest) supported Python found on this machine (the Makefile's PYTHON).

The supported versions are the ``Programming Language :: Python :: 3.X`` classifiers of
``pyproject.toml`` (one place for them). ``make test`` builds the main environment with the
newest of them found and the floor environment with the oldest, the two ends of the support
window (SPEC 0): ``python3 tools/find_python.py newest`` / ``oldest``.

An interpreter counts as found when it runs and reports the version its name promises:
``python3.X`` on ``PATH`` (pyenv's shims answer to every name but fail for versions that are
installed and not selected, so running them is the only test), then pyenv's installed versions
(``pyenv prefix``). Nothing found: nothing printed, exit status 1 (the Makefile then falls back
to ``python3``).
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CLASSIFIER = re.compile(r"^Programming Language :: Python :: 3\.(\d+)$")
_PROBE = "import sys; print('%d.%d' % sys.version_info[:2], sys.executable)"


def supported_versions(pyproject: Path = ROOT / "pyproject.toml") -> list[tuple[int, int]]:
    """The ``(3, X)`` of every Python version classifier, oldest first."""
    classifiers = tomllib.loads(pyproject.read_text(encoding="utf-8"))["project"]["classifiers"]
    minors = sorted(int(match.group(1)) for text in classifiers
                    if (match := CLASSIFIER.match(text)))
    if not minors:
        raise SystemExit(f"{pyproject}: no 'Programming Language :: Python :: 3.X' classifier")
    return [(3, minor) for minor in minors]


def probe(command: list[str], version: tuple[int, int]) -> str | None:
    """The absolute path of the interpreter ``command`` if it runs as Python ``version``."""
    try:
        done = subprocess.run([*command, "-c", _PROBE], capture_output=True, text=True,
                              encoding="utf-8", timeout=60, check=False)
    except OSError:
        return None
    reported, _, executable = done.stdout.strip().partition(" ")
    if done.returncode != 0 or reported != "{}.{}".format(*version):
        return None
    return executable


def pyenv_interpreter(version: tuple[int, int]) -> str | None:
    """The newest pyenv-installed CPython of ``version`` (``X.Y.Z``, no pre-releases)."""
    pyenv = shutil.which("pyenv")
    if pyenv is None:
        return None
    listed = subprocess.run([pyenv, "versions", "--bare"], capture_output=True, text=True,
                            encoding="utf-8", timeout=60, check=False).stdout.split()
    pattern = re.compile(rf"^{version[0]}\.{version[1]}\.(\d+)$")
    patches = sorted((int(m.group(1)), name) for name in listed if (m := pattern.match(name)))
    for _, name in reversed(patches):
        prefix = subprocess.run([pyenv, "prefix", name], capture_output=True, text=True,
                                encoding="utf-8", timeout=60, check=False).stdout.strip()
        found = prefix and probe([str(Path(prefix) / "bin" / "python3")], version)
        if found:
            return found
    return None


def find(version: tuple[int, int]) -> str | None:
    """An interpreter of ``version``: ``python3.X`` on PATH first, then pyenv's."""
    on_path = shutil.which("python{}.{}".format(*version))
    return (on_path and probe([on_path], version)) or pyenv_interpreter(version)


def main(argv: list[str]) -> int:
    if argv not in (["newest"], ["oldest"]):
        print("usage: find_python.py newest|oldest", file=sys.stderr)
        return 2
    versions = supported_versions()
    for version in (reversed(versions) if argv == ["newest"] else versions):
        found = find(version)
        if found:
            print(found)
            return 0
    return 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
