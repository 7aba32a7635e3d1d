"""Build and grade the course's graded assignments, offline, each submission in a sandbox.

Each master notebook in ``assignments/`` holds the questions, their solutions and their public and
hidden tests (otter-grader's master-notebook format). ``build`` runs ``otter assign`` on each into
``dist/assignments/<name>/``: ``student/<name>.ipynb`` is what students get (no solutions, no
hidden tests), ``autograder/`` holds the solutions notebook and the autograder zip (its
``tests/*.py`` are the hidden tests; Gradescope takes the zip as it is). ``grade`` grades
submissions on the instructor's machine::

    python tools/assignments.py build                     # every assignment (make assignments)
    python tools/assignments.py build 02_integrators_and_orders
    python tools/assignments.py grade 02_integrators_and_orders submissions/*/*.ipynb -o graded/

How a submission is graded (``docs/instructors.md`` says it for instructors):

- **Three processes.** The *grader* (this command) starts one *checker* per submission (this
  file, ``_check``), which starts the *runner* (this file, ``_run``) in a sandbox; the runner
  executes the notebook in a kernel of its own (nbclient), with a time limit per cell.
- **Answers cross as data.** The checker runs otter's hidden tests (the autograder zip's
  ``tests/*.py``, read by otter's own test-file classes) in its own process, into which no
  student code is ever loaded. Each name a test asks for is fetched from the kernel as JSON
  (numbers, arrays as lists, SymPy expressions as ``srepr`` text parsed back with a whitelist,
  tuples, lists, dicts); a function answer becomes a stand-in that sends the arguments the test
  chose to the kernel and receives the result as JSON. So a score cannot be forged from the
  notebook: whatever the student's code does, only its answers leave the sandbox. Requests
  reach the kernel over a loopback socket (inside the sandbox's own network namespace) to a
  loop that runs in the kernel once the notebook has run, so a test that calls a student's
  step function a thousand times costs milliseconds, not a kernel execution per call; a call
  that outlasts the cell's time is interrupted, and that function is not called again.
- **The sandbox (Linux, bubblewrap).** The runner sees a read-only view of Python, its packages
  and this file, a private ``/tmp``, a private writable work folder with the notebook's copy and
  a copy of the compiled-kernel cache; no network, no home, no output folder, no other
  submission; its own process namespace, so that all its processes end with its grading. Memory
  (address space) and process count are limited in its first process (rlimits), each cell's
  wall time by the runner, the whole grading's by the grader, which ends the checker and with it
  the sandbox. Where bubblewrap is missing (macOS, Windows, a Linux without it), grading is
  refused unless ``--no-sandbox-i-trust-the-submissions`` is given: then the same processes run
  without the sandbox, and the notes of every submission say so.
- **An instructor's run keeps its work.** Submissions are named by their path relative to
  ``--root`` (the current folder by default); ``graded/<path>.json`` per submission;
  ``grades.csv`` holds one row per submission across runs (a re-grade replaces its row); a
  submission whose content did not change since its row was written is not graded again;
  Ctrl-C or SIGTERM ends every child and writes the CSV of what was graded. ``--jobs`` gradings
  run side by side (default: the cores), with a progress bar and the time left.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import hashlib
import importlib.util
import json
import os
import queue
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
import zipfile
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from dataclasses import dataclass, field
from pathlib import Path

import nbformat

REPO_ROOT = Path(__file__).resolve().parents[1]
ASSIGNMENTS = REPO_ROOT / "assignments"
DIST = REPO_ROOT / "dist" / "assignments"

#: Seconds one cell of a submission may run, and one call of a student's function by a test.
#: The slowest cell of a solution takes a few seconds once the integrators are compiled; a
#: first compilation of a method takes up to half a minute on a loaded machine.
CELL_SECONDS = 120.0
#: Seconds the grading of one submission may take in all (kernel start, every cell, every test).
TOTAL_SECONDS = 900.0
#: Address space of each process in the sandbox [MB]. A solution's kernel (NumPy, SymPy, Numba
#: and LLVM loaded, the integrators compiled) maps about 2 GB of address space here.
MEMORY_MB = 6144
#: Processes and threads in the sandbox. A kernel has about 15 threads (the thread pools are
#: held to one thread each in the sandbox).
PROCESSES = 256
#: Seconds a kernel has to come back after it was interrupted at the end of a cell's time; a
#: kernel that does not (the student's code ignores the interrupt) is stopped.
INTERRUPT_GRACE_SECONDS = 5.0
#: The flag that grades without a sandbox, named after what it gives up.
NO_SANDBOX_FLAG = "--no-sandbox-i-trust-the-submissions"
#: Output kept per cell of the executed notebook [characters]; the rest is dropped and noted.
OUTPUT_CHARS = 100_000
DROPPED_OUTPUT = "the grader dropped the rest of this cell's output"
#: The longest line of data accepted from a sandbox [bytes] (an answer, a function's result).
REPLY_BYTES = 32 * 1024 * 1024
#: Where the sandbox sees its work folder, its cache and this file.
SANDBOX_WORK = "/sandbox/work"
SANDBOX_CACHE = "/sandbox/cache"
SANDBOX_TOOL = "/sandbox/grader/assignments.py"

_CHECK_CALL = re.compile(r"""\.check\(\s*["']([^"']+)["']\s*\)""")
_POINTS = re.compile(r"^points\s*=\s*([0-9.]+)\s*$", re.MULTILINE)


# ------------------------------------------------------------------------------ building
def masters(names: list[str] | None = None) -> list[Path]:
    """The master notebooks in ``assignments/``, or those named (file stems)."""
    found = {path.stem: path for path in sorted(ASSIGNMENTS.glob("*.ipynb"))}
    if not names:
        return list(found.values())
    unknown = [name for name in names if name not in found]
    if unknown:
        raise ValueError(f"no assignment named {unknown}; the assignments are {sorted(found)}")
    return [found[name] for name in names]


def build(master: Path, dist: Path = DIST) -> Path:
    """Run ``otter assign`` on ``master`` into ``dist/<name>/`` (replaced); return that folder.

    No PDFs are made and nothing is fetched. otter's own run of the tests on the solutions is
    left out (``--no-run-tests``): grading the solutions with the autograder zip, as ``build``
    on the command line (unless ``--no-check``) and the test suite do next, runs the same
    tests. Raises ``RuntimeError`` with otter's output if the build fails or does not produce
    the student notebook, the solutions and the autograder zip.
    """
    out = dist / master.stem
    if out.exists():
        shutil.rmtree(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    command = [sys.executable, "-m", "otter", "assign", "--no-pdfs", "--no-run-tests",
               master.name, str(out)]
    completed = subprocess.run(command, cwd=master.parent, capture_output=True, text=True,
                               encoding="utf-8", errors="replace",
                               env={**os.environ, "PYTHONWARNINGS": "ignore"}, check=False)
    log = completed.stdout + completed.stderr
    expected = [out / "student" / master.name, out / "autograder" / master.name]
    if completed.returncode != 0 or not all(path.exists() for path in expected):
        raise RuntimeError(f"otter assign failed on {master.name}:\n{log}")
    add_package(autograder_zip(out))  # exactly one zip, then the course's package in it
    return out


#: Where the package's wheel goes inside the autograder zip, and how its requirements name it:
#: relative to the folder the zip is unpacked in (Gradescope's /autograder/source), which is
#: where conda runs the pip part of environment.yml, and where requirements.txt lies.
WHEEL_FOLDER = "files"
_WHEEL: dict[str, bytes] = {}  # file name -> contents: built once per process


def package_wheel() -> tuple[str, bytes]:
    """The course's package as a wheel: its file name and its bytes (built once per process)."""
    if not _WHEEL:
        with tempfile.TemporaryDirectory(prefix="wheel-") as folder:
            # With the build backend at hand (the assignments extra) nothing is downloaded.
            isolation = ([] if importlib.util.find_spec("hatchling") is None
                         else ["--no-build-isolation"])
            completed = subprocess.run(
                [sys.executable, "-m", "pip", "wheel", "--no-deps", "--quiet", *isolation,
                 "-w", folder, str(REPO_ROOT)], capture_output=True, text=True,
                encoding="utf-8", errors="replace", check=False)
            wheels = sorted(Path(folder).glob("pendulum_lab-*.whl"))
            if completed.returncode != 0 or len(wheels) != 1:
                raise RuntimeError(f"building the package's wheel failed:\n{completed.stderr}")
            _WHEEL[wheels[0].name] = wheels[0].read_bytes()
    return next(iter(_WHEEL.items()))


