"""Item 6: the C RK4 loop itself, its speed per step and that it does our arithmetic."""

from __future__ import annotations

import math

import c_yardstick
import numpy as np
from harness import Config, Row, Sample, Section, explorer_start, fmt_time, interleave, med, median
from item_ensemble import ensemble_grid

import pendulum_lab as pl


def bench_c_limit(cfg: Config, cloop: c_yardstick.CLoop | None) -> Section:
    """The C RK4 loop itself: its speed per step, and that it does the same work as ours."""
    if cloop is None:
        return Section(
            "c_limit",
            "6. Physical limit (C)",
            [Row("6", "C RK4 loop", "-", "-", "-", "-", "not available")],
            [f"No C compiler (`{c_yardstick.COMPILER}`) found."],
            {},
        )
    dp, theta0, omega0, p0 = explorer_start()
    n_steps = pl.step_count(cfg.slider_t_end, cfg.dt)
    last = {}

    def ours():
        traj = pl.simulate(
            dp, theta0, omega0, t_end=cfg.slider_t_end, dt=cfg.dt, method="rk4", progress=False
        )
        last["ours"] = traj
        return Sample(traj.wall_time, float("nan"))

    def c_loop():
        run = cloop.single(theta0, p0, n_steps, cfg.dt, reps=cfg.c_inner_reps)
        last["C"] = run
        return Sample(median(run.seconds), median(run.cpu))

    ours()
    samples = interleave({"C": c_loop, "ours": ours}, cfg.rounds)
    c_step = med(samples["C"], "wall") / n_steps
    our_step = med(samples["ours"], "wall") / n_steps
    q, p = last["C"].theta, last["C"].p
    gap = max(
        float(np.max(np.abs(q - last["ours"].theta[-1]))),
        float(np.max(np.abs(p - last["ours"].p[-1]))),
    )
    rows = [
        Row(
            "6",
            f"C RK4, one trajectory ({n_steps} steps)",
            f"rk4 loop {our_step * 1e6:.3g} us/step",
            f"C {c_step * 1e6:.3g} us/step",
            f"{our_step / c_step:.1f}x",
            "(yardstick)",
            "info",
        ),
        Row(
            "6",
            f"C vs pl.simulate rk4: end state at t={cfg.slider_t_end:g}",
            f"max |diff| = {gap:.2g}",
            "-",
            "-",
            "<= 1e-9",
            "PASS" if gap <= 1e-9 else "MISS",
        ),
    ]
    # A small ensemble, checked member by member.
    theta = ensemble_grid(max(2, int(math.sqrt(cfg.limit_members)))).reshape(-1, 2)
    members = theta.shape[0]
    t_end = cfg.limit_steps * cfg.dt
    traj = pl.simulate(
        dp,
        theta,
        np.zeros_like(theta),
        t_end=t_end,
        dt=cfg.dt,
        method="rk4",
        save_every=cfg.limit_steps,
        progress=False,
    )
    run = cloop.ensemble(theta, np.zeros_like(theta), cfg.limit_steps, cfg.dt)
    egap = max(
        float(np.max(np.abs(run.theta - traj.theta[-1]))), float(np.max(np.abs(run.p - traj.p[-1])))
    )
    rows.append(
        Row(
            "6",
            f"C vs pl.simulate rk4: {members}-member ensemble, end states",
            f"max |diff| = {egap:.2g}",
            "-",
            "-",
            "<= 1e-9",
            "PASS" if egap <= 1e-9 else "MISS",
        )
    )
    source = cloop.source.read_text(encoding="utf-8")
    details = [
        f"Generated from `pl.derive_chain(2)`: the mass matrix and dL/dq printed with "
        f"`sympy.ccode` after `sympy.cse` (the Hamiltonian form our kernels use: "
        f"dq = M^-1 p by Cramer's rule, dp = dL/dq at omega = dq), RK4 on (theta, p) with "
        f"every sum associated as in `integrators.explicit_rk`; compiled as "
        f"`{cloop.command}` ({c_yardstick.compiler_version()}) in a temporary folder; "
        f"the program times itself with clock_gettime(CLOCK_MONOTONIC). "
        f"{len(source.splitlines())} lines of C.",
        f"Per step: C {c_step * 1e9:.0f} ns, ours (compiled loop only, "
        f"`traj.wall_time`) {our_step * 1e9:.0f} ns; {cfg.rounds} interleaved rounds, "
        f"medians. Ensemble check: {members} members x {cfg.limit_steps} steps, C "
        f"{fmt_time(run.seconds[0])} on one thread, ours {fmt_time(traj.wall_time)}.",
        "Identical arithmetic makes the end states agree to the last bit when the same "
        "libm is used; a nonzero difference would grow with the motion's chaos.",
    ]
    data = {"c_step": c_step, "our_step": our_step, "gap": gap, "ensemble_gap": egap}
    return Section("c_limit", "6. Physical limit (C)", rows, details, data)
