"""Generated code and compiled kernels on disk: keys, layers, locks and damaged files.

**Keys.** Numba keeps compiled machine code on disk but checks only the file a function is
defined in: a change in a function that the file imports would leave stale machine code. So
every generated module is named after a key of everything its code depends on, found by
reading the code, not listed by hand (:func:`code_key`):

* the generated source itself;
* every module of the package that it imports, and every package module those import in turn,
  each as its syntax tree without docstrings (comments are not part of the tree), so that
  editing a docstring or a comment changes no key while editing a line of code does;
* the module that generated the source, and the modules of any objects injected into it;
* the versions of Python, NumPy, Numba and llvmlite.

A module of the package that a key needs but cannot find is an error, never a stale load.
The package's own cached kernels (:func:`cached_njit` in a package module) are keyed the same
way, on their module's code.

**Layers.** Kernels are looked up in read-only layers first (``$PENDULUM_LAB_SHARED_CACHE``:
folders separated by ``os.pathsep``, filled once by ``pendulum-lab warmup --cache DIR``, for
example in a classroom image), then in the user's own cache (``$PENDULUM_LAB_CACHE``, by
default the user cache folder), which takes whatever is missing. Every layer holds the
generated modules in ``<layer>/kernels`` and Numba's index and data files (``.nbi``,
``.nbc``) in ``<layer>/kernels/__pycache__``, for generated and package kernels alike
(``NUMBA_CACHE_DIR`` is not consulted for them). Nothing is ever written into a read-only
layer, not even a lock file. A user cache that cannot be written (read-only, no permission,
a missing home) never stops a run: it is read if it exists, and whatever is missing is
compiled in memory for the session, with one :class:`KernelCacheWarning` that names the
folder and the variable to set.

Numba's own cache cannot do this: each of its locators accepts a folder only if it can write
a file there (``_CacheLocator.ensure_cache_path``), so a read-only folder is never read, and
with no writable folder ``cache=True`` raises "no locator available". Hence
:func:`cached_njit`, which gives a Numba dispatcher a :class:`KernelCache` of the layers, and
is the one way the package caches a kernel.

**Damaged files.** An index or data file that cannot be read back (truncated, garbage, from
another Numba version or for another source) and a generated module whose text is not what
its name promises are reported (:class:`KernelCacheWarning` naming the file), set aside as
``<name>.damaged`` in the user's cache (skipped in a read-only layer) and built again.

**Threads and processes** sharing a cache folder:

* **threads:** a generated module is executed (and its kernels compiled) by one thread while
  others that need it wait, and only a complete module is ever handed out. Syntax trees are
  built under a lock of their own: CPython 3.11 keeps one recursion counter for building
  syntax trees per interpreter, and two threads parsing at once can fail with "SystemError:
  AST constructor recursion depth mismatch" (python/cpython#106905), which a Dask worker with
  two threads met on first use;
* **processes:** Numba writes each cache file to a temporary name and renames it into place,
  so no process reads a half-written file, but the number of a new data file is picked from
  the index: two processes saving one function at once can give two versions one number, so
  that the index and the data disagree (numba/numba#10128). So every save holds an exclusive
  lock on ``__pycache__/index.lock`` of the user's layer, and a generated module is written,
  executed and first called (where its kernels compile or load) under a lock on a file
  beside it (``<module>.lock``): the first process compiles and saves, the second waits and
  loads. :func:`file_lock` locks with ``fcntl.flock`` on Linux and macOS and with
  ``msvcrt.locking`` on Windows.
"""

from __future__ import annotations

import ast
import contextlib
import errno
import functools
import hashlib
import importlib.metadata
import importlib.util
import inspect
import linecache
import os
import platform
import sys
import threading
import time
import types
import uuid
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import compile_status, numba_cache
from .compile_status import compiling

__all__ = [
    "CACHE_VARIABLE",
    "MODULE_PREFIX",
    "PACKAGE",
    "SHARED_VARIABLE",
    "CacheLayers",
    "KernelCache",
    "KernelCacheWarning",
    "cache_dir",
    "cache_layers",
    "cached_njit",
    "code_key",
    "file_lock",
    "imported_modules",
    "load_generated",
    "module_dependencies",
    "text_key",
]

