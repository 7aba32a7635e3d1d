"""Compiled vector fields: SymPy expressions printed as Numba kernels.

For each number of links ``n``, conservative or forced, this module writes
one small Python source file (into a cache folder) holding two kernels
generated from the symbolic equations of :mod:`pendulum_lab.mechanics`:

``hamilton(t, q, p, params, dq, dp)``
    Hamilton's equations: ``dq = dH/dp = M(q)^-1 p`` and ``dp = -dH/dq + Q``,
    where ``-dH/dq`` equals ``dL/dq`` evaluated at ``omega = M^-1 p`` and the
    generalized forces ``Q(omega, t)`` are zero unless the chain is forced.
``acceleration(t, q, v, params, out)``
    ``out = M(q)^-1 (F(q, v) + Q(v, t))``, for the course report's
    velocity-variable methods.

``M`` is solved numerically (Cholesky; it is symmetric positive definite), as
PyDy's code generator does, rather than inverted symbolically. The kernels are
compiled by Numba with ``cache=True``: compilation happens once per machine,
later processes load machine code from disk. A lambdified function cannot be
cached by Numba (it has no source file), which is why the source is written out.

Parameters are passed in the array ``params = (m_1..m_n, l_1..l_n, g)``,
followed for a forced chain by ``(c_1..c_n, A, Omega)`` (joint damping, drive
amplitude and frequency): the order of ``Chain.parameters``. The
conservative kernels are generated from the conservative chain, so they
contain no zero force terms and ignore ``t``.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import inspect
import math
import os
import sys
import tempfile
from pathlib import Path
from types import SimpleNamespace

import numba
import numpy as np
import sympy as sp
from numba import types

from ._signatures import VECTOR
from .mechanics import Chain, derive_chain
from .model import UNROLLED_MAX_LINKS

__all__ = ["kernel_source", "load_kernels", "looped_kernels", "parameters_array", "solve_spd"]



@numba.njit(types.void(types.float64[:, ::1], VECTOR, VECTOR), cache=True)
def solve_spd(matrix, rhs, out):
    """Solve ``matrix @ out = rhs`` for a small symmetric positive-definite matrix.

    Cholesky factorisation ``matrix = L L^T`` in place (lower triangle), then
    forward and back substitution. ``matrix`` is overwritten.
    """
    n = rhs.size
    for j in range(n):
        d = matrix[j, j]
        for k in range(j):
            d -= matrix[j, k] * matrix[j, k]
        d = math.sqrt(d)
        matrix[j, j] = d
        for i in range(j + 1, n):
            s = matrix[i, j]
            for k in range(j):
                s -= matrix[i, k] * matrix[j, k]
            matrix[i, j] = s / d
    for i in range(n):
        s = rhs[i]
        for k in range(i):
            s -= matrix[i, k] * out[k]
        out[i] = s / matrix[i, i]
    for i in range(n - 1, -1, -1):
        s = out[i]
        for k in range(i + 1, n):
            s -= matrix[k, i] * out[k]
        out[i] = s / matrix[i, i]


def _plain_symbols(chain: Chain):
    """Map the chain's symbols to short names that cannot clash with the arguments."""
    n = chain.n
    th = sp.symbols(f"th0:{n}", real=True)
    w = sp.symbols(f"w0:{n}", real=True)
    pars = sp.symbols(f"par0:{len(chain.parameters)}", real=True)
    mapping = dict(zip(chain.q, th)) | dict(zip(chain.omega, w))
    mapping |= dict(zip(chain.parameters, pars))
    return th, w, pars, mapping


def _assignments(targets: list[str], exprs: list[sp.Expr], mapping: dict, prefix: str) -> list[str]:
    """Lines ``target = expression`` with common subexpressions shared (``cse``)."""
    exprs = [sp.sympify(e).xreplace(mapping) for e in exprs]
    temps, reduced = sp.cse(exprs, symbols=sp.numbered_symbols(prefix))
    lines = [f"{t} = {sp.pycode(e)}" for t, e in temps]
    lines += [f"{t} = {sp.pycode(e)}" for t, e in zip(targets, reduced)]
    return lines


def _solve_lines(chain: Chain, mapping: dict, rhs: list[str], rhs_array: str, out: str,
                 prefix: str) -> list[str]:
    """Lines that solve ``M(q) out = rhs``.

    ``rhs`` names the right-hand side's entries, ``rhs_array`` the array that
    holds them. For one or two links the closed form needs no array at all
    (this is the hot path of the course); longer chains fill ``mass`` and call
    :func:`solve_spd`.
    """
    n = chain.n
    mass = list(chain.mass_matrix)
    if n == 1:
        (m00,) = _assignments(["m00"], mass, mapping, prefix)
        return [m00, f"{out}[0] = {rhs[0]} / m00"]
    if n == 2:
        lines = _assignments(["m00", "m01", "m11"], [mass[0], mass[1], mass[3]], mapping, prefix)
        return lines + [
            "det = m00 * m11 - m01 * m01",
            f"{out}[0] = (m11 * {rhs[0]} - m01 * {rhs[1]}) / det",
            f"{out}[1] = (m00 * {rhs[1]} - m01 * {rhs[0]}) / det",
        ]
    lines = [f"mass = np.empty(({n}, {n}))"]
    lines += _assignments([f"mass[{i}, {j}]" for i in range(n) for j in range(n)], mass,
                          mapping, prefix)
    return lines + [f"solve_spd(mass, {rhs_array}, {out})"]


