"""The Binder configuration in ``binder/`` is complete, exactly pinned, and works.

Once ``binder/`` exists, repo2docker ignores the files at the repository root, including
``pyproject.toml``: ``binder/requirements.txt`` must therefore pin every runtime dependency of
the package, the lab and kernel, and the widget front-end packages that must match ipywidgets,
and install the package itself with ``-e .``.

The fast tests read the files. The ``slow`` tests prove the configuration without Docker:
``jupyter-repo2docker --no-build .`` must accept it and pick the Python build pack with our
runtime, and a fresh virtual environment built only from ``binder/requirements.txt`` must
hold exactly the pins and run the notebooks of :data:`BINDER_NOTEBOOKS` under nbval. Every
notebook runs, and has its checked outputs compared, in JupyterLab with the newest versions the
ranges allow (tests/browser). As with the browser tests, a missing tool skips those tests with
the reason, except under ``CI=true``, where it fails them.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import tomllib
import warnings
from importlib import metadata
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.specifiers import SpecifierSet
from packaging.version import Version
from repository_scripts import load_script

REPO_ROOT = Path(__file__).resolve().parents[2]
BINDER = REPO_ROOT / "binder"
REQUIREMENTS = BINDER / "requirements.txt"
RUNTIME = BINDER / "runtime.txt"
VENV_CACHE = REPO_ROOT / "test-artifacts" / "binder-venv"

# Needed on Binder beyond the package's own dependencies: the lab, the kernel, and the two
# front-end packages that must be in step with ipywidgets (else "Error displaying widget").
BINDER_ALSO_NEEDS = ("jupyterlab", "ipykernel", "jupyterlab_widgets", "widgetsnbextension")

# What Binder's pinned versions must run under nbval: the notebook a Binder link opens first
# (the package, a first simulation, its figures), the live simulator (the widget packages the
# pins add) and the phase portraits (SciPy, whose pinned release is older than the newest).
# Running every notebook here as well would run the course twice in one `make test` (about six
# minutes); tests/browser runs all of them.
BINDER_NOTEBOOKS = ("00_start_here.ipynb", "03_phase_portraits.ipynb",
                    "10_pendulum_simulator.ipynb")

_PIN = re.compile(r"(?P<name>[A-Za-z0-9](?:[A-Za-z0-9._-]*[A-Za-z0-9])?)==(?P<version>\S+)")
_RUNTIME = re.compile(r"python-(?P<version>3\.\d+)")


def skip_or_fail(reason: str) -> None:
    """Skip with ``reason``; under ``CI=true`` fail with it instead (CI must run the test)."""
    if os.environ.get("CI", "").strip().lower() == "true":
        pytest.fail(f"{reason} (CI=true: this test must run in CI)", pytrace=False)
    pytest.skip(reason)


def canonical(name: str) -> str:
    """PEP 503 normalized project name: ``jupyterlab_widgets`` == ``JupyterLab-Widgets``."""
    return re.sub(r"[-_.]+", "-", name).lower()


def parse_pins(text: str) -> tuple[dict[str, str], list[str], int]:
    """Read a requirements text: ({canonical name: version}, problems, number of ``-e .``)."""
    pins: dict[str, str] = {}
    problems: list[str] = []
    editables = 0
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        if line == "-e .":
            editables += 1
            continue
        match = _PIN.fullmatch(line)
        if match is None:
            problems.append(
                f"line {number}: {line!r} is neither an exact pin 'name==version' nor '-e .'"
            )
            continue
        name, version = canonical(match["name"]), match["version"]
        try:
            Version(version)
        except ValueError:
            problems.append(f"line {number}: {version!r} is not a version")
        if name in pins:
            problems.append(f"line {number}: {match['name']} is pinned twice")
        pins[name] = version
    return pins, problems, editables


def check_requirements(
    text: str, dependencies: list[str], also_needed=BINDER_ALSO_NEEDS
) -> list[str]:
    """Everything wrong with a Binder requirements text; empty when it is right.

    ``dependencies`` are requirement strings such as ``"numpy>=2.0"`` (pyproject's
    ``[project].dependencies``): each must be pinned exactly, at a version it allows.
    """
    pins, problems, editables = parse_pins(text)
    if editables != 1:
        problems.append(
            f"'-e .' must appear exactly once (found {editables}): it installs pendulum_lab itself"
        )
    for spec in dependencies:
        requirement = Requirement(spec)
        name = canonical(requirement.name)
        if name not in pins:
            problems.append(f"{requirement.name} (a dependency in pyproject.toml) is not pinned")
        elif not requirement.specifier.contains(pins[name], prereleases=True):
            problems.append(
                f"{requirement.name}=={pins[name]} does not satisfy pyproject's '{requirement}'"
            )
    for name in also_needed:
        if canonical(name) not in pins:
            problems.append(f"{name} is not pinned (Binder needs it)")
    return problems


def project_table() -> dict:
    with (REPO_ROOT / "pyproject.toml").open("rb") as handle:
        return tomllib.load(handle)["project"]


def runtime_version() -> str:
    text = RUNTIME.read_text().strip()
    match = _RUNTIME.fullmatch(text)
    assert match, f"binder/runtime.txt must read 'python-3.X', found {text!r}"
    return match["version"]


def notebook_dir() -> Path:
    override = os.environ.get("PENDULUM_LAB_NOTEBOOKS")
    return Path(override).resolve() if override else REPO_ROOT / "notebooks"


# ---------------------------------------------------------------------------------------------
# Fast
# ---------------------------------------------------------------------------------------------


def test_requirements_are_exact_pins_covering_pyproject():
    problems = check_requirements(REQUIREMENTS.read_text(), project_table()["dependencies"])
    assert problems == []


def test_requirements_checker_rejects_a_bad_file():
    """Negative control: the checker must catch each of these mistakes."""
    bad = "\n".join(
        [
            "numpy>=2.0",  # not an exact pin
            "scipy==1.17.1",
            "scipy==1.17.1",  # twice
            "matplotlib==3.1.0",  # outside pyproject's matplotlib>=3.8
            "jupyterlab",  # unpinned
            "-e ./elsewhere",  # not the repository root
        ]
    )
    problems = check_requirements(
        bad, ["numpy>=2.0", "scipy>=1.13", "sympy>=1.13", "matplotlib>=3.8"]
    )
    expected = [
        "'numpy>=2.0' is neither an exact pin",
        "scipy is pinned twice",
        "'jupyterlab' is neither an exact pin",
        "'-e ./elsewhere' is neither an exact pin",
        "'-e .' must appear exactly once (found 0)",
        "numpy (a dependency in pyproject.toml) is not pinned",
        "sympy (a dependency in pyproject.toml) is not pinned",
        "matplotlib==3.1.0 does not satisfy pyproject's 'matplotlib>=3.8'",
        "ipykernel is not pinned",
        "jupyterlab_widgets is not pinned",
    ]
    for fragment in expected:
        assert any(fragment in problem for problem in problems), (fragment, problems)
    # and a correct text passes the same checker
    good = "numpy==2.4.6\n-e .\n# comment\n\njupyterlab==4.6.6\n"
    assert check_requirements(good, ["numpy>=2.0"], also_needed=("jupyterlab",)) == []


def test_runtime_matches_requires_python():
    version = runtime_version()
    requires = SpecifierSet(project_table().get("requires-python", ""))
    assert requires.contains(f"{version}.0"), (
        f"runtime python-{version} vs requires-python {requires}"
    )


def test_widget_front_end_pins_match_the_ipywidgets_pin():
    """jupyterlab_widgets and widgetsnbextension must be the ones that pinned ipywidgets asks
    for; out of step, JupyterLab shows "Error displaying widget"."""
    pins, _, _ = parse_pins(REQUIREMENTS.read_text())
    pinned = pins.get("ipywidgets")
    try:
        installed = metadata.version("ipywidgets")
    except metadata.PackageNotFoundError:
        pytest.skip("ipywidgets is not installed here, so its requirements cannot be read")
    if installed != pinned:
        pytest.skip(
            f"installed ipywidgets {installed} is not the pinned {pinned}, "
            "so its requirements cannot be read here"
        )
    companions = [
        Requirement(r) for r in metadata.requires("ipywidgets") or [] if "extra ==" not in r
    ]
    checked = 0
    for requirement in companions:
        name = canonical(requirement.name)
        if name in ("jupyterlab-widgets", "widgetsnbextension"):
            checked += 1
            assert requirement.specifier.contains(pins[name]), (
                f"ipywidgets {pinned} requires {requirement}, binder pins {name}=={pins[name]}"
            )
    assert checked == 2


# ---------------------------------------------------------------------------------------------
# Slow: repo2docker, and a fresh environment from the pins
# ---------------------------------------------------------------------------------------------


@pytest.mark.slow
def test_repo2docker_accepts_the_binder_configuration(monkeypatch):
    try:
        from repo2docker.app import Repo2Docker
        from repo2docker.buildpacks import PythonBuildPack
    except ImportError as exc:
        skip_or_fail(
            f"jupyter-repo2docker is not importable ({exc}); pip install jupyter-repo2docker"
        )
    exe = Path(sys.executable).with_name("jupyter-repo2docker")
    if not exe.exists():
        found = shutil.which("jupyter-repo2docker")
        if found is None:
            skip_or_fail("the jupyter-repo2docker command is not installed")
        exe = Path(found)
    version = runtime_version()

    proc = subprocess.run(
        [str(exe), "--no-build", "."],
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        timeout=600,
        stdin=subprocess.DEVNULL,
    )
    assert proc.returncode == 0, proc.stderr[-4000:]
    # The log names the Python the Python build pack chose; with no runtime.txt it would warn
    # "Python version unspecified" and pick its default.
    assert f"python={version}" in proc.stderr, proc.stderr[-4000:]
    assert "Python version unspecified" not in proc.stderr
    # The Dockerfile installs our requirements after copying the repository (needed by -e .).
    dockerfile = proc.stdout
    install = dockerfile.find('pip install --no-cache-dir -r "binder/requirements.txt"')
    assert install != -1, dockerfile[-3000:]
    whole_repo = re.search(r"COPY --chown=\S+ src/ \$\{REPO_DIR\}/", dockerfile)
    assert whole_repo is not None and whole_repo.start() < install, dockerfile[-3000:]

    # The same detection in-process: the first build pack that claims the repository.
    monkeypatch.chdir(REPO_ROOT)
    app = Repo2Docker()
    picked = None
    for pack_class in app.buildpacks:
        pack = pack_class(base_image=app.base_image)
        if pack.detect():
            picked = pack
            break
    assert type(picked) is PythonBuildPack, f"repo2docker picked {type(picked).__name__}"
    assert picked.binder_dir == "binder"
    assert picked.python_version == version


def _python_for(version: str) -> tuple[str, str]:
    """An interpreter for ``version`` (on PATH or pyenv's, as the Makefile finds its own) or,
    failing that, this one; with its X.Y."""
    find_python = load_script("tools/find_python.py")
    major, minor = (int(part) for part in version.split("."))
    candidate = find_python.find((major, minor)) or sys.executable
    probe = subprocess.run(
        [candidate, "-c", "import sys; print('%d.%d' % sys.version_info[:2])"],
        capture_output=True,
        text=True,
        check=False,
    )
    actual = probe.stdout.strip()
    if probe.returncode != 0 or not actual:
        candidate = sys.executable
        actual = "{}.{}".format(*sys.version_info[:2])
    if actual != version:
        message = (
            f"binder/runtime.txt asks for Python {version}, python{version} is not on PATH: "
            f"building the venv with {candidate} (Python {actual})"
        )
        warnings.warn(message, stacklevel=2)
        print(message)
    return candidate, actual


def _binder_venv(python: str, version: str) -> Path:
    """A venv with only ``pip install -r binder/requirements.txt``, cached per requirements."""
    key = hashlib.sha256(REQUIREMENTS.read_bytes() + f"\npython {version}".encode()).hexdigest()[
        :16
    ]
    venv = VENV_CACHE / key
    done = venv / ".complete"
    if done.exists():
        return venv
    if VENV_CACHE.exists():  # keep one environment: drop those of older requirements
        for old in VENV_CACHE.iterdir():
            shutil.rmtree(old, ignore_errors=True)
    VENV_CACHE.mkdir(parents=True, exist_ok=True)
    subprocess.run([python, "-m", "venv", str(venv)], check=True, timeout=300)
    log = venv / "install.log"
    with log.open("w") as sink:
        # --no-compile: the few modules the run imports are compiled as they are imported,
        # instead of every installed module (about 40 s of CPU for this environment).
        proc = subprocess.run(
            [str(venv / "bin" / "python"), "-m", "pip", "install", "--no-compile", "-r",
             "binder/requirements.txt"],
            cwd=REPO_ROOT,  # as repo2docker does, so that "-e ." is the repository root
            stdout=sink,
            stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL,
            timeout=3600,
        )
    if proc.returncode != 0:
        tail = log.read_text(errors="replace")[-4000:]
        shutil.rmtree(venv, ignore_errors=True)
        pytest.fail(f"pip install -r binder/requirements.txt failed:\n{tail}", pytrace=False)
    done.write_text("ok\n")
    return venv


@pytest.mark.slow
def test_fresh_venv_from_binder_requirements_runs_the_binder_notebooks(tmp_path):
    python, version = _python_for(runtime_version())
    venv = _binder_venv(python, version)
    bin_dir = venv / "bin"

    # The test tools go in on top (at this environment's versions; Binder's image has none),
    # then the environment must still hold exactly the pinned versions, and the package imports.
    tools = [f"{name}=={metadata.version(name)}" for name in ("pytest", "nbval")]
    installed_tools = subprocess.run(
        [str(bin_dir / "python"), "-m", "pip", "install", "--quiet", *tools],
        capture_output=True, text=True, stdin=subprocess.DEVNULL, timeout=1800,
    )
    assert installed_tools.returncode == 0, installed_tools.stderr[-3000:]
    pins, _, _ = parse_pins(REQUIREMENTS.read_text())
    probe = subprocess.run(
        [
            str(bin_dir / "python"),
            "-c",
            "import json, importlib.metadata as m, sys; import pendulum_lab; "
            "print(json.dumps({n: m.version(n) for n in sys.argv[1:]}))",
            *pins,
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert probe.returncode == 0, probe.stderr[-3000:]
    installed = {canonical(k): v for k, v in json.loads(probe.stdout).items()}
    assert installed == pins

    notebooks = [notebook_dir() / name for name in BINDER_NOTEBOOKS
                 if (notebook_dir() / name).exists()]
    if not notebooks:
        pytest.skip(f"environment built and pendulum_lab imports; none of {BINDER_NOTEBOOKS} "
                    f"in {notebook_dir()}")
    work = tmp_path / "notebooks"
    shutil.copytree(notebook_dir(), work, ignore=shutil.ignore_patterns(".ipynb_checkpoints"))
    env = dict(os.environ)
    env["PATH"] = f"{bin_dir}{os.pathsep}{env.get('PATH', '')}"
    env["VIRTUAL_ENV"] = str(venv)
    env.pop("PYTHONPATH", None)
    env.pop("JUPYTER_PATH", None)
    for var in (
        "JUPYTER_CONFIG_DIR",
        "JUPYTER_DATA_DIR",
        "JUPYTER_RUNTIME_DIR",
        "IPYTHONDIR",
        "MPLCONFIGDIR",
    ):
        (tmp_path / var.lower()).mkdir()
        env[var] = str(tmp_path / var.lower())

    # Every cell runs, the cells marked NBVAL_CHECK_OUTPUT print what they stored
    # (notebooks/conftest.py, copied along, sets the rules).
    report = tmp_path / "nbval.xml"
    proc = subprocess.run(
        [str(bin_dir / "python"), "-m", "pytest", "-p", "no:cacheprovider", "-o", "addopts=",
         "--nbval-lax", "--nbval-current-env", f"--junitxml={report}", "-q",
         "--rootdir", str(work), *(str(work / notebook.name) for notebook in notebooks)],
        cwd=work,
        env=env,
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=3600,
    )
    assert proc.returncode == 0, proc.stdout[-8000:]
    # Each notebook was collected and run (a notebook nbval could not read would be missing).
    ran = set(re.findall(r'classname="([^"]+?)"', report.read_text()))
    ran_notebooks = {name for name in (notebook.stem for notebook in notebooks)
                     if any(name in entry for entry in ran)}
    assert ran_notebooks == {notebook.stem for notebook in notebooks}, sorted(ran)
