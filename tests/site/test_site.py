"""The course website as a reader gets it: built with warnings as errors, every page opened in
Chromium from a local server, in light and dark mode.

The negative controls that show each check can fail are in ``test_site_controls.py``.
"""

from __future__ import annotations

import concurrent.futures
import functools
import html
import importlib
import inspect
import pkgutil
import re

import pytest
from site_harness import (
    CATEGORIES,
    CHROMIUM_ARGS,
    MODES,
    REPO_ROOT,
    SCREENSHOTS,
    api_pages_checked_in_one_mode,
    chromium_path,
    list_pages,
    serve,
)

import pendulum_lab

pytestmark = pytest.mark.site

NOTEBOOKS = sorted((REPO_ROOT / "notebooks").glob("*.ipynb"))


def _report(found: list[str], limit: int = 25) -> str:
    shown = "\n  ".join(found[:limit])
    more = f"\n  ... and {len(found) - limit} more" if len(found) > limit else ""
    return f"{len(found)} problem(s):\n  {shown}{more}"


# ---------------------------------------------------------------------------------------------
# The build
# ---------------------------------------------------------------------------------------------
def test_site_builds_with_warnings_as_errors(course_site):
    if not course_site.ok:
        pytest.fail(
            "make docs failed (warnings are errors):\n" + "\n".join(course_site.warnings()[:40]),
            pytrace=False,
        )


def test_every_notebook_is_a_page_in_reading_order(course_site):
    html = course_site.output
    assert NOTEBOOKS, "no notebooks found"
    for notebook in NOTEBOOKS:
        assert (html / "notebooks" / f"{notebook.stem}.html").is_file(), notebook.name
        # The download button offers the notebook as it is in the repository.
        download = html / "_sources" / "notebooks" / notebook.name
        assert download.read_bytes() == notebook.read_bytes(), notebook.name
    # The navigation lists the notebooks in the order of their numbers.
    index = (html / "index.html").read_text(encoding="utf-8")
    order = re.findall(r'href="notebooks/([^"#]+)\.html"', index)
    listed = list(dict.fromkeys(order))
    assert listed == [n.stem for n in NOTEBOOKS]


def test_every_notebook_page_offers_the_ipynb_download(course_site):
    for notebook in NOTEBOOKS:
        page = (course_site.output / "notebooks" / f"{notebook.stem}.html").read_text("utf-8")
        assert f'href="../_sources/notebooks/{notebook.name}"' in page, notebook.name


def _documented_members(module):
    """Public objects a module's API page documents: its ``__all__``, else what it defines."""
    names = getattr(module, "__all__", None)
    if names is None:
        names = [
            name
            for name, obj in vars(module).items()
            if not name.startswith("_") and getattr(obj, "__module__", None) == module.__name__
        ]
    return [getattr(module, name) for name in names]


def test_api_pages_cover_every_public_module_and_show_the_examples(course_site):
    modules = ["pendulum_lab"] + [
        info.name
        for info in pkgutil.walk_packages(pendulum_lab.__path__, "pendulum_lab.")
        if not any(part.startswith("_") for part in info.name.split("."))
    ]
    examples = 0
    for name in modules:
        page = course_site.output / "reference" / f"{name}.html"
        assert page.is_file(), f"no API page for {name}"
        text = html.unescape(re.sub(r"<[^>]+>", "", page.read_text(encoding="utf-8")))
        module = importlib.import_module(name)
        if hasattr(module, "__path__"):
            continue  # a package's page lists its modules; their pages show the members
        for obj in _documented_members(module):
            doc = inspect.getdoc(obj) or ""
            first = next((line for line in doc.splitlines() if line.startswith(">>> ")), None)
            if first:  # Sphinx shows examples without their doctest flags
                first = re.sub(r"\s*# doctest:.*$", "", first)
            if "Examples\n--------" in doc and first:
                examples += 1
                assert first in text, f"{name}: the example {first!r} is not on its page"
    assert examples > 0, "no docstring example found: the check would pass vacuously"


