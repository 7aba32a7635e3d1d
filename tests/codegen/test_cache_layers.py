"""The kernel cache on shared, read-only and damaged folders, and its locks on every system.

A read-only folder is made for real, with a read-only bind mount (as root, permission bits
stop no write); where mounting is not permitted those tests are skipped, saying so. A tiny
generated module of two kernels stands in for the course's kernels, so that each compile
takes a fraction of a second; what was compiled and what was loaded is read from Numba's own
counters (``dispatcher.stats``) and from the cache's (``compile_status.compile_counts``),
never from timings.
"""

from __future__ import annotations

import contextlib
import errno
import itertools
import json
import os
import pickle
import subprocess
import sys
import textwrap
import threading
import time
import types
import uuid

import numba
import pytest
from numba.core import caching as numba_caching

try:
    import fcntl  # the emulated msvcrt locks with it
except ImportError:  # Windows: the real msvcrt is used instead
    fcntl = None

from pendulum_lab.codegen import cache, compile_status
from pendulum_lab.codegen.cache import (
    CACHE_VARIABLE,
    SHARED_VARIABLE,
    KernelCacheWarning,
    cache_layers,
    file_lock,
    load_generated,
)

_TAGS = itertools.count()


def tiny_source(tag: str) -> str:
    """Two kernels with signatures (compiled while the module runs); ``tag`` makes it new."""
    return textwrap.dedent(f'''\
        """A tiny generated module for the cache tests ({tag})."""
        from pendulum_lab.codegen.cache import cached_njit


        @cached_njit("float64(float64)")
        def triple(x):
            return 3.0 * x


        @cached_njit("float64(float64)")
        def square(x):
            return x * x
        ''')


def new_source() -> str:
    return tiny_source(f"{os.getpid()}-{next(_TAGS)}-{uuid.uuid4().hex[:6]}")


def forget(module) -> None:
    """Drop a generated module from this process, as a new session would not have it."""
    sys.modules.pop(module.__name__, None)


def counts(module) -> tuple[int, int]:
    """(loaded, compiled) versions of the module's two kernels, from Numba's counters."""
    kernels = (module.triple, module.square)
    return (sum(sum(k.stats.cache_hits.values()) for k in kernels),
            sum(sum(k.stats.cache_misses.values()) for k in kernels))


@pytest.fixture
def layers(tmp_path, monkeypatch):
    """Empty, temporary cache folders (never the user's), and fresh per-process checks."""
    monkeypatch.setenv(CACHE_VARIABLE, str(tmp_path / "user"))
    monkeypatch.delenv(SHARED_VARIABLE, raising=False)
    monkeypatch.setenv(compile_status.NOTES_VARIABLE, "off")
    cache._unwritable_reason.cache_clear()
    monkeypatch.setattr(cache, "_warned", set())
    yield tmp_path
    cache._unwritable_reason.cache_clear()


@pytest.fixture
def read_only(tmp_path):
    """``make(folder)``: a read-only view of ``folder`` (a bind mount), unmounted at the end."""
    mounts = []

    def make(folder):
        view = folder.with_name(folder.name + "_read_only")
        view.mkdir()
        done = subprocess.run(["mount", "--bind", str(folder), str(view)], capture_output=True,
                              text=True, check=False)
        if done.returncode != 0:
            pytest.skip(f"a read-only bind mount is not permitted here: {done.stderr.strip()}")
        mounts.append(view)
        subprocess.run(["mount", "-o", "remount,ro,bind", str(view)], check=True)
        with pytest.raises(OSError):  # really read-only, for root too
            (view / "probe").write_text("x")
        return view

    if sys.platform != "linux":
        pytest.skip("read-only bind mounts are made with Linux's mount")
    yield make
    for view in mounts:
        subprocess.run(["umount", str(view)], check=False)


