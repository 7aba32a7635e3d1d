"""The pendulum-lab command: argument parsing, copying the course, the JupyterLab command line.

JupyterLab is never started here: the command is built by ``lab_command`` and ``_run`` is
replaced by a recorder.
"""

import importlib.util
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from pendulum_lab import cli


@pytest.fixture
def course(tmp_path):
    """A fake shipped course folder with notebooks, an asset, and files that must not be copied."""
    src = tmp_path / "shipped"
    (src / "figures").mkdir(parents=True)
    (src / ".ipynb_checkpoints").mkdir()
    (src / cli.START_NOTEBOOK).write_text('{"cells": ["start"]}')
    (src / "01_next.ipynb").write_text('{"cells": ["next"]}')
    (src / "figures" / "sketch.svg").write_text("<svg/>")
    (src / "conftest.py").write_text("# nbval hooks")
    (src / ".ipynb_checkpoints" / "x.ipynb").write_text("{}")
    return src


@pytest.fixture
def recorded(monkeypatch):
    calls = []

    def fake_run(command):
        calls.append(command)
        return 0

    monkeypatch.setattr(cli, "_run", fake_run)
    return calls


# --------------------------------------------------------------------------- parsing
def parse(argv):
    return cli.parse_arguments(cli.build_parser(), argv)


def test_lab_is_the_default_command():
    args = parse([])
    assert (args.command, args.dir, args.force, args.no_browser, args.port) == (
        "lab",
        None,
        False,
        False,
        None,
    )
    assert args.handler is cli.run_lab
    args = parse(["--dir", "here", "--no-browser", "--port", "8899"])
    assert (args.command, args.dir, args.no_browser, args.port) == ("lab", "here", True, 8899)
    assert parse(["lab", "--force"]).force is True
    assert parse([]).jupyter_options == []


def test_options_after_double_dash_go_to_jupyterlab(course):
    args = parse(["--no-browser", "--", "--allow-root", "--ServerApp.token="])
    assert args.command == "lab" and args.no_browser
    assert args.jupyter_options == ["--allow-root", "--ServerApp.token="]
    command = cli.lab_command(course, extra=args.jupyter_options)
    assert command[-2:] == ["--allow-root", "--ServerApp.token="]


@pytest.mark.parametrize("bad", [["--port", "0"], ["--port", "http"], ["lab", "--colour"]])
def test_bad_arguments_exit_with_usage(bad, capsys):
    with pytest.raises(SystemExit) as exc:
        parse(bad)
    assert exc.value.code == 2
    assert "usage: pendulum-lab" in capsys.readouterr().err


def test_top_level_help_and_version_are_not_redirected(capsys):
    with pytest.raises(SystemExit) as exc:
        cli.main(["--version"])
    assert exc.value.code == 0
    assert "pendulum-lab" in capsys.readouterr().out


def test_optional_report_command_is_registered_when_present():
    commands = cli.build_parser().get_default("commands")
    assert "lab" in commands
    try:
        import pendulum_lab.app.report  # noqa: F401
    except ModuleNotFoundError:
        assert "report" not in commands
    else:
        assert "report" in commands


# --------------------------------------------------------------------------- copying
def test_copy_course_copies_notebooks_and_assets_only(course, tmp_path):
    dest = tmp_path / "student"
    report = cli.copy_course(course, dest)
    assert sorted(report.copied) == sorted(
        ["00_start_here.ipynb", "01_next.ipynb", "figures/sketch.svg"]
    )
    assert (dest / "01_next.ipynb").read_text() == '{"cells": ["next"]}'
    assert not (dest / "conftest.py").exists()
    assert not (dest / ".ipynb_checkpoints").exists()


def test_copy_course_never_overwrites_an_edited_copy_without_force(course, tmp_path):
    dest = tmp_path / "student"
    cli.copy_course(course, dest)
    edited = dest / "01_next.ipynb"
    edited.write_text('{"cells": ["my answer"]}')
    report = cli.copy_course(course, dest)
    assert report.kept == ["01_next.ipynb"]
    assert edited.read_text() == '{"cells": ["my answer"]}'
    assert "--force" in report.summary()
    # Negative control: the unedited notebook is recognised as up to date, not as "kept".
    assert "00_start_here.ipynb" in report.unchanged
    report = cli.copy_course(course, dest, force=True)
    assert report.replaced == ["01_next.ipynb"]
    assert edited.read_text() == '{"cells": ["next"]}'


