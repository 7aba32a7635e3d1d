"""Numba's internals (``numba.core``) are used in two modules only.

``codegen.lowlevel`` builds intrinsics with them and ``codegen.numba_cache`` plugs the kernel
cache into Numba. Every other module uses Numba's public interface, so that a Numba upgrade
that moves an internal breaks one known place. The source is parsed; nothing is imported.
"""

from __future__ import annotations

import ast
from pathlib import Path

SOURCE = Path(__file__).resolve().parents[2] / "src" / "pendulum_lab"
ALLOWED = {"pendulum_lab.codegen.lowlevel", "pendulum_lab.codegen.numba_cache"}
INTERNAL = "numba.core"


def _is_internal(name: str) -> bool:
    return name == INTERNAL or name.startswith(INTERNAL + ".")


def _dotted(node: ast.AST) -> str | None:
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if isinstance(node, ast.Name):
        return ".".join([node.id, *reversed(parts)])
    return None


def internal_uses(source: str) -> list[int]:
    """Lines of ``source`` that import ``numba.core`` or reach it as ``numba.core...``."""
    lines = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found = any(_is_internal(alias.name) for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            found = node.level == 0 and _is_internal(node.module or "")
            found = found or (node.module == "numba"
                              and any(alias.name == "core" for alias in node.names))
        elif isinstance(node, ast.Attribute):
            found = _dotted(node) == INTERNAL
        else:
            found = False
        if found:
            lines.append(node.lineno)
    return lines


def modules_using_internals() -> dict[str, list[int]]:
    found = {}
    for path in sorted(SOURCE.rglob("*.py")):
        module = ".".join(("pendulum_lab", *path.relative_to(SOURCE).with_suffix("").parts))
        lines = internal_uses(path.read_text(encoding="utf-8"))
        if lines:
            found[module] = lines
    return found


def test_only_the_named_modules_use_numba_internals():
    found = modules_using_internals()
    assert set(found) - ALLOWED == set(), {m: found[m] for m in set(found) - ALLOWED}
    assert "pendulum_lab.codegen.numba_cache" in found  # the scan sees the module that does


def test_the_scan_finds_each_way_of_reaching_the_internals():
    # negative controls: each form is found, the public interface is not
    assert internal_uses("from numba.core import caching\n") == [1]
    assert internal_uses("import numba.core.caching as c\n") == [1]
    assert internal_uses("from numba import core\n") == [1]
    assert internal_uses("import numba\nx = numba.core.caching.Cache\n") == [2]
    assert internal_uses("import numba\nfrom numba import njit, types\nnumba.njit\n") == []
