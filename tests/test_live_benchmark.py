"""Smoke test of benchmarks/live_widget.py: it runs and its byte count is the run's size.

No timing is asserted (timings belong to the benchmark run); the browser part is left out
here (the browser tests in tests/browser/test_live_widgets.py drive the same page).
"""

from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
COLUMNS = ["#", "benchmark", "ours", "peer", "ratio", "target", "result"]


@pytest.fixture(scope="module")
def live_widget():
    with pytest.MonkeyPatch.context() as mp:
        mp.syspath_prepend(str(BENCHMARKS))
        import live_widget as module
    return module


def test_kernel_items_run_and_return_well_formed_rows(live_widget):
    result = live_widget.bench_live(quick=True, browser=False)
    assert [row["#"] for row in result["rows"]] == ["7", "7"]
    for row in result["rows"]:
        assert list(row) == COLUMNS and all(isinstance(v, str) and v for v in row.values())
        assert row["result"] in {"PASS", "info"} or row["result"].startswith("MISS")
    kernel = result["data"]["kernel"]
    assert kernel["steps"] == 2000 and kernel["messages"] == 1
    # 2001 states of (2 angles, 3 energies, 1 energy error) as float32.
    assert kernel["buffer_bytes"] == 2001 * 6 * 4
    assert kernel["frames"] == 401 and kernel["image_bytes"] > kernel["buffer_bytes"]
    assert all(t > 0 for t in kernel["update_cpu"] + kernel["recompute_cpu"])
