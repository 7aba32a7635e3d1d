"""Benchmark of the browser-drawn live simulator (issue 16): three ratios, measured side by side.

1. **Kernel time per update.** ``LiveSimulator.update()`` (2000 steps of glrk4, the run
   encoded as float32 buffers and sent through a real ipykernel comm) against the recompute
   alone (``pendulum_lab.widgets.simulate_controls`` on the same controls), interleaved rounds
   inside one kernel started with jupyter_client, CPU time, medians. Target: at most 3x.
2. **Frames drawn per second in Chromium.** The demo notebook
   ``tests/browser/live_demo/live_widgets.ipynb`` in JupyterLab (the harness of
   ``tests/browser/lab_harness.py``); the simulator plays for 5 s and its ``data-frames``
   counter is read before and after. A bare ``requestAnimationFrame`` counter runs in the same
   page over the same 5 s: the display's rate, the peer. Target: at least 55 frames per second
   at 60 Hz.
3. **Bytes sent per update** for 20 s of motion: the live simulator sends the run once
   (buffers plus JSON headers); the matplotlib ``animation.Simulator`` sends one image per
   frame while it plays, 20 frames per second for the same 20 s. Information only.

Self-contained: ``bench_live(quick=False)`` returns ``{"rows": [...], "details": [...],
"data": {...}}``, each row a dict keyed like the results table's columns (``#``,
``benchmark``, ``ours``, ``peer``, ``ratio``, ``target``, ``result``). Run it alone with
``.venv/bin/python benchmarks/live_widget.py [--quick]``.
"""

from __future__ import annotations

import json
import os
import statistics
import sys
import tempfile
import textwrap
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
BROWSER = REPO / "tests" / "browser"
DEMO = BROWSER / "live_demo"
ITEM = "7"

# Runs inside a fresh ipykernel: the comm there serialises and sends every message as a
# front end would receive it (nobody listens, which costs the kernel nothing extra).
KERNEL_CODE = """
import json, statistics, time
import numpy as np
import pendulum_lab as pl
from pendulum_lab import animation
from pendulum_lab.widgets import live_simulator
from pendulum_lab.widgets.controls import simulate_controls
from pendulum_lab.widgets.live import run_messages

dp = pl.double_pendulum()
sim = live_simulator(dp, t_end=20.0, dt=0.01, method="glrk4")

def cpu(fn):
    start = time.process_time(); wall = time.perf_counter()
    fn()
    return time.process_time() - start, time.perf_counter() - wall

def update():
    sim.update()

def recompute():
    simulate_controls(dp.n, sim.controls)

samples = {"update": [], "recompute": []}
names = list(samples)
for r in range(ROUNDS):
    for name in names[r % 2:] + names[:r % 2]:
        samples[name].append(cpu(update if name == "update" else recompute))

steps = len(sim.trajectory.t) - 1
messages = run_messages(sim.trajectory, dp, run=1)
buffer_bytes = sum(b.nbytes for _, bs in messages for b in bs)
header_bytes = sum(len(json.dumps(c)) for c, _ in messages)
status_bytes = len(sim._status.value.encode())

old = animation.simulator(dp, t_end=20.0, dt=0.01, method="glrk4")
frames = old.frame.max + 1
image_bytes = [len(old._image.value)]
for k in range(1, frames):
    old.play.value = k
    image_bytes.append(len(old._image.value))

print(json.dumps({
    "steps": steps,
    "update_cpu": [s[0] for s in samples["update"]],
    "update_wall": [s[1] for s in samples["update"]],
    "recompute_cpu": [s[0] for s in samples["recompute"]],
    "recompute_wall": [s[1] for s in samples["recompute"]],
    "messages": len(messages),
    "buffer_bytes": buffer_bytes,
    "header_bytes": header_bytes,
    "status_bytes": status_bytes,
    "frames": int(frames),
    "image_format": old._image.format,
    "image_bytes": int(sum(image_bytes)),
}))
"""


def _row(name, ours, peer, ratio, target, result) -> dict:
    return {
        "#": ITEM,
        "benchmark": name,
        "ours": ours,
        "peer": peer,
        "ratio": ratio,
        "target": target,
        "result": result,
    }


def _verdict(ratio: float, limit: float, at_most: bool) -> str:
    ok = ratio <= limit if at_most else ratio >= limit
    if ok:
        return "PASS"
    return f"MISS ({(ratio / limit if at_most else limit / ratio):.2f}x off)"


def _ms(seconds: float) -> str:
    return f"{seconds * 1e3:.3g} ms"


