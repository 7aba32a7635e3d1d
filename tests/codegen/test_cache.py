"""The kernel cache: keys found from the code itself, and loading that threads and processes share.

A generated module is named after a key of its source and of every package module it imports
(transitively), read as syntax trees without docstrings. So editing a line of code anywhere
below a kernel gives it a new file (and a fresh Numba cache), editing a docstring or a comment
does not, and a module that moved away is an error rather than stale machine code.
"""

from __future__ import annotations

import ast
import contextlib
import json
import os
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab.codegen import cache
from pendulum_lab.integrators import ButcherTableau, Method


@pytest.fixture
def fake_package(tmp_path, monkeypatch):
    """A package ``pendulum_lab`` of two modules in a temporary folder, read by the cache."""
    root = tmp_path / "pendulum_lab"
    root.mkdir()
    (root / "__init__.py").write_text('"""A package made by a test."""\n')
    (root / "kernel.py").write_text(textwrap.dedent('''\
        """The kernel."""
        from .helper import twice


        def kernel(x):
            """Four times x."""
            return twice(twice(x))
        '''))
    (root / "helper.py").write_text(textwrap.dedent('''\
        """A helper."""


        def twice(x):
            """Two times x."""
            return 2 * x  # doubled
        '''))
    (root / "writer.py").write_text('"""Writes generated code."""\nSOURCE = "VALUE = 1"\n')
    monkeypatch.setattr(cache, "_PACKAGE_ROOT", root)
    cache._parsed.cache_clear()
    yield root
    cache._parsed.cache_clear()


GENERATED = "from pendulum_lab.kernel import kernel\nVALUE = kernel(1)\n"


def key_after(root, path, old, new):
    """The key of ``GENERATED`` after replacing ``old`` by ``new`` in ``path``."""
    file = root / path
    file.write_text(file.read_text().replace(old, new))
    cache._parsed.cache_clear()
    return cache.code_key(GENERATED)


def test_the_key_follows_the_imports_to_every_package_module(fake_package):
    assert cache.module_dependencies(["pendulum_lab.kernel"]) == [
        "pendulum_lab.helper", "pendulum_lab.kernel"]


def test_editing_code_below_a_kernel_changes_its_key(fake_package):
    before = cache.code_key(GENERATED)
    assert cache.code_key(GENERATED) == before  # the same code, the same key
    assert key_after(fake_package, "helper.py", "2 * x", "x + x") != before


def test_editing_a_docstring_or_a_comment_keeps_the_key(fake_package):
    before = cache.code_key(GENERATED)
    assert key_after(fake_package, "helper.py", "Two times x.", "Twice x, as a sum.") == before
    assert key_after(fake_package, "helper.py", "# doubled", "# times two") == before
    assert key_after(fake_package, "kernel.py", '"""The kernel."""', '"""A kernel."""') == before
    # negative control: the same file edited in its code
    assert key_after(fake_package, "kernel.py", "twice(twice(x))", "twice(x)") != before


def test_a_module_that_moved_away_is_an_error_not_a_stale_key(fake_package):
    cache.code_key(GENERATED)
    (fake_package / "helper.py").rename(fake_package / "helpers.py")
    cache._parsed.cache_clear()
    with pytest.raises(ImportError, match="pendulum_lab.helper"):
        cache.code_key(GENERATED)


def test_the_generator_and_injected_objects_count(fake_package):
    plain = cache.code_key(GENERATED)
    assert cache.code_key(GENERATED, generator="pendulum_lab.writer") != plain
    assert cache.code_key(GENERATED, generator="pendulum_lab.helper") == plain  # counted already
    assert cache.code_key(GENERATED, inject={"scale": np.array([1.0])}) != cache.code_key(
        GENERATED, inject={"scale": np.array([2.0])})


def test_a_package_kernels_files_follow_the_modules_it_imports(fake_package):
    # a kernel of a package module (cached_njit) is keyed on its module's code and on every
    # package module that imports in turn (relative imports too), as generated code is
    def key():
        cache._parsed.cache_clear()
        return cache._module_key("pendulum_lab.kernel", "")

    before = key()
    helper = fake_package / "helper.py"
    helper.write_text(helper.read_text().replace("Two times x.", "Twice x."))
    assert key() == before  # a docstring
    helper.write_text(helper.read_text().replace("2 * x", "x + x"))
    assert key() != before  # negative control: code below the kernel


