"""Sphinx configuration of the course website (`make docs`; see docs/README.md).

The site is built with Sphinx, MyST-NB and sphinx-book-theme, fully offline: MathJax is served
from the local copy that `make docs` unpacks into ``docs/_vendor/`` (from the npm registry), the
theme ships its fonts and scripts, and no intersphinx inventory is fetched. What is specific to
this course (launch buttons from one setting, alt text from the cells' metadata, static
pictures instead of live widgets, the course map, re-execution when the package changes) lives
in ``docs/_ext/course_site.py``.
"""

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))

# ------------------------------------------------------------------------------------------
# Launch buttons: the one setting.
#
# The public address of the course's repository, for example
# "https://github.com/OWNER/pendulum_lab". While it is empty, no Binder or JupyterHub button and
# no Binder link is rendered anywhere (there is nothing to launch). Once it is set, every
# notebook page gets a Binder button opening that notebook in JupyterLab, and the landing page
# gets the Binder link. Set it here, or for one build with
#   .venv/bin/python tools/build_site.py -D course_repository_url=https://github.com/OWNER/REPO
course_repository_url = ""
# Optional: a JupyterHub that can clone the repository (adds a JupyterHub button).
course_jupyterhub_url = ""
# Branch that Binder builds.
course_repository_branch = "main"
# Widget outputs that have no static picture yet, per page (see docs/README.md, "Static
# pictures"). The build fails if a page has a different number of them, so this list must shrink
# as explorers gain their picture, and nothing new can slip in.
course_widgets_without_picture = {
    "notebooks/00_start_here": 1,  # the warm-up button (nothing to picture)
}
# ------------------------------------------------------------------------------------------

project = "pendulum_lab"
author = "the pendulum_lab authors"
copyright = "2026, " + author

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "numpydoc",
    "course_site",
]

root_doc = "index"

# The course's table of contents: the notebook whose table "What the course covers" lists every
# notebook in reading order. The site's navigation and course map follow it, and a notebook in
# notebooks/ that it does not list stops the build (see docs/README.md).
course_table_of_contents = "notebooks/00_start_here.ipynb"

exclude_patterns = ["_build", "_vendor", "README.md", "**/.ipynb_checkpoints", "Thumbs.db"]

# ---- notebooks: executed with a cache, so an unchanged notebook is not re-run ----------------
nb_execution_mode = "cache"
nb_execution_timeout = 900  # seconds per cell
nb_execution_raise_on_error = True  # a cell that raises fails the build
nb_execution_show_tb = True
# No widget manager from a CDN; the widget state is dropped too (course_site.py), since its
# controls would do nothing without a kernel.
nb_ipywidgets_js = {}
# In HTML a widget view is never chosen: the static picture (image/png) in the same output is.
nb_mime_priority_overrides = [("html", "application/vnd.jupyter.widget-view+json", None)]
nb_merge_streams = True

myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence"]
myst_heading_anchors = 3

# ---- API reference -----------------------------------------------------------------------------
# One page per public module of this package, written into this folder by course_site.py
# (git-ignored, written anew every build); api.md links the package's page.
course_api_package = "pendulum_lab"
course_api_folder = "reference"
autodoc_typehints = "none"  # numpydoc sections carry the types
autodoc_member_order = "bysource"
numpydoc_show_class_members = False
numpydoc_xref_param_type = False
# A References section may list works that the text does not cite by label.
suppress_warnings = ["ref.citation"]

# ---- mathematics from the local copy (docs/_vendor/mathjax, made by `make docs`) -------------
mathjax_path = "mathjax/tex-mml-chtml.js"

# ---- HTML ------------------------------------------------------------------------------------
html_theme = "sphinx_book_theme"
html_title = "pendulum_lab"
# The package's browser modules (the simulator, its kernel-free engine, the generated models)
# go into _static as they ship, for the live simulators of the "try it" page.
html_static_path = ["_static", "_vendor", "../src/pendulum_lab/widgets/static"]
html_css_files = ["course.css", "live.css"]
html_favicon = "_static/favicon.svg"  # also spares the browser a request for /favicon.ico
html_context = {"default_mode": "auto"}  # light or dark as the reader's system prefers
html_last_updated_fmt = None
html_theme_options = {
    "home_page_in_toc": True,
    "use_download_button": True,
    "use_fullscreen_button": False,
    "show_toc_level": 2,
}
