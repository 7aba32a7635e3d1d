"""Shared by the assignment tests: the grading tool loaded as a module, the session's kit.

``tools/assignments.py`` (the command behind ``make assignments``) is driven as a library. Each
grading runs a submission in a fresh kernel in a sandbox, so the kit builds every assignment once
per session, keeps the solutions' gradings for every test that needs them, and keeps the kernels
they compiled for every later sandbox to start from (a copy each).
"""

from __future__ import annotations

import copy
from pathlib import Path

import nbformat
from repository_scripts import load_script

REPO_ROOT = Path(__file__).resolve().parents[2]
ARTIFACTS = REPO_ROOT / "test-artifacts" / "assignments"


tool = load_script("tools/assignments.py", "assignment_tool")
NAMES = [path.stem for path in tool.masters()]


class Kit:
    """The built assignments of this session and the gradings made so far."""

    def __init__(self, dist: Path, work: Path):
        self.dist = dist
        self.work = work
        self.folders = {name: tool.build(master, dist) for name, master in
                        zip(NAMES, tool.masters(), strict=True)}
        self._solutions = {}
        self.seconds = {}
        # The compiled kernels every sandbox starts from, filled by the solutions' gradings.
        self.cache = work / "kernel-cache"

    def master(self, name: str) -> nbformat.NotebookNode:
        return nbformat.read(tool.ASSIGNMENTS / f"{name}.ipynb", as_version=4)

    def notebook(self, name: str, version: str) -> nbformat.NotebookNode:
        """``version``: "student" (handed out) or "autograder" (the solutions)."""
        return nbformat.read(self.folders[name] / version / f"{name}.ipynb", as_version=4)

    def grade(self, name: str, notebook, label: str, **limits):
        """Grade ``notebook`` (a NotebookNode, or a path) as a submission of ``name``."""
        if isinstance(notebook, nbformat.NotebookNode):
            path = self.work / f"{name}-{label}.ipynb"
            nbformat.write(notebook, path)
        else:
            path = Path(notebook)
        limits.setdefault("cache", self.cache)
        result = tool.grade(self.folders[name], path, **limits)
        self.seconds[f"{name} {label}"] = round(result.seconds, 1)
        # Shown by pytest when the test fails: why a question lost its points, where it hung.
        print(f"graded {name} ({label}) in {result.seconds:.0f} s; notes:", *result.notes,
              sep="\n")
        return result

    def solutions(self, name: str):
        if name not in self._solutions:
            self._solutions[name] = self.grade(
                name, self.folders[name] / "autograder" / f"{name}.ipynb", "solutions",
                warm_cache=True)
        return self._solutions[name]


def replace_cell(notebook, marker: str, source: str):
    """A copy of ``notebook`` whose one code cell containing ``marker`` now holds ``source``."""
    changed = copy.deepcopy(notebook)
    hits = [cell for cell in changed.cells if cell.cell_type == "code" and marker in cell.source]
    assert len(hits) == 1, f"{len(hits)} code cells contain {marker!r}"
    hits[0].source = source
    return changed