def kernel_source(chain: Chain) -> str:
    """The Python source of the two Numba kernels for ``chain``."""
    n = chain.n
    _, _, _, mapping = _plain_symbols(chain)
    unpack = [f"th{i} = q[{i}]" for i in range(n)]
    unpack += [f"par{i} = params[{i}]" for i in range(len(chain.parameters))]
    hamilton = list(unpack)
    hamilton += _solve_lines(chain, mapping, [f"p[{i}]" for i in range(n)], "p", "dq", "a")
    hamilton += [f"w{i} = dq[{i}]" for i in range(n)]
    momentum_rates = chain.dlagrangian_dq
    if chain.forced:
        momentum_rates = momentum_rates + chain.generalized_forces
    hamilton += _assignments([f"dp[{i}]" for i in range(n)], list(momentum_rates), mapping, "b")
    accel = unpack + [f"w{i} = v[{i}]" for i in range(n)]
    forcing = [f"f{i}" for i in range(n)] if n <= 2 else [f"rhs[{i}]" for i in range(n)]
    if n > 2:
        accel += [f"rhs = np.empty({n})"]
    accel += _assignments(forcing, list(chain.forcing), mapping, "c")
    accel += _solve_lines(chain, mapping, forcing, "rhs", "out", "a")

    def body(lines):
        return "\n".join("    " + line for line in lines)

    forces = f", c_1..c_{n}, A, Omega" if chain.forced else ""
    kind = "forced chain" if chain.forced else "chain"
    plus_q = " + Q" if chain.forced else ""
    rhs = "(F(q, v) + Q(v, t))" if chain.forced else "F(q, v)"
    return f'''"""Generated by pendulum_lab.codegen for a {kind} of {n} link(s); do not edit.

State order q = (theta_1..theta_{n}), params = (m_1..m_{n}, l_1..l_{n}, g{forces}).
"""
import math

import numba
import numpy as np

from pendulum_lab._signatures import ACCELERATION, HAMILTON
from pendulum_lab.codegen import solve_spd


@numba.njit(HAMILTON, cache=True)
def hamilton(t, q, p, params, dq, dp):
    """dq = M(q)^-1 p (= dH/dp); dp = dL/dq{plus_q} at omega = dq (= -dH/dq{plus_q})."""
{body(hamilton)}


@numba.njit(ACCELERATION, cache=True)
def acceleration(t, q, v, params, out):
    """out = M(q)^-1 {rhs}."""
{body(accel)}
'''


def cache_dir() -> Path:
    """Where generated kernels live: ``$PENDULUM_LAB_CACHE`` or the user cache folder."""
    root = os.environ.get("PENDULUM_LAB_CACHE")
    if root is None:
        base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
        root = Path(base) / "pendulum_lab"
    return Path(root) / "kernels"


def _write_if_changed(path: Path, text: str) -> None:
    # Rewriting an unchanged file would change its timestamp and invalidate
    # Numba's cache; several processes may race here, so write atomically.
    if path.exists() and path.read_text() == text:
        return
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
    with os.fdopen(fd, "w") as handle:
        handle.write(text)
    os.replace(tmp, path)


@functools.cache
def load_kernels(n: int, forced: bool = False, looped: bool | None = None) -> SimpleNamespace:
    """Compile (or load from the disk cache) the kernels for ``n`` links.

    ``forced`` selects the chain with damping and drive (see
    :class:`~pendulum_lab.mechanics.Chain`). Returns a namespace with
    ``hamilton`` and ``acceleration`` (and their ``source`` and ``path``).
    ``looped``: whether to take :func:`looped_kernels` instead of generating
    them from the expressions; by default for chains longer than
    ``UNROLLED_MAX_LINKS`` (tests and benchmarks compare the two).
    """
    if looped if looped is not None else n > UNROLLED_MAX_LINKS:
        return looped_kernels()
    source = kernel_source(derive_chain(n, forced))
    # The file name carries a hash of the generated text and of this module,
    # so a change in either gets a fresh file and a fresh Numba cache.
    here = Path(__file__).parent
    support = (here / "codegen.py").read_bytes() + (here / "_signatures.py").read_bytes()
    digest = hashlib.sha256(source.encode() + support).hexdigest()[:16]
    stem = f"chain{n}_forced" if forced else f"chain{n}"
    path = cache_dir() / f"{stem}_{digest}.py"
    _write_if_changed(path, source)
    name = f"pendulum_lab_kernels_{stem}_{digest}"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return SimpleNamespace(hamilton=module.hamilton, acceleration=module.acceleration,
                           source=source, path=path)


@functools.cache
def looped_kernels() -> SimpleNamespace:
    """The kernels of every chain longer than ``UNROLLED_MAX_LINKS``, conservative or forced.

    They loop over the links instead of unrolling the expressions
    (:mod:`pendulum_lab.long_chains`): ``O(n)`` per evaluation, one source
    for every ``n``, compiled once per machine and cached by Numba like the
    generated kernels. Returns the namespace of :func:`load_kernels`.
    """
    from . import long_chains  # compiles (or loads) the kernels on first use

    return SimpleNamespace(hamilton=long_chains.hamilton, acceleration=long_chains.acceleration,
                           source=inspect.getsource(long_chains),
                           path=Path(long_chains.__file__))


def parameters_array(masses, lengths, g) -> np.ndarray:
    """``params`` of a conservative chain as the kernels expect it."""
    return np.array([*masses, *lengths, g], dtype=float)