def compile_into(folder, monkeypatch, source):
    """Compile ``source`` into the cache ``folder`` (as ``pendulum-lab warmup --cache`` does);
    the user's cache is the test's ``user`` folder again afterwards."""
    user = os.environ[CACHE_VARIABLE]
    monkeypatch.setenv(CACHE_VARIABLE, str(folder))
    module, path = load_generated("layer_test", source)
    assert counts(module) == (0, 2) and path.parent == folder / "kernels"
    forget(module)
    monkeypatch.setenv(CACHE_VARIABLE, user)
    cache._unwritable_reason.cache_clear()
    return module


# ------------------------------------------------------------------------------ layers
def test_a_warm_read_only_layer_is_loaded_and_nothing_is_compiled(layers, read_only,
                                                                   monkeypatch):
    source = new_source()
    compile_into(layers / "image", monkeypatch, source)
    shared = read_only(layers / "image")
    monkeypatch.setenv(SHARED_VARIABLE, str(shared))
    monkeypatch.setenv(CACHE_VARIABLE, str(layers / "user"))
    before = compile_status.compile_counts()
    module, path = load_generated("layer_test", source)
    assert module.triple(2.0) == 6.0 and module.square(3.0) == 9.0
    assert counts(module) == (2, 0)
    loaded, compiled = (a - b for a, b in zip(compile_status.compile_counts(), before))
    assert (loaded, compiled) == (2, 0)
    assert path.parent == shared / "kernels"  # the module itself came from the shared layer
    user = layers / "user" / "kernels"
    assert not list(user.rglob("*.nbc")) and not list(user.glob("*.py"))  # nothing copied
    forget(module)


def test_numbas_own_cache_cannot_read_a_read_only_layer(layers, read_only, monkeypatch):
    # negative control: the same warm, read-only layer through Numba's own cache is not
    # read (each of its locators needs a folder it can write), so everything compiles again
    source = new_source()
    compile_into(layers / "image", monkeypatch, source)
    shared = read_only(layers / "image")
    monkeypatch.setenv(SHARED_VARIABLE, str(shared))
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(layers / "numba"))
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(layers / "numba"))
    monkeypatch.setattr(cache, "KernelCache", numba.core.caching.FunctionCache)
    module, _ = load_generated("layer_test", source)
    assert counts(module) == (0, 2)
    forget(module)


def test_a_partial_read_only_layer_leaves_only_the_missing_to_the_users_cache(
        layers, read_only, monkeypatch):
    in_image, missing = new_source(), new_source()
    compile_into(layers / "image", monkeypatch, in_image)
    shared = read_only(layers / "image")
    monkeypatch.setenv(SHARED_VARIABLE, str(shared))
    monkeypatch.setenv(CACHE_VARIABLE, str(layers / "user"))
    first, _ = load_generated("layer_test", in_image)
    second, second_path = load_generated("layer_test", missing)
    assert counts(first) == (2, 0) and counts(second) == (0, 2)
    user = layers / "user" / "kernels"
    assert second_path.parent == user
    stem = second.__name__.removeprefix(cache.MODULE_PREFIX)
    saved = {p.name.split(".")[0] for p in (user / "__pycache__").glob("*.nbc")}
    assert saved == {stem}  # only the missing module's kernels, into the user's cache
    # and the next session loads both, from their own layers
    forget(first), forget(second)
    again = [load_generated("layer_test", s)[0] for s in (in_image, missing)]
    assert [counts(m) for m in again] == [(2, 0), (2, 0)]
    for module in again:
        forget(module)


def test_a_warm_read_only_user_cache_loads_with_one_warning(layers, read_only, monkeypatch):
    # the case: PENDULUM_LAB_CACHE itself is the image's read-only folder
    source = new_source()
    compile_into(layers / "image", monkeypatch, source)
    folder = read_only(layers / "image")
    monkeypatch.setenv(CACHE_VARIABLE, str(folder))
    with pytest.warns(KernelCacheWarning) as caught:
        module, _ = load_generated("layer_test", source)
    assert counts(module) == (2, 0)
    (warning,) = caught
    text = str(warning.message)
    assert "\n" not in text and str(folder / "kernels") in text and CACHE_VARIABLE in text
    # (and no lock was opened for writing there: on this mount that raises, see below)
    forget(module)


