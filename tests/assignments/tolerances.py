"""How far correct answers to the graded assignments spread, against each hidden test's tolerance.

A hidden test compares a student's answer with the grader's own computation. A correct answer
computed on another machine, with another libm, another NumPy or another arrangement of the same
arithmetic differs from the grader's by round-off, and on a chaotic orbit by much more. This
module produces such answers and measures them in each test's own metric:

- **round-off histories**: the start of a computation nudged by a few units in the last place
  (``nudge``), which is what another machine's arithmetic does to a trajectory;
- **arrangements**: a step function written another way (``math`` or NumPy, another order of
  the operations, vectors or scalars), all correct;
- **routes and step sizes the question allows** (a root finder's tolerance, dt = 0.005 beside
  0.01 for the chaotic estimate);
- **both ends of the dependency ranges**: run this file in an environment with the floors
  pinned (``tools/floor_pins.py``) with ``--save floors.json``, then in the newest with
  ``--against floors.json``: each answer computed there is measured against the grader's
  computation here, and the other way round.

``python tests/assignments/tolerances.py`` prints the table (question, test, spread measured,
tolerance, the nearest plausible wrong answer); ``--histories N`` sets the number of round-off
histories of each answer (16), ``--draws N`` those of the chaotic estimate per step size
(256). The suite (``test_assignments_tolerances.py``) grades a few of these answers with the
hidden tests themselves, called directly, and a wrong answer per question, which must fail.
"""

from __future__ import annotations

import argparse
import ast
import contextlib
import io
import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import nbformat
import numpy as np
import sympy as sp

ASSIGNMENTS = Path(__file__).resolve().parents[2] / "assignments"
G = 9.81


# ------------------------------------------------------------------ the tests of the masters
def master_tests(name: str) -> tuple[dict, dict]:
    """The hidden and the public tests of assignment ``name`` as functions.

    Returns ``hidden``, keyed by ``(question, function name)``, and ``public``, keyed by
    question. Each test cell's functions are executed on their own (the cell's closing call
    left out), so a test is called with answers as arguments, as the grader's kernel does.
    """
    notebook = nbformat.read(ASSIGNMENTS / f"{name}.ipynb", as_version=4)
    hidden, public, question, in_tests = {}, {}, None, False
    for cell in notebook.cells:
        source = cell.source.strip()
        if cell.cell_type == "raw":
            if source.startswith("# BEGIN QUESTION"):
                question = next(line.split(":", 1)[1].strip() for line in source.splitlines()
                                if line.startswith("name:"))
            in_tests = {"# BEGIN TESTS": True, "# END TESTS": False}.get(source, in_tests)
            continue
        if cell.cell_type != "code" or not in_tests:
            continue
        tree = ast.parse(cell.source)
        functions = [node for node in tree.body if isinstance(node, ast.FunctionDef)]
        namespace: dict = {}
        exec(compile(ast.Module(body=functions, type_ignores=[]), f"<{name} {question}>",
                     "exec"), namespace)
        for node in functions:
            if source.startswith("# HIDDEN"):
                hidden[(question, node.name)] = namespace[node.name]
            else:
                public[question] = namespace[node.name]
    return hidden, public


def passes(test, answers: dict) -> tuple[bool, str]:
    """Call ``test`` with the answers its parameters name: passed, and what it printed or raised."""
    names = test.__code__.co_varnames[:test.__code__.co_argcount]
    out = io.StringIO()
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
            test(*(answers[n] for n in names))
    except AssertionError as failure:  # ExerciseNotPassed is one
        return False, str(failure)
    return True, out.getvalue()


def nudge(x: float, k: int) -> float:
    """``x`` moved by ``k`` units in the last place: one round-off history per ``k``."""
    for _ in range(abs(k)):
        x = float(np.nextafter(x, math.copysign(math.inf, k)))
    return x


# ------------------------------------------------------------------ step functions, arranged
# Correct steps written in different ways (history % len picks one): the arrangements a class
# hands in, whose results differ from each other and from the package's by round-off.
def _euler_steps():
    def vector(theta, p, h):
        y = np.array([theta, p])
        new = y + h * np.array([p, -G * np.sin(theta)])
        return float(new[0]), float(new[1])
    return [lambda theta, p, h: (theta + h * p, p - h * G * np.sin(theta)),
            lambda theta, p, h: (p * h + theta, p - G * math.sin(theta) * h),
            vector]


def _leapfrog_steps():
    def kicks(theta, p, h):
        def kick(angle, momentum, tau):
            return momentum - tau * G * math.sin(angle)
        p_half = kick(theta, p, h / 2)
        theta = theta + h * p_half
        return theta, kick(theta, p_half, h / 2)

    def solution(theta, p, h):
        p_half = p - 0.5 * h * G * np.sin(theta)
        theta_new = theta + h * p_half
        return theta_new, p_half - 0.5 * h * G * np.sin(theta_new)
    return [solution, kicks,
            lambda theta, p, h: _leapfrog_scaled(theta, p, h)]


def _leapfrog_scaled(theta, p, h):
    force = -G * np.sin(theta)
    p_half = p + force * (h / 2)
    theta_new = p_half * h + theta
    return float(theta_new), float(p_half + (-G * np.sin(theta_new)) * (h / 2))


