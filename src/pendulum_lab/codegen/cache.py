"""Generated code, written into a cache folder and imported under a name that says what it is.

Numba keeps compiled machine code on disk (``cache=True``) but checks only the file a function
is defined in: a change in a function that the file imports would leave stale machine code. So
every generated module is named after a key of everything its code depends on, found by
reading the code, not listed by hand (:func:`code_key`):

* the generated source itself;
* every module of the package that it imports, and every package module those import in turn,
  each as its syntax tree without docstrings (comments are not part of the tree), so that
  editing a docstring or a comment changes no key while editing a line of code does;
* the module that generated the source, and the modules of any objects injected into it;
* the versions of Python, NumPy, Numba and llvmlite.

A module of the package that a key needs but cannot find is an error, never a stale load.

Loading is safe from several threads and from several processes sharing a cache folder:

* **threads:** a generated module is executed (and its kernels compiled) by one thread while
  others that need it wait, and only a complete module is ever handed out. The keys are
  computed under the same lock: CPython 3.11 keeps one recursion counter for building syntax
  trees per interpreter, and two threads parsing at once can fail with "SystemError: AST
  constructor recursion depth mismatch" (python/cpython#106905), which a Dask worker with two
  threads met on first use;
* **processes:** Numba writes each cache file to a temporary name and renames it into place, so
  no process reads a half-written file, but it picks the file number of a new compiled version
  from the index it read before compiling: two processes compiling one function at once can give
  two versions one number, so that the index and the data disagree (numba/numba#10128). So a
  generated module is written, executed and first called (where Numba compiles it or loads it
  from disk) under an exclusive lock on a file beside it (``<module>.lock``, :func:`file_lock`):
  the first process compiles and saves, the second waits and loads. Where the system has no
  ``fcntl`` (Windows) only the threads of one process are kept apart.
"""

from __future__ import annotations

import ast
import contextlib
import functools
import hashlib
import importlib.metadata
import importlib.util
import inspect
import os
import platform
import sys
import tempfile
import threading
from pathlib import Path

import numba
import numpy as np

from .compile_status import compiling

__all__ = [
    "MODULE_PREFIX",
    "PACKAGE",
    "cache_dir",
    "code_key",
    "file_lock",
    "imported_modules",
    "load_generated",
    "module_dependencies",
]

PACKAGE = "pendulum_lab"
_PACKAGE_ROOT = Path(__file__).resolve().parents[1]
#: Generated modules are imported under this prefix (followed by their stem and key).
MODULE_PREFIX = "pendulum_lab_kernels_"
#: Held while a module is generated, keyed or loaded (and while syntax trees are built).
_LOADING = threading.RLock()


def cache_dir() -> Path:
    """Where generated kernels live: ``$PENDULUM_LAB_CACHE`` or the user cache folder."""
    root = os.environ.get("PENDULUM_LAB_CACHE")
    if root is None:
        base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
        root = Path(base) / "pendulum_lab"
    return Path(root) / "kernels"


def _module_path(module: str) -> Path | None:
    """The source file of a package module (``pendulum_lab.x.y``), or None if there is none."""
    parts = module.split(".")[1:]
    folder = _PACKAGE_ROOT.joinpath(*parts)
    for candidate in (folder / "__init__.py", folder.with_suffix(".py")):
        if candidate.is_file():
            return candidate
    return None


def _without_docstrings(tree: ast.AST) -> ast.AST:
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) \
                    and isinstance(body[0].value.value, str):
                node.body = body[1:] or [ast.Pass()]
    return tree


def imported_modules(tree: ast.AST, module: str, is_package: bool) -> set[str]:
    """The package modules a syntax tree imports (``import``, ``from ... import``, anywhere)."""
    found = set()
    base = module.split(".") if is_package else module.split(".")[:-1]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            required, optional = [alias.name for alias in node.names], []
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                origin = ".".join(base[: len(base) - node.level + 1] + ([node.module]
                                                                        if node.module else []))
            else:
                origin = node.module or ""
            # ``from package import name``: the name may be a submodule, imported too
            required, optional = [origin], [f"{origin}.{alias.name}" for alias in node.names]
        else:
            continue
        for name in required + optional:
            if name != PACKAGE and not name.startswith(PACKAGE + "."):
                continue
            if name == PACKAGE or _module_path(name) is not None:
                found.add(name)
            elif name in required:
                raise ImportError(f"{module} imports {name}, which is not a module of the "
                                  f"package at {_PACKAGE_ROOT}: regenerate it from the current "
                                  "code")
    return found


@functools.cache
def _parsed(module: str) -> tuple[str, frozenset[str]]:
    """(normalised syntax tree, imported package modules) of one package module."""
    path = _module_path(module)
    if path is None:
        raise ImportError(f"generated code depends on {module}, which is not a module of the "
                          f"package at {_PACKAGE_ROOT}: regenerate it from the current code")
    with _LOADING:  # building syntax trees from two threads at once can fail (see above)
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    imports = imported_modules(tree, module, path.name == "__init__.py")
    return ast.dump(_without_docstrings(tree)), frozenset(imports - {module})


def module_dependencies(modules) -> list[str]:
    """``modules`` (package module names) and every package module they import, transitively.

    The package's root ``__init__`` is left out unless named: it only gathers the public names.
    """
    seen, todo = set(), [m for m in modules if m != PACKAGE]
    while todo:
        module = todo.pop()
        if module in seen:
            continue
        seen.add(module)
        todo.extend(m for m in _parsed(module)[1] if m != PACKAGE and m not in seen)
    return sorted(seen)


