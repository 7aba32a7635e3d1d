"""The equations printed for the browser: a system's SymPy expressions as an ES module.

:func:`browser_module_source` prints the expressions that feed the Numba kernels of
:mod:`pendulum_lab.codegen.kernels` (the mass matrix, ``dL/dq``, the generalized forces, the
momentum offset ``b``) and those of the energies and the points' positions as a small
JavaScript module with no imports, which the kernel-free simulator of the course website runs
(``widgets/static/browser/``). It exports

``hamilton(t, q, p, params, dq, dp)``
    Hamilton's equations, as the ``hamilton`` kernel: ``dq = M(q, t)^-1 (p - b)`` (= dH/dp),
    ``dp = dL/dq + Q`` at ``omega = dq``. ``q, p, dq, dp`` are arrays of ``COORDINATES``
    numbers, ``params`` the parameters in the order of ``PARAMETERS``.
``momenta(t, q, omega, params, p)``
    ``p = M omega + b``.
``energies(t, q, omega, params, out)``
    ``out[0] = T``, ``out[1] = V``.
``positions(t, q, params, out)``
    ``out[D k + j]``: coordinate ``j`` of the position of point ``k`` (``POINTS`` of them, none
    for a system given by its Lagrangian), ``D = DIMENSIONS``: ``(x, y)`` for a plane, ``(x, y,
    z)`` for points in space.

The printer is SymPy's :class:`~sympy.printing.jscode.JavascriptCodePrinter` with integer
powers written as products (``x*x``, as Numba evaluates ``x**2``; ``Math.pow`` is not
guaranteed to be correctly rounded). Shared subexpressions come from ``sympy.cse``, as in the
kernels. ``M`` is solved in closed form for one or two coordinates, as in the kernels, and by
a Cholesky factorisation beyond.

An equation that uses a function JavaScript's ``Math`` lacks (a Bessel function, ``erf``) is
refused with a :class:`ValueError` naming it: the browser cannot run that model.

The module's name carries a key (:func:`~pendulum_lab.codegen.cache.text_key`): of its text
and of the code of this generator and of every package module it imports, the rules of the
Python kernels' keys.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import sympy as sp
from sympy.printing.codeprinter import PrintMethodNotImplementedError
from sympy.printing.jscode import JavascriptCodePrinter
from sympy.printing.precedence import precedence

from ..symbolic.mechanics import Chain
from .cache import text_key

__all__ = ["BrowserModule", "BrowserPrinter", "browser_module", "browser_module_source",
           "unprintable_functions"]

#: Integer powers up to this size are printed as products.
_PRODUCT_POWERS = 4


class BrowserPrinter(JavascriptCodePrinter):
    """SymPy's JavaScript printer, with small integer powers written as products."""

    def __init__(self):
        super().__init__({"strict": True})

    def _print_Pow(self, expr):
        base, exponent = expr.as_base_exp()
        if exponent.is_Integer and 1 <= abs(int(exponent)) <= _PRODUCT_POWERS:
            factor = self.parenthesize(base, precedence(expr))
            product = "*".join([factor] * abs(int(exponent)))
            if exponent > 0:
                return product if exponent == 1 else f"({product})"
            return f"1/{factor}" if exponent == -1 else f"1/({product})"
        return super()._print_Pow(expr)


def unprintable_functions(exprs) -> list[str]:
    """The names of the functions in ``exprs`` that the JavaScript printer cannot print (sorted):
    those ``Math`` lacks."""
    printer = BrowserPrinter()
    missing = set()
    for expr in exprs:
        for call in sp.sympify(expr).atoms(sp.Function):
            try:
                printer.doprint(call.func(*[sp.Symbol(f"x{k}") for k in range(len(call.args))]))
            except (PrintMethodNotImplementedError, TypeError, ValueError):
                missing.add(call.func.__name__)
    return sorted(missing)


def _printed(expr) -> str:
    return BrowserPrinter().doprint(expr)


def _symbols(system) -> dict:
    """The system's coordinates, velocities and parameters mapped to short local names."""
    n = system.n
    mapping = {q: sp.Symbol(f"th{i}", real=True) for i, q in enumerate(system.q)}
    mapping |= {w: sp.Symbol(f"w{i}", real=True) for i, w in enumerate(system.omega)}
    mapping |= {s: sp.Symbol(f"par{i}", real=True) for i, s in enumerate(system.parameters)}
    assert len(mapping) == 2 * n + len(system.parameters)
    return mapping