PACKAGE = "pendulum_lab"
_PACKAGE_ROOT = Path(__file__).resolve().parents[1]
#: Generated modules are imported under this prefix (followed by their stem and key).
MODULE_PREFIX = "pendulum_lab_kernels_"
#: The user's own, writable cache (its kernels are in the folder ``kernels`` inside it).
CACHE_VARIABLE = "PENDULUM_LAB_CACHE"
#: Read-only cache layers, searched before the user's (folders separated by ``os.pathsep``).
SHARED_VARIABLE = "PENDULUM_LAB_SHARED_CACHE"
#: Held while a module is generated, keyed or loaded.
_LOADING = threading.RLock()
#: Held while a syntax tree is built; nothing else is taken meanwhile (see above).
_PARSING = threading.Lock()


class KernelCacheWarning(UserWarning):
    """A kernel cache folder that cannot be written or read, or a damaged file in one."""


def cache_dir() -> Path | None:
    """Where the user's generated kernels live: ``$PENDULUM_LAB_CACHE/kernels``, by default
    ``kernels`` in the user cache folder (``$XDG_CACHE_HOME`` or ``~/.cache``, then
    ``pendulum_lab``); None when there is no home folder to put it in."""
    root = os.environ.get(CACHE_VARIABLE)
    if root is None:
        base = os.environ.get("XDG_CACHE_HOME")
        if not base:
            try:
                base = Path.home() / ".cache"
            except RuntimeError:  # no home folder (a service account, a bare container)
                return None
        root = Path(base) / "pendulum_lab"
    return Path(root) / "kernels"


def _shared_dirs() -> list[Path]:
    value = os.environ.get(SHARED_VARIABLE, "")
    return [Path(part) / "kernels" for part in value.split(os.pathsep) if part.strip()]


@dataclass(frozen=True)
class CacheLayers:
    """The kernel folders of this process: ``read`` in the order they are searched (the
    read-only layers, then the user's if it exists), ``write`` the user's if it can be
    written (None: whatever is missing is compiled in memory)."""

    read: tuple[Path, ...]
    write: Path | None


_warned: set[str] = set()


def _warn_once(text: str) -> None:
    """A :class:`KernelCacheWarning`, once per text and process, shown as one line (it is
    attributed to the package, not to a line of code that would be printed below it)."""
    if text not in _warned:
        _warned.add(text)
        warnings.warn_explicit(text, KernelCacheWarning, filename=PACKAGE, lineno=0)


@functools.lru_cache(maxsize=64)
def _unwritable_reason(folder: Path) -> str | None:
    """None if ``folder`` can be created and written, else why not.

    Checked once per folder and process by writing a file, as Numba's locators do:
    permission bits say nothing to root, nor on Windows.
    """
    try:
        folder.mkdir(parents=True, exist_ok=True)
        probe = folder / f".write-test-{os.getpid()}-{uuid.uuid4().hex[:8]}"
        with open(probe, "xb"):
            pass
        probe.unlink()
    except OSError as err:
        return err.strerror or type(err).__name__
    return None


def cache_layers() -> CacheLayers:
    """The kernel folders to search and the one to write (see the module docstring).

    Warns once per folder (:class:`KernelCacheWarning`) when the user's cache cannot be
    written, and when a shared layer is not a folder.
    """
    read = []
    for folder in _shared_dirs():
        if folder.is_dir():
            read.append(folder)
        else:
            _warn_once(f"the shared kernel cache {folder} (from {SHARED_VARIABLE}) "
                       "is not a folder; it is ignored")
    user = cache_dir()
    write = None
    if user is None:
        _warn_once("there is no home folder for the kernel cache; kernels are "
                   f"compiled in memory for this session. Set {CACHE_VARIABLE} to a writable "
                   "folder to keep them.")
    elif user not in read:  # (the user's cache named as a shared layer is read-only too)
        reason = _unwritable_reason(user)
        if reason is None:
            write = user
            read.append(user)
        else:
            if user.is_dir():
                read.append(user)  # read what it holds
            _warn_once(f"cannot write the kernel cache {user} ({reason}); kernels "
                       f"missing from it are compiled in memory for this session. Set "
                       f"{CACHE_VARIABLE} to a writable folder to keep them.")
    return CacheLayers(tuple(read), write)


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
    with _PARSING:  # building syntax trees from two threads at once can fail (see above)
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
            f"{numba_cache.NUMBA_VERSION} llvmlite {importlib.metadata.version('llvmlite')}")


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
    with _PARSING:  # building syntax trees from two threads at once can fail (see above)
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


