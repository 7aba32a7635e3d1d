"""Symbolic mechanics of a planar chain of pendulums (SymPy only).

This module knows pendulums and nothing about integrators. It gives, for a
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

the kinetic and potential energies, the Lagrangian, the Euler-Lagrange
equations in the form ``M(q) q'' = F(q, q')``, the canonical momenta
``p = M(q) q'``, the Hamiltonian by Legendre transform, Hamilton's equations,
and the equilibria with their Jacobians.

The equations have a closed structure. Bob ``k`` sits at
``(sum_(j<=k) l_j sin(theta_j), -sum_(j<=k) l_j cos(theta_j))``, so with the
*tail masses* ``mu_i = m_i + ... + m_n`` (everything at or below bob ``i``):

``M_ij = mu_max(i,j) l_i l_j cos(theta_i - theta_j)``,
``V = -g sum_i mu_i l_i cos(theta_i)``,
``dL/dtheta_i = -omega_i sum_j mu_max(i,j) l_i l_j sin(theta_i - theta_j) omega_j
- g mu_i l_i sin(theta_i)``,
``F_i = -sum_j mu_max(i,j) l_i l_j sin(theta_i - theta_j) omega_j^2 - g mu_i l_i sin(theta_i)``.

(Differentiating ``T = 1/2 sum_ij M_ij omega_i omega_j``: ``dT/dtheta_i`` and
the ``d/dt`` of ``dT/domega_i`` share the term in ``omega_i omega_j``, which
cancels in ``F``.) :class:`Chain` builds its matrices entry by entry from
these formulas, in ``O(n^2)`` SymPy operations;
:func:`lagrangian_derivation` derives the same equations the long way, by
expanding the Lagrangian of the bob positions, and the tests assert that the
two agree exactly. For short chains the entries are expanded into the very
terms the long way gives.

A *forced* chain (``Chain(n, forced=True)``) also has generalized forces
``Q`` that are not derived from a potential: a viscous damping torque at every
joint, from Rayleigh's dissipation function
``R = 1/2 sum_i c_i (omega_i - omega_(i-1))^2`` (``omega_0 = 0``: the pivot),
and a periodic drive torque ``A cos(Omega t)`` at the pivot, on the first
link. They enter the Euler-Lagrange equations as ``M q'' = F + Q`` with
``Q = -dR/domega + (A cos(Omega t), 0, ..., 0)``; with absolute angles the
damping part is ``-C omega`` with ``C`` tridiagonal. The conservative chain
is the special case ``c_i = A = 0``; it is built separately so that its
expressions carry no zero terms.

Masses, lengths, ``g`` and the force parameters stay symbolic. Nothing here
inverts ``M`` symbolically unless asked to (:attr:`Chain.hamiltonian` does,
lazily): the numeric layer solves ``M x = b`` numerically, as PyDy's code
generator does. What grows faster than ``n^2`` (a symbolic inverse, all
``2**n`` equilibria, the expanded Lagrangian) is refused for long chains with
a message that says the limit and why (:data:`LIMITS`).

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

__all__ = [
    "LIMITS",
    "Chain",
    "Equilibrium",
    "LagrangianDerivation",
    "derive_chain",
    "hamilton_equations_of",
    "is_identically_zero",
    "lagrangian_derivation",
    "legendre_transform_of",
]

#: Chains up to this many links get their entries expanded into the terms the
#: Lagrangian derivation gives (the forms the course shows, counts and prints
#: kernels from; cheap at this size, docs/design/long-chains.md); expanded, an entry
#: of a longer chain's forcing would hold about n^2 / 2 terms instead of n.
EXPANDED_MAX_LINKS = 10
#: Building the symbolic equations shows a progress bar from this many links.
PROGRESS_LINKS = 30
#: The parts of a chain refused beyond a number of links: ``{part: (limit, why)}``.
#: Times measured on a 2-core machine; numeric models (``pl.n_pendulum``) need
#: none of these parts.
LIMITS = {
    "the symbolic equations": (
        100, "their matrices hold n^2 entries, built one by one (about 20 s for 100 links); "
             "numeric models (pl.n_pendulum) do not need them"),
    "the Lagrangian derivation": (
        6, "it expands the Lagrangian into about n^3 / 3 terms (seconds per link from 6 on); "
           "Chain builds the same equations from their closed form"),
    "the closed-form accelerations": (
        2, "solving M alpha = F symbolically did not finish in 10 minutes for 3 links; "
           "PendulumModel.accelerations evaluates them numerically for any chain"),
    "the closed-form Jacobian": (
        2, "it differentiates the closed-form accelerations (refused beyond 2 links); "
           "PendulumModel.jacobian evaluates it numerically for any chain"),
    "the closed-form inverse mass matrix": (
        3, "its determinant has n! terms (over a minute for 4 links); the numeric layer "
           "solves M x = b instead"),
    "the list of all equilibria": (
        8, "there are 2**n of them; Chain.equilibrium(name) builds any one"),
}


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

    The equations are built entry by entry from their closed form (see the
    module docstring), on first access of each attribute; constructing a
    ``Chain`` only makes its symbols. :func:`lagrangian_derivation` derives
    the same equations the long way, from the bob positions, as a check.

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
    tail_masses : tuple of sympy.Expr
        ``mu_i = m_i + ... + m_n``, the mass at or below bob ``i``.
    mass_matrix : sympy.Matrix, shape (n, n)
    kinetic, potential, lagrangian : sympy.Expr
    dlagrangian_dq : sympy.Matrix, shape (n, 1)
        ``dL/dq``: the rate of change of the momenta, ``-dH/dq``.
    momenta : sympy.Matrix, shape (n, 1)
        ``p = M(q) omega``.
    generalized_forces : sympy.Matrix, shape (n, 1)
        ``Q(omega, t)``, zero for the conservative chain.
    forcing : sympy.Matrix, shape (n, 1)
        The right-hand side of ``M(q) alpha = forcing``, ``Q`` included.

    Raises
    ------
    ValueError
        On first access of a part that is refused for this ``n`` (the message
        says the limit and why; see :data:`LIMITS`).

    Examples
    --------
    >>> chain = derive_chain(1)
    >>> chain.mass_matrix
    Matrix([[l**2*m]])
    >>> chain.forcing
    Matrix([[-g*l*m*sin(theta)]])
    >>> derive_chain(1, forced=True).forcing
    Matrix([[A*cos(Omega*t) - c*omega - g*l*m*sin(theta)]])
    >>> derive_chain(3).mass_matrix[0, 2]
    l_1*l_3*m_3*cos(theta_1 - theta_3)
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
        if forced:
            self.damping = sp.Matrix(sp.symbols(_names("c", n), nonnegative=True))
            self.drive_amplitude = sp.Symbol("A", real=True)
            self.drive_frequency = sp.Symbol("Omega", positive=True)
            self.parameters += (*self.damping, self.drive_amplitude, self.drive_frequency)

    # ---- the closed form, entry by entry ----------------------------------
    def _require(self, part: str) -> None:
        """Refuse ``part`` (a key of :data:`LIMITS`) beyond its number of links."""
        limit, why = LIMITS[part]
        if self.n > limit:
            raise ValueError(f"{part[0].upper()}{part[1:]} of a chain of {self.n} links: refused "
                             f"beyond {limit} links, because {why}")

    def _rows(self, label: str):
        """``range(n)``, with a progress bar for chains long enough to take seconds."""
        if self.n < PROGRESS_LINKS:
            return range(self.n)
        from tqdm.auto import tqdm

        return tqdm(range(self.n), desc=f"{label} of {self.n} links", unit="link",
                    mininterval=0.5)

    def _canonical(self, expr, form=sp.expand):
        """``form(expr)`` for short chains (by default expanded, as the Lagrangian derivation
        gives it); else ``expr`` as built: compact, and quick to make."""
        return form(expr) if self.n <= EXPANDED_MAX_LINKS else expr

    @functools.cached_property
    def tail_masses(self) -> tuple:
        self._require("the symbolic equations")
        return tuple(sp.Add(*self.masses[i:]) for i in range(self.n))

    @functools.cached_property
    def _trig_differences(self) -> dict:
        """``{(i, j): (cos(theta_i - theta_j), sin(theta_i - theta_j))}`` for ``i < j``.

        Made unevaluated, in the sign SymPy's evaluation would choose: the
        difference of the two angles whose first symbol sorts first (what
        ``could_extract_minus_sign`` decides for a difference of two symbols,
        checked by the tests). Evaluating would cost most of the build.
        """
        table = {}
        keys = [sp.default_sort_key(angle) for angle in self.q]
        for i in range(self.n):
            for j in range(i + 1, self.n):
                first, second, sign = (i, j, 1) if keys[i] < keys[j] else (j, i, -1)
                angle = self.q[first] - self.q[second]
                table[i, j] = sp.cos(angle, evaluate=False), sign * sp.sin(angle, evaluate=False)
        return table

    def _cos_difference(self, i: int, j: int):
        return sp.Integer(1) if i == j else self._trig_differences[min(i, j), max(i, j)][0]

    def _sin_difference(self, i: int, j: int):
        """``sin(theta_i - theta_j)``."""
        if i == j:
            return sp.Integer(0)
        sine = self._trig_differences[min(i, j), max(i, j)][1]
        return sine if i < j else -sine

    def _coupling(self, i: int, j: int):
        """``mu_max(i,j) l_i l_j``: the coefficient of entry ``(i, j)`` of ``M``."""
        return sp.Mul(self.tail_masses[max(i, j)], self.lengths[i], self.lengths[j])

    @functools.cached_property
    def mass_matrix(self) -> sp.Matrix:
        """``M_ij = mu_max(i,j) l_i l_j cos(theta_i - theta_j)``, shape (n, n)."""
        n = self.n
        mass = sp.zeros(n, n)
        for i in self._rows("mass matrix"):
            for j in range(i, n):
                mass[i, j] = mass[j, i] = sp.Mul(self._coupling(i, j), self._cos_difference(i, j))
        return mass

    @functools.cached_property
    def positions(self) -> list:
        """Cartesian bob positions ``[(x_i, y_i)]``, pivot at the origin, ``y`` pointing up."""
        self._require("the symbolic equations")
        xs = itertools.accumulate(li * sp.sin(qi) for qi, li in zip(self.q, self.lengths))
        ys = itertools.accumulate(-li * sp.cos(qi) for qi, li in zip(self.q, self.lengths))
        return list(zip(xs, ys))

    @functools.cached_property
    def potential(self) -> sp.Expr:
        """``V = -g sum_i mu_i l_i cos(theta_i)``, zero at the pivot's height."""
        return self._canonical(sp.Add(*(
            -self.g * mu * li * sp.cos(qi)
            for mu, li, qi in zip(self.tail_masses, self.lengths, self.q))))

    @functools.cached_property
    def kinetic(self) -> sp.Expr:
        """``T = 1/2 omega^T M omega``."""
        mass, w = self.mass_matrix, self.omega
        terms = [mass[i, i] * w[i] ** 2 / 2 for i in range(self.n)]
        terms += [mass[i, j] * w[i] * w[j] for i in range(self.n) for j in range(i + 1, self.n)]
        return self._canonical(sp.Add(*terms))

    @functools.cached_property
    def lagrangian(self) -> sp.Expr:
        return self.kinetic - self.potential

    def _link_sum(self, i: int, weights) -> sp.Expr:
        """``-sum_j mu_max(i,j) l_i l_j sin(theta_i - theta_j) weights_j
        - g mu_i l_i sin(theta_i)``."""
        terms = [-self._coupling(i, j) * self._sin_difference(i, j) * weights[j]
                 for j in range(self.n) if j != i]
        terms.append(-self.g * self.tail_masses[i] * self.lengths[i] * sp.sin(self.q[i]))
        return sp.Add(*terms)

    @functools.cached_property
    def dlagrangian_dq(self) -> sp.Matrix:
        """``dL/dtheta_i = -omega_i sum_j mu_max(i,j) l_i l_j sin(theta_i - theta_j) omega_j
        - g mu_i l_i sin(theta_i)``."""
        w = self.omega
        return sp.Matrix([self._canonical(self._link_sum(i, [w[i] * wj for wj in w]))
                          for i in self._rows("dL/dq")])

    @property
    def momenta(self) -> sp.Matrix:
        """``p = M(q) omega``."""
        return self.mass_matrix * self.omega

    @property
    def momentum_offset(self) -> sp.Matrix:
        """``b`` of ``p = M omega + b``: zero, the pivot is fixed (the attribute of every system
        the code generator reads, :class:`~pendulum_lab.symbolic.systems.MechanicalSystem`)."""
        return sp.zeros(self.n, 1)

    @functools.cached_property
    def dissipation(self) -> sp.Expr:
        """Rayleigh's ``R = 1/2 sum_i c_i (omega_i - omega_(i-1))^2``; zero unless forced."""
        if not self.forced:
            return sp.Integer(0)
        relative = [self.omega[i] - (self.omega[i - 1] if i else 0) for i in range(self.n)]
        return sum(c * w**2 for c, w in zip(self.damping, relative)) / 2

    @functools.cached_property
    def generalized_forces(self) -> sp.Matrix:
        """``Q = -C omega + (A cos(Omega t), 0, ..., 0)``; zero unless forced.

        Joint ``i`` joins link ``i-1`` (the pivot for ``i = 1``) to link ``i``;
        its damping torque ``-c_i (omega_i - omega_(i-1))`` acts on link ``i``
        and, reversed, on link ``i-1``: entry ``i`` is
        ``-c_i (omega_i - omega_(i-1)) + c_(i+1) (omega_(i+1) - omega_i)``
        (:attr:`damping_matrix`), which is ``-dR/domega_i`` (Rayleigh's
        :attr:`dissipation`, as :func:`lagrangian_derivation` computes it).
        """
        if not self.forced:
            return sp.zeros(self.n, 1)
        forces = -self.damping_matrix * self.omega
        forces[0] += self.drive_amplitude * sp.cos(self.drive_frequency * self.t)
        return forces.applyfunc(sp.expand)

    @functools.cached_property
    def forcing(self) -> sp.Matrix:
        """``F_i + Q_i``: ``F_i = -sum_j mu_max(i,j) l_i l_j sin(theta_i - theta_j) omega_j^2
        - g mu_i l_i sin(theta_i)``."""
        squares = [w**2 for w in self.omega]
        forces = self.generalized_forces
        return sp.Matrix([self._canonical(self._link_sum(i, squares) + forces[i])
                          for i in self._rows("forcing")])

    @functools.cached_property
    def damping_matrix(self) -> sp.Matrix:
        """``C = d^2 R / domega^2``, shape (n, n): the damping force is ``-C omega``.

        Tridiagonal, ``C_ii = c_i + c_(i+1)`` (no ``c_(n+1)``),
        ``C_(i,i+1) = C_(i+1,i) = -c_(i+1)``; zero for the conservative chain.
        """
        n = self.n
        damping = sp.zeros(n, n)
        if not self.forced:
            return damping
        c = self.damping
        for i in range(n):
            damping[i, i] = c[i] + (c[i + 1] if i + 1 < n else 0)
            if i + 1 < n:
                damping[i, i + 1] = damping[i + 1, i] = -c[i + 1]
        return damping

    # ---- derived on demand (these can be slow for n >= 3) ---------------------
    @property
    def euler_lagrange(self) -> sp.Eq:
        """The equations of motion ``M(q) alpha = F(q, omega) (+ Q)``, ``alpha = omega'``."""
        return sp.Eq(self.mass_matrix * self.omega_dot, self.forcing)

    @functools.cached_property
    def accelerations(self) -> sp.Matrix:
        """``omega' = M^-1 F`` in closed form (cheap for ``n <= 2``, refused beyond)."""
        self._require("the closed-form accelerations")
        return self.mass_matrix.LUsolve(self.forcing).applyfunc(sp.cancel)

    @functools.cached_property
    def inverse_mass_matrix(self) -> sp.Matrix:
        """``M(q)^-1``, by cofactors; only requested for display and checks.

        Simplified for ``n <= 2`` only: beyond, simplification costs minutes
        and the numeric code never needs this matrix.
        """
        self._require("the closed-form inverse mass matrix")
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
        return hamilton_equations_of(self)

    def legendre_transform(self) -> sp.Expr:
        """``omega . p - L`` written in ``(q, omega)``; it equals ``T + V``."""
        return legendre_transform_of(self)

    # ---- equilibria --------------------------------------------------------
    @functools.cached_property
    def equilibria(self) -> list[Equilibrium]:
        """All ``2**n`` equilibria (each link straight down or straight up).

        With ``omega = 0`` the forcing vanishes exactly when every
        ``sin(theta_i) = 0``; the Jacobian there is ``[[0, I], [M^-1 dF/dq, 0]]``
        because ``F`` is quadratic in ``omega`` and zero at the equilibrium.
        See :meth:`equilibrium` for one of them.
        """
        self._require("the list of all equilibria")
        return [self._equilibrium(ups) for ups in itertools.product((False, True), repeat=self.n)]

    def _equilibrium(self, ups: tuple) -> Equilibrium:
        """The equilibrium with link ``i`` up where ``ups[i]``, built once per chain."""
        found = self.__dict__.setdefault("_equilibria_found", {})
        if ups not in found:
            found[ups] = self._build_equilibrium(ups)
        return found[ups]

    def _build_equilibrium(self, ups: tuple) -> Equilibrium:
        """The equilibrium with link ``i`` up where ``ups[i]``: ``M^-1 dF/dq`` in closed form.

        There ``M = S Lambda B Lambda S`` with ``S = diag(cos theta_i) = diag(+-1)``,
        ``Lambda = diag(l_i)`` and ``B_ij = mu_max(i,j)``, and
        ``dF/dq = -g diag(mu_i l_i cos theta_i)``. ``B = U diag(m) U^T`` with
        ``U`` the upper triangle of ones, so ``B^-1`` is tridiagonal:
        ``(B^-1)_ii = 1/m_i + 1/m_(i-1)`` (no second term for ``i = 1``),
        ``(B^-1)_(i,i+1) = -1/m_i``. No symbolic solve is needed.
        """
        if self.forced:
            raise ValueError(
                "the equilibria are those of the unforced chain, derive_chain(n): with a drive "
                "there are none, and damping only changes their Jacobians"
            )
        n, m, lengths = self.n, self.masses, self.lengths
        signs = [-1 if up else 1 for up in ups]

        def b_inverse(i, j):
            if i == j:
                return 1 / m[i] + (1 / m[i - 1] if i else 0)
            return -1 / m[min(i, j)] if abs(i - j) == 1 else 0

        ratio = sp.zeros(n, n)
        for i in range(n):
            for j in range(max(0, i - 1), min(n, i + 2)):
                stiffness = -self.g * self.tail_masses[j] * lengths[j] * signs[j]
                inverse_mass = signs[i] * signs[j] * b_inverse(i, j) / (lengths[i] * lengths[j])
                ratio[i, j] = self._canonical(inverse_mass * stiffness, sp.factor)
        jacobian = sp.BlockMatrix([[sp.zeros(n), sp.eye(n)], [ratio, sp.zeros(n)]])
        angles = tuple(sp.pi if up else sp.Integer(0) for up in ups)
        name = "-".join("up" if up else "down" for up in ups)
        return Equilibrium(name, angles, sp.Matrix(jacobian), ratio)

    def equilibrium(self, name: str) -> Equilibrium:
        """The equilibrium called ``name`` (``"down"``, ``"up-down"``, ...).

        Examples
        --------
        >>> derive_chain(2).equilibrium("down-up").angles
        (0, pi)
        """
        words = name.split("-") if isinstance(name, str) else []
        if len(words) != self.n or not set(words) <= {"down", "up"}:
            example = "-".join(["down"] * self.n)
            raise ValueError(f"`equilibrium` must be one of the 2**{self.n} names that call each "
                             f"of the {self.n} links 'down' or 'up', joined by '-' (such as "
                             f"{example!r}), got {name!r}")
        return self._equilibrium(tuple(word == "up" for word in words))

    def jacobian(self) -> sp.Matrix:
        """Jacobian of ``(omega, M^-1 F)`` with respect to ``(theta, omega)``.

        Uses the closed-form accelerations, so it is refused beyond ``n = 2``;
        :meth:`pendulum_lab.PendulumModel.jacobian` evaluates it numerically
        for any chain.
        """
        self._require("the closed-form Jacobian")
        rhs = sp.Matrix([*self.omega, *self.accelerations])
        return rhs.jacobian(sp.Matrix([*self.q, *self.omega]))

    def __repr__(self) -> str:
        return f"Chain(n={self.n}, forced=True)" if self.forced else f"Chain(n={self.n})"


