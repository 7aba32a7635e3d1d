"""Sphinx extension for the pendulum_lab course site.

What it adds to Sphinx + MyST-NB + sphinx-book-theme (see docs/README.md for the authors' side):

* **Launch buttons from one setting.** ``course_repository_url`` (conf.py) fills the theme's
  ``repository_url`` and ``launch_buttons`` and the ``launch`` tag; while it is empty none of
  them is set, so no launch button and no Binder link is rendered.
* **Alt text from the cell.** A code cell's metadata may carry
  ``{"pendulum_lab": {"alt": [...]}}`` (:data:`ANNOTATIONS`); the texts become the ``alt`` of the
  pictures in that cell's outputs (PNG outputs and ``<img>`` in HTML outputs, such as an embedded
  animation). A picture anywhere on the site left without alt text is a build warning (an error
  under ``-W``).
* **Static pictures instead of live widgets.** An output that is a widget view is shown through
  the ``image/png`` carried in the same output (conf.py's mime priority), followed by a note that
  its controls need a live session. A widget output without such a picture is replaced by that
  note alone and must be listed in ``course_widgets_without_picture``. The widget state that
  the execution stored is dropped from the page.
* **Re-execution when the package changes.** The execution cache keys on the notebooks' code
  only; a fingerprint of ``pendulum_lab``'s source files is kept beside it, and when it changes
  the cache is emptied and every notebook is read again, so no page shows outputs of older code.
* **The course's table of contents.** The notebooks of the course and their order are the rows
  of the table in ``course_table_of_contents`` (conf.py: the table "What the course covers" of
  ``notebooks/00_start_here.ipynb``, which students read too). The directive
  ``course-toctree`` makes the site's navigation from it; a notebook in ``notebooks/`` that the
  table does not list, or a row without its notebook, stops the build before anything runs.
* **The course map** (directive ``course-map``): the notebooks of the table, in its order, each
  with its title and first sentence.
* **Progress.** Each notebook says when its reading starts (executed, or taken from the
  execution cache) and how it ended, with a count, on standard error as it happens (also from
  the parallel readers, whose Sphinx messages arrive only when their batch is done).
* **The course plan** (directive ``course-plan``): notebooks with the time to learn and the
  necessary prerequisites their headers state, in the table of contents's order, and the total
  time (the instructors' page).
* **API pages**: one page per public module of the package, found by walking it.
"""

from __future__ import annotations

import hashlib
import html
import importlib.util
import json
import pkgutil
import re
import shutil
import sys
import time
from pathlib import Path

from docutils import nodes
from docutils.parsers.rst import Directive
from docutils.statemachine import StringList
from sphinx import addnodes
from sphinx.directives.other import TocTree
from sphinx.errors import ExtensionError
from sphinx.util import logging

logger = logging.getLogger(__name__)

WIDGET_VIEW = "application/vnd.jupyter.widget-view+json"
PICTURE_TYPES = ("image/png", "image/jpeg", "image/gif", "image/svg+xml")
#: The key of a live simulator's settings for the browser's engine in its widget view's data
#: (pendulum_lab.widgets.live.BROWSER_SETTINGS).
BROWSER_SETTINGS = "pendulum_lab_browser"
NOTEBOOK_FOLDER = "notebooks"
FINGERPRINT_FILE = ".package-fingerprint"
PROGRESS_FILE = ".notebooks-started"

_IMG_TAG = re.compile(r"<img\b[^>]*>", re.IGNORECASE)
_ALT_VALUE = re.compile(r"""\balt\s*=\s*("([^"]*)"|'([^']*)'|([^\s>"']+))""", re.IGNORECASE)


# ------------------------------------------------------------------------------ alt text
#: The key of a code cell's metadata under which the course keeps what its outputs are:
#: ``{"expect": ["figure", "widget"], "alt": ["what the first picture shows", ...]}``. The
#: browser tests read ``expect``, this extension ``alt``; the student sees neither in the code.
ANNOTATIONS = "pendulum_lab"


