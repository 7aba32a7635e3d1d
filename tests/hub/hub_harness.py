"""A JupyterHub on loopback for the class tests: the hub, its proxy, students' servers and
kernels, and the way a student follows a hand-out link.

* :class:`Hub` starts JupyterHub (from PyPI) with configurable-http-proxy (from npm, installed
  by ``make test`` into ``test-artifacts/hub-proxy``), the shared-password authenticator and
  ``SimpleLocalProcessSpawner`` (users who are not system users, each with a home folder
  under the test's temporary folder), on 127.0.0.1 only. A service token drives the hub's
  REST API and reaches the students' servers. It remembers every process the hub started
  (psutil), so that :meth:`Hub.stop` can say which of them outlived the hub.
* :class:`Student` logs in as a student does, follows a link (the hub's redirects, the
  server's OAuth), reads nbgitpuller's page, and pulls as that page's script does.
* :class:`KernelClient` runs code in a kernel through the Jupyter server's websocket (the
  route JupyterLab takes), with messages in the server's JSON and binary framing.
"""

from __future__ import annotations

import asyncio
import contextlib
import datetime
import html
import json
import os
import re
import secrets
import shutil
import signal
import socket
import struct
import subprocess
import sys
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]
#: Where ``make test`` installs configurable-http-proxy (npm install --prefix).
PROXY_PREFIX = REPO_ROOT / "test-artifacts" / "hub-proxy"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def in_ci() -> bool:
    return os.environ.get("CI", "").strip().lower() == "true"


def proxy_command() -> str | None:
    """configurable-http-proxy: the project's own install, else one on PATH."""
    local = PROXY_PREFIX / "node_modules" / ".bin" / "configurable-http-proxy"
    if local.is_file():
        return str(local)
    return shutil.which("configurable-http-proxy")


def unavailable_reason() -> str | None:
    """Why the hub cannot run here, or None."""
    if not sys.platform.startswith("linux"):
        return ("the hub test runs on Linux only (SimpleLocalProcessSpawner's servers and "
                "configurable-http-proxy on loopback)")
    for module in ("jupyterhub", "nbgitpuller", "psutil", "requests", "tornado"):
        try:
            __import__(module)
        except ImportError:
            return f"{module} is not installed (the test extra has it)"
    if shutil.which("git") is None:
        return "git is not installed"
    if shutil.which("node") is None:
        return "Node.js is not installed (configurable-http-proxy runs on it)"
    if proxy_command() is None:
        return ("configurable-http-proxy is not installed: make test installs it with "
                f"npm install --prefix {PROXY_PREFIX.relative_to(REPO_ROOT)}")
    return None


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def alive(pids) -> list[int]:
    """The processes among ``pids`` that still run (zombies count as ended)."""
    import psutil

    running = []
    for pid in pids:
        with contextlib.suppress(psutil.Error):
            if psutil.Process(pid).status() != psutil.STATUS_ZOMBIE:
                running.append(pid)
    return running


def run_git(*args: str, cwd: Path | None = None) -> str:
    done = subprocess.run(["git", "-c", "user.name=Course", "-c", "user.email=course@example.org",
                           *args], cwd=cwd, capture_output=True, text=True, timeout=300,
                          stdin=subprocess.DEVNULL, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"git {' '.join(args)}: {done.stderr}")
    return done.stdout.strip()


# --------------------------------------------------------------------------- the hub
CONFIG = """\
# Written by tests/hub/hub_harness.py for one test run.
c = get_config()  # noqa: F821
c.JupyterHub.ip = "127.0.0.1"
c.JupyterHub.port = {port}
c.JupyterHub.hub_ip = "127.0.0.1"
c.JupyterHub.hub_port = {hub_port}
c.ConfigurableHTTPProxy.api_url = "http://127.0.0.1:{proxy_api_port}"
c.ConfigurableHTTPProxy.command = [{proxy!r}]
c.ConfigurableHTTPProxy.should_start = True
c.JupyterHub.cleanup_proxy = True
c.JupyterHub.cleanup_servers = True
c.JupyterHub.db_url = "sqlite:///{root}/jupyterhub.sqlite"
c.JupyterHub.cookie_secret_file = "{root}/cookie_secret"
c.JupyterHub.pid_file = "{root}/jupyterhub.pid"
c.JupyterHub.authenticator_class = "shared-password"
c.SharedPasswordAuthenticator.user_password = {password!r}
c.Authenticator.allow_all = True
c.JupyterHub.spawner_class = "simple"
c.SimpleLocalProcessSpawner.home_dir_template = "{homes}/{{username}}"
c.Spawner.cmd = [{python!r}, "-m", "jupyterhub.singleuser"]
c.Spawner.default_url = "/lab"
c.Spawner.args = {server_args!r}
c.Spawner.start_timeout = 180
c.Spawner.http_timeout = 180
c.Spawner.environment = {environment!r}
c.JupyterHub.services = [{{"name": "course-test", "api_token": {token!r}}}]
c.JupyterHub.load_roles = [{{
    "name": "course-test",
    "scopes": ["admin:users", "admin:servers", "access:servers", "read:users"],
    "services": ["course-test"],
}}]
"""


