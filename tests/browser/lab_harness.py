"""Harness that runs the course notebooks in a real JupyterLab inside a real Chromium.

Used by ``conftest.py`` (fixtures) and ``test_jupyterlab.py`` (tests); kept out of the conftest
so that the test module can import it by name.

One JupyterLab server and one Chromium serve all the browser tests (stopped after the last of
them, ``conftest.py``). The server works on a temporary copy of the notebook folder, with its
own settings, workspaces, config, data and runtime folders, so neither the repository nor the
home directory is written to. Each notebook gets one new browser page; the tests of one
notebook run one after the other on that page (the collection hook in conftest.py groups them),
and the page and its kernel are shut down before the next notebook is opened.

Environment variables
---------------------
PENDULUM_LAB_NOTEBOOKS
    Folder of notebooks to test instead of ``notebooks/`` (used to prove the harness on
    throwaway fixture notebooks).
PENDULUM_LAB_BROWSER_TIMEOUT
    Seconds allowed for "run all cells" of one notebook (default 240).
CI
    When it is ``true``, a missing Chromium or Playwright makes the browser tests fail instead
    of being skipped.
"""

from __future__ import annotations

import contextlib
import functools
import http.server
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request
from dataclasses import dataclass, field
from pathlib import Path
from urllib.parse import quote

import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
ARTIFACTS = REPO_ROOT / "test-artifacts" / "browser"
SCREENSHOTS = ARTIFACTS / "screenshots"
TIMINGS = ARTIFACTS / "timings.json"

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]
VIEWPORT = {"width": 1400, "height": 1000}
# Tallest viewport used for a whole-notebook screenshot (Chromium limits texture sizes).
MAX_SCREENSHOT_HEIGHT = 16000

# Per-user JupyterLab settings written into the temporary settings folder: render every cell
# (no windowing, so the DOM holds the whole notebook), no empty space after the last cell, no
# news or update checks (no network here), no extension manager, no autosave.
LAB_SETTINGS = {
    "@jupyterlab/notebook-extension/tracker": {"windowingMode": "none", "scrollPastEnd": False},
    "@jupyterlab/apputils-extension/notification": {
        "fetchNews": "false",
        "checkForUpdates": False,
    },
    "@jupyterlab/extensionmanager-extension/plugin": {"enabled": False},
    "@jupyterlab/docmanager-extension/plugin": {"autosave": False},
}

# Marker convention, see test_jupyterlab.py: the cell metadata {"pendulum_lab": {"expect": [...]}}.
EXPECT_KINDS = ("figure", "widget")

# ---------------------------------------------------------------------------------------------
# Availability policy
# ---------------------------------------------------------------------------------------------


def in_ci() -> bool:
    return os.environ.get("CI", "").strip().lower() == "true"


def skip_or_fail(reason: str) -> None:
    """Skip with ``reason``; under ``CI=true`` fail with it instead (CI must run the test)."""
    if in_ci():
        pytest.fail(f"{reason} (CI=true: this test must run in CI)", pytrace=False)
    pytest.skip(reason)


def chromium_path() -> str | None:
    if os.access(CHROMIUM, os.X_OK):
        return CHROMIUM
    return shutil.which("chromium")


def browser_unavailable_reason() -> str | None:
    """Why the browser tests cannot run here, or None when they can."""
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError as exc:
        return f"Playwright for Python is not importable ({exc}); pip install playwright"
    if chromium_path() is None:
        # Debian's Chromium is what these tests are run with; elsewhere say so, not apt-get
        hint = ("apt-get install -y chromium" if sys.platform.startswith("linux")
                else "put a Chromium executable named `chromium` on PATH")
        return f"Chromium not found at {CHROMIUM} nor on PATH; {hint}"
    return None


def notebook_dir() -> Path:
    override = os.environ.get("PENDULUM_LAB_NOTEBOOKS")
    return Path(override).resolve() if override else REPO_ROOT / "notebooks"


def list_notebooks() -> list[str]:
    """File names of the notebooks to test (top level of the notebook folder, sorted)."""
    folder = notebook_dir()
    if not folder.is_dir():
        return []
    return sorted(p.name for p in folder.glob("*.ipynb"))


