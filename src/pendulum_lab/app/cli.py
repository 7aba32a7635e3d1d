"""The ``pendulum-lab`` command (also ``python -m pendulum_lab``).

Usage::

    pendulum-lab                         same as `pendulum-lab lab`
    pendulum-lab lab [--dir DIR] [--force] [--no-browser] [--port N] [-- JUPYTER_OPTIONS]
    pendulum-lab warmup [--cache DIR] [--n N ...]
    pendulum-lab handout-link --hub URL --repo URL [--branch B] [--path FILE] [--check]
    pendulum-lab report ...              when pendulum_lab/report.py provides it

``lab`` opens JupyterLab on the course notebooks:

* from a source checkout (a ``notebooks/`` folder next to ``src/``), on that
  folder, in place;
* from an installed wheel, the notebooks shipped inside the package
  (``pendulum_lab/notebooks``) are first copied to a writable folder
  (``--dir``, default ``./pendulum_lab_course``), so nobody edits
  site-packages. A notebook already there that differs from the shipped one
  (the student's edited copy) is kept unless ``--force`` is given.

``--dir`` given explicitly always copies, also from a checkout (a scratch
copy of the course). Options after ``--`` go to JupyterLab unchanged, for
example ``pendulum-lab -- --allow-root`` inside a container running as root;
anything else the command does not know is an error (a mistyped command, such
as ``pendulum-lab bogus``, lists the commands instead of starting JupyterLab).

Adding a subcommand from another module
---------------------------------------
:func:`build_parser` imports ``pendulum_lab.app.report`` if it exists and calls
its ``add_report_command(subparsers)``, which must add a subparser (named
``report``) and set its handler with ``parser.set_defaults(handler=...)``; the
handler receives the parsed ``argparse.Namespace`` and returns the exit
status. Nothing else in this file needs to change.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.resources
import importlib.util
import os
import subprocess
import sys
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["CopyReport", "build_parser", "copy_course", "lab_command", "main", "parse_arguments"]

DEFAULT_DIR = "pendulum_lab_course"
START_NOTEBOOK = "00_start_here.ipynb"
# Files of the notebooks folder that are not course material (test hooks, caches).
_NOT_COURSE = {"conftest.py", "__pycache__", ".ipynb_checkpoints", ".pytest_cache"}


# --------------------------------------------------------------------------- where the course is
def checkout_notebooks() -> Path | None:
    """The ``notebooks/`` folder of a source checkout this package runs from, if any."""
    package = Path(__file__).resolve().parents[1]  # pendulum_lab/app/cli.py
    src = package.parent
    root = src.parent
    folder = root / "notebooks"
    if src.name == "src" and (root / "pyproject.toml").is_file() and folder.is_dir():
        return folder
    return None


def packaged_notebooks():
    """The notebooks shipped inside an installed wheel (``pendulum_lab/notebooks``), if any."""
    folder = importlib.resources.files("pendulum_lab") / "notebooks"
    return folder if folder.is_dir() else None


# --------------------------------------------------------------------------- copying
@dataclass
class CopyReport:
    """What :func:`copy_course` did, as paths relative to the destination."""

    copied: list[str] = field(default_factory=list)
    unchanged: list[str] = field(default_factory=list)
    kept: list[str] = field(default_factory=list)
    replaced: list[str] = field(default_factory=list)

    def summary(self) -> str:
        lines = [
            f"{len(self.copied)} copied, {len(self.unchanged)} already up to date, "
            f"{len(self.replaced)} replaced, {len(self.kept)} kept"
        ]
        if self.kept:
            lines.append(
                "Kept your edited copies (run with --force to replace them with the "
                "course's version): " + ", ".join(self.kept)
            )
        return "\n".join(lines)


def _course_files(source, prefix: str = ""):
    """``(relative path, traversable)`` of every course file under ``source``, sorted."""
    for entry in sorted(source.iterdir(), key=lambda e: e.name):
        if entry.name in _NOT_COURSE or entry.name.startswith("."):
            continue
        relative = f"{prefix}{entry.name}"
        if entry.is_dir():
            yield from _course_files(entry, relative + "/")
        else:
            yield relative, entry


def copy_course(source, destination: Path, force: bool = False) -> CopyReport:
    """Copy the course notebooks from ``source`` into ``destination``.

    Parameters
    ----------
    source : pathlib.Path or importlib.resources.abc.Traversable
        Folder of the shipped notebooks.
    destination : pathlib.Path
        Created if missing.
    force : bool
        Replace files that exist and differ from the shipped version. Without
        it they are kept: they are the student's edited (or executed) copies.

    Returns
    -------
    CopyReport
    """
    destination = Path(destination)
    if destination.exists() and not destination.is_dir():
        raise ValueError(f"`--dir` must be a folder, but {destination} is a file")
    report = CopyReport()
    for relative, entry in _course_files(source):
        target = destination / relative
        data = entry.read_bytes()
        if target.exists():
            if target.read_bytes() == data:
                report.unchanged.append(relative)
                continue
            if not force:
                report.kept.append(relative)
                continue
            report.replaced.append(relative)
        else:
            report.copied.append(relative)
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(data)
    return report


# --------------------------------------------------------------------------- JupyterLab
def lab_command(
    root: Path,
    *,
    no_browser: bool = False,
    port: int | None = None,
    extra: Sequence[str] = (),
    python: str | None = None,
    as_root: bool | None = None,
) -> list[str]:
    """The command line that starts JupyterLab on ``root`` (opening the start notebook).

    ``extra`` options are appended unchanged (they come last, so they win).
    Run as root (containers, CI machines), JupyterLab refuses to start unless
    told ``--allow-root``; ``as_root`` (by default: the effective user is
    root) adds it.
    """
    root = Path(root).resolve()
    command = [python or sys.executable, "-m", "jupyterlab", f"--ServerApp.root_dir={root}"]
    if (root / START_NOTEBOOK).is_file():
        command.append(f"--LabApp.default_url=/lab/tree/{START_NOTEBOOK}")
    if no_browser:
        command.append("--no-browser")
    if port is not None:
        command.append(f"--port={port}")
    if as_root is None:
        as_root = hasattr(os, "geteuid") and os.geteuid() == 0
    if as_root and "--allow-root" not in extra:
        command.append("--allow-root")
    return command + list(extra)


def _run(command: list[str]) -> int:
    """Hand over to JupyterLab until it is stopped (Ctrl-C).

    On POSIX the launcher process *becomes* JupyterLab (``os.execv``), so a
    signal sent to it (Ctrl-C, ``kill``) reaches the server directly and no
    orphaned server is left behind. Elsewhere JupyterLab runs as a child.
    """
    sys.stdout.flush()
    sys.stderr.flush()
    if os.name == "posix":
        os.execv(command[0], command)  # does not return
    try:
        return subprocess.call(command)
    except KeyboardInterrupt:
        return 0


def course_folder(args, checkout: Path | None, packaged) -> tuple[Path, object | None]:
    """Where JupyterLab should open, and the source to copy there first (or None).

    Rules: an explicit ``--dir`` copies into it (from the checkout or the
    wheel); otherwise a checkout opens in place and a wheel copies into
    ``./pendulum_lab_course``.
    """
    source = checkout if checkout is not None else packaged
    if source is None:
        raise FileNotFoundError(
            "no course notebooks found: neither a source checkout (notebooks/ next to src/) "
            "nor notebooks inside the installed package (pendulum_lab/notebooks)"
        )
    if args.dir is not None:
        return Path(args.dir), source
    if checkout is not None:
        return checkout, None
    return Path(DEFAULT_DIR), source


def run_lab(args) -> int:
    """The ``lab`` subcommand."""
    if importlib.util.find_spec("jupyterlab") is None:
        print(
            # double quotes: the same command in PowerShell, cmd and a POSIX shell
            "JupyterLab is not installed. Install it with:  "
            'python -m pip install "pendulum_lab[lab]"',
            file=sys.stderr,
        )
        return 1
    try:
        folder, source = course_folder(args, checkout_notebooks(), packaged_notebooks())
        if source is not None:
            report = copy_course(source, folder, force=args.force)
            print(f"Course notebooks in {folder.resolve()}: {report.summary()}")
    except (FileNotFoundError, ValueError, OSError) as err:
        print(f"pendulum-lab: {err}", file=sys.stderr)
        return 1
    command = lab_command(
        folder, no_browser=args.no_browser, port=args.port, extra=args.jupyter_options
    )
    print("Starting JupyterLab (stop it with Ctrl-C):", " ".join(command))
    return _run(command)


# --------------------------------------------------------------------------- parsing
def _port(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer, got {text!r}") from None
    if not 1 <= value <= 65535:
        raise argparse.ArgumentTypeError(f"must be in [1, 65535], got {value}")
    return value


def _add_lab_command(subparsers) -> None:
    lab = subparsers.add_parser(
        "lab",
        help="open JupyterLab on the course (the default command)",
        description="Open JupyterLab on the course notebooks. From an installed package the "
        "notebooks are first copied to a writable folder.",
    )
    lab.add_argument(
        "--dir",
        default=None,
        metavar="DIR",
        help=f"folder to copy the notebooks into and open (default: the checkout's "
        f"notebooks/ in place, or ./{DEFAULT_DIR} for an installed package)",
    )
    lab.add_argument(
        "--force",
        action="store_true",
        help="replace notebooks in DIR that differ from the course's version",
    )
    lab.add_argument("--no-browser", action="store_true", help="do not open a browser")
    lab.add_argument("--port", type=_port, default=None, help="port for JupyterLab")
    # Filled only from the words after `--` (parse_arguments refuses any other).
    lab.add_argument(
        "jupyter_options",
        nargs="*",
        metavar="-- JUPYTER_OPTIONS",
        help="options passed on to JupyterLab unchanged, after `--` (for example: -- --allow-root)",
    )
    lab.set_defaults(handler=run_lab)


def _progress_lines(done: int, total: int, what: str) -> None:
    """``pendulum-lab warmup --progress lines``: one line per job (``warmup.PROGRESS_LINE``)."""
    print(f"{done}/{total} {what}", flush=True)


def _links(text: str) -> int:
    """A chain length for ``warmup --n``: a whole number of links, at least 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number of links, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a number of links >= 1, got {value}")
    return value


