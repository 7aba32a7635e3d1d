"""Item 1: slider latency, the recompute of the default explorer run and a full update."""

from __future__ import annotations

import c_yardstick
from harness import (
    THETA0,
    Config,
    Row,
    Sample,
    Section,
    explorer_start,
    fmt_time,
    interleave,
    med,
    median,
    timed,
    verdict,
)

import pendulum_lab as pl


def bench_slider(cfg: Config, cloop: c_yardstick.CLoop | None) -> Section:
    """Recompute of the default explorer run for every method vs the C RK4 loop; full update."""
    dp, theta0, omega0, p0 = explorer_start()
    n_steps = pl.step_count(cfg.slider_t_end, cfg.dt)
    rows, details, data = [], [], {"n_steps": n_steps, "methods": {}}
    trajectories = {}

    def ours(method):
        def call():
            sample, traj = timed(
                pl.simulate,
                dp,
                theta0,
                omega0,
                t_end=cfg.slider_t_end,
                dt=cfg.dt,
                method=method,
                progress=False,
            )
            trajectories.setdefault(method, []).append(traj)
            return sample

        return call

    contenders = {m: ours(m) for m in pl.METHODS}
    for call in contenders.values():  # load the compiled kernels before timing
        call()
    trajectories.clear()
    if cloop is not None:

        def c_loop():
            run = cloop.single(theta0, p0, n_steps, cfg.dt, cfg.c_inner_reps)
            return Sample(median(run.seconds), median(run.cpu))

        contenders = {"C rk4": c_loop, **contenders}
    samples = interleave(contenders, cfg.rounds)
    nan = float("nan")
    c_cpu = med(samples["C rk4"]) if cloop is not None else nan
    c_wall = med(samples["C rk4"], "wall") if cloop is not None else nan
    data["c_seconds"] = {"cpu": c_cpu, "wall": c_wall}
    details.append(
        f"{n_steps} steps (t_end = {cfg.slider_t_end:g} s, dt = {cfg.dt:g} s) from theta = "
        f"{THETA0} at rest; {cfg.rounds} interleaved rounds, medians; the C figure is the median "
        f"of {cfg.c_inner_reps} repetitions inside each C call: {fmt_time(c_cpu)} CPU, "
        f"{fmt_time(c_wall)} wall. Ratios use CPU time (see the README: a 20 ms job on a "
        "shared machine is preempted far more often than a 0.4 ms one, which would bias a "
        "wall-clock ratio); wall times are in the table below."
    )
    details.append("")
    details.append(
        "| method | CPU | wall | stepping (`traj.wall_time`) | wall outside the loop "
        f"| sweeps/step | field evals/step | ns/eval (C RK4: {c_cpu / (4 * n_steps) * 1e9:.0f}) |"
    )
    details.append("|---|---|---|---|---|---|---|---|")
    for method in pl.METHODS:
        cpu, wall = med(samples[method]), med(samples[method], "wall")
        trajs = trajectories[method]
        stepping = median(t.wall_time for t in trajs)
        evals = trajs[-1].evaluations / n_steps
        per_eval = stepping / trajs[-1].evaluations if trajs[-1].evaluations else nan
        # A composition of s substeps is s steps of its base method per step, by construction:
        # its guard is per substep (item 10 compares its cost per evaluation as for any method).
        composition = pl.get_method(method).composition
        substeps = composition.stages if composition is not None else 1
        ratio = cpu / c_cpu / substeps
        data["methods"][method] = {
            "cpu": cpu,
            "wall": wall,
            "stepping": stepping,
            "sweeps": trajs[-1].mean_iterations,
            "evals_per_step": evals,
            "ratio": ratio,
            "substeps": substeps,
        }
        rows.append(
            Row(
                "1",
                f"recompute {cfg.slider_t_end:g} s, {method}"
                + (f", per substep of {substeps}" if substeps > 1 else ""),
                f"{fmt_time(cpu)} ({fmt_time(wall)} wall)" if substeps == 1 else
                f"{fmt_time(cpu / substeps)} per substep ({fmt_time(cpu)} in all)",
                f"C RK4 {fmt_time(c_cpu)} ({fmt_time(c_wall)} wall)",
                f"{ratio:.1f}x",
                "ours/C <= 20 (CPU)",
                verdict(ratio, 20.0) if cloop is not None else "not available",
            )
        )
        details.append(
            f"| {method} | {fmt_time(cpu)} | {fmt_time(wall)} | {fmt_time(stepping)} | "
            f"{fmt_time(wall - stepping)} | {trajs[-1].mean_iterations:.2f} | {evals:.1f} | "
            f"{per_eval * 1e9:.0f} |"
        )
    details.append("")
    details.append(
        "'outside the loop' = validation, momenta, result arrays and the energies computed by "
        "`pl.simulate` after the compiled loop; ns/eval = stepping time per field evaluation."
    )
    one_step = [
        timed(
            pl.simulate, dp, theta0, omega0, t_end=cfg.dt, dt=cfg.dt, method="rk4", progress=False
        )
        for _ in range(21)
    ]
    call, loop = med([s for s, _ in one_step], "wall"), median(t.wall_time for _, t in one_step)
    data["one_step"] = {"call": call, "loop": loop}
    details.append(
        f"Fixed cost per call (a one-step rk4 `pl.simulate`, median of 21, wall): whole call "
        f"{fmt_time(call)}, of which the compiled loop's call {fmt_time(loop)}."
    )
    rows += _full_update(cfg, dp, data, details)
    return Section("slider", "1. Slider latency", rows, details, data)


