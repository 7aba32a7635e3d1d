"""Print the package's lowest supported versions as pins, one per line (``make test-floors``).

The floors are the lower bounds of ``[project].dependencies`` in ``pyproject.toml`` (one place
for them, each with the reason it cannot go lower); this turns every ``name>=X`` into
``name==X``, a constraints file for ``pip install -c``. Nothing else is pinned: the test tools
come at their newest, as a student's environment would have them.
"""

from __future__ import annotations

import re
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
FLOOR = re.compile(r"^\s*([A-Za-z0-9_.\-]+)(\[[^\]]*\])?\s*>=\s*([0-9][0-9A-Za-z.]*)")


def floor_pins(pyproject: Path = ROOT / "pyproject.toml") -> list[str]:
    """``name==version`` for each runtime dependency with a lower bound."""
    dependencies = tomllib.loads(pyproject.read_text(encoding="utf-8"))["project"]["dependencies"]
    pins = []
    for requirement in dependencies:
        match = FLOOR.match(requirement)
        if match is None:
            raise SystemExit(f"{pyproject}: {requirement!r} has no lower bound (name>=version)")
        pins.append(f"{match.group(1)}=={match.group(3)}")
    return pins


if __name__ == "__main__":
    sys.stdout.write("".join(f"{pin}\n" for pin in floor_pins()))