def run_all_timeout() -> float:
    return float(os.environ.get("PENDULUM_LAB_BROWSER_TIMEOUT", "240"))


def parse_expectations(annotations: dict) -> tuple[set[str], list[str]]:
    """Return (expected kinds, unknown words) from a cell's ``pendulum_lab`` metadata."""
    words = annotations.get("expect", []) if isinstance(annotations, dict) else []
    if isinstance(words, str):
        words = [words]
    kinds = {word for word in words if word in EXPECT_KINDS}
    return kinds, [word for word in words if word not in EXPECT_KINDS]


# ---------------------------------------------------------------------------------------------
# JupyterLab server
# ---------------------------------------------------------------------------------------------


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):  # the tests report what matters
        pass


@contextlib.contextmanager
def serve(folder: Path):
    """Serve ``folder`` on 127.0.0.1 at a free port; yields the base URL (the website's pages,
    the package's static folder)."""
    handler = functools.partial(_QuietHandler, directory=str(folder))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def _descendants(pid: int) -> list[int]:
    """Every process below ``pid`` (kernels run in sessions of their own, not our group).

    psutil (installed with IPython and ipykernel) asks each system its own way; without it,
    Linux's ``/proc``; elsewhere none are found, and only the server itself is stopped.
    """
    try:
        import psutil
    except ImportError:
        psutil = None
    if psutil is not None:
        with contextlib.suppress(psutil.Error):
            return [child.pid for child in psutil.Process(pid).children(recursive=True)]
        return []
    children: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        with contextlib.suppress(OSError, ValueError, IndexError):
            text = stat.read_text(encoding="utf-8", errors="replace")
            ppid = int(text.rsplit(")", 1)[1].split()[1])
            children.setdefault(ppid, []).append(int(stat.parent.name))
    found, todo = [], [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            found.append(child)
            todo.append(child)
    return found


def new_process_group() -> dict:
    """``Popen`` arguments that start a process in a group of its own, on any system."""
    if sys.platform == "win32":
        return {"creationflags": subprocess.CREATE_NEW_PROCESS_GROUP}
    return {"start_new_session": True}


def _end_group(process: subprocess.Popen, force: bool) -> None:
    """Terminate (or with ``force`` kill) ``process`` and its group where groups can be
    signalled (POSIX's ``killpg``), else the process alone (Windows)."""
    with contextlib.suppress(ProcessLookupError, PermissionError, OSError):
        if hasattr(os, "killpg"):
            os.killpg(process.pid, signal.SIGKILL if force else signal.SIGTERM)
        elif force:
            process.kill()
        else:
            process.terminate()


def _kill(pid: int) -> None:
    """Kill one process by its id (Windows has no SIGKILL; its os.kill terminates)."""
    with contextlib.suppress(ProcessLookupError, PermissionError, OSError):
        os.kill(pid, getattr(signal, "SIGKILL", signal.SIGTERM))


def stop_process_tree(process: subprocess.Popen, polite=None, waits=(15, 10, 5)) -> None:
    """Stop ``process`` and everything it started: ``polite()`` first (for instance a
    shutdown request), then terminate, then kill, each followed by a wait; last, every
    descendant found before the first step is killed (kernels start sessions of their own)."""
    if process.poll() is None:
        spawned = _descendants(process.pid)
        if polite is not None:
            polite()
        for step, wait in zip((None, False, True), waits, strict=True):
            if step is not None:
                _end_group(process, force=step)
            with contextlib.suppress(subprocess.TimeoutExpired):
                process.wait(timeout=wait)
                break
        for pid in spawned:
            _kill(pid)
    process.wait(timeout=5)


@dataclass
class LabServer:
    url: str
    root: Path
    log: Path
    process: subprocess.Popen

    def api(self, method: str, path: str, body: dict | None = None, timeout: float = 10):
        data = None if body is None else json.dumps(body).encode()
        request = urllib.request.Request(self.url + path, data=data, method=method)
        with urllib.request.urlopen(request, timeout=timeout) as response:
            payload = response.read()
        return json.loads(payload) if payload else None

    def log_tail(self, chars: int = 3000) -> str:
        with contextlib.suppress(OSError):
            return self.log.read_text(encoding="utf-8", errors="replace")[-chars:]
        return ""

    def shutdown_kernels_of(self, path: str) -> None:
        with contextlib.suppress(OSError, urllib.error.URLError, ValueError):
            for session in self.api("GET", "/api/sessions"):
                if session.get("path") == path:
                    self.api("DELETE", f"/api/sessions/{session['id']}")

    def stop(self) -> None:
        def shutdown_request():
            # Polite first: the server shuts its kernels down and exits.
            with contextlib.suppress(OSError, urllib.error.URLError, ValueError):
                self.api("POST", "/api/shutdown", timeout=5)

        stop_process_tree(self.process, shutdown_request)


#: The setting that saves the widgets' state with a notebook (JupyterLab's default is not to).
SAVE_WIDGET_STATE = {"@jupyter-widgets/jupyterlab-manager/plugin": {"saveState": True}}


def start_lab(workdir: Path, notebooks: Path, save_widget_state: bool = False) -> LabServer:
    root = workdir / "notebooks"
    shutil.copytree(notebooks, root, ignore=shutil.ignore_patterns(".ipynb_checkpoints"))
    settings = workdir / "lab-settings"
    chosen = {**LAB_SETTINGS, **(SAVE_WIDGET_STATE if save_widget_state else {})}
    for plugin, values in chosen.items():
        target = settings / f"{plugin}.jupyterlab-settings"
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(json.dumps(values), encoding="utf-8")
    env = dict(os.environ)
    for var, sub in (
        ("JUPYTER_CONFIG_DIR", "jupyter-config"),
        ("JUPYTER_DATA_DIR", "jupyter-data"),
        ("JUPYTER_RUNTIME_DIR", "jupyter-runtime"),
        ("IPYTHONDIR", "ipython"),
        ("MPLCONFIGDIR", "matplotlib"),
        # jupyter-lsp asks npm for its global prefix at start-up; npm logs into its cache.
        ("npm_config_cache", "npm-cache"),
    ):
        (workdir / sub).mkdir()
        env[var] = str(workdir / sub)
    # The runs' outputs become the website's (tests/site takes them): no notes of this
    # machine's compile times in them, as in the site's own build. The note itself is tested
    # in its own notebook, which switches it back on (compile_demo/).
    env["PENDULUM_LAB_COMPILE_NOTES"] = "off"
    env.pop("JUPYTER_PATH", None)
    env.pop("JUPYTER_CONFIG_PATH", None)
    port = _free_port()
    cmd = [
        sys.executable,
        "-m",
        "jupyterlab",
        "--no-browser",
        "--allow-root",
        "--ServerApp.ip=127.0.0.1",
        f"--ServerApp.port={port}",
        "--ServerApp.port_retries=0",
        "--IdentityProvider.token=",
        "--ServerApp.disable_check_xsrf=True",
        f"--ServerApp.root_dir={root}",
        "--LabApp.expose_app_in_browser=True",
        f"--LabApp.user_settings_dir={settings}",
        f"--LabApp.workspaces_dir={workdir / 'lab-workspaces'}",
        "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate",
    ]
    log = workdir / "jupyterlab.log"
    with log.open("wb") as sink:
        process = subprocess.Popen(
            cmd,
            cwd=workdir,
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=sink,
            stderr=subprocess.STDOUT,
            **new_process_group(),
        )
    server = LabServer(url=f"http://127.0.0.1:{port}", root=root, log=log, process=process)
    deadline = time.monotonic() + 90
    while True:
        if process.poll() is not None:
            raise RuntimeError(
                f"JupyterLab exited with code {process.returncode}:\n{server.log_tail()}"
            )
        with contextlib.suppress(OSError, urllib.error.URLError, ValueError):
            server.api("GET", "/api/status", timeout=2)
            urllib.request.urlopen(server.url + "/lab", timeout=5).close()
            return server
        if time.monotonic() > deadline:
            server.stop()
            raise RuntimeError(f"JupyterLab did not answer within 90 s:\n{server.log_tail()}")
        time.sleep(0.3)


# ---------------------------------------------------------------------------------------------
# Page-side helpers (installed in every page before JupyterLab loads)
# ---------------------------------------------------------------------------------------------

# Close every notebook in the main area without the "save your changes?" dialog (the runs
# leave them modified); true when JupyterLab is there to open the next one.
CLOSE_NOTEBOOKS = """
() => {
  const app = window.jupyterapp;
  if (!app || !app.shell) return false;
  for (const widget of Array.from(app.shell.widgets('main'))) {
    if (widget.context && widget.context.model) widget.context.model.dirty = false;
    widget.dispose();
  }
  return true;
}
"""
OPEN_NOTEBOOK = """
(path) => { window.jupyterapp.commands.execute('docmanager:open', {path}); return 1; }
"""

PAGE_HELPERS = r"""
window.__plab = {
  panel(path) {
    const app = window.jupyterapp;
    if (!app || !app.shell) return null;
    for (const w of app.shell.widgets('main')) {
      if (w.context && w.context.path === path && w.content && w.content.widgets) return w;
    }
    return null;
  },
  state(path) {
    const p = this.panel(path);
    if (!p) return {status: 'no-notebook', dialog: !!document.querySelector('.jp-Dialog')};
    const sc = p.sessionContext;
    const kernel = sc && sc.session && sc.session.kernel;
    const bar = document.querySelector('#jp-main-statusbar');
    return {
      status: kernel ? sc.kernelDisplayStatus : 'no-kernel',
      ready: p.context.isReady,
      statusBar: bar ? bar.innerText.replace(/\s+/g, ' ') : '',
      dialog: !!document.querySelector('.jp-Dialog'),
      busyCount: (this.busy[path] || 0),
      deaths: (this.deaths[path] || 0),
    };
  },
  busy: {},
  deaths: {},
  // Count the kernel's busy phases (to see that an action reached it) and its deaths.
  watch(path) {
    const p = this.panel(path);
    if (!p || p.__plabWatched) return;
    p.__plabWatched = true;
    this.busy[path] = 0;
    this.deaths[path] = 0;
    p.sessionContext.statusChanged.connect((_, status) => {
      if (status === 'busy') this.busy[path] += 1;
      if (['dead', 'restarting', 'autorestarting'].includes(status)) this.deaths[path] += 1;
    });
  },
  visible(el) {
    const r = el.getBoundingClientRect();
    const s = getComputedStyle(el);
    if (r.width < 2 || r.height < 2 || s.visibility === 'hidden' || s.display === 'none') {
      return false;
    }
    if (el.tagName === 'IMG') return el.complete && el.naturalWidth > 0;
    return true;
  },
  isControlPart(el) {
    return !!el.closest('.widget-inline-hbox, button, .jp-OutputArea-promptOverlay');
  },
  // Figures: visible img/canvas/svg of at least 24 x 24 px inside an output (not icons such
  // as the "collapse output" overlay, not parts of sliders, dropdowns or buttons).
  figuresIn(root) {
    return Array.from(root.querySelectorAll('img, canvas, svg'))
      .filter((el) => el.closest('.jp-OutputArea-output'))
      .filter((el) => !el.hasAttribute('data-icon') && !el.closest('[data-icon]'))
      .filter((el) => !(el.tagName.toLowerCase() === 'svg' && el.parentElement.closest('svg')))
      .filter((el) => {
        const r = el.getBoundingClientRect();
        return r.width >= 24 && r.height >= 24;
      })
      .filter((el) => this.visible(el) && !this.isControlPart(el));
  },
  cells(path) {
    const p = this.panel(path);
    if (!p) return null;
    return p.content.widgets.map((cell, index) => {
      const model = cell.model;
      const info = {index, type: model.type, source: model.sharedModel.getSource(),
                    annotations: model.getMetadata('pendulum_lab') || {}};
      if (model.type !== 'code') return info;
      const prompt = cell.node.querySelector('.jp-InputArea-prompt');
      info.executionCount = model.executionCount;
      info.prompt = prompt ? prompt.textContent.trim() : '';
      const outputs = model.outputs.toJSON();
      info.errors = outputs.filter((o) => o.output_type === 'error')
        .map((o) => `${o.ename}: ${o.evalue}`);
      const area = cell.node.querySelector('.jp-Cell-outputArea') || cell.node;
      for (const el of area.querySelectorAll(
          '[data-mime-type="application/vnd.jupyter.error"]')) {
        info.errors.push(el.textContent.slice(0, 800));
      }
      info.outputText = Array.from(area.querySelectorAll('.jp-OutputArea-output'))
        .map((el) => el.textContent).join('\n');
      info.figures = this.figuresIn(area).length;
      info.widgets = Array.from(area.querySelectorAll('.jupyter-widgets'))
        .filter((el) => this.visible(el)).length;
      return info;
    });
  },
  contentHeight(path) {
    const p = this.panel(path);
    if (!p) return 0;
    const scroller = p.content.node.querySelector('.jp-WindowedPanel-outer') || p.content.node;
    return scroller.scrollHeight + (window.innerHeight - scroller.clientHeight);
  },
  // Tag the first visible control matching `selector` (and, for sliders, with an editable
  // readout) and the figure nearest to it; returns a description or null.
  tagControl(path, selector, needsEditableReadout) {
    const p = this.panel(path);
    if (!p) return null;
    for (const el of document.querySelectorAll('[data-plab-control], [data-plab-target]')) {
      el.removeAttribute('data-plab-control');
      el.removeAttribute('data-plab-target');
    }
    const controls = Array.from(p.content.node.querySelectorAll(selector))
      .filter((el) => this.visible(el));
    for (const control of controls) {
      const readout = control.querySelector('.widget-readout');
      if (needsEditableReadout && !(readout && readout.isContentEditable)) continue;
      control.setAttribute('data-plab-control', '1');
      const cell = control.closest('.jp-Cell');
      const cellIndex = p.content.widgets.findIndex((c) => c.node === cell);
      const retagged = this.retarget(path);
      return {cellIndex, target: retagged};
    }
    return null;
  },
  // (Re)tag the figure nearest to the tagged control: the first visible img/canvas/svg after
  // the control in the same cell's output, else the first before it, else the cell's output
  // area (then the control itself is masked in screenshots).
  retarget(path) {
    const control = document.querySelector('[data-plab-control]');
    if (!control) return null;
    for (const el of document.querySelectorAll('[data-plab-target]')) {
      el.removeAttribute('data-plab-target');
    }
    const cell = control.closest('.jp-Cell');
    const area = cell.querySelector('.jp-Cell-outputArea') || cell;
    const figures = this.figuresIn(area);
    const after = figures.filter(
      (f) => control.compareDocumentPosition(f) & Node.DOCUMENT_POSITION_FOLLOWING);
    const chosen = after[0] || figures[0];
    if (chosen) {
      chosen.setAttribute('data-plab-target', '1');
      return chosen.tagName.toLowerCase();
    }
    area.setAttribute('data-plab-target', '1');
    return 'output-area';
  },
  // Scroll the tagged target into view and return its kind and box in page pixels.
  targetBox(path) {
    const kind = this.retarget(path);
    const el = document.querySelector('[data-plab-target]');
    if (!el) return null;
    el.scrollIntoView({block: 'center', inline: 'nearest'});
    const r = el.getBoundingClientRect();
    return {kind, x: r.x, y: r.y, width: r.width, height: r.height};
  },
};
"""


# ---------------------------------------------------------------------------------------------
# Running one notebook
# ---------------------------------------------------------------------------------------------


@dataclass
class NotebookRun:
    """What happened when one notebook was opened and run in the browser."""

    name: str
    page: object
    seconds: float | None = None
    finished: bool = False
    problems: list[str] = field(default_factory=list)
    cells: list[dict] = field(default_factory=list)
    screenshot: Path | None = None
    console_errors: list[str] = field(default_factory=list)
    #: After a clean run: the notebook as JupyterLab holds it (nbformat's JSON), outputs and all.
    model: dict | None = None

    @property
    def ok(self) -> bool:
        return self.finished and not self.problems

    def report(self) -> str:
        lines = [f"{self.name}: " + ("; ".join(self.problems) or "no problems")]
        if self.screenshot:
            lines.append(f"screenshot: {self.screenshot}")
        if self.console_errors:
            lines.append("browser console errors:\n  " + "\n  ".join(self.console_errors[:10]))
        return "\n".join(lines)


class NotebookRunner:
    """Opens notebooks one at a time and runs all their cells once.

    JupyterLab and Chromium are started on the first ``get`` (inside a test, so that a missing
    browser under ``CI=true`` is reported as that test's failure) and stopped by ``close``.
    The first notebook opens JupyterLab in a page; each next one opens in the same page once
    the previous is closed and its kernel shut down (JupyterLab's front end takes seconds to
    start, once per page). A page that crashed or closed is replaced by a new one.
    """

    def __init__(self, make_workdir, executions: dict | None = None):
        self._make_workdir = make_workdir
        #: With a dict: name -> (the notebook as JupyterLab holds it after a clean run-all,
        #: saved with its widgets' state, by which the website's build tells progress bars
        #: apart; and the run's seconds). Without, notebooks are saved as JupyterLab's default
        #: saves them, without widget state.
        self.executions = executions
        self._start_error: str | None = None
        self._playwright = None
        self.browser = None
        self.server: LabServer | None = None
        self.context = None
        self.current: NotebookRun | None = None

    def start(self) -> None:
        reason = browser_unavailable_reason()
        if reason is not None:
            skip_or_fail(reason)
        if self._start_error is not None:
            pytest.fail(f"browser harness failed to start: {self._start_error}", pytrace=False)
        if self.context is not None:
            return
        try:
            workdir = self._make_workdir()
            self.server = start_lab(workdir, notebook_dir(),
                                    save_widget_state=self.executions is not None)
            from playwright.sync_api import sync_playwright

            # Chromium's profile is a temporary one of Playwright's; its caches go here too.
            xdg = workdir / "chromium-xdg"
            xdg.mkdir()
            env = dict(os.environ, XDG_CONFIG_HOME=str(xdg), XDG_CACHE_HOME=str(xdg))
            self._playwright = sync_playwright().start()
            self.browser = self._playwright.chromium.launch(
                executable_path=chromium_path(), args=CHROMIUM_ARGS, env=env
            )
            self.context = self.browser.new_context(viewport=VIEWPORT, device_scale_factor=1)
            self.context.set_default_timeout(30_000)
            self.context.add_init_script(PAGE_HELPERS)
        except Exception as exc:
            self._start_error = f"{type(exc).__name__}: {exc}"
            self.close()
            raise

    def close(self) -> None:
        """Stop everything that was started, each step on its own."""
        self.close_current()
        for step in (
            lambda: self.context and self.context.close(),
            lambda: self.browser and self.browser.close(),
            lambda: self._playwright and self._playwright.stop(),
            lambda: self.server and self.server.stop(),
        ):
            with contextlib.suppress(Exception):
                step()
        self.context = self.browser = self._playwright = self.server = None

    def get(self, name: str) -> NotebookRun:
        if self.current is not None and self.current.name == name:
            return self.current
        self.start()
        page = self._close_notebook_keep_page()
        if page is None:
            page = self.context.new_page()
            # Errors are the current notebook's: the page outlives each run.
            page.on("console", lambda msg: self._console_error(msg.text) if msg.type == "error"
                    else None)
            page.on("pageerror", lambda exc: self._console_error(f"page error: {exc}"))
        run = NotebookRun(name=name, page=page)
        self.current = run
        try:
            self._open_and_run(run)
            if run.ok:
                # Before any test moves a control: the outputs as the run left them (saved to
                # disk only for the runner that keeps executions, as before).
                run.model = page.evaluate(
                    """async ([p, save]) => { const context = window.__plab.panel(p).context;
                                              if (save) await context.save();
                                              return context.model.toJSON(); }""",
                    [name, self.executions is not None])
                if self.executions is not None and not run.console_errors:
                    self.executions[name] = (run.model, run.seconds)
        finally:
            self._screenshot(run)
            record_timing(run)
        return run

    def _console_error(self, text: str) -> None:
        if self.current is not None:
            self.current.console_errors.append(text[:300])

    def _close_notebook_keep_page(self):
        """Close the current notebook and shut its kernel down; return its page for the next
        notebook, or None when there is none or it cannot be used (then it is closed)."""
        if self.current is None:
            return None
        run, self.current = self.current, None
        page = None
        with contextlib.suppress(Exception):
            if not run.page.is_closed() and run.page.evaluate(CLOSE_NOTEBOOKS):
                page = run.page
        if page is None:
            with contextlib.suppress(Exception):
                run.page.close()
        if self.server is not None:
            self.server.shutdown_kernels_of(run.name)
        return page

    def close_current(self) -> None:
        if self.current is None:
            return
        with contextlib.suppress(Exception):
            self.current.page.close()
        if self.server is not None:
            self.server.shutdown_kernels_of(self.current.name)
        self.current = None

    # -- steps ------------------------------------------------------------------------------

    def state(self, run: NotebookRun) -> dict:
        return run.page.evaluate("(p) => window.__plab.state(p)", run.name)

    def cells(self, run: NotebookRun) -> list[dict]:
        return run.page.evaluate("(p) => window.__plab.cells(p)", run.name) or []

    def wait_idle(self, run: NotebookRun, timeout: float, min_busy: int | None = None) -> dict:
        """Wait for the kernel to read Idle; with ``min_busy``, only after that many busy
        phases have been seen since the page opened (so an action's busy phase is not missed).
        """
        deadline = time.monotonic() + timeout
        while True:
            state = self.state(run)
            if state.get("dialog"):
                # e.g. "Select Kernel" for a notebook without kernelspec: take the default.
                accept = run.page.locator(".jp-Dialog .jp-mod-accept")
                if accept.count():
                    accept.first.click()
            busy_ok = min_busy is None or state.get("busyCount", 0) >= min_busy
            # The kernel's own status, and what the status bar shows a person.
            bar = state.get("statusBar", "")
            bar_ok = not bar or "Idle" in bar
            if state.get("status") == "idle" and state.get("ready") and bar_ok and busy_ok:
                return state
            if time.monotonic() > deadline:
                raise TimeoutError(
                    f"kernel of {run.name} not idle after {timeout:.0f} s (last state {state})"
                )
            time.sleep(0.2)

    def _open_and_run(self, run: NotebookRun) -> None:
        page = run.page
        if page.evaluate("() => !!(window.jupyterapp && window.jupyterapp.shell)"):
            page.evaluate(OPEN_NOTEBOOK, run.name)
        else:
            page.goto(f"{self.server.url}/lab/tree/{quote(run.name)}?reset")
            page.wait_for_function("() => window.jupyterapp && window.jupyterapp.shell",
                                   timeout=90_000)
        try:
            self.wait_idle(run, timeout=120)
        except TimeoutError as exc:
            run.problems.append(str(exc))
            return
        page.evaluate("(p) => window.__plab.watch(p)", run.name)
        with contextlib.suppress(Exception):
            page.evaluate("() => window.jupyterapp.shell.collapseLeft()")

        saved_text = "\n".join(c.get("outputText", "") for c in self.cells(run))
        if "Error displaying widget" in saved_text:
            run.problems.append(
                "'Error displaying widget' in the saved outputs as opened (widget state or "
                "outputs committed with the notebook?)"
            )
        # Start from empty outputs and execution counts, so "every cell has a count" can only
        # become true through this run.
        page.evaluate("() => window.jupyterapp.commands.execute('notebook:clear-all-cell-outputs')")
        page.wait_for_function(
            """(p) => window.__plab.cells(p).every(
                   (c) => c.type !== 'code' || c.executionCount === null)""",
            arg=run.name,
            timeout=10_000,
        )

        timeout = run_all_timeout()
        start = time.monotonic()
        page.evaluate(
            "() => { window.jupyterapp.commands.execute('notebook:run-all-cells'); return 1; }"
        )
        deadline = start + timeout
        while True:
            cells = self.cells(run)
            state = self.state(run)
            code = [c for c in cells if c["type"] == "code" and c["source"].strip()]
            running = [c for c in code if "*" in c["prompt"]]
            unrun = [c for c in code if c["executionCount"] is None]
            errored = any(c["errors"] for c in code)
            if state.get("deaths"):
                run.seconds = time.monotonic() - start
                run.problems.append(
                    f"the kernel died or restarted during run-all (state {state['status']}); "
                    f"cells {[c['index'] for c in unrun]} without execution count"
                )
                run.cells = cells
                return
            if state["status"] == "idle" and not running and (not unrun or errored):
                run.seconds = time.monotonic() - start
                break
            if time.monotonic() > deadline:
                run.seconds = time.monotonic() - start
                run.problems.append(
                    f"run-all not finished after {timeout:.0f} s: cells "
                    f"{[c['index'] for c in running]} running, "
                    f"{[c['index'] for c in unrun]} without execution count"
                )
                run.cells = cells
                return
            time.sleep(0.25)
        run.finished = not unrun

        # Widget views and images render a moment after the kernel reports idle: give the
        # expectations a few seconds to come true before judging them.
        settle = time.monotonic() + 15
        while True:
            run.cells = self.cells(run)
            problems = judge_cells(run.cells)
            if not problems or time.monotonic() > settle:
                break
            time.sleep(0.3)
        run.problems.extend(problems)

    def _screenshot(self, run: NotebookRun) -> None:
        """The notebook's first screen after a clean run; the whole notebook after a run with
        problems, to see them (a whole notebook costs Chromium seconds; the website's
        screenshots show every notebook whole)."""
        page = run.page
        SCREENSHOTS.mkdir(parents=True, exist_ok=True)
        target = SCREENSHOTS / f"{Path(run.name).stem}.png"
        if run.ok:
            try:
                page.screenshot(path=str(target))
                run.screenshot = target
            except Exception as exc:  # a screenshot must never hide the real result
                run.problems.append(f"screenshot failed: {exc}")
            return
        try:
            height = page.evaluate("(p) => window.__plab.contentHeight(p)", run.name) or 0
            height = int(min(max(height + 40, VIEWPORT["height"]), MAX_SCREENSHOT_HEIGHT))
            page.set_viewport_size({"width": VIEWPORT["width"], "height": height})
            page.wait_for_timeout(500)
            page.screenshot(path=str(target), full_page=True)
            run.screenshot = target
        except Exception as exc:  # a screenshot must never hide the real result
            run.problems.append(f"screenshot failed: {exc}")
        finally:
            with contextlib.suppress(Exception):
                page.set_viewport_size(VIEWPORT)
                page.wait_for_timeout(300)


def judge_cells(cells: list[dict]) -> list[str]:
    """Problems visible in the executed cells: errors, tracebacks, widget failures ("Error
    displaying widget", or a view stuck at "Loading widget..."), and marked cells whose figure
    or widget is missing."""
    problems = []
    for cell in cells:
        if cell["type"] != "code":
            continue
        where = f"cell {cell['index']}"
        for error in cell["errors"]:
            problems.append(f"{where} raised {error.strip()[:400]}")
        text = cell.get("outputText", "")
        if "Traceback" in text and not cell["errors"]:
            start = text.find("Traceback")
            problems.append(f"{where} shows a traceback: {text[start : start + 400]!r}")
        if "Error displaying widget" in text:
            problems.append(f"{where} shows 'Error displaying widget'")
        if "Loading widget..." in text:
            problems.append(f"{where} still shows 'Loading widget...': the widget never rendered")
        kinds, unknown = parse_expectations(cell.get("annotations", {}))
        if unknown:
            problems.append(
                f"{where} has unknown `expect` words {unknown}; use {list(EXPECT_KINDS)}"
            )
        if "figure" in kinds and cell.get("figures", 0) < 1:
            problems.append(f"{where} expects a figure but shows no visible figure")
        if "widget" in kinds and cell.get("widgets", 0) < 1:
            problems.append(f"{where} expects a widget but shows no visible widget")
    return problems


def record_timing(run: NotebookRun) -> None:
    """Merge this notebook's run-all time and screenshot path into timings.json."""
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    data: dict = {}
    if TIMINGS.exists():
        with contextlib.suppress(ValueError, OSError):
            data = json.loads(TIMINGS.read_text(encoding="utf-8"))
    notebooks = data.setdefault("notebooks", {})
    screenshot = None
    if run.screenshot is not None:
        with contextlib.suppress(ValueError):
            screenshot = str(run.screenshot.relative_to(REPO_ROOT))
    notebooks[run.name] = {
        "run_all_seconds": None if run.seconds is None else round(run.seconds, 2),
        "finished": run.finished,
        "problems": run.problems,
        "screenshot": screenshot,
        "notebook_dir": str(notebook_dir()),
        "recorded_at": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
    }
    TIMINGS.write_text(json.dumps(data, indent=2, sort_keys=True) + "\n", encoding="utf-8")
