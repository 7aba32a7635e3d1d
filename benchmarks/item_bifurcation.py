"""Item 8: a bifurcation diagram of the damped, driven pendulum, against the C RK4 loop.

``chaos.bifurcation_diagram`` over the drive amplitude runs every value as one
member of a single ensemble (a model family, one parameter row per member).
The target: 600 values x 300 drive periods after a 300-period
transient at 100 steps per period in under 30 s on 2 cores. The C yardstick is
the same RK4 on the same equations (``c_yardstick.build(pl.driven_pendulum())``),
timed on a slice of the members in the same run; the ratio is CPU time per
member-step, ours over C's.
"""

from __future__ import annotations

import os
import tempfile

import c_yardstick
import numpy as np
from harness import Config, Row, Sample, Section, fmt_time, interleave, med, median, timed, verdict

import pendulum_lab as pl
from pendulum_lab import chaos

#: The target for the full configuration [s, on 2 cores].
TARGET_SECONDS = 30.0
AMPLITUDES = (0.9, 1.5)


def bench_bifurcation(cfg: Config) -> Section:
    """The diagram's time (CPU and wall) and its cost per member-step against C's."""
    model = pl.driven_pendulum()
    values = np.linspace(*AMPLITUDES, cfg.bif_values)
    steps = cfg.bif_steps_per_period
    n_steps = (cfg.bif_transient + cfg.bif_periods) * steps
    work = cfg.bif_values * n_steps  # member-steps
    kwargs = dict(theta0=[0.2], omega0=[0.0], n_periods=cfg.bif_periods,
                  transient_periods=cfg.bif_transient, steps_per_period=steps, method="rk4",
                  max_period=min(16, cfg.bif_periods // 2), progress=False)
    chaos.bifurcation_diagram(model, "drive_amplitude", values[:2], **(kwargs | dict(
        n_periods=2, transient_periods=0, max_period=1)))  # load the compiled kernels
    last = {}

    def ours():
        sample, diagram = timed(chaos.bifurcation_diagram, model, "drive_amplitude", values,
                                **kwargs)
        last["diagram"] = diagram
        return sample

    contenders = {"ours": ours}
    c_members = max(1, min(cfg.bif_values, cfg.bif_c_members))
    rows, details = [], []
    with tempfile.TemporaryDirectory(prefix="pendulum_bench_") as tmp:
        try:
            cloop = c_yardstick.build(model, tmp)
        except RuntimeError as err:
            cloop = None
            details.append(f"C loop unavailable: {err}")
        if cloop is not None:
            theta0 = np.full((c_members, 1), 0.2)
            p0 = model.momenta(theta0, np.zeros_like(theta0))
            dt = model.drive_period / steps

            def c_loop():
                run = cloop.ensemble(theta0, p0, n_steps, dt)
                last["C"] = run
                return Sample(median(run.seconds), median(run.cpu))

            contenders["C"] = c_loop
        samples = interleave(contenders, cfg.bif_rounds)
        if cloop is not None:
            # the same arithmetic: C's end state is ours, for the model's own amplitude
            ref = pl.simulate(model, [0.2], [0.0], t_end=n_steps * dt, dt=dt, method="rk4",
                              keep="final", progress=False)
            gap = float(max(np.max(np.abs(last["C"].theta - ref.theta[-1])),
                            np.max(np.abs(last["C"].p - ref.p[-1]))))
    wall, cpu = med(samples["ours"], "wall"), med(samples["ours"], "cpu")
    cores = os.cpu_count() or 1
    two_core = cpu / min(2, cores)  # what an idle 2-core machine would take
    data = {"values": cfg.bif_values, "n_steps": n_steps, "work": work, "wall": wall,
            "cpu": cpu, "two_core_estimate": two_core}
    name = (f"bifurcation diagram {cfg.bif_values} values x {cfg.bif_periods} periods "
            f"(+{cfg.bif_transient} transient), {steps} steps/period")
    target = TARGET_SECONDS * work / (600 * 600 * 100)  # scaled for reduced configurations
    rows.append(Row("8", name, f"{fmt_time(wall)} wall, {fmt_time(cpu)} CPU",
                    f"target {fmt_time(target)} on 2 cores", f"{two_core / target:.2f}x",
                    "CPU / 2 cores <= target", verdict(two_core / target, 1.0)))
    details.append(
        f"`chaos.bifurcation_diagram(pl.driven_pendulum(), 'drive_amplitude', "
        f"np.linspace(0.9, 1.5, {cfg.bif_values}), theta0=[0.2], omega0=[0.0], "
        f"n_periods={cfg.bif_periods}, transient_periods={cfg.bif_transient}, "
        f"steps_per_period={steps}, method='rk4')`: one ensemble run of {cfg.bif_values} "
        f"members x {n_steps} steps = {work:.3g} member-steps; {cfg.bif_rounds} round(s), "
        f"medians: {fmt_time(wall)} wall, {fmt_time(cpu)} CPU (cores effectively used "
        f"{cpu / wall:.2f} of {cores}). The verdict uses CPU / 2, what an idle 2-core machine "
        f"would need; the wall time depends on the load."
    )
    if "C" in samples:
        c_cpu = med(samples["C"], "cpu")
        c_step = c_cpu / (c_members * n_steps)
        our_step = cpu / work
        data |= {"c_step": c_step, "our_step": our_step, "ratio": our_step / c_step, "gap": gap}
        rows.append(Row("8", "bifurcation diagram per member-step vs C RK4 (same equations)",
                        f"{our_step * 1e9:.0f} ns/CPU", f"C {c_step * 1e9:.0f} ns/CPU",
                        f"{our_step / c_step:.1f}x", "(info: ours/C per step)", "info"))
        rows.append(Row("8", "C vs pl.simulate rk4 on the driven pendulum: end state",
                        f"max |diff| = {gap:.2g}", "-", "-", "<= 1e-9",
                        "PASS" if gap <= 1e-9 else "MISS"))
        details.append(
            f"C yardstick: RK4 on the damped, driven pendulum generated from "
            f"`pl.derive_chain(1, forced=True)` (`{cloop.command}`), {c_members} members x "
            f"{n_steps} steps on one thread: {fmt_time(c_cpu)} CPU, {c_step * 1e9:.0f} ns per "
            f"step; ours {our_step * 1e9:.0f} ns per member-step (CPU, all threads, including "
            f"the sampling, the conversions and the period detection). The whole diagram at "
            f"C's rate on 2 cores: {fmt_time(c_step * work / 2)}."
        )
    if "diagram" in last:
        doublings = ", ".join(f"{d.period}->{2 * d.period} at {d.value:.4f}"
                              for d in last["diagram"].doublings())
        details.append(f"Period doublings found in the data: {doublings or 'none'}.")
    return Section("bifurcation", "8. Bifurcation diagram", rows, details, data)