def _assignments(targets, exprs, mapping, prefix) -> list[str]:
    """Lines ``target = expression;`` with shared subexpressions (``cse``) as constants. A target
    that names an array entry (``dq[0]``) is assigned, any other is declared."""
    exprs = [sp.sympify(e).xreplace(mapping) for e in exprs]
    temps, reduced = sp.cse(exprs, symbols=sp.numbered_symbols(prefix))
    lines = [f"const {t} = {_printed(e)};" for t, e in temps]
    for target, expr in zip(targets, reduced):
        declare = "" if "[" in target else "const "
        lines.append(f"{declare}{target} = {_printed(expr)};")
    return lines


def _solve_lines(mass, rhs: list[str], out: str, mapping, prefix) -> list[str]:
    """Lines that solve ``mass out = rhs`` (``mass`` symmetric positive definite)."""
    n = len(rhs)
    if n == 1:
        return _assignments(["m00"], [mass[0, 0]], mapping, prefix) + [
            f"{out}[0] = {rhs[0]} / m00;"]
    if n == 2:
        return _assignments(["m00", "m01", "m11"], [mass[0, 0], mass[0, 1], mass[1, 1]],
                            mapping, prefix) + [
            "const det = m00 * m11 - m01 * m01;",
            f"{out}[0] = (m11 * {rhs[0]} - m01 * {rhs[1]}) / det;",
            f"{out}[1] = (m00 * {rhs[1]} - m01 * {rhs[0]}) / det;",
        ]
    lines = [f"const mass = new Float64Array({n * n});",
             f"const rhs = [{', '.join(rhs)}];"]
    lines += _assignments([f"mass[{i * n + j}]" for i in range(n) for j in range(n)],
                          list(mass), mapping, prefix)
    return lines + [f"solveSymmetric(mass, rhs, {out}, {n});"]


# Cholesky's factorisation and two substitutions, for more than two coordinates (the kernels'
# ``solve_spd``, in JavaScript).
_SOLVE_SYMMETRIC = """
// Solve mass out = rhs for a symmetric positive-definite mass (n by n, row-major, overwritten).
function solveSymmetric(mass, rhs, out, n) {
  for (let j = 0; j < n; j++) {
    let d = mass[j * n + j];
    for (let k = 0; k < j; k++) d -= mass[j * n + k] * mass[j * n + k];
    d = Math.sqrt(d);
    mass[j * n + j] = d;
    for (let i = j + 1; i < n; i++) {
      let s = mass[i * n + j];
      for (let k = 0; k < j; k++) s -= mass[i * n + k] * mass[j * n + k];
      mass[i * n + j] = s / d;
    }
  }
  for (let i = 0; i < n; i++) {
    let s = rhs[i];
    for (let k = 0; k < i; k++) s -= mass[i * n + k] * out[k];
    out[i] = s / mass[i * n + i];
  }
  for (let i = n - 1; i >= 0; i--) {
    let s = out[i];
    for (let k = i + 1; k < n; k++) s -= mass[k * n + i] * out[k];
    out[i] = s / mass[i * n + i];
  }
}
"""


def _function(name: str, arguments: str, comment: str, lines: list[str]) -> str:
    body = "\n".join("  " + line for line in lines)
    return f"\n// {comment}\nexport function {name}({arguments}) {{\n{body}\n}}\n"


def _points(system) -> list:
    """The positions ``(x, y)`` or ``(x, y, z)`` of the system's points (a chain's bobs)."""
    return list(system.positions) if isinstance(system, Chain) else list(system.points)


def _dimensions(system) -> int:
    """2 for a chain or a planar system, 3 for points in space."""
    return 2 if isinstance(system, Chain) else system.dimensions


def _describe(system) -> str:
    if isinstance(system, Chain):
        from .kernels import chain_description

        return chain_description(system.n, system.forced)
    return system.name