def text_key(text: str, generator: str) -> str:
    """A key (16 hex digits) of generated code that is not Python (the browser's ES modules),
    by the rules of :func:`code_key`: the text itself, and the code of the package module
    ``generator`` that wrote it and of every package module that one imports. No compiler
    version counts: the text is all a browser runs. The modules count by their source text,
    not their syntax trees, whose dumps differ between Python versions (a file shipped with
    the package must have one key on every Python)."""
    digest = hashlib.sha256(text.encode())
    for module in module_dependencies([generator]):
        digest.update(module.encode())
        digest.update(_module_path(module).read_bytes().replace(b"\r\n", b"\n"))
    return digest.hexdigest()[:16]


def _module_key(module: str, source: str) -> str:
    """A key (16 hex digits) of a module's code, as :func:`code_key` is of generated code: the
    syntax trees of the module and of every package module it imports, and the versions.
    A module outside the package is keyed on its text and the package modules it imports."""
    if not (module == PACKAGE or module.startswith(PACKAGE + ".")) or _module_path(module) is None:
        return code_key(source)
    digest = hashlib.sha256(_versions().encode())
    for name in module_dependencies([module]):
        digest.update(name.encode())
        digest.update(_parsed(name)[0].encode())
    return digest.hexdigest()[:16]