def test_steps_with_different_coefficients_get_different_loops():
    # the step of a Runge-Kutta method closes over its tableau: the constants are in the key
    euler = Method.from_tableau("a_method", ButcherTableau(a=[[0.0]], b=[1.0]), "Euler")
    other = Method.from_tableau("a_method", ButcherTableau(a=[[0.5]], b=[1.0]), "not Euler")
    keys = [cache.code_key("x = 1\n", inject={"step": m.kernel.compiled}) for m in (euler, other)]
    assert keys[0] != keys[1]
    again = Method.from_tableau("a_method", ButcherTableau(a=[[0.0]], b=[1.0]), "Euler")
    assert cache.code_key("x = 1\n", inject={"step": again.kernel.compiled}) == keys[0]


def test_the_package_kernels_key_includes_the_long_chains_module():
    # the long chains' kernels live in a package module: the stage kernel generated around
    # them must be keyed on it (Numba alone would check only the generated file)
    looped = pl.codegen.load_kernels(3, looped=True)
    source = f"from {looped.hamilton.py_func.__module__} import hamilton\n"
    with_kernel, without = cache.code_key(source), cache.code_key("hamilton = None\n")
    assert looped.hamilton.py_func.__module__ == "pendulum_lab.codegen.long_chains"
    assert "pendulum_lab.codegen.long_chains" in cache.module_dependencies(
        cache.imported_modules(ast.parse(source), "generated", False))
    assert with_kernel != without


# The module announces that it has started running, then takes its time before it is complete.
SLOW_SOURCE = "STARTED.set()\nimport time\ntime.sleep(0.5)\nVALUE = 42\n"


class Started(threading.Event):
    """An event whose text does not change when it is set (it is part of the module's key)."""

    def __repr__(self):
        return "Started()"


def _first_use_from_two_threads(stem):
    """Two threads load one new module; the second starts once the first is running it."""
    started, results, errors = Started(), [], []

    def use():
        try:
            module, _ = cache.load_generated(stem, SLOW_SOURCE, inject={"STARTED": started})
            results.append(module.VALUE)
        except Exception as error:  # noqa: BLE001 (collected for the assertion)
            errors.append(error)

    first, second = threading.Thread(target=use), threading.Thread(target=use)
    first.start()
    assert started.wait(timeout=60)
    second.start()
    for thread in (first, second):
        thread.join()
    return results, errors


def test_two_threads_using_a_module_first_both_get_it_complete(tmp_path, monkeypatch):
    monkeypatch.setenv("PENDULUM_LAB_CACHE", str(tmp_path))
    results, errors = _first_use_from_two_threads("race_test")
    assert errors == [] and results == [42, 42]


def test_without_the_lock_the_second_thread_sees_a_half_built_module(tmp_path, monkeypatch):
    # negative control: the race the lock prevents really happens with this source
    monkeypatch.setenv("PENDULUM_LAB_CACHE", str(tmp_path))
    monkeypatch.setattr(cache, "_LOADING", contextlib.nullcontext())
    monkeypatch.setattr(cache, "file_lock", lambda path: contextlib.nullcontext())
    results, errors = _first_use_from_two_threads("race_control")
    assert len(errors) == 1 and isinstance(errors[0], AttributeError)
    sys.modules.pop(next(name for name in list(sys.modules) if "race_control" in name), None)


def test_two_threads_simulating_a_new_model_first_both_finish(tmp_path):
    # the report of the race: two threads' first run of one model, in a fresh process and cache
    script = textwrap.dedent("""\
        import threading
        import pendulum_lab as pl
        model = pl.simple_pendulum()
        errors = []
        def run():
            try:
                pl.simulate(model, [1.0], [0.0], t_end=1.0, method="explicit_euler")
            except Exception as error:
                errors.append(repr(error))
        threads = [threading.Thread(target=run) for _ in range(2)]
        [thread.start() for thread in threads]
        [thread.join() for thread in threads]
        print(errors)
        """)
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                            env={**os.environ, "PENDULUM_LAB_CACHE": str(tmp_path)},
                            timeout=600)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "[]"