def _versions() -> str:
    return (f"python {platform.python_version()} numpy {np.__version__} numba "
            f"{numba.__version__} llvmlite {importlib.metadata.version('llvmlite')}")


def _value_fingerprint(value) -> str:
    """A stable text for a value compiled into code as a constant (arrays, numbers, functions)."""
    if isinstance(value, np.ndarray):
        return f"array {value.dtype} {value.shape} {value.tobytes().hex()}"
    function = getattr(value, "py_func", value)
    if inspect.isfunction(function):
        return f"function {function.__module__}.{function.__qualname__}"
    return repr(value)


def _object_dependencies(value) -> tuple[list[str], list[str]]:
    """(package modules, constants) that an injected object's compiled code depends on."""
    function = getattr(value, "py_func", value)
    if not inspect.isfunction(function):
        return [], [_value_fingerprint(value)]
    modules = [function.__module__] if function.__module__.startswith(PACKAGE) else []
    constants = [function.__qualname__]
    for cell in function.__closure__ or ():
        inner_modules, inner_constants = _object_dependencies(cell.cell_contents)
        modules += inner_modules
        constants += inner_constants
    return modules, constants


def code_key(source: str, generator: str | None = None, inject: dict | None = None) -> str:
    """A key (16 hex digits) of generated ``source`` and of all the code it depends on.

    ``generator`` is the package module that wrote ``source``; ``inject`` the objects set as
    module globals before the source runs (their modules and constants count too).
    """
    with _LOADING:  # building syntax trees from two threads at once can fail (see above)
        tree = ast.parse(source)
    modules = set(imported_modules(tree, "generated", False))
    constants = []
    if generator is not None and generator.startswith(PACKAGE):
        modules.add(generator)
    for name, value in sorted((inject or {}).items()):
        inner_modules, inner_constants = _object_dependencies(value)
        modules.update(inner_modules)
        constants.append(f"{name}: {' '.join(inner_constants)}")
    digest = hashlib.sha256()
    for part in [source, _versions(), *constants]:
        digest.update(part.encode())
    for module in module_dependencies(modules):
        digest.update(module.encode())
        digest.update(_parsed(module)[0].encode())
    return digest.hexdigest()[:16]


def _write_if_changed(path: Path, text: str) -> None:
    # Rewriting an unchanged file would change its timestamp and invalidate Numba's cache;
    # several processes may race here, so the file is replaced atomically.
    if path.exists() and path.read_text() == text:
        return
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
    with os.fdopen(fd, "w") as handle:
        handle.write(text)
    os.replace(tmp, path)


@contextlib.contextmanager
def file_lock(path: Path):
    """An exclusive lock on ``path`` (created if missing), shared by every process and thread.

    Each use opens the file anew, and ``flock`` locks belong to an open file, so two threads of
    one process exclude each other as two processes do. Without ``fcntl`` (Windows) it locks
    nothing; the caller's threads are then kept apart by :data:`_LOADING` alone.
    """
    try:
        import fcntl
    except ImportError:  # pragma: no cover (Windows)
        yield
        return
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def load_generated(stem: str, source: str, inject: dict | None = None,
                   what: str | None = None):
    """Write generated Python ``source`` into the kernel cache folder (if new) and import it.

    The file is ``<stem>_<key>.py`` with the key of :func:`code_key` (the calling module counts
    as the generator), and the module is registered in ``sys.modules`` as
    ``pendulum_lab_kernels_<stem>_<key>``; a second call returns the same module (its kernels
    stay the objects that other generated code imports by name). ``inject`` sets module globals
    before the source runs (objects that cannot be imported by name). Returns
    ``(module, path)``.

    Running the module compiles its kernels (their Numba signatures are given) or loads them
    from Numba's disk cache; that is announced as a compilation of ``what`` (for people:
    "glrk4 for the double pendulum"; by default the stem), expected to load when the file
    was already there (:func:`~pendulum_lab.codegen.compile_status.compiling`).

    The file is written and executed under :func:`file_lock` of ``<stem>_<key>.lock``, so that
    one process compiles and saves while another waits, then loads.
    """
    caller = inspect.currentframe().f_back
    generator = caller.f_globals.get("__name__") if caller is not None else None
    with _LOADING:  # one thread builds a module; the others wait and get the finished one
        key = code_key(source, generator, inject)
        path = cache_dir() / f"{stem}_{key}.py"
        name = f"{MODULE_PREFIX}{stem}_{key}"
        if name in sys.modules:
            return sys.modules[name], path
        with file_lock(path.with_suffix(".lock")):  # and one process
            seen_before = path.exists()
            _write_if_changed(path, source)
            spec = importlib.util.spec_from_file_location(name, path)
            module = importlib.util.module_from_spec(spec)
            module.__dict__.update(inject or {})
            # Registered before it runs, as the import system does: Numba's cache finds a
            # function's file through its module. Removed again if it fails.
            sys.modules[name] = module
            try:
                with compiling(what or f"the generated module {stem}", loading=seen_before):
                    spec.loader.exec_module(module)
            except BaseException:
                del sys.modules[name]
                raise
    return module, path