@functools.cache
def _public_modules() -> tuple[str, ...]:
    return ("pendulum_lab",) + tuple(
        info.name
        for info in pkgutil.walk_packages(pendulum_lab.__path__, "pendulum_lab.")
        if not any(part.startswith("_") for part in info.name.split("."))
    )


@functools.cache
def _page_text(path) -> str:
    return path.read_text(encoding="utf-8")


def _reexported_names():
    """(package, name, object) for every class and function a package exports in ``__all__``."""
    for name in _public_modules():
        module = importlib.import_module(name)
        if not hasattr(module, "__path__"):
            continue
        for attr in getattr(module, "__all__", []):
            obj = getattr(module, attr)
            if inspect.isclass(obj) or inspect.isfunction(obj):
                yield name, attr, obj


def _api_anchors(html_dir, obj) -> list[str]:
    """The anchors of ``obj`` on the API pages of the public modules that document it (a
    module page documents its ``__all__``, including names it imports)."""
    found = []
    for name in _public_modules():
        module = importlib.import_module(name)
        if hasattr(module, "__path__"):
            continue  # a package's page lists its modules
        for member_name in getattr(module, "__all__", None) or [obj.__name__]:
            if getattr(module, member_name, None) is obj:
                anchor = f'id="{name}.{member_name}"'
                page = html_dir / "reference" / f"{name}.html"
                if page.is_file() and anchor in _page_text(page):
                    found.append(f"{name}.{member_name}")
    return found


def test_every_name_a_package_exports_is_documented(course_site):
    # A name that a package exports from a private module (one whose name starts with "_")
    # has a page only if a public module lists it in its __all__: the walk skips private ones.
    names = list(_reexported_names())
    assert len(names) > 100, "too few exported names found: the check would pass vacuously"
    missing = [
        f"{package}.{attr} (defined in {obj.__module__})"
        for package, attr, obj in names
        if not _api_anchors(course_site.output, obj)
    ]
    assert not missing, missing
    # Negative control: a private function (no public module lists it, so it has no page).
    from pendulum_lab.model.numeric import _lambdify

    assert not _api_anchors(course_site.output, _lambdify)


def test_no_launch_link_while_the_repository_is_unset(course_site):
    # docs/conf.py leaves course_repository_url empty until the course has a public address.
    # The guides may name Binder and show the form of a launch address in a code block; what
    # must be absent is a launch link (a link to mybinder.org/v2/...) and the theme's buttons.
    launch_link = re.compile(r"""href=["']https://mybinder\.org/v2/""")
    for page in list_pages(course_site.output):
        text = (course_site.output / page).read_text(encoding="utf-8")
        assert not launch_link.search(text) and "launch-buttons" not in text, page
    # Negative control: the pattern finds the link the theme writes once the address is set
    # (test_site_controls.py builds such a site).
    assert launch_link.search('<a href="https://mybinder.org/v2/gh/o/r/main?urlpath=lab">')


# ---------------------------------------------------------------------------------------------
# Every page in the browser
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("category", CATEGORIES)
def test_pages_in_the_browser(course_pages, category):
    """No error output or traceback; every picture loaded and described; mathematics typeset;
    each animation advances when played; no request outside the site and none failing; no
    console error; every internal link and anchor resolves; readable in dark mode; every code
    cell shown as a code block."""
    _, found = course_pages
    if found[category]:
        pytest.fail(f"{category}: {_report(found[category])}", pytrace=False)


