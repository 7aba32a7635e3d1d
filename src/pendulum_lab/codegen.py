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

import ctypes
import ctypes.util
import functools
import hashlib
import importlib.util
import math
import os
import sys
import tempfile
from pathlib import Path
from types import SimpleNamespace

import numba
import numpy as np
import sympy as sp
from llvmlite import ir as llvm_ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from ._signatures import VECTOR
from .mechanics import Chain, derive_chain

__all__ = [
    "kernel_source",
    "load_generated",
    "load_kernels",
    "parameters_array",
    "sincos",
    "solve_spd",
]



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


def _c_library_has_sincos() -> bool:
    try:
        return hasattr(ctypes.CDLL(ctypes.util.find_library("m")), "sincos")
    except OSError:
        return False


#: Whether the C math library has ``sincos`` (glibc does; it is not standard C).
HAVE_SINCOS = _c_library_has_sincos()


@intrinsic
def sincos(typingctx, x):
    """``(sin(x), cos(x))`` for a float ``x``, from one call of the C library's ``sincos``.

    The kernels need the sine and the cosine of the same angle differences
    (the mass matrix has ``cos(theta_i - theta_j)``, the forces
    ``sin(theta_i - theta_j)``); one call shares the argument reduction, as a C
    compiler arranges by itself (LLVM, behind Numba, does not). glibc's
    ``sincos`` returns exactly ``sin(x)`` and ``cos(x)``. Without ``sincos`` in
    the C library, two separate calls.
    """
    if not isinstance(x, types.Float):
        return None
    signature = types.UniTuple(types.float64, 2)(types.float64)

    def codegen(context, builder, sig, args):
        double = llvm_ir.DoubleType()
        if HAVE_SINCOS:
            function = cgutils.get_or_insert_function(
                builder.module,
                llvm_ir.FunctionType(llvm_ir.VoidType(), [double, double.as_pointer(),
                                                          double.as_pointer()]),
                "sincos",
            )
            sine = cgutils.alloca_once(builder, double)
            cosine = cgutils.alloca_once(builder, double)
            builder.call(function, [args[0], sine, cosine])
            values = [builder.load(sine), builder.load(cosine)]
        else:
            values = [builder.call(builder.module.declare_intrinsic(name, [double]), args)
                      for name in ("llvm.sin", "llvm.cos")]
        return context.make_tuple(builder, sig.return_type, values)

    return signature, codegen


def _plain_symbols(chain: Chain):
    """Map the chain's symbols to short names that cannot clash with the arguments."""
    n = chain.n
    th = sp.symbols(f"th0:{n}", real=True)
    w = sp.symbols(f"w0:{n}", real=True)
    pars = sp.symbols(f"par0:{len(chain.parameters)}", real=True)
    mapping = dict(zip(chain.q, th)) | dict(zip(chain.omega, w))
    mapping |= dict(zip(chain.parameters, pars))
    return th, w, pars, mapping


def _paired_trig(exprs: list[sp.Expr], mapping: dict) -> tuple[list[str], dict]:
    """Lines computing ``sin(x)`` and ``cos(x)`` together where ``exprs`` need both.

    Returns the lines ``sin0, cos0 = sincos(x)`` (see :func:`sincos`) and the
    substitution ``{sin(x): sin0, cos(x): cos0}`` for the expressions.
    """
    kinds: dict = {}
    for expr in exprs:
        for call in sp.sympify(expr).xreplace(mapping).atoms(sp.sin, sp.cos):
            kinds.setdefault(call.args[0], set()).add(call.func)
    lines, substitution = [], {}
    for k, angle in enumerate(sorted((x for x, f in kinds.items() if len(f) == 2), key=str)):
        sine, cosine = sp.Symbol(f"sin{k}", real=True), sp.Symbol(f"cos{k}", real=True)
        lines.append(f"{sine}, {cosine} = sincos({sp.pycode(angle)})")
        substitution |= {sp.sin(angle): sine, sp.cos(angle): cosine}
    return lines, substitution


def _assignments(targets: list[str], exprs: list[sp.Expr], mapping: dict, prefix: str,
                 trig: dict | None = None) -> list[str]:
    """Lines ``target = expression`` with common subexpressions shared (``cse``).

    ``trig`` replaces sines and cosines computed beforehand (:func:`_paired_trig`).
    """
    exprs = [sp.sympify(e).xreplace(mapping).xreplace(trig or {}) for e in exprs]
    temps, reduced = sp.cse(exprs, symbols=sp.numbered_symbols(prefix))
    lines = [f"{t} = {sp.pycode(e)}" for t, e in temps]
    lines += [f"{t} = {sp.pycode(e)}" for t, e in zip(targets, reduced)]
    return lines


