"""Item 9: the browser-drawn live simulator, three ratios measured side by side.

1. **Kernel time per update.** ``LiveSimulator.update()`` (2000 steps of glrk4, the run
   encoded as float32 buffers and sent through a real ipykernel comm) against the recompute
   alone (``widgets.controls.simulate_controls`` on the same controls), interleaved rounds
   inside one kernel started with jupyter_client, CPU time, medians. Target: at most 3x.
2. **Frames drawn per second in Chromium.** The demo notebook
   ``tests/browser/live_demo/live_widgets.ipynb`` in JupyterLab (the harness of
   ``tests/browser/lab_harness.py``); the simulator plays for a few seconds and its
   ``data-frames`` counter is read before and after, while a bare ``requestAnimationFrame``
   counter in the same page measures the display's rate over the same interval: the peer.
   Target: at least 55 frames per second at 60 Hz, i.e. the widget draws at least 55/60 of
   the frames the page is given (a loaded machine gives fewer than 60; the ratio stays fair).
3. **Bytes sent per update** for 20 s of motion: the live simulator sends the run once
   (buffers plus JSON headers); the matplotlib ``animation.Simulator`` sends one image per
   frame while it plays, 20 frames per second for the same 20 s. Information only.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
from pathlib import Path

from harness import HERE, Config, Row, Section, fmt_time, load_average, median, verdict

BROWSER = HERE.parent / "tests" / "browser"
DEMO = BROWSER / "live_demo"
#: States of the demo's 60 s run at 10 ms: the widget has all of it.
DEMO_STATES = 6001
#: The target: 55 frames drawn per second on a 60 Hz display.
FRAME_SHARE = 55 / 60

# Runs inside a fresh ipykernel: the comm there serialises and sends every message as a
# front end would receive it (nobody listens, which costs the kernel nothing extra).
KERNEL_CODE = """
import json, time
import ipywidgets
import pendulum_lab as pl
from pendulum_lab import animation
from pendulum_lab.widgets import live_simulator
from pendulum_lab.widgets.controls import simulate_controls
from pendulum_lab.widgets.live import run_messages

dp = pl.double_pendulum()
sim = live_simulator(dp, t_end=20.0, dt=0.01, method="glrk4")

def timed(fn):
    cpu, wall = time.process_time(), time.perf_counter()
    fn()
    return time.process_time() - cpu, time.perf_counter() - wall

contenders = {"update": sim.update, "recompute": lambda: simulate_controls(dp, sim.controls)}
samples = {name: [] for name in contenders}
names = list(contenders)
for r in range(ROUNDS):
    for name in names[r % 2:] + names[:r % 2]:
        samples[name].append(timed(contenders[name]))

messages = run_messages(sim.trajectory, dp, run=1)
old = animation.simulator(dp, t_end=20.0, dt=0.01, method="glrk4")
image = next(w for w in old.widget.children if isinstance(w, ipywidgets.Image))
image_bytes = [len(image.value)]
for frame in range(1, old.frame.max + 1):
    old.play.value = frame
    image_bytes.append(len(image.value))

print(json.dumps({
    "steps": len(sim.trajectory.t) - 1,
    "samples": samples,
    "messages": len(messages),
    "buffer_bytes": sum(b.nbytes for _, bs in messages for b in bs),
    "header_bytes": sum(len(json.dumps(c)) for c, _ in messages),
    "frames": old.frame.max + 1,
    "image_format": image.format,
    "image_bytes": sum(image_bytes),
}))
"""

# The widget's frame counter and a bare rAF counter over the same interval of one page.
COUNT_FRAMES = """(ms) => new Promise((done) => {
    const root = document.querySelector('.plab-live');
    let ticks = 0;
    let finished = false;
    const count = () => { ticks += 1; if (!finished) requestAnimationFrame(count); };
    requestAnimationFrame(count);
    const frames0 = Number(root.dataset.frames);
    const start = performance.now();
    setTimeout(() => {
        finished = true;
        done({frames: Number(root.dataset.frames) - frames0, ticks,
              elapsed: (performance.now() - start) / 1000, playing: root.dataset.playing,
              drawMs: Number(root.dataset.drawMs)});
    }, ms);
})"""


def _in_kernel(rounds: int, timeout: float = 600) -> dict:
    """Run :data:`KERNEL_CODE` in a fresh ipykernel; return the JSON it prints."""
    from jupyter_client.manager import start_new_kernel

    manager, client = start_new_kernel(kernel_name="python3")
    printed: list[str] = []

    def collect(message):
        if message["msg_type"] == "stream":
            printed.append(message["content"]["text"])
        elif message["msg_type"] == "error":
            printed.append("ERROR " + "\n".join(message["content"]["traceback"]))

    try:
        code = KERNEL_CODE.replace("ROUNDS", str(rounds))
        client.execute_interactive(code, output_hook=collect, timeout=timeout)
    finally:
        client.stop_channels()
        manager.shutdown_kernel(now=True)
    text = "".join(printed)
    if "ERROR" in text:
        raise RuntimeError(text[-2000:])
    return json.loads(text.strip().splitlines()[-1])


def _frame_rate(seconds: float) -> dict:
    """Frames the widget drew over ``seconds`` of play in Chromium, and the page's rAF ticks."""
    if str(BROWSER) not in sys.path:
        sys.path.insert(0, str(BROWSER))
    from lab_harness import CHROMIUM_ARGS, NotebookRunner

    previous = os.environ.get("PENDULUM_LAB_NOTEBOOKS")
    os.environ["PENDULUM_LAB_NOTEBOOKS"] = str(DEMO)
    with tempfile.TemporaryDirectory(prefix="live_bench_") as folder:
        runner = NotebookRunner(lambda: Path(folder))
        try:
            run = runner.get("live_widgets.ipynb")
            if not run.ok:
                raise RuntimeError(run.report())
            page = run.page
            page.wait_for_function(
                "() => { const r = document.querySelector('.plab-live');"
                f" return r && r.dataset.states === '{DEMO_STATES}'; }}",
                timeout=60_000,
            )
            page.locator(".plab-live").first.scroll_into_view_if_needed()
            page.evaluate("() => document.querySelector('.plab-live').focus()")
            page.keyboard.press("Home")  # paused at t = 0: 60 s of run ahead
            page.keyboard.press("Space")
            page.wait_for_timeout(500)
            measured = page.evaluate(COUNT_FRAMES, int(seconds * 1000))
            measured["chromium_args"] = CHROMIUM_ARGS
            measured["version"] = runner.browser.version
            measured["load"] = (load_average() or [None])[0]
            return measured
        finally:
            runner.close()
            if previous is None:
                os.environ.pop("PENDULUM_LAB_NOTEBOOKS", None)
            else:
                os.environ["PENDULUM_LAB_NOTEBOOKS"] = previous


