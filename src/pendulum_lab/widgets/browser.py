"""The live simulator without a kernel: what a static page needs to integrate in the browser.

In JupyterLab the live simulator (:mod:`pendulum_lab.widgets.live`) computes in the kernel.
On a page without a kernel (the course website) the same drawing (``static/simulator.js``)
is driven by ``static/browser/engine.js``, which integrates in the browser with the model's
equations printed as an ES module (:mod:`pendulum_lab.codegen.browser`) and the course's
methods written as ES modules (``static/browser/methods/``, mirroring
:mod:`pendulum_lab.integrators.reference`).

The modules of the models the course shows are shipped in ``static/browser/models/``
(:data:`SHIPPED_MODELS`; a test checks that they equal what the generator makes now; after a
change to the generator or the symbolic layer, ``python -m pendulum_lab.widgets.browser``
writes them again). Any other model's module is made on demand (:func:`model_module`).

:func:`browser_config` is what a page hands to ``engine.js``'s ``mount``; :func:`browser_refusal`
says why a model cannot run in the browser (then the page keeps its still picture, with that
sentence).
"""

from __future__ import annotations

import html
import json
import math
import sys
from pathlib import Path

import numpy as np

from ..codegen.browser import BrowserModule, browser_module
from ..driver.simulate import hamiltonian_field
from ..integrators.registry import MAIN_METHODS, get_method, unsuitability
from ..model import (
    PendulumModel,
    double_pendulum,
    driven_pendulum,
    elastic_pendulum,
    n_pendulum,
    require_model,
    simple_pendulum,
)
from .channel import BROWSER_SETTINGS, STATIC, figure_message
from .controls import SPEEDS, energy_changers, energy_is_conserved, forces_text

__all__ = [
    "BROWSER_FOLDER",
    "MAX_BROWSER_COORDINATES",
    "SHIPPED_MODELS",
    "browser_config",
    "browser_refusal",
    "model_module",
    "shipped_sources",
    "run_settings",
    "simulator_html",
    "stale_shipped",
    "with_run_settings",
    "write_shipped",
]

#: The engine, the methods and the shipped models.
BROWSER_FOLDER = STATIC / "browser"
#: The models whose modules ship with the package, by file stem.
SHIPPED_MODELS = {
    "simple_pendulum": simple_pendulum,
    "double_pendulum": double_pendulum,
    "triple_pendulum": lambda: n_pendulum(3),
    "driven_pendulum": driven_pendulum,
    "elastic_pendulum": elastic_pendulum,
}
#: Longer chains are not run in the browser: glrk4 at dt = 0.01 would no longer keep up with
#: real time on a phone (the evaluation's cost grows as n^2 to n^3 in the printed form).
MAX_BROWSER_COORDINATES = 6


def _stem(model: PendulumModel) -> str:
    for stem, factory in SHIPPED_MODELS.items():
        if _same_equations(model, factory()):
            return stem
    if model.is_chain:
        return f"chain{model.n}{'_forced' if model.forced else ''}"
    return "system_" + "".join(c if c.isalnum() else "_" for c in model.system.name)[:40]


def _same_equations(model: PendulumModel, other: PendulumModel) -> bool:
    if model.is_chain != other.is_chain:
        return False
    if model.is_chain:
        return (model.n, model.forced) == (other.n, other.forced)
    return model.system is other.system or model.system.name == other.system.name and \
        str(model.system.lagrangian) == str(other.system.lagrangian)


def model_module(model: PendulumModel) -> BrowserModule:
    """The ES module of ``model``'s equations (made once per process), named after the shipped
    model with the same equations, else after the model; a ``ValueError`` saying why if the
    browser cannot run it (:func:`browser_refusal`)."""
    require_model(model)
    reason = browser_refusal(model)
    if reason is not None:
        raise ValueError(reason)
    return browser_module(model.chain, _stem(model))