def _rk4_steps(field_of):
    """RK4 steps for ``field_of(t, theta, p) -> (dtheta, dp)``: vector and scalar forms."""
    def vector(t, theta, p, h):
        def f(time, y):
            return np.array(field_of(time, y[0], y[1]))
        y = np.array([theta, p], dtype=float)
        k1 = f(t, y)
        k2 = f(t + h / 2, y + h / 2 * k1)
        k3 = f(t + h / 2, y + h / 2 * k2)
        k4 = f(t + h, y + h * k3)
        new = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        return float(new[0]), float(new[1])

    def scalar(t, theta, p, h):
        a1, b1 = field_of(t, theta, p)
        a2, b2 = field_of(t + 0.5 * h, theta + 0.5 * h * a1, p + 0.5 * h * b1)
        a3, b3 = field_of(t + 0.5 * h, theta + 0.5 * h * a2, p + 0.5 * h * b2)
        a4, b4 = field_of(t + h, theta + h * a3, p + h * b3)
        return (theta + h * (a1 + 2 * a2 + 2 * a3 + a4) / 6,
                p + (h / 6) * (b1 + b4) + (h / 3) * (b2 + b3))
    return [vector, scalar]


def _pendulum_field(t, theta, p):
    return p, -G * math.sin(theta)


def _driven_field(t, theta, omega):
    return omega, -0.5 * omega - math.sin(theta) + 1.2 * math.cos(2.0 / 3.0 * t)


def _adjoint_steps():
    def solution(theta, p, h):
        theta_new = theta + h * p
        return theta_new, p - h * G * np.sin(theta_new)
    return [solution, lambda theta, p, h: (p * h + theta, p - G * h * math.sin(p * h + theta))]


def _pick(variants, history):
    return variants[history % len(variants)]


# ------------------------------------------------------------------ correct answers, perturbed
def answers_01(history: int = 0) -> dict:
    """Assignment 01: symbolic answers in one of their correct forms; numbers from nudged starts."""
    from scipy.optimize import brentq, newton

    import pendulum_lab as pl
    from pendulum_lab import analysis

    m, l, g = sp.symbols("m l g", positive=True)  # noqa: E741
    theta, omega, p = sp.symbols("theta omega p", real=True)
    # Other correct forms (whole multiples of theta only: is_identically_zero, which the
    # hidden tests use, does not relate theta / 2 to theta).
    lagrangians = [m * l**2 * omega**2 / 2 + m * g * l * sp.cos(theta),
                   sp.Rational(1, 2) * m * ((l * omega * sp.cos(theta)) ** 2
                                            + (l * omega * sp.sin(theta)) ** 2)
                   + m * g * l * (1 - 2 * sp.sin(theta) ** 2 + sp.cos(2 * theta)
                                  + 2 * sp.cos(theta)) / 2 - m * g * l * sp.cos(2 * theta)]
    hamiltonians = [p**2 / (2 * m * l**2) - m * g * l * sp.cos(theta),
                    (p / l) ** 2 / (2 * m) - m * g * l * (sp.cos(2 * theta) * sp.cos(theta)
                                                          + sp.sin(2 * theta) * sp.sin(theta))]
    jacobians = [sp.Matrix([[0, 1 / (m * l**2)], [m * g * l, 0]]),
                 sp.Matrix([[0, l**-2 / m], [-m * g * l * sp.cos(sp.pi), 0]])]
    k = history
    # Normal modes: the solution's route (eigenvalues of M^-1 K), or the exact roots.
    double = pl.double_pendulum()
    if k % 2:
        modes = np.sqrt(np.array([2 - math.sqrt(2), 2 + math.sqrt(2)]) * nudge(9.81, k))
    else:
        modes = analysis.normal_mode_frequencies(double)
    swing = pl.simulate(pl.simple_pendulum(), [nudge(2.0, k)], [0.0], t_end=30.0, dt=0.01,
                        method="glrk4", keep="all", progress=False)
    pendulum = pl.simple_pendulum()
    small = 2 * np.pi * np.sqrt(pendulum.lengths[0] / pendulum.g)

    def excess(a):
        return analysis.exact_period(pendulum, a) / small - 1.1
    if k % 3 == 1:
        amplitude = newton(excess, nudge(1.0, k))
    else:  # brentq at its default tolerance, or at the solution's
        amplitude = brentq(excess, 0.1, 3.0, **({} if k % 3 else {"xtol": 1e-12}))
    return {"lagrangian": lagrangians[k % 2], "hamiltonian": hamiltonians[k % 2],
            "jacobian_up": jacobians[k % 2], "normal_modes": modes,
            "period_2rad": float(analysis.oscillation_period(swing)),
            "amplitude_10_percent": float(amplitude)}


def answers_02(history: int = 0) -> dict:
    import pendulum_lab as pl
    from pendulum_lab import analysis

    k = history
    g, l, y = sp.symbols("g l", positive=True) + (sp.symbols("y", positive=True),)  # noqa: E741
    fit = analysis.observed_order(pl.double_pendulum(), [nudge(2.0, k), nudge(2.5, -k)],
                                  [0.0, 0.0], method="rk4", dts=analysis.order_steps("rk4"))
    rk4 = _pick(_rk4_steps(_pendulum_field), k)
    return {"explicit_euler_step": _pick(_euler_steps(), k),
            "leapfrog_step": _pick(_leapfrog_steps(), k),
            "rk4_step": lambda theta, p, h: rk4(0.0, theta, p, h),
            "rk4_double_order": float(fit.slope),
            "leapfrog_limit": [2 / sp.sqrt((2 + sp.sqrt(2)) * g / l),
                               sp.sqrt(2 * l / g) * sp.sqrt(2 - sp.sqrt(2))][k % 2],
            "energy_factor": [1 + y**2, (1 + sp.I * y) * (1 - sp.I * y)][k % 2]}


