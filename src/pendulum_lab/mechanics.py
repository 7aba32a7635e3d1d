"""Symbolic mechanics of a planar chain of pendulums (SymPy only).

This module knows pendulums and nothing about integrators. It derives, for a
chain of ``n`` point masses on massless rigid rods::

      pivot
        o
         \\  theta_1        angles are absolute and measured from the
          \\                downward vertical, counter-clockwise positive
           (m_1)
             |  theta_2
             |
           (m_2)
              ...

the kinetic and potential energies from the Cartesian bob positions, the
Lagrangian, the Euler-Lagrange equations in the form ``M(q) q'' = F(q, q')``,
the canonical momenta ``p = M(q) q'``, the Hamiltonian by Legendre transform,
Hamilton's equations, and the equilibria with their Jacobians.

A *forced* chain (``Chain(n, forced=True)``) also has generalized forces
``Q`` that are not derived from a potential: a viscous damping torque at every
joint, from Rayleigh's dissipation function
``R = 1/2 sum_i c_i (omega_i - omega_(i-1))^2`` (``omega_0 = 0``: the pivot),
and a periodic drive torque ``A cos(Omega t)`` at the pivot, on the first
link. They enter the Euler-Lagrange equations as ``M q'' = F + Q`` with
``Q = -dR/domega + (A cos(Omega t), 0, ..., 0)``; with absolute angles the
damping part is ``-C omega`` with ``C`` tridiagonal. The conservative chain
is the special case ``c_i = A = 0``; it is derived separately so that its
expressions carry no zero terms.

Masses, lengths, ``g`` and the force parameters stay symbolic. Nothing here inverts ``M``
symbolically unless asked to (:attr:`Chain.hamiltonian` does, lazily): the
numeric layer solves ``M x = b`` numerically, as PyDy's code generator does.

Notes
-----
State order everywhere: ``q = (theta_1, ..., theta_n)``,
``omega = (omega_1, ..., omega_n)`` with ``omega_i = d theta_i / dt``, and
``p = (p_1, ..., p_n)``. For ``n = 1`` the symbols carry no index
(``theta``, ``omega``, ``p``, ``m``, ``l``, ``c``). Parameters, in the order
the numeric layers pass them: ``m_1..m_n, l_1..l_n, g``, then for a forced
chain ``c_1..c_n, A, Omega``.

References
----------
.. [G] H. Goldstein, C. Poole, J. Safko, *Classical Mechanics*, 3rd ed.,
   Addison-Wesley 2002, Sect. 1.5 (generalized forces, Rayleigh's
   dissipation function).
"""

from __future__ import annotations

import functools
import itertools
from dataclasses import dataclass

import sympy as sp
from sympy.simplify.fu import TR10i

__all__ = ["Chain", "Equilibrium", "derive_chain", "is_identically_zero"]


def _names(base: str, n: int) -> list[str]:
    return [base] if n == 1 else [f"{base}_{i}" for i in range(1, n + 1)]


@dataclass(frozen=True)
class Equilibrium:
    """An equilibrium ``(q*, omega* = 0)`` of the chain.

    Attributes
    ----------
    name : str
        ``"down"``/``"up"`` for each link, joined by ``-`` (``"down-up"``).
    angles : tuple of sympy.Expr
        ``q*``, each entry 0 or pi.
    jacobian : sympy.Matrix, shape (2n, 2n)
        Jacobian of ``(theta', omega')`` with respect to ``(theta, omega)``.
    stiffness_ratio : sympy.Matrix, shape (n, n)
        ``M^-1 dF/dq`` at the equilibrium: the eigenvalues of the Jacobian are
        the square roots of its eigenvalues.
    """

    name: str
    angles: tuple
    jacobian: sp.Matrix
    stiffness_ratio: sp.Matrix

    def eigenvalues(self, subs: dict | None = None) -> list:
        """Eigenvalues of the Jacobian, with multiplicity.

        Parameters
        ----------
        subs : dict, optional
            Values for some or all parameters; without it the eigenvalues are
            symbolic (practical for ``n <= 2``).
        """
        k = self.stiffness_ratio if subs is None else self.stiffness_ratio.subs(subs)
        values = []
        for mu, mult in k.eigenvals().items():
            root = sp.sqrt(mu)
            values += [root, -root] * mult
        return values

    def classify(self, subs: dict) -> str:
        """``"center"``, ``"saddle"`` or ``"saddle-center"`` for numeric parameters.

        Each eigenvalue ``mu`` of ``M^-1 dF/dq`` gives a pair ``+-sqrt(mu)``: an
        oscillation (``mu < 0``) or a hyperbolic, unstable direction (``mu > 0``).
        """
        ratio = self.stiffness_ratio.subs(subs).evalf()
        mus = [complex(mu) for mu in ratio.eigenvals(multiple=True)]
        if any(abs(mu.imag) > 1e-12 * max(1.0, abs(mu)) or mu.real == 0 for mu in mus):
            raise ValueError(f"degenerate equilibrium {self.name}: eigenvalues {mus}")
        unstable = sum(mu.real > 0 for mu in mus)
        if unstable == 0:
            return "center"
        return "saddle" if unstable == len(mus) else "saddle-center"


