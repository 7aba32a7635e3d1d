"""Compiled vector fields: SymPy expressions printed as Numba kernels.

For each number of links ``n``, conservative or forced, this module writes
one small Python source file (into a cache folder) holding two kernels
generated from the symbolic equations of :mod:`pendulum_lab.symbolic.mechanics`:

``hamilton(t, q, p, params, dq, dp)``
    Hamilton's equations: ``dq = dH/dp = M(q)^-1 p`` and ``dp = -dH/dq + Q``,
    where ``-dH/dq`` equals ``dL/dq`` evaluated at ``omega = M^-1 p`` and the
    generalized forces ``Q(omega, t)`` are zero unless the chain is forced.
``acceleration(t, q, v, params, out)``
    ``out = M(q)^-1 (F(q, v) + Q(v, t))``, for the course report's
    velocity-variable methods.
``stages(ts, y, params, dy, work)``
    ``hamilton`` at the columns of ``y = (q, p)`` (an implicit Runge-Kutta
    step's stages, see :mod:`pendulum_lab.codegen.signatures`). For one or two links
    it is ``hamilton``'s lines in one loop over the columns, with the sines
    and cosines of :mod:`pendulum_lab.codegen.lowlevel`, so that the compiler
    evaluates 8 columns per pass with SIMD instructions; an angle beyond
    those functions' range sends the call to the C library's, column by
    column. Longer chains, and fields made elsewhere
    (:func:`stage_kernel`), evaluate one column at a time.

``M`` is solved numerically (Cholesky; it is symmetric positive definite), as
PyDy's code generator does, rather than inverted symbolically. The kernels are
compiled by Numba with the package's disk cache
(:func:`~pendulum_lab.codegen.cache.cached_njit`): compilation happens once per machine,
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
import inspect
import math
import re
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import sympy as sp

from ..symbolic.discrete_mechanics import DiscreteLagrangian, discrete_lagrangian
from ..symbolic.mechanics import Chain, derive_chain
from .cache import cached_njit, load_generated
from .compile_status import compiling
from .lowlevel import LANE_GROUP

__all__ = [
    "UNROLLED_MAX_LINKS",
    "chain_description",
    "discrete_kernel_source",
    "import_name",
    "kernel_source",
    "load_discrete_kernels",
    "load_kernels",
    "load_system_kernels",
    "looped_kernels",
    "paired_trig",
    "parameters_array",
    "solve_spd",
    "stage_kernel",
]



#: Chains up to this many links are evaluated from their SymPy expressions,
#: unrolled (lambdified by :mod:`pendulum_lab.model.numeric`, printed as kernels here);
#: longer ones link by link, from the closed form (:mod:`pendulum_lab.codegen.long_chains`),
#: which is the faster from three links on and needs no code generated per chain.
UNROLLED_MAX_LINKS = 2

@cached_njit  # compiled with the first kernel that calls it, never at import
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


def _trig_functions(exprs: list[sp.Expr], mapping: dict) -> dict:
    """``{angle: {sin, cos} or one of them}``: the trigonometry of ``exprs`` after ``mapping``."""
    kinds: dict = {}
    for expr in exprs:
        for call in sp.sympify(expr).xreplace(mapping).atoms(sp.sin, sp.cos):
            kinds.setdefault(call.args[0], set()).add(call.func)
    return kinds


def paired_trig(exprs: list[sp.Expr], mapping: dict) -> tuple[list[tuple], dict]:
    """The angles whose sine and cosine ``exprs`` both need, to compute them together.

    Returns ``pairs``, a list of ``(sine, cosine, angle)`` (new symbols
    ``sin0``, ``cos0``, ... and the angle, after ``mapping``), and the
    substitution ``{sin(angle): sine, cos(angle): cosine}`` for the
    expressions. The kernels compute each pair with
    :func:`~pendulum_lab.codegen.lowlevel.sincos`; the C
    yardstick of the benchmarks with C's ``sincos`` behind the same shift near
    ``+-pi``, so that both do the same arithmetic.
    """
    kinds = _trig_functions(exprs, mapping)
    pairs, substitution = [], {}
    for k, angle in enumerate(sorted((x for x, f in kinds.items() if len(f) == 2), key=str)):
        sine, cosine = sp.Symbol(f"sin{k}", real=True), sp.Symbol(f"cos{k}", real=True)
        pairs.append((sine, cosine, angle))
        substitution |= {sp.sin(angle): sine, sp.cos(angle): cosine}
    return pairs, substitution


def _trig_lines(exprs: list[sp.Expr], mapping: dict) -> tuple[list[str], dict]:
    """:func:`paired_trig` as kernel lines ``sin0, cos0 = sincos(angle)``, and the substitution."""
    pairs, substitution = paired_trig(exprs, mapping)
    return [f"{s}, {c} = sincos({sp.pycode(angle)})" for s, c, angle in pairs], substitution


def _assignments(targets: list[str], exprs: list[sp.Expr], mapping: dict, prefix: str,
                 trig: dict | None = None) -> list[str]:
    """Lines ``target = expression`` with common subexpressions shared (``cse``).

    ``trig`` replaces sines and cosines computed beforehand (:func:`paired_trig`).
    """
    exprs = [sp.sympify(e).xreplace(mapping).xreplace(trig or {}) for e in exprs]
    temps, reduced = sp.cse(exprs, symbols=sp.numbered_symbols(prefix))
    lines = [f"{t} = {sp.pycode(e)}" for t, e in temps]
    lines += [f"{t} = {sp.pycode(e)}" for t, e in zip(targets, reduced)]
    return lines


def _solve_lines(chain: Chain, mapping: dict, rhs: list[str], rhs_array: str, out: str,
                 prefix: str, trig: dict | None = None,
                 mass: sp.Matrix | None = None) -> list[str]:
    """Lines that solve ``M(q) out = rhs`` (or ``mass out = rhs``, ``mass`` SPD).

    ``rhs`` names the right-hand side's entries, ``rhs_array`` the array that
    holds them. For one or two links the closed form needs no array at all
    (this is the hot path of the course); longer chains fill ``mass`` and call
    :func:`solve_spd`.
    """
    n = chain.n
    mass = list(chain.mass_matrix if mass is None else mass)
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
    """The Python source of the Numba kernels for ``chain`` (see the module docstring)."""
    n = chain.n
    _, _, _, mapping = _plain_symbols(chain)
    unpack = [f"th{i} = q[{i}]" for i in range(n)]
    parameters = [f"par{i} = params[{i}]" for i in range(len(chain.parameters))]
    momentum_rates = chain.dlagrangian_dq
    if chain.forced:
        momentum_rates = momentum_rates + chain.generalized_forces
    mass = list(chain.mass_matrix)
    offset = _momentum_offset(chain)
    trig_lines, trig = _trig_lines(mass + list(momentum_rates) + offset, mapping)
    hamilton = trig_lines
    if offset:  # p = M omega + b: solve M omega = p - b
        # the sines and cosines of b recur in dL/dq: computed once, before both
        calls = {call for b in offset
                 for call in sp.sympify(b).xreplace(mapping).xreplace(trig).atoms(sp.sin, sp.cos)}
        for k, call in enumerate(sorted(calls, key=str)):
            hamilton.append(f"trig{k} = {sp.pycode(call)}")
            trig = trig | {call: sp.Symbol(f"trig{k}", real=True)}
        shifted = [f"r{i}" for i in range(n)] if n <= 2 else [f"shifted[{i}]" for i in range(n)]
        if n > 2:
            hamilton += [f"shifted = np.empty({n})"]
        hamilton += _assignments(shifted, [sp.Symbol(f"p[{i}]") - b for i, b in
                                           enumerate(offset)], mapping, "e", trig)
        hamilton += _solve_lines(chain, mapping, shifted, "shifted", "dq", "a", trig)
    else:
        hamilton += _solve_lines(chain, mapping, [f"p[{i}]" for i in range(n)], "p", "dq", "a",
                                 trig)
    hamilton += [f"w{i} = dq[{i}]" for i in range(n)]
    hamilton += _assignments([f"dp[{i}]" for i in range(n)], list(momentum_rates), mapping, "b",
                             trig)
    if n <= UNROLLED_MAX_LINKS:
        angles = sorted(_trig_functions(mass + list(momentum_rates), mapping), key=str)
        stages = _lane_source(parameters, unpack, hamilton, angles)
    else:
        stages = _ONE_BY_ONE.format(name="stages", field="hamilton")
    trig_lines, trig = _trig_lines(mass + list(chain.forcing), mapping)
    accel = unpack + parameters + trig_lines + [f"w{i} = v[{i}]" for i in range(n)]
    forcing = [f"f{i}" for i in range(n)] if n <= 2 else [f"rhs[{i}]" for i in range(n)]
    if n > 2:
        accel += [f"rhs = np.empty({n})"]
    accel += _assignments(forcing, list(chain.forcing), mapping, "c", trig)
    accel += _solve_lines(chain, mapping, forcing, "rhs", "out", "a", trig)

    plus_q = " + Q" if chain.forced else ""
    rhs = "(F(q, v) + Q(v, t))" if chain.forced else "F(q, v)"
    dq_rule = "M(q)^-1 p"
    if offset:
        dq_rule, rhs = "M(q, t)^-1 (p - b(q, t))", rhs.replace("q, v", "q, v, t")
    return f'''"""{_source_header(chain)}
