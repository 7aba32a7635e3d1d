"""Bad input to the models (factories, numeric methods, families): clear errors, at once.

Each case names the argument and what is accepted; the huge chain lengths are refused
before anything is built for them (they used to overflow or exhaust memory). The family of a
million members is checked as whole arrays, and its parameters are those of its members
built one by one (the way it was done before, kept here as the reference).
"""

import numpy as np
import pytest

import pendulum_lab as pl

SP = pl.simple_pendulum()
DP = pl.double_pendulum()
DRIVEN = pl.driven_pendulum()

CASES = {
    "n_pendulum(10**100)": (lambda: pl.n_pendulum(10**100), ValueError,
                            "`n` must be at most 1000 links, got 1e\\+100"),
    "n_pendulum(10**9)": (lambda: pl.n_pendulum(10**9), ValueError,
                          "`n` must be at most 1000 links, got 1e\\+09"),
    "PendulumModel(10**100, ...)": (lambda: pl.PendulumModel(10**100, [1.0], [1.0], 9.81),
                                    ValueError, "`n` must be at most 1000 links"),
    "length = 1e-300": (lambda: pl.simple_pendulum(length=1e-300), ValueError,
                        r"`length` must be in \[1e-09, 1e\+09\], got 1e-300"),
    "mass = 1e-300": (lambda: pl.double_pendulum(m1=1e-300), ValueError, "`m1` must be in"),
    "lengths[1] = 1e12": (lambda: pl.n_pendulum(3, lengths=[1.0, 1e12, 1.0]), ValueError,
                          r"`lengths\[1\]` must be in"),
    "g = 1e300": (lambda: pl.simple_pendulum(g=1e300), ValueError,
                  "`g` must be of size at most 1e\\+09"),
    "drive_amplitude = -1e20": (lambda: pl.driven_pendulum(drive_amplitude=-1e20), ValueError,
                                "`drive_amplitude` must be of size at most"),
    "accelerations of one angle for two links": (
        lambda: DP.accelerations([1.0], [0.0]), ValueError,
        r"`theta` must have shape \(\.\.\., 2\) for a model with 2 link\(s\), got shape \(1,\)"),
    "energy of three angles for two links": (
        lambda: DP.energy([1.0, 2.0, 3.0], [0, 0, 0]), ValueError, r"`theta` must have shape"),
    "momenta of strings": (lambda: DP.momenta("a", "b"), TypeError,
                           "`theta` must be an array of real numbers"),
    "velocities with p of the wrong length": (lambda: DP.velocities([1.0, 2.0], [1.0]),
                                              ValueError, "`p` must have shape"),
    "jacobian of a scalar": (lambda: SP.jacobian(0.5, 0.0), ValueError, "`theta` must have"),
    "family with a negative damping": (lambda: DRIVEN.family(damping=[0.1, -1.0]), ValueError,
                                       r"`damping` must be non-negative \(>= 0\), got -1.0"),
    "family with a zero drive frequency": (lambda: DRIVEN.family(drive_frequency=[1.0, 0.0]),
                                           ValueError, "`drive_frequency` must be a positive"),
    "family with a huge g": (lambda: DP.family(g=[9.81, 1e12]), ValueError,
                             "`g` must be of size at most"),
    "family driven without a frequency": (lambda: SP.family(drive_amplitude=[0.0, 1.0]),
                                          ValueError, "`drive_frequency` must be given"),
    "family of no values": (lambda: DRIVEN.family(drive_amplitude=[]), ValueError,
                            "`drive_amplitude` must hold at least one value"),
}


@pytest.mark.parametrize("case", CASES)
def test_bad_input_is_refused_with_a_message_naming_the_argument(case, before_any_work):
    call, error, message = CASES[case]
    with before_any_work(), pytest.raises(error, match=message):  # nothing built first
        call()


def test_the_valid_neighbours_are_accepted():
    assert pl.simple_pendulum(length=1e-9).lengths == (1e-9,)
    assert pl.simple_pendulum(g=-9.81).g == -9.81  # gravity upwards is allowed
    assert DP.accelerations([1.0, 0.5], [0.0, 0.0]).shape == (2,)
    assert DP.energy(np.zeros((4, 3, 2)), np.zeros((4, 3, 2))).shape == (4, 3)
    assert DRIVEN.family(damping=[0.0, 0.5]).shape == (2,)
    # frequencies without a drive are no parameters of the equations, but the family has them
    assert SP.family(drive_frequency=[1.0, 2.0]).drive_frequency.tolist() == [1.0, 2.0]


def _members_one_by_one(base, values):
    """The family's parameters as the members built one by one give them (the old way)."""
    arrays = {k: np.broadcast_to(np.asarray(v, float), np.broadcast_shapes(
        *(np.shape(a) for a in values.values()))) for k, v in values.items()}
    shape = next(iter(arrays.values())).shape
    members = [base.replace(**{k: float(a[index]) for k, a in arrays.items()})
               for index in np.ndindex(shape)]
    forced = any(m.forced for m in members)
    rows = np.array([m._parameters(forced) for m in members], dtype=float)
    return forced, rows.T.reshape(-1, *shape)


@pytest.mark.parametrize("base, values", [
    (DRIVEN, dict(drive_amplitude=[1.0, 1.2, 1.5])),
    (DRIVEN, dict(damping=[[0.0], [0.3]], drive_frequency=[0.5, 2 / 3, 1.0])),
    (DP, dict(g=[1.0, 9.81])),
    (DP, dict(damping=[0.0, 0.1])),
    (pl.n_pendulum(3, drive_amplitude=0.5, drive_frequency=1.0), dict(damping=[0.0, 0.2])),
])
def test_a_family_checked_as_arrays_has_the_members_parameters(base, values):
    family = base.family(**values)
    forced, params = _members_one_by_one(base, values)
    assert family.forced == forced
    assert len(family._params) == len(params)
    for mine, theirs in zip(family._params, params):
        assert np.array_equal(mine, theirs)
    # negative control: a different value gives different parameters
    other = base.family(**{k: np.asarray(v, float) * 1.5 for k, v in values.items()})
    assert any(not np.array_equal(a, b) for a, b in zip(other._params, params))


def test_a_family_of_a_million_members_is_made_as_arrays_not_member_by_member(monkeypatch):
    made = []
    constructor = pl.PendulumModel.__init__

    def counted(self, *args, **kwargs):
        made.append(self)
        constructor(self, *args, **kwargs)

    monkeypatch.setattr(pl.PendulumModel, "__init__", counted)
    family = DRIVEN.family(drive_amplitude=np.linspace(1.0, 1.5, 10**6))
    assert family.shape == (10**6,) and family.drive_amplitude[-1] == 1.5
    family_made = len(made)
    assert family_made <= 1, family_made  # at most the family itself, no member one by one
    # negative control: building the members one by one is counted, one model each
    _members_one_by_one(DRIVEN, dict(drive_amplitude=[1.0, 1.2, 1.5]))
    assert len(made) - family_made == 3