def test_a_lock_file_in_a_read_only_folder_cannot_be_opened(layers, read_only):
    # negative control: what the cache never does (the failure of issue 41)
    (layers / "user").mkdir()
    folder = read_only(layers / "user")
    with pytest.raises(OSError, match="Read-only file system"), file_lock(folder / "x.lock"):
        pass


def test_an_empty_read_only_cache_folder_compiles_in_memory(layers, read_only, monkeypatch):
    (layers / "empty").mkdir()
    folder = read_only(layers / "empty")
    monkeypatch.setenv(CACHE_VARIABLE, str(folder))
    with pytest.warns(KernelCacheWarning, match=CACHE_VARIABLE) as caught:
        module, path = load_generated("layer_test", new_source())
    assert module.triple(2.0) == 6.0 and counts(module) == (0, 2)
    assert path is None and str(folder / "kernels") in str(caught[0].message)
    forget(module)


def test_an_unwritable_cache_folder_compiles_in_memory_and_says_where(layers, monkeypatch):
    (layers / "a_file").write_text("not a folder")
    folder = layers / "a_file" / "cache"  # cannot be made, whoever runs the test
    monkeypatch.setenv(CACHE_VARIABLE, str(folder))
    events = []
    with pytest.warns(KernelCacheWarning) as caught, compile_status.listen(events.append):
        module, path = load_generated("layer_test", new_source())
    assert module.square(4.0) == 16.0 and path is None
    assert events[-1].message.endswith("for this session only")
    (warning,) = [w for w in caught if issubclass(w.category, KernelCacheWarning)]
    text = str(warning.message)
    assert str(folder / "kernels") in text and CACHE_VARIABLE in text and "\n" not in text
    assert cache_layers().write is None
    forget(module)
    # negative control: a writable folder says nothing
    monkeypatch.setenv(CACHE_VARIABLE, str(layers / "user"))
    with warnings_as_errors():
        module, path = load_generated("layer_test", new_source())
    assert path is not None
    forget(module)


def test_a_full_disk_compiles_in_memory_and_says_for_this_session_only(layers, monkeypatch):
    """A student's home that fills up while kernels are saved (emulated: the index's save
    raises ENOSPC, as a full disk does): the kernel runs, a warning names the folder, and the
    note no longer promises that it loads from disk next time."""
    def full_disk(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    def compile_once():
        events = []
        with compile_status.listen(events.append):
            module, _ = load_generated("layer_test", new_source(), what="a tiny kernel")
        assert module.triple(2.0) == 6.0
        forget(module)
        return events[-1]

    monkeypatch.setattr(numba_caching.IndexDataCacheFile, "save", full_disk)
    with pytest.warns(KernelCacheWarning, match="No space left on device"):
        full = compile_once()
    assert not full.kept and full.message.endswith("for this session only")
    monkeypatch.undo()  # negative control: the same compilation with room on the disk
    monkeypatch.setenv(CACHE_VARIABLE, str(layers / "user"))
    monkeypatch.setenv(compile_status.NOTES_VARIABLE, "off")
    with warnings_as_errors():
        room = compile_once()
    assert room.kept and "from now on it loads from the disk cache" in room.message


def test_no_home_folder_compiles_in_memory(layers, monkeypatch):
    # a service account or a bare container: Path.home() raises
    monkeypatch.delenv(CACHE_VARIABLE)
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)

    def no_home():
        raise RuntimeError("Could not determine home directory.")

    monkeypatch.setattr(cache.Path, "home", staticmethod(no_home))
    assert cache.cache_dir() is None
    with pytest.warns(KernelCacheWarning, match=f"no home folder.*{CACHE_VARIABLE}"):
        module, path = load_generated("layer_test", new_source())
    assert module.triple(1.0) == 3.0 and path is None and counts(module) == (0, 2)
    forget(module)


@contextlib.contextmanager
def warnings_as_errors():
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", KernelCacheWarning)
        yield


