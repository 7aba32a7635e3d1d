"""Item 7: how a variational step solves its implicit equation, fixed-point iteration or Newton.

Both solvers iterate the generated update of the discrete Legendre transform
``p0 = -D_1 L_d(q0, q1)`` to round-off with the same stopping rule; they
differ in the update (``q1 + h Mbar^-1 (p0 - p_k)`` or a Newton step with
the generated Jacobian). Measured side by side: CPU time of whole runs,
iterations per step, and how far each converges as the step grows.
"""

from __future__ import annotations

import numpy as np
from harness import Config, Row, Section, explorer_start, fmt_time, interleave, med, timed

import pendulum_lab as pl
from pendulum_lab.integrators import variational_method
from pendulum_lab.symbolic.discrete_mechanics import RULES

SOLVERS = ("fixed_point", "newton")
# A fast state for the convergence scan: |omega| = 7 rad/s.
FAST_THETA, FAST_OMEGA = np.array([0.3, -1.0]), np.array([4.0, -6.0])


def _reach(dp, method, steps) -> float:
    """The largest step of ``steps`` (increasing) up to which every step converged."""
    reached = 0.0
    for h in steps:
        try:
            pl.step(dp, FAST_THETA, FAST_OMEGA, dt=h, method=method)
        except pl.ConvergenceError:
            break
        reached = h
    return reached


def bench_variational(cfg: Config) -> Section:
    """Fixed-point iteration against Newton's method in the variational steps."""
    dp, theta0, omega0, _ = explorer_start()
    T, dt = cfg.variational_t_end, cfg.dt
    rows, details, data = [], [], {}
    steps = np.round(np.arange(0.05, 1.0, 0.05), 2)
    for rule in RULES:
        methods = {s: variational_method(rule, s) for s in SOLVERS}
        last = {}

        def contender(solver, methods=methods, last=last):
            def run():
                sample, traj = timed(pl.simulate, dp, theta0, omega0, t_end=T, dt=dt,
                                     method=methods[solver], progress=False)
                last[solver] = traj
                return sample

            return run

        for solver in SOLVERS:  # compile outside the timing
            pl.simulate(dp, theta0, omega0, t_end=2 * dt, dt=dt, method=methods[solver])
        samples = interleave({s: contender(s) for s in SOLVERS}, cfg.variational_rounds)
        cpu = {s: med(samples[s]) for s in SOLVERS}
        iterations = {s: last[s].mean_iterations for s in SOLVERS}
        reach = {s: _reach(dp, methods[s], steps) for s in SOLVERS}
        ratio = cpu["fixed_point"] / cpu["newton"]
        rows.append(Row(
            "7",
            f"variational_{rule}, dt={dt:g}, T={T:g}: fixed-point / Newton CPU time",
            f"fixed point {fmt_time(cpu['fixed_point'])}, {iterations['fixed_point']:.2f} it/step",
            f"Newton {fmt_time(cpu['newton'])}, {iterations['newton']:.2f} it/step",
            f"{ratio:.2f}",
            "(info: the registry uses fixed point)",
            "info",
        ))
        details.append(
            f"variational_{rule}: medians of {cfg.variational_rounds} interleaved round(s) of "
            f"CPU time (wall: fixed point {fmt_time(med(samples['fixed_point'], 'wall'))}, "
            f"Newton {fmt_time(med(samples['newton'], 'wall'))}). From theta = "
            f"{FAST_THETA.tolist()}, omega = {FAST_OMEGA.tolist()} rad/s, steps of 0.05 .. 0.95 s "
            f"converge up to {reach['fixed_point']:g} s (fixed point) and {reach['newton']:g} s "
            "(Newton); beyond a fold of the discrete equations Newton's method can converge to "
            "a root off the small-step branch (tests/integrators/test_variational.py)."
        )
        data[rule] = {"cpu": cpu, "iterations": iterations, "reach": reach, "ratio": ratio}
    return Section("variational", "7. Variational steps: fixed point or Newton", rows, details,
                   data)
