"""Bad input to the public functions of the geometric layer: a clear error naming the argument.

Each case names the argument (or the model's problem) and what is accepted; the
last test shows that the same functions accept the valid neighbours of these
inputs, so the checks do not refuse everything.
"""

import numpy as np
import pytest
import sympy as sp

import pendulum_lab as pl
from pendulum_lab import analysis
from pendulum_lab import discrete_mechanics as dm
from pendulum_lab.geometric import adaptive as ad
from pendulum_lab.geometric import backward_error as be
from pendulum_lab.geometric import long_time as lt
from pendulum_lab.geometric import modified_equations as me
from pendulum_lab.geometric import phase_space as ps
from pendulum_lab.geometric import standard_map as sm

SP = pl.simple_pendulum()
DP = pl.double_pendulum()
DAMPED = pl.driven_pendulum()
DRIVEN = DAMPED.replace(damping=0.0)
FORCED = "must be conservative and autonomous"

CASES = {
    # unsupported models: damped or driven, or the wrong number of links
    "modified_hamiltonian, damped": (lambda: be.modified_hamiltonian(DAMPED, "leapfrog", 1),
                                     ValueError, FORCED),
    "modified_hamiltonian, driven": (lambda: be.modified_hamiltonian(DRIVEN, "leapfrog", 1),
                                     ValueError, FORCED),
    "modified_hamiltonian, n = 3": (lambda: be.modified_hamiltonian(pl.n_pendulum(3),
                                                                    "leapfrog", 1),
                                    ValueError, "simple or a double pendulum"),
    "modified_equation, damped": (lambda: be.modified_equation(DAMPED, "rk4", 1), ValueError,
                                  FORCED),
    "modified_equation, n = 2": (lambda: be.modified_equation(DP, "rk4", 1), ValueError,
                                 "simple pendulum"),
    "exact_libration, driven": (lambda: lt.exact_libration(DRIVEN, 1.0, [0.0]), ValueError,
                                FORCED),
    "standard map, damped": (lambda: sm.to_standard_map(DAMPED, [0.0], [0.0], 0.1), ValueError,
                             FORCED),
    "naive leapfrog, damped": (lambda: ad.naive_adaptive_leapfrog(DAMPED, [1.0], [0.0],
                                                                  t_end=1.0, tol=1e-2),
                               ValueError, FORCED),
    "Sundman leapfrog, driven": (lambda: ad.reversible_adaptive_leapfrog(
        DRIVEN, [1.0], [0.0], t_end=1.0, epsilon=0.1), ValueError, FORCED),
    "Poincare transform, damped": (lambda: ad.poincare_adaptive_midpoint(
        DAMPED, [1.0], [0.0], t_end=1.0, epsilon=0.1), ValueError, FORCED),
    "step density, not a model": (lambda: ad.step_density("pendulum", [1.0], [0.0]), TypeError,
                                  "`model` must be a PendulumModel"),
    "hamiltonian_function, not a model": (lambda: be.hamiltonian_function("pendulum", 0),
                                          TypeError, "`model` must be a PendulumModel"),
    # unknown methods, rules and options
    "modified_hamiltonian, variational": (lambda: be.modified_hamiltonian(
        SP, "variational_midpoint", 1), ValueError, "`method` must be one of"),
    "modified_equation, conformal": (lambda: be.modified_equation(SP, "conformal_euler", 1),
                                     ValueError, "`method` must be one of"),
    "reference_step, unknown rule": (lambda: dm.reference_step(1, "simpson", SP.parameter_values,
                                                               [0.1], [0.0], 0.1),
                                     ValueError, "`rule`"),
    "round trip, unknown method": (lambda: ad.round_trip_error(SP, "adaptive", [1.0], [0.0],
                                                               steps=3),
                                   ValueError, "`method` must be 'reversible' or 'naive'"),
    "round trip, missing option": (lambda: ad.round_trip_error(SP, "reversible", [1.0], [0.0],
                                                               steps=3),
                                   TypeError, r"missing \['epsilon'\]"),
    "round trip, unknown option": (lambda: ad.round_trip_error(SP, "naive", [1.0], [0.0], steps=3,
                                                               tol=1e-2, epsilon=0.1),
                                   TypeError, r"unknown \['epsilon'\]"),
    "scipy_run, unknown solver": (lambda: analysis.scipy_run(SP, [1.0], [0.0], t_end=1.0,
                                                             method="LSODA"),
                                  ValueError, "`method` must be 'RK45' or 'DOP853'"),
    # orders, counts and sizes out of range
    "modified_energy_orders, no orders": (lambda: be.modified_energy_orders(
        SP, "leapfrog", [1.0], [0.0], dts=[0.1, 0.05], orders=[], t_end=1.0), ValueError,
        "`orders`"),
    "energy_drift, one step size": (lambda: be.energy_drift(SP, "rk4", 1.0, dts=[0.1],
                                                            t_end=10.0),
                                    ValueError, "`dts` must hold at least two"),
    "abstract_problem, n = 0": (lambda: me.abstract_problem(0, False), ValueError, "`n`"),
    "step_series, order 0": (lambda: me.step_series("leapfrog", sp.Symbol("x"),
                                                    [sp.Symbol("x")], [sp.Symbol("v")], 0),
                             ValueError, "`order`"),
    "ellipse_loop, 2 points": (lambda: ps.ellipse_loop([0.0, 0.0], np.eye(2), 2), ValueError,
                               "`points`"),
    "ellipse_loop, 2.5 points": (lambda: ps.ellipse_loop([0.0, 0.0], np.eye(2), 2.5), TypeError,
                                 "`points`"),
    "polygon_area, shapes": (lambda: ps.polygon_area([0.0, 1.0, 2.0], [0.0, 1.0]), ValueError,
                             "`x` and `y`"),
    "iterate, shapes": (lambda: sm.iterate([0.0, 1.0], [0.0, 1.0, 2.0], 1.0, 3), ValueError,
                        "`phi` and `action`"),
    "first_crossings, 2-d ks": (lambda: sm.first_crossings([[1.0]], [0.1], [0.0], 3), ValueError,
                                "`ks`"),
    "transport_threshold, a string": (lambda: sm.transport_threshold("100"), TypeError,
                                      "`iterations`"),
    "transport_threshold, empty": (lambda: sm.transport_threshold(()), TypeError,
                                   "`iterations`"),
    "crossing_times, K below K_c": (lambda: sm.crossing_times([-0.1]), ValueError, "`excess`"),
    "crossing_times, odd orbits": (lambda: sm.crossing_times([0.5], orbits=17), ValueError,
                                   "`orbits`"),
    "step density, frequency": (lambda: ad.step_density(SP, [1.0], [0.0], frequency=-1.0),
                                ValueError, "`frequency`"),
    "reference_step, shapes": (lambda: dm.reference_step(2, "midpoint", DP.parameter_values,
                                                         [0.1], [0.0], 0.1),
                               ValueError, r"`q0` and `p0` must have shape \(2,\)"),
    "reference_step, h = 0": (lambda: dm.reference_step(1, "midpoint", SP.parameter_values,
                                                        [0.1], [0.0], 0.0),
                              ValueError, "`h`"),
    "symplectic_form_defect, odd size": (lambda: analysis.symplectic_form_defect(np.eye(3)),
                                         ValueError, "`matrix`"),
    "finite_difference_jacobian, not callable": (lambda: analysis.finite_difference_jacobian(
        3.0, [0.0]), TypeError, "`function`"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_bad_input_gets_a_clear_error(case):
    call, error, message = CASES[case]
    with pytest.raises(error, match=message):
        call()


def test_the_valid_neighbours_are_accepted():
    assert be.modified_hamiltonian(DP, "semi_implicit_euler", 1).has(be.STEP_SIZE)
    assert len(be.modified_equation(SP, "rk4", 1)) == 2
    assert ps.ellipse_loop([0.0, 0.0], np.eye(2), 3).shape == (3, 2)
    assert float(ps.polygon_area([0.0, 1.0, 0.0], [0.0, 0.0, 1.0])) == 0.5
    assert sm.iterate([0.0, 1.0], [0.5], 1.0, 3)[0].shape == (4, 2)  # broadcasting is fine
    assert sm.first_crossings(1.0, [0.1], [0.0], 3).shape == (1, 1)
    assert ad.round_trip_error(SP, "naive", [1.0], [0.0], steps=3, tol=1e-2, h_initial=0.02) >= 0
    assert ad.step_density(SP, [1.0], [0.0], frequency=2.0).shape == (2,)
    q1, p1 = dm.reference_step(1, "midpoint", SP.parameter_values, [0.1], [0.0], -0.1)
    assert q1.shape == p1.shape == (1,)
