"""The graded assignments: built offline, solutions full marks, blank zero, no leaks, controls.

Every assignment of ``assignments/`` is built once per session (``conftest.py``); here each is
graded as its solutions, as handed out (blank), and with one answer deliberately wrong.
"""

from __future__ import annotations

import ast
import json
import re
import zipfile

import pytest
from assignment_harness import NAMES, replace_cell, tool

# One deliberately wrong answer per assignment: the question, the answer cell (a string only it
# holds) and the slip, a mistake a student could make. No later question uses these answers.
WRONG_ANSWERS = {
    "01_derivations_and_fixed_points": (
        "q4_normal_modes", "normal_modes = np.sort(",
        # the coupling of the two links dropped: only the diagonal of M^-1 K
        ("np.sqrt(-np.linalg.eigvals(ratio))", "np.sqrt(-np.diag(ratio))")),
    "02_integrators_and_orders": (
        "q2_leapfrog", "def leapfrog_step",
        # explicit Euler handed in as the leapfrog: fails all four properties
        ("p_half = p - 0.5 * h * G * np.sin(theta)\n"
         "    theta_new = theta + h * p_half\n"
         "    return theta_new, p_half - 0.5 * h * G * np.sin(theta_new)",
         "return theta + h * p, p - h * G * np.sin(theta)")),
    "03_symplecticity_and_modified_hamiltonian": (
        "q3_modified_hamiltonian", "H1 = sp.simplify(",
        # the sign of -1/2 H_theta H_p lost
        ("H1 = sp.simplify(-sp.diff(H, theta)", "H1 = sp.simplify(sp.diff(H, theta)")),
    "04_chaos_and_the_driven_pendulum": (
        "q2_driven_rk4_step", "def driven_rk4_step",
        # the drive evaluated at the start of the step for every stage
        ("np.cos(DRIVE_FREQUENCY * time)", "np.cos(DRIVE_FREQUENCY * t)")),
}

_POINTS_IN_PROMPT = re.compile(r"\*\*Question (\d+) \((\d+(?:\.\d+)?) points?\)")


def _question_prompts(notebook) -> list[tuple[int, float]]:
    found = []
    for cell in notebook.cells:
        if cell.cell_type == "markdown":
            found += [(int(n), float(p)) for n, p in _POINTS_IN_PROMPT.findall(cell.source)]
    return found


@pytest.mark.parametrize("name", NAMES)
def test_each_question_states_its_points(kit, name):
    possible = tool.question_points(kit.folders[name])
    stated = _question_prompts(kit.notebook(name, "student"))
    assert 4 <= len(possible) <= 8
    assert [number for number, _ in stated] == list(range(1, len(possible) + 1))
    assert [points for _, points in stated] == list(possible.values())


def test_four_assignments_cover_the_course():
    assert len(NAMES) >= 4
    for topic in ("derivations", "integrators", "symplecticity", "chaos"):
        assert any(topic in name for name in NAMES), topic


@pytest.mark.parametrize("name", NAMES)
def test_solutions_score_full_marks(kit, name):
    solutions = kit.solutions(name)
    assert solutions.scores == solutions.possible, solutions.outputs
    assert solutions.notes == []


@pytest.mark.parametrize("name", NAMES)
def test_blank_student_version_scores_zero_and_only_fails_as_not_answered(kit, name):
    blank = kit.grade(name, kit.notebook(name, "student"), "blank")
    assert blank.score == 0 and set(blank.scores.values()) == {0.0}
    # No cell of the handed-out notebook raised while it ran ...
    assert blank.executed is not None and blank.notes == []
    # ... and every test that failed says "not answered", and nothing else.
    for question, output in blank.outputs.items():
        failures = output.split("❌ Test case failed")[1:]
        assert failures, question
        for failure in failures:
            assert re.search(r"AssertionError: Q\d+ is not answered yet", failure), failure


def _normal(text: str) -> str:
    """Without spaces and quotes, so that a reformatted copy (ast.unparse) still matches."""
    return re.sub(r"\\n|[\s'\"\\]", "", text)


