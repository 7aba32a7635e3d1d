"""The Gradescope route: the autograder zip's own requirements make an environment that grades.

Gradescope builds its grading image from the zip alone: it unpacks it into /autograder/source and
installs the pip part of its ``environment.yml`` there. This test does the same in a fresh
virtual environment outside the repository (Python 3.13 as the zip asks, when this machine has
it; pip's cache makes later runs quick), then grades the solutions of assignment 01 with otter
from that environment: full marks. Negative control: the same environment without the course's
package (as the zip was before it carried the wheel) grades the same notebook zero.
"""

from __future__ import annotations

import glob
import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
import yaml
from assignment_harness import tool

NAME = "01_derivations_and_fixed_points"
#: The zip's environment.yml asks for this Python (otter's default).
GRADESCOPE_PYTHON = (3, 13)


def _gradescope_python() -> str:
    """A Python of the version the zip asks for if this machine has one (on the PATH or from
    pyenv), else the one running the tests."""
    candidates = [shutil.which("python{}.{}".format(*GRADESCOPE_PYTHON)), *sorted(glob.glob(
        os.path.expanduser("~/.pyenv/versions/{}.{}*/bin/python3".format(*GRADESCOPE_PYTHON))))]
    for candidate in filter(None, candidates):
        probe = subprocess.run([candidate, "-c", "import sys, venv; print(sys.version_info[:2])"],
                               capture_output=True, text=True, check=False)
        if probe.returncode == 0 and probe.stdout.strip() == str(GRADESCOPE_PYTHON):
            return candidate
    return sys._base_executable


def _fresh_env() -> dict:
    """The environment of a process that sees none of the repository's code."""
    return {key: value for key, value in os.environ.items()
            if key not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME")} | {
        "PYTHONWARNINGS": "ignore", "PIP_DISABLE_PIP_VERSION_CHECK": "1"}


def _run(command, cwd, timeout=900):
    completed = subprocess.run(command, cwd=cwd, env=_fresh_env(), capture_output=True,
                               text=True, timeout=timeout, check=False)
    assert completed.returncode == 0, completed.stdout[-3000:] + completed.stderr[-3000:]
    return completed


def _grade(python: Path, autograder: Path, submission: Path, out: Path) -> dict[str, float]:
    """Points per question (Gradescope's results format) of ``otter run`` in that Python."""
    out.mkdir()
    subprocess.run([str(python), "-m", "otter", "run", "-a", str(autograder), "-o", str(out),
                    "--no-logo", str(submission)], cwd=out, env=_fresh_env(),
                   capture_output=True, text=True, timeout=900, check=False)
    results = out / "results.json"
    tests = json.loads(results.read_text()).get("tests", []) if results.exists() else []
    # Otter adds a "Public Tests" entry without a score: only the questions count.
    return {test["name"]: float(test.get("score") or 0.0) for test in tests
            if test.get("max_score")}


@pytest.mark.slow
def test_the_zip_installs_what_its_hidden_tests_import_and_grades(kit, tmp_path):
    autograder = tool.autograder_zip(kit.folders[NAME])
    source = tmp_path / "source"  # Gradescope's /autograder/source
    with zipfile.ZipFile(autograder) as archive:
        archive.extractall(source)
    environment = yaml.safe_load((source / "environment.yml").read_text())
    pip = next(item["pip"] for item in environment["dependencies"] if isinstance(item, dict))
    requirements = (source / "requirements.txt").read_text().split()
    # The wheel is in the zip, and both lists name it where the zip puts it.
    wheels = sorted((source / tool.WHEEL_FOLDER).glob("pendulum_lab-*.whl"))
    assert len(wheels) == 1 and requirements == [f"./{tool.WHEEL_FOLDER}/{wheels[0].name}"]
    assert set(requirements) <= set(pip) and any(r.startswith("otter-grader") for r in pip)

    venv = tmp_path / "env"
    _run([_gradescope_python(), "-m", "venv", str(venv)], tmp_path)
    venv_python = venv / "bin" / "python"
    (source / "pip-part.txt").write_text("\n".join(pip) + "\n")
    # As conda does with environment.yml's pip part: one requirements file, run where the zip
    # was unpacked (without compiling every module to bytecode: that is only time here).
    _run([str(venv_python), "-m", "pip", "install", "--quiet", "--no-compile", "-r",
          "pip-part.txt"], source)

    solutions = kit.folders[NAME] / "autograder" / f"{NAME}.ipynb"
    graded = _grade(venv_python, autograder, solutions, tmp_path / "graded")
    assert graded == tool.question_points(kit.folders[NAME])

    # Negative control: without the package (the zip's requirements before it carried the
    # wheel), the same environment grades the same notebook zero.
    _run([str(venv_python), "-m", "pip", "uninstall", "--quiet", "-y", "pendulum_lab"], source)
    without = _grade(venv_python, autograder, solutions, tmp_path / "without")
    assert sum(without.values()) == 0
