"""The warm-up job by job, in a separate process, and the notebook's button that starts it.

The background runs are limited to explicit Euler (two jobs: the simple and the driven
pendulum) so that they are quick where the kernel cache is warm.
"""

from __future__ import annotations

import pytest

from pendulum_lab.app import cli, warmup

# The warm-up's wiring (jobs, progress, a background process, the notebook's button) over
# compilations the unit tests make: not again at the floors.
pytestmark = pytest.mark.plumbing

ONE_METHOD = ["explicit_euler"]


def test_the_jobs_name_what_they_compile():
    jobs = warmup.warm_up_jobs(ns=(1, 2), methods=["rk4", "glrk4"])
    assert [job.what for job in jobs] == [
        "rk4 for the simple pendulum", "glrk4 for the simple pendulum",
        "rk4 for the double pendulum", "glrk4 for the double pendulum",
        "rk4 for the damped, driven pendulum", "glrk4 for the damped, driven pendulum"]
    everything = warmup.warm_up_jobs(ns=(2,))
    assert everything[-1].what == "the standard map's loop"  # only when all methods are
    with pytest.raises(ValueError, match="`ns`"):
        warmup.warm_up_jobs(ns=(0,))


def test_a_progress_callable_hears_each_job_and_the_end():
    heard = []
    warmup.warm_up(ns=(1,), methods=ONE_METHOD, progress=lambda *args: heard.append(args))
    assert heard == [(0, 2, "explicit_euler for the simple pendulum"),
                     (1, 2, "explicit_euler for the damped, driven pendulum"), (2, 2, "")]
    with pytest.raises(TypeError, match="`progress`"):
        warmup.warm_up(ns=(1,), methods=ONE_METHOD, progress="yes")


def test_the_command_prints_one_line_per_job(capsys):
    assert cli.main(["warmup", "--n", "1", "--methods", *ONE_METHOD, "--progress", "lines"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[:3] == ["0/2 explicit_euler for the simple pendulum",
                         "1/2 explicit_euler for the damped, driven pendulum", "2/2 "]
    assert all(warmup.PROGRESS_LINE.match(line) for line in lines[:3])


def test_the_background_warm_up_reports_its_progress_and_its_end():
    seen = []
    job = warmup.warm_up_in_background(ns=[1], methods=ONE_METHOD,
                                       on_progress=lambda w: seen.append((w.done, w.total)))
    assert job.wait(timeout=900) == 0, job.error
    assert not job.running and job.current == ""
    assert seen[0] == (0, 2) and seen[-1] == (2, 2)
    assert [done for done, _ in seen] == sorted(done for done, _ in seen)


def test_a_failing_background_warm_up_says_why():
    # negative control: the process fails, and the reason reaches the notebook side
    job = warmup.warm_up_in_background(ns=[1])
    job.stop()
    assert job.returncode != 0 and not job.running
    bad = warmup.BackgroundWarmUp(
        [*job.command[:job.command.index("--n")], "--n", "1", "--methods", "no_such_method"])
    assert bad.wait(timeout=300) == 2
    assert "no_such_method" in bad.error


def test_the_offer_starts_nothing_until_pressed_then_shows_the_progress():
    offer = warmup.warm_up_offer(ns=[1], methods=ONE_METHOD)
    (button,) = offer.children
    assert offer.warmup is None  # nothing runs, and there is no progress bar yet
    button.click()
    assert offer.warmup is not None and button.disabled
    bar, label = offer.children[1].children
    assert offer.warmup.wait(timeout=900) == 0, offer.warmup.error
    assert (bar.value, bar.max, bar.bar_style) == (2, 2, "success")
    assert label.value.startswith("done: 2 kernels")
    assert button.disabled and button.description == "Compiled"
