"""The ways in, tried as a newcomer tries them: the README's student command in a fresh clone,
and the wheel and the sdist installed into fresh environments outside the repository.

* The README's student commands (section "Open the course") are parsed from the README, so the
  two cannot drift apart, and the one for this OS runs verbatim in a ``git clone`` of the
  repository (the tracked files as they are in the working tree): it must create ``.venv``,
  install, print the launcher's help, and on a second run open JupyterLab on the course without
  installing again. The student's ``python3`` is Python 3.12 when this machine has it (the main
  environment runs on the newest supported Python, the floors on the oldest; this is the one in
  between), else the ``python3`` on ``PATH``.
* ``python -m build`` makes the sdist and, from the sdist, the wheel (so the wheel proves that
  the sdist holds everything it needs); their contents are checked, then each is installed into
  a fresh virtual environment in a temporary folder, where ``pendulum-lab --help`` works, the
  launcher copies the course to a folder of the student's, and notebook 00 runs headless
  (nbclient).

Installing the dependencies takes minutes, so they are installed once, by the student command,
and the two fresh environments see them through a ``.pth`` file naming a folder of links to
that environment's packages, pendulum_lab's own left out; pendulum_lab itself is installed from
the wheel or the sdist (``--no-deps``). What is checked is what the artifacts bring; that their
dependencies resolve is what the student command (and every ``make`` environment) checks.

These tests start servers and environments of their own: they run in the environments job of
``make test`` (tools/run_tests.py). A missing tool (git, the ``build`` package) skips them with
the reason, except under ``CI=true``, where it fails them.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tarfile
import time
import urllib.error
import urllib.request
import zipfile
from pathlib import Path

import pytest
from repository_scripts import load_script

REPO_ROOT = Path(__file__).resolve().parents[2]
README = REPO_ROOT / "README.md"
STUDENT_SECTION = "## Open the course"
# The README's fenced block of each OS: its language tag, and the interpreter it must name.
STUDENT_BLOCKS = {"bat": "py", "sh": "python3"}
find_python = load_script("tools/find_python.py")

WINDOWS = os.name == "nt"


def skip_or_fail(reason: str) -> None:
    """Skip with ``reason``; under ``CI=true`` fail with it instead (CI must run the test)."""
    if os.environ.get("CI", "").strip().lower() == "true":
        pytest.fail(f"{reason} (CI=true: this test must run in CI)", pytrace=False)
    pytest.skip(reason)


# --------------------------------------------------------------------------- the README
def student_commands(readme: str) -> dict[str, str]:
    """``{language tag: command}`` of the fenced blocks in the README's student section.

    Raises ``ValueError`` unless the section holds exactly one one-line block per OS
    (``STUDENT_BLOCKS``), each naming its interpreter, with the same words after it.
    """
    if STUDENT_SECTION not in readme:
        raise ValueError(f"the README has no section {STUDENT_SECTION!r}")
    section = readme.split(STUDENT_SECTION, 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"^```(\w+)\n(.*?)^```", section, flags=re.MULTILINE | re.DOTALL)
    commands = {tag: body.strip() for tag, body in blocks}
    if sorted(tag for tag, _ in blocks) != sorted(STUDENT_BLOCKS):
        raise ValueError(f"expected one block each of {sorted(STUDENT_BLOCKS)}, found "
                         f"{[tag for tag, _ in blocks]}")
    rests = set()
    for tag, command in commands.items():
        words = command.split()
        if "\n" in command or not words or words[0] != STUDENT_BLOCKS[tag]:
            raise ValueError(f"the {tag} block must be one line starting with "
                             f"{STUDENT_BLOCKS[tag]!r}: {command!r}")
        if "#" in command:  # cmd has no comments: the line must be pasteable as it is
            raise ValueError(f"the {tag} block carries a comment: {command!r}")
        rests.add(tuple(words[1:]))
    if len(rests) != 1:
        raise ValueError(f"the blocks differ beyond the interpreter: {commands}")
    return commands


def test_the_readme_shows_one_command_for_every_os():
    commands = student_commands(README.read_text(encoding="utf-8"))
    script = commands["sh"].split()[1]
    assert (REPO_ROOT / script).is_file(), script
    # Negative controls: a README without the Windows block, or with different commands, fails.
    text = README.read_text(encoding="utf-8")
    with pytest.raises(ValueError, match="one block each"):
        student_commands(text.replace("```bat\n", "```text\n", 1))
    with pytest.raises(ValueError, match="differ"):
        student_commands(text.replace("py open_course.py", "py open_course.py --dir x", 1))
    with pytest.raises(ValueError, match="comment"):
        student_commands(text.replace("py open_course.py", "py open_course.py  # Windows", 1))


# --------------------------------------------------------------------------- a fresh clone
def _git(*args: str, cwd: Path) -> str:
    done = subprocess.run(["git", *args], cwd=cwd, capture_output=True, text=True, timeout=300,
                          check=False)
    if done.returncode != 0:
        raise RuntimeError(f"git {' '.join(args)}: {done.stderr}")
    return done.stdout.strip()


@pytest.fixture(scope="module")
def fresh_clone(tmp_path_factory) -> Path:
    """A ``git clone`` of the repository, at its tracked files as the working tree has them."""
    if shutil.which("git") is None:
        skip_or_fail("git is not installed")
    try:
        _git("rev-parse", "--git-dir", cwd=REPO_ROOT)
    except RuntimeError:
        skip_or_fail(f"{REPO_ROOT} is not a git repository (an unpacked sdist?)")
    # A commit of the working tree's changes to tracked files (none: HEAD), shared by the clone.
    snapshot = _git("stash", "create", cwd=REPO_ROOT) or _git("rev-parse", "HEAD", cwd=REPO_ROOT)
    clone = tmp_path_factory.mktemp("clone") / "pendulum_lab"
    _git("clone", "--quiet", "--shared", "--no-checkout", str(REPO_ROOT), str(clone),
         cwd=REPO_ROOT)
    _git("checkout", "--quiet", "--detach", snapshot, cwd=clone)
    return clone


def _student_python() -> str | None:
    """The interpreter the student's ``python3`` stands for: 3.12 here if found, else PATH's."""
    return find_python.find((3, 12))


@pytest.fixture(scope="module")
def student_env(fresh_clone, tmp_path_factory) -> dict[str, str]:
    """The environment variables of a student's shell, whose ``python3`` is ``_student_python``."""
    home = tmp_path_factory.mktemp("student_home")
    env = {k: v for k, v in os.environ.items()
           if k not in ("VIRTUAL_ENV", "PYTHONPATH", "PYTHONHOME", "JUPYTER_PATH", "CONDA_PREFIX")}
    for name in ("JUPYTER_CONFIG_DIR", "JUPYTER_DATA_DIR", "JUPYTER_RUNTIME_DIR", "IPYTHONDIR",
                 "MPLCONFIGDIR"):
        env[name] = str(home / name.lower())
    env["PENDULUM_LAB_CACHE"] = str(home / "kernels")
    env["NUMBA_CACHE_DIR"] = str(home / "numba")
    python = _student_python()
    if python is not None and not WINDOWS:
        shims = home / "bin"
        shims.mkdir()
        (shims / "python3").symlink_to(python)
        env["PATH"] = f"{shims}{os.pathsep}{env.get('PATH', '')}"
    return env