def run_warmup(args) -> int:
    """Compile the numerical kernels now instead of on first use.

    With ``--cache DIR`` everything is compiled into ``DIR`` (read-only layers are not
    consulted, so that ``DIR`` is complete on its own): an image's shared cache, read by its
    users through ``PENDULUM_LAB_SHARED_CACHE=DIR``.
    """
    from ..codegen.cache import CACHE_VARIABLE, SHARED_VARIABLE, cache_layers
    from .warmup import warm_up

    if args.cache is not None:
        os.environ[CACHE_VARIABLE] = str(args.cache)
        os.environ.pop(SHARED_VARIABLE, None)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # said below, as the reason to stop
        layers = cache_layers()
    if layers.write is None:
        where = args.cache if args.cache is not None else f"${CACHE_VARIABLE}"
        print(f"pendulum-lab warmup: the kernel cache {where} cannot be written; give a "
              f"writable folder with --cache DIR or {CACHE_VARIABLE}", file=sys.stderr)
        return 1
    progress = {"bar": True, "lines": _progress_lines, "none": False}[args.progress]
    try:
        seconds = warm_up(ns=args.n, methods=args.methods, progress=progress)
    except (TypeError, ValueError) as err:
        print(f"pendulum-lab warmup: {err}", file=sys.stderr)
        return 2
    print(f"pendulum_lab kernels ready for chains of {args.n} link(s) ({seconds:.1f} s) in "
          f"{layers.write}")
    return 0