def _body(system) -> str:
    """The module's text after its first line (which names the key)."""
    n = system.n
    mapping = _symbols(system)
    mass = system.mass_matrix
    offset = [sp.sympify(b) for b in system.momentum_offset]
    has_offset = any(b != 0 for b in offset)
    rates = list(system.dlagrangian_dq)
    if system.forced:
        rates = [r + f for r, f in zip(rates, system.generalized_forces)]
    points = _points(system)
    used = [*mass, *offset, *rates, system.kinetic, system.potential,
            *(c for point in points for c in point)]
    missing = unprintable_functions(used)
    if missing:
        raise ValueError(
            f"the equations of {_describe(system)} use {', '.join(missing)}, which JavaScript's "
            "Math does not have, so the browser cannot run this model (it runs in the kernel)")

    unpack = [f"const th{i} = q[{i}];" for i in range(n)]
    parameters = [f"const par{i} = params[{i}];" for i in range(len(system.parameters))]
    hamilton = unpack + parameters
    if has_offset:
        shifted = [f"r{i}" for i in range(n)]
        hamilton += _assignments(shifted, [sp.Symbol(f"p[{i}]") - b
                                           for i, b in enumerate(offset)], mapping, "e")
    else:
        shifted = [f"p[{i}]" for i in range(n)]
    hamilton += _solve_lines(mass, shifted, "dq", mapping, "a")
    hamilton += [f"const w{i} = dq[{i}];" for i in range(n)]
    hamilton += _assignments([f"dp[{i}]" for i in range(n)], rates, mapping, "b")

    velocities = [f"const w{i} = omega[{i}];" for i in range(n)]
    momenta = unpack + velocities + parameters + _assignments(
        [f"p[{i}]" for i in range(n)], list(mass * system.omega + sp.Matrix(offset)), mapping,
        "c")
    energies = unpack + velocities + parameters + _assignments(
        ["out[0]", "out[1]"], [system.kinetic, system.potential], mapping, "d")
    width = _dimensions(system)
    places = unpack + parameters + _assignments(
        [f"out[{width * k + j}]" for k in range(len(points)) for j in range(width)],
        [c for point in points for c in point], mapping, "x")
    names = ", ".join(f'"{s}"' for s in system.parameters)
    dq_rule = "M(q, t)^-1 (p - b(q, t))" if has_offset else "M(q)^-1 p"
    forces = " + Q" if system.forced else ""
    text = (
        f"// {_describe(system)[0].upper()}{_describe(system)[1:]}: its equations printed "
        "from SymPy; generated, do not edit.\n"
        f"// State order q = ({', '.join(map(str, system.q))}); params = "
        f"({', '.join(map(str, system.parameters))}).\n\n"
        f'export const NAME = "{_describe(system)}";\n'
        f"export const COORDINATES = {n};\n"
        f"export const PARAMETERS = [{names}];\n"
        f"export const POINTS = {len(points)};\n"
        f"export const DIMENSIONS = {width};\n"
    )
    if n > 2:
        text += _SOLVE_SYMMETRIC
    text += _function("hamilton", "t, q, p, params, dq, dp",
                      f"dq = {dq_rule} (= dH/dp); dp = dL/dq{forces} at omega = dq "
                      f"(= -dH/dq{forces}).", hamilton)
    text += _function("momenta", "t, q, omega, params, p", "p = M omega + b.", momenta)
    text += _function("energies", "t, q, omega, params, out",
                      "out[0] = T (kinetic), out[1] = V (potential).", energies)
    text += _function("positions", "t, q, params, out",
                      f"out[{width} k ...] = {', '.join('xyz'[:width])} of point k.", places)
    return text


@dataclass(frozen=True)
class BrowserModule:
    """A generated ES module: ``name`` (``<stem>_<key>.js``), ``key`` and ``source``."""

    stem: str
    key: str
    source: str

    @property
    def name(self) -> str:
        return f"{self.stem}_{self.key}.js"


def browser_module_source(system) -> str:
    """The ES module of ``system`` (a :class:`~pendulum_lab.symbolic.mechanics.Chain` or a
    :class:`~pendulum_lab.symbolic.systems.MechanicalSystem`), its key on the first line."""
    body = _body(system)
    key = text_key(body, __name__)
    return f"// Generated by {__name__} (key {key}).\n{body}"


@functools.cache
def browser_module(system, stem: str) -> BrowserModule:
    """:func:`browser_module_source` of ``system`` as a :class:`BrowserModule` named ``stem``
    and its key; made once per system and process."""
    source = browser_module_source(system)
    key = source.split("key ", 1)[1].split(")", 1)[0]
    return BrowserModule(stem, key, source)