def _student_line() -> str:
    return student_commands(README.read_text(encoding="utf-8"))["bat" if WINDOWS else "sh"]


@pytest.fixture(scope="module")
def student_install(fresh_clone, student_env) -> Path:
    """The README's command with ``--help``, run verbatim in the fresh clone: the first run."""
    done = subprocess.run(f"{_student_line()} --help", shell=True, cwd=fresh_clone,
                          env=student_env, capture_output=True, text=True,
                          stdin=subprocess.DEVNULL, timeout=3600, check=False)
    output = done.stdout + done.stderr
    assert done.returncode == 0, output[-6000:]
    assert "usage: pendulum-lab" in done.stdout, output[-3000:]
    assert "installing pendulum_lab" in output  # the first run installs
    return fresh_clone / ".venv"


def _venv_bin(venv: Path) -> Path:
    return venv / ("Scripts" if WINDOWS else "bin")


@pytest.mark.slow
def test_the_student_command_installs_the_launcher(student_install, student_env):
    assert (student_install / ".installed-lab").is_file()
    launcher = _venv_bin(student_install) / "pendulum-lab"
    done = subprocess.run([str(launcher), "--help"], env=student_env, capture_output=True,
                          text=True, timeout=600, check=False)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "usage: pendulum-lab" in done.stdout and "warmup" in done.stdout
    # The environment runs on the student's Python (the interpreter the command was given).
    wanted = _student_python()
    if wanted is not None and not WINDOWS:
        probe = subprocess.run([str(_venv_bin(student_install) / "python"), "-c",
                                "import sys; print('%d.%d' % sys.version_info[:2])"],
                               capture_output=True, text=True, timeout=300, check=True)
        assert probe.stdout.strip() == "3.12"


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def _get(url: str) -> tuple[int, object]:
    try:
        with urllib.request.urlopen(url, timeout=60) as response:  # noqa: S310 (loopback)
            return response.status, json.loads(response.read())
    except urllib.error.HTTPError as err:
        return err.code, None


