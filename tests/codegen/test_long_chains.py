"""Long chains: the closed-form equations, the looped kernels, and the limits.

The closed form (``M_ij = mu_max(i,j) l_i l_j cos(theta_i - theta_j)`` and
the forcing built entry by entry) must equal the Lagrangian derivation from
the Cartesian bob positions exactly; the looped kernels must equal the
kernels printed from the expressions; sizes beyond a limit are refused with
the limit and the reason.
"""

import numpy as np
import pytest
import sympy as sp

import pendulum_lab as pl
from pendulum_lab import codegen
from pendulum_lab.codegen.long_chains import LoopedChain
from pendulum_lab.model import numeric, pendulum
from pendulum_lab.symbolic.mechanics import (
    LIMITS,
    Chain,
    is_identically_zero,
    lagrangian_derivation,
)

PARTS = ("mass_matrix", "kinetic", "potential", "dlagrangian_dq", "generalized_forces", "forcing")


@pytest.mark.parametrize("forced", [False, True])
@pytest.mark.parametrize("n", [1, 2, 3, 4, 5])
def test_closed_form_equals_the_lagrangian_derivation(n, forced):
    chain = Chain(n, forced)
    long_way = lagrangian_derivation(chain)
    for part in PARTS:
        # Expanded the same way, the two are the same expressions, term for term.
        assert getattr(chain, part) == getattr(long_way, part), part
    relative = [chain.omega[i] - (chain.omega[i - 1] if i else 0) for i in range(n)]
    rayleigh = sum(c * v**2 for c, v in zip(chain.damping, relative)) / 2 if forced else 0
    assert chain.damping_matrix == sp.hessian(sp.sympify(rayleigh), list(chain.omega)) or (
        not forced and chain.damping_matrix == sp.zeros(n))
    if n == 1:
        return
    # Negative control: the bob's own mass instead of the tail mass in M.
    m, lengths = chain.masses, chain.lengths
    wrong = sp.Matrix(n, n, lambda i, j: m[max(i, j)] * lengths[i] * lengths[j]
                      * sp.cos(chain.q[i] - chain.q[j]))
    assert not all(is_identically_zero(e) for e in wrong - long_way.mass_matrix)


def test_forced_closed_form_has_damping_and_drive_negative_control():
    forced, plain = Chain(3, forced=True), Chain(3)
    derivation = lagrangian_derivation(forced)
    difference = derivation.forcing - plain.forcing
    assert not all(e == 0 for e in difference)  # the forced chain's Q is really there
    assert difference == forced.generalized_forces
    # A sign slip in one damping term is caught.
    slipped = forced.generalized_forces.copy()
    slipped[1] = slipped[1].subs(forced.damping[2], -forced.damping[2])
    assert slipped != derivation.generalized_forces


def test_unevaluated_angle_differences_have_sympys_sign():
    # Past nine links names sort as text (theta_10 before theta_2): the case to check.
    chain = Chain(12)
    for i in range(chain.n):
        for j in range(chain.n):
            angle = chain.q[i] - chain.q[j]
            assert chain._sin_difference(i, j) == sp.sin(angle), (i, j)
            assert chain._cos_difference(i, j) == sp.cos(angle), (i, j)
    # Negative control: the unevaluated form of the other sign is another expression.
    assert sp.sin(chain.q[1] - chain.q[0], evaluate=False) != sp.sin(chain.q[1] - chain.q[0])


@pytest.mark.parametrize("name", ["down-up-up", "up-down-up"])
def test_equilibrium_in_closed_form_equals_the_symbolic_solve(name):
    chain = Chain(3)
    eq = chain.equilibrium(name)
    at = dict(zip(chain.q, eq.angles)) | {w: 0 for w in chain.omega}
    solved = chain.mass_matrix.subs(at).LUsolve(chain.forcing.jacobian(chain.q).subs(at))
    assert all(is_identically_zero(e) for e in solved - eq.stiffness_ratio)
    other = chain.equilibrium("down-down-down")  # negative control
    assert not all(is_identically_zero(e) for e in solved - other.stiffness_ratio)


