"""pytest wiring of the website tests: the ``site`` marker, the skip/fail policy and the session
fixtures (the course site built once, its pages crawled once). See ``README.md`` beside this file.
"""

from __future__ import annotations

import shutil

import pytest
from site_harness import (
    ARTIFACTS,
    SCREENSHOTS,
    api_pages_checked_in_one_mode,
    build_site,
    crawl,
    in_ci,
    problems,
    site_unavailable_reason,
    summary,
    write_json,
)


def pytest_collection_modifyitems(config, items):
    reason = site_unavailable_reason()
    if reason is None or in_ci():
        return
    for item in items:
        if item.get_closest_marker("site") is not None:
            item.add_marker(pytest.mark.skip(reason=reason))


@pytest.fixture(scope="session")
def course_site(notebooks_run_in_jupyterlab):
    """The course website, built exactly as ``make docs`` builds it (same folder, same execution
    cache: notebooks unchanged since the last build are not run again). The notebooks that
    ran cleanly in JupyterLab earlier in this session (tests/browser) go into the execution
    cache first: the build shows their outputs and runs only the others."""
    reason = site_unavailable_reason()
    if reason is not None:
        pytest.fail(f"{reason} (CI=true: the site tests must run)", pytrace=False)
    notebooks = build_site.DOCS / "notebooks"
    seeded = build_site.seed_execution_cache(
        {notebooks / name: run for name, run in notebooks_run_in_jupyterlab.items()})
    result = build_site.build()
    write_json(ARTIFACTS / "build.json", {**build_site.report(result),
                                          "outputs_from_jupyterlab": seeded})
    return result


@pytest.fixture(scope="session")
def course_pages(course_site):
    """Every page of the course site opened in Chromium in light and dark mode (the API pages
    but the first in one of them): the records and the problems found, by category.
    Screenshots go to test-artifacts/site/screenshots/."""
    if not course_site.ok:
        pytest.fail("the course site did not build; see test_site_builds", pytrace=False)
    shutil.rmtree(SCREENSHOTS, ignore_errors=True)
    reports = crawl(course_site.output, screenshots=SCREENSHOTS,
                    one_mode=api_pages_checked_in_one_mode(course_site.output))
    found = problems(reports, course_site.output)
    write_json(ARTIFACTS / "pages.json", {**summary(reports), "problems": found})
    return reports, found