class Hub:
    """JupyterHub on loopback, started by :meth:`start`, ended by :meth:`stop`."""

    def __init__(self, root: Path, shared_cache: Path):
        self.root = Path(root)
        self.homes = self.root / "homes"
        self.homes.mkdir(parents=True, exist_ok=True)
        self.shared_cache = shared_cache
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.token = secrets.token_hex(16)
        self.password = secrets.token_hex(8)
        self.log = self.root / "hub.log"
        self.process: subprocess.Popen | None = None
        self.seen: set[int] = set()
        self.stopped = False

    def environment(self) -> dict[str, str]:
        """The students' servers' environment: this checkout's package, the image's cache."""
        return {
            "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}",
            "PYTHONPATH": str(REPO_ROOT / "src"),
            "LANG": "C.UTF-8",
            "PENDULUM_LAB_SHARED_CACHE": str(self.shared_cache),
        }

    def start(self, timeout: float = 120.0) -> None:
        config = self.root / "jupyterhub_config.py"
        config.write_text(CONFIG.format(
            port=self.port, hub_port=free_port(), proxy_api_port=free_port(),
            proxy=proxy_command(), root=self.root, password=self.password, homes=self.homes,
            python=sys.executable, environment=self.environment(), token=self.token,
            # a container or CI machine running the tests as root
            server_args=["--allow-root"] if os.geteuid() == 0 else []))
        env = {key: value for key, value in os.environ.items()
               if not key.startswith(("PENDULUM_LAB", "JUPYTER", "NUMBA"))}
        env.update(self.environment())
        env.pop("PENDULUM_LAB_SHARED_CACHE")
        with self.log.open("w") as sink:
            self.process = subprocess.Popen(
                [sys.executable, "-m", "jupyterhub", "-f", str(config)], cwd=self.root,
                env=env, stdout=sink, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                start_new_session=True)
        deadline = time.monotonic() + timeout
        while True:
            self.remember_processes()
            if self.process.poll() is not None:
                raise RuntimeError(f"JupyterHub ended at start:\n{self.log_tail()}")
            with contextlib.suppress(OSError):
                status, _ = self.api("GET", "/", timeout=5)
                if status == 200:
                    return
            if time.monotonic() > deadline:
                raise RuntimeError(f"JupyterHub did not answer in {timeout:.0f} s:\n"
                                   f"{self.log_tail()}")
            time.sleep(0.5)

    def log_tail(self, chars: int = 4000) -> str:
        return self.log.read_text(errors="replace")[-chars:] if self.log.exists() else ""

    def remember_processes(self) -> None:
        """Note every process the hub has started so far (the proxy, servers, kernels)."""
        import psutil

        if self.process is None:
            return
        with contextlib.suppress(psutil.Error):
            hub = psutil.Process(self.process.pid)
            self.seen.add(hub.pid)
            self.seen.update(child.pid for child in hub.children(recursive=True))

    def api(self, method: str, path: str, body: dict | None = None, timeout: float = 30):
        """``(status, JSON or None)`` of a request to the hub's REST API, with the token."""
        import requests

        response = requests.request(method, f"{self.url}/hub/api{path}", json=body,
                                    headers={"Authorization": f"token {self.token}"},
                                    timeout=timeout)
        try:
            return response.status_code, response.json()
        except ValueError:
            return response.status_code, None

    def server_api(self, user: str, method: str, path: str, body=None, timeout: float = 60):
        """``(status, JSON or None)`` of a request to ``user``'s Jupyter server's REST API."""
        import requests

        response = requests.request(method, f"{self.url}/user/{user}/api{path}", json=body,
                                    headers={"Authorization": f"token {self.token}"},
                                    timeout=timeout)
        try:
            return response.status_code, response.json()
        except ValueError:
            return response.status_code, None

    def start_servers(self, users, timeout: float = 240.0) -> None:
        """Ask the hub for each user's server (all at once), then wait until all are ready."""
        for user in users:
            status, _ = self.api("POST", f"/users/{user}")
            assert status in (201, 409), f"creating user {user}: HTTP {status}"
            status, _ = self.api("POST", f"/users/{user}/server")
            assert status in (201, 202), f"starting {user}'s server: HTTP {status}\n" \
                                         f"{self.log_tail()}"
        deadline = time.monotonic() + timeout
        waiting = set(users)
        while waiting:
            self.remember_processes()
            for user in sorted(waiting):
                _, model = self.api("GET", f"/users/{user}")
                server = (model or {}).get("servers", {}).get("")
                if server and server.get("ready"):
                    waiting.discard(user)
            if time.monotonic() > deadline:
                raise RuntimeError(f"servers of {sorted(waiting)} not ready in {timeout:.0f} s:"
                                   f"\n{self.log_tail()}")
            if waiting:
                time.sleep(0.5)
        self.remember_processes()

    def home(self, user: str) -> Path:
        return self.homes / user

    def stop(self, timeout: float = 90.0) -> list[int]:
        """End the hub (SIGTERM: it stops the servers and the proxy); the processes it had
        started that are still alive afterwards, each then killed."""
        if self.process is None or self.stopped:
            return []
        self.stopped = True
        self.remember_processes()
        with contextlib.suppress(ProcessLookupError):
            self.process.send_signal(signal.SIGTERM)
        try:
            self.process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait(timeout=30)
        deadline = time.monotonic() + 15  # a server's kernels end just after the server
        while alive(self.seen) and time.monotonic() < deadline:
            time.sleep(0.5)
        survivors = alive(self.seen)
        for pid in survivors:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
        return survivors


