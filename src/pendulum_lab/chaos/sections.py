"""Poincare sections: crossings of a surface located to round-off.

A crossing is detected between two saved steps and then landed on the
surface in one of two ways (``landing`` of :func:`poincare_section`): Newton's
method on the length of one extra step in time (:func:`pendulum_lab.driver.events.land`),
or Henon's trick, one step with the angle as the independent variable
(:func:`pendulum_lab.henon_step`). :func:`landing_errors` measures how far
either lands from the exact crossing.

References
----------
.. [Henon] M. Henon, "On the numerical computation of Poincare maps",
   Physica D 5 (1982) 412-414.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from .. import validation as check
from ..driver.events import check_direction, find_crossings, land
from ..driver.henon import henon_step
from ..driver.segments import simulate_segments
from ..driver.simulate import canonical_state, step
from ..integrators import get_method
from ..model import require_double_pendulum, require_model
from ..model.angles import wrap_angle
from ..model.pendulum import PendulumModel
from ..plot_dispatch import plot_with
from .common import phase_distance, require_finite

__all__ = [
    "LANDINGS",
    "LandingErrors",
    "PoincareSection",
    "energy_sections",
    "landing_errors",
    "poincare_section",
    "section_spread",
    "section_states",
]

#: How a detected crossing is put on the surface (``landing`` of :func:`poincare_section`).
LANDINGS = ("newton", "henon", "nearest")


def section_states(
    model: PendulumModel,
    energy: float,
    theta_rest,
    p_rest,
    *,
    link: int = 0,
    value: float = 0.0,
    direction: int = 1,
) -> tuple[np.ndarray, np.ndarray]:
    """Initial states on the surface ``theta_link = value`` with a given energy.

    The other angles and momenta are given; the remaining momentum ``x =
    p_link`` solves ``H = energy``. ``H = 1/2 p^T A p + V`` with ``A = M^-1``
    is quadratic in ``x``: ``1/2 a x^2 + b x + c = 0`` with ``a = A_ii``,
    ``b = sum_{j != i} A_ij p_j`` and ``c = H(x = 0) - energy``. Its roots give
    ``theta_i' = dH/dp_i = a x + b = +-sqrt(b^2 - 2 a c)``, so the root with the
    sign of ``direction`` crosses the surface in that direction. Points where
    ``b^2 < 2 a c`` cannot reach the surface at this energy and are dropped.

    Parameters
    ----------
    model : PendulumModel
        ``n >= 2``.
    energy : float
        Total energy [J] (zero potential at the pivot's height).
    theta_rest, p_rest : array_like, shape (..., n - 1)
        The angles and momenta other than ``theta_link``, ``p_link``, in
        link order.
    link : int
        Which link's angle defines the surface (0-based).
    value : float
        The surface ``theta_link = value``.
    direction : {1, -1}
        Sign of ``theta_link'`` at the initial states.

    Returns
    -------
    theta0, omega0 : ndarray, shape (K, n)
        The ``K`` accessible points, flattened, ready for
        :func:`poincare_section`.

    Raises
    ------
    ValueError
        If no point is accessible at this energy.

    Examples
    --------
    >>> import numpy as np, pendulum_lab as pl
    >>> dp = pl.double_pendulum()
    >>> theta0, omega0 = section_states(dp, -15.0, [[0.0], [0.5]], [[0.0], [1.0]])
    >>> bool(np.allclose(dp.energy(theta0, omega0), -15.0)), bool(np.all(omega0[:, 0] > 0))
    (True, True)
    """
    require_model(model)
    n = model.n
    if not model.is_autonomous:
        raise ValueError(f"`model` ({model!r}) depends on the time, so its energy is not "
                         "constant and no energy level fixes the states; start from states of "
                         "your own, or take a stroboscopic section (stroboscopic_section)")
    if n < 2:
        raise ValueError("`model` must have at least two coordinates for a Poincare section")
    energy = check.real_number("energy", energy)
    link = check.index_below("link", link, n)
    value = check.real_number("value", value)
    direction = check_direction(direction, allow_both=False)
    theta_rest = check.state_array("theta_rest", theta_rest, n - 1)
    p_rest = check.state_array("p_rest", p_rest, n - 1)
    theta_rest, p_rest = np.broadcast_arrays(theta_rest, p_rest)
    theta = np.insert(theta_rest.reshape(-1, n - 1), link, value, axis=-1)
    p = np.insert(p_rest.reshape(-1, n - 1), link, 0.0, axis=-1)
    inverse = np.linalg.inv(model.mass_matrix_at(theta))
    a = inverse[:, link, link]
    b = np.einsum("kj,kj->k", inverse[:, link, :], p)
    c = model.hamiltonian_value(theta, p) - energy
    disc = b**2 - 2 * a * c
    ok = disc >= 0
    if not np.any(ok):
        raise ValueError(
            f"no point reaches the surface at `energy` = {energy} J: it is below "
            "the potential energy there"
        )
    p[ok, link] = (-b[ok] + direction * np.sqrt(disc[ok])) / a[ok]
    return theta[ok], model.velocities(theta[ok], p[ok])


@dataclass(frozen=True)
class PoincareSection:
    """Crossings of the surface ``theta_link = value (mod 2 pi)``.

    Attributes
    ----------
    t : ndarray, shape (C,)
        Crossing times [s].
    theta : ndarray, shape (C, n)
        Angles at the crossings, wrapped to ``(-pi, pi]``.
    p : ndarray, shape (C, n)
        Momenta at the crossings.
    orbit : ndarray of int, shape (C,)
        Which initial state (flat index into the ensemble) each crossing
        belongs to.
    residual : ndarray, shape (C,)
        ``|theta_link - (value + 2 pi m)|`` at each located crossing: how far
        it lies from the surface.
    link, value, direction
        The surface and the crossing direction (``1``: ``theta_link``
        increasing, ``-1``: decreasing, ``0``: both).
    landing : {"newton", "henon", "nearest"}
        How the crossings were put on the surface (see :func:`poincare_section`).
    landing_steps : ndarray of int, shape (C,)
        Integrator steps spent landing each crossing (0 for ``"nearest"``, 1
        for ``"henon"``, Newton's iterations for ``"newton"``).
    """

    t: np.ndarray
    theta: np.ndarray
    p: np.ndarray
    orbit: np.ndarray
    residual: np.ndarray
    link: int
    value: float
    direction: int
    landing: str
    landing_steps: np.ndarray

    def subset(self, keep, orbit_offset: int = 0) -> PoincareSection:
        """The crossings where ``keep`` is true, orbits renumbered by ``- orbit_offset``."""
        return dataclasses.replace(
            self, t=self.t[keep], theta=self.theta[keep], p=self.p[keep],
            orbit=self.orbit[keep] - orbit_offset, residual=self.residual[keep],
            landing_steps=self.landing_steps[keep],
        )

    def shown_link(self, link: int | None = None) -> int:
        """``link``, or by default the first link off the surface."""
        return (1 if self.link == 0 else 0) if link is None else link

    def coordinates(self, link: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``(theta_j, p_j)`` of the crossings for link ``j`` (the first one off the surface)."""
        link = self.shown_link(link)
        return self.theta[:, link], self.p[:, link]

    def plot(self, ax=None, link: int | None = None, s: float = 2.0, **kwargs):
        """The section in ``(theta_j, p_j)``, one colour per orbit; returns the Figure."""
        return plot_with("plot_section", self, ax=ax, link=link, s=s, **kwargs)



def poincare_section(
    model: PendulumModel,
    theta0,
    omega0=None,
    *,
    t_end: float,
    dt: float = 0.01,
    method="glrk4",
    p0=None,
    link: int = 0,
    value: float = 0.0,
    direction: int = 1,
    landing: str = "newton",
    progress: bool | None = None,
    t0: float = 0.0,
) -> PoincareSection:
    """Crossings of ``theta_link = value (mod 2 pi)`` located to round-off.

    The ensemble runs in segments (:func:`~pendulum_lab.simulate_segments`)
    with every step kept; a crossing is a step over which the unwrapped angle
    passes ``value + 2 pi m``, upwards for ``direction = 1``
    (:func:`pendulum_lab.driver.events.find_crossings` with period ``2 pi``). Each
    crossing, between saved steps ``k`` and ``k+1``, is then put on the
    surface by one of two landings, both with the same integrator and both
    starting from step ``k``:

    ``"newton"``
        The cubic Hermite interpolant of ``theta_link`` (values and slopes
        ``dH/dp_link`` at both steps) gives a first guess ``tau`` of the
        crossing time after ``t_k``; Newton's method on ``tau``, each iterate
        one step of length ``tau`` (:func:`~pendulum_lab.step`), drives
        ``theta_link`` onto the surface (:func:`pendulum_lab.driver.events.land`).
        A root solve in time: a few steps per crossing.
    ``"henon"``
        Henon's trick (1982): one step of the integrator with ``theta_link``
        as the independent variable, from ``theta_link(t_k)`` to the surface
        (:func:`~pendulum_lab.henon_step`). One step per crossing, no
        iteration; methods in canonical variables only.

    Both land on the surface to round-off, with an error of the integrator's
    local order (:func:`landing_errors`). ``landing="nearest"`` returns the
    nearest saved step instead (off the surface by up to
    ``dt |theta_link'| / 2``: a negative control).

    Parameters
    ----------
    model : PendulumModel
    theta0, omega0, p0 : array_like, shape (..., n)
        Initial states (for example from :func:`section_states`).
    t_end, dt, method, t0
        As for :func:`~pendulum_lab.simulate`.
    link : int
        The link whose angle defines the surface (0-based).
    value : float
        Surface ``theta_link = value``.
    direction : {1, -1, 0}
        ``1``: crossings with ``theta_link`` increasing (``dH/dp_link > 0``),
        ``-1``: decreasing, ``0``: both.
    landing : {"newton", "henon", "nearest"}
        How each crossing is put on the surface (see above).
    progress : bool, optional

    Returns
    -------
    PoincareSection
        Crossings sorted by orbit, then time.

    Notes
    -----
    For the double pendulum the section ``theta_1 = 0`` is often described
    with ``p_1 > 0``; the crossing direction is the sign of
    ``theta_1' = (M^-1 p)_1``, which is not always the sign of ``p_1``. The
    direction used here is that of ``theta_1'``: it makes the section a
    one-sided surface crossed transversally, on which the return map
    preserves area in ``(theta_2, p_2)``.

    References
    ----------
    M. Henon, "On the numerical computation of Poincare maps", Physica D 5
    (1982) 412-414.

    Examples
    --------
    >>> import numpy as np, pendulum_lab as pl
    >>> dp = pl.double_pendulum()
    >>> theta0, omega0 = section_states(dp, -20.0, [[0.3]], [[0.0]])
    >>> sec = poincare_section(dp, theta0, omega0, t_end=5.0, method="rk4")
    >>> henon = poincare_section(dp, theta0, omega0, t_end=5.0, method="rk4", landing="henon")
    >>> bool(np.all(sec.residual < 1e-10)), bool(np.all(henon.residual < 1e-10))
    (True, True)
    >>> bool(np.max(np.abs(sec.p - henon.p)) < 1e-8), set(henon.landing_steps.tolist())
    (True, {1})
    """
    require_model(model)
    n = model.n
    link = check.index_below("link", link, n)
    value = check.real_number("value", value)
    direction = check_direction(direction)
    landing = check.choice("landing", landing, LANDINGS)
    if landing == "henon" and get_method(method).variables != "canonical":
        raise ValueError(f"landing='henon' needs a method in canonical variables, got "
                         f"`method` {get_method(method).name!r}; use landing='newton'")
    run = simulate_segments(model, theta0, omega0, t_end=t_end, dt=dt, method=method, p0=p0,
                            progress=progress, label="Poincare section", t0=t0)
    found = {name: [] for name in ("t", "theta", "p", "orbit", "residual", "landing_steps")}
    for segment in run:
        require_finite(segment, "poincare_section")
        _crossings(model, segment, link, value, direction, landing, found)
    arrays = {k: np.asarray(v) for k, v in found.items()}
    if arrays["t"].size == 0:
        arrays = {
            "t": np.empty(0),
            "theta": np.empty((0, n)),
            "p": np.empty((0, n)),
            "orbit": np.empty(0, dtype=int),
            "residual": np.empty(0),
            "landing_steps": np.empty(0, dtype=int),
        }
    order = np.lexsort((arrays["t"], arrays["orbit"]))
    return PoincareSection(
        t=arrays["t"][order],
        theta=wrap_angle(arrays["theta"][order]),
        p=arrays["p"][order],
        orbit=arrays["orbit"][order].astype(int),
        residual=arrays["residual"][order],
        link=link,
        value=value,
        direction=direction,
        landing=landing,
        landing_steps=arrays["landing_steps"][order].astype(int),
    )


def _crossings(model, segment, link, value, direction, landing, found):
    """Append the crossings in one segment (``theta`` of shape ``(L+1, K, n)``) to ``found``."""
    hits = find_crossings(segment.theta[..., link], direction, level=value, period=2 * np.pi)
    if len(hits) == 0:
        return
    steps, orbits = hits.step, hits.member
    if landing == "nearest":
        k, residual = hits.nearest()
        found["t"].extend(segment.t[k])
        found["theta"].extend(segment.theta[k, orbits])
        found["p"].extend(segment.p[k, orbits])
        found["orbit"].extend(orbits)
        found["residual"].extend(residual)
        found["landing_steps"].extend(np.zeros(len(hits), dtype=int))
        return
    if landing == "henon":
        for k in np.unique(steps):  # one call per start time (the equations may depend on it)
            rows = steps == k
            theta, p, elapsed = henon_step(model, segment.theta[k, orbits[rows]],
                                           p0=segment.p[k, orbits[rows]], link=link,
                                           level=hits.level[rows], method=segment.method,
                                           t0=float(segment.t[k]))
            found["t"].extend(segment.t[k] + elapsed)
            found["theta"].extend(theta)
            found["p"].extend(p)
            found["orbit"].extend(orbits[rows])
            found["residual"].extend(np.abs(theta[:, link] - hits.level[rows]))
            found["landing_steps"].extend(np.ones(int(rows.sum()), dtype=int))
        return
    dt = segment.dt
    guess = hits.fraction(dt * segment.omega[steps, orbits, link],
                          dt * segment.omega[steps + 1, orbits, link])
    for k, j, s, target in zip(steps, orbits, guess, hits.level):
        theta, p = segment.theta[k, j], segment.p[k, j]
        t_k = float(segment.t[k])

        def advance(tau, theta=theta, p=p, t_k=t_k):
            if tau == 0.0:
                return theta, p, t_k
            return (*step(model, theta, p0=p, dt=tau, method=segment.method, t0=t_k), t_k + tau)

        miss, (q, p_landed, _), tau, used = land(
            advance,
            lambda state, target=target: state[0][link] - target,
            lambda state: model.dH_dp(*state)[link],
            float(s * dt),
            (-dt, 2 * dt),
            scale=target,
        )
        found["t"].append(segment.t[k] + tau)
        found["theta"].append(q)
        found["p"].append(p_landed)
        found["orbit"].append(j)
        found["residual"].append(miss)
        found["landing_steps"].append(used)


@dataclass(frozen=True)
class LandingErrors:
    """How far landed crossings lie from the exact ones (see :func:`landing_errors`).

    Attributes
    ----------
    state_error : ndarray, shape (K,)
        Euclidean distance in ``(theta, p)`` between each landed crossing and
        the exact one.
    time_error : ndarray, shape (K,)
        ``|t_landed - t_exact|`` [s].
    landing_steps : ndarray of int, shape (K,)
        Integrator steps each landing took.
    speed : ndarray, shape (K,)
        ``|theta_link'|`` at each exact crossing [rad/s]: how briskly the
        surface is crossed.
    landing, method : str
    dt : float
    """

    state_error: np.ndarray
    time_error: np.ndarray
    landing_steps: np.ndarray
    speed: np.ndarray
    landing: str
    method: str
    dt: float

    def plot(self, ax=None, **kwargs):
        """The error against the crossing speed (log-log); returns the Figure."""
        return plot_with("plot_landing_errors", self, ax=ax, **kwargs)


def landing_errors(
    model: PendulumModel,
    theta,
    omega=None,
    *,
    dt: float,
    method="rk4",
    landing: str = "newton",
    p0=None,
    link: int = 0,
    lead: float = 0.5,
) -> LandingErrors:
    """Land on known crossings and measure the error of the landing alone.

    ``theta`` and ``omega`` (or ``p0``) are states exactly on the surface
    ``theta_link = 0`` (from :func:`section_states`, for example). Each is
    moved back in time by ``lead * dt`` with many small steps of the
    eighth-order ``glrk8`` (an error near round-off); from there
    :func:`poincare_section` runs one step of ``dt`` with ``method`` and
    lands the crossing with ``landing``. The distance between the landed and
    the original state is the error of one step plus its landing, with no
    error accumulated before: it shrinks like ``dt ** (order + 1)``. Henon's
    step integrates a field divided by ``theta_link'``; where the surface is
    crossed slowly (``speed`` small) that field varies fast and the error of
    ``"henon"`` grows, while Newton's steps in time do not notice.

    Parameters
    ----------
    model : PendulumModel
    theta, omega, p0 : array_like, shape (K, n)
        States on the surface, crossing it (give ``omega`` or ``p0``).
    dt : float
        Step of ``method`` [s], ``> 0``.
    method : str or Method
    landing : {"newton", "henon"}
    link : int
        The surface is ``theta_link = 0``.
    lead : float
        Where in its step the crossing lies, in ``(0, 1)``.

    Returns
    -------
    LandingErrors

    Examples
    --------
    >>> import numpy as np, pendulum_lab as pl
    >>> dp = pl.double_pendulum()
    >>> theta, omega = pl.chaos.section_states(dp, -10.0, [[0.4], [1.0]], [[0.0], [0.5]])
    >>> coarse = landing_errors(dp, theta, omega, dt=0.02, method="rk4", landing="henon")
    >>> fine = landing_errors(dp, theta, omega, dt=0.01, method="rk4", landing="henon")
    >>> bool(16 < coarse.state_error.max() / fine.state_error.max() < 64)  # about 2**5
    True
    """
    require_model(model)
    if not model.is_autonomous:
        raise ValueError(f"`model` ({model!r}) depends on the time: landing_errors measures "
                         "landings on an autonomous flow (it steps back from t = 0)")
    landing = check.choice("landing", landing, ("newton", "henon"))
    dt = check.positive_number("dt", dt)
    lead = check.number_in("lead", lead, 0.0, 1.0, open_low=True)
    if lead == 1.0:
        raise ValueError("`lead` must be below 1 (the crossing must lie inside the step)")
    link = check.index_below("link", link, model.n)
    theta, p = canonical_state(model, theta, omega, p0)
    theta, p = theta.reshape(-1, model.n), p.reshape(-1, model.n)
    if np.any(theta[:, link] != 0.0):
        raise ValueError(f"`theta` must lie on the surface: theta[:, {link}] must be 0")
    back_theta, back_p = theta, p
    for _ in range(16):
        back_theta, back_p = step(model, back_theta, p0=back_p, dt=-lead * dt / 16,
                                  method="glrk8")
    sec = poincare_section(model, back_theta, p0=back_p, t_end=dt, dt=dt, method=method,
                           link=link, direction=0, landing=landing, progress=False)
    if not np.array_equal(sec.orbit, np.arange(len(theta))):
        raise ValueError("each state must cross the surface exactly once within the step "
                         f"(found crossings of orbits {sec.orbit.tolist()}); use a smaller `dt`")
    return LandingErrors(
        state_error=phase_distance(sec.theta, sec.p, theta, p, wrap=True),
        time_error=np.abs(sec.t - lead * dt),
        landing_steps=sec.landing_steps,
        speed=np.abs(model.dH_dp(theta, p)[:, link]),
        landing=landing,
        method=get_method(method).name,
        dt=dt,
    )


def energy_sections(
    model: PendulumModel,
    energies,
    *,
    orbits: int = 10,
    t_end: float = 100.0,
    dt: float = 0.01,
    method="glrk4",
    landing: str = "newton",
    progress: bool | None = None,
) -> dict[float, PoincareSection]:
    """Poincare sections ``theta_1 = 0``, ``theta_1' > 0`` of a double pendulum, several energies.

    For each energy, ``orbits`` initial states are spread over the section:
    by :func:`section_spread`. All orbits of all energies run as one ensemble.

    Parameters
    ----------
    model : PendulumModel
        A double pendulum.
    energies : sequence of float
        Energies [J], above the minimum ``V(0, 0)``.
    orbits : int
        Initial states per energy, ``>= 2``.
    t_end, dt, method, landing, progress
        As for :func:`poincare_section`.

    Returns
    -------
    dict
        ``{energy: PoincareSection}``; each section's ``orbit`` numbers its
        own orbits from 0.
    """
    require_double_pendulum(model)
    orbits = check.integer_at_least("orbits", orbits, 2)
    energies = [check.real_number("energies", e) for e in np.atleast_1d(energies)]
    starts, owner = [], []
    for number, energy in enumerate(energies):
        theta0, omega0 = _spread(model, energy, orbits, "energies")
        starts.append((theta0, omega0))
        owner += [number] * len(theta0)
    theta0 = np.concatenate([s[0] for s in starts])
    omega0 = np.concatenate([s[1] for s in starts])
    sec = poincare_section(model, theta0, omega0, t_end=t_end, dt=dt, method=method,
                           landing=landing, progress=progress)
    owner = np.asarray(owner)
    first = np.cumsum([0] + [len(s[0]) for s in starts])
    result = {}
    for number, energy in enumerate(energies):
        result[energy] = sec.subset(owner[sec.orbit] == number, orbit_offset=first[number])
    return result


def section_spread(model: PendulumModel, energy: float, orbits: int = 10
                   ) -> tuple[np.ndarray, np.ndarray]:
    """``orbits`` states on the section ``theta_1 = 0``, ``theta_1' > 0`` at one energy.

    Half of them lie along ``p_2 = 0`` at ``theta_2`` evenly spread between 0
    and the largest angle the energy reaches, half along ``theta_2 = 0`` at
    ``p_2 > 0`` up to the largest momentum it allows; ``p_1`` follows from
    ``H = energy`` (:func:`section_states`). These are the starts of
    :func:`energy_sections`: all on one energy surface, reaching across it.

    Parameters
    ----------
    model : PendulumModel
        A double pendulum.
    energy : float
        Total energy [J], above the minimum ``V(0, 0)``.
    orbits : int
        Number of states, ``>= 2``.

    Returns
    -------
    theta0, omega0 : ndarray, shape (orbits, 2)

    Examples
    --------
    >>> import numpy as np, pendulum_lab as pl
    >>> dp = pl.double_pendulum()
    >>> theta0, omega0 = section_spread(dp, 5.0, orbits=6)
    >>> theta0.shape, bool(np.allclose(dp.energy(theta0, omega0), 5.0))
    ((6, 2), True)
    """
    require_double_pendulum(model)
    energy = check.real_number("energy", energy)
    orbits = check.integer_at_least("orbits", orbits, 2)
    return _spread(model, energy, orbits, "energy")


def _spread(model, energy, orbits, name):
    """:func:`section_spread` without the checks; ``name`` is the argument an error names."""
    along_theta = orbits - orbits // 2
    grid = np.linspace(0.0, np.pi, 400)
    bottom = model.potential_energy(np.column_stack([np.zeros_like(grid), grid]))
    reach = grid[bottom < energy]
    if reach.size == 0:
        raise ValueError(
            f"`{name}` must lie above the minimum of the potential energy "
            f"({float(bottom[0]):.6g} J), got {energy}"
        )
    theta2 = np.linspace(0.0, reach[-1], along_theta + 1)[:-1] + reach[-1] / (2 * along_theta)
    # Largest p_2 on theta = 0: the discriminant of the quadratic for p_1 vanishes.
    inverse = np.linalg.inv(model.mass_matrix_at(np.zeros(2)))
    depth = energy - float(model.potential_energy(np.zeros(2)))
    p2_max = np.sqrt(2 * depth / (inverse[1, 1] - inverse[0, 1] ** 2 / inverse[0, 0]))
    count = orbits // 2
    p2 = (np.arange(count) + 0.5) / count * p2_max
    theta_rest = np.concatenate([theta2, np.zeros(count)])[:, None]
    p_rest = np.concatenate([np.zeros(along_theta), p2])[:, None]
    return section_states(model, energy, theta_rest, p_rest)