def add_package(zip_path: Path) -> None:
    """Put the course's package into an autograder zip, as Gradescope needs it.

    The hidden tests import ``pendulum_lab``, which no public index serves: its wheel goes into
    the zip (``files/``), ``requirements.txt`` names it, and so does the pip part of the zip's
    ``environment.yml`` (what Gradescope's image installs), beside otter-grader; the wheel's
    own requirements bring NumPy, SciPy, SymPy and Numba.
    """
    import yaml  # otter-grader's dependency

    name, contents = package_wheel()
    requirement = f"./{WHEEL_FOLDER}/{name}"
    with zipfile.ZipFile(zip_path) as archive:
        entries = {entry: archive.read(entry) for entry in archive.namelist()}
    environment = yaml.safe_load(entries["environment.yml"])
    pip = next(item["pip"] for item in environment["dependencies"] if isinstance(item, dict))
    pip.append(requirement)
    entries["environment.yml"] = yaml.safe_dump(environment, sort_keys=False).encode("utf-8")
    entries["requirements.txt"] = f"{requirement}\n".encode()
    entries[f"{WHEEL_FOLDER}/{name}"] = contents
    rebuilt = zip_path.with_suffix(".tmp")
    with zipfile.ZipFile(rebuilt, "w", zipfile.ZIP_DEFLATED) as archive:
        for entry, data in entries.items():
            archive.writestr(entry, data)
    rebuilt.replace(zip_path)


def autograder_zip(folder: Path) -> Path:
    """The autograder zip of a built assignment folder (otter names it with a time stamp)."""
    zips = sorted((folder / "autograder").glob("*-autograder_*.zip"))
    if len(zips) != 1:
        raise FileNotFoundError(f"expected one autograder zip in {folder / 'autograder'}, "
                                f"found {len(zips)}: build the assignment first")
    return zips[0]


def question_points(folder: Path) -> dict[str, float]:
    """Question name -> points, in the order of the autograder's test files."""
    points = {}
    with zipfile.ZipFile(autograder_zip(folder)) as archive:
        for name in sorted(archive.namelist()):
            if name.startswith("tests/") and name.endswith(".py"):
                match = _POINTS.search(archive.read(name).decode("utf-8"))
                points[Path(name).stem] = float(match.group(1)) if match else 1.0
    return points




# ------------------------------------------------------------------------------ answers as data
# These two functions run on both sides: in the student's kernel (their source is sent there
# once the notebook has run) and in the checker. They import what they use, inside.
def encode_answer(value, depth=0):
    """An answer as JSON-ready data: numbers, NumPy arrays and scalars, SymPy objects (``srepr``
    text), tuples, lists, dicts with string keys; ``{"callable": True}`` for a function and
    ``{"unsupported": type name}`` for anything else."""
    import numbers

    if depth > 32:
        return {"unsupported": "nested deeper than 32 levels"}
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, int) and type(value) is int:
        return value
    if isinstance(value, float) and type(value) is float:
        return value
    module = type(value).__module__.split(".")[0]
    if module == "numpy":
        import numpy as np

        array = np.asarray(value)
        if array.dtype.kind in "biuf":
            return {"ndarray": array.tolist(), "kind": array.dtype.kind,
                    "scalar": not isinstance(value, np.ndarray)}
        if array.dtype.kind == "c":
            return {"ndarray": array.real.tolist(), "imag": array.imag.tolist(),
                    "kind": "c", "scalar": not isinstance(value, np.ndarray)}
        return {"unsupported": f"numpy array of {array.dtype}"}
    if module == "sympy":
        import sympy

        if isinstance(value, (sympy.Basic, sympy.MatrixBase)):
            return {"sympy": sympy.srepr(value)}
    if isinstance(value, complex):
        return {"complex": [value.real, value.imag]}
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, numbers.Real):
        return float(value)
    if isinstance(value, tuple):
        return {"tuple": [encode_answer(item, depth + 1) for item in value]}
    if isinstance(value, list):
        return [encode_answer(item, depth + 1) for item in value]
    if isinstance(value, dict) and all(isinstance(key, str) for key in value):
        return {"dict": {key: encode_answer(item, depth + 1) for key, item in value.items()}}
    if callable(value) and not isinstance(value, type):
        return {"callable": True}
    return {"unsupported": type(value).__name__}


def decode_answer(data, depth=0):
    """The value that :func:`encode_answer` encoded. SymPy text is parsed by
    :func:`parse_srepr` (a whitelist of SymPy's constructors), never evaluated as Python."""
    if depth > 32:
        raise ValueError("an answer nested deeper than 32 levels")
    if data is None or isinstance(data, (bool, int, float, str)):
        return data
    if isinstance(data, list):
        return [decode_answer(item, depth + 1) for item in data]
    if not isinstance(data, dict) or len(data) == 0:
        raise ValueError(f"not an encoded answer: {type(data).__name__}")
    if "ndarray" in data:
        import numpy as np

        kind = {"b": bool, "i": np.int64, "u": np.uint64, "f": np.float64,
                "c": np.complex128}[data["kind"]]
        array = np.array(data["ndarray"], dtype=float if kind is np.complex128 else kind)
        if kind is np.complex128:
            array = array + 1j * np.array(data["imag"], dtype=float)
        if data.get("scalar"):
            return array.reshape(()).astype(kind)[()]
        return array
    if "sympy" in data:
        return parse_srepr(data["sympy"])
    if "complex" in data:
        real, imag = data["complex"]
        return complex(float(real), float(imag))
    if "tuple" in data:
        return tuple(decode_answer(item, depth + 1) for item in data["tuple"])
    if "dict" in data:
        return {str(key): decode_answer(item, depth + 1) for key, item in data["dict"].items()}
    raise ValueError(f"not an encoded answer: keys {sorted(data)[:5]}")


def parse_srepr(text):
    """A SymPy object from its ``srepr`` text, built only from SymPy's classes and functions.

    The text is checked first: calls of names that SymPy exports (classes and functions of
    ``sympy``), string, number and boolean constants, keyword arguments, lists and tuples; any
    attribute, subscript, operator or other name is refused (ValueError). Then
    ``sympy.parsing.sympy_parser.parse_expr`` builds it with a namespace of those names and no
    builtins, without automatic symbols or evaluation changes.
    """
    import ast
    import inspect

    import sympy
    from sympy.parsing.sympy_parser import parse_expr

    if not isinstance(text, str) or len(text) > 4_000_000:
        raise ValueError("SymPy text must be a string of at most 4e6 characters")
    allowed = {name: obj for name, obj in vars(sympy).items()
               if not name.startswith("_") and (inspect.isclass(obj) or inspect.isfunction(obj)
                                               or isinstance(obj, sympy.Basic))}
    allowed.update({"Symbol": sympy.Symbol, "Dummy": sympy.Dummy, "Function": sympy.Function,
                    "MutableDenseMatrix": sympy.MutableDenseMatrix,
                    "ImmutableDenseMatrix": sympy.ImmutableDenseMatrix,
                    "true": sympy.true, "false": sympy.false})
    try:
        tree = ast.parse(text, mode="eval")
    except SyntaxError as err:
        raise ValueError(f"SymPy text does not parse: {err.msg}") from None
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            if not isinstance(node.func, (ast.Name, ast.Call)):
                raise ValueError("SymPy text calls something other than a SymPy name")
        elif isinstance(node, ast.Name):
            if node.id not in allowed:
                raise ValueError(f"SymPy text names {node.id!r}, which is not SymPy's")
        elif isinstance(node, ast.Constant):
            if not isinstance(node.value, (str, int, float, bool)) and node.value is not None:
                raise ValueError("SymPy text holds a constant of another kind")
        elif isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub) \
                and isinstance(node.operand, ast.Constant):
            continue
        elif not isinstance(node, (ast.Expression, ast.keyword, ast.List, ast.Tuple, ast.Load,
                                   ast.USub)):
            raise ValueError(f"SymPy text holds a {type(node).__name__}, which srepr never makes")
    namespace = {**allowed, "__builtins__": {}}
    return parse_expr(text, local_dict={}, global_dict=namespace, transformations=(),
                      evaluate=True)