def _write_atomically(path: Path, text: str) -> None:
    """Write ``path`` through a temporary name and rename it into place (several processes
    may race here). Opened as an ordinary file, so the umask gives it the permissions of the
    user's other files (readable by every user of an image, unlike a private temporary
    file)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(f"{path.name}.tmp.{uuid.uuid4().hex[:16]}")
    try:
        with open(temporary, "x", encoding="utf-8", newline="\n") as handle:
            handle.write(text)
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(OSError):
            temporary.unlink()
        raise


def _set_aside(path: Path, reason: str, writable: bool) -> None:
    """Report a damaged cache file; rename it ``<name>.damaged`` if its layer is writable."""
    if not writable:
        _warn_once(f"damaged kernel cache file {path} ({reason}) in a read-only "
                   "layer; skipped (rebuild that layer with `pendulum-lab warmup --cache`)")
        return
    aside = path.with_name(path.name + ".damaged")
    try:
        os.replace(path, aside)
    except FileNotFoundError:
        return  # another process set it aside first
    except OSError as err:
        _warn_once(f"damaged kernel cache file {path} ({reason}) could not be "
                   f"set aside ({err.strerror}); delete it")
        return
    _warn_once(f"damaged kernel cache file {path} ({reason}); set aside as "
               f"{aside.name}, building it again")


# ------------------------------------------------------------------------------ file locks
def _lock_functions():
    """``(lock, unlock)`` of an open file descriptor for this system, or None.

    ``fcntl.flock`` where it exists (Linux, macOS, the BSDs); ``msvcrt.locking`` of the first
    byte on Windows, retried without blocking (its blocking mode gives up after 10 s).
    Both locks belong to one opening of the file, so two threads of one process exclude each
    other as two processes do.
    """
    try:
        import fcntl
    except ImportError:
        pass
    else:
        return (lambda fd: fcntl.flock(fd, fcntl.LOCK_EX),
                lambda fd: fcntl.flock(fd, fcntl.LOCK_UN))
    try:
        import msvcrt
    except ImportError:
        return None

    def lock(fd):
        pause = 0.005
        while True:
            os.lseek(fd, 0, os.SEEK_SET)  # the locked byte is the one at the position
            try:
                msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
                return
            except OSError as err:
                if err.errno not in _HELD_ELSEWHERE:
                    raise
                time.sleep(pause)  # held by another opening of the file: try again shortly
                pause = min(2 * pause, 0.1)

    def unlock(fd):
        os.lseek(fd, 0, os.SEEK_SET)
        msvcrt.locking(fd, msvcrt.LK_UNLCK, 1)

    return lock, unlock


#: What ``msvcrt.locking`` raises while another opening of the file holds the lock.
_HELD_ELSEWHERE = {errno.EACCES, errno.EDEADLK, getattr(errno, "EDEADLOCK", errno.EDEADLK)}
_THREAD_LOCKS: dict[str, threading.Lock] = {}


@contextlib.contextmanager
def file_lock(path: Path):
    """An exclusive lock on ``path`` (created if missing), shared by every process and thread.

    Each use opens the file anew, so two threads of one process exclude each other as two
    processes do (see :func:`_lock_functions`). On a system with neither ``fcntl`` nor
    ``msvcrt`` only the threads of this process are kept apart. Only ever called on a
    writable layer.
    """
    functions = _lock_functions()
    if functions is None:
        with _THREAD_LOCKS.setdefault(str(path), threading.Lock()):
            yield
        return
    lock, unlock = functions
    path.parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
    try:
        lock(fd)
        try:
            yield
        finally:
            unlock(fd)
    finally:
        os.close(fd)


# ------------------------------------------------------------------------- Numba's files
class KernelCache(numba_cache.DispatcherCache):
    """The disk cache of one function, over the layers of :func:`cache_layers`.

    A compiled version is loaded from the first layer that holds it. It is saved into the
    user's writable layer only, and nowhere when there is none (it stays in memory). The files
    are Numba's own, in ``<layer>/kernels/__pycache__``, read and written through
    :mod:`~pendulum_lab.codegen.numba_cache`. A file that cannot be read is told apart from a
    missing one and set aside (:func:`_set_aside`). Every load and every compilation is told to
    :mod:`~pendulum_lab.codegen.compile_status`, so that a compilation is reported as a load
    only when nothing was compiled.

    For a function of a package module the file names carry the module's name and
    :func:`code_key` of its code, so that a change in any module it imports gives new files.
    A generated module's name already holds its key.
    """

    def __init__(self, py_func):  # noqa: D107
        super().__init__(py_func)
        self._identity = None

    @property
    def cache_path(self) -> str:
        folder = cache_layers().write
        return str(folder / "__pycache__") if folder is not None else "(in memory)"

    def _base_and_stamp(self) -> tuple[str, bytes] | None:
        """The function's file name base and the stamp of its source. None when the function
        has no source to key it on (then it is not cached)."""
        if self._identity is None:
            function = self._py_func
            module = function.__module__
            path = function.__code__.co_filename
            source = _GENERATED_SOURCES.get(path)
            if source is None:
                try:
                    with open(path, encoding="utf-8") as handle:
                        source = handle.read()
                except OSError:
                    self._identity = ()
                    return None
            if module.startswith(MODULE_PREFIX):  # the file name holds its key
                stem = module.removeprefix(MODULE_PREFIX)
            else:
                stem = f"{module}-{_module_key(module, source)}"
            self._identity = (numba_cache.index_name(stem, function),
                              hashlib.sha256(source.encode()).digest())
        return self._identity or None

    def load(self, key, read):
        """The first layer's compiled version for ``key``, or None (Numba compiles it)."""
        identity = self._base_and_stamp() if key is not None else None
        if identity is not None:
            base, stamp = identity
            layers = cache_layers()
            for folder in layers.read:
                result = self._load_from(folder / "__pycache__", base, stamp, key, read,
                                         writable=folder == layers.write)
                if result is not None:
                    compile_status.count_load()
                    return result
        compile_status.count_compilation()  # Numba compiles it next
        return None

    @staticmethod
    def _load_from(folder: Path, base: str, stamp: bytes, key, read, writable: bool):
        index = folder / f"{base}.nbi"
        try:
            overloads = numba_cache.read_index(index, stamp)
        except numba_cache.DamagedFile as damage:
            _set_aside(index, str(damage), writable)
            return None
        name = overloads.get(key)
        if name is None:
            return None
        data = folder / name
        try:
            return read(data)
        except FileNotFoundError:
            return None  # set aside, or replaced, by another process a moment ago
        except numba_cache.DamagedFile as damage:
            _set_aside(data, str(damage), writable)
            return None

    def save(self, key, write) -> None:
        """Add the compiled version to the user's layer, if there is one."""
        identity = self._base_and_stamp()
        folder = cache_layers().write
        if identity is None or folder is None:
            return
        base, stamp = identity
        folder = folder / "__pycache__"
        try:
            folder.mkdir(parents=True, exist_ok=True)
            # the index is read, extended and written again: one process at a time
            with file_lock(folder / "index.lock"):
                index = folder / f"{base}.nbi"
                try:
                    numba_cache.read_index(index, stamp)
                except numba_cache.DamagedFile as damage:
                    _set_aside(index, str(damage), True)
                    if index.exists():  # could not be set aside (open elsewhere, on Windows)
                        return
                write(folder, base, stamp)
        except OSError as err:  # full, or no longer writable: the kernel stays in memory
            compile_status.count_unsaved()
            _warn_once(f"cannot save a compiled kernel into {folder} "
                       f"({err.strerror or err}); it is compiled in memory for this session. "
                       f"Set {CACHE_VARIABLE} to a writable folder to keep it.")