def _in_kernel(rounds: int, timeout: float = 600) -> dict:
    """Run KERNEL_CODE in a fresh ipykernel; return the JSON it prints."""
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
    """Frames the widget drew over ``seconds`` of play in Chromium, and the page's rAF rate."""
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
                " return r && r.dataset.states === '6001'; }",
                timeout=60_000,
            )
            page.locator(".plab-live").first.scroll_into_view_if_needed()
            page.evaluate("() => document.querySelector('.plab-live').focus()")
            page.keyboard.press("Home")
            page.keyboard.press("Space")
            page.wait_for_timeout(500)
            measured = page.evaluate(
                """(ms) => new Promise((done) => {
                    const root = document.querySelector('.plab-live');
                    let ticks = 0;
                    let finished = false;
                    const count = () => {
                        ticks += 1;
                        if (!finished) requestAnimationFrame(count);
                    };
                    requestAnimationFrame(count);
                    const frames0 = Number(root.dataset.frames);
                    const drawMs = Number(root.dataset.drawMs);
                    const start = performance.now();
                    setTimeout(() => {
                        finished = true;
                        const elapsed = (performance.now() - start) / 1000;
                        done({frames: Number(root.dataset.frames) - frames0, ticks, elapsed,
                              playing: root.dataset.playing,
                              drawMs: Number(root.dataset.drawMs) || drawMs});
                    }, ms);
                })""",
                int(seconds * 1000),
            )
            # The same count on a blank page right after: the rate Chromium gives any page
            # on this machine now (it drops below 60 Hz when the cores are busy).
            blank = runner.context.new_page()
            try:
                measured["blank_ticks"] = blank.evaluate(
                    """(ms) => new Promise((done) => {
                        let ticks = 0;
                        const start = performance.now();
                        const count = () => {
                            ticks += 1;
                            if (performance.now() - start < ms) requestAnimationFrame(count);
                            else done(ticks / ((performance.now() - start) / 1000));
                        };
                        requestAnimationFrame(count);
                    })""",
                    int(seconds * 1000),
                )
            finally:
                blank.close()
            measured["chromium_args"] = CHROMIUM_ARGS
            measured["version"] = runner.browser.version
            measured["load"] = os.getloadavg()[0]
            return measured
        finally:
            runner.close()
            if previous is None:
                os.environ.pop("PENDULUM_LAB_NOTEBOOKS", None)
            else:
                os.environ["PENDULUM_LAB_NOTEBOOKS"] = previous


def bench_live(quick: bool = False, browser: bool = True) -> dict:
    """The three measurements (the first two without ``browser``); rows keyed like the
    results table, details, raw numbers."""
    rows, details, data = [], [], {}
    kernel = _in_kernel(rounds=4 if quick else 15)
    data["kernel"] = kernel
    update = statistics.median(kernel["update_cpu"])
    recompute = statistics.median(kernel["recompute_cpu"])
    ratio = update / recompute
    rows.append(
        _row(
            f"live simulator update ({kernel['steps']} steps glrk4, arrays sent)",
            _ms(update),
            f"recompute alone {_ms(recompute)}",
            f"{ratio:.2f}x",
            "<= 3x",
            _verdict(ratio, 3.0, at_most=True),
        )
    )
    details.append(
        f"Kernel (CPU medians of {len(kernel['update_cpu'])} interleaved rounds): update "
        f"{_ms(update)} (wall {_ms(statistics.median(kernel['update_wall']))}), recompute "
        f"{_ms(recompute)} (wall {_ms(statistics.median(kernel['recompute_wall']))})."
    )

    sent = kernel["buffer_bytes"] + kernel["header_bytes"] + kernel["status_bytes"]
    images = kernel["image_bytes"]
    rows.append(
        _row(
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
        f"JSON headers {kernel['header_bytes']} B, status line {kernel['status_bytes']} B. "
        f"animation.Simulator: {kernel['frames']} {kernel['image_format']} frames, "
        f"{images} B in all ({images / kernel['frames'] / 1e3:.1f} kB per frame)."
    )

    if not browser:
        return {"rows": rows, "details": details, "data": data}
    seconds = 2.0 if quick else 5.0
    try:
        browser = _frame_rate(seconds)
    except Exception as err:  # noqa: BLE001 - no Chromium here: say so, keep the other rows
        rows.append(_row("frames per second in Chromium", "-", "-", "-", ">= 55", "not available"))
        details.append(f"Browser measurement not available: {type(err).__name__}: {err}")
        return {"rows": rows, "details": details, "data": data}
    data["browser"] = browser
    fps = browser["frames"] / browser["elapsed"]
    display = browser["ticks"] / browser["elapsed"]
    rows.append(
        _row(
            f"frames drawn per second in Chromium over {seconds:g} s",
            f"{fps:.1f} fps",
            f"display (rAF) {display:.1f} Hz",
            f"{fps / display:.2f}",
            ">= 55 fps",
            _verdict(fps, 55.0, at_most=False),
        )
    )
    details.append(
        f"Chromium {browser['version']} headless, flags {' '.join(browser['chromium_args'])} "
        f"(none added for the frame rate). The widget drew {browser['frames']} frames in "
        f"{browser['elapsed']:.2f} s while a bare rAF counter in the same page ticked "
        f"{browser['ticks']} times; a blank page right after ticked at "
        f"{browser['blank_ticks']:.1f} Hz (load average {browser['load']:.2f} on "
        f"{os.cpu_count()} cores). Drawing one frame took {browser['drawMs']:.2f} ms on "
        f"average (of the {1000 / 60:.1f} ms a 60 Hz frame allows)."
    )
    return {"rows": rows, "details": details, "data": data}


def main(argv=None) -> int:
    quick = "--quick" in (argv if argv is not None else sys.argv[1:])
    load = os.getloadavg()
    start = time.perf_counter()
    result = bench_live(quick=quick)
    columns = ["#", "benchmark", "ours", "peer", "ratio", "target", "result"]
    print("| " + " | ".join(columns) + " |")
    print("|" + "---|" * len(columns))
    for row in result["rows"]:
        print("| " + " | ".join(row[c] for c in columns) + " |")
    print()
    for line in result["details"]:
        print(textwrap.fill(line, 100))
    print(
        f"\nLoad average at start {load[0]:.2f}, at end {os.getloadavg()[0]:.2f}; "
        f"{time.perf_counter() - start:.0f} s."
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
