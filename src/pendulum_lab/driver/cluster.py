"""Ensembles beyond one process: a batch cut into chunks for the workers of a Dask cluster.

The ensemble measurements (:func:`~pendulum_lab.chaos.flip_time_map`;
:func:`~pendulum_lab.chaos.lyapunov_benettin`,
:func:`~pendulum_lab.chaos.lyapunov_variational` and
:func:`~pendulum_lab.chaos.lyapunov_spectrum` over a grid of initial states;
:func:`~pendulum_lab.chaos.bifurcation_diagram`,
:func:`~pendulum_lab.chaos.basins_of_attraction`) take one keyword, ``client``: a
``dask.distributed.Client``. Without it the whole batch is one chunk,
computed in this process (its members in parallel threads, as
:func:`~pendulum_lab.simulate` does). With it the batch is cut into
contiguous chunks that the cluster's workers compute with the same function
and the same compiled kernels, and the results come back in order. Members
of an ensemble never interact (every member is integrated on its own, with
the same steps, a driven model's step times computed from the step's number
since the run's start, whatever the segments), so the result is the local one
bit for bit, provided a family's chunk keeps its own members
(:func:`members_of`). The tests check all of this on
a ``LocalCluster``.

A model travels to the workers as its constructor call (it pickles small);
each worker builds its own numeric functions and loads the compiled kernels
from its disk cache, compiling them the first time it sees them. Dask is an
optional dependency: ``pip install "pendulum_lab[cluster]"``.

References
----------
.. [Dask] Dask Development Team, *Dask: library for dynamic task scheduling*,
   https://dask.org; ``Client.map`` and ``Client.gather`` of ``dask.distributed``.
"""

from __future__ import annotations

import math

import numpy as np

from .. import validation as check

__all__ = ["check_client", "map_members", "members_of", "portable_method"]

#: Chunks per worker when the caller gives no ``chunk_size``: a few, so that a
#: slow worker (or a chunk of slow members) does not hold up the rest.
CHUNKS_PER_WORKER = 4


def check_client(client):
    """``client`` if it is None or a ``dask.distributed.Client``; else a clear error.

    Raises
    ------
    ImportError
        A client is given but Dask is not installed.
    TypeError
        ``client`` is something else.
    ValueError
        ``client`` is closed (or not yet connected).
    """
    if client is None:
        return None
    try:
        from distributed import Client
    except ImportError as err:
        raise ImportError(
            "`client` needs dask.distributed: pip install \"pendulum_lab[cluster]\"") from err
    if not isinstance(client, Client):
        raise TypeError(f"`client` must be a dask.distributed.Client or None, got "
                        f"{type(client).__name__}")
    status = getattr(client, "status", "running")
    if status != "running":
        raise ValueError(f"`client` must be a running dask.distributed.Client, but this one is "
                         f"{status!r}: start a new Client (or pass client=None to compute here)")
    return client


def members_of(model, rows):
    """The model of rows ``rows`` (indices into a flattened batch) of a run of ``model``.

    A plain model serves every row; a
    :class:`~pendulum_lab.model.ModelFamily` flattened for the batch
    (``for_ensemble``) gives those members, so that a chunk of the batch
    carries its own parameters.
    """
    return model.select(np.asarray(rows)) if model.shape else model


def portable_method(method, client):
    """``method`` (a :class:`~pendulum_lab.integrators.Method`) as a chunk's argument.

    Locally the method itself; for a cluster its name, which workers look up
    in the registry (compiled kernels do not pickle), so it must be a
    registered method.
    """
    from ..integrators import get_method

    if client is None:
        return method
    if get_method(method.name) is not method:
        raise ValueError(f"`method` must be a registered method to run on a cluster (workers "
                         f"look it up by name), got an unregistered one named {method.name!r}")
    return method.name


def _chunk_bounds(members: int, client, chunk_size) -> list[tuple[int, int]]:
    if chunk_size is None:
        workers = max(1, len(client.nthreads()))
        chunk_size = math.ceil(members / (CHUNKS_PER_WORKER * workers))
    chunk_size = max(1, check.integer_at_least("chunk_size", chunk_size, 1))
    return [(a, min(a + chunk_size, members)) for a in range(0, members, chunk_size)]


def map_members(function, members, *, args=(), client=None, chunk_size=None,
                progress: bool | None = None, label: str = "ensemble"):
    """``function(*members, *args)`` over a batch, here or on a Dask cluster, in order.

    Parameters
    ----------
    function : callable
        A module-level function (workers import it by name) taking the
        member arrays, then ``args``, and returning an array, or a tuple of
        arrays, whose first axis runs over the members given.
    members : tuple of ndarray, each shape (K, ...)
        The batch: ``K`` members, cut along the first axis.
    args : tuple
        The same for every chunk (the model, the step, ...), pickled with each.
    client : dask.distributed.Client, optional
        Compute on its cluster; without it, in this process, as one chunk.
    chunk_size : int, optional
        Members per chunk on a cluster; by default the batch is cut into
        ``CHUNKS_PER_WORKER`` chunks per worker.
    progress : bool, optional
        A progress bar over the chunks on a cluster (by default when there
        are more than ``CHUNKS_PER_WORKER`` chunks). Locally ``function``
        shows its own.
    label : str
        The progress bar's name.

    Returns
    -------
    ndarray or tuple of ndarray
        The chunks' results joined along their first axis: what
        ``function(*members, *args)`` returns.

    Examples
    --------
    >>> import numpy as np
    >>> map_members(np.add, (np.arange(3.0),), args=(1.0,))
    array([1., 2., 3.])
    """
    client = check_client(client)
    members = tuple(np.asarray(m) for m in members)
    count = len(members[0])
    if client is None or count == 0:
        return function(*members, *args)
    bounds = _chunk_bounds(count, client, chunk_size)
    futures = [client.submit(function, *(m[a:b] for m in members), *args, pure=False)
               for a, b in bounds]
    if progress or (progress is None and len(futures) > CHUNKS_PER_WORKER):
        from distributed import as_completed
        from tqdm.auto import tqdm

        for _ in tqdm(as_completed(futures), total=len(futures), desc=label, unit="chunk"):
            pass
    results = client.gather(futures)
    if isinstance(results[0], tuple):
        return tuple(np.concatenate(parts) for parts in zip(*results))
    return np.concatenate(results)