def cached_njit(signature=None, **options):
    """``numba.njit`` with the package's disk cache (:class:`KernelCache`).

    It is the one way the package caches a kernel, in its modules and in generated code.
    ``@cached_njit`` compiles on first use. ``@cached_njit(signature)`` compiles (or loads)
    when the decorator runs and then accepts only that signature, as ``numba.njit(signature)``
    does. So a package module gives no signature (nothing compiles at import), and generated
    code does (its kernels compile while :func:`load_generated` runs it). ``options`` are
    ``numba.njit``'s (``error_model``, ``nogil``, ...), not ``cache``.
    """
    if inspect.isfunction(signature) and not options:  # used bare: @cached_njit
        return cached_njit()(signature)
    if "cache" in options:
        raise TypeError("cached_njit caches always; do not pass `cache`")

    def decorate(function):
        # the class is looked up when the decorator runs (a test swaps in Numba's own)
        return numba_cache.jit_with_cache(function, lambda f: KernelCache(f), signature,
                                          options)

    return decorate


# --------------------------------------------------------------------------- generated code
#: The text of every generated module executed in this process, by its file name (the key of
#: a kernel's files is taken from it, without reading the file again).
_GENERATED_SOURCES: dict[str, str] = {}


def _numba_disk_cache_calls(source: str) -> list[int]:
    """Lines of ``source`` that ask Numba for its own disk cache (``cache=True``)."""
    with _PARSING:
        tree = ast.parse(source)
    return [node.lineno for node in ast.walk(tree) if isinstance(node, ast.Call)
            and any(k.arg == "cache" and not (isinstance(k.value, ast.Constant)
                                                and k.value.value is False)
                    for k in node.keywords)]


def _find_source(folders, name: str, source: str, writable: Path | None) -> Path | None:
    """The first file ``name`` in ``folders`` whose text is ``source``; a file whose text is
    not (cut short, edited) is set aside where it can be and skipped."""
    for folder in folders:
        path = folder / name
        try:
            text = path.read_text(encoding="utf-8")
        except FileNotFoundError:
            continue
        except (OSError, UnicodeDecodeError) as err:
            text = f"unreadable: {err}"
        if text == source:
            return path
        _set_aside(path, "its text is not the generated source its name stands for",
                   folder == writable)
    return None


