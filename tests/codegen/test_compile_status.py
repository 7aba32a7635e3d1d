"""Compilations said while they happen: listeners, the note, the compile time apart.

A compilation is made by running a generated module that sleeps (as a Numba compile would
take its time), so that the timing of the note is under the test's control; the time loop of a
real method on a small field made here checks that a loop is compiled when it is made, never
on its first run.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import time
import types

import numba
import numpy as np
import pytest

from pendulum_lab.codegen import cache, compile_status
from pendulum_lab.codegen.compile_status import Compilation, compile_seconds, compiling, listen
from pendulum_lab.driver.loops import compile_method
from pendulum_lab.integrators import HamiltonianField, get_method


@pytest.fixture
def fresh_cache(tmp_path, monkeypatch):
    """An empty kernel cache, the note switched on and quick to appear."""
    monkeypatch.setenv("PENDULUM_LAB_CACHE", str(tmp_path))
    monkeypatch.delenv(compile_status.NOTES_VARIABLE, raising=False)
    monkeypatch.setattr(compile_status, "NOTE_DELAY", 0.05)
    monkeypatch.setattr(compile_status, "NOTE_TICK", 0.05)
    yield tmp_path
    for name in [n for n in sys.modules if "status_test" in n]:
        del sys.modules[name]


def slow_source(seconds: float, tag: str) -> str:
    return f"import time\ntime.sleep({seconds})\nVALUE = {tag!r}\n"


def source_lasting_until(condition: str, tag: str) -> str:
    """A module that runs until ``condition`` holds (at most 60 s): a compilation that lasts
    until its note has been seen, however late a busy machine runs the note's thread."""
    return (f"import sys, time\nend = time.monotonic() + 60\n"
            f"while not ({condition}) and time.monotonic() < end:\n    time.sleep(0.01)\n"
            f"VALUE = {tag!r}\n")


def test_listeners_hear_the_start_and_the_end(fresh_cache):
    events = []
    with listen(events.append):
        cache.load_generated("status_test_a", slow_source(0.1, "a"), what="a test module")
    assert [e.state for e in events] == ["started", "finished"]
    assert {e.what for e in events} == {"a test module"}
    assert events[0].loading is False and events[0].seconds == 0.0
    assert events[1].seconds >= 0.1
    assert events[0].message == "compiling a test module, once per machine…"


def test_the_second_load_of_a_file_is_announced_as_a_load(fresh_cache):
    source = slow_source(0.0, "b")
    module, _ = cache.load_generated("status_test_b", source, what="a test module")
    del sys.modules[module.__name__]  # as in a new session: the file is on disk
    events = []
    with listen(events.append):
        cache.load_generated("status_test_b", source, what="a test module")
    assert events[0].loading is True
    assert events[1].message.startswith("loaded a test module from the disk cache in ")
    # negative control: a module already in this session is neither compiled nor announced
    with listen(events.append):
        cache.load_generated("status_test_b", source, what="a test module")
    assert len(events) == 2


def test_nested_compilations_speak_and_count_once():
    events = []
    before = compile_seconds()
    with listen(events.append):
        with compiling("the outer work"):
            with compiling("the inner work"):
                time.sleep(0.05)
    spent = compile_seconds() - before
    assert [(e.what, e.state) for e in events] == [("the outer work", "started"),
                                                   ("the outer work", "finished")]
    assert spent == pytest.approx(events[1].seconds)
    # negative control: two compilations one after the other count twice
    with listen(events.append):
        with compiling("first"):
            time.sleep(0.01)
        with compiling("second"):
            time.sleep(0.01)
    assert [e.what for e in events[2:]] == ["first", "first", "second", "second"]


def test_a_failed_compilation_is_reported_and_raises():
    events = []
    with pytest.raises(ZeroDivisionError), listen(events.append), compiling("a broken kernel"):
        raise ZeroDivisionError("a kernel that does not compile")
    assert [e.state for e in events] == ["started", "failed"]
    assert events[1].message.startswith("compiling a broken kernel failed after ")


def test_a_failing_listener_warns_and_the_compilation_goes_on():
    def broken(event):
        raise RuntimeError("the status line is gone")

    with pytest.warns(RuntimeWarning, match="the status line is gone"), listen(broken):
        with compiling("a kernel"):
            done = True
    assert done


def test_bad_arguments_are_refused():
    with pytest.raises(TypeError, match="`listener`"), listen("print"):
        pass
    with pytest.raises(TypeError, match="`what`"), compiling(""):
        pass


# ------------------------------------------------------------------------------- the note
def test_the_note_says_what_compiles_after_the_delay(fresh_cache, capsys, monkeypatch):
    shown = "'compiling a slow test module' in sys.stderr.getvalue()"  # capsys's stream
    cache.load_generated("status_test_c", source_lasting_until(shown, "c"),
                         what="a slow test module")
    err = capsys.readouterr().err.splitlines()
    assert err[0] == "compiling a slow test module, once per machine…"
    assert err[-1].startswith("compiled a slow test module in ")
    # negative control: a compilation that ends before the delay says nothing (a delay far
    # beyond it, so that a loaded machine cannot make the quick one slow)
    monkeypatch.setattr(compile_status, "NOTE_DELAY", 60.0)
    cache.load_generated("status_test_d", slow_source(0.0, "d"), what="a quick test module")
    assert capsys.readouterr().err == ""


