"""What a student may type into MechanicalSystem: each case a clear error naming the argument
or the name, or the right answer, with its negative control (a good neighbour accepted, or
the bad case let through without the check)."""

import os

import pytest
import sympy as sp

from pendulum_lab.symbolic import systems
from pendulum_lab.symbolic.systems import MAX_COORDINATES, MechanicalSystem

a, b, x, th = sp.symbols("a b x theta", real=True)
m, l, g = sp.symbols("m l g", positive=True)  # noqa: E741 (the rod's length, as written)
t = sp.Symbol("t", real=True)
x_dot = sp.Symbol("x_dot", real=True)
VALUES = {m: 1.0, l: 1.0, g: 9.81}


def pendulum(**changes):
    """A simple pendulum from its point, with some arguments changed."""
    arguments = dict(points=[(l * sp.sin(th), -l * sp.cos(th))], masses=[m], gravity=g)
    return MechanicalSystem([th], VALUES, **(arguments | changes))


# ---- names ---------------------------------------------------------------------------------
def test_a_coordinate_named_like_a_generated_momentum_is_refused_never_merged():
    p_a = sp.Symbol("p_a", real=True)
    with pytest.raises(ValueError, match="'p_a' is both coordinate p_a and the momentum of a"):
        MechanicalSystem([a, p_a], {}, points=[(a, 0), (0, p_a)], masses=[1, 1])
    # negative control: two other names give two momenta, Hamilton's equations uncoupled
    system = MechanicalSystem([a, b], {}, points=[(a, 0), (0, b)], masses=[1, 1])
    p = sp.symbols("p_a p_b", real=True)
    assert system.hamiltonian == p[0] ** 2 / 2 + p[1] ** 2 / 2
    assert list(system.hamilton_equations[0]) == list(p)


def test_a_coordinate_named_like_a_generated_velocity_is_refused():
    with pytest.raises(ValueError, match="'x_dot' is both coordinate x_dot and the velocity "
                                         "of x"):
        MechanicalSystem([x, x_dot], {}, points=[(x, x_dot)], masses=[1])
    # negative control: with the velocities named otherwise, the same coordinates are accepted
    v, w = sp.symbols("v w", real=True)
    system = MechanicalSystem([x, x_dot], {}, points=[(x, x_dot)], masses=[1],
                              velocities=[v, w])
    assert system.mass_matrix == sp.eye(2)


@pytest.mark.parametrize("assumptions", [{"real": True}, {}])
def test_a_coordinate_or_parameter_named_t_is_refused(assumptions):
    time_like = sp.Symbol("t", **assumptions)
    with pytest.raises(ValueError, match="'t' is both the time and coordinate t"):
        MechanicalSystem([time_like], VALUES, points=[(l * sp.sin(time_like), 0)], masses=[m])
    with pytest.raises(ValueError, match="'t' is both the time and parameter t"):
        MechanicalSystem([th], {m: 1.0, l: 1.0, "t": 9.81},
                         points=[(l * sp.sin(th), -l * sp.cos(th))], masses=[m],
                         gravity=time_like)
    # negative control: the time itself in a description is the time (a moving pivot)
    system = pendulum(points=[(l * sp.sin(th), sp.cos(t) - l * sp.cos(th))])
    assert not system.autonomous


def test_a_coordinate_named_like_a_parameter_is_refused():
    plain_m = sp.Symbol("m")
    with pytest.raises(ValueError, match="'m' is both coordinate m and parameter m"):
        MechanicalSystem([plain_m], VALUES, points=[(l * sp.sin(plain_m), 0)], masses=[m])


def test_a_symbol_with_other_assumptions_or_a_string_is_the_declared_symbol():
    plain_l, plain_th = sp.Symbol("l"), sp.Symbol("theta")
    declared = pendulum()
    other = pendulum(points=[(plain_l * sp.sin(plain_th), -plain_l * sp.cos(plain_th))])
    written = pendulum(points=[("l*sin(theta)", "-l*cos(theta)")], masses=["m"], gravity="g")
    for system in (other, written):
        assert system.mass_matrix == declared.mass_matrix
        assert system.forcing == declared.forcing
        assert system.lagrangian.free_symbols == declared.lagrangian.free_symbols
    # negative control: a name that is declared nowhere is still refused, and named
    with pytest.raises(ValueError, match="`points\\[0\\]` uses L, which is neither"):
        pendulum(points=[("L*sin(theta)", "-l*cos(theta)")])


# ---- strings ---------------------------------------------------------------------------------
@pytest.mark.parametrize("text", ["__import__('os').getcwd()", "().__class__", "m.func",
                                  "[m][0]", "lambda: 1", "getattr(m, 'func')", "'m'",
                                  "9**9**9**9", "theta**(2**1000)"])