def test_building_keys_from_many_threads_at_once_never_fails():
    # CPython 3.11 keeps one recursion counter for building syntax trees: parsing from two
    # threads at once failed with "SystemError: AST constructor recursion depth mismatch"
    # inside a Dask worker. The keys are now built under the cache's lock.
    # Four threads parsing side by side for a few rounds each: every round re-parses the
    # package's modules (the parse cache is cleared), so the threads overlap throughout.
    errors = []

    def keys():
        try:
            for k in range(5):
                cache._parsed.cache_clear()
                cache.code_key(f"from pendulum_lab.driver.loops import time_loop\nK = {k}\n")
        except Exception as error:  # noqa: BLE001 (collected for the assertion)
            errors.append(repr(error))

    threads = [threading.Thread(target=keys) for _ in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert errors == []


_DASK_FIRST_USE = textwrap.dedent("""\
    import contextlib, json, sys, threading, time
    from dask.distributed import Client, LocalCluster
    import pendulum_lab as pl
    from pendulum_lab.codegen import cache

    without_locks = sys.argv[1] == "without_locks"
    RUNNING = threading.Event()  # set when the first thread's module has started to run
    if without_locks:  # the negative control: no lock, and a module that takes a while to run
        cache._LOADING = cache._PARSING = contextlib.nullcontext()
        run_module = cache._execute
        def slow(name, source, *args):
            # the pause is inside the module, after it is registered in sys.modules
            RUNNING.set()
            return run_module(name, "import time as _t\\n_t.sleep(2.0)\\n" + source, *args)
        cache._execute = slow
    model = pl.double_pendulum(m2=0.75)  # first used here, in this process
    # Found through sys.modules: Dask pickles the task, and a lock cannot be pickled.
    BARRIER = threading.Barrier(2, timeout=60)

    def first_use(k):
        if without_locks:
            if k:  # the second comes while the first is running the module
                sys.modules["__main__"].RUNNING.wait(300)
                time.sleep(0.3)
        else:
            sys.modules["__main__"].BARRIER.wait()  # both at once
        start = time.perf_counter()
        try:
            traj = pl.simulate(model, [1.0, 0.5], [0.0, 0.0], t_end=1.0, dt=0.01, method="rk4")
            outcome = traj.theta[-1].tolist()
        except Exception as error:
            outcome = f"{type(error).__name__}: {error}"
        return threading.get_ident(), start, time.perf_counter(), outcome

    with LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        futures = [client.submit(first_use, k, pure=False) for k in range(2)]
        print(json.dumps(client.gather(futures)))
    """)


def _dask_first_use(variant):
    pytest.importorskip("distributed")
    result = subprocess.run([sys.executable, "-c", _DASK_FIRST_USE, variant],
                            capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr[-2000:]
    return json.loads(result.stdout.strip().splitlines()[-1])


def test_a_dask_worker_with_two_threads_uses_a_new_model_first_in_both():
    (ident_a, start_a, end_a, theta_a), (ident_b, start_b, end_b, theta_b) = \
        _dask_first_use("with_locks")
    expected = pl.simulate(pl.double_pendulum(m2=0.75), [1.0, 0.5], [0.0, 0.0], t_end=1.0,
                           dt=0.01, method="rk4").theta[-1].tolist()
    assert theta_a == theta_b == expected
    # not vacuous: two threads of the worker, both in their first use at the same time
    assert ident_a != ident_b and max(start_a, start_b) < min(end_a, end_b)


def test_without_the_locks_a_dask_worker_meets_a_race():
    # negative control: the same worker, no lock, modules that take a second to run: the
    # second thread meets the first's half-built module (AttributeError), or the two build
    # syntax trees at once (SystemError from CPython's recursion counter)
    outcomes = [outcome for *_, outcome in _dask_first_use("without_locks")]
    failures = [o for o in outcomes if isinstance(o, str)]
    assert len(failures) >= 1
    assert all(o.startswith(("AttributeError", "SystemError: AST constructor")) for o in failures)


# How Numba writes its cache (numba/core/caching.py): every index and data file goes to a
# temporary name and is renamed into place, so no process reads half a file; but the number
# of a new data file is chosen from the index read before compiling, so two processes
# compiling one function at once can give two versions one number (numba/numba#10128). The
# cache therefore makes one process compile a module and save it while the other waits and
# loads: each function is compiled once, by one of them.
_FIRST_USE_IN_A_PROCESS = textwrap.dedent("""\
    import contextlib, json, os, sys, time
    import pendulum_lab as pl
    from pendulum_lab.codegen import cache, kernels
    from pendulum_lab.driver import loops

    go, what, ready = sys.argv[1], sys.argv[2], sys.argv[3]
    if what == "tiny_without_locks":
        cache.file_lock = lambda path: contextlib.nullcontext()
        save = cache.KernelCache._save_overload
        def slow_save(self, sig, data):  # the other process looks meanwhile, on a busy machine
            time.sleep(3.0)
            save(self, sig, data)
        cache.KernelCache._save_overload = slow_save
    open(ready, "w").close()
    deadline = time.monotonic() + 300
    while not os.path.exists(go):  # both processes start their first use together
        if time.monotonic() > deadline:
            sys.exit("no go")
        time.sleep(0.005)
    start = time.perf_counter()
    if what == "kernels":
        model = pl.simple_pendulum(length=0.8)
        traj = pl.simulate(model, [1.0], [0.0], t_end=1.0, dt=0.01, method="explicit_euler")
        field = pl.hamiltonian_field(model)
        compiled = loops.compile_method(pl.get_method("explicit_euler"), field, 1)
        chain = kernels.load_kernels(1, False)
        functions = {"run": compiled.run, "hamilton": chain.hamilton,
                     "acceleration": chain.acceleration, "stages": chain.stages}
        result = traj.theta[-1].tolist() + traj.p[-1].tolist()
    else:
        source = ("import time\\nfrom pendulum_lab.codegen.cache import cached_njit\\n"
                  "time.sleep(1.0)\\n\\n\\n"
                  "@cached_njit('float64(float64)')\\ndef double(x):\\n"
                  "    return 2.0 * x\\n")
        module, _ = cache.load_generated("process_race", source)
        functions, result = {"double": module.double}, [module.double(1.5)]
    print(json.dumps({"start": start, "end": time.perf_counter(), "result": result,
                      "misses": {k: sum(f.stats.cache_misses.values())
                                 for k, f in functions.items()},
                      "hits": {k: sum(f.stats.cache_hits.values())
                               for k, f in functions.items()}}))
    """)


def _first_use_in_two_processes(tmp_path, what):
    tmp_path.mkdir(parents=True, exist_ok=True)
    folder = tmp_path / "cache"
    go = tmp_path / "go"
    # Numba's files go beside the generated ones, in the empty folder (not NUMBA_CACHE_DIR)
    env = {**{k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"},
           "PENDULUM_LAB_CACHE": str(folder)}
    ready = [tmp_path / f"ready{k}" for k in range(2)]
    processes = [subprocess.Popen([sys.executable, "-c", _FIRST_USE_IN_A_PROCESS, str(go), what,
                                   str(ready[k])], env=env, stdout=subprocess.PIPE,
                                  stderr=subprocess.PIPE, text=True) for k in range(2)]
    try:
        deadline = time.monotonic() + 300
        while not all(path.exists() for path in ready) and time.monotonic() < deadline:
            time.sleep(0.01)  # both have imported the package
        go.write_text("go")
        reports = []
        for process in processes:
            out, err = process.communicate(timeout=600)
            assert process.returncode == 0, err[-2000:]
            reports.append(json.loads(out.strip().splitlines()[-1]))
    finally:
        for process in processes:  # none is left waiting
            if process.poll() is None:
                process.kill()
                process.wait()
    return reports, folder


def test_two_processes_compiling_new_kernels_into_one_empty_cache(tmp_path):
    (a, b), folder = _first_use_in_two_processes(tmp_path, "kernels")
    model = pl.simple_pendulum(length=0.8)
    here = pl.simulate(model, [1.0], [0.0], t_end=1.0, dt=0.01, method="explicit_euler")
    assert a["result"] == b["result"] == here.theta[-1].tolist() + here.p[-1].tolist()
    # each function compiled once, by one of the two, and loaded from disk by the other
    for name in a["misses"]:
        assert a["misses"][name] + b["misses"][name] == 1, name
        assert a["hits"][name] + b["hits"][name] == 1, name
    # not vacuous: the cache folder was empty, and the two first uses overlapped in time
    assert max(a["start"], b["start"]) < min(a["end"], b["end"])
    assert any(folder.rglob("*.nbi"))


def test_two_processes_share_a_tiny_module_and_without_the_lock_both_compile(tmp_path):
    (a, b), _ = _first_use_in_two_processes(tmp_path / "locked", "tiny")
    assert a["result"] == b["result"] == [3.0]
    assert a["misses"]["double"] + b["misses"]["double"] == 1
    # negative control: without the file lock both compile the same function at once
    (a, b), _ = _first_use_in_two_processes(tmp_path / "unlocked", "tiny_without_locks")
    assert a["result"] == b["result"] == [3.0]
    assert a["misses"]["double"] + b["misses"]["double"] == 2, (a, b)
