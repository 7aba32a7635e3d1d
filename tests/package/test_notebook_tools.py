"""The script that stores checked notebook outputs keeps exactly what nbval compares, and
compares a run's checked outputs with them by the same rule."""

import nbformat
import pytest
from repository_scripts import load_script

tool = load_script("tools/refresh_checked_outputs.py")


def notebook(tmp_path, cells):
    nb = nbformat.v4.new_notebook()
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3",
                                 "language": "python"}
    nb.cells = [nbformat.v4.new_code_cell(source) for source in cells]
    path = tmp_path / "example.ipynb"
    nbformat.write(nb, path)
    return path


def test_only_checked_cells_keep_their_outputs(tmp_path):
    path = notebook(tmp_path, ["# NBVAL_CHECK_OUTPUT\nprint(6 * 7)", "print('not compared')"])
    tool.refresh(path)
    checked, other = nbformat.read(path, as_version=4).cells
    assert checked.outputs[0]["text"] == "42\n" and checked.execution_count == 1
    assert other.outputs == [] and other.execution_count is None


def test_errors_stop_the_refresh_and_leave_the_file_alone(tmp_path):
    path = notebook(tmp_path, ["# NBVAL_CHECK_OUTPUT\nimport sys; print('x', file=sys.stderr)"])
    before = path.read_text()
    with pytest.raises(RuntimeError, match="stderr"):
        tool.refresh(path)
    assert path.read_text() == before


def test_widget_state_is_dropped():
    nb = nbformat.v4.new_notebook()
    nb.metadata["widgets"] = {"application/vnd.jupyter.widget-state+json": {}}
    assert "widgets" not in tool.keep_checked_outputs(nb).metadata


def run_of(*outputs_per_cell, checked=True):
    """A notebook's JSON with one code cell per list of outputs, each marked as checked."""
    marker = "# NBVAL_CHECK_OUTPUT\n" if checked else ""
    return {"cells": [{"cell_type": "code", "source": [marker, "print(x)"], "outputs": outputs}
                      for outputs in outputs_per_cell]}


def stdout(text, name="stdout"):
    return {"output_type": "stream", "name": name, "text": text}


def test_a_run_printing_what_is_stored_has_no_differences():
    stored = run_of([stdout(["energy error 1.5e-03\n", "order 2\n"])])
    # JupyterLab joins the streams and saves the text as one string; stderr is left out
    ran = run_of([stdout("energy error 1.5e-03\n"), stdout("a warning\n", "stderr"),
                  stdout("order 2\n")])
    assert tool.differences(stored, ran) == []
    # a progress line overwritten in place prints what its last state shows
    assert tool.differences(run_of([stdout("done\n")]),
                            run_of([stdout("10%\r50%\rdone\n")])) == []


def test_each_difference_in_a_checked_cell_is_found():
    stored = run_of([stdout("order 2\n")], [stdout("1.00\n")])
    one_digit = run_of([stdout("order 2\n")], [stdout("1.01\n")])
    assert ["cell 1" in found for found in tool.differences(stored, one_digit)] == [True]
    figure = {"output_type": "display_data", "data": {"text/plain": "<Figure>"}, "metadata": {}}
    extra = run_of([stdout("order 2\n"), figure], [stdout("1.00\n")])
    assert "besides the printed text" in tool.differences(stored, extra)[0]
    assert tool.differences(stored, run_of([stdout("order 2\n")])) != []
    # a cell that is not marked is not compared
    assert tool.differences(run_of([stdout("1\n")], checked=False),
                            run_of([stdout("2\n")], checked=False)) == []