def test_parts_that_grow_too_fast_are_refused_naming_the_limit():
    with pytest.raises(ValueError, match="refused beyond 6 links, because it expands"):
        lagrangian_derivation(Chain(7))
    with pytest.raises(ValueError, match="accelerations of a chain of 3 links: refused beyond 2"):
        _ = Chain(3).accelerations
    with pytest.raises(ValueError, match="2\\*\\*n"):
        _ = Chain(9).equilibria
    limit = LIMITS["the symbolic equations"][0]
    with pytest.raises(ValueError, match=f"refused beyond {limit} links"):
        _ = Chain(limit + 1).mass_matrix
    assert Chain(9).equilibrium("-".join(["down"] * 9)).angles == (0,) * 9  # one is fine
    with pytest.raises(ValueError, match="`equilibrium`"):
        Chain(3).equilibrium("down-up")
    with pytest.raises(ValueError, match=f"`n` must be at most {pendulum.MAX_LINKS} links"):
        pl.n_pendulum(pendulum.MAX_LINKS + 1)


def test_long_symbolic_builds_show_progress(capsys):
    chain = Chain(30)
    assert chain.forcing.shape == (30, 1)
    assert "forcing of 30 links" in capsys.readouterr().err
    _ = Chain(5).forcing  # negative control: short builds stay quiet
    assert capsys.readouterr().err == ""


# ---------------------------------------------------------------- numeric
def _random_state(n, forced, seed=1):
    rng = np.random.default_rng(seed)
    params = [*rng.uniform(0.5, 2.0, n), *rng.uniform(0.5, 2.0, n), 9.81]
    if forced:
        params += [*rng.uniform(0.0, 0.5, n), 1.3, 0.7]
    return (rng.uniform(-3, 3, n), rng.normal(size=n), np.array(params), float(rng.normal()))


@pytest.mark.parametrize("forced", [False, True])
def test_looped_kernels_equal_the_kernels_printed_from_the_expressions(forced):
    n = 3
    printed = codegen.load_kernels(n, forced, looped=False)
    looped = codegen.load_kernels(n, forced, looped=True)
    assert printed.hamilton is not looped.hamilton
    q, v, params, t = _random_state(n, forced)
    results = []
    for kernels in (printed, looped):
        dq, dp, acc = np.empty(n), np.empty(n), np.empty(n)
        kernels.hamilton(t, q, v, params, dq, dp)
        kernels.acceleration(t, q, v, params, acc)
        results.append(np.concatenate([dq, dp, acc]))
    assert np.allclose(results[0], results[1], rtol=1e-12, atol=1e-12)
    # Negative control: another last mass changes the looped kernels' result.
    params[n - 1] *= 1.01
    dq, dp = np.empty(n), np.empty(n)
    looped.hamilton(t, q, v, params, dq, dp)
    assert not np.allclose(np.concatenate([dq, dp]), results[1][: 2 * n], rtol=1e-6)


@pytest.mark.parametrize("forced", [False, True])
def test_looped_model_functions_equal_the_lambdified_ones(forced):
    n = 3
    lambdified = numeric.CompiledChain(pl.derive_chain(n, forced))
    looped = LoopedChain(n, forced)
    rng = np.random.default_rng(2)
    theta, omega = rng.uniform(-3, 3, (4, n)), rng.normal(size=(4, n))
    _, _, params, _ = _random_state(n, forced)
    t = rng.normal(size=4)
    calls = {
        "mass_matrix": (theta, params, t), "potential": (theta, params, t),
        "velocities": (theta, omega, params, t), "momenta": (theta, omega, params, t),
        "dlagrangian_dq": (theta, omega, params, t), "kinetic": (theta, omega, params, t),
        "hamiltonian": (theta, omega, params, t),
        "lag_qq": (theta, omega, params, t), "lag_qw": (theta, omega, params, t),
        "dmomenta_dq": (theta, omega, params, t), "forcing": (theta, omega, params, t),
        "accelerations": (theta, omega, params, t),
        "generalized_forces": (theta, omega, params, t), "damping_matrix": (params,),
    }
    for name, args in calls.items():
        expected, got = getattr(lambdified, name)(*args), getattr(looped, name)(*args)
        assert np.shape(got) == np.shape(expected), name
        assert np.allclose(got, expected, rtol=1e-12, atol=1e-12), name
    # Negative control: the first link's angle moved a little.
    moved = theta.copy()
    moved[:, 0] += 1e-4
    assert not np.allclose(looped.lag_qq(moved, omega, params, t),
                           lambdified.lag_qq(theta, omega, params, t), rtol=1e-9, atol=1e-9)