@pytest.mark.slow
def test_the_student_command_opens_the_course(student_install, student_env, tmp_path):
    port = _free_port()
    log = tmp_path / "lab.log"
    with log.open("w") as sink:
        server = subprocess.Popen(f"{_student_line()} --no-browser --port {port}", shell=True,
                                  cwd=student_install.parent, env=student_env, stdout=sink,
                                  stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                  start_new_session=not WINDOWS)
    try:
        address = re.compile(rf"http://(?:localhost|127\.0\.0\.1):{port}/lab\S*token=(\w+)")
        deadline = time.monotonic() + 600
        while (found := address.search(log.read_text(errors="replace"))) is None:
            assert server.poll() is None, log.read_text(errors="replace")[-4000:]
            assert time.monotonic() < deadline, log.read_text(errors="replace")[-4000:]
            time.sleep(1.0)
        api = f"http://127.0.0.1:{port}/api/contents"
        status, listing = _get(f"{api}?token={found.group(1)}")
        assert status == 200
        shown = {item["name"] for item in listing["content"] if item["type"] == "notebook"}
        course = {path.name for path in (student_install.parent / "notebooks").glob("*.ipynb")}
        assert "00_start_here.ipynb" in shown and shown == course
        # Negative control: the same request for a notebook that is not there fails.
        assert _get(f"{api}/no_such_notebook.ipynb?token={found.group(1)}")[0] == 404
    finally:
        if WINDOWS:
            server.terminate()
        else:  # the command became JupyterLab (exec); its session holds the kernel, if any
            os.killpg(server.pid, signal.SIGTERM)
        try:
            server.wait(timeout=60)
        except subprocess.TimeoutExpired:
            if not WINDOWS:
                os.killpg(server.pid, signal.SIGKILL)
            server.wait(timeout=60)
    text = log.read_text(errors="replace")
    assert "installing pendulum_lab" not in text, text[-3000:]  # second run: nothing installed
    assert "00_start_here.ipynb" in text  # opened at the start notebook


# --------------------------------------------------------------------------- wheel and sdist
@pytest.fixture(scope="module")
def distributions(fresh_clone, tmp_path_factory) -> dict[str, Path]:
    """``python -m build`` of the fresh clone: the sdist, then the wheel built from it."""
    try:
        import build  # noqa: F401
    except ImportError:
        skip_or_fail("the `build` package is not installed (the test extra has it)")
    out = tmp_path_factory.mktemp("dist")
    done = subprocess.run([sys.executable, "-m", "build", "--outdir", str(out), str(fresh_clone)],
                          capture_output=True, text=True, stdin=subprocess.DEVNULL, timeout=1800,
                          check=False)
    assert done.returncode == 0, (done.stdout + done.stderr)[-6000:]
    (wheel,) = out.glob("*.whl")
    (sdist,) = out.glob("*.tar.gz")
    return {"wheel": wheel, "sdist": sdist}


def _tracked(clone: Path, folder: str) -> set[str]:
    return set(_git("ls-files", folder, cwd=clone).splitlines())


def test_the_wheel_holds_the_package_and_the_course_and_no_tests(distributions, fresh_clone):
    names = zipfile.ZipFile(distributions["wheel"]).namelist()
    package = {name for name in names if not name.startswith(("pendulum_lab/notebooks/",
                                                              "pendulum_lab-"))}
    # Every tracked file of the package, the widgets' JavaScript and CSS among them, and no other.
    expected = {path.removeprefix("src/") for path in _tracked(fresh_clone, "src/pendulum_lab")}
    assert package == expected
    assert any(name.endswith(".js") for name in package)
    assert any(name.endswith(".css") for name in package)
    course = {name.removeprefix("pendulum_lab/notebooks/") for name in names
              if name.startswith("pendulum_lab/notebooks/")}
    assert course == {path.name for path in (fresh_clone / "notebooks").glob("*.ipynb")}
    assert not [name for name in names if Path(name).name == "conftest.py"]
    metadata = zipfile.ZipFile(distributions["wheel"]).read(
        next(name for name in names if name.endswith(".dist-info/METADATA"))).decode()
    assert "License-Expression: MIT" in metadata
    assert any(name.endswith(".dist-info/licenses/LICENSE") for name in names)
    assert {f"Programming Language :: Python :: 3.{minor}" for minor in (11, 12, 13)} <= {
        line.removeprefix("Classifier: ") for line in metadata.splitlines()}


