"""Run pendulum_lab's benchmark suite and write the results table.

Usage (from the repository root; ``make bench`` runs the first line)::

    .venv/bin/python benchmarks/run.py                  # full run, ~3-5 min
    .venv/bin/python benchmarks/run.py --quick          # short smoke run, ~30 s
    .venv/bin/python benchmarks/run.py --only slider --only 5
    .venv/bin/python benchmarks/run.py --out /tmp/bench.md

The table is printed and written as Markdown to
``benchmarks/results/YYYY-MM-DD_HHMM[-quick|-partial].md``; a full run also
copies it to ``benchmarks/results/latest.md``. ``--out FILE`` writes only FILE.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))

import matplotlib  # noqa: E402

matplotlib.use("Agg")

import suite  # noqa: E402


def markdown(cfg, machine: dict, sections, keys, seconds: float) -> str:
    """The whole results file: header with the machine, the table, the details."""
    m = machine
    env = ", ".join(f"{k}={v}" for k, v in m["env"].items()) or "none set"
    load_start, load_end = suite.load_text(m["load_start"]), suite.load_text(m["load_end"])
    versions = ", ".join(f"{k} {v}" for k, v in m["versions"].items())
    lines = [
        f"# pendulum_lab benchmarks ({cfg.name} run, {m['date']})",
        "",
        "Every figure with a target is a ratio of two contenders measured side by side in this "
        "run (interleaved rounds, medians). See `benchmarks/README.md` for what each item "
        "measures.",
        "",
    ]
    if cfg.name != "full":
        lines += [
            f"**{cfg.name.upper()} run: reduced sizes and repetitions; the figures are "
            "indicative only, the targets refer to the full run.**",
            "",
        ]
    lines += [
        "## Machine",
        "",
        f"- CPU: {m['cpu']}; {m['cores']} logical cores (os.cpu_count), "
        f"{m['cores_available']} available to this process; Numba threads "
        f"{m['numba_threads']}",
        f"- Load average (1, 5, 15 min) at start: {load_start}; at end: {load_end} "
        "(the machine is shared: other work was running)",
        f"- {m['platform']}; Python {m['python']}; {versions}",
        f"- C compiler: {m['compiler']}",
        f"- Thread-related environment variables (OPENBLAS_*, OMP_*, MKL_*, NUMBA_*, "
        f"PENDULUM_LAB_*): {env}",
        f"- pendulum_lab {m['pendulum_lab']}, git {m['git']}",
        f"- Items run: {', '.join(keys)}; total wall time of this run: {seconds / 60:.1f} min "
        f"({seconds:.0f} s)",
        "",
        "## Results",
        "",
        "| " + " | ".join(suite.COLUMNS) + " |",
        "|" + "---|" * len(suite.COLUMNS),
    ]
    for section in sections:
        for row in section.rows:
            lines.append("| " + " | ".join(c.replace("|", "/") for c in row.cells()) + " |")
    lines += ["", "## Details", ""]
    for section in sections:
        lines += [f"### {section.title} ({section.seconds:.0f} s)", ""]
        lines += _paragraphs(section.details)
        lines.append("")
    return "\n".join(lines).rstrip() + "\n"


def _paragraphs(details: list[str]) -> list[str]:
    """Detail lines become paragraphs; Markdown table lines stay together."""
    out = []
    for line in details:
        if line.startswith("|"):
            out.append(line)
        elif line:
            out += [line, ""]
        else:
            out.append("")
    return out


def text_table(sections) -> str:
    """The results table as aligned plain text, for the terminal."""
    rows = [suite.COLUMNS] + [row.cells() for s in sections for row in s.rows]
    widths = [max(len(r[i]) for r in rows) for i in range(len(suite.COLUMNS))]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    lines = [fmt.format(*rows[0]), fmt.format(*("-" * w for w in widths))]
    lines += [fmt.format(*r) for r in rows[1:]]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--quick",
        action="store_true",
        help="short smoke run: small sizes, one round, cached item-3 search",
    )
    parser.add_argument(
        "--only",
        action="append",
        metavar="NAME",
        help=f"run only this item (repeatable): {', '.join(suite.ITEMS)} or 1-{len(suite.ITEMS)}",
    )
    parser.add_argument(
        "--out", type=Path, metavar="FILE", help="write the Markdown table here (and nowhere else)"
    )
    args = parser.parse_args(argv)
    try:
        keys = suite.resolve(args.only)
    except ValueError as err:
        parser.error(str(err))
    cfg = suite.QUICK if args.quick else suite.FULL
    machine = suite.machine_description()
    print(
        f"pendulum_lab benchmarks, {cfg.name} run; load average {machine['load_start']}", flush=True
    )
    start = time.perf_counter()
    sections = suite.run_items(cfg, keys, log=lambda msg: print(msg, flush=True))
    seconds = time.perf_counter() - start
    machine["load_end"] = suite.load_average()
    text = markdown(cfg, machine, sections, keys, seconds)
    print()
    print(text_table(sections))
    print(f"\ntotal {seconds:.0f} s")

    suffix = None
    if args.out is not None:
        targets = [args.out]
    else:
        suffix = (
            ""
            if (cfg.name == "full" and keys == list(suite.ITEMS))
            else ("-quick" if cfg.name == "quick" else "-partial")
        )
        stamp = time.strftime("%Y-%m-%d_%H%M")
        targets = [suite.RESULTS / f"{stamp}{suffix}.md"]
    for target in targets:
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(text, encoding="utf-8")
        print(f"written: {target}")
    if suffix == "":
        latest = suite.RESULTS / "latest.md"
        shutil.copyfile(targets[0], latest)
        print(f"written: {latest}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
