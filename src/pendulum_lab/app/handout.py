"""The link that hands the course out on a JupyterHub (``pendulum-lab handout-link``).

A student who opens the link logs in to the hub, which starts their server; nbgitpuller (a
server extension in the hub's image) then clones the course's git repository into their
home folder, or, when the folder is already there, merges the course's new commits into it
keeping the student's edits, and opens the notebook the link names. docs/instructors.md
says what happens to an edited notebook when the course changes.

The link's form is nbgitpuller's::

    HUB/hub/user-redirect/git-pull?repo=REPO&branch=BRANCH&targetpath=FOLDER&urlpath=lab/tree/FOLDER/PATH

with every value URL-encoded. ``FOLDER`` (the folder in the student's home) is the
repository's name without ``.git``; it is given in the link so that the folder cloned into
and the notebook opened cannot disagree.

:func:`check_handout` asks the hub and the repository whether the link can work, before it is
sent to a class: the hub must answer as a JupyterHub, and the repository (and branch) must be
readable with ``git ls-remote`` from this machine.
"""

from __future__ import annotations

import json
import posixpath
import re
import shutil
import subprocess
import urllib.error
import urllib.parse
import urllib.request

__all__ = ["DEFAULT_PATH", "check_handout", "course_folder_name", "handout_link"]

#: The notebook a link opens by default: the course's first.
DEFAULT_PATH = "notebooks/00_start_here.ipynb"
#: Schemes git clones from (an scp-like ``user@host:path`` is accepted too).
REPO_SCHEMES = ("https", "http", "ssh", "git", "file")
# Pages of a hub whose address a teacher may copy instead of the hub's own.
_HUB_PAGES = ("login", "home", "spawn", "api", "token", "admin", "user-redirect")
_SCP_LIKE = re.compile(r"^[\w.-]+@[\w.-]+:[^/\\].*$")
# What git refuses in a branch name (git check-ref-format), as far as a link can carry it.
_BAD_BRANCH = re.compile(r"(^[-/.])|(\.\.)|([\s~^:?*\[\\])|(@\{)|([/.]$)|(\.lock$)|(//)")


def _hub_address(hub: str) -> str:
    """``hub`` checked and without its trailing ``/``; ``ValueError`` naming ``--hub``."""
    if not isinstance(hub, str):
        raise TypeError(f"`--hub` must be the hub's address as text, got {type(hub).__name__}")
    parts = urllib.parse.urlsplit(hub.strip())
    if parts.scheme not in ("https", "http") or not parts.hostname:
        raise ValueError(f"`--hub` must be the hub's address, such as https://hub.example.edu "
                         f"(http or https, with a host name), got {hub!r}")
    if parts.query or parts.fragment:
        raise ValueError(f"`--hub` must be the hub's address without '?' or '#' parts, "
                         f"got {hub!r}")
    path = parts.path.rstrip("/")
    segments = path.split("/")
    if "user" in segments or (len(segments) >= 2 and segments[-2] == "hub"
                              and segments[-1] in _HUB_PAGES):
        raise ValueError(f"`--hub` must be the hub's address, not one of its pages (drop "
                         f"'/hub/...' or '/user/...' from it), got {hub!r}")
    try:
        parts.port  # noqa: B018 (a port that is not a number raises here)
    except ValueError:
        raise ValueError(f"`--hub` has a port that is not a number: {hub!r}") from None
    return urllib.parse.urlunsplit((parts.scheme, parts.netloc, path, "", ""))


def _repository(repo: str) -> str:
    """``repo`` checked; ``ValueError`` naming ``--repo``."""
    if not isinstance(repo, str):
        raise TypeError(f"`--repo` must be the course repository's URL as text, got "
                        f"{type(repo).__name__}")
    repo = repo.strip()
    if _SCP_LIKE.match(repo):
        return repo
    parts = urllib.parse.urlsplit(repo)
    if parts.scheme not in REPO_SCHEMES:
        raise ValueError(f"`--repo` must be a git URL the hub can clone, such as "
                         f"https://github.com/ORG/COURSE.git (schemes: "
                         f"{', '.join(REPO_SCHEMES)}, or user@host:path), got {repo!r}")
    if parts.scheme != "file" and not parts.hostname:
        raise ValueError(f"`--repo` has no host name: {repo!r}")
    if parts.query or parts.fragment:
        raise ValueError(f"`--repo` must be the repository's URL without '?' or '#' parts "
                         f"(give a branch with --branch), got {repo!r}")
    if not parts.path.strip("/"):
        raise ValueError(f"`--repo` names no repository (its path is empty): {repo!r}")
    return repo


def course_folder_name(repo: str) -> str:
    """The folder the course is cloned into in a student's home: the repository's name.

    >>> course_folder_name("https://github.com/physics/pendulum_lab.git")
    'pendulum_lab'
    """
    name = re.split(r"[/:]", _repository(repo).rstrip("/"))[-1]
    name = name[:-4] if name.endswith(".git") else name
    if not name or name in (".", ".."):
        raise ValueError(f"`--repo` ends in no folder name: {repo!r}")
    return name


