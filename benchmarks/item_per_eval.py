"""Item 10: the cost per field evaluation of every method against C, now and at an older commit.

Three contenders per round, interleaved: the C RK4 loop (per evaluation:
its CPU time over four evaluations a step), :mod:`per_eval_probe` on the
working tree ("after") and the same probe on the package as it was at
:data:`BEFORE` ("before": ``git archive`` of that revision's ``src`` into a
temporary folder, with its own kernel cache). The probe also measures the
energy floor of a long ``glrk8`` run, before (plain update) and after
(compensated summation).
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import tarfile
import tempfile
from pathlib import Path

import c_yardstick
from harness import (
    HERE,
    THETA0,
    Config,
    Row,
    Sample,
    Section,
    child_json,
    explorer_start,
    median,
    verdict,
)

import pendulum_lab as pl

#: The last commit before the per-(field, method) loops (function-pointer loop, no starting values).
BEFORE = "122f41b"
#: The target: a step kernel's time per evaluation within this factor of C's.
TARGET = 1.5


def _export(revision: str, folder: Path) -> Path | None:
    """``src`` of ``revision`` unpacked into ``folder``; None if git cannot give it."""
    archive = folder / "src.tar"
    try:
        with archive.open("wb") as out:
            done = subprocess.run(["git", "-C", str(HERE.parent), "archive", revision, "src"],
                                  stdout=out, stderr=subprocess.PIPE, check=False, timeout=60)
    except (OSError, subprocess.TimeoutExpired):
        return None
    if done.returncode != 0:
        return None
    with tarfile.open(archive) as tar:
        tar.extractall(folder, filter="data")
    return folder / "src"


def _probe(settings: dict, src: Path | None, cache: Path | None) -> dict:
    env = dict(os.environ)
    if src is not None:
        env["PYTHONPATH"] = str(src)
    if cache is not None:
        env["PENDULUM_LAB_CACHE"] = str(cache)
    return child_json([str(HERE / "per_eval_probe.py"), json.dumps(settings)],
                      "per-evaluation probe", env=env, timeout=1800)


def bench_per_eval(cfg: Config, cloop: c_yardstick.CLoop | None) -> Section:
    """ns per field evaluation, every method, against the C RK4 loop; before and after."""
    _, theta0, _, p0 = explorer_start()
    methods = list(pl.METHODS)
    settings = {
        "theta0": list(THETA0),
        "dt": cfg.dt,
        "n_steps": cfg.per_eval_steps,
        "methods": methods,
        "repeats": cfg.per_eval_repeats,
        "floor": {"method": "glrk8", "dt": cfg.floor_dt, "t_end": cfg.floor_t_end,
                  "save_every": 5},
    }
    rows, details, data = [], [], {"settings": settings}
    with tempfile.TemporaryDirectory(prefix="pendulum_before_") as tmp:
        before_src = _export(BEFORE, Path(tmp)) if cfg.per_eval_before else None
        before_cache = Path(tmp) / "kernels"
        contenders = {"after": lambda: _probe(settings, None, None)}
        if before_src is not None:
            contenders["before"] = lambda: _probe(settings, before_src, before_cache)
        if cloop is not None:

            def c_loop():
                run = cloop.single(theta0, p0, cfg.per_eval_steps, cfg.dt, cfg.c_inner_reps)
                return Sample(median(run.seconds), median(run.cpu))

            contenders["C"] = c_loop
        results: dict = {name: [] for name in contenders}
        names = list(contenders)
        for r in range(cfg.per_eval_rounds):
            for name in names[r % len(names):] + names[: r % len(names)]:
                results[name].append(contenders[name]())
    c_ns = (median(s.cpu for s in results["C"]) / (4 * cfg.per_eval_steps) * 1e9
            if "C" in results else float("nan"))

    def per_method(name, method, key="ns_per_eval"):
        values = [r["methods"][method][key] for r in results.get(name, [])
                  if method in r["methods"]]
        return median(values) if values else float("nan")

    before_state = "done" if "before" in results else (
        "not run: git archive failed" if cfg.per_eval_before else "not run in this configuration"
    )
    details.append(
        f"One trajectory from theta = {THETA0} at rest, dt = {cfg.dt:g}; per method, CPU time "
        f"of `pl.simulate` over {cfg.per_eval_steps} and {cfg.per_eval_steps // 10} steps "
        f"(median of {cfg.per_eval_repeats} each, inside a fresh process), and ns/eval = "
        "difference / difference of evaluations (the fixed cost of a call cancels). "
        f"C: the RK4 loop of item 6 over {cfg.per_eval_steps} steps, CPU / (4 x steps). "
        f"{cfg.per_eval_rounds} interleaved rounds (C, after, before), medians. "
        f"'before' = `git archive {BEFORE} src` run by the same probe "
        f"({before_state})."
    )
    details.append("")
    details.append("| method | after ns/eval | after / C | before ns/eval | before / C "
                   "| evals/step after (before) | sweeps/step after (before) |")
    details.append("|---|---|---|---|---|---|---|")
    data.update({"c_ns_per_eval": c_ns, "methods": {}})
    for method in methods:
        after, before = per_method("after", method), per_method("before", method)
        ratio = after / c_ns
        data["methods"][method] = {"after": after, "before": before, "ratio": ratio,
                                   "before_ratio": before / c_ns}
        # a method added after BEFORE has no "before" (glrk12)
        was = (f"before {before:.0f} ns" if math.isfinite(before)
               else f"not in {BEFORE}" if "before" in results else "before: not run")
        was_ratio = f"before {before / c_ns:.2f}x" if math.isfinite(before) else "-"
        rows.append(Row(
            "10", f"per evaluation, {method}", f"{after:.0f} ns ({was})",
            f"C RK4 {c_ns:.0f} ns", f"{ratio:.2f}x ({was_ratio})",
            f"ours/C <= {TARGET:g} (CPU)",
            verdict(ratio, TARGET) if "C" in results else "not available",
        ))
        details.append(
            f"| {method} | {after:.0f} | {ratio:.2f} | {before:.0f} | {before / c_ns:.2f} | "
            f"{per_method('after', method, 'evals_per_step'):.1f} "
            f"({per_method('before', method, 'evals_per_step'):.1f}) | "
            f"{per_method('after', method, 'sweeps'):.2f} "
            f"({per_method('before', method, 'sweeps'):.2f}) |"
        )
    floors = {name: [r["floor"] for r in results.get(name, []) if "floor" in r]
              for name in ("after", "before")}
    if floors["after"]:
        after = floors["after"][-1]
        before = floors["before"][-1] if floors["before"] else None
        rows.append(Row(
            "10", f"energy floor, glrk8 dt={cfg.floor_dt:g} T={cfg.floor_t_end:g} (compensated)",
            f"max rel. error {after['max']:.2g}",
            f"before (plain sum) {before['max']:.2g}" if before else "before: not available",
            f"{before['max'] / after['max']:.1f}x lower" if before else "-",
            "(show before/after)", "info",
        ))
        data["floor"] = {"after": after, "before": before}
        details.append("")
        details.append(
            f"Energy floor: glrk8 at dt = {cfg.floor_dt:g} over T = {cfg.floor_t_end:g} (its "
            "truncation error in the energy is far below round-off at this step), energy every "
            f"5 steps: after (compensated update) max {after['max']:.3g}, last tenth "
            f"{after['last_tenth']:.3g}"
            + (f"; before (plain update) max {before['max']:.3g}, last tenth "
               f"{before['last_tenth']:.3g}." if before else ".")
        )
    return Section("per_eval", "10. Per field evaluation vs C (before/after)", rows, details, data)
