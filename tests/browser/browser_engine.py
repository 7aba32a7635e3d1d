"""Harness of the kernel-free simulator's tests: the package's static folder served locally and
one Chromium page that imports the generated models and the methods (ES modules).

Used by ``test_browser_engine.py`` (and the benchmark of steps per second); see README.md.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

from lab_harness import (
    CHROMIUM_ARGS,
    browser_unavailable_reason,
    chromium_path,
    serve,
    skip_or_fail,
)

from pendulum_lab.widgets.browser import BROWSER_FOLDER, SHIPPED_MODELS

STATIC = BROWSER_FOLDER.parent


@contextlib.contextmanager
def engine_page(folder: Path = STATIC, tmp: Path | None = None):
    """A Chromium page on a local server of ``folder`` (the package's ``static``): yields
    ``(page, base_url, requests)``; ``requests`` records every URL the page asked for."""
    reason = browser_unavailable_reason()
    if reason is not None:
        skip_or_fail(reason)
    from playwright.sync_api import sync_playwright

    with serve(folder) as base, sync_playwright() as playwright:
        env = dict(os.environ)
        if tmp is not None:  # Chromium's caches in a temporary folder, not the home folder
            env |= {"XDG_CONFIG_HOME": str(tmp), "XDG_CACHE_HOME": str(tmp)}
        browser = playwright.chromium.launch(executable_path=chromium_path(), args=CHROMIUM_ARGS,
                                             env=env)
        try:
            page = browser.new_page(viewport={"width": 1000, "height": 800})
            requests: list[str] = []
            page.on("request", lambda request: requests.append(request.url))
            errors: list[str] = []
            page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
            page.on("pageerror", lambda e: errors.append(str(e)))
            # a browser asks every host for its icon; the package has none
            page.route("**/favicon.ico", lambda route: route.fulfill(status=204))
            page.goto(f"{base}/browser/")  # a directory listing: an origin to import from
            page.errors = errors
            yield page, base, requests
        finally:
            browser.close()


#: JavaScript: import a model (by URL, or from its text) and the methods.
IMPORTS = """
  const load = async (model, methods) => {
    const url = model.startsWith("http") ? model
      : "data:text/javascript," + encodeURIComponent(model);
    return [await import(url), await import(methods)];
  };
"""

#: JavaScript: one step of each ``[t, q, p]`` in ``states``.
STEPS = """
async ({model, methods, method, params, states, h, tableau}) => {""" + IMPORTS + """
  const [module, m] = await load(model, methods);
  const field = m.makeField(module, params);
  return states.map(([t, q, p]) => {
    const args = [field, t, Float64Array.from(q), Float64Array.from(p), h, null];
    if (tableau) args.push(tableau);
    return m.METHODS[method].step(...args).map((x) => Array.from(x));
  });
}
"""

#: JavaScript: the generated functions at each ``[t, q, p, omega]`` in ``states``.
FIELD = """
async ({model, methods, params, states}) => {""" + IMPORTS + """
  const [module] = await load(model, methods);
  const n = module.COORDINATES;
  return states.map(([t, q, p, omega]) => {
    const [dq, dp, momenta, energies] = [n, n, n, 2].map((k) => new Float64Array(k));
    const places = new Float64Array((module.DIMENSIONS || 2) * module.POINTS);
    module.hamilton(t, q, p, params, dq, dp);
    module.momenta(t, q, omega, params, momenta);
    module.energies(t, q, omega, params, energies);
    module.positions(t, q, params, places);
    return [dq, dp, momenta, energies, places].map((x) => Array.from(x));
  });
}
"""

#: JavaScript: a run of the engine (``engine.simulate``): energies at every step.
RUN = """
async ({engine, model, params, method, theta0, omega0, tEnd, dt, tableau}) => {
  const module = await import(model.startsWith("http") ? model
    : "data:text/javascript," + encodeURIComponent(model));
  const e = await import(engine);
  if (tableau) {  // a wrong weight: the method's step with another tableau
    const m = await import(engine.replace("engine.js", "methods/index.js"));
    const original = m.METHODS[method].step;
    m.METHODS[method].step = (f, t, q, p, h, memory) => original(f, t, q, p, h, memory, tableau);
    try { return run(e, module); } finally { m.METHODS[method].step = original; }
  }
  return run(e, module);
  function run(e, module) {
    const started = performance.now();
    const r = e.simulate(module, params, method, theta0, omega0, tEnd, dt);
    const seconds = (performance.now() - started) / 1000;
    const energy = Array.from(r.kinetic, (k, i) => k + r.potential[i]);
    return {energy, steps: r.steps, kept: r.kept, seconds, theta: Array.from(r.theta.slice(-r.n))};
  }
}
"""


def shipped_model_url(base: str, stem: str) -> str:
    return f"{base}/browser/models/{stem}.js"


def shipped_models() -> dict:
    return {stem: factory() for stem, factory in SHIPPED_MODELS.items()}