def browser_refusal(model: PendulumModel) -> str | None:
    """Why ``model`` cannot run in the browser (a sentence), or None if it can."""
    require_model(model)
    if model.shape:
        return "a family of models runs in the kernel only: the browser simulates one model"
    if model.n > MAX_BROWSER_COORDINATES:
        return (f"a model of {model.n} coordinates is beyond what a browser integrates in real "
                f"time (at most {MAX_BROWSER_COORDINATES}); it runs in the kernel")
    if not model.is_chain and not model.system.points:
        return (f"{model.system.name} was given by its Lagrangian, so it has no points to draw "
                "in the browser")
    try:
        browser_module(model.chain, _stem(model))
    except ValueError as err:
        return str(err)
    return None


def _refusals(model: PendulumModel, methods) -> dict:
    """The methods the browser must refuse for ``model``, with the kernel's reason."""
    field = hamiltonian_field(model)
    refused = {}
    for name in methods:
        reason = unsuitability(get_method(name), field)
        if reason is not None:
            refused[name] = f"{name} cannot integrate this model: {reason}"
    return refused


def browser_config(model: PendulumModel, theta0=None, omega0=None, *, t_end: float = 20.0,
                   dt: float = 0.01, method: str = "glrk4", module: str | None = None,
                   trail: float = 2.0) -> dict:
    """What ``engine.js``'s ``mount`` needs to run ``model`` in the browser (JSON-ready).

    ``module`` is the URL of the model's ES module relative to ``engine.js`` (by default the
    shipped one, ``models/<stem>.js``; for a model that is not shipped, its module's text
    travels as ``source``, made on demand); the initial angles and velocities default to the
    simulators' (:func:`pendulum_lab.widgets.live_simulator`). ``method`` is one of
    :data:`~pendulum_lab.integrators.registry.MAIN_METHODS`, the five the browser has.
    """
    require_model(model)
    made = model_module(model)
    if method not in MAIN_METHODS:
        raise ValueError(f"`method` must be one of {list(MAIN_METHODS)} in the browser, got "
                         f"{method!r}")
    if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
        raise ValueError(f"`dt` must be a positive finite number, got {dt!r}")
    if not (isinstance(t_end, (int, float)) and math.isfinite(t_end) and t_end >= dt):
        raise ValueError(f"`t_end` must be a finite number of at least `dt`, got {t_end!r}")
    if theta0 is None:
        theta0 = (model.start if not model.is_chain else
                  [1.0] if model.n == 1 else [2.0, 2.5] if model.n == 2 else [2.0] * model.n)
    theta0 = np.asarray(theta0, dtype=float).reshape(model.n)
    omega0 = np.zeros(model.n) if omega0 is None else np.asarray(omega0, float).reshape(model.n)
    points = None
    if not model.is_chain:
        points = np.stack(model.positions(theta0[None], np.zeros(1)), axis=-1)
    figure = figure_message(model, points)
    shipped = made.stem in SHIPPED_MODELS
    refused = _refusals(model, MAIN_METHODS)
    if method in refused:
        raise ValueError(refused[method])
    return {
        # a shipped model's module is a file beside engine.js; any other travels in the page
        "module": module or (f"./models/{made.stem}.js" if shipped else None),
        "source": None if module or shipped else made.source,
        "key": made.key,
        "name": model.chain.name if not model.is_chain else made.stem.replace("_", " "),
        "params": [float(v) for v in model.parameter_values.values()],
        "theta0": theta0.tolist(),
        "omega0": omega0.tolist(),
        "t_end": float(t_end),
        "dt": float(dt),
        "method": method,
        "methods": list(MAIN_METHODS),
        "refused": refused,
        "figure": figure,
        "lengths": list(model.lengths) if model.is_chain else [],
        "angle_coordinates": [bool(a) for a in model.angle_coordinates],
        "conserved": energy_is_conserved(model),
        "forces": forces_text(model),
        "changed_by": energy_changers(model),
        "speeds": list(SPEEDS),
        "trail": float(trail),
    }


