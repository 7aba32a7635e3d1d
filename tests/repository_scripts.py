"""The repository's scripts (``open_course.py``, ``tools/``) as modules for the tests: neither
the root nor ``tools/`` is a package, so a script is loaded from its path."""

from __future__ import annotations

import importlib.util
import sys
import types
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]


def load_script(relative_path: str, name: str | None = None) -> types.ModuleType:
    """The script at ``relative_path`` (from the repository's root) as a module named ``name``
    (the file's stem by default), registered in ``sys.modules``: dataclasses look their module
    up there."""
    path = REPO_ROOT / relative_path
    spec = importlib.util.spec_from_file_location(name or path.stem, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module
