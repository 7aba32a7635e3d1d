"""Item 13: long chains: first use for n = 10, 20, 50 and the cost per step against n.

Three measurements, each side by side in this run:

* first use in a fresh process (import, ``pl.n_pendulum(n)``, a 1 s ``glrk4``
  run; warm compiler cache), for the long chains against the double
  pendulum's, with their targets (n = 20 under 5 s, n = 50 under 30 s);
* one evaluation of Hamilton's equations, the kernels that loop over the
  links (every chain longer than two links) against the kernels printed from
  the expanded expressions, for three to five links;
* the cost per step of ``glrk4`` and ``rk4`` against ``n``, with the slope of
  its log-log fit (1 for linear growth, 2 for the ``n^2`` of building ``M``,
  3 for a dense solve).
"""

from __future__ import annotations

import numba
import numpy as np
from harness import Config, Row, Section, fmt_time, interleave, med, timed, verdict
from item_first_use import _fresh_process
from numba import types

import pendulum_lab as pl
from pendulum_lab import codegen
from pendulum_lab.codegen.signatures import HAMILTON, VECTOR

#: The two kernels are compared as first-class functions, the same call for both.
HamiltonFn = types.FunctionType(HAMILTON)

FIRST_USE = (
    "import numpy as np; import pendulum_lab as pl; m = pl.n_pendulum({n}); "
    "pl.simulate(m, np.full({n}, 0.5), np.zeros({n}), t_end=1.0, dt=0.01, method='glrk4')"
)
#: The targets for first use [s]; the other sizes are reported for information.
FIRST_USE_TARGETS = {20: 5.0, 50: 30.0}


@numba.njit(types.float64(HamiltonFn, VECTOR, VECTOR, VECTOR, types.int64), cache=True)
def _evaluate(hamilton, q, p, params, count):
    """Call ``hamilton`` ``count`` times as the integrators do (a first-class function)."""
    dq, dp = np.empty(q.size), np.empty(q.size)
    total = 0.0
    for _ in range(count):
        hamilton(0.0, q, p, params, dq, dp)
        total += dq[0] + dp[-1]  # keeps the calls from being optimised away
    return total


def _chain_state(n):
    theta, p = np.linspace(0.5, 0.1, n), np.linspace(0.2, -0.2, n)
    return theta, p, codegen.parameters_array(np.ones(n), np.ones(n), 9.81)