def test_the_checks_saw_what_they_check(course_pages, course_site):
    reports, _ = course_pages
    light = [r for r in reports if r.mode == MODES[0]]
    assert {r.page for r in reports} == set(list_pages(course_site.output))
    assert sum(len(r.images) for r in light) >= len(NOTEBOOKS), "too few pictures seen"
    assert sum(r.typeset for r in light) > 0, "no typeset mathematics seen"
    assert sum(len(r.animations) for r in light) >= 1, "no embedded animation was played"
    # The simulator and the key motions play on the pages of the notebooks that embed them
    # (notebook 06: the report's failing leapfrog; 10: the simulator; 11: chaos; 12: a chain).
    embedding = {
        f"notebooks/{n.stem}.html"
        for n in NOTEBOOKS
        if "animation.html_animation(" in n.read_text(encoding="utf-8")
    }
    assert {"notebooks/06_leapfrog.html", "notebooks/11_double_pendulum_chaos.html"} <= embedding
    played = {r.page for r in light if r.animations}
    assert embedding <= played, f"no animation played on {sorted(embedding - played)}"
    assert sum(len(r.links) for r in light) > 0


# Speech and the explorer (MathJax's menu, Accessibility) load the speech rule engine, whose
# bundled defaults name a CDN for its rule files; MathJax points it at the local copy instead.
_SPEECH_ON = """async () => {
    await MathJax.startup.promise;
    const pool = MathJax.startup.document.menu.menu.pool;
    pool.lookup('speech').setValue(true);
    pool.lookup('explorer').setValue(true);
    for (let i = 0; i < 100 && !window.SREfeature; i++) await new Promise(r => setTimeout(r, 100));
    await new Promise(r => setTimeout(r, 3000));  // the rule files load after the engine
}"""


def _requests_with_speech_on(html_dir) -> tuple[str, list[str]]:
    """The server's address and every URL a notebook page requests once speech is on.

    Runs in a thread of its own, as the crawl does: Playwright's sync API refuses a thread
    where an asyncio loop runs (the browser tests leave one in the main thread).
    """
    from urllib.parse import urlsplit

    from playwright.sync_api import sync_playwright

    def visit():
        requests = []
        with serve(html_dir) as base, sync_playwright() as p:
            browser = p.chromium.launch(executable_path=chromium_path(), args=CHROMIUM_ARGS)
            try:
                page = browser.new_page()
                page.on("request", lambda request: requests.append(request.url))
                page.route("**/*", lambda r: r.abort() if urlsplit(r.request.url).netloc
                           != urlsplit(base).netloc else r.continue_())
                page.goto(f"{base}/notebooks/01_deriving_the_equations.html", wait_until="load")
                page.wait_for_function(
                    "window.MathJax && MathJax.startup && MathJax.startup.document"
                )
                page.evaluate(_SPEECH_ON)
            finally:
                browser.close()
        return base, requests

    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        return pool.submit(visit).result()


def test_mathematics_read_aloud_fetches_nothing_outside_the_site(course_site):
    """A reader who turns on MathJax's speech loads the speech engine and its rule files from
    the site itself: the rule files must be requested (the feature ran) and only locally."""
    from urllib.parse import urlsplit

    if not course_site.ok:
        pytest.fail("the course site did not build; see test_site_builds", pytrace=False)
    base, requests = _requests_with_speech_on(course_site.output)
    rule_files = [url for url in requests if "/sre/mathmaps/" in url]
    assert rule_files, "speech did not load its rule files: the check saw nothing"
    outside = [url for url in requests if urlsplit(url).netloc != urlsplit(base).netloc]
    assert not outside, f"requests outside the site: {outside}"


def test_screenshots_of_every_page_in_both_modes(course_pages, course_site):
    # Every page but the API pages that the first of them stands for (conftest.py), which are
    # checked in one mode each, both modes taking some.
    one_mode = api_pages_checked_in_one_mode(course_site.output)
    pages = [page for page in list_pages(course_site.output) if page not in one_mode]
    assert set(one_mode.values()) == set(MODES)
    assert any(page.startswith("reference/") for page in pages)
    for mode in MODES:
        for page in pages:
            shot = SCREENSHOTS / mode / (page.removesuffix(".html").replace("/", "__") + ".png")
            assert shot.is_file() and shot.stat().st_size > 0, shot
        seen = {r.page for r in course_pages[0] if r.mode == mode}
        assert seen == set(pages) | {page for page, its in one_mode.items() if its == mode}