def alt_texts(metadata: dict) -> list[str]:
    """The alt texts a code cell's metadata gives its pictures (one for all, or one each).

    >>> alt_texts({"pendulum_lab": {"expect": ["figure"], "alt": ["Energy against time."]}})
    ['Energy against time.']
    >>> alt_texts({"pendulum_lab": {"alt": ["  "]}}), alt_texts({})
    ([], [])
    """
    texts = metadata.get(ANNOTATIONS, {}).get("alt", [])
    if isinstance(texts, str):
        texts = [texts]
    return [text.strip() for text in texts if isinstance(text, str) and text.strip()]


def _img_lacks_alt(tag: str) -> bool:
    match = _ALT_VALUE.search(tag)
    return match is None or not "".join(g or "" for g in match.groups()[1:]).strip()


def html_without_alt(markup: str) -> bool:
    """Whether an HTML fragment has an ``<img>`` with no or blank alt text.

    >>> html_without_alt('<p><img src="a.png" alt="a curve"></p>')
    False
    >>> html_without_alt('<img src="a.png"> <img src="b.png" alt=" ">')
    True
    """
    return any(_img_lacks_alt(tag) for tag in _IMG_TAG.findall(markup))


def _is(element: str):
    return lambda node: isinstance(node, nodes.container) and node.get("nb_element") == element


def _pictures(bundle: nodes.Element) -> list[nodes.Element]:
    """Image nodes and raw HTML nodes with an ``<img>`` inside one output."""
    found = list(bundle.findall(nodes.image))
    found += [
        raw
        for raw in bundle.findall(nodes.raw)
        if "html" in raw.get("format", "").split() and _IMG_TAG.search(raw.astext())
    ]
    return found


def _set_alt(picture: nodes.Element, text: str) -> None:
    if isinstance(picture, nodes.image):
        if not picture.get("alt", "").strip():
            picture["alt"] = text
        return
    attribute = f' alt="{html.escape(text, quote=True)}"'

    def with_alt(match: re.Match) -> str:
        tag = match.group(0)
        if not _img_lacks_alt(tag):
            return tag
        return "<img" + attribute + _ALT_VALUE.sub("", tag[len("<img") :], count=1)

    markup = _IMG_TAG.sub(with_alt, picture.astext())
    picture.replace_self(nodes.raw("", markup, format=picture["format"]))


def _missing_alt(picture: nodes.Element) -> bool:
    if isinstance(picture, nodes.image):
        return not picture.get("alt", "").strip()
    return html_without_alt(picture.astext())


def fill_alt_text(app, doctree: nodes.document) -> None:
    """Give the pictures in each code cell's outputs the cell's alt texts; warn about
    every picture on the page still without alt text."""
    for cell in doctree.findall(_is("cell_code")):
        texts = alt_texts(cell.get("cell_metadata") or {})
        outputs = [
            bundle
            for bundle in cell.findall(_is("mime_bundle"))
            if any(_missing_alt(p) for p in _pictures(bundle))
        ]
        if not outputs or not texts:
            continue
        if len(texts) != 1 and len(texts) != len(outputs):
            logger.warning(
                f"cell {cell.get('cell_index')}: {len(texts)} alt texts for "
                f"{len(outputs)} pictures; give one text for all or one per picture",
                location=cell,
                type="course",
                subtype="alt",
            )
            continue
        for k, bundle in enumerate(outputs):
            for picture in _pictures(bundle):
                _set_alt(picture, texts[0] if len(texts) == 1 else texts[k])

    for picture in _pictures(doctree):
        if _missing_alt(picture):
            cell = next(
                (a for a in _ancestors(picture) if a.get("nb_element") == "cell_code"), None
            )
            where = f"the output of cell {cell.get('cell_index')}" if cell is not None else "page"
            logger.warning(
                f"a picture in {where} has no alt text: give the cell the metadata "
                f'{{"{ANNOTATIONS}": {{"alt": ["what it shows"]}}}} (notebooks) or give the '
                "image alt text (pages)",
                location=picture,
                type="course",
                subtype="alt",
            )


def _ancestors(node: nodes.Node):
    while node.parent is not None:
        node = node.parent
        if isinstance(node, nodes.Element):
            yield node


# ------------------------------------------------------------------------------ widgets
def _live_only_note(text: str) -> nodes.paragraph:
    """A short note that links to the landing page's section on running the course live."""
    link = addnodes.pending_xref(
        "",
        nodes.inline("", "launch the notebook"),
        refdomain="std",
        reftype="ref",
        reftarget="run-live",
        refexplicit=True,
        refwarn=True,
    )
    return nodes.paragraph(
        "",
        "",
        nodes.Text(text + " To use them, "),
        link,
        nodes.Text("."),
        classes=["course-live-note"],
    )


