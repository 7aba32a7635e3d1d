"""Bad input at the entry of the chaos measurements: clear errors before any work.

Seeds must be what NumPy's generator takes as the package documents it (an integer >= 0 or
None); runs beyond the work budget are refused before their arrays are made (a Lyapunov
estimate over t_end = 1e12 used to ask NumPy for 14.6 TiB).
"""

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab import chaos

DP = pl.double_pendulum()
DRIVEN = pl.driven_pendulum()
START = dict(theta0=[1.0, 0.5], omega0=[0.0, 0.0])

CASES = {
    "Benettin, seed 'abc'": (lambda: chaos.lyapunov_benettin(DP, **START, t_end=1.0,
                                                             seed="abc"),
                             TypeError, "`seed` must be an integer >= 0 or None"),
    "Benettin, seed -1": (lambda: chaos.lyapunov_benettin(DP, **START, t_end=1.0, seed=-1),
                          ValueError, r"`seed` must be an integer >= 0 or None \(a fresh random "
                          r"choice\), got -1"),
    "variational, seed 1.5": (lambda: chaos.lyapunov_variational(DP, **START, t_end=1.0,
                                                                 seed=1.5),
                              TypeError, "`seed`"),
    "by energy, seed True": (lambda: chaos.lyapunov_by_energy(DP, [-10.0], orbits=2,
                                                              t_end=1.0, seed=True),
                             TypeError, "`seed`"),
    "separation, seed 1.5": (lambda: chaos.separation(DP, **START, t_end=1.0, seed=1.5),
                             TypeError, "`seed`"),
    "Benettin, t_end 1e12": (lambda: chaos.lyapunov_benettin(DP, **START, t_end=1e12),
                             ValueError, "`t_end` / `dt` = 1e\\+12 s / 0.01 s = 1e\\+14 steps"),
    "variational, t_end 1e12": (lambda: chaos.lyapunov_variational(DP, **START, t_end=1e12),
                                ValueError, "budget"),
    "spectrum, t_end 1e12": (lambda: chaos.lyapunov_spectrum(DP, **START, t_end=1e12),
                             ValueError, "budget"),
    "Poincare section, t_end 1e12": (lambda: chaos.poincare_section(DP, **START, t_end=1e12),
                                     ValueError, "budget"),
    "stroboscopic, 1e12 periods": (lambda: chaos.stroboscopic_section(
        DRIVEN, [0.2], [0.0], n_periods=10**12), ValueError, "budget"),
    "bifurcation, 1e8 values": (lambda: chaos.bifurcation_diagram(
        DRIVEN, "drive_amplitude", np.broadcast_to(1.2, 10**8), theta0=[0.2], omega0=[0.0]),
        ValueError, "100000000 `values` over .* = 4e\\+04 steps x 100000000 trajectories"),
}


@pytest.mark.parametrize("case", CASES)
def test_bad_input_is_refused_at_once_naming_the_argument(case, before_any_work):
    call, error, message = CASES[case]
    with before_any_work(), pytest.raises(error, match=message):
        call()


def test_the_valid_seeds_are_accepted_and_fix_the_direction():
    a = chaos.lyapunov_benettin(DP, **START, t_end=1.0, method="rk4", seed=np.int64(3))
    b = chaos.lyapunov_benettin(DP, **START, t_end=1.0, method="rk4", seed=3)
    assert np.array_equal(a.running, b.running)
    chaos.lyapunov_benettin(DP, **START, t_end=1.0, method="rk4", seed=None)