def _full_update(cfg: Config, dp, data: dict, details: list[str]) -> list[Row]:
    """Time a slider change in the explorer (recompute + redraw + PNG), Agg backend."""
    try:
        from pendulum_lab import widgets
    except ImportError:
        widgets = None
    if widgets is None or not hasattr(widgets, "explore"):
        details.append("Full update: `pendulum_lab.widgets.explore` is not available.")
        return [Row("1", "full update incl. redraw", "-", "-", "-", "<= 50 ms", "not available")]
    import matplotlib

    matplotlib.use("Agg")
    ex = widgets.explore(dp, method="glrk4", t_end=cfg.slider_t_end, dt=cfg.dt)
    rows, data["full_update"] = [], {}
    details.append("")
    details.append(
        f"Full update: `ex = pl.widgets.explore(dp, t_end={cfg.slider_t_end:g}, dt={cfg.dt:g})`, "
        f"then `ex.controls['theta1'].value = x` with alternating x (recompute + redraw + PNG "
        f"encoding), {cfg.update_rounds} changes per method, medians. The verdict uses CPU time "
        "(what an idle machine would show); the wall time on this shared machine is given too. "
        "'redraw' = full update minus the method's recompute above (CPU). The explorer redraws "
        "the pieces of a panel's frame (axes, ticks, labels) that changed (`ex.background`); "
        "the frames reused and redrawn are counted below, and the last row redraws every frame."
    )
    slider = ex.controls["theta1"]

    def change(forget_frames=False):
        # a new value every time, or the slider would not fire
        x = round(THETA0[0] + (0.02 if slider.value == THETA0[0] + 0.01 else 0.01), 2)
        before = ex.trajectory
        if forget_frames:
            ex.background.clear()
        sample, _ = timed(setattr, slider, "value", x)
        return sample, ex.trajectory is not before and float(ex.trajectory.theta[0, 0]) == x

    frames = {"reused": 0, "redrawn": 0, "pieces": 0}
    for method in pl.METHODS:
        ex.controls["method"].value = method  # this update also warms the method up
        times, ok = [], True
        hits, misses, pieces = (ex.background.hits, ex.background.misses,
                                ex.background.pieces_drawn)
        for _ in range(cfg.update_rounds):
            sample, updated = change()
            ok = ok and updated
            times.append(sample)
        frames["reused"] += ex.background.hits - hits
        frames["redrawn"] += ex.background.misses - misses
        frames["pieces"] += ex.background.pieces_drawn - pieces
        cpu, wall = med(times), med(times, "wall")
        redraw = cpu - data["methods"][method]["cpu"]
        data["full_update"][method] = {"cpu": cpu, "wall": wall, "redraw": redraw, "updated": ok}
        status = verdict(cpu, 0.050) if ok else "ERROR (no update)"
        rows.append(
            Row(
                "1",
                f"full update incl. redraw, {method}",
                f"{fmt_time(cpu)} ({fmt_time(wall)} wall)",
                f"redraw {fmt_time(redraw)}",
                f"{cpu / 0.1:.2f} of 100 ms",
                "well under 100 ms (<= 50 ms CPU)",
                status,
            )
        )
    details.append(
        f"Frames (one per panel and change) in the timed changes above: {frames['reused']} "
        f"reused whole, {frames['redrawn']} redrawn in part ({frames['pieces']} pieces drawn: "
        "patch, x axis, y axis, titles, from the first that changed on)."
    )
    method = "glrk4"
    ex.controls["method"].value = method
    samples = [change(forget_frames=True)[0] for _ in range(cfg.update_rounds)]
    cpu, wall = med(samples), med(samples, "wall")
    data["full_update"]["every_frame_redrawn"] = {"method": method, "cpu": cpu, "wall": wall}
    rows.append(
        Row(
            "1",
            f"full update, every frame redrawn, {method}",
            f"{fmt_time(cpu)} ({fmt_time(wall)} wall)",
            f"redraw {fmt_time(cpu - data['methods'][method]['cpu'])}",
            f"{cpu / 0.1:.2f} of 100 ms",
            "(report)",
            "info",
        )
    )
    return rows
