"""Negative controls for the website tests: small throwaway sites, built with the course's own
configuration (docs/conf.py and its extension), each with one defect that a check must catch.

* At build time (warnings are errors): a notebook cell that raises, a figure without alt text, a
  widget without a static picture, a broken cross-reference.
* In the browser: a traceback shown on a page, a broken internal link and anchor, a picture
  without alt text, an external script, untypeset mathematics, a console error, an animation
  that does not advance, a transparent picture on the dark page. A clean page in the same site
  must show no problem at all (the positive control).
* Launch buttons: present, with the right address, once ``course_repository_url`` is set.
"""

from __future__ import annotations

import base64
import io
import json
import re
import sys
import textwrap
from pathlib import Path

import pytest
from site_harness import CATEGORIES, REPO_ROOT, build_site, crawl, problems

pytestmark = pytest.mark.site

sys.path.insert(0, str(REPO_ROOT / "docs" / "_ext"))


class Markdown(str):
    """The source of a Markdown cell (any other string is a code cell)."""


class Annotated(str):
    """The source of a code cell with the course's metadata (``{"alt": [...], ...}``)."""

    def __new__(cls, source: str, **annotations):
        made = super().__new__(cls, source)
        made.annotations = annotations
        return made


def notebook(*cells: str) -> str:
    """A notebook (JSON) with these cells, Python 3 kernel, no outputs."""
    made = []
    for source in cells:
        kind = "markdown" if isinstance(source, Markdown) else "code"
        metadata = {"pendulum_lab": source.annotations} if isinstance(source, Annotated) else {}
        cell = {"cell_type": kind, "id": f"c{len(made)}", "metadata": metadata,
                "source": str(source)}
        if kind == "code":
            cell.update(outputs=[], execution_count=None)
        made.append(cell)
    return json.dumps(
        {
            "cells": made,
            "metadata": {"kernelspec": {"name": "python3", "display_name": "Python 3"}},
            "nbformat": 4,
            "nbformat_minor": 5,
        }
    )


def make_site(folder: Path, files: dict[str, str]) -> Path:
    for name, text in files.items():
        path = folder / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(textwrap.dedent(text), encoding="utf-8")
    return folder


def build(folder: Path, overrides: dict | None = None, **kwargs):
    """Build a throwaway site with the course configuration, without the API reference."""
    overrides = {"course_api_package": "", **(overrides or {})}
    return build_site.build(
        source=folder, output=folder / "_build" / "html", jobs=1, overrides=overrides, **kwargs
    )


INDEX = """\
# Control site

```{toctree}
:glob:

*
```
"""

FIGURE = "import matplotlib.pyplot as plt\nplt.plot([0, 1], [1, 0]);"


# ---------------------------------------------------------------------------------------------
# Build-time controls
# ---------------------------------------------------------------------------------------------
def test_a_cell_that_raises_fails_the_build(tmp_path):
    site = make_site(
        tmp_path,
        {
            "index.md": INDEX,
            "lesson.ipynb": notebook(Markdown("# Lesson"), "raise RuntimeError('boom')"),
        },
    )
    result = build(site)
    assert not result.ok
    assert "RuntimeError" in result.log and "boom" in result.log


def test_a_figure_without_alt_text_fails_the_build_and_alt_metadata_mends_it(tmp_path):
    site = make_site(
        tmp_path, {"index.md": INDEX, "lesson.ipynb": notebook(Markdown("# Lesson"), FIGURE)}
    )
    result = build(site)
    assert not result.ok
    assert "has no alt text" in result.log
    described = Annotated(FIGURE, expect=["figure"], alt=["A straight line falling from 1 to 0."])
    (site / "lesson.ipynb").write_text(notebook(Markdown("# Lesson"), described))
    result = build(site)
    assert result.ok, "\n".join(result.warnings())
    page = (site / "_build" / "html" / "lesson.html").read_text(encoding="utf-8")
    assert 'alt="A straight line falling from 1 to 0."' in page
    # The cell's code is shown as highlighted code, as the student sees it: the annotations
    # stay in the metadata.
    code = '<div class="highlight"><pre><span></span><span class="kn">import</span>'
    assert code in page
    # ... and the metadata does not reach the page (its title may name the project, so look for
    # the metadata's key as JSON and for the word "expect").
    assert '"pendulum_lab"' not in page and "&quot;pendulum_lab&quot;" not in page
    assert "expect" not in page


def test_a_widget_without_a_static_picture_fails_the_build(tmp_path):
    site = make_site(
        tmp_path,
        {
            "index.md": INDEX,
            "lesson.ipynb": notebook(
                Markdown("# Lesson"), "import ipywidgets\nipywidgets.IntSlider()"
            ),
        },
    )
    result = build(site)
    assert not result.ok
    assert "without a static picture" in result.log