def test_a_string_is_read_without_running_python(monkeypatch, text):
    called = []
    monkeypatch.setattr(os, "getcwd", lambda: called.append(True) or "/")
    with pytest.raises(ValueError, match="`potential` = .* which a description cannot"):
        pendulum(potential=text)
    assert not called


def test_a_string_of_arithmetic_and_accepted_functions_is_read():
    system = pendulum(potential="m*g*l*(1 - cos(theta))**2/2 + exp(-theta**2) + pi "
                                "+ theta**-2.5 + 2**theta")
    expected = pendulum(potential=m * g * l * (1 - sp.cos(th)) ** 2 / 2 + sp.exp(-th ** 2)
                        + sp.pi + th ** -2.5 + 2**th)
    assert system.potential == expected.potential
    # negative control: implicit multiplication is not Python, and is refused with a hint
    with pytest.raises(ValueError, match="is not an expression \\(write products with \\*"):
        pendulum(potential="2 theta")


# ---- the shape of the description ----------------------------------------------------------
def test_a_point_not_nested_is_refused_as_a_type_error():
    with pytest.raises(TypeError, match=r"`points\[0\]` must be an \(x, y\) pair"):
        pendulum(points=[l * sp.sin(th), -l * sp.cos(th)])
    with pytest.raises(ValueError, match=r"`points\[0\]` must be an \(x, y\) pair \(a point "
                                         r"in a plane\) or an \(x, y, z\) triple .*got 4"):
        pendulum(points=[(l * sp.sin(th), -l * sp.cos(th), 0, 0)])
    assert pendulum().points == [(l * sp.sin(th), -l * sp.cos(th))]  # negative control


@pytest.mark.parametrize("mass, message", [
    (1 + 2j, "must be a real mass"), (float("nan"), "must be a finite mass"),
    (float("inf"), "must be a finite mass"), (-2.0, "must be non-negative"),
    (sp.I, "numbers must be real and finite"), (th, "a mass does not change with the motion"),
])
def test_a_mass_that_is_not_real_finite_and_non_negative_is_refused_by_name(mass, message):
    with pytest.raises(ValueError, match=rf"`masses\[0\]`.*{message}"):
        pendulum(masses=[mass])


def test_a_real_finite_mass_is_accepted_as_a_number_or_an_expression():
    assert pendulum(masses=[2.0]).mass_matrix == sp.Matrix([[2.0 * l**2]])
    assert pendulum(masses=[2 * m]).mass_matrix == sp.Matrix([[2 * m * l**2]])
    pivot = pendulum(points=[(0, 0), (l * sp.sin(th), -l * sp.cos(th))], masses=[0, m])
    assert pivot.mass_matrix == sp.Matrix([[m * l**2]])  # a massless point


@pytest.mark.parametrize("forces", [1.0, th, "1.0"])
def test_forces_that_are_not_a_sequence_are_a_type_error_naming_forces(forces):
    with pytest.raises(TypeError, match="`forces` must be a sequence of expressions, one per "
                                        "coordinate"):
        pendulum(forces=forces)
    with pytest.raises(ValueError, match="`forces` must hold 1 expressions"):
        pendulum(forces=[1.0, 2.0])
    assert pendulum(forces=[1.0]).forced  # negative control


# ---- functions -----------------------------------------------------------------------------
@pytest.mark.parametrize("term, named", [
    (sp.Function("f")(th), "f \\(an undefined function\\)"), (sp.floor(th), "floor"),
    (sp.Integral(sp.sin(x) * th, (x, 0, 1)), "Integral"), (sp.Heaviside(th), "Heaviside"),
    (sp.Abs(th), "Abs"), (sp.sign(th), "sign"), (sp.Max(th, 0), "Max"),
    (sp.Derivative(sp.Function("f")(th), th), "Derivative"),
    (sp.Function("sin")(th), "sin \\(an undefined function\\)"),
])
def test_a_function_the_equations_cannot_be_generated_from_is_named_with_those_accepted(
        term, named):
    with pytest.raises(ValueError, match=rf"`potential` holds {named}.*may use only sin, cos"):
        pendulum(potential=term)


@pytest.mark.parametrize("constant, message", [
    (sp.GoldenRatio, "the constant GoldenRatio: the constants accepted are pi and E"),
    (sp.oo, "oo: numbers must be real and finite"), (sp.nan, "nan: numbers must be real"),
    (2 * sp.I, "I: numbers must be real and finite"),
])
def test_a_constant_that_is_not_a_real_finite_number_or_pi_or_e_is_refused(constant, message):
    with pytest.raises(ValueError, match=f"`potential` holds {message}"):
        pendulum(potential=constant * th)
    assert pendulum(potential=(sp.pi + sp.E) * th).potential.has(sp.pi)  # negative control


