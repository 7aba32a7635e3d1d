"""The general derivation of MechanicalSystem against sympy.physics.mechanics and Chain(n).

Each identity is decided exactly (is_identically_zero), and each has a negative control: a
system that differs by one term must fail the same check.
"""

import math

import pytest
import sympy as sp
from sympy.physics import mechanics as me
from sympy.physics.mechanics.models import n_link_pendulum_on_cart

from pendulum_lab.symbolic.mechanics import derive_chain, is_identically_zero
from pendulum_lab.symbolic.systems import MechanicalSystem, chain_system

r, th, x = sp.symbols("r theta x", real=True)
m, k, l0, g, l, big_m = sp.symbols("m k l_0 g l M", positive=True)  # noqa: E741
t = sp.Symbol("t", real=True)


def elastic(extra_potential=0):
    return MechanicalSystem([r, th], {m: 1.0, k: 40.0, l0: 1.0, g: 9.81},
                            points=[(r * sp.sin(th), -r * sp.cos(th))], masses=[m], gravity=g,
                            potential=k * (r - l0) ** 2 / 2 + extra_potential)


def cart(bob_offset=0):
    return MechanicalSystem([x, th], {big_m: 1.0, m: 0.5, l: 1.0, g: 9.81},
                            points=[(x, 0), (x + l * sp.sin(th) + bob_offset, -l * sp.cos(th))],
                            masses=[big_m, m], gravity=g)


def lagranges_method(lagrangian, coordinates):
    """sympy.physics.mechanics' LagrangesMethod: M and forcing, in plain symbols."""
    qs = me.dynamicsymbols(f"s0:{len(coordinates)}")
    us = [qi.diff(me.dynamicsymbols._t) for qi in qs]
    method = me.LagrangesMethod(lagrangian(qs, us), qs)
    method.form_lagranges_equations()
    plain = {}
    for qi, ui, c in zip(qs, us, coordinates):
        plain[ui] = sp.Symbol(f"{c}_dot", real=True)
        plain[qi] = c
    # velocities first: they contain the coordinates' functions
    return (method.mass_matrix.subs({u: plain[u] for u in us}).subs(plain),
            method.forcing.subs({u: plain[u] for u in us}).subs(plain))


def elastic_lagrangian(qs, us):
    (rr, tt), (rd, td) = qs, us
    return (m * (rd**2 + rr**2 * td**2) / 2 + m * g * rr * sp.cos(tt)
            - k * (rr - l0) ** 2 / 2)


def cart_lagrangian(qs, us):
    (_, tt), (xd, td) = qs, us
    vx, vy = xd + l * sp.cos(tt) * td, l * sp.sin(tt) * td
    return big_m * xd**2 / 2 + m * (vx**2 + vy**2) / 2 + m * g * l * sp.cos(tt)


def same(a, b) -> bool:
    return all(is_identically_zero(e) for e in (sp.Matrix(a) - sp.Matrix(b)))


@pytest.mark.parametrize("make, lagrangian, coordinates",
                         [(elastic, elastic_lagrangian, [r, th]),
                          (cart, cart_lagrangian, [x, th])], ids=["elastic", "cart"])
def test_equations_equal_lagranges_method(make, lagrangian, coordinates):
    system = make()
    mass, forcing = lagranges_method(lagrangian, coordinates)
    assert same(system.mass_matrix, mass)
    assert same(system.forcing, forcing)


def test_negative_control_a_changed_system_differs_from_lagranges_method():
    mass, forcing = lagranges_method(elastic_lagrangian, [r, th])
    assert not same(elastic(extra_potential=m * g * r / 100).forcing, forcing)
    mass, forcing = lagranges_method(cart_lagrangian, [x, th])
    assert not same(cart(bob_offset=l * sp.sin(th) / 10).mass_matrix, mass)


