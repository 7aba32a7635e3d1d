"""The kernel-free simulator integrates in real time, frame by frame, in Chromium.

``widgets/static/browser/engine.js`` takes, on each animation frame, the steps the time elapsed
calls for (a little ahead of the motion shown) and hands the drawing the states kept, as the
kernel's run messages, one state per chunk. Checked here:

* while it plays the drawing's run (the energy-error trace) grows; on pause it stops growing;
* after N frames of a given length the state is that of the steps those frames called for,
  bit for bit the engine's whole-run integration, and ``pl.simulate``'s to the step tolerance
  of ``test_browser_engine`` times the steps;
* a frame calling for more steps than the cap takes the cap and says it falls behind;
* an implicit step that fails later in a run shows the kernel's sentence and the previous
  motion goes on; in a first run, with nothing to go back to, the run ends at its last step;
* negative controls: a frame within the cap shows no note, one step more or fewer is another
  state, nothing fails before the failing step.

The tests drive the frames by hand (``frame(ms)`` of ``mount``'s handle, its own loop stopped)
so that they do not depend on this machine's speed, except the first, which watches the loop.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from browser_engine import engine_page
from test_browser_engine import step_tolerance

import pendulum_lab as pl
from pendulum_lab.widgets.browser import browser_config

pytestmark = pytest.mark.browser

DT = 0.01
#: Steps integrated ahead at the start (engine.js: LEAD_SECONDS / dt).
LEAD_STEPS = 5

#: A frame's computing budget far beyond what any frame here needs: the frames driven by hand
#: are then limited by their steps alone, whatever the load of this machine.
NO_TIME_LIMIT = {"frame_budget_ms": 1e9}
HOLDERS = {  # id: (method, extra settings, stop the engine's own loop)
    "free": ("glrk4", {}, False),
    "frames": ("glrk4", NO_TIME_LIMIT, True),
    "capped": ("rk4", {**NO_TIME_LIMIT, "max_steps_per_frame": 3}, True),
    "failing": ("glrk4", NO_TIME_LIMIT, True),
    "alone": ("leapfrog", {**NO_TIME_LIMIT, "dt": 0.1}, True),  # fails, nothing to go back to
}


@pytest.fixture(scope="module")
def live(tmp_path_factory):
    """A page with five kernel-free simulators of the double pendulum; four of them are moved
    on only by the test's calls of their ``frame``."""
    model = pl.double_pendulum()
    configs = {key: {**browser_config(model, method=method, t_end=10.0, dt=DT), **extra}
               for key, (method, extra, _) in HOLDERS.items()}
    stopped = [key for key, (_, _, stop) in HOLDERS.items() if stop]
    html = (
        '<!doctype html><html><head><link rel="stylesheet" href="/live.css"></head><body>'
        + "".join(f'<div id="{key}"></div>' for key in HOLDERS)
        + '<script type="module">\nimport { mount } from "/browser/engine.js";\n'
        f"const configs = {json.dumps(configs)};\nconst stopped = {json.dumps(stopped)};\n"
        "window.handles = {};\n"
        "for (const [key, config] of Object.entries(configs)) {\n"
        "  const handle = await mount(document.getElementById(key), config);\n"
        "  if (stopped.includes(key)) handle.stop();  // before its first frame\n"
        "  window.handles[key] = handle;\n}\nwindow.ready = true;\n</script></body></html>"
    )
    with engine_page(tmp=tmp_path_factory.mktemp("chromium")) as (page, base, requests):
        page.route(f"{base}/realtime.html",
                   lambda route: route.fulfill(body=html, content_type="text/html"))
        page.goto(f"{base}/realtime.html")
        page.wait_for_function("() => window.ready === true")
        yield page, base, requests


def drawing(page, key) -> dict:
    return page.evaluate("k => ({...document.querySelector(`#${k} .plab-live`).dataset})", key)


def frames(page, key, count, ms) -> int:
    """``count`` frames of ``ms`` each; returns the steps taken."""
    return page.evaluate("([k, count, ms]) => { let s = 0; for (let i = 0; i < count; i++) "
                         "s += window.handles[k].frame(ms); return s; }", [key, count, ms])


def integrated(page, key) -> dict:
    return page.evaluate("k => { const r = window.handles[k].state.run.integration; "
                         "return {k: r.k, q: Array.from(r.q), p: Array.from(r.p)}; }", key)


def status(page, key) -> tuple[str, str]:
    node = page.locator(f"#{key} .plab-engine-status")
    return node.text_content(), node.get_attribute("data-kind")


def test_the_trace_grows_while_it_plays_and_stops_growing_on_pause(live):
    page, _, _ = live
    page.wait_for_function("() => +document.querySelector('#free .plab-live').dataset.states > 20")
    first = int(drawing(page, "free")["states"])
    page.wait_for_timeout(400)
    playing = int(drawing(page, "free")["states"])
    assert playing > first + 10  # 0.4 s at 100 kept states a second
    assert int(drawing(page, "free")["states"]) < 1001  # not the whole run at once
    text, kind = status(page, "free")  # on a loaded machine it may be falling behind, and say so
    assert "1000 steps of glrk4 (Δt = 0.01 s) computed in the browser as the motion plays" \
        in text or kind == "behind", text
    page.locator("#free .plab-play").click()
    page.wait_for_function("() => document.querySelector('#free .plab-live').dataset.playing "
                           "=== '0'")
    paused = int(drawing(page, "free")["states"])
    page.wait_for_timeout(400)
    assert int(drawing(page, "free")["states"]) == paused
    page.locator("#free .plab-play").click()  # the control: playing again, it grows again
    page.wait_for_timeout(400)
    assert int(drawing(page, "free")["states"]) > paused + 10


