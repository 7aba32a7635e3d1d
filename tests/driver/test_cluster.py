"""Ensembles on a Dask cluster: the same results, bit for bit, as in this process.

A ``LocalCluster`` of two workers (threads of this process, so the test
starts in about a second) stands in for a real cluster: the chunks go
through the scheduler, are pickled, and come back in order exactly as they
would from remote machines. ``tests/driver/test_cluster.py::test_models_pickle``
covers what a separate process needs beyond that: the model travels as its
constructor call.
"""

import pickle

import numpy as np
import pytest

import pendulum_lab as pl
from pendulum_lab import chaos, segments
from pendulum_lab.chaos.basins import basin_samples
from pendulum_lab.chaos.bifurcation import bifurcation_samples
from pendulum_lab.chaos.lyapunov import tangent_running
from pendulum_lab.driver.cluster import check_client, map_members
from pendulum_lab.integrators import Method, get_method

distributed = pytest.importorskip("distributed")

DP = pl.double_pendulum()


@pytest.fixture(scope="module")
def client():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        with distributed.Client(cluster) as connected:
            yield connected


def test_flip_time_map_on_the_cluster_is_the_local_map(client, monkeypatch):
    # Little memory per segment: the whole batch and a chunk of it are then run in
    # segments of different lengths (as a large map is), which must not matter.
    monkeypatch.setattr(segments, "SEGMENT_FLOATS", 8000)
    local = chaos.flip_time_map(DP, size=14, t_end=2.0)
    remote = chaos.flip_time_map(DP, size=14, t_end=2.0, client=client, chunk_size=9)
    assert np.isfinite(local.time).sum() > 10  # some cells flip: the map is not trivial
    assert np.array_equal(remote.time, local.time)
    assert np.array_equal(remote.forbidden, local.forbidden)
    # Negative control: another step gives another map, so equality is a real check.
    other = chaos.flip_time_map(DP, size=14, t_end=2.0, dt=0.005, client=client, chunk_size=9)
    assert not np.array_equal(other.time, local.time)


def test_lyapunov_map_on_the_cluster_is_the_local_map(client):
    grid = np.stack(np.meshgrid(np.linspace(0.5, 2.5, 4), np.linspace(0.3, 2.7, 3)), axis=-1)
    rest = np.zeros_like(grid)
    local = pl.chaos.lyapunov_benettin(DP, grid, rest, t_end=3.0, method="rk4")
    remote = chaos.lyapunov_benettin(DP, grid, rest, t_end=3.0, method="rk4", client=client,
                                     chunk_size=5)
    assert remote.running.shape == local.running.shape == (6, 3, 4)
    assert np.array_equal(remote.running, local.running)
    # Negative control: another perturbation direction changes the estimates.
    seeded = chaos.lyapunov_benettin(DP, grid, rest, t_end=3.0, method="rk4", client=client,
                                     chunk_size=5, seed=1)
    assert not np.array_equal(seeded.running, local.running)