def _execute(name: str, source: str, filename: str, inject: dict | None):
    """Run ``source`` as the module ``name`` whose file is ``filename``; registered in
    ``sys.modules`` before it runs, as the import system does (Numba finds a function's
    module there), and removed again if it fails."""
    module = types.ModuleType(name)
    module.__file__ = filename
    module.__dict__.update(inject or {})
    _GENERATED_SOURCES[filename] = source
    if not os.path.exists(filename):  # in memory: tracebacks and Numba's messages show lines
        linecache.cache[filename] = (len(source), None, source.splitlines(True), filename)
    sys.modules[name] = module
    try:
        exec(compile(source, filename, "exec"), module.__dict__)  # noqa: S102 (our own code)
    except BaseException:
        del sys.modules[name]
        raise
    return module


def load_generated(stem: str, source: str, inject: dict | None = None,
                   what: str | None = None):
    """Run generated Python ``source`` as a module, its file in the kernel cache.

    The file is ``<stem>_<key>.py`` with the key of :func:`code_key` (the calling module counts
    as the generator), and the module is registered in ``sys.modules`` as
    ``pendulum_lab_kernels_<stem>_<key>``; a second call returns the same module (its kernels
    stay the objects that other generated code imports by name). ``inject`` sets module globals
    before the source runs (objects that cannot be imported by name). Returns
    ``(module, path)``; ``path`` is None when the module lives in memory only (no cache layer
    holds it and none can be written).

    The file is taken from the first layer of :func:`cache_layers` that holds it with the
    right text; otherwise it is written into the user's layer. Its kernels are declared with
    :func:`cached_njit` and a signature (Numba's own ``cache=True`` is refused: it cannot
    read a read-only layer), so they compile, or load from a layer, while the module runs;
    that is announced as a compilation of ``what`` (for people: "glrk4 for the double
    pendulum"; by default the stem), expected to load when the file was already there
    (:func:`~pendulum_lab.codegen.compile_status.compiling`).

    Where the user's layer can be written, the file is written and run under
    :func:`file_lock` of ``<stem>_<key>.lock`` there, so that one process compiles and saves
    while another waits, then loads.
    """
    caller = inspect.currentframe().f_back
    generator = caller.f_globals.get("__name__") if caller is not None else None
    with _LOADING:  # one thread builds a module; the others wait and get the finished one
        key = code_key(source, generator, inject)
        filename = f"{stem}_{key}.py"
        name = f"{MODULE_PREFIX}{stem}_{key}"
        if name in sys.modules:
            module = sys.modules[name]
            return module, (Path(module.__file__) if os.path.exists(module.__file__) else None)
        lines = _numba_disk_cache_calls(source)
        if lines:
            raise ValueError(f"generated source `{stem}` asks Numba for its own disk cache "
                             f"(cache=True, line {lines[0]}), which cannot read a read-only "
                             "layer: declare kernels with pendulum_lab.codegen.cache."
                             "cached_njit(signature)")
        layers = cache_layers()
        shared = [folder for folder in layers.read if folder != layers.write]
        path = _find_source(shared, filename, source, None)
        expected_load = path is not None or (
            layers.write is not None and (layers.write / filename).exists())
        with compiling(what or f"the generated module {stem}", loading=expected_load,
                       kept=layers.write is not None):
            if layers.write is None:
                guard = contextlib.nullcontext()
            else:  # and one process
                guard = file_lock(layers.write / f"{stem}_{key}.lock")
            with guard:
                if path is None and layers.write is not None:
                    path = _find_source([layers.write], filename, source, layers.write)
                    if path is None:
                        path = _write_or_none(layers.write / filename, source)
                shown = str(path) if path is not None else f"<in memory>/{filename}"
                module = _execute(name, source, shown, inject)
    return module, path


def _write_or_none(path: Path, source: str) -> Path | None:
    """Write a generated module; None (it then runs from memory) if the folder refuses."""
    try:
        _write_atomically(path, source)
    except OSError as err:
        compile_status.count_unsaved()
        _warn_once(f"cannot write {path} ({err.strerror or err}); kernels are "
                   f"compiled in memory for this session. Set {CACHE_VARIABLE} to a writable "
                   "folder to keep them.")
        return None
    return path
