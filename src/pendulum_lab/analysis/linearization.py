"""Motion near an equilibrium: the linearised equations and their exact solution.

Each of the ``2**n`` equilibria of a chain (every link straight down or up)
is named in ``model.chain.equilibria`` (``"down"``, ``"down-up"``, ...). About
the all-down one the linearised motion is a sum of normal modes; about any of
them it is ``x(t) = exp(A t) x(0)`` with the equilibrium's Jacobian ``A``.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import expm

from .. import validation as check
from ..driver.simulate import velocity_state
from ..model import require_chain, require_model
from ..model.pendulum import PendulumModel
from ..symbolic.mechanics import Equilibrium

__all__ = [
    "equilibrium_angles",
    "find_equilibrium",
    "linearized_solution",
    "normal_mode_frequencies",
    "normal_modes",
    "rest_coordinates",
    "rest_state_at_energy",
]


def find_equilibrium(model: PendulumModel, equilibrium=None) -> Equilibrium:
    """The equilibrium named ``equilibrium`` (or given as one), all links down by default.

    Parameters
    ----------
    model : PendulumModel
    equilibrium : str or Equilibrium, optional
        A name from ``[eq.name for eq in model.chain.equilibria]`` or one of
        those objects. For a system that is not a chain, a name from
        ``[eq.name for eq in model.equilibria]``, or a point ``q*`` (checked);
        by default the equilibrium of least potential energy.
    """
    require_model(model)
    if not model.is_chain:
        return _system_equilibrium(model, equilibrium)
    if equilibrium is None:
        return model.chain.equilibria[0]
    if isinstance(equilibrium, str):
        return model.chain.equilibrium(equilibrium)
    if equilibrium in model.chain.equilibria:
        return equilibrium
    names = [eq.name for eq in model.chain.equilibria]
    raise TypeError(f"`equilibrium` must be a name in {names} or one of model.chain.equilibria")


def _system_equilibrium(model, equilibrium) -> Equilibrium:
    """A system's equilibrium: by name, as one, as a point ``q*``, or the lowest."""
    found = model.equilibria
    if equilibrium is None or isinstance(equilibrium, str):
        if not found:
            raise ValueError(f"SymPy finds no equilibrium of {model.name}: give one as a point, "
                             "`equilibrium=(q1, q2, ...)`")
        if equilibrium is None:
            return found[0]
        for eq in found:
            if eq.name == equilibrium:
                return eq
        raise ValueError(f"`equilibrium` must be one of {[eq.name for eq in found]} or a point "
                         f"(q1, ..., q{model.n}), got {equilibrium!r}")
    if isinstance(equilibrium, Equilibrium):
        return equilibrium
    point = check.state_vector("equilibrium", equilibrium, model.n)
    return model.system.equilibrium_at(tuple(point), model.parameter_values)


def equilibrium_angles(model: PendulumModel, equilibrium=None) -> np.ndarray:
    """The angles of an equilibrium as floats (0 or pi each), shape ``(n,)``.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> equilibrium_angles(pl.double_pendulum(), "down-up").tolist()
    [0.0, 3.141592653589793]
    """
    return np.array([float(a) for a in find_equilibrium(model, equilibrium).angles])


def rest_coordinates(model: PendulumModel) -> np.ndarray:
    """Where the step-stability tools linearise: the bottom, shape ``(n,)``.

    Every link straight down (zeros) for a chain, damped or driven as well;
    for a system that is not a chain, its equilibrium of least potential
    energy (the elastic pendulum's bob hangs at the spring's stretched length).
    """
    require_model(model)
    return np.zeros(model.n) if model.is_chain else equilibrium_angles(model)


def normal_modes(model: PendulumModel) -> tuple[np.ndarray, np.ndarray]:
    """Small-oscillation angular frequencies [rad/s] and shapes about the all-down equilibrium.

    For a system that is not a chain, about its equilibrium of least potential
    energy; a coordinate that equilibrium leaves free (a cart's position) gives
    a mode of frequency 0, and each shape is scaled so that its largest entry is 1.

    Near the bottom ``theta'' = K theta`` with ``K = M^-1 dF/dq``; a normal mode
    ``theta(t) = a cos(omega t) v`` needs ``K v = -omega^2 v``. So the
    frequencies are ``sqrt(-mu)`` for the eigenvalues ``mu`` of ``K`` (the
    imaginary parts of the Jacobian's eigenvalues ``+-i omega``) and the shapes
    are its eigenvectors.

    Returns
    -------
    frequencies : ndarray, shape (n,)
        Ascending.
    shapes : ndarray, shape (n, n)
        ``shapes[k]`` is the shape of mode ``k``: the relative amplitudes of the
        angles, scaled so that the first link's is 1 (links swinging the same
        way have the same sign).

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> frequencies, shapes = normal_modes(pl.double_pendulum(g=9.81))
    >>> np.round(shapes, 4)  # equal masses and lengths: (1, sqrt 2) and (1, -sqrt 2)
    array([[ 1.    ,  1.4142],
           [ 1.    , -1.4142]])
    """
    down = find_equilibrium(model)
    ratio = np.array(down.stiffness_ratio.subs(model.parameter_values), dtype=float)
    mus, vectors = np.linalg.eig(ratio)
    mus, vectors = mus.real, vectors.real
    order = np.argsort(-mus)  # mu closest to 0 first: the slowest mode
    mus, shapes = mus[order], vectors[:, order].T
    if model.is_chain:
        if np.any(mus >= 0):
            raise ValueError(f"the all-down equilibrium is not a center for g = {model.g}")
        return np.sqrt(-mus), shapes / shapes[:, :1]
    # A free coordinate (the cart's x) gives mu = 0: a mode of frequency 0, a drift.
    free = np.abs(mus) <= 1e-9 * max(1.0, float(np.max(np.abs(mus))))
    if np.any(mus[~free] > 0):
        raise ValueError(f"the equilibrium {down.name} of {model.name} is unstable "
                         f"(eigenvalues {mus.tolist()} of M^-1 dF/dq, one positive), so it has "
                         "no normal modes")
    # Each shape scaled so that its largest entry is +1 (a coordinate may not move at all).
    largest = shapes[np.arange(len(shapes)), np.argmax(np.abs(shapes), axis=1)]
    return np.sqrt(np.where(free, 0.0, -mus)), shapes / largest[:, None]


