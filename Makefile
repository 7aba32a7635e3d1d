# The contributors' two commands of the README (students use open_course.py, which needs no make):
#   make lab    create the environment if needed and open JupyterLab on the course
#               (options for JupyterLab: make lab ARGS="--no-browser --port 8899")
#   make test   create or update the environment and run the whole test suite, and the unit
#               suite once more with the oldest supported versions (make test-floors)
# and the course website:
#   make docs   build the site into docs/_build/html (notebooks executed, with a cache)
# and the instructor's kit:
#   make assignments   build every graded assignment into dist/assignments/<name>/
# The main environment runs on the newest supported Python found here, the floor environment
# on the oldest: the two ends of the support window (tools/find_python.py reads the versions
# from pyproject.toml's classifiers; found once per use, and only when an environment is made).
# Either can be given: make test PYTHON=python3.12 FLOORS_PYTHON=/usr/bin/python3.11
PYTHON ?= $(shell python3 tools/find_python.py newest || echo python3)
FLOORS_PYTHON ?= $(shell python3 tools/find_python.py oldest || echo python3)
VENV ?= .venv
BIN := $(VENV)/bin
# Passed to `pendulum-lab` by `make lab` (its options, then JupyterLab's after `--`).
ARGS ?=

# What each command installs on top of the package (extras of pyproject.toml): a student's
# `make lab` needs the package and JupyterLab only; the others add what they use.
extras_lab := lab
extras_test := lab,test,docs,bench,assignments
extras_docs := docs
extras_bench := bench
extras_assignments := lab,assignments
# The environment with every dependency at its floor in pyproject.toml (tools/floor_pins.py).
FLOORS_VENV ?= .venv-floors
FLOORS_BIN := $(FLOORS_VENV)/bin
# MathJax for the website, served from the site itself (from the npm registry, checked by npm).
MATHJAX_VERSION := 3.2.2
MATHJAX := docs/_vendor/mathjax/tex-mml-chtml.js

# The proxy of the JupyterHub that tests/hub starts (from the npm registry, as MathJax is),
# installed into a git-ignored folder of the project.
HUB_PROXY_VERSION := 5.3.0
HUB_PROXY := test-artifacts/hub-proxy/node_modules/.bin/configurable-http-proxy

.PHONY: lab test test-floors check lint bench docs mathjax assignments clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --upgrade pip

# One stamp per set of extras, made again when pyproject.toml changes.
$(VENV)/.installed-%: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install -e ".[$(extras_$*)]"
	touch $@

# The floors pinned, the test tools at their newest (the lab extra: the command line's tests).
$(FLOORS_BIN)/.installed: pyproject.toml tools/floor_pins.py
	$(FLOORS_PYTHON) -m venv $(FLOORS_VENV)
	$(FLOORS_BIN)/python -m pip install --upgrade pip
	$(FLOORS_BIN)/python tools/floor_pins.py > $(FLOORS_VENV)/floors.txt
	$(FLOORS_BIN)/python -m pip install -e ".[lab,test]" -c $(FLOORS_VENV)/floors.txt
	touch $@

# The browser build of MathJax (es5/), without the SVG output and the other combined files.
$(MATHJAX):
	rm -rf docs/_vendor/mathjax docs/_vendor/package
	mkdir -p docs/_vendor
	cd docs/_vendor && npm pack --silent mathjax@$(MATHJAX_VERSION) >/dev/null \
		&& tar xzf mathjax-$(MATHJAX_VERSION).tgz && rm mathjax-$(MATHJAX_VERSION).tgz
	mv docs/_vendor/package/es5 docs/_vendor/mathjax && rm -rf docs/_vendor/package
	cd docs/_vendor/mathjax && rm -rf output/svg output/svg.js latest.js node-main.js \
		tex-svg*.js tex-chtml*.js tex-mml-svg.js mml-*.js
	test -f $@

mathjax: $(MATHJAX)

$(HUB_PROXY):
	npm install --silent --no-audit --no-fund --prefix test-artifacts/hub-proxy \
		configurable-http-proxy@$(HUB_PROXY_VERSION)
	test -x $@

docs: $(VENV)/.installed-docs $(MATHJAX)
	$(BIN)/python tools/build_site.py

# otter assign on every master notebook of assignments/, then its solutions graded (offline).
assignments: $(VENV)/.installed-assignments
	$(BIN)/python tools/assignments.py build

lab: $(VENV)/.installed-lab
	$(BIN)/pendulum-lab $(ARGS)

# A queue of pytest jobs, two at a time, longest first (tools/run_tests.py; --serial for one):
# the browser and the website, the core, the environments (Binder, the installs, the hub); the
# floors beside them from the start, at the lowest priority.
test: $(VENV)/.installed-test $(FLOORS_BIN)/.installed $(MATHJAX) $(HUB_PROXY)
	$(BIN)/ruff check .
	$(BIN)/python tools/run_tests.py --floors $(FLOORS_BIN)/python

# The unit suite (as make check) with the oldest supported versions: the floors of pyproject.toml.
test-floors: $(FLOORS_BIN)/.installed
	$(FLOORS_BIN)/python tools/run_tests.py --floors-only

# The inner loop of day-to-day work: unit, property and symbolic tests and the doctests, without
# the notebooks, the browser, the website, Binder, the installs or the graded assignments
# (docs/testing.md).
check: $(VENV)/.installed-test
	$(BIN)/ruff check .
	$(BIN)/python -m pytest src tests --ignore=tests/browser --ignore=tests/site --ignore=tests/binder \
		--ignore=tests/install --ignore=tests/assignments --ignore=tests/hub

bench: $(VENV)/.installed-bench
	$(BIN)/python benchmarks/run.py

clean:
	rm -rf $(VENV) $(FLOORS_VENV) .venv-floors-caches .pytest_cache docs/_build docs/_vendor \
		docs/reference
