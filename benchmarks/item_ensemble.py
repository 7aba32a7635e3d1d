"""Item 5: ensemble throughput against the C loop, and the flip-time map."""

from __future__ import annotations

import os

import c_yardstick
import numpy as np
from harness import (
    Config,
    Row,
    Sample,
    Section,
    double_pendulum,
    fmt_rate,
    fmt_time,
    interleave,
    med,
    timed,
    verdict,
)

import pendulum_lab as pl


def ensemble_grid(side: int) -> np.ndarray:
    """``side x side`` angles uniform on ``[-pi/2, pi/2]^2``, shape (side, side, 2)."""
    axis = np.linspace(-np.pi / 2, np.pi / 2, side)
    return np.stack(np.meshgrid(axis, axis, indexing="ij"), axis=-1)


def bench_ensemble(cfg: Config, cloop: c_yardstick.CLoop | None) -> Section:
    """RK4 and GLRK4 trajectory-steps per second on side^2 initial conditions vs C per core."""
    dp = double_pendulum()
    theta = ensemble_grid(cfg.ensemble_side)
    omega = np.zeros_like(theta)
    members = theta.shape[0] * theta.shape[1]
    cores = os.cpu_count() or 1
    last = {}

    def ours(method):
        steps = cfg.ensemble_steps[method]

        def call():
            sample, traj = timed(
                pl.simulate,
                dp,
                theta,
                omega,
                t_end=steps * cfg.dt,
                dt=cfg.dt,
                method=method,
                save_every=steps,
                progress=False,
            )
            last[method] = traj
            return sample

        return call

    for method in cfg.ensemble_steps:  # load kernels
        pl.simulate(dp, theta[:2, :2], omega[:2, :2], t_end=cfg.dt, dt=cfg.dt, method=method)
    contenders = {m: ours(m) for m in cfg.ensemble_steps}
    c_steps = cfg.ensemble_steps["rk4"]
    if cloop is not None:

        def c_loop():
            run = cloop.ensemble(theta.reshape(-1, 2), np.zeros((members, 2)), c_steps, cfg.dt)
            last["C"] = run
            return Sample(run.seconds[0], run.cpu[0])

        contenders = {"C rk4": c_loop, **contenders}
    samples = interleave(contenders, cfg.ensemble_rounds)
    nan = float("nan")
    c_wall = members * c_steps / med(samples["C rk4"], "wall") if cloop else nan
    c_cpu = members * c_steps / med(samples["C rk4"]) if cloop else nan
    rows = []
    data = {
        "members": members,
        "cores": cores,
        "c_rate_wall": c_wall,
        "c_rate_cpu": c_cpu,
        "methods": {},
    }
    details = [
        f"{members} initial conditions ({cfg.ensemble_side} x {cfg.ensemble_side} grid on "
        f"[-pi/2, pi/2]^2, at rest), dt = {cfg.dt:g}, save_every = steps; "
        f"{cfg.ensemble_rounds} interleaved round(s), medians. The C loop runs on ONE thread "
        f"({c_steps} steps): {fmt_rate(c_wall)} by the wall clock, {fmt_rate(c_cpu)} per "
        f"CPU-second. `pl.simulate` splits the ensemble over os.cpu_count() = {cores} threads.",
        "'Per core' is measured as trajectory-steps per CPU-second on both sides (process CPU "
        "time: all our threads, Python included; the C program's CLOCK_PROCESS_CPUTIME_ID), "
        "which stays fair when the shared machine gives our threads less than a core each. "
        f"The naive figure, our wall-clock rate divided by {cores} cores against C's wall-clock "
        "rate, is given below as well ('nominal').",
    ]
    for method, steps in cfg.ensemble_steps.items():
        seconds, cpu_seconds = med(samples[method], "wall"), med(samples[method])
        traj = last[method]
        rate, per_cpu = members * steps / seconds, members * steps / cpu_seconds
        evals = traj.evaluations / (members * steps)
        ratio, nominal = c_cpu / per_cpu, c_wall / (rate / cores)
        data["methods"][method] = {
            "seconds": seconds,
            "cpu_seconds": cpu_seconds,
            "rate_wall": rate,
            "rate_cpu": per_cpu,
            "steps": steps,
            "evals_per_step": evals,
            "ratio": ratio,
            "ratio_nominal": nominal,
        }
        name = f"ensemble {members} x {steps} steps, {method}"
        ours_text = f"{fmt_rate(rate)} wall, {fmt_rate(per_cpu)}/CPU-s"
        peer_text = f"C RK4 {fmt_rate(c_cpu)}/CPU-s"
        if method == "rk4":
            rows.append(
                Row(
                    "5",
                    name,
                    ours_text,
                    peer_text,
                    f"{ratio:.1f}x",
                    "C/ours per core <= 3",
                    verdict(ratio, 3.0) if cloop else "not available",
                )
            )
        else:
            eval_ratio = ratio * 4 / evals
            rows.append(
                Row(
                    "5",
                    name,
                    ours_text,
                    peer_text,
                    f"{ratio:.1f}x",
                    "(info: another method)",
                    "info",
                )
            )
            rows.append(
                Row(
                    "5",
                    f"ensemble, {method} per field evaluation",
                    f"{fmt_rate(per_cpu * evals)} evals/CPU-s",
                    f"C RK4 {fmt_rate(c_cpu * 4)} evals/CPU-s",
                    f"{eval_ratio:.1f}x",
                    "C/ours per core <= 3",
                    verdict(eval_ratio, 3.0) if cloop else "not available",
                )
            )
        details.append(
            f"{method}: {fmt_time(seconds)} wall and {fmt_time(cpu_seconds)} CPU per run "
            f"(cores effectively used {cpu_seconds / seconds:.2f} of {cores}); "
            f"{evals:.1f} field evaluations/step ({traj.mean_iterations:.2f} sweeps); "
            f"nominal ratio {nominal:.1f}x."
        )
    if cloop is not None:
        traj, run = last["rk4"], last["C"]
        gap = max(
            float(np.max(np.abs(run.theta - traj.theta[-1].reshape(-1, 2)))),
            float(np.max(np.abs(run.p - traj.p[-1].reshape(-1, 2)))),
        )
        data["c_gap"] = gap
        details.append(
            f"C vs `pl.simulate(..., 'rk4')` final states, max |difference| over "
            f"all members: {gap:.3g}."
        )
    rows += _flip_map(cfg, dp, c_cpu, data, details)
    return Section("ensemble", "5. Ensemble throughput", rows, details, data)