# ------------------------------------------------------------------------------ the sandbox
class SandboxUnavailable(RuntimeError):
    """No sandbox on this machine, and grading without one was not asked for by name."""


def sandbox_problem() -> str | None:
    """Why submissions cannot be sandboxed here, or None when they can (Linux with bubblewrap)."""
    if not sys.platform.startswith("linux"):
        return (f"no sandbox on this OS ({sys.platform}): bubblewrap, which grading uses to "
                "isolate a submission, exists on Linux only")
    if shutil.which("bwrap") is None:
        return ("bubblewrap is not installed (Debian/Ubuntu: apt-get install bubblewrap; "
                "Fedora: dnf install bubblewrap)")
    return None


def _read_only_sources() -> list[Path]:
    """What the sandbox needs to see, read-only: the system's programs and libraries, Python,
    its packages (its environment, the folders that its ``.pth`` files and ``PYTHONPATH`` add,
    as for an editable install), nothing else."""
    import site

    wanted = [Path(p) for p in ("/usr", "/bin", "/lib", "/lib64", "/sbin")]
    wanted += [Path(p) for p in ("/etc/ld.so.cache", "/etc/alternatives", "/etc/localtime",
                                 "/etc/ssl", "/etc/fonts")]
    wanted += [Path(sys.prefix), Path(sys.base_prefix), Path(sys.exec_prefix),
               Path(os.path.realpath(sys.executable)).parent.parent]
    wanted += [Path(entry) for entry in os.environ.get("PYTHONPATH", "").split(os.pathsep)
               if entry and Path(entry).is_absolute()]
    for packages in site.getsitepackages():
        for pth in Path(packages).glob("*.pth"):
            for line in pth.read_text(encoding="utf-8", errors="replace").splitlines():
                if line.startswith("/") and Path(line.strip()).is_dir():
                    wanted.append(Path(line.strip()))
    kept = []
    for path in sorted({Path(os.path.abspath(p)) for p in wanted}, key=lambda p: len(p.parts)):
        if path.exists() and not any(parent in kept for parent in path.parents):
            kept.append(path)
    return kept


def sandbox_command(work: Path, cache: Path, command: list[str]) -> list[str]:
    """The bubblewrap command that runs ``command`` in the sandbox."""
    args = ["bwrap", "--unshare-all", "--die-with-parent", "--new-session", "--cap-drop", "ALL",
            "--clearenv"]

    def bind(source: Path, target: str, writable: bool = False) -> None:
        if source.is_symlink() and source.parent == Path("/"):
            args.extend(["--symlink", os.readlink(source), target])
            return
        args.extend(["--bind" if writable else "--ro-bind", str(source), target])

    # The private /tmp first: a read-only source may itself live under /tmp (a clone there,
    # its environment in it), and a later tmpfs would hide it.
    args += ["--proc", "/proc", "--dev", "/dev", "--tmpfs", "/tmp"]
    for source in _read_only_sources():
        bind(source, str(source))
    bind(Path(__file__).resolve(), SANDBOX_TOOL)
    bind(work, SANDBOX_WORK, writable=True)
    bind(cache, SANDBOX_CACHE, writable=True)
    for name, value in _sandbox_env(SANDBOX_WORK, SANDBOX_CACHE).items():
        args += ["--setenv", name, value]
    args += ["--chdir", SANDBOX_WORK, "--", *command]
    return args


def _sandbox_env(work: str, cache: str) -> dict[str, str]:
    """The whole environment of a grading: none of the instructor's variables but the paths."""
    bin_dir = str(Path(sys.executable).parent)
    python_path = os.environ.get("PYTHONPATH", "")
    env = {"PATH": f"{bin_dir}:/usr/local/bin:/usr/bin:/bin", "HOME": work, "TMPDIR": "/tmp",
           "LANG": "C.UTF-8", "PYTHONWARNINGS": "ignore", "MPLBACKEND": "Agg",
           "MPLCONFIGDIR": f"{work}/.matplotlib", "JUPYTER_PLATFORM_DIRS": "1",
           "PENDULUM_LAB_CACHE": f"{cache}/pendulum_lab", "NUMBA_CACHE_DIR": f"{cache}/numba",
           # One thread per pool: gradings run side by side, one per core.
           "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
           "NUMBA_NUM_THREADS": "1"}
    if python_path:
        env["PYTHONPATH"] = python_path
    if sys.platform == "win32":  # a Windows process needs these to start at all
        for name in ("SYSTEMROOT", "COMSPEC", "PATHEXT", "WINDIR"):
            if name in os.environ:
                env[name] = os.environ[name]
        env["PATH"] = os.pathsep.join([bin_dir, os.environ.get("PATH", "")])
        env["TMPDIR"] = env["TEMP"] = env["TMP"] = str(Path(work) / "tmp")
    return env


def end_process_tree(process: subprocess.Popen) -> None:
    """End ``process`` and every process it started, on every OS (psutil walks the tree; a
    process that left the tree, as a double fork does, escapes: only the sandbox's process
    namespace catches those)."""
    import psutil

    try:
        children = psutil.Process(process.pid).children(recursive=True)
    except psutil.Error:
        children = []
    with contextlib.suppress(OSError):
        process.kill()
    for child in children:
        with contextlib.suppress(psutil.Error):
            child.kill()
    psutil.wait_procs(children, timeout=5)
    with contextlib.suppress(subprocess.TimeoutExpired):
        process.wait(timeout=5)


def _new_group() -> dict:
    """Popen arguments that keep a child out of the terminal's Ctrl-C (the grader ends it)."""
    if sys.platform == "win32":
        return {"creationflags": getattr(subprocess, "CREATE_NEW_PROCESS_GROUP", 0x200)}
    return {"start_new_session": True}


# ------------------------------------------------------------------------------ the runner
# It runs inside the sandbox, with the student's code in its kernel: everything it sends out is
# treated as untrusted data by the checker.
_KERNEL_TOOLS = '''
def _grader_serve(port, token):
    import json, socket
    sources = {sources!r}
    scope = {{}}
    for source in sources:
        exec(source, scope)
    namespace = globals()

    def answer(request):
        try:
            name = request["name"]
            if request["op"] == "get":
                if name not in namespace:
                    return {{"missing": True}}
                return {{"value": scope["encode_answer"](namespace[name])}}
            args = [scope["decode_answer"](arg) for arg in request["args"]]
            return {{"value": scope["encode_answer"](namespace.get(name)(*args))}}
        except Exception as err:
            return {{"error": [type(err).__name__, str(err)[:1000]]}}

    connection = socket.create_connection(("127.0.0.1", port))
    connection.sendall(token.encode() + b"\\n")
    lines = connection.makefile("rb")
    while True:
        try:
            line = lines.readline()
        except KeyboardInterrupt:  # an interrupt that came just after a reply
            continue
        if not line:
            break
        request = json.loads(line)
        if request.get("op") == "end":
            break
        try:
            reply = answer(request)
        except KeyboardInterrupt:  # the runner's interrupt at the end of the call's time
            reply = {{"interrupted": True}}
        connection.sendall(json.dumps(reply).encode() + b"\\n")
    connection.close()
'''