"""
import math

import numpy as np

from pendulum_lab.codegen.cache import cached_njit
from pendulum_lab.codegen.kernels import solve_spd
from pendulum_lab.codegen.lowlevel import (
    LIMIT,
    align_stack,
    inline_into_callers,
    lane_cos,
    lane_sin,
    lane_sincos,
    sincos,
)
from pendulum_lab.codegen.signatures import ACCELERATION, HAMILTON, STAGES

#: Coordinates of the state (``q`` and ``p`` each have this many).
COORDINATES = {n}


@cached_njit(HAMILTON)
def hamilton(t, q, p, params, dq, dp):
    """dq = {dq_rule} (= dH/dp); dp = dL/dq{plus_q} at omega = dq (= -dH/dq{plus_q})."""
{_indent(unpack + parameters + hamilton)}


@cached_njit(ACCELERATION)
def acceleration(t, q, v, params, out):
    """out = M(q)^-1 {rhs}."""
{_indent(accel)}
{stages}'''


def _momentum_offset(system) -> list:
    """The entries of ``b`` in ``p = M omega + b`` (a moving pivot's); ``[]`` when all zero."""
    offset = system.momentum_offset
    return [] if all(sp.sympify(b) == 0 for b in offset) else list(offset)


def _source_header(system) -> str:
    """The docstring of a generated kernel module: what it is for and the state order."""
    n = system.n
    if isinstance(system, Chain):
        forces = f", c_1..c_{n}, A, Omega" if system.forced else ""
        kind = "forced chain" if system.forced else "chain"
        return (f"Generated by pendulum_lab.codegen.kernels for a {kind} of {n} link(s); do not\n"
                f"edit.\n\nState order q = (theta_1..theta_{n}), params = (m_1..m_{n}, "
                f"l_1..l_{n}, g{forces}).")
    names = ", ".join(map(str, system.q))
    return (f"Generated by pendulum_lab.codegen.kernels for {system.name}; do not edit.\n\n"
            f"State order q = ({names}), params = ({', '.join(map(str, system.parameters))}).")


def _indent(lines: list[str], depth: int = 1) -> str:
    return "\n".join("    " * depth + line for line in lines)


# The field at each column of the states in turn, through a kernel of the
# ``hamilton`` type called ``{field}`` (columns copied to contiguous vectors).
_ONE_BY_ONE = '''

@cached_njit(STAGES)
def {name}(ts, y, params, dy, work):
    """``{field}`` at each column of ``y`` in turn (see pendulum_lab.codegen.signatures)."""
    n = y.shape[0] // 2
    q, p, dq, dp = work[:n], work[n:2 * n], work[2 * n:3 * n], work[3 * n:]
    for k in range(ts.size):
        for i in range(2 * n):
            work[i] = y[i, k]
        {field}(ts[k], q, p, params, dq, dp)
        for i in range(2 * n):
            dy[i, k] = work[2 * n + i]
'''


def _column_rewrites(n: int) -> list:
    """How ``hamilton``'s lines read at column ``k`` of ``y = (q, p)`` and ``dy = (dq, dp)``."""
    rows = {"q": ("y", 0), "p": ("y", n), "dq": ("dy", 0), "dp": ("dy", n)}

    def subscript(match):
        array, offset = rows[match[1]]
        return f"{array}[{int(match[2]) + offset}, k]"

    return [(re.compile(r"\b(q|p|dq|dp)\[(\d+)\]"), subscript)]


#: The lane functions in place of the C library's (:mod:`pendulum_lab.codegen.lowlevel`).
_LANE_TRIG = [
    (re.compile(r"\bsincos\("), "lane_sincos("),
    (re.compile(r"\bmath\.sin\("), "lane_sin("),
    (re.compile(r"\bmath\.cos\("), "lane_cos("),
]


def _rewrite(lines: list[str], rewrites: list) -> list[str]:
    for pattern, replacement in rewrites:
        lines = [pattern.sub(replacement, line) for line in lines]
    return lines


def _lane_source(parameters: list[str], unpack: list[str], hamilton: list[str],
                 angles: list[sp.Expr]) -> str:
    """The vectorized ``stages`` kernel: ``hamilton``'s lines in a loop over the columns.

    The loop is written twice from the same lines: with the lane functions
    (:mod:`pendulum_lab.codegen.lowlevel`), which the compiler vectorizes, and with
    the C library's sines and cosines, for what the lane loop does not serve.
    That is fewer columns than one vector pass (``LANE_GROUP``): as scalar
    code the lane functions always reduce and evaluate both series, which
    costs more than the C library's sines for small arguments
    (docs/design/stage-kernel.md). And it is
    a column where an argument of a sine or cosine exceeds the lane
    functions' range (``LIMIT``): then all columns are evaluated again, since
    a branch per column inside the loop would stop the vectorization. The
    division's check for zero is left to NumPy's rules (``error_model``), for
    the same reason: a zero determinant gives infinities, which the
    integrators report, not an exception.
    """
    body = _rewrite(["t = ts[k]"] + unpack + hamilton, _column_rewrites(len(unpack)))
    far = " | ".join(f"(abs({sp.pycode(angle)}) > LIMIT)" for angle in angles) or "False"
    lanes = _rewrite(body, _LANE_TRIG) + [f"far |= {far}"]
    return f'''

@cached_njit(STAGES, error_model="numpy")
def stages(ts, y, params, dy, work):
    """hamilton at every column of y, {LANE_GROUP} columns per pass (codegen.lowlevel)."""
    align_stack()
    inline_into_callers()
{_indent(parameters)}
    if ts.size >= {LANE_GROUP}:
        far = False
        for k in range(ts.size):
{_indent(lanes, 3)}
        if not far:
            return
    # fewer columns than a vector pass, or an angle beyond LIMIT: the C library's
    for k in range(ts.size):
{_indent(body, 2)}
'''


@functools.cache
def load_kernels(n: int, forced: bool = False, looped: bool | None = None) -> SimpleNamespace:
    """Compile (or load from the disk cache) the kernels for ``n`` links.

    ``forced`` selects the chain with damping and drive (see
    :class:`~pendulum_lab.symbolic.mechanics.Chain`). Returns a namespace with
    ``hamilton``, ``acceleration``, ``source``, ``path`` and ``module`` (the
    name the generated module is imported under, which also defines
    ``COORDINATES = n``).
    ``looped``: whether to take :func:`looped_kernels` instead of generating
    them from the expressions; by default for chains longer than
    ``UNROLLED_MAX_LINKS`` (tests and benchmarks compare the two).
    """
    if looped if looped is not None else n > UNROLLED_MAX_LINKS:
        return looped_kernels()
    source = kernel_source(derive_chain(n, forced))
    description = chain_description(n, forced)
    module, path = load_generated(f"chain{n}_forced" if forced else f"chain{n}", source,
                                  what=f"the vector field of {description}")
    return SimpleNamespace(hamilton=module.hamilton, acceleration=module.acceleration,
                           stages=module.stages, source=source, path=path,
                           module=module.__name__, description=description)


@functools.cache
def load_system_kernels(system) -> SimpleNamespace:
    """Compile (or load from the disk cache) the kernels of a
    :class:`~pendulum_lab.symbolic.systems.MechanicalSystem`: the same generator as a chain's
    (:func:`kernel_source`), so the same namespace as :func:`load_kernels`."""
    source = kernel_source(system)
    module, path = load_generated(_system_stem(system), source,
                                  what=f"the vector field of {system.name}")
    return SimpleNamespace(hamilton=module.hamilton, acceleration=module.acceleration,
                           stages=module.stages, source=source, path=path,
                           module=module.__name__, description=system.name)


def _system_stem(system) -> str:
    """The start of the file names of a system's generated modules (from its name)."""
    return "system_" + re.sub(r"\W+", "_", system.name).strip("_")[:40]


def chain_description(n: int, forced: bool = False) -> str:
    """What the kernels of ``n`` links are for, in words (messages about compilations).

    Examples
    --------
    >>> chain_description(2), chain_description(1, forced=True), chain_description(5)
    ('the double pendulum', 'the damped, driven pendulum', 'a chain of 5 links')
    """
    if n > 2:
        return f"a {'damped, driven ' if forced else ''}chain of {n} links"
    name = {1: "pendulum", 2: "double pendulum"}[n]
    if forced:
        return f"the damped, driven {name}"
    return f"the {'simple ' if n == 1 else ''}{name}"


@functools.cache
def looped_kernels() -> SimpleNamespace:
    """The kernels of every chain longer than ``UNROLLED_MAX_LINKS``, conservative or forced.

    They loop over the links instead of unrolling the expressions
    (:mod:`pendulum_lab.codegen.long_chains`): ``O(n)`` per evaluation, one source
    for every ``n``, compiled once per machine and cached by Numba like the
    generated kernels. Returns the namespace of :func:`load_kernels`.
    """
    description = "chains of three or more links"
    with compiling(f"the vector field of {description}"):
        from . import long_chains  # compiles (or loads) the kernels on first use

        stages = stage_kernel(long_chains.hamilton)
    return SimpleNamespace(hamilton=long_chains.hamilton, acceleration=long_chains.acceleration,
                           stages=stages, source=inspect.getsource(long_chains),
                           path=Path(long_chains.__file__), module=long_chains.__name__,
                           description=description)


def import_name(kernel) -> tuple[str, str]:
    """The module and the name a compiled kernel is imported by (generated code imports it)."""
    module, name = kernel.py_func.__module__, kernel.py_func.__name__
    if getattr(sys.modules.get(module), name, None) is not kernel:
        raise TypeError(f"the kernel {module}.{name} cannot be imported by that name: a kernel "
                        "must be a module-level function of a module (generate it with "
                        "codegen.load_generated), not a closure")
    return module, name


@functools.cache
def stage_kernel(hamilton, field: str | None = None):
    """A ``stages`` kernel for a field known only by its ``hamilton`` kernel: one column at a time.

    For fields made outside :func:`kernel_source` (the long chains' looped
    kernels, Henon's rescaled field). Generated into the kernel cache, like
    the fields, so that Numba keeps it on disk. ``field`` names the field in the message of
    its compilation (by default the kernel's module and name).
    """
    module, name = import_name(hamilton)
    source = (f'"""Generated by pendulum_lab.codegen.kernels: the stages kernel of '
              f'{module}.{name}; do not edit."""\n'
              'from pendulum_lab.codegen.cache import cached_njit\n'
              'from pendulum_lab.codegen.signatures import STAGES\n'
              f'from {module} import {name} as field\n')
    source += _ONE_BY_ONE.format(name="stages", field="field")
    stem = f"stages_{module.removeprefix('pendulum_lab_kernels_')}_{name}".replace(".", "_")
    return load_generated(stem, source,
                          what=f"the stage kernel of {field or f'{module}.{name}'}")[0].stages


def parameters_array(masses, lengths, g) -> np.ndarray:
    """``params`` of a conservative chain as the kernels expect it."""
    return np.array([*masses, *lengths, g], dtype=float)


# ----------------------------------------------------------------------- variational integrators
def _discrete_symbols(dl: DiscreteLagrangian) -> dict:
    """Map ``q_k``, ``q_{k+1}``, ``v``, ``h`` and the parameters to the kernels' local names."""
    n = dl.n
    plain = [sp.symbols(f"{base}0:{n}", real=True) for base in ("a", "b", "v")]
    pars = sp.symbols(f"par0:{len(dl.chain.parameters)}", real=True)
    mapping = dict(zip(dl.q, plain[0])) | dict(zip(dl.q_next, plain[1]))
    mapping |= dict(zip(dl.v, plain[2])) | dict(zip(dl.chain.parameters, pars))
    return mapping | {dl.h: sp.Symbol("h", positive=True)}


def _general_solve_lines(n: int, matrix: str, rhs: str, out: str) -> list[str]:
    """Lines ``out_i = (matrix^-1 rhs)_i`` for a general (not symmetric) matrix.

    ``matrix`` names entries ``{matrix}ij`` and ``rhs`` entries ``{rhs}i``
    (local variables); closed forms for ``n <= 2``, LAPACK beyond.
    """
    if n == 1:
        return [f"{out}0 = {rhs}0 / {matrix}00"]
    if n == 2:
        return [
            f"det = {matrix}00 * {matrix}11 - {matrix}01 * {matrix}10",
            f"{out}0 = ({matrix}11 * {rhs}0 - {matrix}01 * {rhs}1) / det",
            f"{out}1 = ({matrix}00 * {rhs}1 - {matrix}10 * {rhs}0) / det",
        ]
    entries = ", ".join("(" + ", ".join(f"{matrix}{i}{j}" for j in range(n)) + ",)"
                        for i in range(n))
    return [f"solution = np.linalg.solve(np.array(({entries})), "
            f"np.array(({', '.join(f'{rhs}{i}' for i in range(n))},)))"] + [
        f"{out}{i} = solution[{i}]" for i in range(n)]


def discrete_kernel_source(dl: DiscreteLagrangian) -> str:
    """The Python source of the Numba kernels of a variational integrator.

    Three kernels, printed from the velocity forms of ``dl`` (see
    :class:`~pendulum_lab.symbolic.discrete_mechanics.DiscreteLagrangian`), where
    ``v = (q1 - q0) / h`` is formed once, so no ``1/h`` cancels at run time:

    ``fixed_point_update(h, q0, q1, params, p0, out)``
        ``out = q1 + h Mbar^-1 (p0 - p_k(q0, q1))`` with ``p_k = -D_1 L_d``
        and the mean mass matrix ``Mbar`` (SPD): a fixed point ``q1`` solves
        the transform, and the map contracts by ``O(h |omega|)``.
    ``newton_update(h, q0, q1, params, p0, out)``
        One Newton step ``out = q1 - (dp_k/dq1)^-1 (p_k(q0, q1) - p0)`` with the
        generated Jacobian.
    ``impulse(h, q0, q1, params, out)``
        ``out = D_2 L_d(q0, q1) + D_1 L_d(q0, q1)``: the momentum after the step
        minus the one before, ``h`` times forces. Written as ``p1 = p0 +
        impulse`` the update keeps round-off at the level of ``p``; evaluating
        ``D_2 L_d`` itself would form ``Mbar v`` with ``v = (q1 - q0) / h``
        and carry the rounding of ``q1`` divided by ``h``.
    """
    n = dl.n
    chain, mapping = dl.chain, _discrete_symbols(dl)
    unpack = [f"a{i} = q0[{i}]" for i in range(n)] + [f"b{i} = q1[{i}]" for i in range(n)]
    unpack += [f"v{i} = (b{i} - a{i}) / h" for i in range(n)]
    unpack += [f"par{i} = params[{i}]" for i in range(len(chain.parameters))]

    fixed = list(unpack)
    fixed += _assignments([f"k{i}" for i in range(n)], list(dl.momentum_minus_form), mapping, "c")
    residual = [f"r{i}" for i in range(n)] if n <= 2 else [f"rhs[{i}]" for i in range(n)]
    if n > 2:
        fixed.append(f"rhs = np.empty({n})")
    fixed += [f"{r} = p0[{i}] - k{i}" for i, r in enumerate(residual)]
    fixed += _solve_lines(chain, mapping, residual, "rhs", "out", "d", mass=dl.mean_mass)
    fixed += [f"out[{i}] = b{i} + h * out[{i}]" for i in range(n)]

    newton = list(unpack)
    jacobian = dl.momentum_minus_jacobian_form
    newton += _assignments([f"k{i}" for i in range(n)] + [f"j{i}{j}" for i in range(n)
                                                            for j in range(n)],
                           [*dl.momentum_minus_form, *jacobian], mapping, "c")
    newton += [f"r{i} = k{i} - p0[{i}]" for i in range(n)]
    newton += _general_solve_lines(n, "j", "r", "x")
    newton += [f"out[{i}] = b{i} - x{i}" for i in range(n)]

    impulse = list(unpack)
    impulse += _assignments([f"out[{i}]" for i in range(n)], list(dl.impulse_form), mapping, "c")

    kernels = [
        ("DISCRETE_UPDATE", "fixed_point_update", "h, q0, q1, params, p0, out",
         "out = q1 + h Mbar(q0, q1)^-1 (p0 - p_k(q0, q1)).", fixed),
        ("DISCRETE_UPDATE", "newton_update", "h, q0, q1, params, p0, out",
         "out = q1 - J^-1 (p_k(q0, q1) - p0), J = dp_k/dq1.", newton),
        ("DISCRETE_MOMENTUM", "impulse", "h, q0, q1, params, out",
         "out = p_(k+1) - p_k = D_2 L_d(q0, q1) + D_1 L_d(q0, q1).", impulse),
    ]
    if isinstance(chain, Chain):
        what = f"a chain of {n} link(s)"
        order = f"(theta_1..theta_{n})", f"(m_1..m_{n}, l_1..l_{n}, g)"
    else:
        what = chain.name
        order = (f"({', '.join(map(str, chain.q))})",
                 f"({', '.join(map(str, chain.parameters))})")
    header = f'''"""Generated by pendulum_lab.codegen.kernels: the discrete Legendre transforms of
the {dl.rule} rule for {what}; do not edit.

q0, q1 = {order[0]} at the start and the end of a step of size h,
params = {order[1]}, p_k = -D_1 L_d(q0, q1), p_(k+1) = D_2 L_d(q0, q1).
"""
import math

import numpy as np

from pendulum_lab.codegen.cache import cached_njit
from pendulum_lab.codegen.kernels import solve_spd
from pendulum_lab.codegen.signatures import DISCRETE_MOMENTUM, DISCRETE_UPDATE
'''
    return header + "".join(_kernel_text(*kernel) for kernel in kernels)


def _kernel_text(signature: str, name: str, arguments: str, docstring: str, lines) -> str:
    """One generated kernel: decorator, signature line, docstring, indented body."""
    body = "\n".join("    " + line for line in lines)
    return (f"\n\n@cached_njit({signature})\ndef {name}({arguments}):\n"
            f'    """{docstring}"""\n{body}\n')


@functools.cache
def load_discrete_kernels(n, rule: str) -> SimpleNamespace:
    """Compile (or load from the disk cache) the variational kernels for ``n`` links, or for
    a conservative, autonomous :class:`~pendulum_lab.symbolic.systems.MechanicalSystem` ``n``.

    Returns a namespace with ``fixed_point_update``, ``newton_update`` and
    ``impulse`` (see :func:`discrete_kernel_source`), ``source`` and ``path``.
    """
    source = discrete_kernel_source(discrete_lagrangian(n, rule))
    if isinstance(n, int):
        stem, description = f"discrete{n}_{rule}", chain_description(n)
    else:
        stem, description = f"discrete_{_system_stem(n)}_{rule}", n.name
    module, path = load_generated(
        stem, source, what=f"the variational kernels ({rule} rule) of {description}")
    return SimpleNamespace(fixed_point_update=module.fixed_point_update,
                           newton_update=module.newton_update,
                           impulse=module.impulse, source=source, path=path)