def _flip_map(cfg, dp, c_cpu, data, details) -> list[Row]:
    try:
        from pendulum_lab import chaos
    except ImportError:
        chaos = None
    if chaos is None or not hasattr(chaos, "flip_time_map"):
        return [Row("5", "flip-time map", "-", "-", "-", "-", "not available")]
    chaos.flip_time_map(dp, size=4, t_end=0.1, dt=cfg.dt, progress=False)
    sample, fm = timed(
        chaos.flip_time_map, dp, size=cfg.flip_size, t_end=cfg.flip_t_end, dt=cfg.dt, progress=False
    )
    seconds, cpu_seconds = sample.wall, sample.cpu
    simulated = ~fm.forbidden
    work = int(np.sum(np.ceil(np.minimum(fm.time[simulated], fm.t_end) / fm.dt)))
    c_equivalent = work / c_cpu
    ratio = cpu_seconds / c_equivalent
    data["flip_map"] = {
        "seconds": seconds,
        "cpu_seconds": cpu_seconds,
        "work": work,
        "cells": int(simulated.sum()),
        "c_equivalent_cpu": c_equivalent,
    }
    details.append(
        f"Flip-time map: `chaos.flip_time_map(dp, size={cfg.flip_size}, "
        f"t_end={cfg.flip_t_end:g}, dt={cfg.dt:g})` (method {fm.method}, default grid "
        f"half-width), one run: {fmt_time(seconds)} wall, {fmt_time(cpu_seconds)} CPU. "
        f"{int(simulated.sum())} of {fm.time.size} cells simulated (the rest cannot flip on "
        f"energy grounds), at least {work} trajectory-steps (each cell up to its flip time; "
        f"cells leave at the end of a segment, so the real count is a little higher). "
        f"'C-equivalent' = that work at the C loop's rate per CPU-second; the ratio compares "
        f"CPU time with it."
    )
    return [
        Row(
            "5",
            f"flip-time map {cfg.flip_size}x{cfg.flip_size} to t={cfg.flip_t_end:g}",
            f"{fmt_time(seconds)} wall, {fmt_time(cpu_seconds)} CPU",
            f"C-equivalent {fmt_time(c_equivalent)} CPU",
            f"{ratio:.1f}x",
            "(info)",
            "info",
        )
    ]
