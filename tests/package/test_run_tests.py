"""The suite runner (tools/run_tests.py): its queue keeps to the number of workers and its
order, the jobs beside the queue start at once; it reports each job's CPU minutes where the
operating system counts them (the POSIX branch for real, Windows, without the ``resource``
module, by emulation)."""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
import time
from pathlib import Path

import pytest

TOOL = Path(__file__).resolve().parents[2] / "tools" / "run_tests.py"


@pytest.fixture(scope="module")
def run_tests():
    spec = importlib.util.spec_from_file_location("run_tests_tool", TOOL)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.skipif(sys.platform == "win32", reason="the resource module is POSIX")
def test_a_reaped_child_s_cpu_time_is_counted(run_tests):
    before = run_tests.children_cpu_seconds()
    subprocess.run([sys.executable, "-c", "sum(i * i for i in range(3_000_000))"], check=True)
    assert run_tests.children_cpu_seconds() - before > 0.05
    # the control: nothing reaped, nothing counted
    again = run_tests.children_cpu_seconds()
    assert run_tests.children_cpu_seconds() == again


def test_without_the_resource_module_no_cpu_time_is_claimed(run_tests, monkeypatch):
    monkeypatch.setitem(sys.modules, "resource", None)  # import resource raises ImportError
    assert run_tests.children_cpu_seconds() is None


def _job(folder: Path, name: str, seconds: float, code: int = 0):
    """A job that records when it started and ended, sleeps, and exits with ``code``."""
    script = (f"import json, sys, time; t = time.time(); time.sleep({seconds}); "
              f"open({str(folder / name)!r}, 'w').write(json.dumps([t, time.time()])); "
              f"sys.exit({code})")
    return [sys.executable, "-c", script], None


def _spans(folder: Path, names) -> dict[str, list[float]]:
    return {name: json.loads((folder / name).read_text()) for name in names}


def _overlap(a, b) -> bool:
    return a[0] < b[1] and b[0] < a[1]


def test_the_queue_keeps_its_workers_and_order_and_the_beside_jobs_start_at_once(
        run_tests, tmp_path, capsys):
    jobs = {name: _job(tmp_path, name, 0.3) for name in ("first", "second", "third")}
    jobs["beside"] = _job(tmp_path, "beside", 2.5, code=3)
    started = time.time()
    code = run_tests.run_jobs(jobs, ["first", "second", "third"], ["beside"], workers=1)
    spans = _spans(tmp_path, jobs)
    assert code == 3  # the highest exit code, here the beside job's
    assert spans["beside"][0] - started < 1.0
    # one worker: the queued jobs one after the other, in order, while the beside job runs
    assert spans["first"][1] <= spans["second"][0] and spans["second"][1] <= spans["third"][0]
    assert _overlap(spans["beside"], spans["first"])
    assert "whole suite" in capsys.readouterr().out
    # the control: with two workers the first two queued jobs do overlap
    for name in ("first", "second"):
        (tmp_path / name).unlink()
    assert run_tests.run_jobs({name: jobs[name] for name in ("first", "second")},
                              ["first", "second"], [], workers=2) == 0
    both = _spans(tmp_path, ["first", "second"])
    assert _overlap(both["first"], both["second"])


def test_the_core_job_is_the_unit_suite_and_every_folder_has_one_job(run_tests):
    tested = [path for folders in run_tests.FOLDERS.values() for path in folders]
    assert len(tested) == len(set(tested))
    assert {f"--ignore={path}" for path in tested} <= set(run_tests.CORE)
    assert set(run_tests.BESIDE).isdisjoint(run_tests.ORDER)
    assert set(run_tests.BESIDE) | set(run_tests.ORDER) == {"core", "floors", *run_tests.FOLDERS}