def test_cart_equals_n_link_pendulum_on_cart():
    """SymPy's model measures the angle from the upward vertical: theta = q1 + pi."""
    kane = n_link_pendulum_on_cart(1, cart_force=False)
    q0, q1 = kane.q
    u0, u1 = kane.u
    m0, m1 = sp.symbols("m:2")
    (l_0,) = sp.symbols("l:1")
    gs = sp.Symbol("g")
    system = cart()
    ours = {x: q0, th: q1 + sp.pi, system.omega[0]: u0, system.omega[1]: u1,
            big_m: m0, m: m1, l: l_0, g: gs}
    mass = system.mass_matrix.xreplace(ours)
    forcing = system.forcing.xreplace(ours)
    theirs = {q0: sp.Symbol("a"), q1: sp.Symbol("b"), u0: sp.Symbol("c"), u1: sp.Symbol("d")}
    # forcing contains u's derivatives of q only through u: substitute the functions away
    assert same(mass.subs(theirs), kane.mass_matrix.subs(theirs))
    assert same(forcing.subs(theirs), kane.forcing.subs(theirs))
    assert not same((forcing + sp.Matrix([0, gs * m1 * l_0 / 10])).subs(theirs),
                    kane.forcing.subs(theirs))


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_general_derivation_of_a_chain_equals_chain(n):
    chain, general = derive_chain(n), chain_system(n)
    assert same(general.mass_matrix, chain.mass_matrix)
    assert same(general.forcing, chain.forcing)
    assert same(general.dlagrangian_dq, chain.dlagrangian_dq)
    assert same([general.potential], [chain.potential])
    assert all(b == 0 for b in general.momentum_offset)


def test_negative_control_chain_with_a_changed_length_differs():
    chain = derive_chain(2)
    general = chain_system(2)
    longer = general.mass_matrix.xreplace({chain.lengths[1]: 2 * chain.lengths[1]})
    assert not same(longer, chain.mass_matrix)


def test_moving_pivot_gives_momentum_offset_and_legendre_transform():
    a, w = sp.symbols("a w", positive=True)
    kapitza = MechanicalSystem([th], {m: 1.0, l: 1.0, g: 9.81, a: 0.05, w: 100.0},
                               points=[(l * sp.sin(th), a * sp.cos(w * t) - l * sp.cos(th))],
                               masses=[m], gravity=g)
    assert not kapitza.autonomous
    assert is_identically_zero(kapitza.momentum_offset[0]
                               + a * w * m * l * sp.sin(w * t) * sp.sin(th))
    # effective gravity g + y_pivot'': the classic form of the Kapitza equation
    expected = -m * l * (g - a * w**2 * sp.cos(w * t)) * sp.sin(th)
    assert is_identically_zero(kapitza.forcing[0] - expected)
    # H(q, p(q, q')) equals the Legendre transform q' p - L
    at = {kapitza.p[0]: kapitza.momenta[0]}
    assert is_identically_zero(kapitza.hamiltonian.xreplace(at) - kapitza.legendre_transform())
    dq, dp = kapitza.hamilton_equations
    assert is_identically_zero(dq[0].xreplace(at) - kapitza.omega[0])
    with pytest.raises(ValueError, match="depend on the time t"):
        kapitza.equilibria()


def test_elastic_equilibria_and_normal_modes():
    system = elastic()
    found = {eq.angles: eq for eq in system.equilibria()}
    down = found[(l0 + m * g / k, 0)]
    assert (l0 - m * g / k, sp.pi) in found
    assert down.classify(system.defaults) == "center"
    values = [sp.simplify(-mu) for mu in down.stiffness_ratio.eigenvals()]
    assert set(values) == {k / m, g * k / (g * m + k * l0)}


def test_lagrangian_given_directly_equals_points():
    rd, td = sp.symbols("r_dot theta_dot", real=True)
    lagrangian = elastic_lagrangian((r, th), (rd, td))
    direct = MechanicalSystem([r, th], {m: 1.0, k: 40.0, l0: 1.0, g: 9.81},
                              lagrangian=lagrangian)
    assert same(direct.forcing, elastic().forcing)
    assert same(direct.mass_matrix, elastic().mass_matrix)


def test_rayleigh_dissipation_and_forces_enter_forcing():
    c, f = sp.symbols("c f", positive=True)
    damped = MechanicalSystem([th], {m: 1.0, l: 1.0, g: 9.81, c: 0.1, f: 1.0},
                              points=[(l * sp.sin(th), -l * sp.cos(th))], masses=[m], gravity=g,
                              dissipation=c * sp.Symbol("theta_dot", real=True) ** 2 / 2,
                              forces=[f * sp.cos(t)])
    w = damped.omega[0]
    assert damped.forced
    assert sp.expand(damped.forcing[0] - (-g * l * m * sp.sin(th) - c * w + f * sp.cos(t))) == 0