def test_the_looped_functions_take_states_in_any_memory_order():
    """A Fortran-ordered or broadcast batch (an ensemble's velocities given as one row repeated)
    is copied to rows the compiled kernels are typed for, after a C-ordered batch was seen."""
    chain = pl.n_pendulum(3)
    rng = np.random.default_rng(5)
    theta, omega = rng.uniform(-2, 2, (3, 3)), rng.normal(size=(3, 3))
    expected = chain.accelerations(theta, omega)
    for layout in (np.asfortranarray(omega), omega[:, ::-1][:, ::-1]):
        assert np.array_equal(chain.accelerations(theta, layout), expected)
    row = np.broadcast_to(omega[0], omega.shape)
    assert np.array_equal(chain.accelerations(theta, row),
                          chain.accelerations(theta, np.array(row)))
    # negative control: other velocities give other accelerations
    assert not np.array_equal(chain.accelerations(theta, np.asfortranarray(omega[::-1])), expected)


def test_linear_time_solve_matches_a_dense_solve_up_to_the_largest_chain():
    n = pendulum.MAX_LINKS
    rng = np.random.default_rng(3)
    chain = pl.n_pendulum(n, masses=rng.uniform(0.5, 2, n), lengths=rng.uniform(0.5, 2, n))
    theta, p = rng.uniform(-3, 3, n), rng.normal(size=n)
    dense = np.linalg.solve(chain.mass_matrix_at(theta), p)
    fast = chain.velocities(theta, p)
    assert np.max(np.abs(fast - dense)) < 1e-9 * np.max(np.abs(dense))
    # Negative control: another configuration's matrix (M depends on the angles'
    # differences only, so bend one joint) gives another answer.
    bent = theta.copy()
    bent[n // 2] += 1e-3
    assert not np.allclose(chain.velocities(bent, p), dense, rtol=1e-6)


def test_twenty_links_keep_their_energy_with_gl4_and_not_with_euler():
    chain = pl.n_pendulum(20)
    theta0, omega0 = np.linspace(0.6, 0.2, 20), np.zeros(20)
    gl4 = pl.simulate(chain, theta0, omega0, t_end=2.0, dt=0.005, method="glrk4")
    euler = pl.simulate(chain, theta0, omega0, t_end=2.0, dt=0.005, method="explicit_euler")
    assert gl4.completed
    assert np.max(np.abs(gl4.relative_energy_error)) < 1e-7
    assert np.max(np.abs(euler.relative_energy_error)) > 1e-3  # negative control


def test_a_family_of_long_chains_gives_each_member_its_own_parameters():
    base = pl.n_pendulum(3, damping=0.1, drive_amplitude=0.5, drive_frequency=1.3)
    family = base.family(damping=[0.0, 0.2, 0.4], drive_amplitude=[0.5, 1.0, 0.0])
    rng = np.random.default_rng(4)
    theta, p = rng.uniform(-2, 2, (3, 3)), rng.normal(size=(3, 3))
    omega = family.velocities(theta, p)
    together = (family.accelerations(theta, omega, 0.4), family.jacobian(theta, p, 0.4),
                family.energy(theta, omega))
    for k in range(3):
        member = family.member(k)
        alone = (member.accelerations(theta[k], omega[k], 0.4),
                 member.jacobian(theta[k], p[k], 0.4), member.energy(theta[k], omega[k]))
        for got, expected in zip(together, alone):
            assert np.allclose(got[k], expected, rtol=1e-13, atol=1e-13)
    # Negative control: every member with the first member's parameters differs.
    first = family.member(0)
    assert not np.allclose(first.accelerations(theta, omega, 0.4), together[0], rtol=1e-6)


def test_repeated_runs_of_a_long_chain_give_the_same_state():
    """The time loop's own state survives the kernels' allocations.

    The loop steps a working copy of the state through views that hold no
    reference to it; Numba freed that copy after its last named use, and a
    long chain's kernels, which allocate a workspace at every call, could be
    given its memory. Repeated runs of a 100-link chain then failed to
    converge, or silently differed, in most processes (keep="final", glrk4).
    Every run of the same start must now give the same bits.
    """
    chain = pl.n_pendulum(100)
    theta0 = np.linspace(0.5, 0.1, 100)
    runs = [pl.simulate(chain, theta0, np.zeros(100), t_end=t_end, dt=0.001, method="glrk4",
                        keep="final", progress=False)
            for t_end in (0.002, 0.001, 0.002, 0.01, 0.002, 0.01)]
    for first, again in ((0, 2), (0, 4), (3, 5)):
        assert np.array_equal(runs[first].theta, runs[again].theta)
        assert np.array_equal(runs[first].p, runs[again].p)
    # negative control: one step less is a different state
    assert not np.array_equal(runs[0].theta[-1], runs[1].theta[-1])
