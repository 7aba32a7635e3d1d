"""Bad input to the command line and the warm-up: an error with the usage, never a traceback.

A mistyped subcommand used to start JupyterLab (with the typo as an option for it); now it
lists the commands, and only the words after ``--`` reach JupyterLab.
"""

import subprocess
import sys

import pytest

import pendulum_lab as pl
from pendulum_lab.app import cli

CASES = {
    "a mistyped command": (["bogus"], "unknown command 'bogus'; the commands are lab, warmup"),
    "a word for JupyterLab before --": (["lab", "bogus"],
                                        "unrecognized arguments: bogus (options for JupyterLab "
                                        "go after `--`)"),
    "warmup --n 0": (["warmup", "--n", "0"], "argument --n: must be a number of links >= 1"),
    "warmup --n two": (["warmup", "--n", "two"], "must be a whole number of links, got 'two'"),
    "warmup -- --x": (["warmup", "--", "--x"], "unrecognized arguments"),
}


@pytest.fixture
def never_start_lab(monkeypatch):
    def refuse(command):
        raise AssertionError(f"JupyterLab was started: {command}")

    monkeypatch.setattr(cli, "_run", refuse)


@pytest.mark.parametrize("case", CASES)
def test_bad_command_lines_exit_with_the_usage(case, capsys, never_start_lab):
    argv, message = CASES[case]
    with pytest.raises(SystemExit) as info:
        cli.main(argv)
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "usage: pendulum-lab" in err and message in err


def test_the_installed_command_refuses_a_typo_without_starting_anything():
    result = subprocess.run([sys.executable, "-m", "pendulum_lab", "bogus"],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 2 and "unknown command 'bogus'" in result.stderr
    assert "Starting JupyterLab" not in result.stdout


def test_jupyterlab_options_still_pass_after_the_double_dash(never_start_lab):
    args = cli.parse_arguments(cli.build_parser(), ["--no-browser", "--", "--allow-root", "x"])
    assert args.command == "lab" and args.jupyter_options == ["--allow-root", "x"]
    assert cli.parse_arguments(cli.build_parser(), ["--", "--allow-root"]).jupyter_options == [
        "--allow-root"]


@pytest.mark.parametrize("ns, error, message", [
    (5, TypeError, "`ns` must be a sequence of chain lengths"),
    ([0], ValueError, "`ns` must be an integer >= 1, got 0"),
    ([1.5], TypeError, "`ns`"),
])
def test_warm_up_names_its_argument(ns, error, message):
    with pytest.raises(error, match=message):
        pl.warm_up(ns=ns, progress=False)