def test_clock_parameters_read_the_forces_as_well_as_the_lagrangian():
    f, drive = sp.symbols("f Omega", positive=True)
    pendulum = {"points": [(l * sp.sin(th), -l * sp.cos(th))], "masses": [m], "gravity": g}
    values = {m: 1.0, l: 1.0, g: 9.81, f: 1.0, drive: 2.0}
    driven = MechanicalSystem([th], values, forces=[f * sp.cos(drive * t)], **pendulum)
    assert driven.clock_parameters == ("Omega",)
    assert not driven.autonomous
    # negative controls: a force without the time sets no clock, nor does a bare cos(t)
    steady = MechanicalSystem([th], values, forces=[f * sp.sin(th)], **pendulum)
    assert steady.clock_parameters == () and steady.autonomous
    bare = MechanicalSystem([th], values, forces=[f * sp.cos(t)], **pendulum)
    assert bare.clock_parameters == () and not bare.autonomous


# ---- refusals -------------------------------------------------------------------------------
def test_refuses_lagrangian_not_quadratic_in_velocities():
    rd, td = sp.symbols("r_dot theta_dot", real=True)
    with pytest.raises(ValueError, match="degree at most two.*got degree 4"):
        MechanicalSystem([r, th], {m: 1.0}, lagrangian=m * rd**4 + m * td**2)
    with pytest.raises(ValueError, match="not a polynomial"):
        MechanicalSystem([r, th], {m: 1.0}, lagrangian=m * sp.cos(rd) + m * td**2)


def test_refuses_singular_mass_matrix_naming_the_redundant_coordinates():
    y = sp.Symbol("y", real=True)
    with pytest.raises(ValueError, match="singular: the coordinates x, y are redundant"):
        MechanicalSystem([x, y], {m: 1.0}, points=[(x + y, 0)], masses=[m])
    with pytest.raises(ValueError, match=r"`masses\[0\]` = -m must be non-negative"):
        MechanicalSystem([x], {m: 1.0}, points=[(x, 0)], masses=[-m])
    x_dot = sp.Symbol("x_dot", real=True)
    with pytest.raises(ValueError, match="not positive definite"):
        MechanicalSystem([x], {m: 1.0}, lagrangian=-m * x_dot**2 / 2)


def test_refuses_undeclared_symbols_naming_them():
    with pytest.raises(ValueError, match="`potential` uses g, k, which are neither a coordinate "
                                         r"\(r, theta\).*declare them in `parameters`"):
        MechanicalSystem([r, th], {m: 1.0}, points=[(r * sp.sin(th), -r * sp.cos(th))],
                         masses=[m], potential=k * (r - 1) ** 2 - m * g * r * sp.cos(th))
    with pytest.raises(ValueError, match="`gravity` uses g, which is neither"):
        MechanicalSystem([x], {m: 1.0}, points=[(x, 0)], masses=[m], gravity=g)


@pytest.mark.parametrize("value, error, words", [
    (math.nan, ValueError, "finite"), (math.inf, ValueError, "finite"),
    (1 + 2j, ValueError, "a real number"), ("1", TypeError, "a real number"),
    (True, TypeError, "a real number")])
def test_refuses_non_real_or_non_finite_parameters(value, error, words):
    with pytest.raises(error, match=rf"`parameters\[m\]` must be {words}"):
        MechanicalSystem([x], {m: value}, points=[(x, 0)], masses=[m])


def test_refuses_malformed_descriptions():
    with pytest.raises(TypeError, match="exactly one of `points`"):
        MechanicalSystem([x], {m: 1.0})
    with pytest.raises(TypeError, match="`coordinates` must hold SymPy symbols"):
        MechanicalSystem(["x"], {m: 1.0}, points=[(x, 0)], masses=[m])
    with pytest.raises(ValueError, match="`masses` must hold one mass per point"):
        MechanicalSystem([x], {m: 1.0}, points=[(x, 0)], masses=[])
    with pytest.raises(ValueError, match="both coordinate x and parameter x"):
        MechanicalSystem([x], {x: 1.0}, points=[(x, 0)], masses=[1])
