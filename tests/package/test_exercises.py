"""The exercise checks of the notebooks: a verdict and a hint, never the expected answer."""

import pytest

from pendulum_lab.exercises import Exercise, ExerciseNotPassed


def test_an_unanswered_exercise_says_so_and_checks_nothing(capsys):
    exercise = Exercise("3. A period", 1.0, None)
    assert not exercise.answered
    with pytest.raises(RuntimeError, match="answered"):
        exercise.require(True, "never reached")
    exercise.report()
    assert "not answered yet" in capsys.readouterr().out


def test_a_right_answer_passes_and_a_wrong_one_fails_with_its_hint_only(capsys):
    target = 6.283185307179586
    answer = 2 * 3.141592653589793
    right = Exercise("3. A period", answer)
    right.require(abs(answer - target) < 1e-9, "compare with 2 pi sqrt(l / g)")
    right.report()
    assert "correct" in capsys.readouterr().out
    wrong = Exercise("3. A period", 6.0)
    wrong.require(abs(6.0 - target) < 1e-9, "the period of small swings is 2 pi sqrt(l / g)")
    wrong.require(6.0 > 0, "a period is positive")  # holds: its hint must not be shown
    with pytest.raises(ExerciseNotPassed) as failure:
        wrong.report()
    message = str(failure.value)
    assert "2 pi sqrt(l / g)" in message and "positive" not in message
    assert "6.28" not in message  # the expected value never appears


def test_a_check_without_requirements_is_refused():
    with pytest.raises(RuntimeError, match="no requirement"):
        Exercise("4. Empty", 1).report()
    with pytest.raises(TypeError, match="hint"):
        Exercise("4. Empty", 1).require(True, "")
    with pytest.raises(TypeError, match="title"):
        Exercise("", 1)


def test_in_a_notebook_a_wrong_answer_shows_its_verdict_and_hints_not_a_traceback():
    from IPython.core.interactiveshell import InteractiveShell

    shell = InteractiveShell.instance()
    shown = []
    original = shell._showtraceback
    shell._showtraceback = lambda etype, value, lines: shown.append(lines)
    try:
        shell.run_cell(
            "from pendulum_lab.exercises import Exercise\n"
            "wrong = Exercise('3. A period', 6.0)\n"
            "wrong.require(False, 'the period of small swings is 2 pi sqrt(l / g)')\n"
            "wrong.require(False, 'a period has units of seconds')\n"
            "wrong.report()\n")
        assert shown[-1] == ["Exercise 3. A period: not yet.",
                             "Hint: the period of small swings is 2 pi sqrt(l / g)",
                             "Hint: a period has units of seconds"]
        # negative control: any other error keeps its full traceback into the code
        shell.run_cell("from pendulum_lab.exercises import Exercise\nExercise('', 1)\n")
        assert len(shown[-1]) > 3 and any("exercises.py" in line for line in shown[-1])
    finally:
        shell._showtraceback = original