def answers_03(history: int = 0) -> dict:
    import pendulum_lab as pl
    from pendulum_lab import analysis, geometric

    k = history
    m, l, g = sp.symbols("m l g", positive=True)  # noqa: E741
    theta, p, h = sp.symbols("theta p h", real=True)
    double = pl.double_pendulum()
    J = np.block([[np.zeros((2, 2)), np.eye(2)], [-np.eye(2), np.zeros((2, 2))]])
    start = [nudge(2.0, k), nudge(2.5, k // 2)]

    def defect(method):
        psi = analysis.step_jacobian(double, start, p0=[0.0, 0.0], dt=0.1, method=method)
        return float(np.max(np.abs(psi.T @ J @ psi - J)))
    pendulum = pl.simple_pendulum(mass=1.0, length=1.0, g=G)
    run = pl.simulate(pendulum, [nudge(1.5, k)], [0.0], t_end=100.0, dt=0.05,
                      method="semi_implicit_euler", progress=False)
    if k % 2:  # the energy written out, not the run's
        energy = run.p[:, 0] ** 2 / 2 - G * np.cos(run.theta[:, 0])
    else:
        energy = run.energy
    modified = geometric.modified_energy(pendulum, "semi_implicit_euler", 1)(run.theta, run.p,
                                                                              0.05)
    return {"adjoint_euler_step": _pick(_adjoint_steps(), k),
            "defect_rk4": defect("rk4"), "defect_gl4": defect("glrk4"),
            "H1": [-g * p * sp.sin(theta) / (2 * l), -(m * g * l * sp.sin(theta))
                   * (p / (m * l**2)) / 2][k % 2],
            "energy_error": float(np.max(np.abs(energy - energy[0]))),
            "modified_error": float(np.max(np.abs(modified - modified[0]))),
            "area_factor": [1 + h**2 * g * sp.cos(theta) / l,
                            sp.Matrix([[1, h / (m * l**2)],
                                       [-h * m * g * l * sp.cos(theta), 1]]).det()][k % 2]}


def answers_04(history: int = 0, *, chaotic: float | None = None) -> dict:
    """Assignment 04; ``chaotic`` replaces the 200 s estimate (it is measured as an ensemble)."""
    import pendulum_lab as pl
    from pendulum_lab import chaos

    k = history
    double = pl.double_pendulum()
    if chaotic is None:
        chaotic = chaos.lyapunov_benettin(double, [nudge(2.0, k), 2.5], [0.0, 0.0],
                                          t_end=200, progress=False).exponent
    regular = chaos.lyapunov_benettin(double, [nudge(0.1, k), 0.1], [0.0, 0.0], t_end=200,
                                      progress=False).exponent
    c, Omega = sp.symbols("c Omega", positive=True)

    def section(amplitude):
        return chaos.stroboscopic_section(pl.driven_pendulum(drive_amplitude=amplitude),
                                          [nudge(0.2, k)], [0.0], n_periods=64,
                                          transient_periods=300, progress=False)
    periods = [int(chaos.orbit_periods(s.theta, s.omega)) for s in map(section, (1.07, 1.47))]
    step = _pick(_rk4_steps(_driven_field), k)
    return {"lyapunov_chaotic": float(chaotic), "lyapunov_regular": float(regular),
            "driven_rk4_step": step,
            "area_per_period": [sp.exp(-2 * sp.pi * c / Omega),
                                sp.exp(-sp.pi * c / Omega) ** 2][k % 2],
            "omega_on_attractor": float(section(0.9).omega[-1][0]),
            "period_at_107": periods[0], "period_at_147": periods[1]}


ANSWERS = {"01_derivations_and_fixed_points": answers_01,
           "02_integrators_and_orders": answers_02,
           "03_symplecticity_and_modified_hamiltonian": answers_03,
           "04_chaos_and_the_driven_pendulum": answers_04}


def chaotic_estimates(histories: int, dt: float = 0.01) -> np.ndarray:
    """The 200 s estimate from (2.0, 2.5) in ``histories`` round-off histories (one ensemble)."""
    import pendulum_lab as pl
    from pendulum_lab import chaos

    theta1 = np.array([nudge(2.0, k) for k in range(histories)])
    starts = np.stack([theta1, np.full(histories, 2.5)], axis=-1)
    return np.asarray(chaos.lyapunov_benettin(pl.double_pendulum(), starts, np.zeros_like(starts),
                                              t_end=200, dt=dt, progress=False).exponent)


# ------------------------------------------------------------------ plausible wrong answers
def wrong_answers(name: str) -> list[tuple[str, str, dict]]:
    """Per assignment: (question, the slip, the answers changed): each must lose points."""
    m, l, g = sp.symbols("m l g", positive=True)  # noqa: E741
    theta, omega, p, h = sp.symbols("theta omega p h", real=True)
    y = sp.symbols("y", positive=True)
    c, Omega = sp.symbols("c Omega", positive=True)
    gs, ls = sp.symbols("g l", positive=True)
    base = cached_answers(name)
    if name.startswith("01"):
        return [
            ("q1_lagrangian", "the potential's sign flipped",
             {"lagrangian": m * l**2 * omega**2 / 2 - m * g * l * sp.cos(theta)}),
            ("q2_hamiltonian", "the mass left out of the kinetic term",
             {"hamiltonian": p**2 / (2 * l**2) - m * g * l * sp.cos(theta)}),
            ("q3_jacobian_up", "the Jacobian at the bottom, not the top",
             {"jacobian_up": sp.Matrix([[0, 1 / (m * l**2)], [-m * g * l, 0]])}),
            ("q4_normal_modes", "the coupling dropped (diagonal of M^-1 K only)",
             {"normal_modes": np.sqrt(np.array([9.81, 2 * 9.81]))}),
            ("q5_period_from_simulation", "the leapfrog at the same step",
             {"period_2rad": _leapfrog_period()}),
            ("q6_ten_percent_amplitude", "read off a plot to two digits",
             {"amplitude_10_percent": 1.07}),
        ]
    if name.startswith("02"):
        euler = _euler_steps()[0]
        return [
            ("q1_explicit_euler", "the new angle used in the kick (symplectic Euler)",
             {"explicit_euler_step": lambda t_, p_, h_: (t_ + h_ * p_,
                                                         p_ - h_ * G * np.sin(t_ + h_ * p_))}),
            ("q2_leapfrog", "explicit Euler handed in as the leapfrog",
             {"leapfrog_step": euler}),
            ("q2_leapfrog", "both half kicks at the old angle (not symmetric, not symplectic)",
             {"leapfrog_step": lambda t_, p_, h_: (t_ + h_ * (p_ - h_ / 2 * G * np.sin(t_)),
                                                   p_ - h_ * G * np.sin(t_))}),
            ("q3_rk4", "the last stage at h/2",
             {"rk4_step": _wrong_rk4}),
            ("q4_measured_order", "the textbook order", {"rk4_double_order": 4.0}),
            ("q5_leapfrog_limit", "the slow mode's frequency",
             {"leapfrog_limit": 2 / sp.sqrt((2 - sp.sqrt(2)) * gs / ls)}),
            ("q6_euler_energy_factor", "the amplification, not its square",
             {"energy_factor": sp.sqrt(1 + y**2)}),
        ]
    if name.startswith("03"):
        return [
            ("q1_adjoint_euler", "symplectic Euler itself (kick first)",
             {"adjoint_euler_step": lambda t_, p_, h_: (
                 t_ + h_ * (p_ - h_ * G * np.sin(t_)), p_ - h_ * G * np.sin(t_))}),
            ("q2_symplecticity_defects", "the Jacobian in (theta, omega) (RK4's defect)",
             {"defect_rk4": _defect_in_omega(), "defect_gl4": 3e-10}),
            ("q2_symplecticity_defects", "GL4's defect given as exactly 0",
             {"defect_rk4": base["defect_rk4"], "defect_gl4": 0.0}),
            ("q3_modified_hamiltonian", "the sign of -1/2 lost",
             {"H1": g * p * sp.sin(theta) / (2 * l)}),
            ("q4_modified_energy_kept", "a step of 0.045",
             dict(zip(("energy_error", "modified_error"), _energy_errors(0.045), strict=True))),
            ("q5_euler_area_factor", "1, as for a symplectic step", {"area_factor": sp.Integer(1)}),
        ]
    return [
        ("q1_lyapunov", "log10 in place of the natural logarithm",
         {"lyapunov_chaotic": base["lyapunov_chaotic"] / math.log(10)}),
        ("q1_lyapunov", "the exponent per step of 0.01 s, not per second",
         {"lyapunov_chaotic": base["lyapunov_chaotic"] * 0.01}),
        ("q1_lyapunov", "the two releases swapped",
         {"lyapunov_chaotic": base["lyapunov_regular"],
          "lyapunov_regular": base["lyapunov_chaotic"]}),
        ("q2_driven_rk4_step", "the drive at the start of the step for every stage",
         {"driven_rk4_step": _pick(_rk4_steps(lambda t, a, b: _driven_field(0.0, a, b)), 0)}),
        ("q3_area_per_period", "over half a drive period",
         {"area_per_period": sp.exp(-sp.pi * c / Omega)}),
        ("q4_period_one_attractor", "the default drive F = 1.2, not 0.9",
         {"omega_on_attractor": _sample_at(1.2, 300)}),
        ("q5_attractor_periods", "the two periods swapped",
         {"period_at_107": base["period_at_147"],
          "period_at_147": base["period_at_107"]}),
    ]


def _leapfrog_period() -> float:
    import pendulum_lab as pl
    from pendulum_lab import analysis

    swing = pl.simulate(pl.simple_pendulum(), [2.0], [0.0], t_end=30.0, dt=0.01,
                        method="leapfrog", progress=False)
    return float(analysis.oscillation_period(swing))


def _wrong_rk4(theta, p, h):
    a1, b1 = _pendulum_field(0, theta, p)
    a2, b2 = _pendulum_field(0, theta + h / 2 * a1, p + h / 2 * b1)
    a3, b3 = _pendulum_field(0, theta + h / 2 * a2, p + h / 2 * b2)
    a4, b4 = _pendulum_field(0, theta + h / 2 * a3, p + h / 2 * b3)
    return theta + h * (a1 + 2 * a2 + 2 * a3 + a4) / 6, p + h * (b1 + 2 * b2 + 2 * b3 + b4) / 6


def _defect_in_omega() -> float:
    import pendulum_lab as pl
    from pendulum_lab import analysis

    return float(analysis.symplecticity_defect(pl.double_pendulum(), [2.0, 2.5], p0=[0.0, 0.0],
                                               dt=0.1, method="rk4", variables="velocity"))


def _energy_errors(dt: float) -> tuple[float, float]:
    import pendulum_lab as pl
    from pendulum_lab import geometric

    pendulum = pl.simple_pendulum(mass=1.0, length=1.0, g=G)
    run = pl.simulate(pendulum, [1.5], [0.0], t_end=100.0, dt=dt, method="semi_implicit_euler",
                      progress=False)
    kept = geometric.modified_energy(pendulum, "semi_implicit_euler", 1)(run.theta, run.p, dt)
    return (float(np.max(np.abs(run.energy - run.energy[0]))),
            float(np.max(np.abs(kept - kept[0]))))


def _sample_at(amplitude: float, transient: int) -> float:
    """The last sample of the section of Q4 at another drive or after another transient."""
    import pendulum_lab as pl
    from pendulum_lab import chaos

    section = chaos.stroboscopic_section(pl.driven_pendulum(drive_amplitude=amplitude), [0.2],
                                         [0.0], n_periods=1, transient_periods=transient,
                                         progress=False)
    return float(section.omega[-1][0])


def cached_answers(name: str, history: int = 0) -> dict:
    """``ANSWERS[name](history)``, kept on the function (the wrong answers reuse history 0)."""
    function = ANSWERS[name]
    if history == 0:
        if getattr(function, "cached", None) is None:
            function.cached = function(0)
        return function.cached
    return function(history)


for _function in ANSWERS.values():
    _function.cached = None


# ------------------------------------------------------------------ each test's own metric
def _worst_against_steps(step, method, points, model=None):
    """Largest difference between ``step`` and ``pl.step(..., method)`` at ``points``."""
    import pendulum_lab as pl

    model = model or pl.simple_pendulum(mass=1.0, length=1.0, g=G)
    worst = 0.0
    for point in points:
        *state, h = point
        if len(state) == 3:  # (t, theta, omega): a driven model
            t, theta, omega = state
            expected = pl.step(model, [theta], [omega], dt=h, t0=t, method=method)
            got = step(t, theta, omega, h)
        else:
            theta, p = state
            expected = pl.step(model, [theta], p0=[p], dt=h, method=method)
            got = step(theta, p, h)
        worst = max(worst, abs(float(got[0]) - expected[0][0]), abs(float(got[1]) - expected[1][0]))
    return worst


_STEP_POINTS = [(1.0, 0.5, 0.1), (-2.0, 1.0, 0.05), (3.0, -2.0, 0.2), (0.1, 0.0, 0.01),
                (2.5, 3.0, -0.1)]
_DRIVEN_POINTS = [(0.0, 1.0, 0.5, 0.1), (1.3, -2.0, 1.0, 0.05), (4.0, 3.0, -2.0, 0.2),
                  (10.0, 0.1, 0.0, 0.01), (2.5, 2.0, 1.5, 0.3)]


def _order_deviation(step, order, steps, t_end=1.0):
    """|slope - order| of ``step`` from (1, 0) over ``t_end`` against SciPy's DOP853."""
    import pendulum_lab as pl
    from pendulum_lab import analysis

    model = pl.simple_pendulum(mass=1.0, length=1.0, g=G)
    theta_ref, omega_ref = analysis.reference_solution(model, [1.0], [0.0], t_end=t_end)
    errors = []
    for h in steps:
        theta, p = 1.0, 0.0
        for _ in range(round(t_end / h)):
            theta, p = step(theta, p, float(h))
        errors.append(max(abs(float(theta) - theta_ref[0]), abs(float(p) - omega_ref[0])))
    return abs(np.polyfit(np.log(steps), np.log(errors), 1)[0] - order)


def _driven_order_deviation(step):
    import pendulum_lab as pl

    reference = pl.simulate(pl.driven_pendulum(), [1.0], [0.5], t_end=2.0, dt=0.001,
                            method="glrk8", keep="final", progress=False)
    steps = np.array([0.08, 0.04, 0.02])
    errors = []
    for h in steps:
        t, theta, omega = 0.0, 1.0, 0.5
        for _ in range(round(2.0 / h)):
            theta, omega = step(t, theta, omega, float(h))
            t += float(h)
        errors.append(max(abs(float(theta) - reference.theta[-1][0]),
                          abs(float(omega) - reference.omega[-1][0])))
    return abs(np.polyfit(np.log(steps), np.log(errors), 1)[0] - 4)


def _step_defect(step):
    from pendulum_lab import analysis

    jacobian = analysis.finite_difference_jacobian(
        lambda z: np.array([float(x) for x in step(z[0], z[1], 0.1)]), np.array([1.0, 0.5]))
    return analysis.symplectic_form_defect(jacobian)


@dataclass
class Measure:
    """One hidden test: its metric in words, its tolerance, the metric of a set of answers."""

    assignment: str
    question: str
    test: str
    metric: str
    tolerance: float
    #: answers -> the test's metric; None for an exact test (0 if the test passes, else inf).
    deviation: object


def measures() -> list[Measure]:
    import pendulum_lab as pl
    from pendulum_lab import analysis, chaos

    def rel(a, b):
        return abs(float(a) / float(b) - 1)

    def cached(function):
        store = {}

        def inner():
            if "value" not in store:
                store["value"] = function()
            return store["value"]
        return inner

    # The grader's side of each comparison, computed once per run.
    modes = cached(lambda: analysis.normal_mode_frequencies(pl.double_pendulum()))
    exact_2 = cached(lambda: analysis.exact_period(pl.simple_pendulum(), 2.0))
    order_fit = cached(lambda: analysis.observed_order(
        pl.double_pendulum(), [2.0, 2.5], [0.0, 0.0], method="rk4",
        dts=analysis.order_steps("rk4")).slope)
    rk4_defect = cached(lambda: analysis.symplecticity_defect(
        pl.double_pendulum(), [2.0, 2.5], p0=[0.0, 0.0], dt=0.1, method="rk4"))
    energy_pair = cached(lambda: _energy_errors(0.05))
    chaotic_reference = cached(lambda: float(np.median(chaotic_estimates(16))))
    regular_reference = cached(lambda: chaos.lyapunov_benettin(
        pl.double_pendulum(), [0.1, 0.1], [0.0, 0.0], t_end=200, progress=False).exponent)
    attractor = cached(lambda: chaos.stroboscopic_section(
        pl.driven_pendulum(drive_amplitude=0.9), [0.2], [0.0], n_periods=64,
        transient_periods=300, progress=False).omega[-1][0])

    def period_of(amplitude):
        return cached(lambda: int(chaos.orbit_periods(*(lambda s: (s.theta, s.omega))(
            chaos.stroboscopic_section(pl.driven_pendulum(drive_amplitude=amplitude), [0.2],
                                       [0.0], n_periods=64, transient_periods=300,
                                       progress=False)))))
    periods = {1.07: period_of(1.07), 1.47: period_of(1.47)}

    def ratio_at(a):
        pendulum = pl.simple_pendulum()
        small = 2 * np.pi * np.sqrt(pendulum.lengths[0] / pendulum.g)
        return analysis.exact_period(pendulum, float(a)) / small

    def energy_factor_deviation(answers):
        unit = pl.simple_pendulum(length=1.0, g=1.0)
        steps = np.array([0.03, 0.1, 0.3, 0.6])
        expected = analysis.amplification(unit, steps, method="explicit_euler") ** 2
        expr = sp.sympify(answers["energy_factor"])
        got = np.array([complex(expr.subs({s: v for s in expr.free_symbols})).real
                        for v in steps])
        return float(np.max(np.abs(got / expected - 1)))

    def composition(step):
        model = pl.simple_pendulum(mass=1.0, length=1.0, g=G)
        worst = 0.0
        for theta, p, h in [(1.0, 0.5, 0.1), (-2.0, 1.0, 0.05), (3.0, -2.0, 0.2),
                            (0.2, 0.0, -0.1)]:
            half = pl.step(model, [theta], p0=[p], dt=h / 2, method="semi_implicit_euler")
            got = step(half[0][0], half[1][0], h / 2)
            expected = pl.step(model, [theta], p0=[p], dt=h, method="leapfrog")
            worst = max(worst, abs(float(got[0]) - expected[0][0]),
                        abs(float(got[1]) - expected[1][0]))
        return worst

    def undoes(step):
        model = pl.simple_pendulum(mass=1.0, length=1.0, g=G)
        worst = 0.0
        for theta, p, h in [(1.0, 0.5, 0.1), (-2.0, 1.0, 0.05), (3.0, -2.0, 0.2)]:
            back = pl.step(model, [theta], p0=[p], dt=-h, method="semi_implicit_euler")
            got = step(back[0][0], back[1][0], h)
            worst = max(worst, abs(float(got[0]) - theta), abs(float(got[1]) - p))
        return worst

    def area_against_jacobian(answers):
        model = pl.simple_pendulum(mass=2.0, length=0.5, g=9.81)
        values = {"m": 2.0, "l": 0.5, "g": 9.81}
        expr = sp.sympify(answers["area_factor"])
        worst = 0.0
        for theta0, h in [(0.0, 0.1), (1.0, 0.05), (2.0, 0.2), (3.0, 0.1), (-1.0, -0.1),
                          (0.5, 0.02)]:
            jac = analysis.step_jacobian(model, [theta0], p0=[0.3], dt=h,
                                         method="explicit_euler")
            subs = {s: {**values, "theta": theta0, "h": h}.get(s.name, 0.0)
                    for s in expr.free_symbols}
            worst = max(worst, abs(complex(expr.subs(subs)) - np.linalg.det(jac)))
        return worst

    def area_against_map(answers):
        model = pl.driven_pendulum()
        period = 2 * np.pi * 1.5

        def one_period(z):
            run = pl.simulate(model, [z[0]], p0=[z[1]], t_end=period * (1 + 1e-9),
                              dt=period / 1000, method="rk4", keep="final", progress=False)
            return np.array([run.theta[-1][0], run.p[-1][0]])
        computed = np.linalg.det(analysis.finite_difference_jacobian(
            one_period, np.array([0.3, 0.1]), delta=1e-5))
        expr = sp.sympify(answers["area_per_period"])
        values = {"c": 0.5, "Omega": 2 / 3}
        return rel(complex(expr.subs({s: values.get(s.name, 0)
                                      for s in expr.free_symbols})).real, computed)

    a1, a2 = "01_derivations_and_fixed_points", "02_integrators_and_orders"
    a3, a4 = "03_symplecticity_and_modified_hamiltonian", "04_chaos_and_the_driven_pendulum"
    exact = "symbolic identity"
    return [
        Measure(a1, "q1_lagrangian", "test_identity", exact, 0.0, None),
        Measure(a1, "q2_hamiltonian", "test_identity", exact, 0.0, None),
        Measure(a1, "q3_jacobian_up", "test_identity", exact, 0.0, None),
        Measure(a1, "q4_normal_modes", "test_values", "max relative deviation", 1e-6,
                lambda a: float(np.max(np.abs(np.sort(np.asarray(a["normal_modes"], float))
                                              / modes() - 1)))),
        Measure(a1, "q5_period_from_simulation", "test_against_exact",
                "relative deviation from the exact period", 1e-5,
                lambda a: rel(a["period_2rad"], exact_2())),
        Measure(a1, "q6_ten_percent_amplitude", "test_property", "|period ratio - 1.1|", 1e-6,
                lambda a: abs(ratio_at(a["amplitude_10_percent"]) - 1.1)),
        Measure(a2, "q1_explicit_euler", "test_agrees_with_library",
                "max |step - pl.step|", 1e-12,
                lambda a: _worst_against_steps(a["explicit_euler_step"], "explicit_euler",
                                               _STEP_POINTS)),
        Measure(a2, "q1_explicit_euler", "test_order", "|observed order - 1|", 0.1,
                lambda a: _order_deviation(a["explicit_euler_step"], 1,
                                           np.array([0.01, 0.005, 0.0025]))),
        Measure(a2, "q2_leapfrog", "test_agrees_with_library", "max |step - pl.step|", 1e-12,
                lambda a: _worst_against_steps(a["leapfrog_step"], "leapfrog", _STEP_POINTS)),
        Measure(a2, "q2_leapfrog", "test_order", "|observed order - 2|", 0.1,
                lambda a: _order_deviation(a["leapfrog_step"], 2, np.array([0.04, 0.02, 0.01]))),
        Measure(a2, "q2_leapfrog", "test_symplectic", "max |Psi^T J Psi - J|", 1e-8,
                lambda a: _step_defect(a["leapfrog_step"])),
        Measure(a2, "q2_leapfrog", "test_reversible", "return error of +h then -h", 1e-12,
                lambda a: (lambda f: (lambda s: max(abs(float(f(*s, -0.1)[0]) - 1.0),
                                                    abs(float(f(*s, -0.1)[1]) - 0.5)))(
                    f(1.0, 0.5, 0.1)))(a["leapfrog_step"])),
        Measure(a2, "q3_rk4", "test_agrees_with_library", "max |step - pl.step|", 1e-12,
                lambda a: _worst_against_steps(a["rk4_step"], "rk4", _STEP_POINTS)),
        Measure(a2, "q3_rk4", "test_order", "|observed order - 4|", 0.2,
                lambda a: _order_deviation(a["rk4_step"], 4, np.array([0.04, 0.02, 0.01]))),
        Measure(a2, "q4_measured_order", "test_measured", "|slope - grader's slope|", 0.01,
                lambda a: abs(float(a["rk4_double_order"]) - order_fit())),
        Measure(a2, "q5_leapfrog_limit", "test_identity", exact, 0.0, None),
        Measure(a2, "q6_euler_energy_factor", "test_against_the_package",
                "max relative deviation from amplification**2", 1e-5, energy_factor_deviation),
        Measure(a3, "q1_adjoint_euler", "test_composition_is_leapfrog",
                "max |Euler(h/2) adjoint(h/2) - leapfrog|", 1e-12,
                lambda a: composition(a["adjoint_euler_step"])),
        Measure(a3, "q1_adjoint_euler", "test_is_the_adjoint", "return error", 1e-12,
                lambda a: undoes(a["adjoint_euler_step"])),
        Measure(a3, "q1_adjoint_euler", "test_symplectic", "max |Psi^T J Psi - J|", 1e-8,
                lambda a: _step_defect(a["adjoint_euler_step"])),
        Measure(a3, "q2_symplecticity_defects", "test_rk4", "relative deviation", 0.01,
                lambda a: rel(a["defect_rk4"], rk4_defect())),
        Measure(a3, "q2_symplecticity_defects", "test_gl4", "the defect itself (> 0)", 1e-8,
                lambda a: float(a["defect_gl4"]) if a["defect_gl4"] > 0 else math.inf),
        Measure(a3, "q3_modified_hamiltonian", "test_identity", exact, 0.0, None),
        Measure(a3, "q4_modified_energy_kept", "test_energy_error", "relative deviation", 1e-6,
                lambda a: rel(a["energy_error"], energy_pair()[0])),
        Measure(a3, "q4_modified_energy_kept", "test_modified_error", "relative deviation",
                1e-6, lambda a: rel(a["modified_error"], energy_pair()[1])),
        Measure(a3, "q5_euler_area_factor", "test_against_step_jacobian",
                "max |answer - det(step_jacobian)|", 1e-7, area_against_jacobian),
        Measure(a4, "q1_lyapunov", "test_chaotic",
                "relative deviation from the grader's 16-history median", CHAOTIC_TOLERANCE,
                lambda a: rel(a["lyapunov_chaotic"], chaotic_reference())),
        Measure(a4, "q1_lyapunov", "test_regular", "|estimate - grader's estimate| (/s)", 0.01,
                lambda a: abs(float(a["lyapunov_regular"]) - regular_reference())
                if abs(float(a["lyapunov_regular"])) < 0.05 else math.inf),
        Measure(a4, "q2_driven_rk4_step", "test_agrees_with_library", "max |step - pl.step|",
                1e-12, lambda a: _worst_against_steps(a["driven_rk4_step"], "rk4",
                                                      _DRIVEN_POINTS, pl.driven_pendulum())),
        Measure(a4, "q2_driven_rk4_step", "test_order", "|observed order - 4|", 0.2,
                lambda a: _driven_order_deviation(a["driven_rk4_step"])),
        Measure(a4, "q3_area_per_period", "test_against_the_equations", exact, 0.0, None),
        Measure(a4, "q3_area_per_period", "test_against_the_computed_map",
                "relative deviation from det of the one-period map", 1e-5, area_against_map),
        Measure(a4, "q4_period_one_attractor", "test_value", "|omega - grader's omega|", 1e-6,
                lambda a: abs(float(a["omega_on_attractor"]) - attractor())),
        Measure(a4, "q5_attractor_periods", "test_period_at_107", "periods differ (0 or 1)", 0.0,
                lambda a: float(int(a["period_at_107"]) != periods[1.07]())),
        Measure(a4, "q5_attractor_periods", "test_period_at_147", "periods differ (0 or 1)", 0.0,
                lambda a: float(int(a["period_at_147"]) != periods[1.47]())),
    ]


#: Assignment 04 Q1: the relative band around the grader's 16-history median (see the test).
CHAOTIC_TOLERANCE = 0.25

#: The answers that are numbers a student computes in their own environment (the others are
#: symbolic, or functions that run in the grader's): these are measured across environments.
NUMERIC = ("normal_modes", "period_2rad", "amplitude_10_percent", "rk4_double_order",
           "defect_rk4", "defect_gl4", "energy_error", "modified_error", "lyapunov_chaotic",
           "lyapunov_regular", "omega_on_attractor", "period_at_107", "period_at_147")


def _jsonable(value):
    return np.asarray(value, dtype=float).tolist()


def measure(histories: int, draws: int, other: dict | None = None,
            save: Path | None = None) -> list[dict]:
    """Every test's spread over ``histories`` round-off histories (``draws`` per step size for
    the chaotic estimate), across environments when ``other`` holds another one's numeric
    answers, and its nearest wrong answer: the rows of the table."""
    rows, saved = [], {}
    all_measures = measures()
    for name in ANSWERS:
        hidden, _ = master_tests(name)
        sets = [cached_answers(name, k) for k in range(histories)]
        if name.startswith("04"):
            estimates = np.concatenate([chaotic_estimates(draws, 0.01),
                                        chaotic_estimates(draws, 0.005)])
            sets += [{**sets[0], "lyapunov_chaotic": float(x)} for x in estimates]
        saved[name] = [{key: _jsonable(s[key]) for key in NUMERIC if key in s} for s in sets]
        wrong = wrong_answers(name)
        for m in (m for m in all_measures if m.assignment == name):
            test = hidden[(m.question, m.test)]
            parameters = set(test.__code__.co_varnames[:test.__code__.co_argcount])
            deviation = m.deviation or (lambda a, t=test: 0.0 if passes(t, a)[0] else math.inf)
            spread = max(deviation(s) for s in sets)
            across = None
            if other is not None and parameters & set(NUMERIC):
                across = max(deviation({**sets[0], **theirs}) for theirs in other[name])
            slips = [(slip, deviation({**sets[0], **changed}))
                     for question, slip, changed in wrong
                     if question == m.question and parameters & set(changed)]
            nearest = min(slips, key=lambda item: item[1]) if slips else None
            rows.append({"assignment": name, "question": m.question, "test": m.test,
                         "metric": m.metric, "spread": spread, "across": across,
                         "tolerance": m.tolerance, "wrong": nearest, "answers": len(sets)})
    if save is not None:
        save.write_text(json.dumps(saved))
    return rows


def _format(x) -> str:
    if x is None:
        return "-"
    if x == 0:
        return "0"
    if math.isinf(x):
        return "fails"
    return f"{x:.2g}"


def print_table(rows: list[dict]) -> None:
    print(f"{'assignment / question / test':62} {'metric':44} {'spread':>8} {'across':>8} "
          f"{'tolerance':>9}  nearest wrong answer")
    for row in rows:
        label = f"{row['assignment'][:2]} {row['question']} {row['test']}"
        wrong = (f"{_format(row['wrong'][1])} ({row['wrong'][0]})" if row["wrong"] else "-")
        tolerance = "exact" if row["tolerance"] == 0 else _format(row["tolerance"])
        print(f"{label:62} {row['metric'][:44]:44} {_format(row['spread']):>8} "
              f"{_format(row['across']):>8} {tolerance:>9}  {wrong}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--histories", type=int, default=16,
                        help="round-off histories per answer (16)")
    parser.add_argument("--draws", type=int, default=256,
                        help="histories of the chaotic estimate per step size (256)")
    parser.add_argument("--save", type=Path, help="write this environment's numeric answers")
    parser.add_argument("--against", type=Path,
                        help="numeric answers saved in another environment, graded here")
    parser.add_argument("--json", type=Path, help="write the table's rows")
    args = parser.parse_args(argv)
    other = json.loads(args.against.read_text()) if args.against else None
    import numba
    import scipy

    print(f"NumPy {np.__version__}, SciPy {scipy.__version__}, Numba {numba.__version__}, "
          f"SymPy {sp.__version__}, Python {sys.version.split()[0]}")
    rows = measure(args.histories, args.draws, other, args.save)
    print_table(rows)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1, default=str))
    return 0


if __name__ == "__main__":
    sys.exit(main())
