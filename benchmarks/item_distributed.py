"""Item 14: a flip-time map on a Dask ``LocalCluster`` against the same map in this process.

The map (1000 x 1000 cells to t = 10 in the full configuration)
runs once in this process and twice on a local cluster of worker processes
(``pendulum_lab.driver.cluster``: the cells cut into chunks, the same function and
kernels on every worker): with the environment Dask gives its workers, and
without its ``MALLOC_TRIM_THRESHOLD_``. Reported: cells per second per worker
against the in-process run's per core, both by the wall clock and per
CPU-second (the workers' CPU time is read on the workers), and whether the
maps are identical bit for bit. Without ``dask.distributed`` the row says so.
"""

from __future__ import annotations

import os
import time

import numpy as np
from harness import Config, Row, Section, fmt_time, timed

import pendulum_lab as pl
from pendulum_lab import chaos


def _on_cluster(distributed, dp, size, t_end, workers, environ=None):
    """The map on a fresh ``LocalCluster``: (Sample, FlipTimeMap, CPU seconds on the workers).

    ``environ`` updates the environment Dask's nanny sets before it starts a worker (a
    value None removes the variable).
    """
    import dask

    spawn = dict(dask.config.get("distributed.nanny.pre-spawn-environ", {})) | (environ or {})
    saved = dict(os.environ)  # the nanny sets these variables in this process too
    try:
        with dask.config.set({"distributed.nanny.pre-spawn-environ": spawn}), \
                distributed.LocalCluster(n_workers=workers, threads_per_worker=1,
                                         processes=True, dashboard_address=None) as cluster, \
                distributed.Client(cluster) as client:
            # Every worker imports the package and loads the kernels before the timing.
            client.run(chaos.flip_time_map, dp, size=6, t_end=0.1, progress=False)
            before = client.run(time.process_time)
            sample, result = timed(chaos.flip_time_map, dp, size=size, t_end=t_end,
                                   client=client, progress=False)
            after = client.run(time.process_time)
    finally:
        os.environ.clear()
        os.environ.update(saved)
    return sample, result, sum(after[w] - before[w] for w in after)


def bench_distributed(cfg: Config) -> Section:
    size, t_end, workers = cfg.cluster_size, cfg.cluster_t_end, cfg.cluster_workers
    title = f"flip-time map {size}x{size} to t={t_end:g}"
    try:
        import distributed
    except ImportError:
        row = Row("14", f"{title}, Dask LocalCluster", "-", "-", "-", "-", "not available")
        return Section("distributed", "14. Ensembles on Dask", [row],
                       ["dask.distributed is not installed: pip install "
                        "\"pendulum_lab[cluster]\"."], {})
    dp = pl.double_pendulum()
    chaos.flip_time_map(dp, size=4, t_end=0.1, progress=False)  # kernels loaded
    local_sample, local = timed(chaos.flip_time_map, dp, size=size, t_end=t_end, progress=False)
    cores = os.cpu_count() or 1
    remote_sample, remote, worker_cpu = _on_cluster(distributed, dp, size, t_end, workers)
    untrimmed_sample, untrimmed, untrimmed_cpu = _on_cluster(
        distributed, dp, size, t_end, workers, {"MALLOC_TRIM_THRESHOLD_": None})
    cells = int((~local.forbidden).sum())
    local_rate = cells / local_sample.wall / cores
    local_cpu_rate = cells / local_sample.cpu
    remote_rate = cells / remote_sample.wall / workers
    remote_cpu_rate = cells / worker_cpu
    untrimmed_cpu_rate = cells / untrimmed_cpu
    identical = bool(np.array_equal(local.time, remote.time)
                     and np.array_equal(local.time, untrimmed.time))
    data = {
        "cells": cells, "cores": cores, "workers": workers,
        "local": {"wall": local_sample.wall, "cpu": local_sample.cpu},
        "cluster": {"wall": remote_sample.wall, "worker_cpu": worker_cpu,
                    "client_cpu": remote_sample.cpu},
        "cluster_untrimmed": {"wall": untrimmed_sample.wall, "worker_cpu": untrimmed_cpu},
        "identical": identical,
    }
    rows = [
        Row("14", f"{title}, LocalCluster of {workers} workers, per worker (wall)",
            f"{remote_rate:.4g} cells/s", f"in-process {local_rate:.4g} cells/s per core",
            f"{remote_rate / local_rate:.2f}x", "cluster/in-process (info)", "info"),
        Row("14", f"{title}, LocalCluster, per CPU-second",
            f"{remote_cpu_rate:.4g} cells/CPU-s", f"in-process {local_cpu_rate:.4g} cells/CPU-s",
            f"{remote_cpu_rate / local_cpu_rate:.2f}x", "cluster/in-process (info)", "info"),
        Row("14", f"{title}, LocalCluster without MALLOC_TRIM_THRESHOLD_, per CPU-second",
            f"{untrimmed_cpu_rate:.4g} cells/CPU-s",
            f"in-process {local_cpu_rate:.4g} cells/CPU-s",
            f"{untrimmed_cpu_rate / local_cpu_rate:.2f}x", "cluster/in-process (info)", "info"),
        Row("14", f"{title}, same map on the cluster", "bit for bit" if identical else "differs",
            "in-process map", "-", "identical", "PASS" if identical else "MISS"),
    ]
    details = [
        f"`chaos.flip_time_map(dp, size={size}, t_end={t_end:g})` (rk4, dt = 0.01): {cells} of "
        f"{local.time.size} cells simulated. In this process: {fmt_time(local_sample.wall)} "
        f"wall, {fmt_time(local_sample.cpu)} CPU ({cores} threads). With `client=` on a "
        f"`LocalCluster(n_workers={workers}, threads_per_worker=1, processes=True)`: "
        f"{fmt_time(remote_sample.wall)} wall, {fmt_time(worker_cpu)} CPU on the workers "
        f"(each worker's process, read with `client.run`), {fmt_time(remote_sample.cpu)} in "
        f"the client. 'Per worker' divides the wall-clock rate by the workers, 'per core' by "
        f"os.cpu_count(); a worker runs its chunk on as many threads as the machine has cores, "
        f"so on this machine the workers share its cores.",
        f"Dask's nanny starts each worker with `MALLOC_TRIM_THRESHOLD_=65536` (its "
        f"`distributed.nanny.pre-spawn-environ`), which turns off glibc's adaptive mmap "
        f"threshold: every array over 128 kB that a segment allocates is mapped and "
        f"page-faulted afresh, which costs CPU time in the kernel. The "
        f"third row starts the workers without it (the config value None): "
        f"{fmt_time(untrimmed_sample.wall)} wall, {fmt_time(untrimmed_cpu)} CPU on the workers.",
    ]
    return Section("distributed", "14. Ensembles on Dask", rows, details, data)
