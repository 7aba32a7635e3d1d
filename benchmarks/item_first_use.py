"""Item 2: first use in a fresh process against a bare ``import scipy.integrate, sympy``."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import tempfile

try:
    import resource
except ImportError:  # Windows: no resource usage of finished children
    resource = None

from harness import Config, Row, Sample, Section, fmt_time, interleave, med, timed, verdict

FIRST_USE = (
    "import pendulum_lab as pl; dp = pl.double_pendulum(); "
    "pl.simulate(dp, [2.0, 2.5], [0, 0], t_end=1.0, dt=0.01)"
)
BARE_IMPORTS = "import scipy.integrate; import sympy"
#: The import row: ``import pendulum_lab`` against the imports a student's notebook starts with.
IMPORT_OURS = "import pendulum_lab"
IMPORT_PEERS = "import scipy.integrate, sympy, matplotlib.pyplot"
PHASES = r"""
import json, time
t0 = time.perf_counter()
import pendulum_lab as pl
t1 = time.perf_counter()
dp = pl.double_pendulum()
t2 = time.perf_counter()
pl.simulate(dp, [2.0, 2.5], [0, 0], t_end=1.0, dt=0.01)
t3 = time.perf_counter()
pl.simulate(dp, [2.0, 2.5], [0, 0], t_end=1.0, dt=0.01)
t4 = time.perf_counter()
print(json.dumps({"import pendulum_lab": t1 - t0, "pl.double_pendulum()": t2 - t1,
                  "first pl.simulate (kernels loaded)": t3 - t2,
                  "second pl.simulate": t4 - t3}))
"""


def _children_cpu() -> float:
    """CPU seconds of the finished children (POSIX); NaN where the system does not count
    them (Windows), so the item reports its wall times without CPU."""
    if resource is None:
        return math.nan
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _fresh_process(code: str, env: dict | None = None) -> Sample:
    """Wall time of a fresh ``python -c code`` seen from outside, and the child's CPU time."""
    cpu = _children_cpu()
    sample, out = timed(
        subprocess.run,
        [sys.executable, "-c", code],
        env=env,
        capture_output=True,
        text=True,
        encoding="utf-8",
        errors="replace",
        check=False,
    )
    if out.returncode != 0:
        raise RuntimeError(f"fresh process failed: {out.stderr.strip()[-500:]}")
    return Sample(sample.wall, _children_cpu() - cpu)


def _cold_process(code: str) -> Sample:
    """A fresh process whose kernel cache and Numba cache are empty temporary folders."""
    with tempfile.TemporaryDirectory() as kernels, tempfile.TemporaryDirectory() as numba_dir:
        env = {k: v for k, v in os.environ.items() if k != "PENDULUM_LAB_SHARED_CACHE"}
        env |= {"PENDULUM_LAB_CACHE": kernels, "NUMBA_CACHE_DIR": numba_dir}
        return _fresh_process(code, env)


