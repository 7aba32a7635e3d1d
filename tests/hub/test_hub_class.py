"""A class on a JupyterHub, on loopback: one link hands out the course, the image's kernels
are compiled once for everyone, and a student's edits survive an update of the course.

The image: the kernels the first notebooks use are compiled once (``pendulum-lab warmup
--cache``) into a folder made read-only (``chmod -R a-w``), which every student's server reads
as ``PENDULUM_LAB_SHARED_CACHE`` (docs/shared-cache.md). The course: a bare git repository
holding the checkout's tracked files (with their uncommitted changes), reached by a
``file://`` URL. JupyterHub (tests/hub/hub_harness.py) starts ``STUDENTS`` servers through its
REST API; each student logs in and follows the link ``pendulum-lab handout-link`` prints;
then, in all the students' kernels at once, notebook 00 runs to its first figure and notebook
04's explorer has a slider moved. Afterwards the course changes upstream and the students
pull again; then the faults: a repository that cannot be pulled, and a server stopped while a
cell runs, each with the others' work going on. The last test stops the hub and checks that
no process it started is left.

Linux only (the spawner's servers, the proxy); a missing tool skips with the reason, except
under ``CI=true``, where it fails. ``make test`` installs configurable-http-proxy.
"""

from __future__ import annotations

import asyncio
import json
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest
from hub_harness import (
    PNG_MAGIC,
    REPO_ROOT,
    Hub,
    KernelClient,
    ServerGone,
    Student,
    alive,
    in_ci,
    run_git,
    unavailable_reason,
)

from pendulum_lab.app.handout import check_handout, handout_link

STUDENTS = ("ada", "emmy", "sofia")
COURSE = "pendulum_lab"  # the bare repository's name, so the folder in every home
BRANCH = "main"
# The kernels of the two notebooks' first cells: compiled into the image, nothing else
# (chain length, method): glrk4 for notebook 00's double pendulum, explicit Euler for 04's.
IMAGE_KERNELS = (("2", "glrk4"), ("1", "explicit_euler"))
# The first cells of notebook 00 up to its first figure, and of notebook 04 up to the
# explorer, found by what they hold (the first code cell holding each text, in order).
NOTEBOOK_00 = "notebooks/00_start_here.ipynb"
CELLS_00 = ("import pendulum_lab as pl", "pl.double_pendulum(", "pl.simulate(",
            "plotting.plot_energy(")
NOTEBOOK_04 = "notebooks/04_explicit_euler.ipynb"
CELLS_04 = ("import pendulum_lab as pl", "pl.simple_pendulum(", "widgets.explore(")
SLIDER = 'explorer = _\nexplorer.controls["theta"].value = 1.5\nprint(explorer.message)'
COUNTS = ("import json\nfrom pendulum_lab.codegen.compile_status import compile_counts\n"
          "print(json.dumps(compile_counts()))")
# The student's edit of notebook 00 (their answer to the first exercise) and the course's
# later change of the same line, and of a file the student did not touch.
ANSWER_LINE = "lowest_height = None  # your answer, in metres"
STUDENT_LINE = "lowest_height = -1.75  # my answer"
COURSE_LINE = "lowest_height = None  # your answer, in metres (one number)"
COURSE_NEW_FILE = "notebooks/NEWS.md"


def skip_or_fail(reason: str) -> None:
    if in_ci():
        pytest.fail(f"{reason} (CI=true: this test must run in CI)", pytrace=False)
    pytest.skip(reason)


def first_cells(notebook: dict, markers) -> list[str]:
    """The sources of the first code cell holding each marker, in the notebook's order."""
    sources = ["".join(cell["source"]) if isinstance(cell["source"], list) else cell["source"]
               for cell in notebook["cells"] if cell["cell_type"] == "code"]
    chosen = []
    for marker in markers:
        found = next((source for source in sources if marker in source), None)
        assert found is not None, f"no code cell holds {marker!r}: the notebook changed"
        chosen.append(found)
    return chosen


def compiled_into(cache: Path) -> list[str]:
    """The kernels (generated modules, Numba's index and data files) a user's cache holds."""
    if not cache.is_dir():
        return []
    return sorted(str(path.relative_to(cache)) for path in cache.rglob("*")
                  if path.suffix in (".py", ".nbi", ".nbc"))


def user_cache(hub: Hub, user: str) -> Path:
    """The default kernel cache of a student (their home's, docs/shared-cache.md)."""
    return hub.home(user) / ".cache" / "pendulum_lab"


# --------------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def ready():
    reason = unavailable_reason()
    if reason is not None:
        skip_or_fail(reason)


