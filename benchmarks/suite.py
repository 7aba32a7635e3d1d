"""The benchmark suite, items 1 to 14: ratios side by side.

One file per item (``item_slider.py`` ... ``item_live.py``) and a shared
harness (``harness.py``: configurations, result rows, interleaved timing, the
machine's description). This module lists the items and runs them;
``benchmarks/run.py`` is the command-line front end; see
``benchmarks/README.md`` for what each item measures and against which peer.

This directory is a folder of scripts, not a package: ``run.py`` (or a test)
puts it on ``sys.path`` before importing this module.
"""

from __future__ import annotations

import tempfile
import time

import c_yardstick
from harness import (
    COLUMNS,
    CONFIGS,
    FULL,
    QUICK,
    RESULTS,
    SMOKE,
    Config,
    Row,
    Section,
    double_pendulum,
    load_average,
    load_text,
    machine_description,
    verdict,
)
from item_bifurcation import bench_bifurcation
from item_browser import bench_browser
from item_c_limit import bench_c_limit
from item_distributed import bench_distributed
from item_ensemble import bench_ensemble
from item_first_use import bench_first_use
from item_live import bench_live
from item_long_chains import bench_long_chains
from item_long_run import bench_long_run
from item_peers import bench_heyoka, bench_pyhamsys
from item_per_eval import bench_per_eval
from item_report_glrk4 import bench_report_glrk4
from item_slider import bench_slider
from item_systems import bench_systems
from item_variational import bench_variational

__all__ = [
    "COLUMNS",
    "CONFIGS",
    "FULL",
    "ITEMS",
    "QUICK",
    "RESULTS",
    "SMOKE",
    "Config",
    "Row",
    "Section",
    "c_yardstick",
    "load_average",
    "load_text",
    "machine_description",
    "resolve",
    "run_items",
    "verdict",
]

# =========================================================================== running
ITEMS = {
    "slider": (1, bench_slider, True),
    "first_use": (2, bench_first_use, False),
    "long_run": (3, bench_long_run, False),
    "report_glrk4": (4, bench_report_glrk4, False),
    "ensemble": (5, bench_ensemble, True),
    "c_limit": (6, bench_c_limit, True),
    "variational": (7, bench_variational, False),
    "bifurcation": (8, bench_bifurcation, False),
    "live": (9, bench_live, False),
    "per_eval": (10, bench_per_eval, True),
    "heyoka": (11, bench_heyoka, False),
    "pyhamsys": (12, bench_pyhamsys, False),
    "long_chains": (13, bench_long_chains, False),
    "distributed": (14, bench_distributed, False),
    "systems": (15, bench_systems, False),
    "browser": (16, bench_browser, False),
}


def resolve(names) -> list[str]:
    """Item keys from names or numbers (``"slider"``, ``"1"``); all items for none."""
    if not names:
        return list(ITEMS)
    by_number = {str(number): key for key, (number, _, _) in ITEMS.items()}
    keys = []
    for name in names:
        key = by_number.get(str(name), str(name).replace("-", "_"))
        if key not in ITEMS:
            raise ValueError(
                f"unknown benchmark {name!r}; choose from {list(ITEMS)} or 1-{len(ITEMS)}"
            )
        keys.append(key)
    return sorted(set(keys), key=lambda k: ITEMS[k][0])


def run_items(cfg: Config, keys, log=print) -> list[Section]:
    """Build the C loop if needed, run the items in order, never let one failure stop the rest."""
    sections = []
    with tempfile.TemporaryDirectory(prefix="pendulum_bench_") as tmp:
        cloop, c_error = None, ""
        if any(ITEMS[k][2] for k in keys):
            try:
                cloop = c_yardstick.build(double_pendulum(), tmp)
            except RuntimeError as err:
                c_error = str(err)
        for key in keys:
            number, fn, needs_c = ITEMS[key]
            log(f"[{time.strftime('%H:%M:%S')}] item {number}: {key} ...")
            start = time.perf_counter()
            try:
                section = fn(cfg, cloop) if needs_c else fn(cfg)
            except Exception as err:  # noqa: BLE001 - report and go on to the next item
                section = Section(
                    key,
                    f"{number}. {key}",
                    [Row(str(number), key, "-", "-", "-", "-", "ERROR")],
                    [f"ERROR: {type(err).__name__}: {err}"],
                    {},
                )
            if needs_c and cloop is None and c_error:
                section.details.append(f"C loop unavailable: {c_error}")
            section.seconds = time.perf_counter() - start
            log(f"    done in {section.seconds:.1f} s")
            sections.append(section)
    return sections