# --------------------------------------------------------------------------- a student
@dataclass
class PullResult:
    """What nbgitpuller's page and its pull said to a student."""

    page: dict[str, str]
    phase: str
    message: str = ""
    output: list[str] = field(default_factory=list)


class Student:
    """A browser's part, without a browser: cookies, the login form, links, the pull page."""

    def __init__(self, hub: Hub, name: str):
        import requests

        self.hub, self.name = hub, name
        self.session = requests.Session()

    def log_in(self) -> None:
        page = self.session.get(f"{self.hub.url}/hub/login", timeout=60)
        xsrf = re.search(r'name="_xsrf"\s+value="([^"]+)"', page.text)
        form = {"username": self.name, "password": self.hub.password}
        if xsrf:
            form["_xsrf"] = html.unescape(xsrf.group(1))
        done = self.session.post(f"{self.hub.url}/hub/login", data=form, timeout=60,
                                 allow_redirects=False)
        assert done.status_code in (302, 303), f"login of {self.name}: HTTP {done.status_code}"

    def follow(self, link: str, timeout: float = 180.0) -> PullResult:
        """Open ``link`` (an nbgitpuller link) and pull as its page's script does."""
        page = self.session.get(link, timeout=60)
        assert page.status_code == 200, f"{link}: HTTP {page.status_code}\n{page.text[:2000]}"
        data = {key: html.unescape(value) for key, value in
                re.findall(r'data-([a-z-]+)="([^"]*)"', page.text)}
        from urllib.parse import unquote

        data = {key: unquote(value) for key, value in data.items()}
        assert "repo" in data and "targetpath" in data, page.text[:2000]
        query = {"repo": data["repo"], "targetpath": data["targetpath"]}
        if "branch" in data:
            query["branch"] = data["branch"]
        base = f"{self.hub.url}/user/{self.name}/"
        response = self.session.get(f"{base}git-pull/api", params=query, stream=True,
                                    timeout=timeout)
        result = PullResult(page=data, phase="no answer")
        for line in response.iter_lines(decode_unicode=True):
            if not line or not line.startswith("data:"):
                continue
            event = json.loads(line[len("data:"):])
            if "output" in event:
                result.output.append(event["output"])
            if event.get("phase") in ("finished", "error"):
                result.phase = event["phase"]
                result.message = event.get("message", "")
                break
        response.close()
        return result


# --------------------------------------------------------------------------- kernels
class ServerGone(Exception):
    """The kernel's websocket closed: the student's server is no longer there."""