def _add_warmup_command(subparsers) -> None:
    warm = subparsers.add_parser(
        "warmup",
        help="compile the numerical kernels now (otherwise they compile on first use)",
        description="Compile, or load from the disk cache, every integrator kernel for the "
        "given chain lengths. Run once after installing to make the first notebook fast.",
    )
    warm.add_argument("--n", type=_links, nargs="+", default=[1, 2], metavar="N",
                      help="chain lengths (numbers of links) to prepare (default: 1 2)")
    warm.add_argument("--methods", nargs="+", default=None, metavar="METHOD",
                      help="methods to prepare (default: all of them)")
    warm.add_argument("--cache", type=Path, default=None, metavar="DIR",
                      help="compile into this folder (for an image: users then read it with "
                      "PENDULUM_LAB_SHARED_CACHE=DIR); by default the user's kernel cache "
                      "(PENDULUM_LAB_CACHE)")
    warm.add_argument("--progress", choices=("bar", "lines", "none"), default="bar",
                      help="a progress bar (default), one line 'DONE/TOTAL WHAT' per job "
                      "(for a program to read), or nothing")
    warm.set_defaults(handler=run_warmup)


def run_handout_link(args) -> int:
    """Print the nbgitpuller link that hands the course out on a JupyterHub."""
    from .handout import check_handout, handout_link

    try:
        link = handout_link(args.hub, args.repo, branch=args.branch, path=args.path)
    except (TypeError, ValueError) as err:
        print(f"pendulum-lab handout-link: {err}", file=sys.stderr)
        return 2
    if args.check:
        problems = check_handout(args.hub, args.repo, branch=args.branch)
        for problem in problems:
            print(f"pendulum-lab handout-link: {problem}", file=sys.stderr)
        if problems:
            return 1
    print(link)
    return 0


