"""The kernel cache: keys found from the code itself, and loading that two threads can share.

A generated module is named after a key of its source and of every package module it imports
(transitively), read as syntax trees without docstrings. So editing a line of code anywhere
below a kernel gives it a new file (and a fresh Numba cache), editing a docstring or a comment
does not, and a module that moved away is an error rather than stale machine code.
"""

from __future__ import annotations

import ast
import contextlib
import os
import subprocess
import sys
import textwrap
import threading

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