def test_numbas_own_disk_cache_is_refused_in_generated_code(layers):
    source = ("import numba\n\n\n@numba.njit('float64(float64)', cache=True)\n"
              "def f(x):\n    return x\n")
    with pytest.raises(ValueError, match="cached_njit"):
        load_generated("layer_test", source)


# ------------------------------------------------------------------------------ damage
def _warm_user_cache(monkeypatch, layers):
    source = new_source()
    module = compile_into(layers / "user", monkeypatch, source)
    monkeypatch.setenv(CACHE_VARIABLE, str(layers / "user"))
    folder = layers / "user" / "kernels"
    stem = module.__name__.removeprefix(cache.MODULE_PREFIX)
    return source, folder, stem


def _damage_and_reload(monkeypatch, layers, damage):
    """Warm the user's cache, damage one file, load again: the warning, the module, the file."""
    source, folder, stem = _warm_user_cache(monkeypatch, layers)
    path = damage(folder, stem)
    with pytest.warns(KernelCacheWarning, match="damaged") as caught:
        module, _ = load_generated("layer_test", source)
    assert module.triple(2.0) == 6.0 and module.square(3.0) == 9.0
    messages = [str(w.message) for w in caught]
    assert any(str(path) in m for m in messages), messages
    assert path.with_name(path.name + ".damaged").exists()
    forget(module)
    again, _ = load_generated("layer_test", source)  # rebuilt: the next session loads it all
    assert counts(again) == (2, 0)
    forget(again)
    return module


def _index(folder, stem, name="triple"):
    (path,) = (folder / "__pycache__").glob(f"{stem}.{name}-*.nbi")
    return path


def test_a_truncated_index_is_set_aside_and_rebuilt(layers, monkeypatch):
    def truncate(folder, stem):
        path = _index(folder, stem)
        path.write_bytes(path.read_bytes()[:20])
        return path

    module = _damage_and_reload(monkeypatch, layers, truncate)
    assert counts(module) == (1, 1)  # square loaded, triple compiled again


def test_numbas_own_reading_fails_on_a_truncated_index(layers, monkeypatch):
    # negative control: Numba's own index reader raises on the same file (what stopped
    # ``import pendulum_lab`` before)
    _, folder, stem = _warm_user_cache(monkeypatch, layers)
    path = _index(folder, stem)
    path.write_bytes(path.read_bytes()[:20])
    reader = numba.core.caching.IndexDataCacheFile(str(path.parent), path.name[:-4], b"")
    with pytest.raises((pickle.UnpicklingError, EOFError)):
        reader._load_index()


def test_a_garbage_data_file_is_set_aside_and_rebuilt(layers, monkeypatch):
    def garbage(folder, stem):
        (path,) = (folder / "__pycache__").glob(f"{stem}.square-*.nbc")
        path.write_bytes(b"\x80\x05garbage, not a pickle" * 10)
        return path

    module = _damage_and_reload(monkeypatch, layers, garbage)
    assert counts(module) == (1, 1)


def test_an_index_from_another_numba_version_is_set_aside_and_rebuilt(layers, monkeypatch):
    def other_version(folder, stem):
        path = _index(folder, stem, "square")
        data = path.read_bytes()
        with open(path, "rb") as handle:
            pickle.load(handle)
            rest = handle.read()
        path.write_bytes(pickle.dumps("0.1.0") + rest)
        assert path.read_bytes() != data
        return path

    _damage_and_reload(monkeypatch, layers, other_version)


def test_a_generated_module_cut_short_is_set_aside_and_written_again(layers, monkeypatch):
    def cut(folder, stem):
        path = folder / f"{stem}.py"
        path.write_text(path.read_text()[:60])
        return path

    module = _damage_and_reload(monkeypatch, layers, cut)
    assert counts(module) == (2, 0)  # its machine code was sound: loaded


