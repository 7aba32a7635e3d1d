"""The package's architecture, read from its source: layers, import cycles, private names.

Every module of ``src/pendulum_lab`` is parsed (no import is executed) and every ``import``
statement in it is read, at module level or inside a function. The layers, lowest first:

    validation, exercises, plot_dispatch, version  (below every layer: import no package module)
    symbolic -> codegen -> model -> integrators -> driver -> analysis, chaos, geometric
    -> plotting, widgets, animation -> app -> the package's root (the public facade)

A module imports only from its own layer or lower ones; within a layer the imports between
packages form no cycle; no private name (``_x``) is imported from another module; and at most
eight modules sit loose at the top level. Each check is also run on a small made-up import
graph with the defect it looks for, so that it is seen to fail.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SOURCE = Path(__file__).resolve().parents[2] / "src" / "pendulum_lab"
PACKAGE = "pendulum_lab"
BASE = ("validation", "exercises", "plot_dispatch", "version")
LAYERS = [
    ("symbolic",),
    ("codegen",),
    ("model",),
    ("integrators",),
    ("driver",),
    ("analysis", "chaos", "geometric"),
    ("plotting", "widgets", "animation"),
    ("app",),
]
MAX_LOOSE_MODULES = 8


def module_name(path: Path) -> str:
    parts = (PACKAGE, *path.relative_to(SOURCE).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def modules() -> dict[str, Path]:
    return {module_name(path): path for path in sorted(SOURCE.rglob("*.py"))}


def imports(module: str, path: Path, known: set[str]) -> list[tuple[str, str, int]]:
    """(imported module, imported name or '', line) of every package import in a module."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(alias.name, "", node.lineno) for alias in node.names
                      if alias.name.split(".")[0] == PACKAGE]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                origin = ".".join(base + ([node.module] if node.module else []))
            else:
                origin = node.module or ""
            if origin.split(".")[0] != PACKAGE:
                continue
            for alias in node.names:
                submodule = f"{origin}.{alias.name}"
                if submodule in known:
                    found.append((submodule, "", node.lineno))
                else:
                    found.append((origin, alias.name, node.lineno))
    return found


def rank(module: str) -> float:
    """The layer of a module: -1 below all, 0 .. 7 the layers, 8 the package's root."""
    parts = module.split(".")
    if len(parts) == 1:
        return 8
    if parts[1] in BASE:
        return -1
    if parts[1] == "__main__":
        return 8
    for index, layer in enumerate(LAYERS):
        if parts[1] in layer:
            return index
    raise AssertionError(f"{module} belongs to no layer: add its folder to LAYERS")


def graph(found: dict[str, list[tuple[str, str, int]]]) -> dict[str, set[str]]:
    return {module: {target for target, _, _ in edges} for module, edges in found.items()}


def upward_imports(found) -> list[str]:
    return [f"{module} (layer {rank(module)}) imports {target} (layer {rank(target)}), "
            f"line {line}"
            for module, edges in found.items() for target, _, line in edges
            if rank(target) > rank(module)]


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan's algorithm)."""
    index, low, stack, on_stack, result = {}, {}, [], set(), []

    def visit(node):
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for other in edges.get(node, ()):
            if other not in index:
                visit(other)
                low[node] = min(low[node], low[other])
            elif other in on_stack:
                low[node] = min(low[node], index[other])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                result.append(sorted(component))

    for node in sorted(edges):
        if node not in index:
            visit(node)
    return result


def private_imports(found) -> list[str]:
    return [f"{module} imports the private name {name or target} from {target}, line {line}"
            for module, edges in found.items() for target, name, line in edges
            if (name.startswith("_") and name != "__version__")
            or any(part.startswith("_") and part != "__main__" for part in target.split("."))]


@pytest.fixture(scope="module")
def found():
    known = set(modules())
    return {module: imports(module, path, known) for module, path in modules().items()}


def test_every_module_belongs_to_a_layer(found):
    assert all(isinstance(rank(module), (int, float)) for module in found)


def test_no_module_imports_from_a_higher_layer(found):
    assert upward_imports(found) == []


def test_the_imports_have_no_cycle(found):
    assert cycles(graph(found)) == []


def test_no_private_name_is_imported_from_another_module(found):
    assert private_imports(found) == []


def test_few_modules_sit_loose_at_the_top():
    loose = sorted(path.name for path in SOURCE.glob("*.py"))
    assert len(loose) <= MAX_LOOSE_MODULES, loose


def test_only_the_plot_dispatch_names_a_module_to_import_by_string():
    """A result's ``plot`` reaches the plotting layer by name through ``plot_dispatch`` only."""
    by_string = []
    for module, path in modules().items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and getattr(node.func, "attr", None) == "import_module":
                by_string.append(module)
    allowed = {f"{PACKAGE}", f"{PACKAGE}.plot_dispatch", f"{PACKAGE}.codegen.cache"}
    assert set(by_string) <= allowed, sorted(set(by_string) - allowed)


# ------------------------------------------------------------------------ negative controls
def test_the_checks_find_what_they_look_for():
    lower, higher = f"{PACKAGE}.model.pendulum", f"{PACKAGE}.plotting.figures"
    made_up = {lower: [(higher, "figure", 3)], higher: [(lower, "PendulumModel", 1)]}
    assert upward_imports(made_up) and len(upward_imports(made_up)) == 1
    assert cycles(graph(made_up)) == [sorted([lower, higher])]
    assert private_imports({lower: [(f"{PACKAGE}.codegen.kernels", "_secret", 9)]})
    assert private_imports({lower: [(f"{PACKAGE}.codegen._hidden", "", 9)]})
    assert not private_imports({lower: [(f"{PACKAGE}.version", "__version__", 9)]})
    assert cycles({"a": {"b"}, "b": {"c"}, "c": set()}) == []