def run_settings(model: PendulumModel, trajectory, trail: float = 2.0) -> dict:
    """A kernel's run as :func:`browser_config` gives it to the browser's engine (its model,
    first state, length, step and method), or ``{"refusal": sentence}`` if the browser cannot
    run it."""
    refusal = browser_refusal(model)
    if refusal is None:
        try:
            if trajectory.theta.ndim != 2:
                raise ValueError("an ensemble of runs plays in the kernel only")
            return browser_config(model, trajectory.theta[0], trajectory.omega[0],
                                  t_end=float(trajectory.t[-1] - trajectory.t[0]),
                                  dt=trajectory.dt, method=trajectory.method.name, trail=trail)
        except ValueError as err:
            refusal = str(err)
    return {"refusal": refusal}


def with_run_settings(bundle: dict, settings: dict) -> dict:
    """``bundle`` (a widget's display) with ``settings`` in its widget view's data, under
    :data:`~pendulum_lab.widgets.channel.BROWSER_SETTINGS`: the site's notebook reader skips mime
    types it does not know, and the widget managers read only ``model_id`` from the view."""

    view = "application/vnd.jupyter.widget-view+json"
    if isinstance(bundle.get(view), dict):
        bundle[view] = {**bundle[view], BROWSER_SETTINGS: settings}
    return bundle


def simulator_html(config: dict, engine_url: str, *, fallback_html: str = "") -> str:
    """HTML for a static page: a live simulator where JavaScript runs, else ``fallback_html``
    (the still picture), which stays in the page for readers without JavaScript and for print.

    ``engine_url`` is the URL of ``engine.js`` as the page sees it.
    """
    payload = html.escape(json.dumps(config), quote=True)
    return (
        f'<div class="plab-browser-sim" data-config="{payload}">\n'
        f'<div class="plab-still">{fallback_html}</div>\n</div>\n'
        '<script type="module">\n'
        f'import {{ mount }} from "{engine_url}";\n'
        'const holders = document.querySelectorAll(".plab-browser-sim:not([data-mounted])");\n'
        'for (const holder of holders) {\n'
        '  holder.dataset.mounted = "1";\n'
        '  const live = document.createElement("div");\n'
        '  holder.prepend(live);\n'
        '  const config = JSON.parse(holder.dataset.config);\n'
        f'  config.base = new URL("{engine_url}", document.baseURI).href;\n'
        '  mount(live, config).then(() => holder.classList.add("plab-live-ready"))\n'
        '    .catch((error) => { live.textContent = "The live simulator cannot run here: " +\n'
        '      error.message + ". The picture below shows the motion."; });\n'
        '}\n</script>\n'
    )


def shipped_sources() -> dict[str, str]:
    """``{file name: text}`` of the shipped model modules, as the generator makes them now."""
    return {f"{stem}.js": model_module(factory()).source
            for stem, factory in SHIPPED_MODELS.items()}


def stale_shipped(folder: Path | None = None) -> list[str]:
    """The shipped model modules in ``folder`` (by default the package's) that are missing or
    differ from what the generator makes now (empty when none has drifted)."""
    folder = Path(folder) if folder is not None else BROWSER_FOLDER / "models"
    return [name for name, text in shipped_sources().items()
            if not (folder / name).is_file()
            or (folder / name).read_text(encoding="utf-8") != text]


def write_shipped(folder: Path | None = None) -> list[Path]:
    """Write the shipped model modules into ``folder`` (by default the package's); returns
    the paths written."""
    folder = Path(folder) if folder is not None else BROWSER_FOLDER / "models"
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for name, text in shipped_sources().items():
        path = folder / name
        path.write_text(text, encoding="utf-8", newline="\n")
        written.append(path)
    return written


if __name__ == "__main__":  # python -m pendulum_lab.widgets.browser: regenerate the modules
    for path in write_shipped(Path(sys.argv[1]) if len(sys.argv) > 1 else None):
        print(path)