@dataclass(frozen=True)
class LagrangianDerivation:
    """A chain's equations derived the long way (see :func:`lagrangian_derivation`).

    Attributes
    ----------
    kinetic, potential : sympy.Expr
    mass_matrix : sympy.Matrix, shape (n, n)
    dlagrangian_dq, generalized_forces, forcing : sympy.Matrix, shape (n, 1)
    """

    kinetic: sp.Expr
    potential: sp.Expr
    mass_matrix: sp.Matrix
    dlagrangian_dq: sp.Matrix
    generalized_forces: sp.Matrix
    forcing: sp.Matrix


def lagrangian_derivation(chain: Chain) -> LagrangianDerivation:
    """Derive ``chain``'s equations from the Cartesian bob positions, term by term.

    ``T = 1/2 sum_i m_i |v_i|^2`` with ``v_i = J_i omega`` gives
    ``M = sum_i m_i J_i^T J_i``; each entry, a short sum of
    ``cos(theta_j) cos(theta_k) + sin(theta_j) sin(theta_k)`` terms, is folded
    into ``cos(theta_j - theta_k)`` by the targeted rule TR10i. Then
    ``L = T - V`` and the Euler-Lagrange equations
    ``d/dt dL/domega_i = dL/dq_i``, with
    ``d/dt dL/domega_i = sum_j d2L/domega_i dq_j omega_j + sum_j M_ij omega_j'``,
    give the forcing, plus the generalized forces ``-dR/domega`` of Rayleigh's
    dissipation function of the joints and the drive. This is how the
    course derives the equations by hand; the closed form :class:`Chain`
    builds must agree with it (the tests assert so for ``n <= 5``, exactly,
    with :func:`is_identically_zero`). It expands everything, so it is
    refused for long chains (:data:`LIMITS`).

    Examples
    --------
    >>> chain = derive_chain(2)
    >>> long_way = lagrangian_derivation(chain)
    >>> long_way.mass_matrix == chain.mass_matrix, long_way.forcing == chain.forcing
    (True, True)
    """
    chain._require("the Lagrangian derivation")
    n, q, w = chain.n, chain.q, chain.omega
    x, y, xs, ys = sp.Integer(0), sp.Integer(0), [], []
    for qi, li in zip(q, chain.lengths):
        x, y = x + li * sp.sin(qi), y - li * sp.cos(qi)
        xs.append(x)
        ys.append(y)
    jac = [sp.Matrix([[xi], [yi]]).jacobian(q) for xi, yi in zip(xs, ys)]
    mass = sp.zeros(n, n)
    for j, k in itertools.product(range(n), repeat=2):
        if k < j:
            mass[j, k] = mass[k, j]
            continue
        entry = sum(m * (J[:, j].T * J[:, k])[0, 0] for m, J in zip(chain.masses, jac))
        entry = TR10i(sp.factor_terms(sp.expand(entry)))
        entry = sp.expand(entry.subs(sp.sin(q[j]) ** 2, 1 - sp.cos(q[j]) ** 2))
        mass[j, k] = sp.factor_terms(entry)
    kinetic = sp.expand((w.T * mass * w)[0, 0] / 2)
    potential = sp.expand(chain.g * sum(m * yi for m, yi in zip(chain.masses, ys)))
    lagrangian = kinetic - potential
    dl_dq = sp.Matrix([lagrangian.diff(qi) for qi in q])
    dl_dw = sp.Matrix([lagrangian.diff(wi) for wi in w])
    conservative = sp.expand(dl_dq - dl_dw.jacobian(q) * w)
    # Forces without a potential: Rayleigh's dissipation function of the joints'
    # relative angular velocities, and the drive torque on the first link.
    forces = sp.zeros(n, 1)
    if chain.forced:
        relative = [w[i] - (w[i - 1] if i else 0) for i in range(n)]
        dissipation = sum(c * v**2 for c, v in zip(chain.damping, relative)) / 2
        forces = -sp.Matrix([dissipation.diff(wi) for wi in w])
        forces[0] += chain.drive_amplitude * sp.cos(chain.drive_frequency * chain.t)
    forcing = sp.expand(conservative + forces)
    return LagrangianDerivation(kinetic, potential, mass, dl_dq, sp.expand(forces), forcing)


def hamilton_equations_of(system) -> tuple[sp.Matrix, sp.Matrix]:
    """``(dH/dp, -dH/dq + Q)`` of a system with ``hamiltonian``, ``q``, ``p``, ``omega`` and
    ``generalized_forces`` (a :class:`Chain` or a ``MechanicalSystem``); ``Q`` is written in
    ``p`` through ``omega = dH/dp``."""
    h = system.hamiltonian
    dq = sp.Matrix([h.diff(pi) for pi in system.p])
    forces = system.generalized_forces.xreplace(dict(zip(system.omega, dq)))
    return dq, sp.Matrix([-h.diff(qi) for qi in system.q]) + forces


def legendre_transform_of(system) -> sp.Expr:
    """``omega . p - L`` of a system in ``(q, omega)``, from its ``momenta`` and ``lagrangian``."""
    return sp.expand((system.omega.T * system.momenta)[0, 0] - system.lagrangian)


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
    if isinstance(expr, str):  # sympify would run it as Python
        raise TypeError("`expr` must be a SymPy expression, got a string: write it with SymPy "
                        "symbols (sp.symbols(...))")
    expr = sp.expand_trig(sp.sympify(expr, strict=True))
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
