"""The script that stores checked notebook outputs keeps exactly what nbval compares."""

import importlib.util
from pathlib import Path

import nbformat
import pytest

SCRIPT = Path(__file__).parents[2] / "tools" / "refresh_checked_outputs.py"
spec = importlib.util.spec_from_file_location("refresh_checked_outputs", SCRIPT)
tool = importlib.util.module_from_spec(spec)
spec.loader.exec_module(tool)


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
