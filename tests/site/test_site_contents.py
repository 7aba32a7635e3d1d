"""The site is the course's table of contents: throwaway sites built with the course's
configuration, whose ``notebooks/`` agrees with the table, or has a stray notebook, or lacks a
listed one; and the progress a build prints while it reads the notebooks.
"""

from __future__ import annotations

import re

import pytest
from site_harness import build_site
from test_site_controls import Markdown, make_site, notebook

pytestmark = pytest.mark.site

CONTENTS = Markdown(
    "# Start\n\n| Notebook | What you do there |\n| --- | --- |\n"
    "| `00_intro` | this page |\n| `02_second` | the second lesson |\n"
    "| `01_first` | the first lesson |\n"
)
INDEX = """\
# A course

```{course-map}
```

```{course-toctree}
:caption: Course
```
"""


def course_files(*extra: str) -> dict[str, str]:
    files = {
        "index.md": INDEX,
        "notebooks/00_intro.ipynb": notebook(CONTENTS),
        "notebooks/01_first.ipynb": notebook(Markdown("# First\n\nOne."), "print(1)"),
        "notebooks/02_second.ipynb": notebook(Markdown("# Second\n\nTwo."), "print(2)"),
    }
    for name in extra:
        files[f"notebooks/{name}.ipynb"] = notebook(Markdown(f"# {name}"), "print('stray')")
    return files


def build(folder):
    return build_site.build(source=folder, output=folder / "_build" / "html", jobs=1,
                            overrides={"course_api_package": "",
                                       "course_table_of_contents": "notebooks/00_intro.ipynb"})


def test_the_site_follows_the_table_and_reports_each_notebook(tmp_path):
    result = build(make_site(tmp_path, course_files()))
    assert result.ok, "\n".join(result.warnings()) or result.log[-2000:]
    page = (result.output / "index.html").read_text(encoding="utf-8")
    # the table's order (00, 02, 01), not the files' order, in the course map and navigation
    order = [page.index(f"notebooks/{name}.html") for name in ("00_intro", "02_second",
                                                               "01_first")]
    assert order == sorted(order)
    started = re.findall(r"^\[(\d)/(\d)\] (notebooks/\w+): executing", result.log, re.MULTILINE)
    assert sorted(count for count, _, _ in started) == ["1", "2", "3"]
    assert {total for _, total, _ in started} == {"3"}
    assert sorted(name for _, _, name in started) == [
        "notebooks/00_intro", "notebooks/01_first", "notebooks/02_second"]
    assert re.search(r"notebooks/01_first: executed in [\d.]+ s", result.log)
    # built again: the same notebooks now come from the execution cache
    again = build(tmp_path)
    assert again.ok
    assert "notebooks/01_first: taken from the cache" in again.log


def test_a_notebook_the_table_does_not_list_stops_the_build_before_anything_runs(tmp_path):
    result = build(make_site(tmp_path, course_files("99_stray")))
    assert not result.ok
    assert "99_stray.ipynb in notebooks/ is not in the course's table of contents" in result.log
    assert "executing" not in result.log  # stopped before the first notebook


def test_a_listed_notebook_that_is_missing_stops_the_build(tmp_path):
    site = make_site(tmp_path, course_files())
    (site / "notebooks" / "02_second.ipynb").unlink()
    result = build(site)
    assert not result.ok
    assert "lists 02_second, which notebooks/ does not have" in result.log
