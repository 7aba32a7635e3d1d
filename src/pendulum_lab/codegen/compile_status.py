"""What the package is compiling, said while it compiles.

Numba compiles a kernel or a time loop the first time it is used on a machine and loads it from
the disk cache in later processes, which is much quicker. Every place that does either wraps
the work in :func:`compiling`, which tells two kinds of audience:

* **Listeners** (:func:`listen`): functions called with a :class:`Compilation` when a
  compilation starts and when it ends, in the thread that compiles, before the work begins
  and after it is done. An instrument that recomputes on a slider's change listens while it
  recomputes, so that it can say "compiling glrk4 for the double pendulum, once per
  machine…" in its own status area and mark its figure stale until the new picture arrives::

      with listen(lambda event: status_line.say(event.message)):
          trajectory = pl.simulate(...)

  A listener is called synchronously, so keep it quick (set a text, not draw a figure).
* **The note**: where no listener is open in the compiling thread, a one-line note says what is
  compiled once the work has lasted :data:`NOTE_DELAY` seconds, with the seconds elapsed,
  and at the end how long it took. In a Jupyter kernel it is a display in the running cell's
  output, updated in place; elsewhere a line on standard error. Quick loads say nothing.
  ``PENDULUM_LAB_COMPILE_NOTES=off`` in the environment silences the note (the site build
  and the notebook tests set it: the build machine's compile times are not course
  material); listeners are called regardless.

:func:`compile_seconds` counts the seconds a thread has spent compiling, so that a run can
report its compile time apart from its run time (``Trajectory.compile_time``). Nested
compilations (a kernel loaded while its time loop is prepared) count and speak once, as
the outermost.

What a compilation turned out to be is known at its end: the kernel cache
(:class:`~pendulum_lab.codegen.cache.KernelCache`) counts every kernel it loads and every one
Numba compiles (:func:`count_load`, :func:`count_compilation`). A compilation that compiled
nothing but loaded something ends as a load ("loaded ... from the disk cache"), whatever was
expected at its start; one that compiled anything ends as a compilation.
"""

from __future__ import annotations

import contextvars
import os
import sys
import threading
import time
import warnings
from collections.abc import Callable
from contextlib import contextmanager
from dataclasses import dataclass

__all__ = [
    "NOTES_VARIABLE",
    "NOTE_DELAY",
    "STATES",
    "Compilation",
    "compile_counts",
    "compile_seconds",
    "compiling",
    "count_compilation",
    "count_load",
    "listen",
]

#: Seconds a compilation lasts before the note appears (a quick load from disk says nothing).
NOTE_DELAY = 0.5
#: Seconds between updates of the elapsed time in the note.
NOTE_TICK = 0.5
#: The environment variable that silences the note when set to ``off``.
NOTES_VARIABLE = "PENDULUM_LAB_COMPILE_NOTES"
#: The states a :class:`Compilation` reports, in order.
STATES = ("started", "finished", "failed")


@dataclass(frozen=True)
class Compilation:
    """One compilation, as listeners see it.

    Attributes
    ----------
    what : str
        What is compiled, for people ("glrk4 for the double pendulum").
    loading : bool or None
        At the start: True when its machine code is expected in the disk cache (the
        generated source was there before), False when it is expected to compile, None when
        it is not known. At the end, what happened: True when kernels were loaded and none
        was compiled, False when one was compiled (the expectation when the cache saw
        neither).
    state : {"started", "finished", "failed"}
    seconds : float
        Seconds since it started (0 when ``state`` is ``"started"``).
    kept : bool
        Whether what is compiled is saved to the disk cache (False when no kernel cache can
        be written: it is then compiled for this session only).
    """

    what: str
    loading: bool | None
    state: str
    seconds: float = 0.0
    kept: bool = True

    @property
    def message(self) -> str:
        """One sentence for a status line.

        Examples
        --------
        >>> Compilation("rk4 for the simple pendulum", False, "started").message
        'compiling rk4 for the simple pendulum, once per machine…'
        >>> Compilation("rk4 for the simple pendulum", True, "finished", 0.31).message
        'loaded rk4 for the simple pendulum from the disk cache in 0.3 s'
        """
        what, seconds = self.what, self.seconds
        if self.state == "started":
            if self.loading:
                return f"loading {what} from the disk cache…"
            if self.loading is None:
                return f"preparing {what} (compiled once per machine, then loaded from disk)…"
            if not self.kept:
                return f"compiling {what} for this session (the kernel cache cannot be written)…"
            return f"compiling {what}, once per machine…"
        if self.state == "failed":
            return f"compiling {what} failed after {seconds:.1f} s"
        if self.loading:
            return f"loaded {what} from the disk cache in {seconds:.1f} s"
        if not self.kept:
            return f"compiled {what} in {seconds:.1f} s, for this session only"
        return (f"compiled {what} in {seconds:.1f} s (once per machine: from now on it loads "
                "from the disk cache)")


class _ThreadState(threading.local):
    def __init__(self):
        self.depth = 0
        self.seconds = 0.0
        self.compiled_seconds = 0.0  # of outermost compilations that compiled something
        self.loads = 0
        self.compilations = 0
        self.unsaved = 0
        self.listeners: list[Callable[[Compilation], None]] = []


_STATE = _ThreadState()


def compile_seconds(compiled_only: bool = False) -> float:
    """Seconds the calling thread has spent in compilations so far (outermost ones only);
    with ``compiled_only``, in those that compiled something (not only loaded).

    The difference of two readings is the compile time of the work between them.
    """
    return _STATE.compiled_seconds if compiled_only else _STATE.seconds