def test_the_sdist_holds_what_the_wheel_is_built_from(distributions, fresh_clone):
    with tarfile.open(distributions["sdist"]) as archive:
        names = {name.split("/", 1)[1] for name in archive.getnames() if "/" in name}
    for needed in ("pyproject.toml", "README.md", "LICENSE"):
        assert needed in names
    assert _tracked(fresh_clone, "notebooks") <= names
    assert _tracked(fresh_clone, "src/pendulum_lab") <= names
    assert "docs/notebooks" not in names  # the link to ../notebooks, which hid the real folder
    # Negative control of the wheel's check above: the same search finds the hooks here.
    assert "notebooks/conftest.py" in names


def _shared_dependencies(student_venv: Path, folder: Path) -> Path:
    """A folder of links to the student environment's packages, pendulum_lab's left out."""
    purelib = subprocess.run(
        [str(_venv_bin(student_venv) / "python"), "-c",
         "import sysconfig; print(sysconfig.get_path('purelib'))"],
        capture_output=True, text=True, timeout=300, check=True).stdout.strip()
    folder.mkdir(exist_ok=True)
    for entry in Path(purelib).iterdir():
        own = entry.name.lower().lstrip("_").startswith(("pendulum_lab", "editable"))
        if not own and not (folder / entry.name).exists():
            (folder / entry.name).symlink_to(entry)
    return folder


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["wheel", "sdist"])
def test_installed_from_each_distribution_the_course_runs(kind, distributions, student_install,
                                                          student_env, tmp_path_factory):
    if WINDOWS:
        pytest.skip("the shared dependencies are symbolic links, a POSIX layout")
    outside = tmp_path_factory.mktemp(f"from_{kind}")
    python = _student_python() or "python3"
    venv = outside / "env"
    subprocess.run([python, "-m", "venv", str(venv)], check=True, timeout=600,
                   env=student_env)
    shared = _shared_dependencies(student_install, student_install.parent.parent / "shared")
    purelib = subprocess.run([str(venv / "bin" / "python"), "-c",
                              "import sysconfig; print(sysconfig.get_path('purelib'))"],
                             capture_output=True, text=True, timeout=300,
                             check=True).stdout.strip()
    Path(purelib, "student_dependencies.pth").write_text(f"{shared}\n")
    installed = subprocess.run([str(venv / "bin" / "python"), "-m", "pip", "install", "--quiet",
                                "--no-deps", str(distributions[kind])],
                               capture_output=True, text=True, stdin=subprocess.DEVNULL,
                               timeout=1800, env=student_env, check=False)
    assert installed.returncode == 0, installed.stderr[-4000:]

    work = outside / "student"
    work.mkdir()
    run = {"cwd": work, "env": student_env, "capture_output": True, "text": True,
           "stdin": subprocess.DEVNULL}
    helped = subprocess.run([str(venv / "bin" / "pendulum-lab"), "--help"], timeout=600, **run)
    assert helped.returncode == 0 and "usage: pendulum-lab" in helped.stdout, helped.stderr
    where = subprocess.run([str(venv / "bin" / "python"), "-c",
                            "import pendulum_lab; print(pendulum_lab.__file__)"],
                           timeout=600, check=True, **run).stdout.strip()
    assert Path(where).is_relative_to(purelib), where  # this install's, not the clone's

    # The launcher copies the course, then starts JupyterLab (asked only for its version here).
    copied = subprocess.run([str(venv / "bin" / "pendulum-lab"), "lab", "--dir", "course", "--",
                             "--version"], timeout=900, **run)
    assert copied.returncode == 0, copied.stdout + copied.stderr
    assert "Course notebooks in" in copied.stdout
    course = work / "course"
    assert {path.name for path in course.iterdir()} == {
        path.name for path in (student_install.parent / "notebooks").glob("*.ipynb")}

    # Notebook 00 runs headless, in a kernel of this environment.
    execute = (
        "import sys, nbformat, nbclient\n"
        "nb = nbformat.read('00_start_here.ipynb', as_version=4)\n"
        "nb.cells.append(nbformat.v4.new_code_cell('import sys; print(sys.prefix)'))\n"
        "nbclient.NotebookClient(nb, timeout=900, kernel_name='python3').execute()\n"
        "print(nb.cells[-1].outputs[0]['text'].strip())\n"
    )
    ran = subprocess.run([str(venv / "bin" / "python"), "-c", execute], cwd=course,
                         env=student_env, capture_output=True, text=True,
                         stdin=subprocess.DEVNULL, timeout=1800)
    assert ran.returncode == 0, (ran.stdout + ran.stderr)[-6000:]
    assert Path(ran.stdout.strip().splitlines()[-1]).resolve() == venv.resolve()
