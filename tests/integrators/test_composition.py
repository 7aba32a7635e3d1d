"""Composition methods as data: the checks a composition makes on creation, the registered
schemes' weights against their published conditions, and the splitting they stand for."""

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab.integrators import get_method
from pendulum_lab.integrators.composition import ADJOINT, EULER, LEAPFROG, Composition
from pendulum_lab.integrators.source import method_source

COMPOSITIONS = tuple(name for name, method in pl.METHODS.items() if method.composition)
JUMP = 2 ** (1 / 3)
TRIPLE_JUMP = (1 / (2 - JUMP), -JUMP / (2 - JUMP), 1 / (2 - JUMP))


def test_the_registry_holds_the_six_schemes():
    assert set(COMPOSITIONS) >= {"yoshida4", "yoshida6", "suzuki4", "mclachlan4", "omelyan4",
                                 "blanes_moan4"}
    for name in COMPOSITIONS:
        method = get_method(name)
        assert method.symplectic and method.symmetric and method.order % 2 == 0
        assert method.composition.source  # every scheme says where its weights come from
        assert method.composition.conditions_order() == method.order


def test_weights_must_sum_to_one():
    with pytest.raises(ValueError, match="sum to 1"):
        Composition([0.5, 0.4], order=2, symmetric=False)


def test_a_symmetric_claim_is_checked():
    with pytest.raises(ValueError, match="declared symmetric"):
        Composition([0.6, 0.4], order=2)
    # the same weights, declared as they are: two leapfrog steps, second order
    assert Composition([0.6, 0.4], order=2, symmetric=False).stages == 2


def test_a_wrong_order_is_refused_on_creation():
    assert Composition(TRIPLE_JUMP, order=4).conditions_order(8) == 4
    with pytest.raises(ValueError, match="declared of order 6, but its weights give order 4"):
        Composition(TRIPLE_JUMP, order=6)
    with pytest.raises(ValueError, match="order 2, but its weights give order at least 3"):
        Composition(TRIPLE_JUMP, order=2)
    # a mistyped digit of Yoshida's sixth-order weights (w1 off by 1e-6) falls to order 2
    w1, w2, w3 = -1.17767998417887 + 1e-6, 0.235573213359357, 0.784513610477560
    w0 = 1 - 2 * (w1 + w2 + w3)
    with pytest.raises(ValueError, match="give order 2"):
        Composition([w3, w2, w1, w0, w1, w2, w3], order=6)


def test_leapfrog_compositions_meet_the_conditions_on_their_weights():
    """Symmetric compositions of a symmetric method: order 4 needs sum w^3 = 0, order 6 also
    sum w^5 = 0 and one more condition [HLW, Sect. V.3.2]: necessary conditions checked here
    independently of the generic-matrix check."""
    for name in COMPOSITIONS:
        composition = get_method(name).composition
        if composition.base != "leapfrog":
            continue
        w = np.array(composition.weights)
        assert abs(w.sum() - 1) < 1e-15 and abs(np.sum(w**3)) < 1e-14, name
        if composition.order >= 6:
            assert abs(np.sum(w**5)) < 1e-13, name
    assert abs(np.sum(np.array([0.6, 0.4]) ** 3)) > 0.1  # negative control


def splitting(q, p, h, drifts_and_kicks, g=9.81):
    """A splitting method on the simple pendulum (H = p^2/2 - g cos q) written out: drift
    ``q += a h p`` and kick ``p -= b h g sin q`` in turn, starting with a drift."""
    for i, coefficient in enumerate(drifts_and_kicks):
        if i % 2 == 0:
            q = q + coefficient * h * p
        else:
            p = p - coefficient * h * g * np.sin(q)
    return q, p


def test_omelyan_is_the_pefrl_splitting_on_a_separable_hamiltonian():
    xi, lam, chi = 0.1786178958448091, -0.2123418310626054, -0.06626458266981849
    pefrl = [xi, (1 - 2 * lam) / 2, chi, lam, 1 - 2 * (chi + xi), lam, chi, (1 - 2 * lam) / 2, xi]
    sp = pl.simple_pendulum(mass=1.0, length=1.0, g=9.81)
    q, p, h = np.array([1.1]), np.array([0.4]), 0.3
    q1, p1 = pl.step(sp, q, p0=p, dt=h, method="omelyan4")
    q_ref, p_ref = splitting(q, p, h, pefrl)
    assert np.max(np.abs(np.concatenate([q1 - q_ref, p1 - p_ref]))) < 1e-14
    # negative control: the same coefficients starting with a kick are another method
    q_kick, p_kick = splitting(q, p, h, [0.0, *pefrl])
    assert np.max(np.abs(np.concatenate([q1 - q_kick, p1 - p_kick]))) > 1e-4
    kinds = [kind for kind, _ in get_method("omelyan4").composition.substeps]
    assert kinds[:2] == [ADJOINT, EULER] and LEAPFROG not in kinds


def test_blanes_moan_is_their_six_stage_splitting_on_a_separable_hamiltonian():
    # the published coefficients of S6 (J. Comput. Appl. Math. 142 (2002) 313-330, Table 2)
    a1, a2, a3 = 0.0792036964311957, 0.353172906049774, -0.0420650803577195
    b1, b2 = 0.209515106613362, -0.143851773179818
    a4, b3 = 1 - 2 * (a1 + a2 + a3), 0.5 - (b1 + b2)
    s6 = [a1, b1, a2, b2, a3, b3, a4, b3, a3, b2, a2, b1, a1]
    sp = pl.simple_pendulum(mass=1.0, length=1.0, g=9.81)
    q, p, h = np.array([1.1]), np.array([0.4]), 0.3
    q1, p1 = pl.step(sp, q, p0=p, dt=h, method="blanes_moan4")
    q_ref, p_ref = splitting(q, p, h, s6)
    assert np.max(np.abs(np.concatenate([q1 - q_ref, p1 - p_ref]))) < 1e-14
    # negative control: a2 and b1 exchanged is another method
    q_swap, p_swap = splitting(q, p, h, [a1, a2, b1, *s6[3:-3], b1, a2, a1])
    assert np.max(np.abs(np.concatenate([q1 - q_swap, p1 - p_swap]))) > 1e-4


def test_method_source_lists_the_substeps_and_the_source():
    text = method_source("yoshida4")
    lines = text.splitlines()
    assert lines[0].startswith("# yoshida4: composition(field, t, q, p, h, composition=")
    assert lines[1] == f"#   1. leapfrog with step {TRIPLE_JUMP[0]!r} h"
    assert lines[2].startswith("#   2. leapfrog with step -1.70241438391931")
    assert "Yoshida, Phys. Lett. A 150 (1990)" in text
    assert "def composition(field, t, q, p, h, composition):" in text
    # with its helpers: the leapfrog it composes, not the symplectic Euler steps it does not take
    helpers = method_source("yoshida4", helpers=True)
    assert "def leapfrog(" in helpers and "def adjoint_symplectic_euler(" not in helpers
    assert "def adjoint_symplectic_euler(" in method_source("omelyan4", helpers=True)