def test_a_broken_cross_reference_fails_the_build(tmp_path):
    site = make_site(
        tmp_path, {"index.md": INDEX, "page.md": "# Page\n\nSee [the lesson](missing.md).\n"}
    )
    result = build(site)
    assert not result.ok
    assert "missing" in result.log


# ---------------------------------------------------------------------------------------------
# Browser controls
# ---------------------------------------------------------------------------------------------
def _transparent_png() -> str:
    from PIL import Image

    buffer = io.BytesIO()
    image = Image.new("RGBA", (40, 20), (0, 0, 0, 0))
    image.paste((0, 0, 0, 255), (0, 9, 40, 11))  # a black line on nothing
    image.save(buffer, format="PNG")
    return base64.b64encode(buffer.getvalue()).decode()


def _animation(alt: str, moving: bool = True) -> str:
    """matplotlib's JavaScript player (a frame every 200 ms): a dot moving from left to right over
    twelve frames (more than a played check sees, so that a loop cannot come back to the frame it
    started from), or (``moving=False``) three identical frames, so that it can never advance."""
    from matplotlib.animation import FuncAnimation
    from matplotlib.figure import Figure

    figure = Figure(figsize=(2, 1), dpi=40)
    frames = 12 if moving else 3
    axes = figure.add_subplot(xlim=(-0.5, frames - 0.5), ylim=(-1, 1))
    (dot,) = axes.plot([0], [0], "o")

    def draw(k):
        dot.set_xdata([k if moving else 0])
        return [dot]

    html = FuncAnimation(figure, draw, frames=frames, interval=200).to_jshtml(default_mode="loop")
    html = re.sub(r"<link[^>]*https?://[^>]*>", "", html)  # the external-request control is apart
    return html.replace("<img ", f'<img alt="{alt}" ', 1)


def _frozen_animation() -> str:
    return _animation("A frozen animation", moving=False)


def _dead_player() -> str:
    """A player whose frames are never loaded: the script that creates it is missing."""
    html = _animation("A player without its animation")
    html, removed = re.subn(r"<script[^>]*>\s*/\* Instantiate the Animation class.*?</script>",
                            "", html, flags=re.DOTALL)  # fmt: skip
    assert removed == 1
    return html


def _unfound_animation() -> str:
    """A working animation that the crawl cannot find as a player (its wrapper renamed): the
    count of animations embedded in the HTML must catch it."""
    html = _animation("An animation in disguise")
    return html.replace('<div class="animation">', '<div class="movie">', 1)


def _autoplaying_animation() -> str:
    """A working animation that starts by itself: the paused control must notice it moving."""
    html = '<div id="autoplay">' + _animation("An animation that plays by itself") + "</div>"
    return html + (
        "<script>setTimeout(() => document.querySelector('#autoplay button[title=Play]')"
        ".click(), 100);</script>"
    )


@pytest.fixture(scope="module")
def control_crawl(tmp_path_factory):
    """A site whose pages each carry one defect, and one clean page; built without -W so that
    the defective pages exist, then opened in the browser in both modes."""
    folder = tmp_path_factory.mktemp("control_site")
    make_site(
        folder,
        {
            "index.md": INDEX,
            "clean.md": """\
                # A clean page

                A formula, $E = T + V$, a [link to the index](index.md), and a picture:

                ![The course's pendulum icon](_static/favicon.svg)
                """,
            "traceback.ipynb": notebook(Markdown("# A cell that raises"), "1 / 0"),
            "broken_link.md": """\
                # Broken links

                <a href="missing.html">a page that does not exist</a>,
                <a href="index.html#no-such-anchor">an anchor that does not exist</a>
                """,
            "no_alt.md": '# No alt text\n\n<img src="_static/favicon.svg">\n',
            "external_script.md": (
                '# An external script\n\n<script src="https://cdn.example.invalid/x.js"></script>\n'
            ),
            "raw_math.md": "# Untypeset mathematics\n\n<p>$$ E = T + V $$</p>\n",
            "bare_code.md": (
                "# A code cell without its code block\n\n"
                '<div class="cell_input docutils container">x = 1\nprint(x)</div>\n'
            ),
            "console_error.md": (
                '# A console error\n\n<script>console.error("control: failure");</script>\n'
            ),
            "frozen_animation.md": "# A frozen animation\n\n" + _frozen_animation() + "\n",
            "moving_animation.md": "# A working animation\n\n" + _animation("A dot moving") + "\n",
            "dead_player.md": "# A player without its animation\n\n" + _dead_player() + "\n",
            "unfound_animation.md": "# An animation not found\n\n" + _unfound_animation() + "\n",
            "autoplay.md": "# An animation playing by itself\n\n" + _autoplaying_animation() + "\n",
            "transparent.md": (
                "# A transparent picture\n\n"
                f'<img alt="A black line" src="data:image/png;base64,{_transparent_png()}" '
                'style="background-color: transparent !important">\n'
            ),
        },
    )
    result = build(
        folder,
        warnings_are_errors=False,
        overrides={"nb_execution_allow_errors": "1", "suppress_warnings": "course.alt"},
    )
    html = folder / "_build" / "html"
    assert (html / "clean.html").is_file(), result.log[-3000:]
    reports = crawl(html)
    return reports, problems(reports, html)