@pytest.fixture(scope="module")
def image(ready, tmp_path_factory):
    """The image's shared kernel cache: compiled once, then read-only."""
    folder = tmp_path_factory.mktemp("image") / "pendulum_lab-cache"
    env = {"PATH": str(Path(sys.executable).parent) + ":/usr/bin:/bin",
           "PYTHONPATH": str(REPO_ROOT / "src"), "HOME": str(folder.parent), "LANG": "C.UTF-8"}
    for links, method in IMAGE_KERNELS:
        done = subprocess.run([sys.executable, "-m", "pendulum_lab", "warmup", "--cache",
                               str(folder), "--n", links, "--methods", method, "--progress",
                               "none"], env=env, capture_output=True, text=True, timeout=900,
                              stdin=subprocess.DEVNULL, check=False)
        assert done.returncode == 0, done.stdout + done.stderr
    subprocess.run(["chmod", "-R", "a-w", str(folder)], check=True)
    yield folder
    subprocess.run(["chmod", "-R", "u+w", str(folder)], check=False)


@pytest.fixture(scope="module")
def course(ready, tmp_path_factory):
    """A bare repository holding the checkout's tracked files, and its file:// URL."""
    try:
        run_git("rev-parse", "--git-dir", cwd=REPO_ROOT)
    except RuntimeError:
        skip_or_fail(f"{REPO_ROOT} is not a git repository")
    snapshot = (run_git("stash", "create", cwd=REPO_ROOT)
                or run_git("rev-parse", "HEAD", cwd=REPO_ROOT))
    bare = tmp_path_factory.mktemp("origin") / f"{COURSE}.git"
    run_git("init", "--quiet", "--bare", str(bare))
    run_git("push", "--quiet", str(bare), f"{snapshot}:refs/heads/{BRANCH}", cwd=REPO_ROOT)
    run_git("symbolic-ref", "HEAD", f"refs/heads/{BRANCH}", cwd=bare)
    return bare


@pytest.fixture(scope="module")
def hub(ready, image, tmp_path_factory):
    hub = Hub(tmp_path_factory.mktemp("hub"), image)
    try:
        hub.start()
        yield hub
    finally:  # the last test checks what stopping leaves; here only what an error left
        hub.stop()


@pytest.fixture(scope="module")
def timings():
    return {}


@pytest.fixture(scope="module")
def classroom(hub, course, timings):
    """Every student's server started, the course handed out, and the first cells of
    notebooks 00 and 04 run in all the kernels at once: ``{student: results}``."""
    started = time.perf_counter()
    hub.start_servers(STUDENTS)
    timings["servers"] = time.perf_counter() - started
    link = handout_link(hub.url, course.as_uri(), branch=BRANCH)
    students, pulls = {}, {}
    for name in STUDENTS:
        students[name] = Student(hub, name)
        students[name].log_in()
        pulls[name] = students[name].follow(link)
    timings["pulls"] = time.perf_counter() - started - timings["servers"]

    def cells_of(name, notebook, markers):
        status, model = hub.server_api(name, "GET", f"/contents/{COURSE}/{notebook}")
        assert status == 200, (name, notebook, status)
        return first_cells(model["content"], markers)

    async def one_student(name):
        results = {"kernels": []}
        for notebook, markers, extra in ((NOTEBOOK_00, CELLS_00, [COUNTS]),
                                         (NOTEBOOK_04, CELLS_04, [SLIDER, COUNTS])):
            status, session = await asyncio.to_thread(
                hub.server_api, name, "POST", "/sessions",
                {"path": f"{COURSE}/{notebook}", "type": "notebook",
                 "kernel": {"name": "python3"}})
            assert status == 201, (name, status, session)
            client = KernelClient(hub, name, session["kernel"]["id"])
            await client.connect()
            try:
                runs = [await client.run(code)
                        for code in cells_of(name, notebook, markers) + extra]
            finally:
                client.close()
            results[notebook] = runs
            results["kernels"].append(client)
        results["seconds"] = time.perf_counter() - begun
        return name, results

    async def everyone():
        return dict(await asyncio.gather(*(one_student(name) for name in STUDENTS)))

    begun = time.perf_counter()
    results = asyncio.run(everyone())
    timings["cells"] = time.perf_counter() - begun
    hub.remember_processes()
    print(f"\n{len(STUDENTS)} students: servers ready in {timings['servers']:.1f} s, course "
          f"pulled in {timings['pulls']:.1f} s, cells of notebooks 00 and 04 in "
          f"{timings['cells']:.1f} s (each student: "
          + ", ".join(f"{name} {results[name]['seconds']:.1f} s" for name in STUDENTS) + ")")
    return {"link": link, "pulls": pulls, "results": results, "students": students}


