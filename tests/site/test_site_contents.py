"""The site is the course's table of contents: throwaway sites built with the course's
configuration, whose ``notebooks/`` agrees with the table, or has a stray notebook, or lacks a
listed one; and the progress a build prints while it reads the notebooks.
"""

from __future__ import annotations

import copy
import json
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


def _ran_elsewhere(site, name: str, text: str, stream: str = "stdout",
                   source: str | None = None) -> dict:
    """The notebook ``name`` of ``site`` as another front end would hold it after running it:
    its code cell printed ``text`` on ``stream`` (``source``: its code was edited first)."""
    ran = copy.deepcopy(json.loads((site / "notebooks" / f"{name}.ipynb").read_text()))
    ran["metadata"]["language_info"] = {"name": "python"}  # what a front end adds
    cell = next(cell for cell in ran["cells"] if cell["cell_type"] == "code")
    cell.update(execution_count=1, source=source or cell["source"],
                outputs=[{"output_type": "stream", "name": stream, "text": text}])
    return ran


def test_outputs_of_a_run_elsewhere_are_shown_and_other_notebooks_run(tmp_path):
    """The execution cache seeded from runs elsewhere (the JupyterLab run of tests/browser):
    the build shows a matching run's outputs; a run of edited code or one that wrote to
    standard error is not taken, and the build runs those notebooks itself."""
    site = make_site(tmp_path, course_files("03_third"))
    site.joinpath("notebooks/00_intro.ipynb").write_text(notebook(Markdown(
        CONTENTS + "| `03_third` | the third lesson |\n")))
    runs = {site / "notebooks" / "01_first.ipynb": _ran_elsewhere(site, "01_first", "ELSEWHERE\n"),
            site / "notebooks" / "02_second.ipynb": _ran_elsewhere(
                site, "02_second", "EDITED\n", source="print('edited')"),
            site / "notebooks" / "03_third.ipynb": _ran_elsewhere(
                site, "03_third", "a warning\n", stream="stderr")}
    seeded = build_site.seed_execution_cache({path: (ran, 1.5) for path, ran in runs.items()},
                                             output=site / "_build" / "html")
    assert seeded == ["01_first"]
    result = build(site)
    assert result.ok, "\n".join(result.warnings()) or result.log[-2000:]
    assert "notebooks/01_first: taken from the cache" in result.log
    assert re.search(r"notebooks/02_second: executed in [\d.]+ s", result.log)
    assert re.search(r"notebooks/03_third: executed in [\d.]+ s", result.log)
    pages = {name: (result.output / "notebooks" / f"{name}.html").read_text(encoding="utf-8")
             for name in ("01_first", "02_second", "03_third")}
    assert "ELSEWHERE" in pages["01_first"]
    assert "EDITED" not in pages["02_second"] and "a warning" not in pages["03_third"]
    assert "stray" in pages["03_third"]  # its own run's output


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
