"""Numba's side of the kernel cache: the one module that touches Numba's caching internals.

:mod:`~pendulum_lab.codegen.cache` decides where compiled kernels are read and written
(layers, locks, keys, damaged files). This module only speaks Numba's language for it. It
names the internals it relies on, so that a Numba upgrade that moves them breaks here and
nowhere else. :mod:`~pendulum_lab.codegen.lowlevel` is the other module that may import
``numba.core`` (for its intrinsics); ``tests/codegen/test_numba_internals.py`` checks that
no third one does.

The interface:

* :class:`DispatcherCache`, the cache object Numba asks to load and save the compiled
  versions of one function. A subclass supplies the policy in three methods: ``load``,
  ``save`` and the property ``cache_path``.
* :func:`jit_with_cache`, ``numba.njit`` with such a cache attached to the dispatcher.
* :func:`index_name`, Numba's file name of a function's index, from a stem the policy picks.
* :func:`read_index`, the overloads an index file lists, or :class:`DamagedFile`.
* :data:`NUMBA_VERSION`, the version written into every index.

The files are Numba's own. An index ``<base>.nbi`` holds Numba's version and then the pickled
``(stamp, overloads)``. Each overload is a data file ``<base>.<k>.nbc``. Numba writes both, each
through a temporary name renamed into place.

Numba internals used (Numba 0.68): ``numba.core.caching.Cache`` (its ``_index_key`` and its
``_load_overload`` and ``_save_overload`` hooks), ``numba.core.caching.IndexDataCacheFile``,
``numba.core.compiler.CompileResult._rebuild`` and ``_reduce``, the dispatcher's ``_cache``
attribute (what ``Dispatcher.enable_caching`` sets), and
``numba.core.typeinfer.register_dispatcher``.
"""

from __future__ import annotations

import pickle
import sys
from pathlib import Path

import numba
from numba.core import caching as numba_caching
from numba.core import compiler as numba_compiler
from numba.core import dispatcher as numba_dispatcher

__all__ = [
    "NUMBA_VERSION",
    "DamagedFile",
    "DispatcherCache",
    "index_name",
    "jit_with_cache",
    "read_index",
]

#: Numba's version, as its index files record it.
NUMBA_VERSION: str = numba.__version__


class DamagedFile(Exception):
    """A cache file that cannot be read back. The message says why."""


def index_name(stem: str, function) -> str:
    """Numba's base name for the files of ``function``, with ``stem`` in place of its file's.

    The form is ``<stem>.<qualname>-<first line>.py<version><abiflags>``. The caller picks
    ``stem`` so that the name changes whenever the code it depends on does.
    """
    qualname = function.__qualname__.replace("<", "").replace(">", "")
    return (f"{stem}.{qualname}-{function.__code__.co_firstlineno}.py"
            f"{sys.version_info[0]}{sys.version_info[1]}{getattr(sys, 'abiflags', '')}")


def read_index(path: Path, stamp: bytes) -> dict:
    """The overloads that the index file ``path`` lists, as ``{index key: data file name}``.

    A missing file lists nothing (``{}``). A file that cannot be unpickled, that another Numba
    version wrote, or that was written for another source (``stamp``) raises
    :class:`DamagedFile`.
    """
    try:
        with open(path, "rb") as handle:
            try:
                version = pickle.load(handle)
                rest = handle.read()
            except Exception as err:  # noqa: BLE001 (truncated, garbage)
                raise DamagedFile(f"unreadable: {type(err).__name__}: {err}") from None
    except FileNotFoundError:
        return {}
    if version != NUMBA_VERSION:
        raise DamagedFile(f"written by Numba {version}, this is Numba {NUMBA_VERSION}")
    try:
        found, overloads = pickle.loads(rest)
    except Exception as err:  # noqa: BLE001
        raise DamagedFile(f"unreadable: {type(err).__name__}: {err}") from None
    if found != stamp or not isinstance(overloads, dict):
        raise DamagedFile("written for another source")
    return overloads


def _read_compiled(path: Path, target_context):
    """The compiled version in the data file ``path``.

    A missing file raises ``FileNotFoundError``. A file that cannot be unpickled or rebuilt
    raises :class:`DamagedFile`.
    """
    try:
        payload = pickle.loads(path.read_bytes())
    except FileNotFoundError:
        raise
    except Exception as err:  # noqa: BLE001 (any way of failing to read it back)
        raise DamagedFile(f"unreadable: {type(err).__name__}: {err}") from None
    try:
        return numba_compiler.CompileResult._rebuild(target_context, *payload)
    except Exception as err:  # noqa: BLE001
        raise DamagedFile(f"cannot be rebuilt: {type(err).__name__}: {err}") from None


def _can_save(compiled) -> bool:
    """Whether Numba could save this compiled version (its own ``check_cachable``)."""
    if any(not lifted.can_cache for lifted in compiled.lifted):
        return False
    return not compiled.library.has_dynamic_globals


class DispatcherCache(numba_caching.Cache):
    """The cache Numba asks for one function's compiled versions. The policy is a subclass's.

    Numba calls ``load_overload`` before compiling a signature and ``save_overload`` after.
    This class turns those calls into two plain ones that a subclass implements:

    * ``load(key, read)``: return a compiled version or None. ``key`` is Numba's index key
      (signature, CPU, bytecode). ``read(path)`` returns the version in a data file. It raises
      ``FileNotFoundError`` for a missing file and :class:`DamagedFile` for a bad one.
    * ``save(key, write)``: ``write(folder, base, stamp)`` adds the version to the index
      ``<folder>/<base>.nbi`` as Numba does, raising ``OSError`` when it cannot. ``save`` is
      called only for a version Numba could save.

    and the property ``cache_path``, a folder name for Numba's messages.
    """

    def __init__(self, py_func):  # noqa: D107 (Numba's constructor needs a writable folder)
        self._name = repr(py_func)
        self._py_func = py_func
        self.enable()

    @property
    def cache_path(self) -> str:
        raise NotImplementedError

    def flush(self) -> None:
        """Nothing to drop: a stale file never matches (its name or stamp differs)."""

    def load(self, key, read):
        raise NotImplementedError

    def save(self, key, write) -> None:
        raise NotImplementedError

    def _load_overload(self, sig, target_context):
        key = self._index_key(sig, target_context.codegen()) if self._enabled else None
        return self.load(key, lambda path: _read_compiled(path, target_context))

    def _save_overload(self, sig, data):
        if not self._enabled or not _can_save(data):
            return
        key = self._index_key(sig, data.codegen)

        def write(folder: Path, base: str, stamp: bytes) -> None:
            numba_caching.IndexDataCacheFile(str(folder), base, stamp).save(key, data._reduce())

        self.save(key, write)


def jit_with_cache(function, make_cache, signature=None, options=None):
    """``numba.njit(**options)(function)`` with the cache ``make_cache(function)`` attached.

    With a ``signature`` the function is compiled (or loaded) now and accepts only that
    signature, as ``numba.njit(signature)`` does. Where Numba's JIT is disabled
    (``NUMBA_DISABLE_JIT=1``) the plain Python function comes back and no cache is made.
    """
    dispatcher = numba.njit(**(options or {}))(function)
    if not isinstance(dispatcher, numba_dispatcher.Dispatcher):
        return dispatcher
    # what ``Dispatcher.enable_caching`` sets, with the given cache instead of Numba's own
    dispatcher._cache = make_cache(function)
    if signature is not None:
        from numba.core import typeinfer

        with typeinfer.register_dispatcher(dispatcher):
            dispatcher.compile(signature)
        dispatcher.disable_compile()
    return dispatcher