# --------------------------------------------------------------------------- the class
def test_the_link_hands_every_student_the_course(classroom, hub, course):
    for name, pull in classroom["pulls"].items():
        assert pull.phase == "finished", (name, pull.message, pull.output[-5:])
        # nbgitpuller's page read what the link says, and the course is in the student's home
        assert pull.page["repo"] == course.as_uri()
        assert pull.page["targetpath"] == COURSE and pull.page["branch"] == BRANCH
        assert pull.page["path"] == f"lab/tree/{COURSE}/{NOTEBOOK_00}"
        assert (hub.home(name) / COURSE / NOTEBOOK_00).is_file()
        assert (hub.home(name) / COURSE / ".git").is_dir()
    # the hand-out's own check passes against this hub and repository...
    assert check_handout(hub.url, course.as_uri(), branch=BRANCH) == []
    # ...and names what is wrong when the branch is not there (negative control)
    problems = check_handout(hub.url, course.as_uri(), branch="no-such-branch")
    assert len(problems) == 1 and "no branch 'no-such-branch'" in problems[0]


def test_every_student_gets_a_figure_at_the_same_time(classroom):
    for name, results in classroom["results"].items():
        for notebook in (NOTEBOOK_00, NOTEBOOK_04):
            for run in results[notebook]:
                assert run.error is None, (name, notebook, run.code[:200], run.error)
        figure = results[NOTEBOOK_00][len(CELLS_00) - 1]  # plot_energy's cell
        assert figure.pngs and all(png.startswith(PNG_MAGIC) for png in figure.pngs), (
            name, [output["msg_type"] for output in figure.outputs])
        explorer = results[NOTEBOOK_04][len(CELLS_04) - 1]
        assert any(png.startswith(PNG_MAGIC) for png in explorer.pngs), name
        moved = results[NOTEBOOK_04][len(CELLS_04)]  # the slider's change redraws
        assert moved.widget_pngs >= 1, (name, moved.text)


def test_nobody_compiles_what_the_image_holds(classroom, hub):
    for name, results in classroom["results"].items():
        for notebook in (NOTEBOOK_00, NOTEBOOK_04):
            loaded, compiled = json.loads(results[notebook][-1].stdout)
            assert compiled == 0 and loaded > 0, (name, notebook, loaded, compiled)
            assert not any("compiling" in run.text for run in results[notebook]), name
        assert compiled_into(user_cache(hub, name)) == [], name

    # Negative control: a method the image does not hold compiles, into the student's cache,
    # and both checks see it.
    name = STUDENTS[0]
    client = classroom["results"][name]["kernels"][1]
    probe = ("import pendulum_lab as pl\n"
             "pl.simulate(pl.simple_pendulum(), [1.0], [0.0], t_end=0.1, dt=0.01, method='rk4')\n"
             + COUNTS)
    run = asyncio.run(_in_new_loop(client, probe))
    assert run.error is None, run.error
    loaded, compiled = json.loads(run.stdout)
    assert compiled > 0 and "compiling rk4" in run.text, run.text
    assert compiled_into(user_cache(hub, name)) != []


async def _in_new_loop(client: KernelClient, code: str):
    """Run ``code`` on a fresh connection (a websocket belongs to the loop that opened it)."""
    fresh = KernelClient(client.hub, client.user, client.kernel_id)
    await fresh.connect()
    try:
        return await fresh.run(code)
    finally:
        fresh.close()


def _commit_course_update(course: Path, workdir: Path) -> None:
    """The course changes upstream: the line the student edited, and a new file."""
    clone = workdir / "update"
    run_git("clone", "--quiet", str(course), str(clone))
    notebook = clone / NOTEBOOK_00
    text = notebook.read_text(encoding="utf-8")
    assert ANSWER_LINE in text
    notebook.write_text(text.replace(ANSWER_LINE, COURSE_LINE), encoding="utf-8")
    (clone / COURSE_NEW_FILE).write_text("Notebook 19 arrives next week.\n", encoding="utf-8")
    run_git("add", "-A", cwd=clone)
    run_git("commit", "--quiet", "-m", "Course update", cwd=clone)
    run_git("push", "--quiet", "origin", BRANCH, cwd=clone)