def compile_counts() -> tuple[int, int]:
    """``(loaded, compiled)``: kernels the calling thread has loaded from the disk cache and
    compiled so far (counted by the kernel cache)."""
    return _STATE.loads, _STATE.compilations


def count_load() -> None:
    """Called by the kernel cache when it has loaded a kernel's machine code from disk."""
    _STATE.loads += 1


def count_compilation() -> None:
    """Called by the kernel cache when Numba is about to compile a kernel (not in a cache)."""
    _STATE.compilations += 1


def count_unsaved() -> None:
    """Called by the kernel cache when what it compiled could not be saved (a full disk, a
    folder no longer writable): the compilation is then for this session only."""
    _STATE.unsaved += 1


@contextmanager
def listen(listener: Callable[[Compilation], None]):
    """Call ``listener(compilation)`` at the start and the end of every compilation that the
    calling thread does inside the block; the note stays silent meanwhile.

    A listener that raises is reported with a ``RuntimeWarning``; the compilation goes on.
    """
    if not callable(listener):
        raise TypeError(f"`listener` must be callable, got {type(listener).__name__}")
    _STATE.listeners.append(listener)
    try:
        yield listener
    finally:
        _STATE.listeners.remove(listener)


def _tell(listeners, event: Compilation) -> None:
    for listener in listeners:
        try:
            listener(event)
        except Exception as err:  # a status line's failure must not stop the compilation
            warnings.warn(f"a compilation listener failed on {event.state!r} of "
                          f"{event.what}: {err!r}", RuntimeWarning, stacklevel=4)


@contextmanager
def compiling(what: str, *, loading: bool | None = None, kept: bool = True):
    """Announce the compilation (or load from the disk cache) that the block does.

    Parameters
    ----------
    what : str
        What is compiled, for people: "glrk4 for the double pendulum".
    loading : bool or None
        Whether the machine code is expected in the disk cache (see :class:`Compilation`).
    kept : bool
        Whether it is saved to the disk cache (see :class:`Compilation`).

    Inside another compilation of the same thread the block is part of that one: it neither
    speaks nor counts separately.
    """
    if not isinstance(what, str) or not what.strip():
        raise TypeError("`what` must be a non-empty str naming what is compiled")
    state = _STATE
    if state.depth:
        state.depth += 1
        try:
            yield
        finally:
            state.depth -= 1
        return
    listeners = list(state.listeners)
    started = Compilation(what, loading, "started", kept=kept)
    note = None if listeners or _notes_off() else _Note(started)
    _tell(listeners, started)
    state.depth = 1
    counts = state.loads, state.compilations, state.unsaved
    start = time.perf_counter()
    ok = False
    try:
        yield
        ok = True
    finally:
        seconds = time.perf_counter() - start
        state.depth = 0
        state.seconds += seconds
        loaded, compiled = state.loads - counts[0], state.compilations - counts[1]
        outcome = False if compiled else (True if loaded else loading)
        if not outcome:
            state.compiled_seconds += seconds
        kept = kept and state.unsaved == counts[2]
        ended = Compilation(what, outcome, "finished" if ok else "failed", seconds, kept)
        if note is not None:
            note.close(ended)
        _tell(listeners, ended)


def _notes_off() -> bool:
    return os.environ.get(NOTES_VARIABLE, "").strip().lower() in ("off", "0", "no", "false")


def _in_jupyter_kernel() -> bool:
    """Whether this process is a Jupyter kernel (where a display updates in place)."""
    shell = sys.modules.get("IPython")
    if shell is None:
        return False
    ipython = shell.get_ipython()
    return getattr(ipython, "kernel", None) is not None


class _Note:
    """The one-line note of a compilation that nobody listens to (see the module docstring).

    A thread waits :data:`NOTE_DELAY` seconds; if the compilation is still running it shows
    the note and updates the elapsed time every :data:`NOTE_TICK` seconds. The thread runs in
    a copy of the caller's context, so that a Jupyter kernel puts the note into the cell that
    compiles.
    """

    def __init__(self, started: Compilation):
        self._started = started
        self._begin = time.perf_counter()
        self._done = threading.Event()
        self._shown = False
        self._width = 0  # of the text on a terminal's line, to overwrite it in full
        self._jupyter = _in_jupyter_kernel()
        self._display_id = f"pendulum-lab-compile-{id(self)}-{self._begin}"
        context = contextvars.copy_context()
        self._thread = threading.Thread(target=context.run, args=(self._tick,), daemon=True,
                                        name="pendulum_lab compile note")
        self._thread.start()

    def _tick(self) -> None:
        if self._done.wait(NOTE_DELAY):
            return
        self._show(self._started.message, first=True)
        while not self._done.wait(NOTE_TICK):
            self._show(f"{self._started.message} {time.perf_counter() - self._begin:.0f} s")

    def _show(self, text: str, first: bool = False, last: bool = False) -> None:
        if self._jupyter:
            from IPython.display import display, update_display

            bundle = {"text/plain": text}
            if first:
                display(bundle, raw=True, display_id=self._display_id)
            else:
                update_display(bundle, raw=True, display_id=self._display_id)
        else:
            stream = sys.stderr
            live = stream.isatty()
            if live:  # one line, rewritten in place
                stream.write("\r" + text.ljust(self._width) + ("\n" if last else ""))
                self._width = len(text)
            elif first or last:  # a log: the start and the outcome
                stream.write(text + "\n")
            stream.flush()
        self._shown = True

    def close(self, ended: Compilation) -> None:
        """Stop the updates; if the note was shown, end it with the outcome."""
        self._done.set()
        self._thread.join()
        if self._shown:
            self._show(ended.message, last=True)