class Chain:
    """Symbolic equations of a planar chain of ``n`` pendulums.

    Parameters
    ----------
    n : int
        Number of links, ``n >= 1``.
    forced : bool
        Add the generalized forces: damping at each joint and a drive at the
        pivot (see the module docstring).

    Attributes
    ----------
    parameters : tuple of sympy.Symbol
        ``(m_1..m_n, l_1..l_n, g)``, then ``(c_1..c_n, A, Omega)`` if forced.
    generalized_forces : sympy.Matrix, shape (n, 1)
        ``Q(omega, t)``, zero for the conservative chain.
    forcing : sympy.Matrix, shape (n, 1)
        The right-hand side of ``M(q) alpha = forcing``, ``Q`` included.

    Examples
    --------
    >>> chain = derive_chain(1)
    >>> chain.mass_matrix
    Matrix([[l**2*m]])
    >>> chain.forcing
    Matrix([[-g*l*m*sin(theta)]])
    >>> derive_chain(1, forced=True).forcing
    Matrix([[A*cos(Omega*t) - c*omega - g*l*m*sin(theta)]])
    """

    def __init__(self, n: int, forced: bool = False):
        if isinstance(n, bool) or not isinstance(n, int):
            raise TypeError(f"`n` must be an integer >= 1, got {n!r}")
        if n < 1:
            raise ValueError(f"`n` must be an integer >= 1, got {n}")
        if not isinstance(forced, bool):
            raise TypeError(f"`forced` must be True or False, got {forced!r}")
        self.n = n
        self.forced = forced
        self.q = sp.Matrix(sp.symbols(_names(r"theta", n), real=True))
        self.omega = sp.Matrix(sp.symbols(_names(r"omega", n), real=True))
        self.omega_dot = sp.Matrix(sp.symbols(_names(r"alpha", n), real=True))
        self.p = sp.Matrix(sp.symbols(_names("p", n), real=True))
        self.masses = sp.Matrix(sp.symbols(_names("m", n), positive=True))
        self.lengths = sp.Matrix(sp.symbols(_names("l", n), positive=True))
        self.g = sp.Symbol("g", positive=True)
        self.t = sp.Symbol("t", real=True)
        self.parameters = (*self.masses, *self.lengths, self.g)

        # Cartesian bob positions, pivot at the origin, y pointing up.
        x, y, xs, ys = sp.Integer(0), sp.Integer(0), [], []
        for qi, li in zip(self.q, self.lengths):
            x, y = x + li * sp.sin(qi), y - li * sp.cos(qi)
            xs.append(x)
            ys.append(y)
        self.positions = [(xi, yi) for xi, yi in zip(xs, ys)]

        # T = 1/2 sum_i m_i |v_i|^2 with v_i = J_i omega, so T = 1/2 omega^T M omega
        # with M = sum_i m_i J_i^T J_i. Entry (j, k) is a short sum of
        # cos(theta_j) cos(theta_k) + sin(theta_j) sin(theta_k) terms: the targeted
        # rule TR10i folds it into cos(theta_j - theta_k) (sin^2 + cos^2 = 1 on the
        # diagonal). Nothing large is ever simplified.
        jac = [sp.Matrix([[xi], [yi]]).jacobian(self.q) for xi, yi in self.positions]
        mass = sp.zeros(n, n)
        for j, k in itertools.product(range(n), repeat=2):
            if k < j:
                mass[j, k] = mass[k, j]
                continue
            entry = sum(m * (J[:, j].T * J[:, k])[0, 0] for m, J in zip(self.masses, jac))
            entry = TR10i(sp.factor_terms(sp.expand(entry)))
            entry = sp.expand(entry.subs(sp.sin(self.q[j]) ** 2, 1 - sp.cos(self.q[j]) ** 2))
            mass[j, k] = sp.factor_terms(entry)
        self.mass_matrix = mass
        self.kinetic = sp.expand((self.omega.T * mass * self.omega)[0, 0] / 2)
        self.potential = sp.expand(self.g * sum(m * yi for m, yi in zip(self.masses, ys)))
        self.lagrangian = self.kinetic - self.potential

        # Euler-Lagrange: d/dt dL/domega_i = dL/dq_i with
        # d/dt dL/domega_i = sum_j d2L/domega_i dq_j omega_j + sum_j M_ij omega_j'.
        dl_dq = sp.Matrix([self.lagrangian.diff(qi) for qi in self.q])
        dl_dw = sp.Matrix([self.lagrangian.diff(wi) for wi in self.omega])
        self.dlagrangian_dq = dl_dq
        self.momenta = mass * self.omega
        conservative = sp.expand(dl_dq - dl_dw.jacobian(self.q) * self.omega)

        # Generalized forces. Joint i joins link i-1 (the pivot for i = 1) to
        # link i; its damping torque -c_i (omega_i - omega_(i-1)) acts on link i
        # and, reversed, on link i-1: Q = -dR/domega.
        self.dissipation = sp.Integer(0)
        self.generalized_forces = sp.zeros(n, 1)
        if forced:
            self.damping = sp.Matrix(sp.symbols(_names("c", n), nonnegative=True))
            self.drive_amplitude = sp.Symbol("A", real=True)
            self.drive_frequency = sp.Symbol("Omega", positive=True)
            self.parameters += (*self.damping, self.drive_amplitude, self.drive_frequency)
            relative = [self.omega[i] - (self.omega[i - 1] if i else 0) for i in range(n)]
            self.dissipation = sum(c * w**2 for c, w in zip(self.damping, relative)) / 2
            drive = sp.zeros(n, 1)
            drive[0] = self.drive_amplitude * sp.cos(self.drive_frequency * self.t)
            self.generalized_forces = sp.expand(
                drive - sp.Matrix([self.dissipation.diff(w) for w in self.omega])
            )
        self.forcing = sp.expand(conservative + self.generalized_forces)

    @property
    def damping_matrix(self) -> sp.Matrix:
        """``C = d^2 R / domega^2``, shape (n, n): the damping force is ``-C omega``.

        Tridiagonal, ``C_ii = c_i + c_(i+1)``, ``C_(i,i+1) = -c_(i+1)``; zero for
        the conservative chain.
        """
        return sp.hessian(self.dissipation, list(self.omega)) if self.forced else sp.zeros(self.n)

    # ---- derived on demand (these can be slow for n >= 3) ---------------------
    @property
    def euler_lagrange(self) -> sp.Eq:
        """The equations of motion ``M(q) alpha = F(q, omega) (+ Q)``, ``alpha = omega'``."""
        return sp.Eq(self.mass_matrix * self.omega_dot, self.forcing)

    @functools.cached_property
    def accelerations(self) -> sp.Matrix:
        """``omega' = M^-1 F`` in closed form (cheap for ``n <= 2``, large beyond)."""
        return self.mass_matrix.LUsolve(self.forcing).applyfunc(sp.cancel)

    @functools.cached_property
    def inverse_mass_matrix(self) -> sp.Matrix:
        """``M(q)^-1``, by cofactors; only requested for display and checks.

        Simplified for ``n <= 2`` only: beyond, simplification costs minutes
        and the numeric code never needs this matrix.
        """
        inv = self.mass_matrix.adjugate() / self.mass_matrix.det()
        if self.n > 2:
            return inv
        return inv.applyfunc(lambda e: sp.factor(sp.trigsimp(e)))

    @functools.cached_property
    def hamiltonian(self) -> sp.Expr:
        """``H(q, p) = 1/2 p^T M(q)^-1 p + V(q)``, the Legendre transform of L.

        For a forced chain this is still the mechanical energy; the forces do
        work on it at the rate ``omega . Q``.
        """
        return (self.p.T * self.inverse_mass_matrix * self.p)[0, 0] / 2 + self.potential

    @functools.cached_property
    def hamilton_equations(self) -> tuple[sp.Matrix, sp.Matrix]:
        """``(dq/dt, dp/dt) = (dH/dp, -dH/dq + Q)`` as two column matrices.

        ``Q`` (zero unless forced) is written in ``p`` through ``omega = dH/dp``.
        """
        h = self.hamiltonian
        dq = sp.Matrix([h.diff(pi) for pi in self.p])
        forces = self.generalized_forces.xreplace(dict(zip(self.omega, dq)))
        return dq, sp.Matrix([-h.diff(qi) for qi in self.q]) + forces

    def legendre_transform(self) -> sp.Expr:
        """``omega . p - L`` written in ``(q, omega)``; it equals ``T + V``."""
        return sp.expand((self.omega.T * self.momenta)[0, 0] - self.lagrangian)

    # ---- equilibria --------------------------------------------------------
    @functools.cached_property
    def equilibria(self) -> list[Equilibrium]:
        """All ``2**n`` equilibria (each link straight down or straight up).

        With ``omega = 0`` the forcing vanishes exactly when every
        ``sin(theta_i) = 0``; the Jacobian there is ``[[0, I], [M^-1 dF/dq, 0]]``
        because ``F`` is quadratic in ``omega`` and zero at the equilibrium.
        """
        if self.forced:
            raise ValueError(
                "the equilibria are those of the unforced chain, derive_chain(n): with a drive "
                "there are none, and damping only changes their Jacobians"
            )
        n = self.n
        result = []
        for ups in itertools.product((False, True), repeat=n):
            angles = tuple(sp.pi if up else sp.Integer(0) for up in ups)
            at = dict(zip(self.q, angles)) | {w: 0 for w in self.omega}
            mass = self.mass_matrix.subs(at)
            stiffness = self.forcing.jacobian(self.q).subs(at)
            ratio = mass.LUsolve(stiffness).applyfunc(sp.simplify)
            jacobian = sp.BlockMatrix([[sp.zeros(n), sp.eye(n)], [ratio, sp.zeros(n)]])
            name = "-".join("up" if up else "down" for up in ups)
            result.append(Equilibrium(name, angles, sp.Matrix(jacobian), ratio))
        return result

    def equilibrium(self, name: str) -> Equilibrium:
        """The equilibrium called ``name`` (``"down"``, ``"up-down"``, ...).

        Examples
        --------
        >>> derive_chain(2).equilibrium("down-up").angles
        (0, pi)
        """
        names = [eq.name for eq in self.equilibria]
        if name not in names:
            raise ValueError(f"`equilibrium` must be one of {names}, got {name!r}")
        return self.equilibria[names.index(name)]

    def jacobian(self) -> sp.Matrix:
        """Jacobian of ``(omega, M^-1 F)`` with respect to ``(theta, omega)``.

        Uses the closed-form accelerations, so it is meant for ``n <= 2``.
        """
        rhs = sp.Matrix([*self.omega, *self.accelerations])
        return rhs.jacobian(sp.Matrix([*self.q, *self.omega]))

    def __repr__(self) -> str:
        return f"Chain(n={self.n}, forced=True)" if self.forced else f"Chain(n={self.n})"