def test_the_accepted_functions_are_accepted_and_differentiated():
    potential = sp.tanh(th) + sp.atan(th) + sp.sqrt(2 + sp.cos(th)) + sp.log(2 + sp.sin(th))
    system = pendulum(potential=potential)
    assert system.forcing[0] == sp.expand(
        -m * g * l * sp.sin(th) - sp.diff(potential, th))


# ---- the mass matrix -------------------------------------------------------------------------
@pytest.mark.parametrize("kinetic, place", [
    (x * x_dot**2 / 2, "at x = -"), (sp.cos(t) * x_dot**2 / 2, "at t = "),
    ((1 - x**2 / 50) * x_dot**2 / 2, "at x = "),
])
def test_a_mass_matrix_indefinite_outside_the_unit_box_is_refused_with_the_place(kinetic,
                                                                                 place):
    with pytest.raises(ValueError, match=f"not positive definite {place}"):
        MechanicalSystem([x], {}, lagrangian=kinetic - x**2 / 2)


def test_without_the_search_the_unit_box_check_lets_an_indefinite_matrix_through(
        monkeypatch):
    # negative control of the search: the check at points in [0.3, 1.3] alone accepts it
    monkeypatch.setattr(MechanicalSystem, "_search_indefinite", lambda self, params: None)
    assert not MechanicalSystem([x], {}, lagrangian=x * x_dot**2 / 2).positivity_proved


def test_a_mass_matrix_positive_where_declared_is_proved_or_accepted():
    x_positive = sp.Symbol("x", positive=True)
    proved = MechanicalSystem([x_positive], {}, lagrangian=x_positive * x_dot**2 / 2)
    assert proved.positivity_proved
    assert MechanicalSystem([x], {m: 1.0}, lagrangian=m * x_dot**2 / 2).positivity_proved
    # positive but not proved by SymPy: accepted, and checked along each run
    hidden = MechanicalSystem([x], {}, lagrangian=(1 - x**2 / 4000) * x_dot**2 / 2)
    assert not hidden.positivity_proved
    # points with non-negative masses: positive semidefinite by construction
    assert pendulum().positivity_proved


def test_parameter_values_that_break_a_declared_assumption_are_refused():
    system = pendulum()
    with pytest.raises(ValueError, match="`m` must be positive \\(it is declared positive\\), "
                                         "got 0"):
        system.check_values(VALUES | {m: 0.0})
    plain_m = sp.Symbol("m")
    loose = MechanicalSystem([th], {plain_m: 1.0, l: 1.0}, points=[(l * sp.sin(th), 0)],
                             masses=[plain_m])
    with pytest.raises(ValueError, match=r"`masses\[0\]` = m must be non-negative and finite, "
                                         "got -1"):
        loose.check_values({plain_m: -1.0, l: 1.0})
    system.check_values(VALUES | {m: 2.0})  # negative control
    loose.check_values({plain_m: 2.0, l: 1.0})


# ---- size ------------------------------------------------------------------------------------
def test_more_coordinates_than_the_cap_are_refused_at_once_with_advice():
    angles = sp.symbols(f"q1:{MAX_COORDINATES + 2}", real=True)
    xs, ys, points = 0, 0, []
    for q in angles:
        xs, ys = xs + sp.sin(q), ys - sp.cos(q)
        points.append((xs, ys))
    with pytest.raises(ValueError, match=f"holds {MAX_COORDINATES + 1} coordinates: refused "
                                         f"beyond {MAX_COORDINATES}.*pl.n_pendulum"):
        MechanicalSystem(list(angles), {}, points=points, masses=[1] * len(points))
    # negative control: as many coordinates as the cap, each point on one, are derived
    free = MechanicalSystem(list(angles[:MAX_COORDINATES]), {},
                            points=[(q, 0) for q in angles[:MAX_COORDINATES]],
                            masses=[1] * MAX_COORDINATES)
    assert free.mass_matrix == sp.eye(MAX_COORDINATES)


def test_a_derivation_expected_to_be_long_shows_progress(monkeypatch, capsys):
    systems.chain_system(2)
    assert "kinetic energy" not in capsys.readouterr().err  # negative control: quick, quiet
    monkeypatch.setattr(systems, "PROGRESS_AFTER", 0.0)
    systems.chain_system(2)
    assert "kinetic energy of a chain of 2 links" in capsys.readouterr().err


def test_is_identically_zero_refuses_a_string_instead_of_running_it(monkeypatch):
    from pendulum_lab.symbolic.mechanics import is_identically_zero

    called = []
    monkeypatch.setattr(os, "getcwd", lambda: called.append(True) or "/")
    with pytest.raises(TypeError, match="`expr` must be a SymPy expression, got a string"):
        is_identically_zero("__import__('os').getcwd()")
    assert not called
    assert is_identically_zero(sp.sin(th) ** 2 + sp.cos(th) ** 2 - 1)  # negative control