@dataclass
class CellRun:
    code: str
    outputs: list[dict] = field(default_factory=list)  # iopub contents with "msg_type"
    widget_pngs: int = 0  # PNG images sent to widgets (a redrawn figure)
    error: str | None = None
    seconds: float = 0.0

    @property
    def pngs(self) -> list[bytes]:
        import base64

        found = []
        for output in self.outputs:
            data = output.get("data", {})
            if "image/png" in data:
                found.append(base64.b64decode(data["image/png"]))
        return found

    @property
    def stdout(self) -> str:
        return "".join(output["text"] for output in self.outputs
                       if output["msg_type"] == "stream" and output.get("name") == "stdout")

    @property
    def text(self) -> str:
        parts = []
        for output in self.outputs:
            if output["msg_type"] == "stream":
                parts.append(output["text"])
            elif "text/plain" in output.get("data", {}):
                parts.append(output["data"]["text/plain"])
        return "".join(parts)


def _unpack(frame) -> tuple[dict, list[bytes]]:
    """A websocket frame of the Jupyter server: JSON text, or its binary framing (a count, the
    offsets, the JSON message, then the buffers)."""
    if isinstance(frame, str):
        return json.loads(frame), []
    count = struct.unpack("!I", frame[:4])[0]
    offsets = list(struct.unpack(f"!{count}I", frame[4:4 + 4 * count])) + [len(frame)]
    parts = [frame[offsets[i]:offsets[i + 1]] for i in range(count)]
    return json.loads(parts[0].decode("utf-8")), parts[1:]


class KernelClient:
    """One kernel's websocket, through the hub's proxy, authorised by the hub's token."""

    def __init__(self, hub: Hub, user: str, kernel_id: str):
        self.hub, self.user, self.kernel_id = hub, user, kernel_id
        self.session = uuid.uuid4().hex
        self.socket = None

    async def connect(self) -> None:
        from tornado.httpclient import HTTPRequest
        from tornado.websocket import websocket_connect

        url = (f"ws://127.0.0.1:{self.hub.port}/user/{self.user}/api/kernels/"
               f"{self.kernel_id}/channels?session_id={self.session}")
        request = HTTPRequest(url, headers={"Authorization": f"token {self.hub.token}"},
                              request_timeout=120, connect_timeout=120)
        self.socket = await websocket_connect(request, max_message_size=256 * 2**20)

    async def run(self, code: str, timeout: float = 300.0) -> CellRun:
        msg_id = uuid.uuid4().hex
        message = {
            "header": {"msg_id": msg_id, "username": self.user, "session": self.session,
                       "msg_type": "execute_request", "version": "5.3",
                       "date": datetime.datetime.now(datetime.UTC).isoformat()},
            "parent_header": {}, "metadata": {}, "channel": "shell", "buffers": [],
            "content": {"code": code, "silent": False, "store_history": True,
                        "user_expressions": {}, "allow_stdin": False, "stop_on_error": True},
        }
        await self.socket.write_message(json.dumps(message))
        cell = CellRun(code)
        started = time.perf_counter()
        idle = replied = False
        while not (idle and replied):
            left = timeout - (time.perf_counter() - started)
            if left <= 0:
                raise TimeoutError(f"{self.user}: the cell did not finish in {timeout:.0f} s:\n"
                                   f"{code[:300]}")
            frame = await asyncio.wait_for(self.socket.read_message(), left)
            if frame is None:
                raise ServerGone(f"{self.user}'s kernel connection closed during the cell")
            reply, buffers = _unpack(frame)
            if reply.get("parent_header", {}).get("msg_id") != msg_id:
                continue
            kind = reply["header"]["msg_type"]
            content = reply.get("content", {})
            if kind == "status" and content.get("execution_state") == "idle":
                idle = True
            elif kind == "execute_reply":
                replied = True
                if content.get("status") == "error" and cell.error is None:
                    cell.error = f"{content.get('ename')}: {content.get('evalue')}"
            elif kind == "error":
                cell.error = f"{content.get('ename')}: {content.get('evalue')}\n" + \
                             "\n".join(content.get("traceback", []))[-3000:]
            elif kind in ("stream", "display_data", "execute_result", "update_display_data"):
                cell.outputs.append({"msg_type": kind, **content})
            elif kind == "comm_msg":
                cell.widget_pngs += sum(bytes(b[:8]) == PNG_MAGIC for b in buffers)
        cell.seconds = time.perf_counter() - started
        return cell

    def close(self) -> None:
        if self.socket is not None:
            self.socket.close()
