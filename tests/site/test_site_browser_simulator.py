"""A notebook's live simulator on the website: it integrates in the reader's browser.

A throwaway site built with the course's configuration holds a notebook with four live
simulators and an explorer: the double pendulum, which the browser can run from its shipped
module; a chain of seven links, which it cannot (the negative control); the Kapitza pendulum,
whose module is not shipped and travels in the page; the spherical pendulum, a system in space
(drawn in a projection the reader turns, as on notebook 19's page); and an explorer's run. In
Chromium each runnable one is integrated in the browser as it plays, above its still picture;
the chain shows only its picture with the reason.
"""

from __future__ import annotations

import pytest
from browser_engine import engine_page
from test_site_controls import INDEX, Annotated, Markdown, build, make_site, notebook

pytestmark = pytest.mark.site


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    folder = tmp_path_factory.mktemp("browser-sim-site")
    make_site(folder, {
        "index.md": INDEX,
        "lesson.ipynb": notebook(
            Markdown("# Lesson"),
            Annotated("import pendulum_lab as pl\nfrom pendulum_lab import widgets\n"
                      "widgets.live_simulator(pl.double_pendulum(), t_end=5.0)",
                      alt=["The double pendulum's first run and its energies"]),
            Annotated("widgets.live_simulator(pl.n_pendulum(7), t_end=1.0, dt=0.05, "
                      "method='rk4')", alt=["A chain of seven links and its energies"]),
            Annotated("widgets.live_simulator(pl.kapitza_pendulum(), t_end=2.0, dt=0.001, "
                      "method='rk4')", alt=["The Kapitza pendulum held up by its shaking"]),
            Annotated("widgets.explore(pl.double_pendulum(), method='leapfrog', t_end=5.0, "
                      "dt=0.02)", alt=["An explorer's plots of the double pendulum"]),
            Annotated("widgets.live_simulator(pl.spherical_pendulum(), [0.4, 0.0], [0.0, 1.5], "
                      "t_end=1.0, method='rk4')",
                      alt=["The spherical pendulum from above and from the side"]),
        ),
    })
    result = build(folder)
    # the throwaway index has no section "run-live" to link to; nothing else may warn
    warnings = [line for line in result.log.splitlines()
                if ": WARNING:" in line and "run-live" not in line]
    assert warnings == []
    return result.output


def test_a_notebooks_live_simulator_runs_in_the_browser_above_its_picture(site, tmp_path):
    with engine_page(site, tmp=tmp_path) as (page, base, requests):
        page.goto(f"{base}/lesson.html")
        page.wait_for_function(
            "() => [...document.querySelectorAll('.plab-live')].filter("
            "(el) => el.dataset.run === '1').length === 4", timeout=30_000)
        first = page.evaluate("() => ({...document.querySelector('.plab-live').dataset})")
        page.wait_for_timeout(500)
        later = page.evaluate("() => ({...document.querySelector('.plab-live').dataset})")
        assert int(later["frames"]) > int(first["frames"])
        # integrated as it plays: the run (of 501 kept states) grows, it is not there whole
        assert int(first["states"]) < int(later["states"]) < 501
        assert page.locator(".plab-browser-sim").count() == 4  # the 7-link chain has none
        assert page.locator("img").count() == 5  # every still picture stays
        # the system in space: its points with their height, its view buttons shown (a plane's
        # simulators keep theirs hidden)
        space = page.locator(".plab-live").nth(3)
        x, y, z = (float(v) for v in space.get_attribute("data-points").split())
        # on the rod's sphere, to the sag of a chord between states 10 ms apart while it plays
        assert x * x + y * y + z * z == pytest.approx(1.0, abs=1e-3) and z < 0
        assert space.locator(".plab-views").is_visible()
        assert not page.locator(".plab-live").first.locator(".plab-views").is_visible()
        text = page.locator("article, body").first.inner_text()
        assert "cannot run in this page (a model of 7 coordinates" in text
        statuses = page.locator(".plab-engine-status").all_text_contents()
        runs = [(500, "glrk4", 0.01), (2000, "rk4", 0.001), (250, "leapfrog", 0.02),
                (100, "rk4", 0.01)]  # the Kapitza pendulum second, the system in space last
        assert len(statuses) == len(runs)
        for status, run in zip(statuses, runs):
            assert integrating(status, *run), status
        assert all(url.startswith(base) for url in requests)
        assert [e for e in page.errors if "favicon" not in e and "404" not in e] == []


def integrating(status: str, steps: int, method: str, dt: float) -> bool:
    """Whether an engine's status says it integrates ``steps`` of ``method`` at ``dt``, or that
    it is falling behind with that method and step (on a loaded machine, the first frames)."""
    run = f"{method} (Δt = {dt} s)"
    return f"{steps} steps of {run} computed in the browser" in status or (
        status.startswith("Falling behind") and f"steps of {run} this frame called for" in status)