@pytest.fixture(scope="module")
def control_site(control_crawl):
    """The problems found on the control site, by category."""
    return control_crawl[1]


EXPECTED = {
    "traceback": "error output",
    "broken_link": "internal links",
    "no_alt": "alt text",
    "external_script": "external requests",
    "raw_math": "math",
    "console_error": "console errors",
    "frozen_animation": "animations",
    "dead_player": "animations",
    "unfound_animation": "animations",
    "autoplay": "animations",
    "transparent": "dark mode",
    "bare_code": "code cells",
}


@pytest.mark.parametrize("page", sorted(EXPECTED))
def test_each_defect_is_caught(control_site, page):
    category = EXPECTED[page]
    assert any(p.startswith(f"{page}.html ") for p in control_site[category]), (
        f"the {category!r} check missed the defect on {page}.html: {control_site[category]}"
    )


def test_the_clean_page_shows_no_problem(control_site):
    found = [p for category in CATEGORIES for p in control_site[category]]
    assert not [p for p in found if p.startswith("clean.html ")], found


def test_a_working_animation_passes_and_each_broken_one_fails_for_its_reason(control_crawl):
    reports, found = control_crawl
    played = {r.page: r for r in reports if r.embedded_animations is not None}
    # The positive control: found, still until played, then advancing; no problem at all.
    (moving,) = played["moving_animation.html"].animations
    assert moving["frames"] == 12 and not moving["moved_unplayed"]
    assert moving["advanced"] and moving["changed"]
    assert not [p for c in CATEGORIES for p in found[c] if p.startswith("moving_animation.html ")]
    animations = found["animations"]

    def flagged(page: str) -> str:
        return " ".join(p for p in animations if p.startswith(f"{page}.html "))

    assert "did not advance when played" in flagged("frozen_animation")
    assert "did not advance when played" in flagged("dead_player")
    assert "1 animation(s) embedded in the HTML, 0 found" in flagged("unfound_animation")
    assert "changed before it was played" in flagged("autoplay")
    assert "did not advance" not in flagged("autoplay")  # it plays, it just did not wait


def test_both_broken_links_are_caught(control_site):
    broken = [p for p in control_site["internal links"] if p.startswith("broken_link.html ")]
    assert any("missing.html" in p for p in broken)
    assert any("#no-such-anchor" in p for p in broken)


# ---------------------------------------------------------------------------------------------
# Launch buttons
# ---------------------------------------------------------------------------------------------
def test_launch_buttons_appear_once_the_repository_is_set(tmp_path):
    site = make_site(tmp_path, {"index.md": INDEX, "lesson.ipynb": notebook(Markdown("# Lesson"))})
    repository = "https://github.com/someone/pendulum_lab"
    result = build(
        site, overrides={"course_repository_url": repository, "nb_execution_mode": "off"}
    )
    assert result.ok, "\n".join(result.warnings())
    page = (site / "_build" / "html" / "lesson.html").read_text(encoding="utf-8")
    binder = (
        "https://mybinder.org/v2/gh/someone/pendulum_lab/main?urlpath=lab/tree/docs/lesson.ipynb"
    )
    assert binder in page
    # In the course the page docs/notebooks/NAME.ipynb is the notebook itself (a symbolic link
    # to notebooks/), so the launched path exists in the repository.
    assert (REPO_ROOT / "docs" / "notebooks").resolve() == (REPO_ROOT / "notebooks").resolve()


def test_a_repository_address_that_is_not_one_is_refused(tmp_path):
    site = make_site(tmp_path, {"index.md": INDEX})
    result = build(site, overrides={"course_repository_url": "github.com/someone"})
    assert not result.ok
    assert "course_repository_url" in result.log


# ---------------------------------------------------------------------------------------------
# The extension's parsing, without a build
# ---------------------------------------------------------------------------------------------
def test_alt_texts_are_read_from_the_cell_metadata():
    from course_site import alt_texts, html_without_alt

    metadata = {"pendulum_lab": {"expect": ["figure"], "alt": ["Energy.", "A second picture."]}}
    assert alt_texts(metadata) == ["Energy.", "A second picture."]
    assert alt_texts({"pendulum_lab": {"alt": "One text."}}) == ["One text."]
    assert alt_texts({"pendulum_lab": {"alt": ["   "]}}) == []  # an empty text is no text
    assert alt_texts({"pendulum_lab": {"expect": ["figure"]}}) == []
    assert alt_texts({"tags": ["alt"]}) == []
    assert html_without_alt('<img src="a.png">')
    assert html_without_alt('<img src="a.png" alt="">')
    assert not html_without_alt('<img alt="a curve" src="a.png">')
