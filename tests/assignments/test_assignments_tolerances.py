"""Correct answers under perturbed round-off get full marks; plausible wrong answers do not.

The hidden and public tests of each master notebook are called directly (``tolerances.py``
executes the functions of their cells), with answers computed as a class would compute them:
starts nudged by a few units in the last place, step functions written in other correct ways,
symbolic answers in other correct forms. Each must pass every test, every time. For the
chaotic Lyapunov estimate of assignment 04, the extremes of 64 round-off histories at each
step size are graded. Negative controls: each plausible wrong answer of ``wrong_answers`` (for
instance off by the very error the question is about) fails a hidden test of its question, and
the public checks that test a property catch the slips they are written for.
"""

from __future__ import annotations

import numpy as np
import pytest
from tolerances import (
    ANSWERS,
    CHAOTIC_TOLERANCE,
    cached_answers,
    chaotic_estimates,
    master_tests,
    passes,
    wrong_answers,
)

#: Round-off histories graded per assignment (0: computed as the solution computes it).
HISTORIES = (0, 1, 2, 3)

#: The slips that a public check, by the property it tests, must catch (question, slip).
CAUGHT_IN_PUBLIC = {
    ("q1_lagrangian", "the potential's sign flipped"),
    ("q2_hamiltonian", "the mass left out of the kinetic term"),
    ("q3_jacobian_up", "the Jacobian at the bottom, not the top"),
    ("q4_normal_modes", "the coupling dropped (diagonal of M^-1 K only)"),
    ("q6_ten_percent_amplitude", "read off a plot to two digits"),
    ("q1_explicit_euler", "the new angle used in the kick (symplectic Euler)"),
    ("q2_leapfrog", "explicit Euler handed in as the leapfrog"),
    ("q2_leapfrog", "both half kicks at the old angle (not symmetric, not symplectic)"),
    ("q3_rk4", "the last stage at h/2"),
    ("q4_measured_order", "the textbook order"),
    ("q5_leapfrog_limit", "the slow mode's frequency"),
    ("q6_euler_energy_factor", "the amplification, not its square"),
    ("q1_adjoint_euler", "symplectic Euler itself (kick first)"),
    ("q2_symplecticity_defects", "GL4's defect given as exactly 0"),
    ("q3_modified_hamiltonian", "the sign of -1/2 lost"),
    ("q5_euler_area_factor", "1, as for a symplectic step"),
    ("q1_lyapunov", "the two releases swapped"),
    ("q2_driven_rk4_step", "the drive at the start of the step for every stage"),
    ("q5_attractor_periods", "the two periods swapped"),
}


def _failures(tests: dict, answers: dict) -> list[str]:
    return [f"{key}: {message}" for key, test in tests.items()
            for passed, message in [passes(test, answers)] if not passed]


@pytest.mark.parametrize("name", list(ANSWERS))
def test_correct_answers_under_perturbed_roundoff_pass_every_test(name):
    hidden, public = master_tests(name)
    assert len(hidden) >= 5 and len(public) >= 4
    for history in HISTORIES:
        answers = cached_answers(name, history)
        assert _failures(hidden, answers) == [], history
        assert _failures(public, answers) == [], history


def test_the_extremes_of_the_chaotic_estimate_pass():
    """The lowest and highest of 2 x 64 round-off histories (dt = 0.01 and 0.005) pass."""
    name = "04_chaos_and_the_driven_pendulum"
    hidden, _ = master_tests(name)
    test = hidden[("q1_lyapunov", "test_chaotic")]
    draws = np.concatenate([chaotic_estimates(64, 0.01), chaotic_estimates(64, 0.005)])
    # The draws really spread (the point of the test): by several per cent either way.
    assert draws.max() / draws.min() > 1.1
    for value in (draws.min(), draws.max()):
        assert passes(test, {"lyapunov_chaotic": float(value)})[0], value
    # Negative control: just outside the band around the draws' median fails.
    median = float(np.median(draws))
    assert not passes(test, {"lyapunov_chaotic": median * (1 - 1.2 * CHAOTIC_TOLERANCE)})[0]
    assert not passes(test, {"lyapunov_chaotic": median * (1 + 1.2 * CHAOTIC_TOLERANCE)})[0]


@pytest.mark.parametrize("name", list(ANSWERS))
def test_plausible_wrong_answers_lose_their_questions_points(name):
    hidden, public = master_tests(name)
    base = cached_answers(name)
    slips = wrong_answers(name)
    assert {question for question, _, _ in slips} == {question for question, _ in hidden}
    for question, slip, changed in slips:
        answers = {**base, **changed}
        ours = {key: test for key, test in hidden.items() if key[0] == question}
        assert _failures(ours, answers), (question, slip)
        # The other questions' tests do not notice.
        others = {key: test for key, test in hidden.items() if key[0] != question}
        assert _failures(others, answers) == [], (question, slip)
        caught = not passes(public[question], answers)[0]
        if (question, slip) in CAUGHT_IN_PUBLIC:
            assert caught, (question, slip)