def is_identically_zero(expr: sp.Expr) -> bool:
    """Decide whether a trigonometric-rational expression is zero for all arguments.

    ``simplify`` can fail to recognise zero. This check is exact: multiple
    angles are expanded, each ``sin(x)``, ``cos(x)`` becomes a variable
    ``s_x``, ``c_x``, and the numerator is reduced modulo ``s_x^2 + c_x^2 - 1``
    (a Groebner-basis remainder, which is unique).

    Examples
    --------
    >>> x, y = sp.symbols("x y")
    >>> is_identically_zero(sp.cos(x - y) - sp.cos(x) * sp.cos(y) - sp.sin(x) * sp.sin(y))
    True
    >>> is_identically_zero(sp.cos(2 * x) - sp.cos(x) ** 2)
    False
    """
    expr = sp.expand_trig(sp.sympify(expr))
    angles = sorted({f.args[0] for f in expr.atoms(sp.sin, sp.cos)}, key=sp.default_sort_key)
    sines = sp.symbols(f"s0:{len(angles)}")
    cosines = sp.symbols(f"c0:{len(angles)}")
    subs = {sp.sin(a): s for a, s in zip(angles, sines)}
    subs |= {sp.cos(a): c for a, c in zip(angles, cosines)}
    numerator = sp.expand(sp.numer(sp.together(expr.xreplace(subs))))
    if numerator == 0:
        return True
    if not angles:
        return False
    circle = [s**2 + c**2 - 1 for s, c in zip(sines, cosines)]
    _, remainder = sp.reduced(numerator, circle, *sines, *cosines)
    return sp.expand(remainder) == 0


@functools.cache
def _derive(n: int, forced: bool) -> Chain:
    return Chain(n, forced)


def derive_chain(n: int, forced: bool = False) -> Chain:
    """Derive (once per ``n`` and ``forced``, then cached) the symbolic equations of ``n`` links."""
    if isinstance(n, bool) or not isinstance(n, int):
        raise TypeError(f"`n` must be an integer >= 1, got {n!r}")
    if not isinstance(forced, bool):
        raise TypeError(f"`forced` must be True or False, got {forced!r}")
    return _derive(n, forced)