def _add_handout_command(subparsers) -> None:
    from .handout import DEFAULT_PATH

    handout = subparsers.add_parser(
        "handout-link",
        help="print the link that hands the course out on a JupyterHub (nbgitpuller)",
        description="Print the nbgitpuller link that hands the course out on a JupyterHub: "
        "a student who opens it gets the course's repository in their home folder (updated, "
        "keeping their edits, when they open it again) and the notebook it names. The hub's "
        "image needs nbgitpuller (docs/instructors.md).",
    )
    handout.add_argument("--hub", required=True, metavar="URL",
                         help="the hub's address, such as https://hub.example.edu")
    handout.add_argument("--repo", required=True, metavar="URL",
                         help="the course's git repository, as the hub's servers clone it")
    handout.add_argument("--branch", default=None, metavar="B",
                         help="the branch to hand out (default: the repository's default)")
    handout.add_argument("--path", default=DEFAULT_PATH, metavar="FILE",
                         help=f"the notebook the link opens (default: {DEFAULT_PATH})")
    handout.add_argument("--check", action="store_true",
                         help="first check that the hub answers and that the repository "
                         "(and branch) can be read with git from this machine")
    handout.set_defaults(handler=run_handout_link)


def _add_optional_commands(subparsers) -> None:
    """Subcommands of other modules of the application layer (``pendulum_lab.app.report``)."""
    from . import report  # matplotlib: loaded only when the parser is built

    report.add_report_command(subparsers)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with its subcommands (``lab`` and any optional ones)."""
    from ..version import __version__

    parser = argparse.ArgumentParser(
        prog="pendulum-lab",
        description="Hamiltonian mechanics and geometric integration, through pendulums. "
        "Without a command, runs `lab`.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    _add_lab_command(subparsers)
    _add_warmup_command(subparsers)
    _add_handout_command(subparsers)
    _add_optional_commands(subparsers)
    parser.set_defaults(commands=tuple(subparsers.choices))
    return parser


_TOP_LEVEL = ("-h", "--help", "--version")


def parse_arguments(parser: argparse.ArgumentParser, argv: Sequence[str]) -> argparse.Namespace:
    """``argv`` parsed by ``parser`` (:func:`build_parser`), with ``lab`` as the default command.

    ``lab`` is inserted when the words before ``--`` are empty or start with an option (a
    top-level ``--help`` or ``--version`` excepted). A first word that is no command is an
    error listing the commands; words after ``--`` are JupyterLab's options (for ``lab``
    only), and no other word reaches JupyterLab. Errors exit with status 2 and the usage, as
    argparse's own do.
    """
    argv = list(argv)
    split = argv.index("--") if "--" in argv else len(argv)
    head, tail = argv[:split], argv[split + 1:]
    commands = parser.get_default("commands")
    if not head or (head[0].startswith("-") and head[0] not in _TOP_LEVEL):
        head = ["lab", *head]
    elif head[0] not in commands and head[0] not in _TOP_LEVEL:
        parser.error(f"unknown command {head[0]!r}; the commands are {', '.join(commands)} "
                     "(options for JupyterLab go after `--`: pendulum-lab -- --allow-root)")
    args = parser.parse_args(head + argv[split:])
    if args.command == "lab" and list(args.jupyter_options) != tail:
        extra = [word for word in args.jupyter_options if word not in tail]
        parser.error(f"unrecognized arguments: {' '.join(extra)} (options for JupyterLab go "
                     "after `--`)")
    if args.command != "lab" and tail:
        parser.error(f"options after `--` go to JupyterLab, which only `lab` starts; "
                     f"`{args.command}` got {' '.join(tail)}")
    return args


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``pendulum-lab``; returns the exit status."""
    parser = build_parser()
    args = parse_arguments(parser, sys.argv[1:] if argv is None else argv)
    return args.handler(args)


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