def test_copy_course_restores_a_deleted_notebook(course, tmp_path):
    dest = tmp_path / "student"
    cli.copy_course(course, dest)
    (dest / cli.START_NOTEBOOK).unlink()
    assert cli.copy_course(course, dest).copied == [cli.START_NOTEBOOK]


def test_copy_course_refuses_a_file_as_destination(course, tmp_path):
    target = tmp_path / "a_file"
    target.write_text("x")
    with pytest.raises(ValueError, match="--dir"):
        cli.copy_course(course, target)


# --------------------------------------------------------------------------- where and how
def test_lab_command_line(course):
    command = cli.lab_command(course, no_browser=True, port=8899, python="py")
    assert command[:3] == ["py", "-m", "jupyterlab"]
    assert f"--ServerApp.root_dir={course.resolve()}" in command
    assert f"--LabApp.default_url=/lab/tree/{cli.START_NOTEBOOK}" in command
    assert "--no-browser" in command and "--port=8899" in command
    plain = cli.lab_command(course)
    assert plain[0] == sys.executable
    assert "--no-browser" not in plain and not any(a.startswith("--port") for a in plain)


def test_lab_command_without_start_notebook_opens_the_file_browser(tmp_path):
    assert not any("default_url" in a for a in cli.lab_command(tmp_path))


def test_course_folder_rules(course, tmp_path):
    checkout = tmp_path / "repo" / "notebooks"
    assert cli.course_folder(parse([]), checkout, None) == (checkout, None)
    assert cli.course_folder(parse([]), None, course) == (Path(cli.DEFAULT_DIR), course)
    assert cli.course_folder(parse(["--dir", "mine"]), None, course) == (Path("mine"), course)
    assert cli.course_folder(parse(["--dir", "mine"]), checkout, course) == (Path("mine"), checkout)
    with pytest.raises(FileNotFoundError, match="no course notebooks"):
        cli.course_folder(parse([]), None, None)


def test_this_checkout_is_recognised():
    here = Path(cli.__file__).resolve()  # src/pendulum_lab/app/cli.py
    if here.parents[2].name != "src":
        pytest.skip("pendulum_lab is not running from a source checkout")
    assert cli.checkout_notebooks() == here.parents[3] / "notebooks"


def test_main_from_a_wheel_copies_then_starts_lab(course, tmp_path, monkeypatch, recorded):
    monkeypatch.setattr(cli, "checkout_notebooks", lambda: None)
    monkeypatch.setattr(cli, "packaged_notebooks", lambda: course)
    monkeypatch.chdir(tmp_path)
    assert cli.main(["--no-browser", "--port", "8899", "--", "--allow-root"]) == 0
    dest = tmp_path / cli.DEFAULT_DIR
    assert (dest / cli.START_NOTEBOOK).is_file()
    expected = cli.lab_command(dest, no_browser=True, port=8899, extra=["--allow-root"])
    assert recorded == [expected]


def test_main_from_a_checkout_opens_in_place(course, monkeypatch, recorded, tmp_path):
    monkeypatch.setattr(cli, "checkout_notebooks", lambda: course)
    monkeypatch.chdir(tmp_path)
    assert cli.main(["lab"]) == 0
    assert recorded == [cli.lab_command(course)]
    assert not (tmp_path / cli.DEFAULT_DIR).exists()  # nothing copied


def test_main_reports_a_bad_dir_without_traceback(course, monkeypatch, recorded, tmp_path, capsys):
    monkeypatch.setattr(cli, "checkout_notebooks", lambda: course)
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert cli.main(["--dir", str(blocker)]) == 1
    assert "must be a folder" in capsys.readouterr().err
    assert recorded == []


