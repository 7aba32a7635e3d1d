"""Item 16: the simulator without a kernel, integrating in Chromium.

1. **Steps per second.** The double pendulum over 20 s with ``glrk4`` at dt = 0.01: the
   browser's engine (``widgets/static/browser/engine.js``: the generated model, the method's ES
   module) in Chromium, against ``pl.simulate`` with the same method in this process (the
   compiled kernel), interleaved rounds, medians. Information: the ratio says what running
   without a kernel costs.
2. **Real time.** The browser's steps per second against the 100 steps a second of simulated
   time needs at dt = 0.01. Target: at least 1.
3. **Frames drawn per second** by the kernel-free simulator of a page (as the website mounts
   it) while it plays and integrates in real time (each frame takes the steps the time elapsed
   calls for), against a bare ``requestAnimationFrame`` counter in the same page (item 9's
   method). Target: at least 55 of 60.
4. **Steps per second integrated while it plays**, against the 100 a second real time needs at
   dt = 0.01, and the frames that fell behind (took fewer steps than called for). Target: at
   least 0.95 of real time (the count includes the first frame's wait).
"""

from __future__ import annotations

import os
import sys
import time

from harness import HERE, Config, Row, Section, load_average, median, verdict
from item_live import COUNT_FRAMES, FRAME_SHARE

BROWSER = HERE.parent / "tests" / "browser"
T_END, DT, METHOD = 20.0, 0.01, "glrk4"

ENGINE_RUN = """async ({engine, model, rounds}) => {
  const e = await import(engine);
  const m = await import(model);
  const seconds = [];
  for (let r = 0; r < rounds; r++) {
    const started = performance.now();
    const run = e.simulate(m, [1, 1, 1, 1, 9.81], "glrk4", [2.0, 2.5], [0, 0], 20.0, 0.01);
    seconds.push((performance.now() - started) / 1000);
    if (run.steps !== 2000) throw new Error("wrong step count " + run.steps);
  }
  return seconds;
}"""


def _kernel_seconds(rounds: int) -> list[float]:
    import pendulum_lab as pl

    model = pl.double_pendulum()
    pl.simulate(model, [2.0, 2.5], [0.0, 0.0], t_end=T_END, dt=DT, method=METHOD)  # compiled
    seconds = []
    for _ in range(rounds):
        started = time.process_time()
        pl.simulate(model, [2.0, 2.5], [0.0, 0.0], t_end=T_END, dt=DT, method=METHOD)
        seconds.append(time.process_time() - started)
    return seconds


def bench_browser(cfg: Config) -> Section:
    """Steps per second in Chromium against the kernel, real time, frames per second."""
    rows, details, data = [], [], {}
    steps = round(T_END / DT)
    names = (f"steps per second, {METHOD} on the double pendulum, browser against kernel",
             "browser steps per second against real time (dt = 0.01)",
             f"frames per second of the kernel-free simulator over {cfg.live_browser_seconds:g} s",
             "steps per second integrated while it plays, against real time")
    if cfg.live_browser_seconds <= 0:
        for name, target in zip(names, ("-", ">= 1", f">= {FRAME_SHARE:.3f}", ">= 0.95")):
            rows.append(Row("16", name, "-", "-", "-", target, "not available"))
        details.append(f"Browser measurement not run in the {cfg.name} configuration.")
        return Section("browser", "16. Simulator without a kernel", rows, details, data)
    try:
        if str(BROWSER) not in sys.path:
            sys.path.insert(0, str(BROWSER))
        from browser_engine import engine_page

        from pendulum_lab.widgets.browser import browser_config, simulator_html

        kernel, browser = [], []
        with engine_page() as (page, base, _):
            for _ in range(max(1, cfg.live_rounds // 3)):  # interleaved
                browser += page.evaluate(ENGINE_RUN, dict(
                    engine=f"{base}/browser/engine.js",
                    model=f"{base}/browser/models/double_pendulum.js", rounds=3))
                kernel += _kernel_seconds(3)
            import pendulum_lab as pl

            config = browser_config(pl.double_pendulum(), t_end=60.0, method=METHOD, dt=DT)
            html = ("<!doctype html><html><head><link rel='stylesheet' href='/live.css'></head>"
                    f"<body>{simulator_html(config, '/browser/engine.js')}</body></html>")
            page.route(f"{base}/bench.html",
                       lambda route: route.fulfill(body=html, content_type="text/html"))
            page.goto(f"{base}/bench.html")
            page.wait_for_function("() => document.querySelector('.plab-live')?.dataset.run"
                                   " === '1'", timeout=60_000)
            page.wait_for_timeout(500)
            engine = "({...document.querySelector('[data-engine=browser]').dataset})"
            before = page.evaluate(f"() => {engine}")
            frames = page.evaluate(COUNT_FRAMES, int(cfg.live_browser_seconds * 1000))
            after = page.evaluate(f"() => {engine}")
            version = page.context.browser.version
    except Exception as err:  # noqa: BLE001 - no Chromium here: say so
        for name in names:
            rows.append(Row("16", name, "-", "-", "-", "-", "not available"))
        details.append(f"Browser measurement not available: {type(err).__name__}: {err}")
        return Section("browser", "16. Simulator without a kernel", rows, details, data)
    data.update(kernel_seconds=kernel, browser_seconds=browser, frames=frames,
                engine_before=before, engine_after=after)
    browser_rate, kernel_rate = steps / median(browser), steps / median(kernel)
    rows.append(Row("16", names[0], f"{browser_rate:,.0f} steps/s (Chromium)",
                    f"kernel {kernel_rate:,.0f} steps/s (CPU)",
                    f"{browser_rate / kernel_rate:.3f}x", "-", "info"))
    real_time = browser_rate * DT
    rows.append(Row("16", names[1], f"{browser_rate:,.0f} steps/s", f"{1 / DT:.0f} steps/s",
                    f"{real_time:.1f}x", ">= 1", verdict(real_time, 1.0, at_most=False)))
    fps = frames["frames"] / frames["elapsed"]
    display = frames["ticks"] / frames["elapsed"]
    rows.append(Row("16", names[2], f"{fps:.1f} fps", f"display (page's rAF) {display:.1f} Hz",
                    f"{fps / display:.3f}", f">= {FRAME_SHARE:.3f} (55 at 60 Hz)",
                    verdict(fps / display, FRAME_SHARE, at_most=False)))
    integrated = (int(after["steps"]) - int(before["steps"])) / frames["elapsed"]
    behind = int(after.get("behind", 0)) - int(before.get("behind", 0))
    rows.append(Row("16", names[3], f"{integrated:,.0f} steps/s", f"real time {1 / DT:.0f} steps/s",
                    f"{integrated * DT:.3f}", ">= 0.95",
                    verdict(integrated * DT, 0.95, at_most=False)))
    load = (load_average() or [float("nan")])[0]
    details.append(
        f"Chromium {version} headless. Medians of {len(browser)} browser runs (performance.now, "
        f"wall) and {len(kernel)} kernel runs (CPU time) of {steps} steps, interleaved in "
        f"groups of three; load average {load:.2f} on {os.cpu_count()} cores. The page's simulator "
        "integrates as it plays (a 60 s run, so the count ends before the run does); drawing "
        f"one frame took {frames['drawMs']:.2f} ms on average; {behind} frame(s) fell behind "
        "(took fewer steps than the time elapsed called for).")
    return Section("browser", "16. Simulator without a kernel", rows, details, data)