def _widget_models(app, docname: str) -> tuple[dict, dict]:
    """The widget models stored by the execution (id -> model), and the notebook's JS files
    (from which the state is removed: it is not embedded in the page)."""
    try:
        from myst_nb.sphinx_ import NbMetadataCollector
    except ImportError:  # pragma: no cover - MyST-NB is a dependency of the site
        return {}, {}
    js_files = NbMetadataCollector.get_doc_data(app.env).get(docname, {}).get("js_files", {})
    state = js_files.get("ipywidgets_state", (None, {}))[1].get("body", "{}")
    return json.loads(state).get("state", {}), js_files


def _is_progress_bar(model_id: str, models: dict) -> bool:
    """Whether the widget (or a widget inside it) is a progress bar, such as tqdm's."""
    todo, seen = [model_id], set()
    while todo:
        current = todo.pop()
        if current in seen or current not in models:
            continue
        seen.add(current)
        model = models[current]
        if model.get("model_name", "").endswith("ProgressModel"):
            return True
        children = model.get("state", {}).get("children", [])
        todo += [c.removeprefix("IPY_MODEL_") for c in children if isinstance(c, str)]
    return False


def replace_widgets(app, doctree: nodes.document) -> None:
    """Show widget outputs through their static picture; drop progress bars (a finished page
    has nothing in progress); count widgets without a picture; drop the widget state."""
    docname = app.env.docname
    models, js_files = _widget_models(app, docname)
    without_picture = 0
    for bundle in list(doctree.findall(_is("mime_bundle"))):
        kinds = {child.get("mime_type"): child for child in bundle.children}
        if WIDGET_VIEW not in kinds:
            continue
        view = re.search(r'"model_id"\s*:\s*"([^"]+)"', kinds[WIDGET_VIEW].astext())
        if view and _is_progress_bar(view.group(1), models):
            bundle.parent.remove(bundle)
        elif _browser_settings(kinds[WIDGET_VIEW]) and any(k in PICTURE_TYPES for k in kinds):
            _insert_browser_simulator(bundle, _browser_settings(kinds[WIDGET_VIEW]), docname)
        elif any(kind in PICTURE_TYPES for kind in kinds):
            note = _live_only_note(
                "This picture shows the explorer at its default settings; its controls run "
                "only in a live session."
            )
            bundle.parent.insert(bundle.parent.index(bundle) + 1, note)
        else:
            without_picture += 1
            bundle.replace_self(
                _live_only_note("An interactive control is here in the live notebook.")
            )
    expected = app.config.course_widgets_without_picture.get(docname, 0)
    if without_picture != expected:
        logger.warning(
            f"{without_picture} widget output(s) without a static picture, "
            f"course_widgets_without_picture expects {expected}: give the widget an image/png "
            "in its display (see docs/README.md) or update the list in docs/conf.py",
            location=docname,
            type="course",
            subtype="widget",
        )
    # Without a kernel the state would only show controls that do nothing: not embedded.
    for key in [k for k in js_files if k.startswith("ipywidgets")]:
        del js_files[key]


def _browser_settings(view_node) -> dict | None:
    """A live simulator's settings for the browser, from its widget view's data; else None."""
    text = view_node.astext()  # the view's JSON, inside the HTML that shows it
    try:
        view = json.loads(text[text.index("{"):text.rindex("}") + 1])
    except ValueError:
        return None
    return view.get(BROWSER_SETTINGS) if isinstance(view, dict) else None


def _insert_browser_simulator(bundle, config: dict, docname: str) -> None:
    """Put a simulator that integrates in the reader's browser before a live simulator's still
    picture (which stays, for readers without JavaScript and for print); or, if the browser
    cannot run it, the sentence saying why."""
    from pendulum_lab.widgets.browser import simulator_html

    parent, place = bundle.parent, bundle.parent.index(bundle)
    if "refusal" in config:
        parent.insert(place + 1, _live_only_note(
            f"The simulator cannot run in this page ({config['refusal']}); the picture shows "
            "its first run."))
        return
    engine = ("../" * docname.count("/") or "./") + "_static/browser/engine.js"
    parent.insert(place, nodes.raw("", simulator_html(config, engine).replace(
        '<div class="plab-still"></div>\n', ""), format="html"))
    parent.insert(place + 1, nodes.paragraph(
        "", "Above, this run integrated in your browser, without a kernel: drag a bob, pick a "
        "method and a step. Below, the same run as the kernel drew it."))


