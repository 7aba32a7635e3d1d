"""The course website's live simulators, on the built site: they integrate as they play.

On the "try it" page and the pages of notebooks 00 (its explorer's run), 05 (its live
simulator of the canonical method) and 06 (its explorer's run), a simulator runs in the
reader's browser above its still picture. In Chromium each one's run grows while it plays
(real time: it is not computed whole when the page opens), nothing is fetched from another
host, and a screenshot of each goes to ``test-artifacts/site/live/`` for a reader to see. The
negative control: notebook 01's page, which shows no widget, has no live simulator.
"""

from __future__ import annotations

import concurrent.futures

import pytest
from site_harness import ARTIFACTS, CHROMIUM_ARGS, chromium_path, serve

pytestmark = pytest.mark.site

LIVE_SHOTS = ARTIFACTS / "live"
#: Page: the live simulators it shows.
LIVE_PAGES = {
    "try-it.html": 1,
    "notebooks/00_start_here.html": 1,
    "notebooks/05_semi_implicit_euler.html": 1,
    "notebooks/06_leapfrog.html": 1,
    "notebooks/01_deriving_the_equations.html": 0,  # the control
}
WATCH_MS = 1000

STATES = "() => [...document.querySelectorAll('.plab-live')].map((el) => +el.dataset.states)"


def _visit(html_dir) -> tuple[str, dict, list[str]]:
    """What each page showed: live simulators, their states before and after watching, their
    status lines, the screenshot; and every URL requested. In a thread of its own, as the
    crawl (Playwright's sync API refuses a thread where an asyncio loop runs)."""
    from urllib.parse import urlsplit

    from playwright.sync_api import sync_playwright

    def visit():
        seen, requests = {}, []
        LIVE_SHOTS.mkdir(parents=True, exist_ok=True)
        with serve(html_dir) as base, sync_playwright() as p:
            browser = p.chromium.launch(executable_path=chromium_path(), args=CHROMIUM_ARGS)
            try:
                page = browser.new_page(viewport={"width": 1300, "height": 900})
                page.on("request", lambda request: requests.append(request.url))
                errors = []
                page.on("pageerror", lambda e: errors.append(str(e)))
                page.route("**/*", lambda r: r.abort() if urlsplit(r.request.url).netloc
                           != urlsplit(base).netloc else r.continue_())
                for name, expected in LIVE_PAGES.items():
                    page.goto(f"{base}/{name}", wait_until="load")
                    if expected:
                        page.wait_for_function(
                            f"() => document.querySelectorAll('.plab-live[data-run]').length "
                            f">= {expected}", timeout=30_000)
                    first = page.evaluate(STATES)
                    page.wait_for_timeout(WATCH_MS if expected else 0)
                    later = page.evaluate(STATES)
                    shot = None
                    if expected:
                        holder = page.locator(".plab-browser-sim").first
                        holder.scroll_into_view_if_needed()
                        shot = LIVE_SHOTS / (name.removesuffix(".html").replace("/", "__") + ".png")
                        holder.screenshot(path=str(shot))
                    seen[name] = dict(
                        count=page.locator(".plab-browser-sim").count(), first=first, later=later,
                        status=page.locator(".plab-engine-status").all_text_contents(),
                        shot=shot, errors=list(errors))
                    errors.clear()
            finally:
                browser.close()
        return base, seen, requests

    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        return pool.submit(visit).result()


def test_the_live_pages_integrate_as_they_play_and_leave_screenshots(course_site):
    from urllib.parse import urlsplit

    if not course_site.ok:
        pytest.fail("the course site did not build; see test_site_builds", pytrace=False)
    base, seen, requests = _visit(course_site.output)
    for name, expected in LIVE_PAGES.items():
        page = seen[name]
        assert page["count"] == expected, name
        assert page["errors"] == [], name
        if not expected:
            assert page["first"] == [] and page["status"] == []
            continue
        first, later = page["first"][0], page["later"][0]
        # 1 s of playing keeps 50 (dt = 0.02) to 100 states more: the run grows as it plays
        assert later > first + 10, (name, first, later)
        status = page["status"][0]  # on a loaded machine it may be falling behind, and say so
        assert "computed in the browser as the motion plays" in status \
            or status.startswith("Falling behind"), (name, status)
        assert page["shot"].is_file() and page["shot"].stat().st_size > 10_000, name
    assert not [url for url in requests if urlsplit(url).netloc != urlsplit(base).netloc]