def _split_master(master) -> tuple[list[str], list[str], str]:
    """Solution lines, hidden-test lines, and (normalized) everything else of a master."""
    solutions, hidden, rest = [], [], []
    inside = False  # between a question's BEGIN SOLUTION and END SOLUTION raw cells
    for cell in master.cells:
        if cell.cell_type == "raw":
            inside = {"# BEGIN SOLUTION": True, "# END SOLUTION": False}.get(cell.source.strip(),
                                                                             inside)
            continue
        if cell.cell_type == "code" and cell.source.startswith("# HIDDEN"):
            hidden += [line.strip() for line in cell.source.splitlines()]
            continue
        in_block = False
        for line in cell.source.splitlines():
            stripped = line.strip()
            if inside and stripped.startswith("# BEGIN SOLUTION"):
                in_block = True
            elif inside and stripped == "# END SOLUTION":
                in_block = False
            elif inside and (in_block or stripped.endswith("# SOLUTION")):
                solutions.append(stripped)
            else:
                rest.append(stripped)
        if cell.cell_type == "code" and not inside:  # as otter rewrites public tests, too
            rest.append(ast.unparse(ast.parse(cell.source)))
    return solutions, hidden, _normal("\n".join(rest))


def _distinctive(lines: list[str], rest: str) -> list[str]:
    """The lines that could only have come from there: long, and not part of the rest."""
    return [line for line in lines if len(_normal(line)) >= 16 and _normal(line) not in rest]


def _texts(notebook) -> list[str]:
    """What a student can read in a notebook: every cell, and the metadata (public tests)."""
    return [cell.source for cell in notebook.cells] + [json.dumps(notebook.metadata)]


def _leaks(lines, texts) -> list[str]:
    """The lines of ``lines`` that occur in one of ``texts``, up to spacing and quoting."""
    haystacks = [_normal(text) for text in texts]
    return [line for line in lines if any(_normal(line) in text for text in haystacks)]


@pytest.mark.parametrize("name", NAMES)
def test_no_solution_or_hidden_test_leaks_into_the_student_version(kit, name):
    solution_lines, hidden_lines, rest = _split_master(kit.master(name))
    solution_lines = _distinctive(solution_lines, rest)
    hidden_lines = _distinctive(hidden_lines, rest + _normal("\n".join(solution_lines)))
    assert len(solution_lines) >= 5 and len(hidden_lines) >= 20  # the search has material
    student_folder = kit.folders[name] / "student"
    assert sorted(p.name for p in student_folder.iterdir()) == [f"{name}.ipynb"]
    student = _texts(kit.notebook(name, "student"))
    assert _leaks(solution_lines, student) == []
    assert _leaks(hidden_lines, student) == []
    # Negative controls: the same search finds the solutions in the solutions notebook, and
    # (but for comments, and lines that ast.unparse rewrites) the hidden tests in the
    # autograder's test files.
    assert _leaks(solution_lines, _texts(kit.notebook(name, "autograder"))) == solution_lines
    with zipfile.ZipFile(tool.autograder_zip(kit.folders[name])) as archive:
        tests = [archive.read(n).decode() for n in archive.namelist() if n.startswith("tests/")]
    code_lines = [line for line in hidden_lines if not line.startswith("#")]
    assert len(_leaks(code_lines, tests)) >= 0.9 * len(code_lines)


@pytest.mark.parametrize("name", NAMES)
def test_a_wrong_answer_loses_exactly_its_questions_points(kit, name):
    question, marker, (right, wrong) = WRONG_ANSWERS[name]
    solutions = kit.notebook(name, "autograder")
    cell = next(c for c in solutions.cells if c.cell_type == "code" and marker in c.source)
    assert right in cell.source
    submission = replace_cell(solutions, marker, cell.source.replace(right, wrong))
    graded = kit.grade(name, submission, "wrong")
    assert graded.scores[question] == 0
    assert graded.score == graded.max_score - graded.possible[question]
    others = {q: s for q, s in graded.scores.items() if q != question}
    assert others == {q: p for q, p in graded.possible.items() if q != question}
    # The output names a failed requirement, not the expected value.
    assert "not yet. Hint:" in graded.outputs[question]
