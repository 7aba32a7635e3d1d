"""Chains of three to five links: the equations against Kane's method, energy by method.

``tests/symbolic/test_mechanics.py`` already compares the n = 3 mass matrix and forcing
with ``sympy.physics.mechanics.LagrangesMethod`` built from Cartesian
positions. Here Kane's method, built differently (each link a rotating
reference frame, gravity as an applied force, velocities from the
two-point theorem), checks the same equations independently.
"""

import numpy as np
import pytest
import sympy as sp
from sympy.physics import mechanics as me

import pendulum_lab as pl
from pendulum_lab import analysis, timing
from pendulum_lab.symbolic.mechanics import is_identically_zero


def kane_equations(n, gravity_on=None):
    """``(mass_matrix, forcing)`` of an n-link chain by ``KanesMethod``, in our symbols.

    ``gravity_on`` lists the bobs that feel gravity (all by default): leaving one
    out makes a wrong model for the negative control.
    """
    chain = pl.derive_chain(n)
    q = me.dynamicsymbols(f"q1:{n + 1}")
    u = me.dynamicsymbols(f"u1:{n + 1}")
    ground = me.ReferenceFrame("N")
    pivot = me.Point("O")
    pivot.set_vel(ground, 0)
    particles, loads, joint = [], [], pivot
    for i in range(n):
        link = ground.orientnew(f"A{i}", "Axis", (q[i], ground.z))
        link.set_ang_vel(ground, u[i] * ground.z)
        bob = joint.locatenew(f"P{i}", -chain.lengths[i] * link.y)
        bob.v2pt_theory(joint, ground, link)
        particles.append(me.Particle(f"B{i}", bob, chain.masses[i]))
        if gravity_on is None or i in gravity_on:
            loads.append((bob, -chain.masses[i] * chain.g * ground.y))
        joint = bob
    kane = me.KanesMethod(ground, q_ind=q, u_ind=u, kd_eqs=[qi.diff() - ui for qi, ui in zip(q, u)])
    kane.kanes_equations(particles, loads)
    to_ours = dict(zip(u, chain.omega)) | dict(zip(q, chain.q))
    return me.msubs(kane.mass_matrix, to_ours), me.msubs(kane.forcing, to_ours)


def test_three_link_equations_agree_with_kanes_method():
    chain = pl.derive_chain(3)
    mass, forcing = kane_equations(3)
    assert all(is_identically_zero(e) for e in mass - chain.mass_matrix)
    assert all(is_identically_zero(e) for e in forcing - chain.forcing)
    # Negative control: without gravity on the last bob the forcing differs.
    _, wrong = kane_equations(3, gravity_on=(0, 1))
    assert not all(is_identically_zero(e) for e in wrong - chain.forcing)
    assert not is_identically_zero(sp.expand(wrong[0] - chain.forcing[0]))


@pytest.mark.parametrize("n", [3, 4, 5])
def test_symplectic_methods_keep_the_energy_error_bounded(n):
    model = pl.n_pendulum(n)
    theta0, omega0 = np.linspace(0.8, 0.4, n), np.zeros(n)
    runs = analysis.compare_energy(
        model, theta0, omega0, t_end=200.0, dt=0.01, methods=("glrk4", "leapfrog", "rk4"),
        save_every=10,
    )
    growth = runs.growth()
    worst = runs.max_relative_error()
    for name in ("glrk4", "leapfrog"):
        first, last = growth[name]
        assert last < 2.0 * first, name  # no drift: the error oscillates
    assert worst["glrk4"] < 1e-7 and worst["leapfrog"] < 1e-3
    # Negative control: RK4 is more accurate per step than leapfrog, but its error drifts.
    first, last = growth["rk4"]
    assert last > 4.0 * first


@pytest.mark.parametrize("n", [3, 5])
def test_explicit_euler_energy_grows(n):
    model = pl.n_pendulum(n)
    traj = pl.simulate(
        model, np.linspace(0.8, 0.4, n), np.zeros(n), t_end=20.0, dt=0.01, method="explicit_euler"
    )
    first, last = analysis.energy_growth(traj)
    assert last > 3.0 * first
    assert np.max(np.abs(traj.relative_energy_error)) > 0.1


def test_chain_costs_reports_each_chain():
    rows = timing.chain_costs((3,), t_end=0.1, dt=0.01, method="rk4")
    assert [row.n for row in rows] == [3]
    row = rows[0]
    assert row.derivation > 0 and row.build >= 0 and row.first_simulation > 0
    assert 0 < row.per_step < row.first_simulation
    assert row.evaluations_per_step == 4  # RK4: four stages, nothing implicit
    assert row.per_evaluation * row.evaluations_per_step == pytest.approx(row.per_step)
    chain = pl.derive_chain(3)
    assert row.operations == sp.count_ops([*chain.mass_matrix, *chain.forcing])
    with pytest.raises(ValueError, match="`ns`"):
        timing.chain_costs((0,))
