"""The optional peers for long accurate runs: heyoka (Taylor series, LLVM), pyhamsys (Tao).

Both come from the ``bench`` extra (``pip install -e ".[bench]"``). Where one
is not installed, :func:`heyoka_or_reason` / :func:`pyhamsys_or_reason`
return ``(None, reason)`` and the benchmark rows say so.

Both peers are given pendulum_lab's own equations, so that every contender
integrates the same problem: heyoka gets the chain's SymPy mass matrix and
forcing (``model.chain``), solved symbolically and converted with
``heyoka.from_sympy``, on ``(theta, omega)``; pyhamsys (which takes a
Python vector field ``y_dot(t, y)`` in canonical variables) gets our compiled
Hamiltonian kernel, the fastest right-hand side we can hand it. This module
is shared by the benchmark items and by ``tests/benchmarks/test_peers.py``.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from pendulum_lab import codegen
from pendulum_lab.driver.simulate import hamiltonian_field

__all__ = [
    "heyoka_integrator",
    "heyoka_or_reason",
    "heyoka_states",
    "pyhamsys_or_reason",
    "pyhamsys_run",
]


def heyoka_or_reason():
    """``(heyoka module, "")`` or ``(None, why it is unavailable)``."""
    try:
        import heyoka
    except ImportError as err:
        return None, f"heyoka not installed ({err}); `pip install -e '.[bench]'`"
    return heyoka, ""


def pyhamsys_or_reason():
    """``(pyhamsys module, "")`` or ``(None, why it is unavailable)``."""
    try:
        import pyhamsys
    except ImportError as err:
        return None, f"pyhamsys not installed ({err}); `pip install -e '.[bench]'`"
    return pyhamsys, ""


def _accelerations(model):
    """The model's accelerations as SymPy expressions in ``chain.q``, ``chain.omega``.

    ``M(q) omega' = F(q, omega)`` solved by LU (closed form for n <= 3) with
    the model's parameter values substituted.
    """
    chain = model.chain
    values = model.parameter_values
    mass = chain.mass_matrix.xreplace(values)
    forcing = chain.forcing.xreplace(values)
    return chain, list(mass.LUsolve(forcing))


def heyoka_integrator(model, theta0, omega0, tol: float, *, compact_mode: bool = False):
    """A ``heyoka.taylor_adaptive`` integrator of ``model`` from ``(theta0, omega0)``.

    State order ``(theta_0..theta_{n-1}, omega_0..omega_{n-1})``; ``tol`` is
    heyoka's tolerance (it chooses the Taylor order from it).
    """
    hy, reason = heyoka_or_reason()
    if hy is None:
        raise RuntimeError(reason)
    chain, accelerations = _accelerations(model)
    variables = [hy.make_vars(f"th{i}") for i in range(chain.n)]
    variables += [hy.make_vars(f"w{i}") for i in range(chain.n)]
    symbols = list(chain.q) + list(chain.omega)
    mapping = {s: v for s, v in zip(symbols, variables)}
    rhs = [hy.from_sympy(sp.sympify(x), mapping) for x in chain.omega]
    rhs += [hy.from_sympy(sp.simplify(a) if chain.n <= 2 else a, mapping) for a in accelerations]
    state = np.concatenate([np.asarray(theta0, float), np.asarray(omega0, float)])
    return hy.taylor_adaptive(list(zip(variables, rhs)), state, tol=tol,
                              compact_mode=compact_mode)


def heyoka_states(model, theta0, omega0, times, tol: float = 1e-16):
    """heyoka's ``(theta, omega)`` at ``times`` (shape ``(len(times), n)`` each), from ``t = 0``."""
    integrator = heyoka_integrator(model, theta0, omega0, tol)
    grid = np.asarray(times, float)
    if grid[0] != 0.0:
        grid = np.concatenate([[0.0], grid])
    outcome = integrator.propagate_grid(grid)
    states = outcome[-1] if grid.size == len(times) else outcome[-1][1:]
    n = model.n
    return states[:, :n], states[:, n:]


def pyhamsys_run(model, theta0, p0, t_end: float, step: float, t_eval=None, solver: str = "BM4"):
    """pyhamsys' ``solve_ivp_sympext`` (Tao's extension, default scheme BM4 and projection).

    The vector field is our compiled Hamiltonian kernel (canonical ``(q, p)``).
    Returns the solution bunch (``sol.y`` of shape ``(2 n, len(t))``).
    """
    hs_module, reason = pyhamsys_or_reason()
    if hs_module is None:
        raise RuntimeError(reason)
    field = hamiltonian_field(model)
    params, n = np.asarray(field.params, float), model.n
    kernels = codegen.load_kernels(n)
    hamilton = kernels.hamilton

    def y_dot(t, y):
        dq, dp = np.empty(n), np.empty(n)
        hamilton(t, np.ascontiguousarray(y[:n]), np.ascontiguousarray(y[n:]), params, dq, dp)
        return np.concatenate((dq, dp))

    system = hs_module.HamSys(ndof=n, y_dot=y_dot)
    settings = hs_module.Parameters(step=step, solver=solver, display=False)
    y0 = np.concatenate([np.asarray(theta0, float), np.asarray(p0, float)])
    return hs_module.solve_ivp_sympext(system, (0.0, t_end), y0, settings, t_eval=t_eval)
