"""Symbolic derivation checks, against textbook closed forms and the course report.

The course report is ``shared/seed/periodic_pendulums_report.md`` (Kanoun,
Cowley, Ivachtchenko, MAT332, 2024). Its printed equations are typed in here
so that each slip shows up as a non-zero symbolic difference.
"""

import sympy as sp
from sympy.physics import mechanics as me

import pendulum_lab as pl
from pendulum_lab.symbolic.mechanics import Chain, is_identically_zero

is_zero = is_identically_zero


DP = pl.derive_chain(2)
t1, t2 = DP.q
w1, w2 = DP.omega
p1, p2 = DP.p
m1, m2 = DP.masses
L1, L2 = DP.lengths
g = DP.g
D = t1 - t2


def standard_accelerations(cos_term):
    """Section 4.6.1 of the report, with the denominator's cosine term as given."""
    den = 2 * m1 + m2 - m2 * cos_term
    a1 = (-g * (2 * m1 + m2) * sp.sin(t1) - m2 * g * sp.sin(t1 - 2 * t2)
          - 2 * sp.sin(D) * m2 * (w2**2 * L2 + w1**2 * L1 * sp.cos(D))) / (L1 * den)
    a2 = (2 * sp.sin(D) * (w1**2 * L1 * (m1 + m2) + g * (m1 + m2) * sp.cos(t1)
                           + w2**2 * L2 * m2 * sp.cos(D))) / (L2 * den)
    return a1, a2


def test_double_pendulum_accelerations_match_standard_closed_form():
    ours = DP.accelerations
    a1, a2 = standard_accelerations(sp.cos(2 * D))
    assert is_zero(ours[0] - a1)
    assert is_zero(ours[1] - a2)


def test_report_461_denominator_cos_squared_is_a_typo():
    # Printed as cos^2(theta1 - theta2); the standard form has cos(2(theta1 - theta2)).
    a1, _ = standard_accelerations(sp.cos(D) ** 2)
    assert not is_zero(DP.accelerations[0] - a1)


def report_hamilton_equations(l_in_29):
    """The report's (29)-(34), with the length in the second term of (29) as given."""
    s = m1 + m2 * sp.sin(D) ** 2
    th1 = (p1 * L2 - p2 * l_in_29 * sp.cos(D)) / (L1**2 * L2 * s)
    th2 = (p2 * (m1 + m2) * L1 - p1 * m2 * L2 * sp.cos(D)) / (m2 * L1 * L2**2 * s)
    gamma1 = p1 * p2 * sp.sin(D) / (L1 * L2 * s)
    gamma2 = (sp.sin(2 * D) * (p1**2 * m2 * L2**2 - 2 * p1 * p2 * m2 * L1 * L2 * sp.cos(D)
                               + p2**2 * (m1 + m2) * L1**2)) / (2 * L1**2 * L2**2 * s**2)
    pd1 = -(m1 + m2) * g * L1 * sp.sin(t1) - gamma1 + gamma2
    pd2 = -m2 * g * L2 * sp.sin(t2) + gamma1 - gamma2
    return th1, th2, pd1, pd2


def test_hamilton_equations_match_report_30_to_34_and_corrected_29():
    qdot, pdot = DP.hamilton_equations
    th1, th2, pd1, pd2 = report_hamilton_equations(l_in_29=L1)
    assert is_zero(qdot[0] - th1)
    assert is_zero(qdot[1] - th2)
    assert is_zero(pdot[0] - pd1)
    assert is_zero(pdot[1] - pd2)


def test_report_29_second_term_has_l2_where_l1_belongs():
    qdot, _ = DP.hamilton_equations
    printed, _, _, _ = report_hamilton_equations(l_in_29=L2)
    difference = sp.simplify(qdot[0] - printed)
    assert difference != 0
    # The whole difference is the swapped length in the p2 term.
    expected = -p2 * (L1 - L2) * sp.cos(D) / (L1**2 * L2 * (m1 + m2 * sp.sin(D) ** 2))
    assert is_zero(difference - expected)


def test_hamiltonian_is_legendre_transform_and_equals_t_plus_v():
    for n in (1, 2):
        chain = pl.derive_chain(n)
        on_momenta = dict(zip(chain.p, chain.momenta))
        energy = chain.kinetic + chain.potential
        assert is_zero(chain.hamiltonian.subs(on_momenta, simultaneous=True) - energy)
        assert is_zero(chain.legendre_transform() - energy)


