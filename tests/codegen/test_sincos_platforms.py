"""Where the kernels' ``sincos`` comes from on each operating system, by emulation.

``codegen.lowlevel.c_library_has_sincos`` decides, once at import, whether the compiled
kernels call the C library's ``sincos`` (Linux) or ``sin`` and ``cos`` separately (macOS,
Windows, or wherever the symbol cannot be found). Here each branch runs on this machine: the
Windows branch of CPython's own ``ctypes.CDLL`` (whose ``CDLL(None)`` raises TypeError, what
stopped ``import pendulum_lab`` on Windows), a process without ``sincos``, a C library that
cannot be opened; and the module is executed afresh under each emulation, as an import would.
The separate calls give the C library's ``sin`` and ``cos`` to the bit, with no shift near pi.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import importlib.util
import math
import os
import subprocess
import sys
import textwrap
import types
from pathlib import Path

import llvmlite.binding as llvm_binding
import numba
import numpy as np
import pytest

from pendulum_lab.codegen import lowlevel

REPO = Path(__file__).resolve().parents[2]


# ---------------------------------------------------------------- emulated operating systems
def emulate_windows_ctypes(monkeypatch):
    """CPython's ``ctypes.CDLL`` takes its Windows branch, and ``find_library("m")`` is None.

    ``CDLL.__init__`` asks ``ctypes._os.name`` and imports ``nt``; both are faked, so the
    library's own code runs the branch that fails on Windows.
    """
    public = {name: getattr(os, name) for name in dir(os) if not name.startswith("__")}
    fake_os = types.SimpleNamespace(**public)
    fake_os.name = "nt"
    fake_nt = types.ModuleType("nt")
    fake_nt._LOAD_LIBRARY_SEARCH_DEFAULT_DIRS = 0x1000
    fake_nt._LOAD_LIBRARY_SEARCH_DLL_LOAD_DIR = 0x100
    fake_nt._getfullpathname = os.path.abspath
    monkeypatch.setattr(ctypes, "_os", fake_os)
    monkeypatch.setitem(sys.modules, "nt", fake_nt)
    monkeypatch.setattr(ctypes.util, "find_library", lambda name: None)


def old_detection():
    """The detection before it had a branch per system (kept here as the negative control)."""
    try:
        return hasattr(ctypes.CDLL(ctypes.util.find_library("m")), "sincos")
    except OSError:
        return False


def fresh_lowlevel():
    """``codegen/lowlevel.py`` executed as a new module, as ``import`` would run it."""
    spec = importlib.util.spec_from_file_location("lowlevel_emulated", lowlevel.__file__)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_windows_ctypes_stopped_the_old_import_and_not_the_new(monkeypatch):
    emulate_windows_ctypes(monkeypatch)
    # negative control: the emulation is faithful, the old code raises what Windows raised
    with pytest.raises(TypeError, match="NoneType"):
        ctypes.CDLL(ctypes.util.find_library("m"))
    with pytest.raises(TypeError, match="NoneType"):
        old_detection()
    # the new detection, on this emulated Linux process and for Windows itself
    assert lowlevel.c_library_has_sincos() is False
    assert lowlevel.c_library_has_sincos("win32") is False
    module = fresh_lowlevel()
    assert module.HAVE_SINCOS is False and module.SHIFT_NEAR_PI is False


@pytest.mark.parametrize("failure", [OSError("cannot open the process"),
                                     TypeError("argument of type 'NoneType' is not iterable")])
def test_a_c_library_that_cannot_be_opened_means_separate_calls(monkeypatch, failure):
    def refuse(*args, **kwargs):
        raise failure

    monkeypatch.setattr(ctypes, "CDLL", refuse)
    assert lowlevel.c_library_has_sincos("linux") is False
    assert fresh_lowlevel().HAVE_SINCOS is False


def test_a_process_without_sincos_means_separate_calls(monkeypatch):
    class WithoutSincos:  # a C library with sin and cos only (macOS's libSystem, the UCRT)
        def __init__(self, name, *args, **kwargs):
            self.sin = self.cos = object()

    monkeypatch.setattr(ctypes, "CDLL", WithoutSincos)
    assert lowlevel.c_library_has_sincos("linux") is False
    monkeypatch.setattr(WithoutSincos, "sincos", object(), raising=False)
    assert lowlevel.c_library_has_sincos("linux") is True  # control: the lookup can say yes


def test_macos_and_windows_take_the_separate_calls_without_looking(monkeypatch):
    def must_not_be_called(*args, **kwargs):
        raise AssertionError("the C library was opened")

    monkeypatch.setattr(ctypes, "CDLL", must_not_be_called)
    for platform in ("darwin", "win32", "cygwin"):
        assert lowlevel.c_library_has_sincos(platform) is False
    with pytest.raises(AssertionError):  # control: the Linux branch does open it
        lowlevel.c_library_has_sincos("linux")


def test_sincos_is_called_only_where_the_jit_can_link_it():
    @numba.njit
    def first_compile(x):
        return x + 1.0

    first_compile(1.0)  # Numba's JIT exists now and has opened the process's symbols
    linked = llvm_binding.address_of_symbol("sincos") is not None
    assert not lowlevel.HAVE_SINCOS or linked
    if sys.platform.startswith("linux"):
        assert lowlevel.HAVE_SINCOS and linked
    # control: the linker's lookup does fail for a symbol that is not there
    assert llvm_binding.address_of_symbol("pendulum_lab_no_such_symbol") is None


# ---------------------------------------------------------------- the kernels' values there
def compiled_sincos():
    """A new compiled function (compiled under the module's flags as they are now)."""
    @numba.njit
    def paired(xs):
        out = np.empty((xs.size, 2))
        for i in range(xs.size):
            out[i, 0], out[i, 1] = lowlevel.sincos(xs[i])
        return out

    return paired


def test_without_sincos_the_values_are_the_c_librarys_sin_and_cos_to_the_bit(monkeypatch):
    xs = np.concatenate([np.random.default_rng(7).uniform(-10, 10, 4000),
                         np.linspace(2.3, 4.1, 1001), [np.pi, -np.pi, 3.0165786637849092]])
    separate = np.array([[math.sin(x), math.cos(x)] for x in xs])
    monkeypatch.setattr(lowlevel, "HAVE_SINCOS", False)
    monkeypatch.setattr(lowlevel, "SHIFT_NEAR_PI", False)
    np.testing.assert_array_equal(compiled_sincos()(xs), separate)
    # control: the shift, where it is taken (glibc), does change last bits near pi
    monkeypatch.setattr(lowlevel, "SHIFT_NEAR_PI", True)
    assert not np.array_equal(compiled_sincos()(xs), separate)


def test_compiled_steps_match_their_references_in_a_process_without_sincos(tmp_path):
    """The reference-step comparison (``tests/integrators/test_reference_steps.py``) for a
    few methods, in a new process whose C library lacks ``sincos`` (as on macOS and Windows),
    with kernel caches of its own so that nothing compiled with ``sincos`` is loaded."""
    prelude = textwrap.dedent("""
        import ctypes, sys
        real = ctypes.CDLL
        class WithoutSincos(real):
            def __getattr__(self, name):
                if name == "sincos":
                    raise AttributeError(name)
                return super().__getattr__(name)
        ctypes.CDLL = WithoutSincos
        from pendulum_lab.codegen import lowlevel
        assert lowlevel.HAVE_SINCOS is False and lowlevel.SHIFT_NEAR_PI is False
        ctypes.CDLL = real
        import pytest
        sys.exit(pytest.main(sys.argv[1:]))
    """)
    env = dict(os.environ, PENDULUM_LAB_CACHE=str(tmp_path / "kernels"),
               NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    # RK4 evaluates the kernels' sincos at every stage; glrk4's stage kernel has its own
    # sines (lane_sincos) beside the kernels' for the step's end
    test = "tests/integrators/test_reference_steps.py::test_compiled_step_is_the_reference_step"
    cases = [f"{test}[{case}]" for case in ("rk4-2", "glrk4-2")]
    done = subprocess.run(
        [sys.executable, "-c", prelude, "-q", "-p", "no:cacheprovider", *cases],
        cwd=REPO, env=env, capture_output=True, text=True, timeout=900, check=False)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
    assert "2 passed" in done.stdout
