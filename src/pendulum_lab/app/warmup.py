"""Compile every Numba kernel of the course ahead of time (``pendulum-lab warmup``).

Numba compiles each kernel the first time it runs on a machine (a few seconds
each) and keeps the machine code on disk. This module sits on top of the
layers so that it can reach every kernel: the vector fields and the step
functions of every registered method compiled into the time loop of each
field (:mod:`pendulum_lab.driver.loops`), the discrete Legendre transforms of the
variational methods, and the standard map's loop.

Three ways to run it: :func:`warm_up` in this process; ``pendulum-lab warmup`` from a shell
(a progress bar; ``--progress lines`` prints one line per job instead, for a program to read);
and from a notebook, :func:`warm_up_in_background` (a separate process, so the notebook stays
free, with :class:`BackgroundWarmUp` reporting its progress) or :func:`warm_up_offer` (a button
that starts it, with a progress bar).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .. import validation as check
from ..codegen.compile_status import listen
from ..codegen.kernels import chain_description
from ..driver.simulate import hamiltonian_field, simulate
from ..geometric.standard_map import first_crossings
from ..integrators import (
    CONFORMAL_METHODS,
    METHODS,
    VARIATIONAL_METHODS,
    get_method,
    unsuitability,
)
from ..model import driven_pendulum, n_pendulum

__all__ = [
    "BackgroundWarmUp",
    "Job",
    "warm_up",
    "warm_up_in_background",
    "warm_up_jobs",
    "warm_up_offer",
]

#: How ``pendulum-lab warmup --progress lines`` reports a job starting: ``done/total what``.
PROGRESS_LINE = re.compile(r"^(\d+)/(\d+) (.*)$")


@dataclass(frozen=True)
class Job:
    """One piece of the warm-up: ``run()`` compiles (or loads) what ``what`` names."""

    what: str
    run: Callable[[], None]


def _run_method(n: int, name: str) -> None:
    simulate(n_pendulum(n), np.full(n, 0.1), np.zeros(n), t_end=0.01, dt=0.01, method=name)


def _run_driven(name: str) -> None:
    driven = driven_pendulum()
    if unsuitability(get_method(name), hamiltonian_field(driven)) is None:
        simulate(driven, [0.1], [0.0], t_end=0.01, dt=0.01, method=name)


def warm_up_jobs(ns=(1, 2), methods=None) -> list[Job]:
    """What :func:`warm_up` does, job by job (arguments as there), in order.

    Each job runs one short simulation, which compiles (or loads) the field's kernels the
    first time and the method's time loop; a job of the damped, driven pendulum does
    nothing for a method that cannot integrate it.
    """
    everything = [*METHODS, *CONFORMAL_METHODS, *VARIATIONAL_METHODS]
    if isinstance(methods, str):
        methods = [methods]
    names = [get_method(m).name for m in (everything if methods is None else methods)]
    if isinstance(ns, (int, np.integer)) or not hasattr(ns, "__iter__"):
        raise TypeError(f"`ns` must be a sequence of chain lengths (numbers of links), such as "
                        f"[1, 2], got {ns!r}")
    ns = [check.integer_at_least("ns", n, 1) for n in ns]
    jobs = [Job(f"{name} for {chain_description(n)}", lambda n=n, name=name: _run_method(n, name))
            for n in ns for name in names]
    if 1 in ns:  # each (field, method) pair has its own compiled loop: the forced field too
        jobs += [Job(f"{name} for {chain_description(1, forced=True)}",
                     lambda name=name: _run_driven(name)) for name in names]
    if methods is None:
        jobs.append(Job("the standard map's loop",
                        lambda: first_crossings([1.0], [0.1], [0.0], 1)))
    return jobs


def warm_up(ns=(1, 2), methods=None, progress=True) -> float:
    """Compile now, or load from the disk cache, the kernels the course uses.

    Calling this ahead of time (``pendulum-lab warmup``; the Binder image does
    it while it is built) spares students the wait.

    Parameters
    ----------
    ns : sequence of int
        Chain lengths (numbers of links) to prepare: 1 the simple pendulum
        (and the driven pendulum's kernels), 2 the double pendulum, ...
    methods : sequence of str, optional
        Method names; all of :data:`pendulum_lab.METHODS`,
        ``CONFORMAL_METHODS`` and ``VARIATIONAL_METHODS`` by default. The
        standard map's kernel (notebook 15) is compiled too when all methods
        are.
    progress : bool or callable
        Show a progress bar (True), nothing (False), or call ``progress(done, total, what)``
        as each job starts (``done`` jobs finished before it) and ``progress(total, total,
        "")`` at the end. The notes of the compilations (:mod:`pendulum_lab.codegen.
        compile_status`) stay silent: the progress says what is compiled.

    Returns
    -------
    float
        Seconds spent.
    """
    jobs = warm_up_jobs(ns, methods)
    if progress is True:
        report = _bar(len(jobs))
    elif progress is False or progress is None:
        report = None
    elif callable(progress):
        report = progress
    else:
        raise TypeError(f"`progress` must be True, False or a callable, got {progress!r}")
    start = time.perf_counter()
    try:
        with listen(lambda event: None):
            for done, job in enumerate(jobs):
                if report is not None:
                    report(done, len(jobs), job.what)
                job.run()
        if report is not None:
            report(len(jobs), len(jobs), "")
    finally:
        if progress is True:
            report.close()
    return time.perf_counter() - start


def _bar(total: int):
    """A tqdm bar over the jobs that names the one running; call it like a progress callable."""
    from tqdm.auto import tqdm

    bar = tqdm(total=total, desc="compiling kernels", unit="kernel")

    def report(done, total, what):
        bar.n = done
        bar.set_postfix_str(what, refresh=False)
        bar.refresh()

    report.close = bar.close
    return report


# --------------------------------------------------------------------------- in the background
class BackgroundWarmUp:
    """``pendulum-lab warmup`` running in a separate process, and what it has done so far.

    Made by :func:`warm_up_in_background`. The process writes into the same kernel cache
    (``PENDULUM_LAB_CACHE`` is inherited), so whatever it has compiled, this process loads
    from disk instead of compiling; a kernel this process needs before the warm-up reached it
    is compiled here as usual (both write the cache atomically).

    Attributes
    ----------
    done, total : int
        Jobs finished and jobs in all (``total`` is 0 until the process has counted them).
    current : str
        The job running now ("glrk4 for the double pendulum"; empty at the end).
    returncode : int or None
        The process's exit status once it has ended.
    """

    def __init__(self, command: list[str], on_progress=None):
        self.command = command
        self.done, self.total, self.current = 0, 0, ""
        self.returncode: int | None = None
        self._on_progress = on_progress
        self._errors: list[str] = []
        # the child writes UTF-8 and this side reads it, whatever the locale (Windows' is
        # often cp1252)
        self._process = subprocess.Popen(command, stdout=subprocess.PIPE,
                                         stderr=subprocess.PIPE, text=True, encoding="utf-8",
                                         errors="replace", bufsize=1,
                                         env=os.environ | {"PYTHONIOENCODING": "utf-8"})
        self._threads = [threading.Thread(target=self._read, daemon=True,
                                          name="pendulum_lab warm-up"),
                         threading.Thread(target=self._read_errors, daemon=True,
                                          name="pendulum_lab warm-up errors")]
        for thread in self._threads:
            thread.start()

    def _read(self) -> None:
        for line in self._process.stdout:
            match = PROGRESS_LINE.match(line.rstrip("\n"))
            if match is None:
                continue
            self.done, self.total, self.current = int(match[1]), int(match[2]), match[3]
            self._tell()
        self.returncode = self._process.wait()
        for thread in self._threads[1:]:
            thread.join()
        self.current = ""
        self._tell()

    def _read_errors(self) -> None:
        for line in self._process.stderr:
            self._errors = (self._errors + [line.rstrip("\n")])[-20:]

    def _tell(self) -> None:
        if self._on_progress is not None:
            self._on_progress(self)

    @property
    def running(self) -> bool:
        """Whether the process is still going on (False once ``returncode`` is known)."""
        return self.returncode is None

    @property
    def error(self) -> str:
        """The last lines the process wrote to standard error (after a failure: why)."""
        return "\n".join(self._errors)

    def wait(self, timeout: float | None = None) -> int | None:
        """Wait for the end (at most ``timeout`` seconds); the exit status, or None."""
        self._threads[0].join(timeout)
        return self.returncode

    def stop(self) -> None:
        """End the warm-up process (what it compiled so far stays in the cache)."""
        if self._process.poll() is None:
            self._process.terminate()
        self.wait()

    def __repr__(self) -> str:
        state = ("running" if self.running else f"ended with status {self.returncode}")
        return f"<BackgroundWarmUp {self.done}/{self.total} jobs, {state}>"


def warm_up_in_background(ns=(1, 2), methods=None, on_progress=None) -> BackgroundWarmUp:
    """Start ``pendulum-lab warmup`` for ``ns`` and ``methods`` (as :func:`warm_up`) in a
    separate process at a low priority.

    ``on_progress(warmup)`` is called (from a reading thread) whenever a job starts and at
    the end, with the :class:`BackgroundWarmUp`. The notebook that started it stays free to
    run cells meanwhile.
    """
    ns = [check.integer_at_least("ns", n, 1) for n in ns]
    command = [sys.executable, "-m", "pendulum_lab", "warmup", "--progress", "lines",
               "--n", *map(str, ns)]
    if methods is not None:
        command += ["--methods", *(get_method(m).name for m in methods)]
    nice = shutil.which("nice")
    if nice is not None:  # the student's own cells come first
        command = [nice, "-n", "10", *command]
    return BackgroundWarmUp(command, on_progress)


def warm_up_offer(ns=(1, 2, 3), methods=None):
    """A button that warms up the course in the background, with a progress bar (ipywidgets).

    Nothing runs until the button is pressed; then :func:`warm_up_in_background` does the
    work (``ns`` and ``methods`` as :func:`warm_up`; by default every chain length the course
    uses, as the Binder image prepares them) and the bar, its label and the button
    say how far it is (the bar appears once pressed: a page without a kernel, such as the
    course website, shows no progress that cannot happen). The returned box's ``warmup`` is
    the :class:`BackgroundWarmUp` once started (None before).
    """
    import ipywidgets as widgets

    button = widgets.Button(description="Compile everything now, in the background",
                            icon="play", layout=widgets.Layout(width="auto"))
    bar = widgets.IntProgress(value=0, min=0, max=1, layout=widgets.Layout(width="20em"))
    label = widgets.Label("")
    progress = widgets.HBox([bar, label])

    def show(warmup: BackgroundWarmUp) -> None:
        bar.max = max(warmup.total, 1)
        bar.value = warmup.done
        if warmup.running:
            label.value = f"{warmup.done} of {warmup.total or '…'}: {warmup.current}"
            return
        if warmup.returncode == 0:
            bar.bar_style = "success"
            label.value = f"done: {warmup.total} kernels compiled or found on disk"
        else:
            bar.bar_style = "danger"
            last = warmup.error.splitlines()[-1:] or [f"status {warmup.returncode}"]
            label.value = f"the warm-up stopped: {last[0]}"
        button.description = "Compiled" if warmup.returncode == 0 else "Try again"
        button.disabled = warmup.returncode == 0

    def start(_button) -> None:
        button.disabled = True
        button.description = "Compiling in the background…"
        box.children = (button, progress)  # shown once there is progress to show
        bar.bar_style = ""
        box.warmup = warm_up_in_background(ns, methods, on_progress=show)

    button.on_click(start)
    box = widgets.VBox([button])
    box.warmup = None
    return box