def bench_live(cfg: Config) -> Section:
    """Kernel time per update, frames per second in Chromium, bytes per update."""
    rows, details = [], []
    kernel = _in_kernel(cfg.live_rounds)
    data = {"kernel": kernel}
    update_cpu, recompute_cpu = (
        median(cpu for cpu, _ in kernel["samples"][name]) for name in ("update", "recompute")
    )
    update_wall, recompute_wall = (
        median(wall for _, wall in kernel["samples"][name]) for name in ("update", "recompute")
    )
    ratio = update_cpu / recompute_cpu
    rows.append(
        Row(
            "9",
            f"live simulator update ({kernel['steps']} steps glrk4, arrays sent)",
            f"{fmt_time(update_cpu)} ({fmt_time(update_wall)} wall)",
            f"recompute alone {fmt_time(recompute_cpu)} ({fmt_time(recompute_wall)} wall)",
            f"{ratio:.2f}x",
            "<= 3x (CPU)",
            verdict(ratio, 3.0),
        )
    )
    details.append(
        f"Kernel: CPU medians of {len(kernel['samples']['update'])} interleaved rounds in a "
        "fresh ipykernel (jupyter_client); an update is the recompute, the float32 encoding "
        "and the comm messages of the run, and the status line."
    )

    sent = kernel["buffer_bytes"] + kernel["header_bytes"]
    images = kernel["image_bytes"]
    rows.append(
        Row(
            "9",
            "bytes per update, 20 s of motion",
            f"{sent / 1e3:.0f} kB once",
            f"{images / 1e6:.1f} MB of {kernel['image_format'].upper()} frames "
            f"({kernel['frames']} at 20 fps)",
            f"{images / sent:.0f}x fewer",
            "-",
            "info",
        )
    )
    details.append(
        f"Live: {kernel['messages']} message(s), float32 buffers {kernel['buffer_bytes']} B, "
        f"JSON headers {kernel['header_bytes']} B. animation.Simulator: {kernel['frames']} "
        f"{kernel['image_format']} frames, {images} B in all "
        f"({images / kernel['frames'] / 1e3:.1f} kB per frame)."
    )

    seconds = cfg.live_browser_seconds
    name = f"frames drawn per second in Chromium over {seconds:g} s"
    target = f"fps / display >= {FRAME_SHARE:.3f} (55 at 60 Hz)"
    if seconds <= 0:
        rows.append(Row("9", name, "-", "-", "-", target, "not available"))
        details.append(f"Browser measurement not run in the {cfg.name} configuration.")
        return Section("live", "9. Live simulator", rows, details, data)
    try:
        browser = _frame_rate(seconds)
    except Exception as err:  # noqa: BLE001 - no Chromium here: say so, keep the other rows
        rows.append(Row("9", name, "-", "-", "-", target, "not available"))
        details.append(f"Browser measurement not available: {type(err).__name__}: {err}")
        return Section("live", "9. Live simulator", rows, details, data)
    data["browser"] = browser
    fps = browser["frames"] / browser["elapsed"]
    display = browser["ticks"] / browser["elapsed"]
    rows.append(
        Row(
            "9",
            name,
            f"{fps:.1f} fps (widget's counter)",
            f"display (page's rAF) {display:.1f} Hz",
            f"{fps / display:.3f}",
            target,
            verdict(fps / display, FRAME_SHARE, at_most=False),
        )
    )
    details.append(
        f"Chromium {browser['version']} headless, flags {' '.join(browser['chromium_args'])}. "
        f"The widget drew {browser['frames']} frames in {browser['elapsed']:.2f} s while a "
        f"bare rAF counter in the same page ticked {browser['ticks']} times (load average "
        f"{browser['load']:.2f} on {os.cpu_count()} cores; a busy machine lowers both). "
        f"Drawing one frame took {browser['drawMs']:.2f} ms on average, of the "
        f"{1000 / 60:.1f} ms a 60 Hz frame allows."
    )
    return Section("live", "9. Live simulator", rows, details, data)
