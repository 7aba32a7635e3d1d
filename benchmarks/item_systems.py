"""Item 15: systems described by their points against chains of the same number of coordinates.

Two measurements per system (the elastic pendulum, the cart pendulum and the spherical
pendulum, whose bob moves in space, against the double pendulum; the Kapitza pendulum against
the driven pendulum, the chain of one link whose field also depends on the time through a
cosine):

* **first use**: in a fresh process with an empty kernel cache, the seconds from
  ``import pendulum_lab`` to the end of a first ``pl.simulate`` with RK4: building the model
  (for a system, its symbolic derivation), generating and compiling its kernels and RK4's loop;
* **cost per evaluation**: CPU time of ``pl.simulate`` with RK4 over ``systems_steps`` and a
  tenth of them (the fixed cost of a call cancels in the difference), divided by the
  difference of the field evaluations (four per step); the system and its chain take turns in
  the same interleaved rounds; medians. This is measured in ``systems_processes`` fresh
  processes, and the ratio reported is the median of theirs: the same compiled kernels run
  up to 1.7 times as fast in one process as in the next (also with address-space
  randomisation off; the cause was not found), while the rounds within a process vary less,
  so one process decides nothing.

The target: a system's evaluation within 1.5x of the chain's of the same size.
"""

from __future__ import annotations

import os
import tempfile
from statistics import median

from harness import Config, Row, Section, child_json, fmt_time, interleave, med, timed

import pendulum_lab as pl

#: A system's cost per evaluation, at most this many times the chain's of the same size.
TARGET = 1.5
#: The time step of the timed runs: fine enough for the Kapitza pendulum's shaking (100 rad/s).
DT = 0.001
#: ``{name: (factory, initial angles, chain of the same size, its initial angles)}``.
SYSTEMS = {
    "elastic": ("elastic_pendulum", [1.05, 0.5], "double_pendulum", [1.0, 0.5]),
    "cart": ("cart_pendulum", [0.0, 1.0], "double_pendulum", [1.0, 0.5]),
    "kapitza": ("kapitza_pendulum", [3.0], "driven_pendulum", [1.0]),
    "spherical": ("spherical_pendulum", [0.3, 0.0], "double_pendulum", [1.0, 0.5]),
}

_FIRST_USE = """
import json, time
start = time.perf_counter()
import pendulum_lab as pl
model = getattr(pl, {factory!r})()
built = time.perf_counter()
pl.simulate(model, {theta0!r}, [0.0] * model.n, t_end=0.02, dt=0.01, method="rk4")
print(json.dumps({{"build": built - start, "total": time.perf_counter() - start}}))
"""


_PER_EVALUATION = """
import json, sys
sys.path.insert(0, {here!r})
from item_systems import per_evaluation_pair
print(json.dumps(per_evaluation_pair({name!r}, {steps}, {rounds})))
"""


def _in_fresh_process(name: str, steps: int, rounds: int) -> dict:
    """:func:`per_evaluation_pair` in a new Python process (sharing the kernel cache)."""
    code = _PER_EVALUATION.format(here=os.path.dirname(os.path.abspath(__file__)), name=name,
                                  steps=steps, rounds=rounds)
    return child_json(["-c", code], f"timing {name}")


def _first_use(factory: str, theta0: list) -> dict:
    """Seconds of a first use in a fresh process with an empty kernel cache."""
    with tempfile.TemporaryDirectory(prefix="pendulum_systems_") as cache:
        env = dict(os.environ, PENDULUM_LAB_CACHE=cache)
        return child_json(["-c", _FIRST_USE.format(factory=factory, theta0=theta0)],
                          f"first use of {factory}", env=env)