def bench_first_use(cfg: Config) -> Section:
    """Fresh process: import, model, 1 s simulation vs ``import scipy.integrate; import sympy``."""
    _fresh_process(FIRST_USE)  # fills the kernel cache (as any earlier use would have)
    _fresh_process(BARE_IMPORTS)
    samples = interleave(
        {
            "ours": lambda: _fresh_process(FIRST_USE),
            "peer": lambda: _fresh_process(BARE_IMPORTS),
            "python": lambda: _fresh_process("pass"),
        },
        cfg.first_use_runs,
    )
    ours, peer, bare = (med(samples[k], "wall") for k in ("ours", "peer", "python"))
    ours_cpu, peer_cpu = med(samples["ours"]), med(samples["peer"])
    ratio = ours / peer
    rows = [
        Row(
            "2",
            "first use (warm kernel cache)",
            fmt_time(ours),
            fmt_time(peer),
            f"{ratio:.2f}x",
            "ours/peer <= 3 (wall)",
            verdict(ratio, 3.0),
        )
    ]
    details = [
        f"Fresh `{sys.executable} -c ...` processes, wall time from outside (interpreter start "
        f"included for both), {cfg.first_use_runs} alternating runs each, medians. Ours: "
        f"`{FIRST_USE}` (default method glrk4). Peer: `{BARE_IMPORTS}`. A bare `python -c pass` "
        f"takes {fmt_time(bare)}. The verdict uses wall time (both jobs last seconds and include "
        f"file reads); by the children's CPU time: ours {fmt_time(ours_cpu)}, peer "
        f"{fmt_time(peer_cpu)}, ratio {ours_cpu / peer_cpu:.2f}.",
        "Samples, wall (s): "
        + "; ".join(f"{k} " + ", ".join(f"{x.wall:.2f}" for x in v) for k, v in samples.items()),
    ]
    data = {
        "ours": ours,
        "peer": peer,
        "python": bare,
        "ratio": ratio,
        "ours_cpu": ours_cpu,
        "peer_cpu": peer_cpu,
    }
    rows.append(_import_row(cfg, details, data))
    if cfg.cold_runs:
        cold_samples = interleave(
            {
                "cold": lambda: _cold_process(FIRST_USE),
                "peer": lambda: _fresh_process(BARE_IMPORTS),
            },
            cfg.cold_runs,
        )
        cold, cold_peer = med(cold_samples["cold"], "wall"), med(cold_samples["peer"], "wall")
        rows.append(
            Row(
                "2",
                "first use, COLD (empty kernel + Numba caches)",
                fmt_time(cold),
                fmt_time(cold_peer),
                f"{cold / cold_peer:.1f}x",
                "none (information)",
                "info",
            )
        )
        details.append(
            "Cold: `PENDULUM_LAB_CACHE` and `NUMBA_CACHE_DIR` set to new empty temporary "
            "folders, so kernels are generated from SymPy and everything is compiled by Numba: "
            f"what the very first use on a machine costs (once). {cfg.cold_runs} run(s), "
            f"median; CPU {fmt_time(med(cold_samples['cold']))}."
        )
        data["cold"] = cold
    else:
        rows.append(
            Row(
                "2",
                "first use, COLD (empty kernel + Numba caches)",
                "not measured",
                "-",
                "-",
                "none (information)",
                "info",
            )
        )
        details.append(
            "Cold first use (empty caches) is not measured in this configuration; "
            "the full run measures it."
        )
    phases = json.loads(
        subprocess.run(
            [sys.executable, "-c", PHASES], capture_output=True, text=True, encoding="utf-8",
            errors="replace", check=True,
        ).stdout
    )
    data["phases"] = phases
    details.append(
        "Where a warm first use spends its time (one fresh process): "
        + "; ".join(f"{k} {fmt_time(v)}" for k, v in phases.items())
        + "."
    )
    details.append(
        "Largest imports (`python -X importtime`, cumulative): "
        + "; ".join(f"{k} {fmt_time(v)}" for k, v in _import_times()[:6])
        + "."
    )
    return Section("first_use", "2. First use", rows, details, data)


def _import_row(cfg: Config, details: list, data: dict) -> Row:
    """``import pendulum_lab`` on a warm machine against the peers' imports, fresh processes.

    Nothing is compiled or loaded from the kernel cache at import (a first use does that and
    says so), so the import is the package's modules and its dependencies' imports.
    """
    samples = interleave(
        {
            "ours": lambda: _fresh_process(IMPORT_OURS),
            "peer": lambda: _fresh_process(IMPORT_PEERS),
        },
        cfg.first_use_runs,
    )
    ours, peer = med(samples["ours"], "wall"), med(samples["peer"], "wall")
    ratio = ours / peer
    details.append(
        f"Import: fresh processes, `{IMPORT_OURS}` against `{IMPORT_PEERS}`, "
        f"{cfg.first_use_runs} alternating runs each, medians of the wall time from outside; "
        f"by the children's CPU time: ours {fmt_time(med(samples['ours']))}, peer "
        f"{fmt_time(med(samples['peer']))}. Samples, wall (s): "
        + "; ".join(f"{k} " + ", ".join(f"{x.wall:.2f}" for x in v) for k, v in samples.items())
    )
    data["import"] = {"ours": ours, "peer": peer, "ratio": ratio}
    return Row("2", "import pendulum_lab (warm machine)", fmt_time(ours), fmt_time(peer),
               f"{ratio:.2f}x", "ours/peer <= 2 (wall)", verdict(ratio, 2.0))


def _import_times() -> list[tuple[str, float]]:
    """Cumulative import times of the heavy dependencies and of pendulum_lab's modules.

    From ``python -X importtime -c "import pendulum_lab"``; nested entries
    overlap (sympy is imported inside ``pendulum_lab.symbolic.mechanics``).
    """
    out = subprocess.run(
        [sys.executable, "-X", "importtime", "-c", "import pendulum_lab"],
        capture_output=True,
        text=True,
        encoding="utf-8",
        errors="replace",
        check=False,
    )
    heavy = {"numpy", "scipy", "sympy", "numba", "matplotlib", "ipywidgets", "tqdm", "llvmlite"}
    found = {}
    for line in out.stderr.splitlines():
        parts = line.removeprefix("import time:").split("|")
        if len(parts) != 3 or not parts[1].strip().isdigit():
            continue
        name = parts[2].strip()
        if name in heavy or name.startswith("pendulum_lab"):
            found[name] = int(parts[1]) * 1e-6
    return sorted(found.items(), key=lambda kv: -kv[1])