def test_a_damaged_file_in_a_read_only_layer_is_skipped(layers, read_only, monkeypatch):
    source = new_source()
    module = compile_into(layers / "image", monkeypatch, source)
    stem = module.__name__.removeprefix(cache.MODULE_PREFIX)
    path = _index(layers / "image" / "kernels", stem)
    path.write_bytes(path.read_bytes()[:20])
    shared = read_only(layers / "image")
    monkeypatch.setenv(SHARED_VARIABLE, str(shared))
    with pytest.warns(KernelCacheWarning, match="read-only layer"):
        module, _ = load_generated("layer_test", source)
    assert counts(module) == (1, 1)  # triple compiled into the user's cache
    assert list((layers / "user" / "kernels" / "__pycache__").glob(f"{stem}.triple-*.nbc"))
    forget(module)


_IMPORT_AND_LOAD = textwrap.dedent("""\
    import sys
    import pendulum_lab
    from pendulum_lab.codegen.cache import load_generated
    module, _ = load_generated("layer_test", sys.argv[1])
    print(module.triple(2.0))
    """)


def test_import_pendulum_lab_survives_a_damaged_cache(layers, monkeypatch):
    source, folder, stem = _warm_user_cache(monkeypatch, layers)
    index = _index(folder, stem)  # triple's index truncated
    index.write_bytes(index.read_bytes()[:20])
    (data,) = (folder / "__pycache__").glob(f"{stem}.square-*.nbc")  # square's data garbage
    data.write_bytes(b"garbage" * 20)
    module = folder / f"{stem}.py"  # and the module cut short
    module.write_text(module.read_text()[:60])
    env = {**os.environ, CACHE_VARIABLE: str(layers / "user"),
           compile_status.NOTES_VARIABLE: "off"}
    done = subprocess.run([sys.executable, "-c", _IMPORT_AND_LOAD, source], env=env,
                          capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip() == "6.0"
    for path in (index, data, module):
        assert f"damaged kernel cache file {path}" in done.stderr
        assert path.with_name(path.name + ".damaged").exists()
    assert done.stderr.count("KernelCacheWarning") == 3  # one line each


# ------------------------------------------------------------------------- import
_IMPORT_COMPILES = textwrap.dedent("""\
    import json, sys
    from numba.core import event

    compiled = []

    class Listener(event.Listener):
        def on_start(self, event):
            compiled.append(str(event.data["dispatcher"].py_func.__qualname__))

        def on_end(self, event):
            pass

    event.register("numba:compile", Listener())
    import numba
    import pendulum_lab
    from numba.core.registry import CPUDispatcher

    def versions():
        dispatchers = {id(value): value for name, module in list(sys.modules.items())
                       if name.startswith("pendulum_lab") for value in vars(module).values()
                       if isinstance(value, CPUDispatcher)}
        return sum(len(d.overloads) for d in dispatchers.values())

    after_import = versions()
    if sys.argv[1] == "use":  # the control: a first use compiles (and the check sees it)
        import numpy as np
        pendulum_lab.codegen.kernels.solve_spd(np.eye(2), np.ones(2), np.empty(2))
    print(json.dumps({"compiled": compiled, "after_import": after_import,
                      "at_end": versions()}))
    """)


def _import_report(tmp_path, what):
    env = {**os.environ, CACHE_VARIABLE: str(tmp_path / "cache"),
           compile_status.NOTES_VARIABLE: "off"}
    done = subprocess.run([sys.executable, "-c", _IMPORT_COMPILES, what], env=env,
                          capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_import_pendulum_lab_compiles_and_loads_nothing(tmp_path):
    report = _import_report(tmp_path, "import")
    assert report == {"compiled": [], "after_import": 0, "at_end": 0}
    assert not (tmp_path / "cache").exists()  # not even the folder was made
    # negative control: a first use of a package kernel compiles, and both checks see it
    report = _import_report(tmp_path, "use")
    assert "solve_spd" in report["compiled"] and report["at_end"] == 1


# ------------------------------------------------------------------------- file locks
_COUNTER = textwrap.dedent("""\
    import contextlib, os, sys, time
    from pathlib import Path
    from pendulum_lab.codegen.cache import file_lock

    counter, go, locked = Path(sys.argv[1]), Path(sys.argv[2]), sys.argv[3] == "locked"
    Path(sys.argv[4]).write_text("ready")  # imported: both start counting together
    while not go.exists():
        time.sleep(0.002)
    for _ in range(25):
        with file_lock(counter.with_suffix(".lock")) if locked else contextlib.nullcontext():
            value = int(counter.read_text())
            time.sleep(0.003)  # another process reads the same value meanwhile, unless locked
            temporary = counter.with_name(f"{counter.name}.{os.getpid()}")
            temporary.write_text(str(value + 1))
            os.replace(temporary, counter)  # never half written, locked or not
    """)


def _count_in_two_processes(tmp_path, locked: bool) -> int:
    counter, go = tmp_path / f"counter_{locked}", tmp_path / f"go_{locked}"
    ready = [tmp_path / f"ready_{locked}_{k}" for k in range(2)]
    counter.write_text("0")
    processes = [subprocess.Popen([sys.executable, "-c", _COUNTER, str(counter), str(go),
                                   "locked" if locked else "free", str(ready[k])])
                 for k in range(2)]
    deadline = time.monotonic() + 300
    while not all(path.exists() for path in ready) and time.monotonic() < deadline:
        time.sleep(0.01)
    go.write_text("go")
    for process in processes:
        assert process.wait(timeout=300) == 0
    return int(counter.read_text())


@pytest.mark.skipif(sys.platform == "win32", reason="the fcntl branch")
def test_file_lock_keeps_two_processes_apart_with_fcntl(tmp_path):
    assert cache._lock_functions() is not None
    assert _count_in_two_processes(tmp_path, locked=True) == 50
    # negative control: without the lock the two processes lose updates
    assert _count_in_two_processes(tmp_path, locked=False) < 50


def _fake_msvcrt(really_locks: bool, calls: list):
    """A stand-in for Windows' ``msvcrt``: ``locking`` of the byte at the position, refused
    (OSError, as on Windows) while another opening of the file holds it."""
    module = types.ModuleType("msvcrt")
    module.LK_UNLCK, module.LK_LOCK, module.LK_NBLCK = 0, 1, 2

    def locking(fd, mode, nbytes):
        calls.append((mode, nbytes, os.lseek(fd, 0, os.SEEK_CUR)))
        if not really_locks:
            return
        if mode == module.LK_UNLCK:
            fcntl.flock(fd, fcntl.LOCK_UN)
            return
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise OSError(errno.EDEADLOCK, "Resource deadlock avoided") from None

    module.locking = locking
    return module


def _count_in_two_threads(counter) -> int:
    counter.write_text("0")

    def work():
        for _ in range(25):
            with file_lock(counter.with_suffix(".lock")):
                value = int(counter.read_text())
                time.sleep(0.002)
                temporary = counter.with_name(f"{counter.name}.{threading.get_ident()}")
                temporary.write_text(str(value + 1))
                os.replace(temporary, counter)

    threads = [threading.Thread(target=work) for _ in range(2)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    return int(counter.read_text())


@pytest.mark.skipif(fcntl is None, reason="emulates Windows on a system with fcntl")
def test_file_lock_on_windows_locks_with_msvcrt(tmp_path, monkeypatch):
    calls = []
    fake = _fake_msvcrt(True, calls)
    monkeypatch.setitem(sys.modules, "fcntl", None)  # ``import fcntl`` fails, as on Windows
    monkeypatch.setitem(sys.modules, "msvcrt", fake)
    lock, unlock = cache._lock_functions()
    assert _count_in_two_threads(tmp_path / "counter") == 50
    assert {mode for mode, _, _ in calls} == {fake.LK_NBLCK, fake.LK_UNLCK}
    assert {(nbytes, position) for _, nbytes, position in calls} == {(1, 0)}
    assert sum(mode == fake.LK_UNLCK for mode, _, _ in calls) == 50
    # an error other than "held elsewhere" is raised, not retried for ever
    broken = types.ModuleType("msvcrt")
    broken.LK_NBLCK, broken.LK_UNLCK = 2, 0

    def fail(fd, mode, nbytes):
        raise OSError(errno.EBADF, "Bad file descriptor")

    broken.locking = fail
    monkeypatch.setitem(sys.modules, "msvcrt", broken)
    with pytest.raises(OSError, match="Bad file"), file_lock(tmp_path / "broken.lock"):
        pass
    # negative control: a msvcrt whose locking locks nothing loses updates
    monkeypatch.setitem(sys.modules, "msvcrt", _fake_msvcrt(False, []))
    assert _count_in_two_threads(tmp_path / "counter_free") < 50


def test_file_lock_without_fcntl_or_msvcrt_still_keeps_threads_apart(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "fcntl", None)
    monkeypatch.setitem(sys.modules, "msvcrt", None)
    assert cache._lock_functions() is None
    assert _count_in_two_threads(tmp_path / "counter") == 50


# ------------------------------------------------------------------------- what is said
def test_a_compilation_that_only_loaded_says_it_loaded():
    events = []
    with compile_status.listen(events.append), compile_status.compiling("a kernel",
                                                                         loading=False):
        compile_status.count_load()
    assert events[-1].loading is True
    assert events[-1].message.startswith("loaded a kernel from the disk cache in ")
    # negative control: one compilation inside makes it a compilation
    with compile_status.listen(events.append), compile_status.compiling("a kernel",
                                                                         loading=True):
        compile_status.count_load()
        compile_status.count_compilation()
    assert events[-1].loading is False and events[-1].message.startswith("compiled a kernel")


# ------------------------------------------------------------------------- warm-up
def test_warmup_cache_compiles_into_the_given_folder(layers, monkeypatch, capsys):
    from pendulum_lab.app import cli, warmup

    source = new_source()
    seen = {}

    def warm_up(ns, methods, progress):  # a tiny stand-in for the course's kernels
        seen["shared"] = os.environ.get(SHARED_VARIABLE)
        module, path = load_generated("layer_test", source)
        seen["path"] = path
        forget(module)
        return 0.0

    monkeypatch.setattr(warmup, "warm_up", warm_up)
    monkeypatch.setenv(SHARED_VARIABLE, str(layers / "elsewhere"))
    target = layers / "image"
    assert cli.main(["warmup", "--cache", str(target), "--progress", "none"]) == 0
    assert seen["shared"] is None  # the image's folder is complete on its own
    assert seen["path"].parent == target / "kernels"
    assert list((target / "kernels" / "__pycache__").glob("*.nbc"))
    # an unwritable folder stops the warm-up, saying which and how to choose another
    (layers / "a_file").write_text("x")
    assert cli.main(["warmup", "--cache", str(layers / "a_file" / "c"), "--progress",
                     "none"]) == 1
    err = capsys.readouterr().err
    assert str(layers / "a_file" / "c") in err and "--cache" in err


def test_a_run_that_loaded_its_kernels_says_it_loaded_them():
    # issue 43, item 23: a kernel loaded from the cache was reported as "after compiling"
    import numpy as np

    import pendulum_lab as pl
    from pendulum_lab.widgets.instrument import Instrument

    def summary(compiled: bool) -> str:
        trajectory = types.SimpleNamespace(
            energy_error=np.zeros(3), energy=np.ones(3), t=np.arange(3.0), dt=0.1,
            method=types.SimpleNamespace(name="rk4"), wall_time=0.01, compile_time=0.4,
            compiled=compiled)
        fake = types.SimpleNamespace(trajectory=trajectory, model=pl.simple_pendulum())
        return Instrument.summary(fake)

    assert "after loading its compiled kernels from the disk cache in 0.4 s" in summary(False)
    assert "compiling" not in summary(False)
    # negative control: a run that compiled says so
    assert "after compiling for 0.4 s, once per machine" in summary(True)