def test_chunks_come_back_in_order(client):
    numbers = np.arange(23.0)
    quotient, remainder = map_members(np.divmod, (numbers,), args=(4.0,), client=client,
                                      chunk_size=4, progress=False)
    assert np.array_equal(quotient, numbers // 4) and np.array_equal(remainder, numbers % 4)
    reversed_ = map_members(np.flip, (numbers,), client=client, chunk_size=4, progress=False)
    assert not np.array_equal(reversed_, np.flip(numbers))  # each chunk flipped on its own


def test_models_pickle_as_their_constructor_call():
    model = pl.n_pendulum(3, damping=0.2, drive_amplitude=0.5, drive_frequency=1.1)
    copy = pickle.loads(pickle.dumps(model))
    assert repr(copy) == repr(model)
    theta, omega = np.array([0.3, -0.2, 0.1]), np.array([0.1, 0.0, -0.4])
    assert np.array_equal(copy.accelerations(theta, omega, 0.7),
                          model.accelerations(theta, omega, 0.7))


def test_bad_clients_and_unregistered_methods_are_refused(client):
    assert check_client(None) is None
    with pytest.raises(TypeError, match="`client` must be a dask.distributed.Client"):
        chaos.flip_time_map(DP, size=4, t_end=0.1, client="tcp://127.0.0.1:8786")
    rk4 = get_method("rk4")
    homemade = Method(**{f: getattr(rk4, f) for f in rk4.__dataclass_fields__})
    with pytest.raises(ValueError, match="registered method"):
        chaos.flip_time_map(DP, size=4, t_end=0.1, method=homemade, client=client)
    assert chaos.flip_time_map(DP, size=4, t_end=0.1, method=homemade).time.shape == (4, 4)


def test_bifurcation_diagram_on_the_cluster_is_the_local_diagram(client, monkeypatch):
    # Little memory per segment: the whole batch and a chunk of it would then run in
    # segments of different lengths; the step times count from the run's start, so the
    # segmentation does not change a bit.
    monkeypatch.setattr(segments, "SEGMENT_FLOATS", 1000)
    model = pl.driven_pendulum()
    values = np.linspace(0.9, 1.5, 7)
    starts = dict(theta0=[[0.2], [1.0]], omega0=[[0.0], [0.0]], n_periods=32,
                  transient_periods=40, steps_per_period=20)
    local = chaos.bifurcation_diagram(model, "drive_amplitude", values, **starts)
    remote = chaos.bifurcation_diagram(model, "drive_amplitude", values, **starts,
                                       client=client, chunk_size=3)
    for name in ("theta", "omega", "periods", "turns"):
        assert np.array_equal(getattr(remote, name), getattr(local, name)), name
    assert len(set(local.periods.ravel().tolist())) > 1  # not a trivial diagram
    # A chunk in segments of its own size is the same to the bit (the drive's times count
    # from the run's start); negative control: the chunk's neighbours' rows are not.
    family = model.family(drive_amplitude=values)
    rows = np.arange(3)
    own = segments.default_segment_steps(1, 2 * len(rows), 72 * 20, 20)
    whole = segments.default_segment_steps(1, 2 * len(values), 72 * 20, 20)
    assert own != whole
    theta, _, _ = bifurcation_samples(rows, family, np.ones(7), np.array([[0.2], [1.0]]),
                                      np.zeros((2, 1)), 32, 40, 20, "rk4", own)
    assert np.array_equal(np.moveaxis(theta, 0, 1), local.theta[:, :3])
    assert not np.array_equal(np.moveaxis(theta, 0, 1), local.theta[:, 3:6])


def test_lyapunov_map_of_a_family_on_the_cluster_is_the_local_map(client):
    family = pl.driven_pendulum().family(drive_amplitude=[0.9, 1.2, 1.5])
    theta0, omega0 = np.full((2, 3, 1), 0.2), np.zeros((2, 3, 1))
    theta0[1] = 1.0
    local = chaos.lyapunov_benettin(family, theta0, omega0, t_end=4.0, method="rk4")
    remote = chaos.lyapunov_benettin(family, theta0, omega0, t_end=4.0, method="rk4",
                                     client=client, chunk_size=4)
    assert np.array_equal(remote.running, local.running)
    # Negative control: one amplitude for all gives other estimates.
    single = chaos.lyapunov_benettin(family.member(0), theta0, omega0, t_end=4.0, method="rk4")
    assert not np.array_equal(single.running, local.running)


def test_variational_lyapunov_map_on_the_cluster_is_the_local_map(client):
    grid = np.stack(np.meshgrid(np.linspace(0.5, 2.5, 4), np.linspace(0.3, 2.7, 3)), axis=-1)
    rest = np.zeros_like(grid)
    local = chaos.lyapunov_variational(DP, grid, rest, t_end=3.0, method="rk4")
    remote = chaos.lyapunov_variational(DP, grid, rest, t_end=3.0, method="rk4", client=client,
                                        chunk_size=5)
    assert remote.running.shape == local.running.shape == (6, 3, 4)
    assert np.array_equal(remote.running, local.running) and np.array_equal(remote.t, local.t)
    # Negative control: another tangent direction changes the estimates.
    seeded = chaos.lyapunov_variational(DP, grid, rest, t_end=3.0, method="rk4", client=client,
                                        chunk_size=5, seed=1)
    assert not np.array_equal(seeded.running, local.running)


def test_lyapunov_spectrum_of_a_family_on_the_cluster_is_the_local_spectrum(client, monkeypatch):
    # Little memory per segment: the whole batch would run in segments of 10 steps, a
    # chunk of it in longer ones; the driven field's time counts from the run's start, so
    # that changes no bit.
    monkeypatch.setattr(segments, "SEGMENT_FLOATS", 1000)
    family = pl.driven_pendulum().family(drive_amplitude=[0.9, 1.2, 1.5])
    theta0, omega0 = np.full((2, 3, 1), 0.2), np.zeros((2, 3, 1))
    theta0[1] = 1.0
    period = family.member(0).drive_period
    kwargs = dict(t_end=20 * period, dt=period / 20, method="rk4", save_every=10)
    local = chaos.lyapunov_spectrum(family, theta0, omega0, **kwargs)
    remote = chaos.lyapunov_spectrum(family, theta0, omega0, **kwargs, client=client,
                                     chunk_size=2)
    assert remote.running.shape == local.running.shape == (40, 2, 3, 2)
    assert np.array_equal(remote.running, local.running) and np.array_equal(remote.t, local.t)
    # A chunk in segments of its own size is the same to the bit; negative control: other
    # rows of the batch are not.
    rows = np.arange(2)  # released at rest: p0 = 0
    own = segments.segment_length(400, 4 * len(rows) * 4, 10)
    assert own != segments.segment_length(400, 4 * 6 * 4, 10)
    running = tangent_running(theta0.reshape(-1, 1)[rows], np.zeros((2, 1)), rows,
                              family.for_ensemble((2, 3)), period / 20, 10, 40, "rk4",
                              np.eye(2), own)
    assert np.array_equal(running, local.running.reshape(40, 6, 2)[:, rows].swapaxes(0, 1))
    assert not np.array_equal(running,
                              local.running.reshape(40, 6, 2)[:, rows + 2].swapaxes(0, 1))


def test_basins_on_the_cluster_are_the_local_basins(client, monkeypatch):
    # As for the bifurcation diagram: segments of the whole grid differ from a chunk's.
    monkeypatch.setattr(segments, "SEGMENT_FLOATS", 1000)
    model = pl.driven_pendulum(drive_amplitude=1.35)  # two rotations share the plane
    axes = np.linspace(-3, 3, 5), np.linspace(-2.5, 2.5, 4)
    kwargs = dict(transient_periods=30, steps_per_period=40, max_period=4)
    local = chaos.basins_of_attraction(model, *axes, **kwargs)
    remote = chaos.basins_of_attraction(model, *axes, **kwargs, client=client, chunk_size=3)
    assert local.periods == (1, 1) and len(set(local.label.ravel().tolist())) == 2
    assert np.array_equal(remote.label, local.label)
    assert remote.turns == local.turns and remote.method == local.method
    assert len(remote.attractors) == len(local.attractors)
    assert all(np.array_equal(r, a) for r, a in zip(remote.attractors, local.attractors))
    # A chunk in segments of its own size is the same to the bit; negative control: the
    # chunk under another drive is not (the starts themselves settle on the same attractor).
    theta, omega = (a.reshape(-1, 1)[:3] for a in np.meshgrid(*axes))
    own = segments.default_segment_steps(1, 3, 38 * 40, 40)
    whole = segments.default_segment_steps(1, 20, 38 * 40, 40)
    assert own != whole
    as_chunk = basin_samples(theta, omega, np.arange(3), model, 8, 30, 40, "rk4", whole)
    alone = basin_samples(theta, omega, np.arange(3), model, 8, 30, 40, "rk4", own)
    assert np.array_equal(alone[0], as_chunk[0])
    other = basin_samples(theta, omega, np.arange(3), model.replace(drive_amplitude=1.3), 8, 30,
                          40, "rk4", own)
    assert not np.array_equal(other[0], as_chunk[0])


@pytest.mark.parametrize("measure", [
    lambda **kw: chaos.lyapunov_variational(DP, [2.0, 2.5], [0.0, 0.0], t_end=0.5, **kw),
    lambda **kw: chaos.lyapunov_spectrum(DP, [2.0, 2.5], [0.0, 0.0], t_end=0.5, **kw),
    lambda **kw: chaos.basins_of_attraction(pl.driven_pendulum(), [0.0, 1.0], [0.0],
                                            transient_periods=1, steps_per_period=10, **kw),
], ids=["variational", "spectrum", "basins"])
def test_tangent_and_basin_ensembles_refuse_bad_clients(client, measure):
    with pytest.raises(TypeError, match="`client` must be a dask.distributed.Client"):
        measure(client="tcp://127.0.0.1:8786")
    rk4 = get_method("rk4")
    homemade = Method(**{f: getattr(rk4, f) for f in rk4.__dataclass_fields__})
    with pytest.raises(ValueError, match="registered method"):
        measure(method=homemade, client=client)
    measure(method=homemade)  # locally an unregistered method is fine