def test_a_listener_or_the_switch_silences_the_note(fresh_cache, capsys, monkeypatch):
    with listen(lambda event: None):
        cache.load_generated("status_test_e", slow_source(0.3, "e"), what="a test module")
    assert capsys.readouterr().err == ""
    monkeypatch.setenv(compile_status.NOTES_VARIABLE, "off")
    cache.load_generated("status_test_f", slow_source(0.3, "f"), what="a test module")
    assert capsys.readouterr().err == ""


def test_in_a_jupyter_kernel_the_note_is_one_display_updated_in_place(fresh_cache, monkeypatch):
    shown = []
    display_module = types.SimpleNamespace(
        display=lambda bundle, raw, display_id: shown.append(("new", display_id,
                                                               bundle["text/plain"])),
        update_display=lambda bundle, raw, display_id: shown.append(("update", display_id,
                                                                     bundle["text/plain"])),
    )
    kernel_shell = types.SimpleNamespace(kernel=object())
    fake_ipython = types.SimpleNamespace(get_ipython=lambda: kernel_shell,
                                         display=display_module)
    monkeypatch.setitem(sys.modules, "IPython", fake_ipython)
    monkeypatch.setitem(sys.modules, "IPython.display", display_module)
    display_module.shown = shown
    updated = "len(sys.modules['IPython.display'].shown) >= 2"  # shown, then updated once
    cache.load_generated("status_test_g", source_lasting_until(updated, "g"),
                         what="a test module")
    kinds = [kind for kind, _, _ in shown]
    assert kinds[0] == "new" and set(kinds[1:]) == {"update"} and len(kinds) >= 3
    assert len({display_id for _, display_id, _ in shown}) == 1
    assert shown[0][2] == "compiling a test module, once per machine…"
    assert shown[1][2].startswith("compiling a test module, once per machine… ")
    assert shown[-1][2].startswith("compiled a test module in ")


def test_messages_for_each_expectation():
    what = "glrk4 for the double pendulum"
    assert Compilation(what, None, "started").message.startswith(f"preparing {what} ")
    assert Compilation(what, True, "started").message == (
        f"loading {what} from the disk cache…")
    assert "once per machine" in Compilation(what, False, "finished", 12.34).message
    assert "12.3 s" in Compilation(what, False, "finished", 12.34).message


# ------------------------------------------------------------------------------- time loops
OSCILLATOR = '''\
from pendulum_lab.codegen.cache import cached_njit
from pendulum_lab.codegen.signatures import ACCELERATION, HAMILTON


@cached_njit(HAMILTON)
def hamilton(t, q, p, params, dq, dp):
    dq[0] = p[0]
    dp[0] = -params[0] * q[0]


@cached_njit(ACCELERATION)
def acceleration(t, q, v, params, out):
    out[0] = -params[0] * q[0]
'''


def test_a_time_loop_is_compiled_when_made_and_never_when_run(fresh_cache):
    module, _ = cache.load_generated("status_test_oscillator", OSCILLATOR, what="an oscillator")
    field = HamiltonianField(module.hamilton, module.acceleration, np.array([4.0]), True,
                             name="a test oscillator")
    euler = get_method("explicit_euler")
    events = []
    with listen(events.append):
        compiled = compile_method(euler, field, 1)
    assert [(e.what, e.state, e.loading) for e in events] == [
        ("explicit_euler for a test oscillator", "started", False),
        ("explicit_euler for a test oscillator", "finished", False)]
    assert len(compiled.run.signatures) == 1  # compiled already, before any run
    q, p = np.array([[1.0]]), np.array([[0.0]])
    saved = np.zeros((1, 2, 1))
    stats = np.zeros((1, 4), dtype=np.int64)
    before = compile_seconds()
    with listen(events.append):
        compiled.advance(q, p, 0.1, 1, 0, 1, saved, saved.copy(), stats, compiled.new_memory(1))
    assert len(events) == 2 and compile_seconds() == before
    assert len(compiled.run.signatures) == 1
    # one explicit Euler step of q'' = -4 q from (1, 0): (q, p) = (1, -0.4)
    assert (q[0, 0], p[0, 0]) == pytest.approx((1.0, -0.4), abs=1e-15)


def test_a_plain_numba_function_compiles_on_its_first_call():
    # negative control of the check above: without a signature nothing is compiled beforehand
    @numba.njit
    def lazy(x):
        return x + 1

    assert len(lazy.signatures) == 0
    lazy(1.0)
    assert len(lazy.signatures) == 1


def test_a_run_reports_its_compile_time_apart_from_its_run_time(tmp_path):
    # a fresh process: the model's kernels and the loop are loaded (or compiled) once there
    script = textwrap.dedent("""\
        import json
        import pendulum_lab as pl
        from pendulum_lab.codegen.compile_status import listen
        events = []
        model = pl.simple_pendulum()
        with listen(events.append):
            first = pl.simulate(model, [1.0], [0.0], t_end=1.0, dt=0.01, method="rk4")
            second = pl.simulate(model, [1.0], [0.0], t_end=1.0, dt=0.01, method="rk4")
        print(json.dumps({"first": first.compile_time, "second": second.compile_time,
                          "events": [[e.what, e.state, e.seconds] for e in events]}))
        """)
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                            env={**os.environ}, timeout=900, check=False)
    assert result.returncode == 0, result.stderr
    found = json.loads(result.stdout)
    ended = [seconds for _, state, seconds in found["events"] if state == "finished"]
    assert [what for what, state, _ in found["events"] if state == "started"] == [
        "the vector field of the simple pendulum", "rk4 for the simple pendulum"]
    assert found["first"] == pytest.approx(sum(ended)) and found["first"] > 0
    assert found["second"] == 0.0