def test_n_frames_take_the_steps_they_call_for_and_reach_the_methods_state(live):
    page, base, _ = live
    assert integrated(page, "frames")["k"] == LEAD_STEPS
    assert frames(page, "frames", 10, 20.0) == 20  # 20 ms at dt = 0.01: two steps a frame
    assert frames(page, "frames", 5, 10.0) == 5
    got = integrated(page, "frames")
    steps = LEAD_STEPS + 25
    assert got["k"] == steps
    page.wait_for_function(f"() => document.querySelector('#frames .plab-live').dataset.states "
                           f"=== '{steps + 1}'")  # every state kept reached the drawing
    whole = page.evaluate(
        """async ([base, steps]) => {
          const e = await import(base + "/browser/engine.js");
          const m = await import(base + "/browser/models/double_pendulum.js");
          return [steps - 1, steps, steps + 1].map((k) => {
            const r = e.simulate(m, [1, 1, 1, 1, 9.81], "glrk4", [2, 2.5], [0, 0], k * 0.01, 0.01);
            return [...r.theta.slice(-2), ...r.p.slice(-2)];
          });
        }""", [base, steps])
    state = got["q"] + got["p"]
    assert state == whole[1]  # bit for bit the whole-run integration
    assert state != whole[0] and state != whole[2]  # the control: one step off is another state
    model = pl.double_pendulum()
    kernel = pl.simulate(model, [2.0, 2.5], [0.0, 0.0], t_end=steps * DT, dt=DT, method="glrk4")
    want = np.concatenate([kernel.theta[-1], kernel.p[-1]])
    q, p = np.array(got["q"]), np.array(got["p"])
    tolerance = steps * step_tolerance(model, "glrk4", want,
                                       np.concatenate(model.vector_field(q, p, steps * DT)))
    assert len(kernel.t) == steps + 1
    assert np.max(np.abs(np.array(state) - want)) <= tolerance


def test_a_frame_beyond_the_cap_takes_the_cap_and_says_it_falls_behind(live):
    page, _, _ = live
    start = integrated(page, "capped")["k"]
    assert frames(page, "capped", 1, 20.0) == 2  # the control: within the cap, no note
    assert "behind" not in drawing(page, "capped") and "behind" not in page.evaluate(
        "() => ({...document.querySelector('#capped').dataset})")
    assert "Falling behind" not in status(page, "capped")[0]
    assert frames(page, "capped", 1, 100.0) == 3  # 10 steps called for, the cap is 3
    assert integrated(page, "capped")["k"] == start + 5
    text, kind = status(page, "capped")
    assert kind == "behind"
    assert text.startswith("Falling behind: this device computed 3 of the 10 steps of rk4")
    assert page.evaluate("() => document.querySelector('#capped').dataset.behind") == "1"
    # behind, the backlog is dropped: the next short frame asks for its own steps only
    assert frames(page, "capped", 1, 20.0) == 2


def test_a_step_that_fails_later_in_a_run_leaves_the_previous_motion_going_on(live):
    page, _, _ = live
    page.locator("#failing select[aria-label=method]").select_option("leapfrog")
    page.locator("#failing select[aria-label='time step']").select_option("0.1")
    assert drawing(page, "failing")["run"] == "3"
    # the leapfrog at dt = 0.1 from (2.0, 2.5) fails at step 22 (t = 2.2 s), as in the kernel
    frames(page, "failing", 15, 100.0)
    assert status(page, "failing")[1] == "info"  # the control: nothing failed before it
    frames(page, "failing", 10, 100.0)
    text, kind = status(page, "failing")
    assert kind == "error"
    model = pl.double_pendulum()
    with pytest.raises(pl.ConvergenceError) as kernel:
        pl.simulate(model, [2.0, 2.5], [0.0, 0.0], t_end=10.0, dt=0.1, method="leapfrog")
    assert text == f"The solver did not converge: {kernel.value}. The previous motion goes on."
    assert page.locator("#failing select[aria-label='time step']").input_value() == "0.01"
    assert page.locator("#failing select[aria-label=method]").input_value() == "leapfrog"
    assert drawing(page, "failing")["run"] == "4"  # the previous run, shown again
    before = integrated(page, "failing")
    frames(page, "failing", 40, 100.0)  # it goes on integrating where it had stopped
    assert integrated(page, "failing")["k"] > before["k"]
    assert page.errors == []


def test_a_first_run_that_fails_later_ends_at_its_last_step_with_the_kernels_sentence(live):
    page, _, _ = live
    frames(page, "alone", 15, 100.0)
    assert drawing(page, "alone")["run"] == "1" and status(page, "alone")[1] == "info"
    frames(page, "alone", 10, 100.0)  # step 22 fails
    text, kind = status(page, "alone")
    assert kind == "error" and "did not converge within 100 iterations at step 22" in text
    # the run, shown again as a new one, holds its 22 states (t = 0 to 2.1 s) and no more
    page.wait_for_function("() => document.querySelector('#alone .plab-live').dataset.run "
                           "=== '2'")
    assert drawing(page, "alone")["states"] == "22"
    assert frames(page, "alone", 5, 100.0) == 0  # and nothing is integrated any more


def test_nothing_was_fetched_from_another_host(live):
    page, base, requests = live
    assert requests and all(u.startswith(base) or u.startswith("data:") for u in requests)
