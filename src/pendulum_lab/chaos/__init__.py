"""Chaos in the double pendulum, longer chains and the damped, driven pendulum.

The course report (Kanoun, Cowley, Ivachtchenko, MAT332, 2024) observes that
small changes of the initial conditions of the double pendulum give radically
different motion. This package turns that into measurements, one topic per
module:

* :mod:`.separation`: phase-space distance of two nearby trajectories
  (:func:`separation`), or of two computed runs (:func:`separation_between`);
* :mod:`.lyapunov`: the largest Lyapunov exponent by two independent methods
  (:func:`lyapunov_benettin`, :func:`lyapunov_variational`), all of them
  (:func:`lyapunov_spectrum`, for damped and driven fields too), and per energy
  surface (:func:`lyapunov_by_energy`), each with its running estimate and the
  agreement of the full run with its first half (``half_run_difference``);
* :mod:`.tangent`: the variational equations solved along a trajectory
  (fourth-order Magnus propagators), shared by the exponents and the
  multipliers;
* :mod:`.sections`: Poincare sections on energy levels, crossings landed on
  the surface by Newton's method in time or by Henon's trick
  (:func:`section_states`, :func:`section_spread`, :func:`poincare_section`,
  :func:`energy_sections`, :func:`landing_errors`);
* :mod:`.flips`: Heyl's flip-time fractal (:func:`can_flip`,
  :func:`flip_time_map`);
* :mod:`.small_angles`: where the linearised and the full motion part
  (:func:`small_angle_comparison`);
* :mod:`.stroboscopic`, :mod:`.bifurcation`, :mod:`.basins`: the damped,
  driven pendulum sampled once per drive period
  (:func:`stroboscopic_section`, :func:`orbit_periods`), against a
  parameter (:func:`bifurcation_diagram`), and which attractor each start
  ends on (:func:`basins_of_attraction`);
* :mod:`.floquet`: periodic orbits of the driven pendulum by shooting
  (:func:`periodic_orbit`, :func:`continue_orbit`), their Floquet
  multipliers, and the parameter values where they double their period or
  break their symmetry (:func:`locate_bifurcation`,
  :func:`period_doubling_cascade`), with stated errors.

Every trajectory comes from :func:`pendulum_lab.simulate` (an ensemble is a
batch of initial states) or, for runs examined piece by piece, from
:func:`pendulum_lab.simulate_segments`; crossings are located by
:mod:`pendulum_lab.driver.events`. Nothing here steps the equations of motion
itself. The figures of these results are in :mod:`pendulum_lab.plotting`.

Notes
-----
Phase-space distances are Euclidean in the canonical variables
``(theta, p)`` (radians and kg m^2/s). The largest Lyapunov exponent does not
depend on that choice of norm; finite-time estimates do, a little.
"""

from .basins import Basins, basins_of_attraction
from .bifurcation import BifurcationDiagram, PeriodDoubling, PeriodWindow, bifurcation_diagram
from .flips import FlipMap, can_flip, flip_time_map
from .floquet import (
    Bifurcation,
    DoublingCascade,
    PeriodicOrbit,
    continue_orbit,
    locate_bifurcation,
    period_doubling_cascade,
    periodic_orbit,
)
from .lyapunov import (
    REGULAR_BELOW,
    EnergyExponent,
    EnergyLyapunov,
    LyapunovEstimate,
    LyapunovSpectrum,
    lyapunov_benettin,
    lyapunov_by_energy,
    lyapunov_spectrum,
    lyapunov_variational,
)
from .sections import (
    LANDINGS,
    LandingErrors,
    PoincareSection,
    energy_sections,
    landing_errors,
    poincare_section,
    section_spread,
    section_states,
)
from .separation import Separation, separation, separation_between
from .small_angles import SmallAngleComparison, small_angle_comparison
from .stroboscopic import StroboscopicSection, orbit_periods, stroboscopic_section

__all__ = [
    "Basins",
    "Bifurcation",
    "BifurcationDiagram",
    "DoublingCascade",
    "EnergyExponent",
    "EnergyLyapunov",
    "LANDINGS",
    "REGULAR_BELOW",
    "FlipMap",
    "LandingErrors",
    "LyapunovEstimate",
    "LyapunovSpectrum",
    "PeriodDoubling",
    "PeriodWindow",
    "PeriodicOrbit",
    "PoincareSection",
    "Separation",
    "SmallAngleComparison",
    "StroboscopicSection",
    "basins_of_attraction",
    "bifurcation_diagram",
    "can_flip",
    "continue_orbit",
    "energy_sections",
    "flip_time_map",
    "landing_errors",
    "locate_bifurcation",
    "lyapunov_benettin",
    "lyapunov_by_energy",
    "lyapunov_spectrum",
    "lyapunov_variational",
    "orbit_periods",
    "period_doubling_cascade",
    "periodic_orbit",
    "poincare_section",
    "section_spread",
    "section_states",
    "separation",
    "separation_between",
    "small_angle_comparison",
    "stroboscopic_section",
]