def normal_mode_frequencies(model: PendulumModel) -> np.ndarray:
    """Small-oscillation angular frequencies [rad/s] about the all-down equilibrium.

    The frequencies of :func:`normal_modes`.

    Returns
    -------
    ndarray, shape (n,)
        Ascending.

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> np.round(normal_mode_frequencies(pl.simple_pendulum(length=1.0, g=4.0)), 12)
    array([2.])
    """
    return normal_modes(model)[0]


def linearized_solution(model: PendulumModel, theta0, omega0=None, *, t, equilibrium=None,
                        p0=None):
    """Solution of the equations linearised about an equilibrium.

    With ``x = (theta - theta*, omega)`` and the Jacobian ``A`` at the
    equilibrium, ``x(t) = exp(A t) x(0)``.

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0, p0 : array_like, shape (n,)
        Initial angles (absolute, not offsets) and angular velocities (or
        momenta ``p0``).
    t : array_like, shape (N,)
        Times [s].
    equilibrium : str or Equilibrium, optional
        A name from ``[eq.name for eq in model.chain.equilibria]``
        (``"down"``, ``"up"`` for one link; ``"down-up"`` and so on for two);
        all links down by default.

    Returns
    -------
    theta, omega : ndarray, shape (N, n)
        Absolute angles and angular velocities of the linear motion.
    """
    eq = find_equilibrium(model, equilibrium)
    n = model.n
    theta0, omega0 = velocity_state(model, theta0, omega0, p0)
    if theta0.ndim != 1:
        raise ValueError("`theta0` and `omega0` must have shape (n,)")
    t = np.asarray(t, dtype=float)
    if t.ndim != 1:
        raise ValueError(f"`t` must be a 1-D array of times, got shape {t.shape}")
    angles = equilibrium_angles(model, eq)
    jac = np.array(eq.jacobian.subs(model.parameter_values), dtype=float)
    x = np.empty((len(t), 2 * n))
    if len(t):
        x[0] = expm(jac * t[0]) @ np.concatenate([theta0 - angles, omega0])
    spacing = np.diff(t)
    if len(t) > 1 and np.allclose(spacing, spacing[0], rtol=1e-9, atol=0):
        # A uniform grid: one matrix exponential, then repeated products.
        propagator = expm(jac * spacing[0])
        for k in range(1, len(t)):
            x[k] = propagator @ x[k - 1]
    else:
        for k in range(1, len(t)):
            x[k] = expm(jac * (t[k] - t[0])) @ x[0]
    return angles + x[:, :n], x[:, n:]


def rest_state_at_energy(model: PendulumModel, energy: float) -> np.ndarray:
    """Angles of a state at rest with total energy ``energy``, all links at one angle.

    With every ``theta_i = phi`` the potential energy is ``-c cos(phi)``, where
    ``c = -V(0)`` (``V`` is zero at the pivot's height), so
    ``phi = arccos(-energy / c)``. Use it to start runs on a chosen energy
    level, from the bottom (``energy = -c``) to everything straight up
    (``energy = c``).

    Returns
    -------
    ndarray, shape (n,)

    Examples
    --------
    >>> import pendulum_lab as pl
    >>> dp = pl.double_pendulum()
    >>> theta = rest_state_at_energy(dp, 0.0)
    >>> bool(np.allclose(theta, np.pi / 2)), bool(abs(dp.potential_energy(theta)) < 1e-12)
    (True, True)
    """
    require_chain(model, "a state at rest with all links at one angle is a chain's")
    energy = check.real_number("energy", energy)
    depth = -float(model.potential_energy(np.zeros(model.n)))
    if depth <= 0:
        raise ValueError(f"the model's `g` must be positive, got {model.g}")
    if abs(energy) > depth:
        raise ValueError(
            f"`energy` must lie in [{-depth:.6g}, {depth:.6g}] J for a state at rest "
            f"(all down to all up), got {energy}"
        )
    return np.full(model.n, np.arccos(-energy / depth))
