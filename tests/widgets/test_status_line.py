"""The instruments' status line: busy while a run is computed (with the figure marked stale),
the result after; and the hint a reopened notebook shows where the widget cannot be."""

import pytest
from IPython.core.interactiveshell import InteractiveShell
from IPython.utils.capture import capture_output

import pendulum_lab as pl
from pendulum_lab import widgets
from pendulum_lab.widgets import instrument, status
from pendulum_lab.widgets.calls import SimulateCall


def test_the_status_line_is_busy_and_the_figure_stale_while_a_run_is_computed(monkeypatch):
    ex = widgets.explore(pl.double_pendulum(), t_end=2.0, method="rk4")
    seen = []
    run = SimulateCall.run

    def watched(call):
        seen.append((ex.status.kind, ex.status.text, status.STALE_CLASS in ex.widget._dom_classes))
        return run(call)

    monkeypatch.setattr(SimulateCall, "run", watched)
    ex.controls["theta1"].value = 0.4
    assert seen == [("busy", "computing 200 steps of rk4 (dt = 0.01 s)…", True)]
    # After the run: its summary, the figure no longer stale.
    assert ex.status.kind == "info" and ex.status.text.startswith("200 steps of rk4")
    assert status.STALE_CLASS not in ex.widget._dom_classes


def test_a_compile_during_a_run_is_said_in_the_status_line_and_reported_apart(monkeypatch):
    from pendulum_lab.codegen.compile_status import compiling

    ex = widgets.explore(pl.double_pendulum(), t_end=2.0, method="rk4")
    texts = []
    run = SimulateCall.run

    def compiles_first(call):
        with compiling("rk4 for the double pendulum", loading=False):
            texts.append((ex.status.kind, ex.status.text))
        texts.append((ex.status.kind, ex.status.text))
        return run(call)

    monkeypatch.setattr(SimulateCall, "run", compiles_first)
    ex.controls["theta1"].value = 0.4
    during, after = texts
    assert during[0] == "busy" and "compiling rk4 for the double pendulum" in during[1]
    assert after == ("busy", "computing 200 steps of rk4 (dt = 0.01 s)…")
    # negative control: without a compile, the status line never speaks of one
    texts.clear()
    monkeypatch.setattr(SimulateCall, "run", lambda call: texts.append(ex.status.text) or run(call))
    ex.controls["theta1"].value = 0.5
    assert texts and not any("compiling" in text for text in texts)
    assert "compiling" not in ex.status.text


def test_a_failed_run_ends_the_busy_state_with_its_error():
    ex = widgets.explore(pl.double_pendulum(), t_end=2.0, method="rk4")
    ex.controls["dt"].value = 0.0005
    assert not ex.set_controls({"t_end": 100.0})  # 200,000 steps: beyond the explorer's limit
    assert ex.status.kind == "error" and "limit" in ex.message
    assert status.STALE_CLASS not in ex.widget._dom_classes


def test_working_restores_the_sentence_before_unless_the_block_sets_one():
    line = status.StatusLine()
    line.show("the run before", "warning")
    with line.working("compiling glrk4 for the double pendulum, once per machine…"):
        assert (line.kind, line.text.startswith("compiling")) == ("busy", True)
    assert (line.text, line.kind) == ("the run before", "warning")
    with pytest.raises(RuntimeError), line.working("about to fail"):
        raise RuntimeError("boom")
    assert line.kind == "warning"  # an exception does not leave it busy
    with line.working("computing"):
        line.show("done", "info")
    assert (line.text, line.kind) == ("done", "info")


def test_kinds_are_checked():
    line = status.StatusLine()
    with pytest.raises(ValueError, match="`kind`"):
        line.show("x", "busy")  # a busy sentence belongs to `working`
    ex = widgets.explore(pl.simple_pendulum(), t_end=1.0)
    with pytest.raises(ValueError, match="`kind`"):
        ex.set_message("x", "loud")


def displayed(obj) -> list[dict]:
    """The outputs IPython publishes for ``obj`` (a bare name at the end of a cell does the
    same: its display hook calls ``_ipython_display_``)."""
    from IPython.display import display

    InteractiveShell.instance()
    with capture_output() as captured:
        display(obj)
    return [output.data for output in captured.outputs]


@pytest.mark.parametrize("build", [
    lambda: widgets.explore(pl.simple_pendulum(), t_end=1.0),
    lambda: widgets.live_simulator(pl.simple_pendulum(), t_end=1.0),
    lambda: widgets.portrait_explorer(pl.simple_pendulum(), t_end=1.0),
], ids=["explorer", "live", "portrait"])
def test_a_displayed_instrument_is_followed_by_the_reopen_hint(build):
    outputs = displayed(build())
    assert len(outputs) == 2
    shown, hint = outputs
    assert "application/vnd.jupyter.widget-view+json" in shown and "image/png" in shown
    assert set(hint) == {"text/html", "text/plain"} and hint["text/plain"] == ""
    html = hint["text/html"]
    assert "run this cell to bring it back" in html
    # Hidden by default (a static page, a live widget); shown only by its own rule, which needs
    # a widget output JupyterLab failed to show (it marks the output itself jupyter-widgets).
    assert 'class="plab-reopen-hint" style="display:none"' in html
    assert ".jp-OutputArea:has(.jp-OutputArea-output.jupyter-widgets) .plab-reopen-hint" in html
    assert html == instrument.REOPEN_HINT
