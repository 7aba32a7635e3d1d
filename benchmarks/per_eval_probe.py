"""Measure the cost per field evaluation of every method, in a process of its own.

Run as ``python per_eval_probe.py JSON`` with ``JSON`` a dict of settings; it
prints one JSON line. Item 10 runs it twice side by side, once on the working
tree and once on an older revision of the package (``PYTHONPATH`` pointing at
an exported copy), so "before" and "after" are measured by the same code in
the same kind of process. Uses only the public API both revisions share
(``pl.simulate``, ``pl.METHODS``, ``Trajectory.evaluations``).

Per method: CPU time of ``pl.simulate`` over ``n_steps`` and over
``n_steps // 10`` steps (one trajectory, no states saved between), and the
cost per evaluation from the difference, which removes the fixed cost of a
call. ``floor``: the maximum relative energy error of a long ``glrk8`` run at
a step where the method's own error is far below round-off, i.e. the
round-off floor that compensated summation lowers.
"""

from __future__ import annotations

import json
import statistics
import sys
import time

import numpy as np


def _cpu(call):
    start = time.process_time()
    result = call()
    return time.process_time() - start, result


def measure(settings: dict) -> dict:
    import pendulum_lab as pl

    dp = pl.double_pendulum(m1=1.0, m2=1.0, l1=1.0, l2=1.0, g=9.81)
    theta0, dt = settings["theta0"], settings["dt"]
    long_steps = settings["n_steps"]
    short_steps = long_steps // 10
    methods = [m for m in settings["methods"] if m in pl.METHODS]

    def run(method, steps):
        return pl.simulate(dp, theta0, [0.0, 0.0], t_end=steps * dt, dt=dt, method=method,
                           save_every=steps, progress=False)

    out = {"methods": {}, "missing": [m for m in settings["methods"] if m not in pl.METHODS]}
    for method in methods:
        run(method, short_steps)  # compile or load
    for method in methods:
        long_cpu, short_cpu, evals = [], [], None
        for _ in range(settings["repeats"]):
            cpu, traj = _cpu(lambda m=method: run(m, long_steps))
            long_cpu.append(cpu)
            cpu, short = _cpu(lambda m=method: run(m, short_steps))
            short_cpu.append(cpu)
            evals = (traj.evaluations, short.evaluations, traj.mean_iterations)
        per_eval = (statistics.median(long_cpu) - statistics.median(short_cpu)) / (
            evals[0] - evals[1]
        )
        out["methods"][method] = {
            "ns_per_eval": per_eval * 1e9,
            "evals_per_step": evals[0] / long_steps,
            "sweeps": evals[2],
            "cpu_long": statistics.median(long_cpu),
        }
    floor = settings.get("floor")
    if floor:
        cpu, traj = _cpu(lambda: pl.simulate(dp, theta0, [0.0, 0.0], t_end=floor["t_end"],
                                             dt=floor["dt"], method=floor["method"],
                                             save_every=floor["save_every"], progress=False))
        energy = traj.energy
        error = np.abs(energy - energy[0]) / abs(energy[0])
        tail = error[error.size * 9 // 10:]
        out["floor"] = {"max": float(error.max()), "last_tenth": float(tail.max()), "cpu": cpu}
    return out


if __name__ == "__main__":
    print(json.dumps(measure(json.loads(sys.argv[1]))))