def _solve_lines(chain: Chain, mapping: dict, rhs: list[str], rhs_array: str, out: str,
                 prefix: str, trig: dict) -> list[str]:
    """Lines that solve ``M(q) out = rhs``.

    ``rhs`` names the right-hand side's entries, ``rhs_array`` the array that
    holds them. For one or two links the closed form needs no array at all
    (this is the hot path of the course); longer chains fill ``mass`` and call
    :func:`solve_spd`.
    """
    n = chain.n
    mass = list(chain.mass_matrix)
    if n == 1:
        (m00,) = _assignments(["m00"], mass, mapping, prefix, trig)
        return [m00, f"{out}[0] = {rhs[0]} / m00"]
    if n == 2:
        lines = _assignments(["m00", "m01", "m11"], [mass[0], mass[1], mass[3]], mapping, prefix,
                             trig)
        return lines + [
            "det = m00 * m11 - m01 * m01",
            f"{out}[0] = (m11 * {rhs[0]} - m01 * {rhs[1]}) / det",
            f"{out}[1] = (m00 * {rhs[1]} - m01 * {rhs[0]}) / det",
        ]
    lines = [f"mass = np.empty(({n}, {n}))"]
    lines += _assignments([f"mass[{i}, {j}]" for i in range(n) for j in range(n)], mass,
                          mapping, prefix, trig)
    return lines + [f"solve_spd(mass, {rhs_array}, {out})"]


def kernel_source(chain: Chain) -> str:
    """The Python source of the two Numba kernels for ``chain``."""
    n = chain.n
    _, _, _, mapping = _plain_symbols(chain)
    unpack = [f"th{i} = q[{i}]" for i in range(n)]
    unpack += [f"par{i} = params[{i}]" for i in range(len(chain.parameters))]
    momentum_rates = chain.dlagrangian_dq
    if chain.forced:
        momentum_rates = momentum_rates + chain.generalized_forces
    mass = list(chain.mass_matrix)
    trig_lines, trig = _paired_trig(mass + list(momentum_rates), mapping)
    hamilton = unpack + trig_lines
    hamilton += _solve_lines(chain, mapping, [f"p[{i}]" for i in range(n)], "p", "dq", "a",
                             trig)
    hamilton += [f"w{i} = dq[{i}]" for i in range(n)]
    hamilton += _assignments([f"dp[{i}]" for i in range(n)], list(momentum_rates), mapping, "b",
                             trig)
    trig_lines, trig = _paired_trig(mass + list(chain.forcing), mapping)
    accel = unpack + trig_lines + [f"w{i} = v[{i}]" for i in range(n)]
    forcing = [f"f{i}" for i in range(n)] if n <= 2 else [f"rhs[{i}]" for i in range(n)]
    if n > 2:
        accel += [f"rhs = np.empty({n})"]
    accel += _assignments(forcing, list(chain.forcing), mapping, "c", trig)
    accel += _solve_lines(chain, mapping, forcing, "rhs", "out", "a", trig)

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
from pendulum_lab.codegen import sincos, solve_spd

#: Coordinates of the state (``q`` and ``p`` each have this many).
COORDINATES = {n}


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
def load_kernels(n: int, forced: bool = False) -> SimpleNamespace:
    """Compile (or load from the disk cache) the kernels for ``n`` links.

    ``forced`` selects the chain with damping and drive (see
    :class:`~pendulum_lab.mechanics.Chain`). Returns a namespace with
    ``hamilton``, ``acceleration``, ``source``, ``path`` and ``module`` (the
    name the generated module is imported under, which also defines
    ``COORDINATES = n``).
    """
    source = kernel_source(derive_chain(n, forced))
    stem = f"chain{n}_forced" if forced else f"chain{n}"
    here = Path(__file__).parent
    module = load_generated(stem, source, [here / "codegen.py", here / "_signatures.py"])
    return SimpleNamespace(hamilton=module.hamilton, acceleration=module.acceleration,
                           source=source, path=Path(module.__file__), module=module.__name__)


def load_generated(stem: str, source: str, support, inject: dict | None = None):
    """Write generated Python ``source`` into the kernel cache folder and import it.

    The file is ``<stem>_<digest>.py``, where the digest hashes the source and
    the files in ``support`` (the code the generated module relies on), so a
    change in either gets a fresh file and a fresh Numba cache: Numba's cache
    checks only the generated file itself. ``inject`` sets module globals
    before the source runs (objects that cannot be imported by name).
    Returns the module, registered in ``sys.modules`` as
    ``pendulum_lab_kernels_<stem>_<digest>``.
    """
    digest = hashlib.sha256(source.encode() + b"".join(Path(f).read_bytes() for f in support))
    name = f"{stem}_{digest.hexdigest()[:16]}"
    path = cache_dir() / f"{name}.py"
    _write_if_changed(path, source)
    name = f"pendulum_lab_kernels_{name}"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    module.__dict__.update(inject or {})
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def parameters_array(masses, lengths, g) -> np.ndarray:
    """``params`` of a conservative chain as the kernels expect it."""
    return np.array([*masses, *lengths, g], dtype=float)