def test_energy_is_conserved_along_the_lagrangian_flow():
    # dE/dt = E_q . omega + E_omega . alpha with M alpha = F; E_omega = M omega.
    for n in (1, 2, 3):
        chain = pl.derive_chain(n)
        energy = chain.kinetic + chain.potential
        e_q = sp.Matrix([energy.diff(q) for q in chain.q])
        ddt = (e_q.T * chain.omega)[0, 0] + (chain.omega.T * chain.forcing)[0, 0]
        assert is_zero(ddt)
        # Negative control: dropping the velocity-dependent forcing breaks it.
        forcing_without = chain.forcing.subs({w: 0 for w in chain.omega})
        if n >= 2:
            broken = (e_q.T * chain.omega)[0, 0] + (chain.omega.T * forcing_without)[0, 0]
            assert not is_zero(broken)


def test_dH_dt_vanishes_for_hamiltons_equations():
    qdot, pdot = DP.hamilton_equations
    h = DP.hamiltonian
    ddt = sum(h.diff(q) * a + h.diff(p) * b for q, p, a, b in zip(DP.q, DP.p, qdot, pdot))
    assert sp.expand(ddt) == 0


def test_simple_pendulum_equilibria_center_and_saddle():
    chain = pl.derive_chain(1)
    gl = sp.sqrt(chain.g / chain.lengths[0])
    down, up = chain.equilibria
    assert down.name == "down" and up.name == "up"
    assert set(down.eigenvalues()) == {sp.I * gl, -sp.I * gl}
    assert set(up.eigenvalues()) == {gl, -gl}
    subs = {chain.masses[0]: 1.0, chain.lengths[0]: 2.0, chain.g: 9.81}
    assert down.classify(subs) == "center"
    assert up.classify(subs) == "saddle"


def test_double_pendulum_four_equilibria_classified():
    subs = dict(zip(DP.parameters, [1.0, 1.0, 1.0, 1.0, 9.81]))
    kinds = {e.name: e.classify(subs) for e in DP.equilibria}
    assert kinds == {"down-down": "center", "down-up": "saddle-center",
                     "up-down": "saddle-center", "up-up": "saddle"}
    # Normal modes of the hanging double pendulum (m = l = 1): omega^2 = g (2 -+ sqrt 2).
    down = DP.equilibria[0]
    freqs = sorted(abs(complex(v.subs(subs))) for v in down.eigenvalues())
    expected = sorted([(9.81 * (2 - 2**0.5)) ** 0.5] * 2 + [(9.81 * (2 + 2**0.5)) ** 0.5] * 2)
    assert max(abs(a - b) for a, b in zip(freqs, expected)) < 1e-12


def test_mass_matrix_and_forcing_agree_with_sympy_mechanics_for_n3():
    n = 3
    chain = pl.derive_chain(n)
    q = me.dynamicsymbols(f"q1:{n + 1}")
    u = [qi.diff() for qi in q]
    frame = me.ReferenceFrame("N")
    origin = me.Point("O")
    origin.set_vel(frame, 0)
    particles, point, potential = [], origin, 0
    for i in range(n):
        point = point.locatenew(f"P{i}", chain.lengths[i] * (sp.sin(q[i]) * frame.x
                                                             - sp.cos(q[i]) * frame.y))
        point.set_vel(frame, point.pos_from(origin).dt(frame))
        particles.append(me.Particle(f"B{i}", point, chain.masses[i]))
        potential += chain.masses[i] * chain.g * point.pos_from(origin).dot(frame.y)
    lagrangian = me.Lagrangian(frame, *particles) - potential
    method = me.LagrangesMethod(lagrangian, q)
    method.form_lagranges_equations()
    to_ours = dict(zip(u, chain.omega)) | dict(zip(q, chain.q))
    mass = me.msubs(method.mass_matrix, to_ours)
    forcing = me.msubs(method.forcing, to_ours)
    assert all(is_zero(e) for e in mass - chain.mass_matrix)
    assert all(is_zero(e) for e in forcing - chain.forcing)


def test_chain_rejects_bad_n():
    import pytest

    with pytest.raises(ValueError, match="`n`"):
        Chain(0)
    with pytest.raises(TypeError, match="`n`"):
        pl.derive_chain(2.0)