def _runs(model, theta0, steps: int, dt: float) -> dict:
    """Timed RK4 runs of ``model`` over ``steps`` and a tenth of them (compiled first)."""
    omega0 = [0.0] * model.n
    pl.simulate(model, theta0, omega0, t_end=2 * dt, dt=dt, method="rk4")

    def run(n):
        def go():
            sample, _ = timed(pl.simulate, model, theta0, omega0, t_end=n * dt, dt=dt,
                              method="rk4", keep="final", progress=False)
            return sample
        return go

    return {"long": run(steps), "short": run(steps // 10)}


def _per_evaluation(samples: dict, prefix: str, steps: int) -> float:
    """Median CPU seconds per field evaluation (four per RK4 step) from the samples of
    :func:`_runs` stored under ``prefix``."""
    difference = med(samples[prefix + "long"]) - med(samples[prefix + "short"])
    return difference / (4 * (steps - steps // 10))


def per_evaluation_pair(name: str, steps: int, rounds: int) -> dict:
    """Seconds per field evaluation of the system ``name`` and of its chain, in this process:
    the two take turns in ``rounds`` interleaved rounds, so that a slow spell of a shared
    machine falls on both."""
    factory, theta0, chain, chain_theta0 = SYSTEMS[name]
    contenders = {f"system {k}": v for k, v in
                  _runs(getattr(pl, factory)(), theta0, steps, DT).items()}
    contenders |= {f"chain {k}": v for k, v in
                   _runs(getattr(pl, chain)(), chain_theta0, steps, DT).items()}
    samples = interleave(contenders, rounds)
    return {"system": _per_evaluation(samples, "system ", steps),
            "chain": _per_evaluation(samples, "chain ", steps)}


def bench_systems(cfg: Config) -> Section:
    """First use and cost per evaluation of four systems against chains of their size."""
    rows, details, data = [], [], {}
    steps = cfg.systems_steps
    for name, (factory, theta0, chain, chain_theta0) in SYSTEMS.items():
        pairs = [_in_fresh_process(name, steps, cfg.systems_rounds)
                 for _ in range(cfg.systems_processes)]
        ratios = sorted(pair["system"] / pair["chain"] for pair in pairs)
        ours, theirs = (median(pair[k] for pair in pairs) for k in ("system", "chain"))
        ratio = median(ratios)
        rows.append(Row("15", f"{name} ({len(theta0)} coordinates), RK4: cost per evaluation",
                        f"{ours * 1e9:.0f} ns", f"{chain} {theirs * 1e9:.0f} ns",
                        f"{ratio:.2f}", f"<= {TARGET}", _verdict(ratio)))
        details.append(f"{name}: the ratio in each of {len(ratios)} process(es): "
                       + ", ".join(f"{r:.2f}" for r in ratios) + ".")
        entry = {"per_eval": ours, "chain_per_eval": theirs, "ratio": ratio,
                 "ratios_by_process": ratios}
        if cfg.systems_first_use:
            first, first_chain = _first_use(factory, theta0), _first_use(chain, chain_theta0)
            first_ratio = first["total"] / first_chain["total"]
            rows.append(Row("15", f"{name}: first use (build, kernels, first simulate), cold "
                                  "cache", fmt_time(first["total"]),
                            f"{chain} {fmt_time(first_chain['total'])}", f"{first_ratio:.2f}",
                            "(info)", "info"))
            entry |= {"first_use": first, "chain_first_use": first_chain,
                      "first_use_ratio": first_ratio}
        data[name] = entry
    details.append(
        f"RK4 at dt = {DT:g}: CPU time over {steps} steps minus over a tenth of them, per "
        f"evaluation (4 per step), medians of {cfg.systems_rounds} interleaved round(s) in "
        "which the system and its chain take turns, in each of "
        f"{cfg.systems_processes} fresh process(es); the ratio is the median of the "
        "processes' ratios. "
        "First use: a fresh process with an empty kernel cache, from `import pendulum_lab` to "
        "the end of a first `pl.simulate` with RK4 (the system's time includes its symbolic "
        "derivation; both compile their kernels and RK4's loop)"
        + ("." if cfg.systems_first_use else " (not run in this configuration)."))
    return Section("systems", "15. Systems given by their points against chains", rows, details,
                   data)


def _verdict(ratio: float) -> str:
    from harness import verdict

    return verdict(ratio, TARGET)