def _limit_resources(memory_mb: float, processes: int) -> list[str]:
    """Apply the memory and process limits to this process (and so to all it starts); what was
    limited, in words."""
    try:
        import resource
    except ImportError:  # Windows
        return ["memory and process count: not limited (no rlimits on Windows)"]
    done = []
    limit = int(memory_mb * 1024 * 1024)
    try:
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
        done.append(f"memory: {memory_mb:g} MB of address space per process")
    except (ValueError, OSError) as err:
        done.append(f"memory: not limited ({err})")
    if hasattr(resource, "RLIMIT_NPROC"):
        try:
            resource.setrlimit(resource.RLIMIT_NPROC, (processes, processes))
            done.append(f"processes: {processes} (threads included)"
                        + (" (not enforced: the sandbox runs as root)" if os.geteuid() == 0
                           else ""))
        except (ValueError, OSError) as err:
            done.append(f"processes: not limited ({err})")
    return done


class _KernelAnswers:
    """The runner's line to the student's kernel once the notebook has run: a loop in the
    kernel (``_KERNEL_TOOLS``) reads requests from a loopback socket and writes the answers
    back as JSON lines, so that a call costs a fraction of a millisecond, not a cell's
    execution (a hidden test may call a student's step function a thousand times).

    A call that outlasts ``seconds`` is interrupted; a kernel that does not come back within
    the grace time, closes its end or sends what is not a JSON object is taken as gone.
    """

    def __init__(self, client, seconds: float):
        import inspect
        import secrets
        import socket

        self.client, self.seconds, self.alive = client, seconds, False
        self.connection, self.buffer = None, b""
        listener = socket.create_server(("127.0.0.1", 0))
        token = secrets.token_hex(16)
        sources = [inspect.getsource(function)
                   for function in (encode_answer, decode_answer, parse_srepr)]
        client.kc.execute(_KERNEL_TOOLS.format(sources=sources)
                          + f"\n_grader_serve({listener.getsockname()[1]}, {token!r})\n",
                          store_history=False, allow_stdin=False, stop_on_error=False)
        deadline = time.monotonic() + INTERRUPT_GRACE_SECONDS + 30
        try:
            while not self.alive and time.monotonic() < deadline:
                listener.settimeout(max(deadline - time.monotonic(), 0.01))
                self.connection, self.buffer = listener.accept()[0], b""
                # Anything else in the sandbox that connects first is turned away.
                self.alive = self._line(INTERRUPT_GRACE_SECONDS, 100) == token.encode()
                if not self.alive:
                    self.connection.close()
        except OSError:
            self.alive = False
        finally:
            listener.close()

    def _line(self, seconds: float, limit: int = REPLY_BYTES) -> bytes:
        """The next line from the kernel, without its end; OSError (TimeoutError included)
        when none comes within ``seconds``, ConnectionError when it is longer than ``limit``
        or the kernel closed its end."""
        deadline = time.monotonic() + seconds
        while b"\n" not in self.buffer:
            if len(self.buffer) > limit:
                raise ConnectionError("a reply longer than the grader accepts")
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError
            self.connection.settimeout(left)
            chunk = self.connection.recv(1 << 20)
            if not chunk:
                raise ConnectionError("the kernel closed its end")
            self.buffer += chunk
        line, self.buffer = self.buffer.split(b"\n", 1)
        if len(line) > limit:
            raise ConnectionError("a reply longer than the grader accepts")
        return line

    def _reply(self, seconds: float) -> dict:
        reply = json.loads(self._line(seconds))
        if not isinstance(reply, dict):
            raise ValueError("a reply that is not a JSON object")
        return reply

    def ask(self, request: dict) -> dict:
        if not self.alive:
            return {"dead": True}
        try:
            self.connection.sendall(json.dumps(request).encode() + b"\n")
            try:
                return self._reply(self.seconds)
            except TimeoutError:
                pass
            from nbclient.util import run_sync

            with contextlib.suppress(Exception):
                run_sync(self.client.km.interrupt_kernel)()
            # The loop answers an interrupted call with {"interrupted": true}; an answer that
            # came just as the time ran out counts as late all the same.
            self._reply(INTERRUPT_GRACE_SECONDS)
            return {"timeout": True}
        except (OSError, ValueError, RecursionError):
            self.alive = False
            return {"dead": True}

    def close(self) -> None:
        if self.connection is not None:
            with contextlib.suppress(OSError):
                if self.alive:
                    self.connection.sendall(b'{"op": "end"}\n')
                self.connection.close()