def test_python_dash_m_runs_the_same_parser():
    done = subprocess.run(
        [sys.executable, "-m", "pendulum_lab", "lab", "--help"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0
    assert "--no-browser" in done.stdout and "--dir" in done.stdout


@pytest.mark.plumbing
def test_warmup_compiles_the_requested_kernels(capsys):
    from pendulum_lab import cli

    assert cli.main(["warmup", "--n", "1"]) == 0
    assert "chains of [1] link(s)" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        cli.main(["warmup", "--n", "x"])


def test_running_as_root_adds_allow_root_once(course):
    assert "--allow-root" in cli.lab_command(course, as_root=True)
    assert "--allow-root" not in cli.lab_command(course, as_root=False)  # negative control
    twice = cli.lab_command(course, as_root=True, extra=["--allow-root"])
    assert twice.count("--allow-root") == 1


@pytest.mark.plumbing
def test_warm_up_reaches_the_variational_kernels_and_the_standard_map():
    script = (
        "import pendulum_lab as pl, sys\n"
        "from pendulum_lab import codegen\n"
        "from pendulum_lab.geometric import standard_map\n"
        "pl.warm_up(ns=(1,), methods=None if sys.argv[1] == 'all' else ['rk4'], progress=False)\n"
        "print(len(standard_map._first_crossings.signatures),"
        " codegen.load_discrete_kernels.cache_info().currsize)\n"
    )
    counts = {}
    for which in ("all", "rk4"):
        done = subprocess.run([sys.executable, "-c", script, which], capture_output=True,
                              text=True, timeout=600)
        assert done.returncode == 0, done.stderr
        counts[which] = tuple(int(x) for x in done.stdout.split())
    assert counts["all"] == (1, 2)  # the map's loop and both rules' discrete kernels
    assert counts["rk4"] == (0, 0)  # negative control: one method compiles neither


# --------------------------------------------------------------------------- make lab ARGS=...
REPO = Path(__file__).resolve().parents[2]


def make_lab_command(venv: Path, *arguments: str) -> list[str]:
    """The commands ``make lab ...`` would run (``make -n``) with an installed fake venv."""
    (venv / "bin").mkdir(parents=True, exist_ok=True)
    (venv / "bin" / "python").touch()
    (venv / ".installed-lab").touch()  # newer than pyproject.toml: nothing to install
    # --no-print-directory: under `make test` this make is a sub-make (MAKELEVEL > 0), which
    # would otherwise print "Entering directory" lines around the commands.
    done = subprocess.run(["make", "--no-print-directory", "-n", "lab", f"VENV={venv}",
                           *arguments], cwd=REPO, capture_output=True, text=True, timeout=60,
                          check=True)
    return done.stdout.strip().splitlines()


@pytest.mark.skipif(shutil.which("make") is None or not (REPO / "Makefile").is_file(),
                    reason="needs make and the repository's Makefile")
def test_make_lab_passes_args_through_pendulum_lab_to_jupyterlab(tmp_path, monkeypatch,
                                                                 recorded):
    venv = tmp_path / "venv"
    lines = make_lab_command(venv, "ARGS=--no-browser --port 8899 -- --allow-root")
    assert len(lines) == 1, lines  # no install step, only the launcher
    launcher, *argv = shlex.split(lines[0])
    assert launcher == f"{venv}/bin/pendulum-lab"
    assert argv == ["--no-browser", "--port", "8899", "--", "--allow-root"]
    # what pendulum-lab then starts, from this checkout
    if importlib.util.find_spec("jupyterlab") is None:
        pytest.skip("JupyterLab is not installed: the launcher would refuse to start it")
    monkeypatch.setattr(cli, "checkout_notebooks", lambda: tmp_path)
    assert cli.main(argv) == 0
    (command,) = recorded
    assert "--no-browser" in command and "--port=8899" in command
    assert command[-1] == "--allow-root"
    # negative control: without ARGS the launcher gets no options and JupyterLab none of them
    assert shlex.split(make_lab_command(venv)[0]) == [f"{venv}/bin/pendulum-lab"]
    assert cli.main([]) == 0
    assert "--no-browser" not in recorded[1] and not any(a.startswith("--port")
                                                          for a in recorded[1])
