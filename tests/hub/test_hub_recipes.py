"""The hub page's recipes say what the package does: the warm-up lines parse as the command
line does, the variable they set is the one the kernel cache reads, and ``binder/start``
keeps a folder the image already names before the home folder's layer."""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
from pathlib import Path

import pytest

from pendulum_lab.app.cli import build_parser, parse_arguments
from pendulum_lab.codegen.cache import SHARED_VARIABLE

REPO_ROOT = Path(__file__).resolve().parents[2]
HUB_PAGE = REPO_ROOT / "docs" / "hub.md"


def warmup_lines(text: str) -> list[str]:
    return [match.group(1) for match in
            re.finditer(r"(pendulum-lab warmup [^\n\\&]*)", text)]


def test_the_hub_pages_warmups_parse_and_name_the_cache_the_variable_points_at(capsys):
    text = HUB_PAGE.read_text(encoding="utf-8")
    lines = warmup_lines(text)
    assert len(lines) >= 2  # the image's and TLJH's
    caches = set()
    for line in lines:
        args = parse_arguments(build_parser(), shlex.split(line)[1:])
        assert args.command == "warmup" and args.n == [1, 2, 3], line
        caches.add(str(args.cache))
    named = set(re.findall(rf"{SHARED_VARIABLE}[=:]\s*\"?([^\s\"']+)", text))
    assert caches == named == {"/opt/pendulum_lab-cache"}, (caches, named)
    # Negative control: a line with an option the command does not have fails to parse.
    with pytest.raises(SystemExit):
        parse_arguments(build_parser(), ["warmup", "--cache", "/opt/x", "--links", "1"])
    assert "unrecognized arguments: --links" in capsys.readouterr().err


@pytest.mark.skipif(shutil.which("bash") is None, reason="binder/start is a bash script")
def test_binder_start_keeps_the_images_folder_first():
    def shared_after_start(env):
        env = {**{k: v for k, v in os.environ.items() if k != SHARED_VARIABLE}, **env}
        done = subprocess.run(["bash", str(REPO_ROOT / "binder" / "start"), "printenv",
                               SHARED_VARIABLE], env=env, capture_output=True, text=True,
                              timeout=60, check=True)
        return done.stdout.strip()

    assert shared_after_start({"HOME": "/home/s"}) == "/home/s/.pendulum_lab-image-cache"
    assert shared_after_start({"HOME": "/home/s", SHARED_VARIABLE: "/opt/pendulum_lab-cache"}) \
        == "/opt/pendulum_lab-cache:/home/s/.pendulum_lab-image-cache"