def _run_submission(config: dict) -> int:
    """The runner: execute the notebook, then answer the checker's requests (JSON lines on
    standard input and output) until told to end."""
    protocol = os.fdopen(os.dup(1), "w", encoding="utf-8")
    os.dup2(2, 1)  # nothing else may write to the checker's channel
    limits = _limit_resources(config["memory_mb"], config["processes"])

    from nbclient import NotebookClient
    from nbclient.exceptions import DeadKernelError
    from nbclient.util import run_sync  # the kernel manager's methods are coroutines

    work = Path(config["work"])
    notebook = nbformat.read(work / config["notebook"], as_version=4)
    cell_seconds = float(config["cell_seconds"])

    class Client(NotebookClient):
        """nbclient, with each cell's kept output bounded (a kernel sends a stream in pieces
        of any size: each piece is cut to what is left of the cell's allowance), and a cell
        that outlasts its time interrupted by nbclient itself, which then waits a few seconds
        for the cell's last output and marks ``timed_out``. (With ``interrupt_on_timeout``
        off, nbclient 0.11 leaves the timed-out cell's output reader running, and it swallows
        the outputs of the cells after it.)"""

        timed_out = False

        async def _async_handle_timeout(self, timeout, cell=None):
            self.timed_out = True
            return await super()._async_handle_timeout(timeout, cell)

        def output(self, outs, msg, display_id, cell_index):
            left = OUTPUT_CHARS - sum(len(json.dumps(out)) for out in outs)
            if left <= 0:
                return None
            out = super().output(outs, msg, display_id, cell_index)
            if outs and len(json.dumps(outs[-1])) > left:
                if outs[-1].get("output_type") == "stream":
                    outs[-1]["text"] = outs[-1]["text"][:left]
                else:
                    outs.pop()
                outs.append(nbformat.v4.new_output(
                    "stream", name="stderr",
                    text=f"[{DROPPED_OUTPUT} after {OUTPUT_CHARS} characters]"))
            return out

    def send(message: dict) -> None:
        protocol.write(json.dumps(message) + "\n")
        protocol.flush()

    def new_client():
        client = Client(notebook, timeout=cell_seconds, allow_errors=True,
                        interrupt_on_timeout=True, startup_timeout=300, kernel_name="python3",
                        error_on_timeout={"ename": "TimeoutError", "evalue": "", "traceback": []},
                        iopub_timeout=INTERRUPT_GRACE_SECONDS,
                        resources={"metadata": {"path": str(work)}})
        client.km = client.create_kernel_manager()
        client.start_new_kernel(stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        client.start_new_kernel_client()
        return client

    def run_extra(client, source: str):
        """Run code that is not one of the notebook's cells (nbclient files each cell it runs
        in the notebook, so it stays there while it runs)."""
        cell = nbformat.v4.new_code_cell(source)
        notebook.cells.append(cell)
        try:
            client.execute_cell(cell, len(notebook.cells) - 1)
        finally:
            notebook.cells.pop()
        return cell

    def ran_past_its_time(client, cell, index) -> bool:
        client.timed_out = False
        client.execute_cell(cell, index)
        return client.timed_out

    def responsive(client) -> bool:
        """Whether the kernel, interrupted at the end of a cell's time, runs a new cell within
        the grace time."""
        client.timeout, client.timed_out = INTERRUPT_GRACE_SECONDS, False
        try:
            run_extra(client, "pass")
            return not client.timed_out
        except (DeadKernelError, RuntimeError):
            return False
        finally:
            client.timeout = cell_seconds

    notes, skipped = [], set()
    client, stuck = None, None
    for _attempt in range(4):  # a cell that ignores its interrupt is skipped in a fresh kernel
        client = new_client()
        alive, stuck, died = True, None, False
        for index, cell in enumerate(notebook.cells):
            if cell.cell_type != "code":
                continue
            if index in skipped:
                cell.outputs = [nbformat.v4.new_output(
                    "error", ename="GraderSkipped", traceback=[],
                    evalue="not run: in an earlier run it outlasted its time and ignored the "
                           "interrupt, or ended the kernel")]
                continue
            try:
                if ran_past_its_time(client, cell, index):
                    cell.outputs.append(nbformat.v4.new_output(
                        "error", ename="TimeoutError", traceback=[],
                        evalue=f"stopped by the grader: this cell ran longer than "
                               f"{cell_seconds:g} s"))
                    if not responsive(client):
                        stuck = index
                        break
            except DeadKernelError:
                stuck, died = index, True
                break
        if stuck is None:
            break
        notes.append(f"cell {stuck + 1} ended its kernel (os._exit, a crash): the notebook was "
                     "run again in a new kernel without that cell" if died else
                     f"cell {stuck + 1} ran past {cell_seconds:g} s and ignored the interrupt: "
                     "the kernel was stopped and the notebook run again without that cell")
        skipped.add(stuck)
        with contextlib.suppress(Exception):
            run_sync(client.km.shutdown_kernel)(now=True)
        for cell in notebook.cells:
            if cell.cell_type == "code":
                cell.outputs = []
    alive = stuck is None
    nbformat.write(notebook, work / "executed.ipynb")
    kernel = _KernelAnswers(client, cell_seconds) if alive else None
    send({"event": "ran", "alive": kernel is not None and kernel.alive, "limits": limits,
          "notes": notes})
    for line in sys.stdin:
        request = json.loads(line)
        if request.get("op") == "end":
            break
        send(kernel.ask(request) if kernel is not None else {"dead": True})
    if kernel is not None:
        kernel.close()
    with contextlib.suppress(Exception):
        run_sync(client.km.shutdown_kernel)(now=True)
    return 0


# ------------------------------------------------------------------------------ the checker
class _Channel:
    """The checker's line of JSON messages to and from a runner."""

    def __init__(self, process: subprocess.Popen, reply_seconds: float):
        self.process = process
        self.reply_seconds = reply_seconds
        self.lines: queue.Queue = queue.Queue()
        self.stderr: list[str] = []
        self.requests = 0
        threading.Thread(target=self._read_out, daemon=True).start()
        threading.Thread(target=self._read_err, daemon=True).start()

    def _read_out(self) -> None:
        while True:
            line = self.process.stdout.readline(REPLY_BYTES + 1)
            if not line:
                self.lines.put(None)
                return
            self.lines.put(line if len(line) <= REPLY_BYTES else b'{"error": ["GraderError", '
                           b'"a reply longer than the grader accepts"]}')

    def _read_err(self) -> None:
        while True:
            chunk = self.process.stderr.read(65536)
            if not chunk:
                return
            self.stderr = (self.stderr + [chunk.decode("utf-8", "replace")])[-8:]

    def receive(self, seconds: float) -> dict | None:
        """The next message, or None when the runner is gone or silent for ``seconds``."""
        try:
            line = self.lines.get(timeout=seconds)
        except queue.Empty:
            return None
        if line is None:
            self.lines.put(None)  # gone for every later call too
            return None
        try:
            message = json.loads(line)
        except (ValueError, RecursionError):
            return {"error": ["GraderError", "a reply that is not JSON"]}
        return message if isinstance(message, dict) else {"error": ["GraderError", "not JSON"]}

    def ask(self, request: dict) -> dict:
        self.requests += 1
        try:
            self.process.stdin.write((json.dumps(request) + "\n").encode())
            self.process.stdin.flush()
        except OSError:
            return {"dead": True}
        reply = self.receive(self.reply_seconds)
        return {"dead": True} if reply is None else reply


class _StudentFunction:
    """A student's function, as the hidden tests see it: the arguments a test chooses go to the
    kernel as data, and its result comes back as data."""

    def __init__(self, channel: _Channel, name: str, seconds: float):
        self._channel, self._name, self._seconds = channel, name, seconds
        self._timed_out = False

    def __call__(self, *args, **kwargs):
        if kwargs:
            raise TypeError("the grader passes a student's function positional arguments only")
        if self._timed_out:
            # A function that outlasted its time once is not called again: a test that calls it
            # hundreds of times would otherwise wait out each call and use up the grading's
            # total time, and every later question with it.
            raise TimeoutError(f"not called again: an earlier call of {self._name} ran longer "
                               f"than {self._seconds:g} s and was stopped by the grader")
        reply = self._channel.ask({"op": "call", "name": self._name,
                                   "args": [encode_answer(arg) for arg in args]})
        self._timed_out = "timeout" in reply
        return _reply_value(reply, self._name, self._seconds)

    def __repr__(self) -> str:
        return f"<the student's function {self._name}>"


class _Unreadable:
    """An answer that could not be read back (its type is not data); every test of it fails."""

    def __init__(self, why: str):
        self.why = why

    def __repr__(self) -> str:
        return f"<unreadable answer: {self.why}>"


def _reply_value(reply: dict, name: str, seconds: float):
    if "timeout" in reply:
        raise TimeoutError(f"stopped by the grader: {name} ran longer than {seconds:g} s")
    if "dead" in reply:
        raise RuntimeError("the student's kernel is gone (it crashed, exited or was stopped)")
    if "error" in reply:
        ename, evalue = (list(reply["error"]) + ["", ""])[:2]
        ename = re.sub(r"\W", "", str(ename))[:60] or "Error"
        raise type(ename, (Exception,), {})(str(evalue)[:1000])
    value = reply.get("value")
    if isinstance(value, dict) and value.get("unsupported"):
        return _Unreadable(f"{name} is a {str(value['unsupported'])[:80]}, not data")
    return decode_answer(value)


class _StudentAnswers(dict):
    """The answers of the student's kernel, fetched when a test asks for them (otter's test
    cases read their parameters with ``get``)."""

    def __init__(self, channel: _Channel, seconds: float):
        super().__init__()
        self._channel, self._seconds, self._fetched = channel, seconds, {}

    def get(self, name, default=None):
        if name not in self._fetched:
            self._fetched[name] = self._fetch(name)
        return self._fetched[name]

    def _fetch(self, name: str):
        reply = self._channel.ask({"op": "get", "name": name})
        if reply.get("missing") or "dead" in reply:
            return None
        value = reply.get("value")
        if isinstance(value, dict) and value.get("callable") is True:
            return _StudentFunction(self._channel, name, self._seconds)
        try:
            return _reply_value(reply, name, self._seconds)
        except Exception as err:  # a value that does not decode is an answer that fails
            return _Unreadable(f"{type(err).__name__}: {str(err)[:200]}")


def hidden_test_files(zip_path: Path) -> dict[str, str]:
    """Question name -> source of its test file, from the autograder zip."""
    with zipfile.ZipFile(zip_path) as archive:
        return {Path(name).stem: archive.read(name).decode("utf-8")
                for name in sorted(archive.namelist())
                if name.startswith("tests/") and name.endswith(".py")}


def _check_submission(config: dict) -> int:
    """The checker: start the runner (in the sandbox, unless told otherwise), run the hidden
    tests here against its answers, write the results where the sandbox cannot."""
    from otter.test_files.exception_test import ExceptionTestFile

    work, cache = Path(config["work"]), Path(config["cache"])
    sandboxed = config["sandbox"]
    runner = {key: config[key] for key in ("notebook", "cell_seconds", "memory_mb", "processes")}
    runner["work"] = SANDBOX_WORK if sandboxed else str(work)
    command = [sys.executable, SANDBOX_TOOL if sandboxed else str(Path(__file__).resolve()),
               "_run", json.dumps(runner)]
    popen = {"stdin": subprocess.PIPE, "stdout": subprocess.PIPE, "stderr": subprocess.PIPE}
    if sandboxed:
        command = sandbox_command(work, cache, command)
    else:
        popen.update(cwd=work, env={**os.environ, "PYTHONWARNINGS": "ignore", "HOME": str(work),
                                    "MPLBACKEND": "Agg"})
    cell_seconds = float(config["cell_seconds"])
    started_at = time.perf_counter()
    process = subprocess.Popen(command, **popen)
    channel = _Channel(process, cell_seconds + INTERRUPT_GRACE_SECONDS + 30)
    tests, notes = [], []
    started = channel.receive(float(config["total_seconds"]))
    if started is None or started.get("event") != "ran":
        tail = "".join(channel.stderr).strip().splitlines()[-5:]
        notes.append("not graded: the notebook's run ended before it was done"
                     + (":\n" + "\n".join(tail) if tail else ""))
        started = {"alive": False, "notes": []}
    notes += [str(note)[:500] for note in started.get("notes", [])[:20]]
    conditions = [str(note)[:200] for note in started.get("limits", [])[:5]]
    if not started.get("alive"):
        notes.append("the kernel was gone at the end of the run: answers could not be read")
    ran_at = time.perf_counter()
    answers = _StudentAnswers(channel, cell_seconds)
    for name, source in hidden_test_files(Path(config["zip"])).items():
        test_file = ExceptionTestFile.from_string(source, path=f"tests/{name}.py")
        test_file.run(answers)
        tests.append({"name": name, "score": float(test_file.score),
                      "max_score": float(test_file.possible), "output": test_file.summary()})
    with contextlib.suppress(OSError):
        channel.ask({"op": "end"})
    with contextlib.suppress(subprocess.TimeoutExpired):
        process.wait(timeout=10)
    end_process_tree(process)
    conditions.append(f"timing: the notebook ran in {ran_at - started_at:.1f} s, the hidden "
                      f"tests took {time.perf_counter() - ran_at:.1f} s ({channel.requests} "
                      "requests to the kernel)")
    result = {"tests": tests, "score": sum(test["score"] for test in tests), "notes": notes,
              "conditions": conditions}
    Path(config["result"]).write_text(json.dumps(result), encoding="utf-8")
    return 0


# ------------------------------------------------------------------------------ grading
@dataclass
class Grade:
    """The grading of one submission.

    Attributes
    ----------
    submission : Path
    scores, possible : dict of str -> float
        Points earned and points possible per question.
    notes : list of str
        What went wrong with the submission as a whole (not a notebook, empty, cells that
        raised or ran out of time, graded cells missing, grading stopped), and the limits and
        isolation it was graded under, in words.
    outputs : dict of str -> str
        The hidden tests' output per question (which test failed and why).
    results : dict
        The results, in Gradescope's format (``tests``, ``score``), with the notes added.
    executed : nbformat.NotebookNode or None
        The submission as the grader ran it, when it ran.
    seconds : float
        Wall time of the grading.
    """

    submission: Path
    scores: dict[str, float]
    possible: dict[str, float]
    notes: list[str] = field(default_factory=list)
    outputs: dict[str, str] = field(default_factory=dict)
    results: dict = field(default_factory=dict)
    executed: object = None
    seconds: float = 0.0

    @property
    def score(self) -> float:
        return sum(self.scores.values())

    @property
    def max_score(self) -> float:
        return sum(self.possible.values())


def _zero(submission: Path, possible: dict[str, float], reason: str, seconds: float,
          details: tuple[str, ...] = ()) -> Grade:
    """A zero on every question, each test saying why; ``details`` (for the instructor) follow
    the reason in the notes."""
    tests = [{"name": name, "score": 0.0, "max_score": points, "output": reason}
             for name, points in possible.items()]
    notes = [reason, *details]
    results = {"score": 0.0, "tests": tests, "notes": list(notes)}
    return Grade(submission, dict.fromkeys(possible, 0.0), dict(possible), notes,
                 dict.fromkeys(possible, reason), results, None, seconds)


def read_submission(path: Path) -> tuple[nbformat.NotebookNode | None, str | None]:
    """The submission as a notebook, or ``None`` and why it cannot be graded."""
    if not path.is_file():
        return None, f"not graded: {path.name} is not a file"
    if path.suffix != ".ipynb":
        return None, f"not graded: {path.name} is not a notebook (a .ipynb file is expected)"
    text = path.read_text(encoding="utf-8", errors="replace")
    if not text.strip():
        return None, f"not graded: {path.name} is empty"
    try:
        notebook = nbformat.reads(text, as_version=4)
        nbformat.validate(notebook)
    except Exception as err:  # nbformat raises several kinds (JSON, schema, version)
        first_line = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        return None, f"not graded: {path.name} is not a readable notebook ({first_line[:200]})"
    return notebook, None


def missing_checks(notebook: nbformat.NotebookNode, questions) -> list[str]:
    """The questions whose check cell (``grader.check("name")``) is not in the notebook."""
    present = set()
    for cell in notebook.cells:
        if cell.cell_type == "code":
            present.update(_CHECK_CALL.findall(cell.source))
    return [name for name in questions if name not in present]


def _cell_problems(executed) -> list[str]:
    """One note per cell of the graded run that raised (a timeout included)."""
    notes = []
    for cell in executed.cells:
        if cell.cell_type != "code":
            continue
        for output in cell.get("outputs", []):
            if output.get("output_type") == "error":
                first = cell.source.strip().splitlines()[0][:60] if cell.source.strip() else ""
                notes.append(f"a cell raised {str(output.get('ename'))[:60]}: "
                             f"{str(output.get('evalue'))[:200]} (cell starting {first!r})")
    return notes[:30]


#: The checkers running now: ended all at once when the grading is interrupted.
_RUNNING: set[subprocess.Popen] = set()
_RUNNING_LOCK = threading.Lock()
_STOPPING = threading.Event()


def end_all_gradings() -> None:
    """End every grading under way (each checker, its runner, its sandbox)."""
    _STOPPING.set()
    with _RUNNING_LOCK:
        running = list(_RUNNING)
    for process in running:
        end_process_tree(process)


def isolation_note(sandbox: bool) -> str:
    if sandbox:
        return ("isolation: bubblewrap sandbox (no network, no home, read-only Python and "
                "packages, private /tmp and work folder, own process namespace)")
    return (f"isolation: none ({NO_SANDBOX_FLAG}): the submission's code ran with the "
            "instructor's rights, files and network")


def grade(folder: Path, submission: Path, *, cell_seconds: float = CELL_SECONDS,
          total_seconds: float = TOTAL_SECONDS, memory_mb: float = MEMORY_MB,
          processes: int = PROCESSES, sandbox: bool = True, cache: Path | None = None,
          warm_cache: bool = False) -> Grade:
    """Grade one submission with the hidden tests of the built assignment ``folder``.

    Parameters
    ----------
    folder : Path
        ``dist/assignments/<name>`` as made by :func:`build`.
    submission : Path
        The student's notebook.
    cell_seconds : float
        Time limit of each cell, and of each call of a student's function by a test [s].
    total_seconds : float
        Time limit of the whole grading [s]: past it, the checker and the sandbox are ended.
    memory_mb : float
        Address space of each process of the submission [MB].
    processes : int
        Processes and threads the submission may have at once.
    sandbox : bool
        Run the submission in the sandbox (Linux with bubblewrap); ``False`` runs it without
        any isolation, with the instructor's rights.
    cache : Path or None
        Compiled kernels the sandbox starts from (a copy: what a submission compiles is thrown
        away with it); ``warm_cache`` binds this folder itself, writable, to fill it (for the
        solutions only).

    Returns
    -------
    Grade
        Never raises for a bad submission: it scores zero where it could not be graded, and
        ``notes`` and ``outputs`` say why. Raises :class:`SandboxUnavailable` when ``sandbox``
        is asked for and there is none, ``ValueError`` for limits that are not positive.
    """
    if min(cell_seconds, total_seconds, memory_mb, processes) <= 0:
        raise ValueError("`cell_seconds`, `total_seconds`, `memory_mb` and `processes` must be "
                         "positive")
    if sandbox and (problem := sandbox_problem()):
        raise SandboxUnavailable(f"{problem}; to grade without isolation, with your own "
                                 f"rights, pass {NO_SANDBOX_FLAG}")
    started = time.perf_counter()
    folder, submission = Path(folder).resolve(), Path(submission)
    possible = question_points(folder)
    notebook, problem = read_submission(submission)
    if notebook is None:
        return _zero(submission, possible, problem, time.perf_counter() - started)
    conditions = [isolation_note(sandbox),
                  f"limits: {cell_seconds:g} s per cell, {total_seconds:g} s in all, "
                  f"{memory_mb:g} MB of memory per process, {processes} processes"]
    notes = []
    if not any(cell.cell_type == "code" for cell in notebook.cells):
        notes.append("the notebook has no code cells")
    notes += [f"the check cell of {name} is missing (were the graded cells deleted?)"
              for name in missing_checks(notebook, possible)]
    private = Path(tempfile.mkdtemp(prefix="grading-"))
    try:
        work, own_cache = private / "work", private / "cache"
        work.mkdir()
        if warm_cache and cache is not None:
            cache.mkdir(parents=True, exist_ok=True)
            own_cache = cache
        elif cache is not None and cache.is_dir():
            shutil.copytree(cache, own_cache, symlinks=True)
        else:
            own_cache.mkdir()
        # Under the name it was handed out with: its first cell opens the notebook by name.
        nbformat.write(notebook, work / f"{folder.name}.ipynb")
        config = {"zip": str(autograder_zip(folder)), "work": str(work),
                  "cache": str(own_cache), "notebook": f"{folder.name}.ipynb",
                  "cell_seconds": cell_seconds, "total_seconds": total_seconds,
                  "memory_mb": memory_mb, "processes": processes, "sandbox": sandbox,
                  "result": str(private / "result.json")}
        (private / "check.json").write_text(json.dumps(config), encoding="utf-8")
        process = subprocess.Popen(
            [sys.executable, str(Path(__file__).resolve()), "_check",
             str(private / "check.json")], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
            env={**os.environ, "PYTHONWARNINGS": "ignore"}, **_new_group())
        with _RUNNING_LOCK:
            _RUNNING.add(process)
        try:
            log, _ = process.communicate(timeout=total_seconds)
        except subprocess.TimeoutExpired:
            end_process_tree(process)
            reason = (f"not graded: the grading was stopped after {total_seconds:g} s "
                      "(a cell that never ends?); every process of it was ended")
            graded = _zero(submission, possible, reason, time.perf_counter() - started)
            graded.results["notes"] += conditions
            return graded
        finally:
            with _RUNNING_LOCK:
                _RUNNING.discard(process)
        result_file = private / "result.json"
        if not result_file.exists():
            tail = "\n".join(log.decode("utf-8", "replace").strip().splitlines()[-8:])
            reason = ("not graded: the grading was interrupted" if _STOPPING.is_set() else
                      f"not graded: the checker stopped with an error:\n{tail}")
            return _zero(submission, possible, reason, time.perf_counter() - started)
        results = json.loads(result_file.read_text(encoding="utf-8"))
        executed = None
        executed_file = work / "executed.ipynb"
        if executed_file.is_file() and executed_file.stat().st_size < 64 * 1024 * 1024:
            with contextlib.suppress(Exception):
                executed = nbformat.read(executed_file, as_version=4)
    finally:
        shutil.rmtree(private, ignore_errors=True)
    notes += results["notes"]
    if executed is not None:
        notes += _cell_problems(executed)
    scores, outputs = dict.fromkeys(possible, 0.0), {}
    for test in results["tests"]:
        if test["name"] in possible:
            scores[test["name"]] = test["score"]
            outputs[test["name"]] = test["output"]
    results["notes"] = notes + conditions + results.pop("conditions", [])
    return Grade(submission, scores, dict(possible), notes, outputs, results, executed,
                 time.perf_counter() - started)


# ------------------------------------------------------------------------------ a class
def submission_digest(path: Path) -> str:
    """The SHA-256 of a submission's bytes: a re-run grades a submission again only if it
    changed."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def submission_names(submissions: list[Path], root: Path) -> dict[str, Path]:
    """Each submission's name: its path relative to ``root``, with ``/`` between folders (so
    ``alice/hw.ipynb`` and ``bob/hw.ipynb`` stay apart). Raises ValueError for a submission
    outside ``root`` or one given twice."""
    names: dict[str, Path] = {}
    root = root.resolve()
    for path in submissions:
        resolved = Path(os.path.abspath(path))
        try:
            name = resolved.relative_to(root).as_posix()
        except ValueError:
            raise ValueError(f"submission {path} is not under --root {root}: name a --root "
                             "that holds every submission (their names are paths below it)"
                             ) from None
        if name in names:
            raise ValueError(f"submission {name} is given twice")
        names[name] = resolved
    return names


class Gradebook:
    """``grades.csv`` of an output folder: one row per submission, kept across runs; written
    whole (through a temporary file) after every grading, so that an interrupted run keeps what
    it graded."""

    def __init__(self, path: Path, questions: list[str]):
        self.path, self.questions = path, list(questions)
        self.columns = ["submission", *self.questions, "total", "sha256"]
        self.rows: dict[str, dict] = {}
        if path.exists():
            with open(path, newline="", encoding="utf-8") as handle:
                reader = csv.DictReader(handle)
                if reader.fieldnames != self.columns:
                    raise ValueError(f"{path} has the columns {reader.fieldnames}, not this "
                                     f"assignment's {self.columns}: give another -o folder")
                self.rows = {row["submission"]: row for row in reader}

    def unchanged(self, name: str, digest: str) -> bool:
        row = self.rows.get(name)
        return row is not None and row.get("sha256") == digest

    def record(self, name: str, graded: Grade, digest: str) -> None:
        self.rows[name] = {"submission": name, **{q: f"{graded.scores[q]:g}"
                                                   for q in self.questions},
                           "total": f"{graded.score:g}", "sha256": digest}

    def save(self) -> None:
        temporary = self.path.with_name(self.path.name + ".tmp")
        with open(temporary, "w", newline="", encoding="utf-8") as handle:
            writer = csv.DictWriter(handle, fieldnames=self.columns)
            writer.writeheader()
            writer.writerows(self.rows[name] for name in sorted(self.rows))
        os.replace(temporary, self.path)


def results_path(out: Path, name: str) -> Path:
    """Where a submission's results go: its name's path under ``out``, ending in ``.json``."""
    return out.joinpath(*name.split("/")).with_suffix(".json")


def warm_cache(folder: Path, cache: Path, **limits) -> Grade:
    """Fill ``cache`` with the compiled kernels of the assignment's solutions, graded in the
    sandbox with ``cache`` writable (the instructor's own notebook: every submission's sandbox
    then starts from a copy)."""
    return grade(folder, folder / "autograder" / f"{folder.name}.ipynb", cache=cache,
                 warm_cache=True, **limits)


def grade_class(folder: Path, submissions: dict[str, Path], out: Path, *, jobs: int,
                regrade: bool = False, progress: bool = True, **limits) -> dict[str, Grade]:
    """Grade ``submissions`` (name -> path) into ``out``, ``jobs`` at a time; return the grades
    made. ``grades.csv`` and each ``<name>.json`` are written as each grading ends; on
    KeyboardInterrupt every grading under way is ended, the CSV of what was graded is written
    and the interrupt raised again."""
    from tqdm import tqdm

    if jobs < 1:
        raise ValueError(f"`jobs` must be at least 1, got {jobs}")
    out.mkdir(parents=True, exist_ok=True)
    book = Gradebook(out / "grades.csv", list(question_points(folder)))
    digests = {name: submission_digest(path) if path.is_file() else "" for name, path in
               submissions.items()}
    todo = {name: path for name, path in submissions.items()
            if regrade or not book.unchanged(name, digests[name])
            or not results_path(out, name).exists()}
    skipped = len(submissions) - len(todo)
    if skipped:
        print(f"{skipped} submissions unchanged since they were graded: kept (--regrade to "
              "grade them again)")
    sandboxed = limits.get("sandbox", True)
    runs_kernels = any(read_submission(path)[0] is not None for path in todo.values())
    if sandboxed and runs_kernels and "cache" not in limits:
        limits["cache"] = out / ".kernel-cache"
        if not (limits["cache"] / "ready").exists():
            print("compiling the integrators once for the sandboxes (the solutions graded "
                  "into out/.kernel-cache) ...", flush=True)
            warm_cache(folder, limits["cache"], **{k: v for k, v in limits.items()
                                                    if k != "cache"})
            (limits["cache"] / "ready").write_text("", encoding="utf-8")
    _STOPPING.clear()
    graded: dict[str, Grade] = {}
    bar = tqdm(total=len(todo), unit="submission", disable=not progress, smoothing=0.05,
               dynamic_ncols=True)
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        pending = {pool.submit(grade, folder, path, **limits): name
                   for name, path in todo.items()}
        try:
            while pending:
                done, _ = wait(pending, timeout=0.5, return_when=FIRST_COMPLETED)
                for future in done:
                    name = pending.pop(future)
                    result = future.result()
                    target = results_path(out, name)
                    target.parent.mkdir(parents=True, exist_ok=True)
                    target.write_text(json.dumps(result.results, indent=1), encoding="utf-8")
                    book.record(name, result, digests[name])
                    book.save()
                    graded[name] = result
                    bar.write(f"{name}: {result.score:g}/{result.max_score:g} in "
                              f"{result.seconds:.1f} s")
                    for note in result.notes:
                        bar.write(f"    note: {note}")
                    bar.update(1)
        except BaseException:
            for future in pending:
                future.cancel()
            end_all_gradings()
            book.save()
            bar.close()
            raise
    bar.close()
    book.save()
    return graded


# ------------------------------------------------------------------------------ commands
def _build_command(args) -> int:
    # The solutions are the instructor's own: graded in the sandbox where there is one.
    sandbox = sandbox_problem() is None
    for master in masters(args.names):
        start = time.perf_counter()
        folder = build(master, Path(args.dist).resolve())
        points = question_points(folder)
        line = (f"{master.stem}: {len(points)} questions, {sum(points.values()):g} points "
                f"({', '.join(f'{q} {p:g}' for q, p in points.items())}); built in "
                f"{time.perf_counter() - start:.1f} s")
        if args.check:
            # The kernels compiled here serve the later solutions' sandboxes too.
            solutions = grade(folder, folder / "autograder" / master.name, sandbox=sandbox,
                              cache=Path(args.dist).resolve() / ".kernel-cache",
                              warm_cache=True)
            line += (f"; solutions score {solutions.score:g}/{solutions.max_score:g} "
                     f"(graded in {solutions.seconds:.1f} s)")
            if solutions.score != solutions.max_score:
                print(line)
                for name, text in solutions.outputs.items():
                    if solutions.scores[name] != solutions.possible[name]:
                        print(f"--- {name}\n{text}")
                return 1
        print(line, flush=True)
    return 0


def _grade_command(args) -> int:
    folder = Path(args.dist).resolve() / args.name
    autograder_zip(folder)
    if args.sandbox and (problem := sandbox_problem()):
        raise SandboxUnavailable(f"{problem}. Grading runs each submission's code; without a "
                                 f"sandbox it runs with your rights, your files and your "
                                 f"network. To do that anyway, pass {NO_SANDBOX_FLAG}")
    names = submission_names([Path(s) for s in args.submissions], Path(args.root))
    out = Path(args.output).resolve()
    limits = {"cell_seconds": args.cell_seconds, "total_seconds": args.total_seconds,
              "memory_mb": args.memory_mb, "processes": args.processes,
              "sandbox": args.sandbox}
    if not args.sandbox:
        print(f"warning: {NO_SANDBOX_FLAG}: submissions run with your rights, files and "
              "network, and a process they leave behind survives the grading", file=sys.stderr)
    previous = signal.getsignal(signal.SIGTERM) if hasattr(signal, "SIGTERM") else None

    def terminate(signum, frame):
        raise KeyboardInterrupt

    if previous is not None:
        signal.signal(signal.SIGTERM, terminate)
    try:
        grade_class(folder, names, out, jobs=args.jobs, regrade=args.regrade,
                    progress=sys.stderr.isatty() or args.progress, **limits)
    except KeyboardInterrupt:
        print(f"interrupted: every grading under way was ended; {out / 'grades.csv'} holds "
              "what was graded (run again to grade the rest)", file=sys.stderr)
        return 130
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)
    print(f"grades: {out / 'grades.csv'}")
    return 0


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] == ["_run"]:  # inside the sandbox
        return _run_submission(json.loads(argv[1]))
    if argv[:1] == ["_check"]:
        return _check_submission(json.loads(Path(argv[1]).read_text(encoding="utf-8")))
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--dist", default=str(DIST),
                        help="built assignments (dist/assignments; relative to the current "
                             "folder)")
    commands = parser.add_subparsers(dest="command", required=True)
    build_parser = commands.add_parser("build", help="otter assign every (or each named) master")
    build_parser.add_argument("names", nargs="*", help="assignment names (default: all)")
    build_parser.add_argument("--no-check", dest="check", action="store_false",
                              help="do not grade the solutions after building")
    grade_parser = commands.add_parser("grade", help="grade submissions of one assignment")
    grade_parser.add_argument("name", help="the assignment (e.g. 01_derivations_and_fixed_points)")
    grade_parser.add_argument("submissions", nargs="+", help="submitted notebooks")
    grade_parser.add_argument("-o", "--output", default="graded",
                              help="results folder (graded): grades.csv and one JSON each")
    grade_parser.add_argument("--root", default=".",
                              help="submissions are named by their path below this folder "
                                   "(default: the current folder)")
    grade_parser.add_argument("--jobs", "-j", type=int, default=os.cpu_count() or 1,
                              help="gradings side by side (default: the cores)")
    grade_parser.add_argument("--regrade", action="store_true",
                              help="grade again the submissions that did not change")
    grade_parser.add_argument("--cell-seconds", type=float, default=CELL_SECONDS)
    grade_parser.add_argument("--total-seconds", type=float, default=TOTAL_SECONDS)
    grade_parser.add_argument("--memory-mb", type=float, default=MEMORY_MB)
    grade_parser.add_argument("--processes", type=int, default=PROCESSES)
    grade_parser.add_argument("--progress", action="store_true",
                              help="show the progress bar even when not on a terminal")
    grade_parser.add_argument(NO_SANDBOX_FLAG, dest="sandbox", action="store_false",
                              help="grade without the sandbox (where bubblewrap is missing: "
                                   "macOS, Windows): the submissions' code runs with your "
                                   "rights, files and network")
    args = parser.parse_args(argv)
    try:
        return _build_command(args) if args.command == "build" else _grade_command(args)
    except (ValueError, FileNotFoundError, RuntimeError) as err:
        print(f"assignments: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
