"""``pendulum-lab handout-link``: the nbgitpuller link, its encoding, its refusals and its
checks; the instructors' page shows what the command prints. (tests/hub follows such a link
on a real hub.)"""

from __future__ import annotations

import re
import shlex
import socket
import subprocess
import sys
import urllib.parse
from pathlib import Path

import pytest

from pendulum_lab.app.cli import build_parser, main, parse_arguments
from pendulum_lab.app.handout import (
    check_handout,
    course_folder_name,
    handout_link,
)

REPO_ROOT = Path(__file__).resolve().parents[2]
INSTRUCTORS = REPO_ROOT / "docs" / "instructors.md"


def query_of(link: str) -> dict[str, str]:
    parts = urllib.parse.urlsplit(link)
    return dict(urllib.parse.parse_qsl(parts.query, strict_parsing=True))


def test_the_link_is_nbgitpullers_with_every_value_encoded():
    repo = "https://git.example.edu/phys 101/pendulum_lab.git"  # a space, slashes, a colon
    link = handout_link("https://hub.example.edu/course-a/", repo, branch="week/3",
                        path="notebooks/04_explicit_euler.ipynb")
    prefix = "https://hub.example.edu/course-a/hub/user-redirect/git-pull?"
    assert link.startswith(prefix)
    # nothing in the query is left unencoded that would split or end it
    assert not re.search(r"[ /:#?]", link[len(prefix):])
    assert query_of(link) == {
        "repo": repo,
        "branch": "week/3",
        "targetpath": "pendulum_lab",
        "urlpath": "lab/tree/pendulum_lab/notebooks/04_explicit_euler.ipynb",
    }
    # without a branch, nbgitpuller takes the repository's default one
    assert "branch" not in query_of(handout_link("http://127.0.0.1:8000", repo))


@pytest.mark.parametrize(("repo", "folder"), [
    ("https://github.com/physics/pendulum_lab.git", "pendulum_lab"),
    ("https://github.com/physics/pendulum_lab/", "pendulum_lab"),
    ("git@github.com:physics/mechanics.git", "mechanics"),
    ("file:///srv/courses/pendulum_lab.git", "pendulum_lab"),
])
def test_the_course_folder_is_the_repositorys_name(repo, folder):
    assert course_folder_name(repo) == folder
    assert query_of(handout_link("https://hub.example.edu", repo))["targetpath"] == folder


@pytest.mark.parametrize(("arguments", "named", "accepted"), [
    (("hub.example.edu", "https://g.org/c.git"), "`--hub`", "https://hub.example.edu"),
    (("ftp://hub.example.edu", "https://g.org/c.git"), "`--hub`", "http or https"),
    (("https://hub.example.edu/hub/login", "https://g.org/c.git"), "`--hub`", "not one of"),
    (("https://hub.example.edu/user/ada/lab", "https://g.org/c.git"), "`--hub`", "not one of"),
    (("https://hub.example.edu?next=x", "https://g.org/c.git"), "`--hub`", "without '?'"),
    (("https://hub.example.edu", "github.com/physics/c"), "`--repo`", "schemes"),
    (("https://hub.example.edu", "https://g.org/c.git?ref=x"), "`--repo`", "--branch"),
    (("https://hub.example.edu", "https://"), "`--repo`", "host"),
])
def test_bad_addresses_are_refused_naming_the_argument(arguments, named, accepted):
    with pytest.raises(ValueError, match=re.escape(named)) as caught:
        handout_link(*arguments)
    assert accepted in str(caught.value)


@pytest.mark.parametrize(("keyword", "value"), [
    ("branch", "my branch"), ("branch", "-x"), ("branch", "a..b"), ("branch", ""),
    ("path", "/etc/passwd"), ("path", "../elsewhere.ipynb"), ("path", ""),
])
def test_bad_branches_and_paths_are_refused(keyword, value):
    with pytest.raises(ValueError, match=f"`--{keyword}`"):
        handout_link("https://hub.example.edu", "https://g.org/c.git", **{keyword: value})


def test_the_command_prints_the_link_or_says_what_is_wrong(capsys):
    assert main(["handout-link", "--hub", "https://hub.example.edu", "--repo",
                 "https://g.org/c.git"]) == 0
    out = capsys.readouterr().out.strip()
    assert out == handout_link("https://hub.example.edu", "https://g.org/c.git")
    assert main(["handout-link", "--hub", "hub.example.edu", "--repo", "https://g.org/c.git"]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and "`--hub` must be the hub's address" in captured.err


def _closed_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]  # free again once closed: nobody listens there


def test_check_names_an_unreachable_hub_and_a_repository_that_cannot_be_pulled(tmp_path):
    if subprocess.run(["git", "--version"], capture_output=True, check=False).returncode:
        pytest.skip("git is not installed")
    repo = tmp_path / "course.git"
    subprocess.run(["git", "init", "--quiet", "--bare", str(repo)], check=True)
    hub = f"http://127.0.0.1:{_closed_port()}"
    problems = check_handout(hub, (tmp_path / "missing.git").as_uri(), timeout=60)
    assert len(problems) == 2
    assert "cannot be reached" in problems[0] and hub in problems[0]
    assert "cannot be pulled" in problems[1] and "missing.git" in problems[1]
    # an empty repository is readable but has nothing to hand out
    problems = check_handout(hub, repo.as_uri(), branch="main", timeout=60)
    assert any("has no branch 'main'" in problem for problem in problems)
    # and the command reports them, exiting with 1, printing no link
    done = subprocess.run([sys.executable, "-m", "pendulum_lab", "handout-link", "--hub", hub,
                           "--repo", repo.as_uri(), "--check"], capture_output=True, text=True,
                          timeout=120, check=False)
    assert done.returncode == 1 and done.stdout == ""
    assert "cannot be reached" in done.stderr


def test_the_instructors_page_shows_what_the_command_prints():
    text = INSTRUCTORS.read_text(encoding="utf-8")
    found = re.search(r"```bash\n(pendulum-lab handout-link [^\n]*)\n```\s*```text\n(\S+)\n```",
                      text)
    assert found, "docs/instructors.md shows no handout-link command followed by its link"
    words = shlex.split(found.group(1))[1:]
    args = parse_arguments(build_parser(), words)
    assert handout_link(args.hub, args.repo, branch=args.branch, path=args.path) == \
        found.group(2)
    # Negative control: another branch gives another link.
    assert handout_link(args.hub, args.repo, branch="other", path=args.path) != found.group(2)
    # The page states the merge rules that tests/hub checks.
    assert "student's lines win" in text and "comes back" in text