# ------------------------------------------------------------------------------ launch buttons
def configure_launch(app, config) -> None:
    """Turn ``course_repository_url`` into the theme's launch settings (or none at all)."""
    url = config.course_repository_url.strip().rstrip("/")
    options = dict(config.html_theme_options)
    for key in ("repository_url", "launch_buttons", "path_to_docs", "repository_branch"):
        options.pop(key, None)
    if url:
        if not re.match(r"https://[^/\s]+/[^/\s]+/[^/\s]+$", url):
            raise ValueError(
                "`course_repository_url` must look like https://HOST/OWNER/REPOSITORY, "
                f"got {config.course_repository_url!r}"
            )
        buttons = {"binderhub_url": "https://mybinder.org", "notebook_interface": "jupyterlab"}
        if config.course_jupyterhub_url.strip():
            buttons["jupyterhub_url"] = config.course_jupyterhub_url.strip().rstrip("/")
        options.update(
            repository_url=url,
            repository_branch=config.course_repository_branch,
            path_to_docs="docs",
            launch_buttons=buttons,
        )
        app.tags.add("launch")
    config.html_theme_options = options


# ------------------------------------------------------------------------------ package changes
def package_fingerprint() -> str:
    """SHA-256 over the names and contents of the installed ``pendulum_lab`` source files."""
    spec = importlib.util.find_spec("pendulum_lab")
    if spec is None or not spec.submodule_search_locations:
        return "pendulum_lab not importable"
    digest = hashlib.sha256()
    for root in spec.submodule_search_locations:
        for path in sorted(Path(root).rglob("*.py")):
            digest.update(str(path.relative_to(root)).encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()


def empty_cache_if_package_changed(build_dir: Path, cache: Path) -> bool:
    """Empty the execution cache ``cache`` when the package's source changed since the
    fingerprint kept in ``build_dir`` was written, and keep the current one there. Returns
    whether the fingerprint changed (True on a first build too)."""
    stamp = build_dir / FINGERPRINT_FILE
    current = package_fingerprint()
    previous = stamp.read_text(encoding="utf-8") if stamp.exists() else None
    if previous is not None and previous != current:
        logger.info("pendulum_lab changed since the last build: every notebook runs again")
        shutil.rmtree(cache, ignore_errors=True)
    stamp.parent.mkdir(parents=True, exist_ok=True)
    stamp.write_text(current, encoding="utf-8")
    return previous != current


def check_package(app) -> None:
    """Empty the execution cache when the package's source changed since it was filled."""
    build_dir = Path(app.outdir).parent
    cache = Path(app.config.nb_execution_cache_path or build_dir / ".jupyter_cache")
    app.env.course_package_changed = empty_cache_if_package_changed(build_dir, cache)
    app.course_build_started = time.time()


def public_modules(package_name: str) -> list[str]:
    """The package and every module below it whose dotted name has no part starting with
    ``_``, in walking order (a package before its modules)."""
    package = importlib.import_module(package_name)
    found = [package_name]
    for info in pkgutil.walk_packages(package.__path__, package_name + "."):
        if not any(part.startswith("_") for part in info.name.split(".")):
            found.append(info.name)
    return found


def _first_line(module) -> str:
    doc = (module.__doc__ or "").strip()
    return doc.splitlines()[0].rstrip(".") if doc else ""


def write_api_pages(app) -> None:
    """One reST page per public module of ``course_api_package`` in ``course_api_folder``.

    A module's page is ``automodule`` with its members (its ``__all__``); a package's page is
    its docstring and a list of its modules. Written anew on every build, so a removed module
    leaves no orphan page. The modules are imported by name: ``pendulum_lab.simulate`` is the
    module even though the package's attribute ``simulate`` is the function (autosummary's
    lookup takes the attribute, and documented the function instead of the module).
    """
    if not app.config.course_api_package:
        return  # a site without an API reference (the tests' throwaway sites)
    folder = Path(app.srcdir) / app.config.course_api_folder
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    names = public_modules(app.config.course_api_package)
    for name in names:
        children = [other for other in names if other.rpartition(".")[0] == name]
        title = name.replace("_", "\\_")
        lines = [title, "=" * len(title), "", f".. automodule:: {name}"]
        if children:
            lines += ["", ".. rubric:: Modules", ""]
            for child in children:
                summary = _first_line(importlib.import_module(child))
                lines.append(f"* :mod:`{child}`" + (f" -- {summary}" if summary else ""))
            lines += ["", ".. toctree::", "   :hidden:", ""] + [f"   {c}" for c in children]
        else:
            lines += ["   :members:", "   :show-inheritance:"]
        (folder / f"{name}.rst").write_text("\n".join(lines) + "\n", encoding="utf-8")


def write_execution_report(app, exception) -> None:
    """``execution.json`` beside the HTML folder: per notebook, whether this build ran it or
    took it from the cache, and its run time (what the build's speed depends on)."""
    if exception is not None or app.builder.format != "html":
        return
    from myst_nb.sphinx_ import NbMetadataCollector

    started = getattr(app, "course_build_started", 0.0)
    report = {}
    for docname in sorted(app.env.found_docs):
        data = NbMetadataCollector.get_doc_data(app.env).get(docname, {}).get("exec_data")
        if data:
            report[docname] = {
                "ran_in_this_build": bool(data.get("mtime") and data["mtime"] >= started),
                "seconds": data.get("runtime"),
            }
    (Path(app.outdir).parent / "execution.json").write_text(json.dumps(report, indent=1) + "\n",
                                                                  encoding="utf-8")


def outdated_notebooks(app, env, added, changed, removed):
    if not getattr(env, "course_package_changed", False):
        return []
    return [doc for doc in env.found_docs if env.doc2path(doc).suffix == ".ipynb"]


# ------------------------------------------------------------------------------ contents
#: A row of the table of contents: ``| `00_start_here` | what it is about |``.
_CONTENTS_ROW = re.compile(r"^\|\s*`(\d\d[a-z]?_\w+)`\s*\|", re.MULTILINE)


def table_of_contents(path: Path) -> list[str]:
    """The notebook names (without ``.ipynb``) that the table in the notebook ``path`` lists,
    in its order: the rows of its Markdown cells whose first column is a name in backticks.

    >>> import json, tempfile
    >>> cell = {"cell_type": "markdown", "source": "| `00_a` | first |\\n| `01b_c` | next |"}
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "00_a.ipynb"
    ...     _ = path.write_text(json.dumps({"cells": [cell]}))
    ...     table_of_contents(path)
    ['00_a', '01b_c']
    """
    cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
    names = []
    for cell in cells:
        if cell["cell_type"] == "markdown":
            names += _CONTENTS_ROW.findall("".join(cell["source"]))
    return list(dict.fromkeys(names))


def _contents_path(app) -> Path | None:
    """The notebook holding the table of contents, or None for a site without the course."""
    name = app.config.course_table_of_contents.strip()
    return Path(app.srcdir) / name if name else None


def course_notebooks(app) -> list[str]:
    """The course's notebooks as documents (``notebooks/NAME``), in the table's order."""
    path = _contents_path(app)
    if path is None or not path.is_file():
        return []
    return [f"{NOTEBOOK_FOLDER}/{name}" for name in table_of_contents(path)]


def check_contents(app) -> None:
    """Stop the build if ``notebooks/`` and the table of contents disagree (before any notebook
    runs): an unlisted notebook would be published as a page nobody navigates to."""
    folder = Path(app.srcdir) / NOTEBOOK_FOLDER
    path = _contents_path(app)
    if path is None or not folder.is_dir():
        return
    if not path.is_file():
        raise ExtensionError(f"the course's table of contents {path} does not exist: set "
                             "course_table_of_contents in conf.py to the notebook that has it")
    listed = table_of_contents(path)
    present = sorted(p.stem for p in folder.glob("*.ipynb"))
    problems = []
    unlisted = [name for name in present if name not in listed]
    if unlisted:
        problems.append(f"{', '.join(n + '.ipynb' for n in unlisted)} in {NOTEBOOK_FOLDER}/ "
                        f"{'is' if len(unlisted) == 1 else 'are'} not in the course's table "
                        f"of contents ({path.name}): add a row for each notebook of the course "
                        "there, or move the others out of the folder")
    missing = [name for name in listed if name not in present]
    if missing:
        problems.append(f"the table of contents ({path.name}) lists {', '.join(missing)}, "
                        f"which {NOTEBOOK_FOLDER}/ does not have")
    if problems:
        raise ExtensionError("; ".join(problems))


class CourseToctree(TocTree):
    """The ``toctree`` of the course's notebooks, in the order of its table of contents.

    Takes the options of ``toctree`` (``:hidden:``, ``:caption:``); the entries come from the
    table (:func:`course_notebooks`), never from the directive's content.
    """

    has_content = False

    def run(self):
        env = self.state.document.settings.env
        path = _contents_path(env.app)
        if path is not None and path.is_file():
            env.note_dependency(str(path))
        self.content = StringList([f"/{doc}" for doc in course_notebooks(env.app)])
        return super().run()


# ------------------------------------------------------------------------------ progress
#: When this process started reading each notebook (a parallel reader reads several in turn).
_READING_SINCE: dict[str, float] = {}


def _notebook_documents(app) -> list[str]:
    return sorted(doc for doc in app.env.found_docs if app.env.doc2path(doc).suffix == ".ipynb")


def _say(text: str) -> None:
    # Straight to standard error: Sphinx holds a parallel reader's messages until its batch
    # of documents is done, which is what made a long build silent.
    sys.stderr.write(text + "\n")
    sys.stderr.flush()


def reset_progress(app) -> None:
    """Start the count of notebooks read in this build."""
    (Path(app.outdir).parent / PROGRESS_FILE).unlink(missing_ok=True)


def announce_notebook(app, docname: str, source: list) -> None:
    """Say which notebook is read now, and how many have started (readers run in parallel)."""
    if app.env.doc2path(docname).suffix != ".ipynb":
        return
    log = Path(app.outdir).parent / PROGRESS_FILE
    log.parent.mkdir(parents=True, exist_ok=True)
    with open(log, "a", encoding="utf-8") as handle:  # one short append: atomic
        handle.write(docname + "\n")
    started = len(log.read_text(encoding="utf-8").splitlines())
    total = len(_notebook_documents(app))
    _READING_SINCE[docname] = time.monotonic()
    _say(f"[{started}/{total}] {docname}: executing (unless the execution cache has it)…")


def notebook_read(app, doctree) -> None:
    """Say how the notebook's reading ended: executed in so many seconds, or from the cache."""
    docname = app.env.docname
    if app.env.doc2path(docname).suffix != ".ipynb":
        return
    from myst_nb.sphinx_ import NbMetadataCollector

    data = NbMetadataCollector.get_doc_data(app.env).get(docname, {}).get("exec_data") or {}
    ran = bool(data.get("mtime") and data["mtime"] >= getattr(app, "course_build_started", 0))
    seconds = time.monotonic() - _READING_SINCE.pop(docname, time.monotonic())
    how = f"executed in {data.get('runtime') or 0:.1f} s" if ran else "taken from the cache"
    _say(f"      {docname}: {how} ({seconds:.1f} s in all)")


# ------------------------------------------------------------------------------ course map
def _first_sentence(text: str) -> str:
    text = " ".join(text.split())
    match = re.match(r"(.+?[.!?])(\s|$)", text)
    return match.group(1) if match else text


def notebook_summary(path: Path) -> tuple[str, str]:
    """Title (the first ``# `` heading) and first sentence after it of a notebook."""
    cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
    title, sentence = path.stem, ""
    for cell in cells:
        if cell["cell_type"] != "markdown":
            continue
        lines = "".join(cell["source"]).splitlines()
        for k, line in enumerate(lines):
            if line.startswith("# "):
                title = line[2:].strip()
                rest = "\n".join(lines[k + 1 :]).strip().split("\n\n")[0]
                sentence = _first_sentence(rest)
                return title, sentence
    return title, sentence


class CourseMap(Directive):
    """A table of the notebooks in reading order (the table of contents's): number, title
    (linked), first sentence."""

    has_content = False

    def run(self):
        env = self.state.document.settings.env
        table = nodes.table(classes=["course-map"])
        group = nodes.tgroup(cols=2)
        table += group
        group += nodes.colspec(colwidth=8)
        group += nodes.colspec(colwidth=92)
        head = nodes.thead()
        group += head
        head += self._row(nodes.Text("notebook"), nodes.Text("what it is about"))
        body = nodes.tbody()
        group += body
        for document in course_notebooks(env.app):
            path = Path(env.srcdir) / f"{document}.ipynb"
            env.note_dependency(str(path))
            title, sentence = notebook_summary(path)
            link = addnodes.pending_xref(
                "",
                nodes.inline("", title),
                refdomain="std",
                reftype="doc",
                reftarget=f"/{NOTEBOOK_FOLDER}/{path.stem}",
                refexplicit=True,
                refwarn=True,
            )
            number = path.stem.split("_", 1)[0]
            about = nodes.paragraph("", "", nodes.strong("", "", link))
            if sentence:
                # The sentence is Markdown (it may hold $math$): parse it like the page's text.
                parsed, messages = self.state.inline_text(sentence, self.lineno)
                about += [nodes.Text(" "), *parsed, *messages]
            body += self._row(nodes.Text(number), about)
        return [table]

    @staticmethod
    def _row(*cells):
        row = nodes.row()
        for cell in cells:
            entry = nodes.entry()
            entry += cell if isinstance(cell, nodes.paragraph) else nodes.paragraph("", "", cell)
            row += entry
        return row


# ------------------------------------------------------------------------------ course plan
_TIME_TO_LEARN = re.compile(r"\*\*Time to learn:?\*\*:?\s*([^.\n]+)")
_MINUTES = re.compile(r"(\d+)\s*minutes")


def notebook_plan(path: Path) -> tuple[str | None, list[str]]:
    """A notebook's stated time to learn and its necessary prerequisites (from its header).

    Reads the ``**Time to learn:**`` line and the rows of the ``## Prerequisites`` table whose
    importance is "Necessary" (concept, with the notes column in brackets when it has one).
    """
    cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
    time_to_learn, needs = None, []
    for cell in cells[:6]:
        if cell["cell_type"] != "markdown":
            continue
        text = "".join(cell["source"])
        match = _TIME_TO_LEARN.search(text)
        if match and time_to_learn is None:
            time_to_learn = match.group(1).strip()
        if "## Prerequisites" not in text:
            continue
        for line in text.split("## Prerequisites", 1)[1].splitlines():
            columns = [column.strip() for column in line.strip().strip("|").split("|")]
            if line.strip().startswith("|") and len(columns) >= 2 and columns[1] == "Necessary":
                notes = columns[2] if len(columns) > 2 else ""
                needs.append(f"{columns[0]} ({notes})" if notes else columns[0])
    return time_to_learn, needs


class CoursePlan(Directive):
    """Notebooks with their time to learn and necessary prerequisites, read from their headers,
    in the order of the table of contents.

    Option ``notebooks``: the notebooks to list, by the start of their file names
    (``:notebooks: 00 01 01a``); all of them by default. Under the table, the sum of the times
    that are stated in minutes. A notebook that states no time to learn is a build warning.
    """

    has_content = False
    option_spec = {"notebooks": str}

    def run(self):
        env = self.state.document.settings.env
        folder = Path(env.srcdir) / NOTEBOOK_FOLDER
        # The table of contents's order (the build has checked it lists every notebook).
        paths = [Path(env.srcdir) / f"{doc}.ipynb" for doc in course_notebooks(env.app)]
        paths = paths or sorted(folder.glob("*.ipynb"))
        if "notebooks" in self.options:
            wanted = self.options["notebooks"].split()
            paths = [path for path in paths if path.stem.split("_", 1)[0] in wanted]
            missing = set(wanted) - {path.stem.split("_", 1)[0] for path in paths}
            if missing:
                logger.warning(f"course-plan: no notebook numbered {sorted(missing)}",
                               location=(env.docname, self.lineno))
        table = nodes.table(classes=["course-plan"])
        group = nodes.tgroup(cols=3)
        table += group
        for width in (30, 15, 55):
            group += nodes.colspec(colwidth=width)
        head = nodes.thead()
        group += head
        head += CourseMap._row(nodes.Text("notebook"), nodes.Text("time to learn"),
                               nodes.Text("needs (necessary prerequisites)"))
        body = nodes.tbody()
        group += body
        minutes = 0
        for path in paths:
            env.note_dependency(str(path))
            title, _ = notebook_summary(path)
            time_to_learn, needs = notebook_plan(path)
            if time_to_learn is None:
                logger.warning(f"course-plan: {path.name} states no time to learn",
                               location=(env.docname, self.lineno))
            minutes += sum(int(m) for m in _MINUTES.findall(time_to_learn or ""))
            link = addnodes.pending_xref(
                "", nodes.inline("", f"{path.stem.split('_', 1)[0]} {title}"), refdomain="std",
                reftype="doc", reftarget=f"/{NOTEBOOK_FOLDER}/{path.stem}", refexplicit=True,
                refwarn=True)
            needed = nodes.paragraph()
            parsed, messages = self.state.inline_text("; ".join(needs) or "-", self.lineno)
            needed += [*parsed, *messages]
            body += CourseMap._row(nodes.paragraph("", "", link),
                                   nodes.Text(time_to_learn or "-"), needed)
        total = nodes.paragraph(
            "", f"Time to learn, in all: {minutes} minutes ({minutes / 60:.1f} hours) over "
                f"{len(paths)} notebooks.")
        return [table, total]


class LiveSimulator(Directive):
    """``live-simulator``: a simulator that integrates in the reader's browser, no kernel
    (``pendulum_lab.widgets.browser``). Options: ``model`` (a stem of ``SHIPPED_MODELS``),
    ``method``, ``dt``, ``t_end``. The content is the still picture kept for readers without
    JavaScript and for print. A model the browser cannot run leaves the still picture with a
    sentence saying why."""

    has_content = True
    option_spec = {"model": str, "method": str, "dt": float, "t_end": float}

    def run(self):
        from pendulum_lab.widgets.browser import (
            SHIPPED_MODELS,
            browser_config,
            browser_refusal,
            simulator_html,
        )

        env = self.state.document.settings.env
        stem = self.options.get("model", "double_pendulum")
        if stem not in SHIPPED_MODELS:
            raise self.error(f"`model` must be one of {list(SHIPPED_MODELS)}, got {stem!r}")
        model = SHIPPED_MODELS[stem]()
        still = nodes.container(classes=["plab-still"])
        self.state.nested_parse(self.content, self.content_offset, still)
        reason = browser_refusal(model)
        if reason is not None:
            return [nodes.paragraph(text=f"The live simulator cannot run here: {reason}."), still]
        config = browser_config(model, method=self.options.get("method", "glrk4"),
                                dt=self.options.get("dt", 0.01),
                                t_end=self.options.get("t_end", 20.0))
        engine = ("../" * env.docname.count("/") or "./") + "_static/browser/engine.js"
        live = simulator_html(config, engine).replace(
            '<div class="plab-still"></div>\n</div>\n', "</div>\n")
        return [nodes.raw("", live, format="html"), still]


def setup(app):
    app.add_config_value("course_repository_url", "", "html", types=(str,))
    app.add_config_value("course_jupyterhub_url", "", "html", types=(str,))
    app.add_config_value("course_repository_branch", "main", "html", types=(str,))
    app.add_config_value("course_widgets_without_picture", {}, "env", types=(dict,))
    app.add_config_value("course_api_folder", "reference", "env", types=(str,))
    app.add_config_value("course_api_package", "pendulum_lab", "env", types=(str,))
    app.add_config_value("course_table_of_contents", "", "env", types=(str,))
    app.connect("config-inited", configure_launch, priority=100)
    app.connect("builder-inited", check_contents)
    app.connect("builder-inited", reset_progress)
    app.connect("builder-inited", check_package)
    app.connect("builder-inited", write_api_pages)
    app.connect("env-get-outdated", outdated_notebooks)
    app.connect("doctree-read", replace_widgets)
    app.connect("doctree-read", fill_alt_text)
    app.connect("source-read", announce_notebook)
    app.connect("doctree-read", notebook_read)
    app.connect("build-finished", write_execution_report)
    app.add_directive("course-map", CourseMap)
    app.add_directive("course-toctree", CourseToctree)
    app.add_directive("course-plan", CoursePlan)
    app.add_directive("live-simulator", LiveSimulator)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