def test_a_students_edit_survives_an_update_of_the_course(classroom, hub, course,
                                                          tmp_path):
    editor, other = STUDENTS[0], STUDENTS[1]
    path = f"/contents/{COURSE}/{NOTEBOOK_00}"
    status, model = hub.server_api(editor, "GET", path)
    assert status == 200
    notebook = model["content"]
    edited = 0
    for cell in notebook["cells"]:
        if ANSWER_LINE in cell["source"]:
            cell["source"] = cell["source"].replace(ANSWER_LINE, STUDENT_LINE)
            edited += 1
    assert edited == 1
    status, _ = hub.server_api(editor, "PUT", path,
                               {"type": "notebook", "format": "json", "content": notebook})
    assert status == 200
    # The other student deleted the notebook, to get a fresh copy at the next pull.
    (hub.home(other) / COURSE / NOTEBOOK_00).unlink()

    _commit_course_update(course, tmp_path)
    for name in (editor, other):
        pull = classroom["students"][name].follow(classroom["link"])
        assert pull.phase == "finished", (name, pull.message, pull.output[-8:])

    mine = json.loads((hub.home(editor) / COURSE / NOTEBOOK_00).read_text(encoding="utf-8"))
    sources = "\n".join("".join(cell["source"]) for cell in mine["cells"])
    assert STUDENT_LINE in sources and COURSE_LINE not in sources  # the student's line wins
    assert (hub.home(editor) / COURSE / COURSE_NEW_FILE).is_file()  # the rest arrives
    # Negative control: the student who deleted the notebook gets the course's new version.
    fresh = (hub.home(other) / COURSE / NOTEBOOK_00).read_text(encoding="utf-8")
    assert COURSE_LINE in fresh and STUDENT_LINE not in fresh


# --------------------------------------------------------------------------- faults
def test_a_repository_that_cannot_be_pulled_says_so(classroom, hub, course):
    name = STUDENTS[1]
    missing = course.parent / "no_such_course.git"
    pull = classroom["students"][name].follow(handout_link(hub.url, missing.as_uri()))
    assert pull.phase == "error" and pull.message, pull
    # what the instructor's check says about the same link, before sending it
    problems = check_handout(hub.url, missing.as_uri())
    assert len(problems) == 1 and "cannot be pulled" in problems[0]
    # the student's course and server are as they were
    assert (hub.home(name) / COURSE / NOTEBOOK_04).is_file()
    status, _ = hub.server_api(name, "GET", "/status")
    assert status == 200


def test_a_server_stopped_mid_cell_leaves_the_others_working(classroom, hub):
    stopped, others = STUDENTS[2], STUDENTS[:2]
    results = classroom["results"]

    async def scenario():
        victim = KernelClient(hub, stopped, results[stopped]["kernels"][0].kernel_id)
        await victim.connect()
        clients = []
        for name in others:
            client = KernelClient(hub, name, results[name]["kernels"][1].kernel_id)
            await client.connect()
            clients.append(client)
        long_cell = asyncio.ensure_future(victim.run("import time\ntime.sleep(120)"))
        await asyncio.sleep(1.0)
        status, _ = await asyncio.to_thread(hub.api, "DELETE", f"/users/{stopped}/server")
        moved = [client.run('explorer.controls["theta"].value = 0.7') for client in clients]
        outcomes = await asyncio.gather(long_cell, *moved, return_exceptions=True)
        for client in clients:
            client.close()
        return status, outcomes

    begun = time.perf_counter()
    status, outcomes = asyncio.run(scenario())
    assert status in (202, 204), status
    assert isinstance(outcomes[0], ServerGone), outcomes[0]  # not a hang, not a result
    assert time.perf_counter() - begun < 90
    for name, run in zip(others, outcomes[1:]):
        assert not isinstance(run, BaseException), (name, run)
        assert run.error is None and run.widget_pngs >= 1, (name, run.error)
    # The hub says the server is gone, to the API and to the student's next request (its
    # bookkeeping may end a moment after the process, hence the wait).
    deadline = time.monotonic() + 60
    while "" in (model := hub.api("GET", f"/users/{stopped}")[1])["servers"]:
        assert time.monotonic() < deadline, model["servers"]
        time.sleep(0.5)
    status, answer = hub.server_api(stopped, "GET", "/status")
    assert status in (424, 503), (status, answer)
    # The student's work stays in their home for the next start.
    assert (hub.home(stopped) / COURSE / NOTEBOOK_00).is_file()


# --------------------------------------------------------------------------- the end
def test_the_hub_stops_and_leaves_no_process(hub, classroom):
    assert len(hub.seen) >= 1 + 1 + 2 * len(STUDENTS)  # hub, proxy, servers and kernels
    assert alive(hub.seen)  # they were found while they ran
    survivors = hub.stop()
    assert survivors == [], survivors
    assert alive(hub.seen) == []
    # Negative control: the same check reports a process that is still running.
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        assert alive([sleeper.pid]) == [sleeper.pid]
    finally:
        sleeper.kill()
        sleeper.wait()
    assert alive([sleeper.pid]) == []


def test_the_image_cache_was_read_only(image):
    assert not any(path.stat().st_mode & (stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH)
                   for path in [image, *image.rglob("*")])