def bench_long_chains(cfg: Config) -> Section:
    rows, details, data = [], [], {"first_use": {}, "evaluation": {}, "per_step": {}}

    # ---- first use in fresh processes
    sizes = (2, *cfg.chain_first_use)
    for n in sizes:  # fills the caches, as any earlier use on this machine would have
        _fresh_process(FIRST_USE.format(n=n))
    samples = interleave({n: (lambda n=n: _fresh_process(FIRST_USE.format(n=n))) for n in sizes},
                         cfg.chain_rounds)
    base = med(samples[2], "wall")
    for n in cfg.chain_first_use:
        seconds = med(samples[n], "wall")
        data["first_use"][n] = seconds
        target = FIRST_USE_TARGETS.get(n)
        rows.append(Row("13", f"first use, n_pendulum({n}) + 1 s glrk4, fresh process",
                        fmt_time(seconds), f"n = 2: {fmt_time(base)}", f"{seconds / base:.2f}x",
                        f"< {target:g} s" if target else "(info)",
                        verdict(seconds, target) if target else "info"))
    details.append(f"First use: fresh `python -c \"{FIRST_USE.format(n='n')}\"` (warm kernel and "
                   f"Numba caches), wall time seen from outside, median of {cfg.chain_rounds} "
                   f"interleaved round(s); import alone is about a second of it. Ratio: against "
                   f"the same for the double pendulum.")

    # ---- one evaluation: looped kernels against printed ones
    for n in cfg.chain_printed:
        theta, p, params = _chain_state(n)
        printed = codegen.load_kernels(n, looped=False).hamilton
        looped = codegen.load_kernels(n, looped=True).hamilton
        assert np.isclose(_evaluate(printed, theta, p, params, 3),
                          _evaluate(looped, theta, p, params, 3), rtol=1e-12)
        count = cfg.chain_evaluations
        calls = {name: (_evaluate, kernel, theta, p, params, count)
                 for name, kernel in (("printed", printed), ("looped", looped))}
        found = interleave({name: (lambda args=args: timed(*args)[0])
                            for name, args in calls.items()}, cfg.chain_rounds)
        printed_s, looped_s = (med(found[name]) / count for name in ("printed", "looped"))
        data["evaluation"][n] = {"printed": printed_s, "looped": looped_s}
        rows.append(Row("13", f"Hamilton's equations, {n} links, one evaluation",
                        f"looped {fmt_time(looped_s)}", f"printed {fmt_time(printed_s)}",
                        f"{looped_s / printed_s:.2f}x", "looped/printed (info)", "info"))
    details.append(f"One evaluation: {cfg.chain_evaluations} calls of `hamilton` from a compiled "
                   "loop through a first-class function (as the integrators call it), CPU time "
                   "per call, median of the rounds. 'printed' = the kernels generated from the "
                   "SymPy expressions (what chains of every length used before the looped "
                   "kernels), "
                   "'looped' = pendulum_lab.codegen.long_chains (what every chain of three or more "
                   "links uses now).")

    # ---- cost per step against n
    # One small step for every n: the fastest normal mode grows like sqrt(n) (about 85 rad/s
    # at 200 unit links), and GL4's fixed-point iteration needs h omega well below 1.
    for method, dt in (("glrk4", 0.001), ("rk4", 0.001)):
        costs, evaluations = [], []
        for n in cfg.chain_sizes:
            chain = pl.n_pendulum(n)
            theta0, omega0 = np.linspace(0.5, 0.1, n), np.zeros(n)
            steps = max(10, cfg.chain_step_budget // n)

            def run(chain=chain, theta0=theta0, omega0=omega0, steps=steps, dt=dt,
                    method=method):
                return pl.simulate(chain, theta0, omega0, t_end=steps * dt, dt=dt,
                                   method=method, keep="final", progress=False)

            run()  # kernels loaded
            found = interleave({"run": lambda run=run: timed(run)[0]}, cfg.chain_rounds)
            traj = run()
            per_step = med(found["run"]) / steps
            costs.append(per_step)
            evaluations.append(traj.evaluations / steps)
        sizes = np.array(cfg.chain_sizes, float)
        per_eval = np.array(costs) / np.array(evaluations)
        tail = sizes >= 10
        slope_step = float(np.polyfit(np.log(sizes[tail]), np.log(costs)[tail], 1)[0])
        slope_eval = float(np.polyfit(np.log(sizes[tail]), np.log(per_eval[tail]), 1)[0])
        data["per_step"][method] = {
            "n": list(cfg.chain_sizes), "per_step": costs, "evaluations_per_step": evaluations,
            "slope_per_step": slope_step, "slope_per_evaluation": slope_eval}
        table = ", ".join(f"n={n}: {fmt_time(c)}" for n, c in zip(cfg.chain_sizes, costs))
        rows.append(Row("13", f"{method} cost per step against n ({cfg.chain_sizes[0]}.."
                             f"{cfg.chain_sizes[-1]} links)",
                        f"slope {slope_step:.2f} per step, {slope_eval:.2f} per evaluation",
                        "n^2 (build M) .. n^3 (dense solve)", f"{costs[-1] / costs[0]:.1f}x",
                        "slope per evaluation <= 2", verdict(slope_eval, 2.0)))
        details.append(f"{method}, dt = {dt:g}, CPU time per step (median of {cfg.chain_rounds}"
                       f"): {table}; field evaluations per step: "
                       + ", ".join(f"{e:.1f}" for e in evaluations)
                       + f". Slopes of the log-log fit over n >= 10: per step {slope_step:.2f}, "
                       f"per evaluation {slope_eval:.2f}. The ratio column: the largest chain "
                       f"against the smallest, per step.")
    return Section("long_chains", "13. Long chains", rows, details, data)
