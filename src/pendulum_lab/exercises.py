"""Checks for the notebooks' exercises: right or wrong, with a hint, never the answer.

An exercise cell leaves its answer as ``None``; the check cell below it reads::

    exercise = Exercise("2. The order of the leapfrog", measured_order)
    if exercise.answered:
        exercise.require(abs(measured_order - round(measured_order)) < 0.1,
                         "an order is close to a whole number: fit the straight part only")
    exercise.report()

:meth:`Exercise.report` prints that the exercise is not answered yet, or that every
requirement holds, or raises :class:`ExerciseNotPassed` listing the hints of the requirements
that failed. In a notebook the failure shows as two lines, the verdict and the hint, not as a
traceback into this module (a student who reads a traceback thinks something broke); "run
all" still stops there, and tests still see the exception. A requirement states a property
of a right answer (a bound, an identity, an order), so a check tests understanding rather
than a copied number, and no message shows the expected value.
"""

from __future__ import annotations

__all__ = ["Exercise", "ExerciseNotPassed"]


class ExerciseNotPassed(AssertionError):
    """An exercise's answer fails one of its requirements (the message holds the hints).

    IPython shows what :meth:`_render_traceback_` returns instead of the traceback: the
    verdict and the hints, nothing else.
    """

    def _render_traceback_(self) -> list[str]:
        verdict, _, hints = str(self).partition(" Hint: ")
        return [verdict, *(f"Hint: {hint}" for hint in hints.split("; ") if hint)]


class Exercise:
    """The check of one exercise.

    Parameters
    ----------
    title : str
        How the exercise is named in the notebook ("2. The order of the leapfrog").
    *answers : object
        The student's answers; the exercise counts as answered once none is ``None``.

    Examples
    --------
    >>> exercise = Exercise("1. A square", None)
    >>> exercise.report()
    Exercise 1. A square: not answered yet (replace the None in the cell above).
    >>> exercise = Exercise("1. A square", 9)
    >>> exercise.require(9 == 3**2, "square the side")
    >>> exercise.report()
    Exercise 1. A square: correct.
    >>> wrong = Exercise("1. A square", 6)
    >>> wrong.require(6 == 3**2, "multiply the side by itself")
    >>> try:  # in a notebook the failure shows as an error under the check cell
    ...     wrong.report()
    ... except ExerciseNotPassed as failure:
    ...     print(failure)
    Exercise 1. A square: not yet. Hint: multiply the side by itself
    """

    def __init__(self, title: str, *answers):
        if not isinstance(title, str) or not title.strip():
            raise TypeError(f"`title` must be a non-empty str, got {title!r}")
        self.title = title.strip()
        self.answered = all(answer is not None for answer in answers)
        self._hints: list[str] = []
        self._checked = 0

    def require(self, condition, hint: str) -> None:
        """Record one requirement of a right answer; ``hint`` is shown if it fails.

        ``condition`` is a bool (or a NumPy bool); an error computing it is the student's
        to see, so compute it in the check cell, not here.
        """
        if not isinstance(hint, str) or not hint.strip():
            raise TypeError("`hint` must be a non-empty str saying what to look at")
        if not self.answered:
            raise RuntimeError("check `exercise.answered` before requiring anything of the answer")
        self._checked += 1
        if not bool(condition):
            self._hints.append(hint.strip())

    def report(self) -> None:
        """Print the verdict, or raise :class:`ExerciseNotPassed` with the failed hints."""
        if not self.answered:
            print(f"Exercise {self.title}: not answered yet (replace the None in the cell above).")
            return
        if self._checked == 0:
            raise RuntimeError(f"exercise {self.title!r} has no requirement: a check must check")
        if self._hints:
            hints = "; ".join(self._hints)
            raise ExerciseNotPassed(f"Exercise {self.title}: not yet. Hint: {hints}")
        print(f"Exercise {self.title}: correct.")