def _branch(branch: str | None) -> str | None:
    if branch is None:
        return None
    if not isinstance(branch, str) or not branch.strip() or _BAD_BRANCH.search(branch):
        raise ValueError(f"`--branch` must be a git branch name (no spaces, '..', '~', '^', "
                         f"':', '?', '*', '[' or '\\'), got {branch!r}")
    return branch


def _notebook_path(path: str) -> str:
    if not isinstance(path, str):
        raise TypeError(f"`--path` must be a path as text, got {type(path).__name__}")
    clean = posixpath.normpath(path.strip().replace("\\", "/"))
    if (not path.strip() or clean.startswith(("/", "../")) or clean in (".", "..")
            or re.match(r"^[A-Za-z]:", clean)):
        raise ValueError(f"`--path` must be a file's path inside the repository, such as "
                         f"{DEFAULT_PATH}, got {path!r}")
    return clean


def handout_link(hub: str, repo: str, branch: str | None = None,
                 path: str = DEFAULT_PATH) -> str:
    """The nbgitpuller link that hands the course out on ``hub``.

    Parameters
    ----------
    hub : str
        The hub's address (``https://hub.example.edu``, with its base path if it has one).
    repo : str
        The course's git repository, as the hub's servers can clone it.
    branch : str, optional
        The branch to hand out; by default the repository's default branch.
    path : str
        The file the link opens, relative to the repository's root.

    Returns
    -------
    str

    Raises
    ------
    ValueError
        For an address, a repository, a branch or a path that cannot work, naming the
        argument (``--hub``, ``--repo``, ``--branch``, ``--path``) and what it accepts.

    Examples
    --------
    >>> handout_link("https://hub.example.edu", "https://github.com/physics/pendulum_lab.git",
    ...              branch="main")  # doctest: +NORMALIZE_WHITESPACE
    'https://hub.example.edu/hub/user-redirect/git-pull?repo=https%3A%2F%2Fgithub.com%2Fphysics%2Fpendulum_lab.git&branch=main&targetpath=pendulum_lab&urlpath=lab%2Ftree%2Fpendulum_lab%2Fnotebooks%2F00_start_here.ipynb'
    """
    address = _hub_address(hub)
    repository = _repository(repo)
    branch = _branch(branch)
    notebook = _notebook_path(path)
    folder = course_folder_name(repository)
    query = [("repo", repository)]
    if branch is not None:
        query.append(("branch", branch))
    query += [("targetpath", folder), ("urlpath", f"lab/tree/{folder}/{notebook}")]
    encoded = urllib.parse.urlencode(query, quote_via=urllib.parse.quote, safe="")
    return f"{address}/hub/user-redirect/git-pull?{encoded}"


def _hub_problem(hub: str, timeout: float) -> str | None:
    url = f"{_hub_address(hub)}/hub/api"
    try:
        with urllib.request.urlopen(url, timeout=timeout) as response:  # noqa: S310 (http/s)
            answer = json.loads(response.read().decode("utf-8", "replace"))
    except urllib.error.HTTPError as err:
        return f"the hub at {hub} answered {url} with HTTP {err.code} ({err.reason}): is it a " \
               f"JupyterHub, and is --hub its address?"
    except (urllib.error.URLError, OSError) as err:
        reason = getattr(err, "reason", err)
        return f"the hub at {hub} cannot be reached ({reason}): check the address and that " \
               f"the hub is running"
    except ValueError:
        return f"{url} did not answer as a JupyterHub (no JSON): is --hub the hub's address?"
    if not isinstance(answer, dict) or "version" not in answer:
        return f"{url} did not answer as a JupyterHub (no version): is --hub the hub's address?"
    return None


def _repository_problem(repo: str, branch: str | None, timeout: float) -> str | None:
    git = shutil.which("git")
    if git is None:
        return "git is not installed here, so the repository could not be checked"
    command = [git, "ls-remote", "--symref", "--", _repository(repo)]
    command += [f"refs/heads/{branch}"] if branch else ["HEAD"]
    try:
        done = subprocess.run(command, capture_output=True, text=True, encoding="utf-8",
                              errors="replace", timeout=timeout, stdin=subprocess.DEVNULL,
                              check=False)
    except subprocess.TimeoutExpired:
        return f"the repository {repo} did not answer within {timeout:.0f} s"
    if done.returncode != 0:
        said = " ".join(done.stderr.split())[:300] or f"exit status {done.returncode}"
        return f"the repository {repo} cannot be pulled: git says: {said}"
    if not done.stdout.strip():
        what = f"has no branch {branch!r}" if branch else "has no default branch (HEAD)"
        return f"the repository {repo} {what}"
    return None


def check_handout(hub: str, repo: str, branch: str | None = None,
                  timeout: float = 20.0) -> list[str]:
    """What stops the hand-out link from working, as messages; empty when nothing does.

    The hub must answer ``HUB/hub/api`` as a JupyterHub does (its version), and
    ``git ls-remote`` must read the repository (and the branch) from this machine. The
    hub's own servers clone it, so a repository that only this machine can reach (a
    ``file://`` URL of another computer, a private network) still fails there.
    """
    _branch(branch)
    return [problem for problem in (_hub_problem(hub, timeout),
                                    _repository_problem(repo, branch, timeout)) if problem]
