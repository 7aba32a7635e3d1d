"""Re-execute course notebooks and store only the outputs nbval compares; compare a run's.

Usage::

    .venv/bin/python tools/refresh_checked_outputs.py notebooks/02_fixed_points_and_jacobians.ipynb

Each notebook runs top to bottom in a fresh kernel, in its own folder. Any
error, or any output on stderr from a checked cell, stops the script with the
cell's number and changes nothing on disk. Then every code cell loses its
outputs and execution count except those marked ``# NBVAL_CHECK_OUTPUT``, and
the notebook's saved widget state is dropped (it causes "Error displaying
widget" after a restart). Run ``ruff format`` on the result afterwards.

``differences`` compares the checked cells of a notebook run elsewhere (JupyterLab's, in
tests/browser) with the stored outputs by nbval's rule for these cells (notebooks/conftest.py):
the standard output, its streams joined, carriage returns and backspaces applied; standard
error left out; any other output is a difference.
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

import nbformat
from nbclient import NotebookClient

CHECK_MARKER = "# NBVAL_CHECK_OUTPUT"


def _joined(text) -> str:
    """A notebook's multi-line string: saved as a list of lines or as one string."""
    return "".join(text) if isinstance(text, list) else text


def is_checked(cell) -> bool:
    return cell.get("cell_type") == "code" and CHECK_MARKER in _joined(cell.get("source", ""))


def printed(cell) -> tuple[str, list[str]]:
    """A cell's standard output as nbval compares it, and the kinds of its other outputs
    (standard error left out)."""
    stdout, others = "", []
    for output in cell.get("outputs", []):
        if output.get("output_type") == "stream":
            if output.get("name") == "stdout":
                stdout += _joined(output.get("text", ""))
        else:
            others.append(output.get("output_type", "?"))
    while True:  # a character followed by a backspace cancels out, as a terminal shows it
        shorter = re.sub(r"[^\n]\x08", "", stdout)
        if shorter == stdout:
            break
        stdout = shorter
    # what a carriage return not ending the line overwrites
    return re.sub(r"^.*\r(?=[^\n])", "", stdout, flags=re.MULTILINE), others


def differences(stored, ran) -> list[str]:
    """Where the checked cells of ``ran`` (a notebook's JSON after a run) print other than
    ``stored`` (the notebook as committed) prints. The two hold the same cells."""
    stored_cells, ran_cells = stored["cells"], ran["cells"]
    if len(stored_cells) != len(ran_cells):
        return [f"the run has {len(ran_cells)} cells, the notebook {len(stored_cells)}"]
    found = []
    for index, (expected, actual) in enumerate(zip(stored_cells, ran_cells, strict=True)):
        if not is_checked(expected):
            continue
        want, _ = printed(expected)
        got, others = printed(actual)
        if others:
            found.append(f"cell {index}: outputs besides the printed text: {others}")
        if got != want:
            found.append(f"cell {index}: printed\n{got}\ninstead of the stored\n{want}")
    return found


def problems(nb) -> list[str]:
    """Errors anywhere, and stderr in checked cells (nbval would compare it)."""
    found = []
    for index, cell in enumerate(nb.cells):
        for output in cell.get("outputs", []):
            if output.get("output_type") == "error":
                found.append(f"cell {index}: {output.get('ename')}: {output.get('evalue')}")
            elif is_checked(cell) and output.get("name") == "stderr":
                found.append(f"cell {index}: checked cell writes to stderr: {output['text'][:200]}")
    return found


def keep_checked_outputs(nb):
    """Strip every output except the checked cells'; drop widget state. In place."""
    nb.metadata.pop("widgets", None)
    for cell in nb.cells:
        if cell.cell_type != "code":
            continue
        cell.metadata.pop("execution", None)
        if not is_checked(cell):
            cell.outputs = []
            cell.execution_count = None
    return nb


def refresh(path: Path, timeout: int = 600) -> float:
    """Execute, check and strip one notebook in place; return the seconds it ran."""
    nb = nbformat.read(path, as_version=4)
    client = NotebookClient(nb, timeout=timeout, kernel_name="python3",
                            resources={"metadata": {"path": str(path.parent)}})
    start = time.perf_counter()
    client.execute()
    seconds = time.perf_counter() - start
    found = problems(nb)
    if found:
        raise RuntimeError(f"{path.name}: " + "; ".join(found))
    nbformat.write(keep_checked_outputs(nb), path)
    return seconds


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("notebooks", nargs="+", type=Path)
    args = parser.parse_args(argv)
    for path in args.notebooks:
        print(f"{path.name}: executed in {refresh(path):.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
