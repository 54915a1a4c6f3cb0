"""The Dask cluster a survey runs on: a local one by default, or one already running.

Both survey commands go through :func:`open_client`, so that a run on a
laptop and a run on a SLURM/PBS cluster (dask-jobqueue, see
``docs/scale.md``) differ only by ``scheduler``.
"""

from __future__ import annotations

import contextlib
import os

from ..errors import ParameterError


def default_workers() -> int:
    """All the cores this process may use (the CPU affinity mask where the OS has one)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - macOS, Windows
        return max(1, os.cpu_count() or 1)


def _import_distributed():
    try:
        import distributed
    except ImportError:
        raise ParameterError("the survey commands need Dask: pip install 'seahough[survey]'") \
            from None
    return distributed


@contextlib.contextmanager
def open_client(workers: int | None = None, scheduler: str | None = None):
    """A ``distributed.Client`` for the duration of the context.

    Parameters
    ----------
    workers : int, optional
        Worker processes of the local cluster, one thread each (the kernels
        are single-threaded per call); default :func:`default_workers`.
        Ignored with ``scheduler``.
    scheduler : str, optional
        Address of a running scheduler (``tcp://host:8786``, or a
        ``dask-jobqueue`` cluster's ``scheduler_address``); the cluster is
        left running after.

    Yields
    ------
    distributed.Client

    Raises
    ------
    ParameterError
        Dask is not installed, ``workers`` is not a positive integer, or no
        scheduler answers at ``scheduler``.
    """
    distributed = _import_distributed()
    if scheduler is not None:
        try:
            client = distributed.Client(scheduler, timeout="10s")
        except (OSError, TimeoutError, ValueError) as e:
            raise ParameterError(f"scheduler {scheduler}: cannot connect ({e})") from None
        try:
            yield client
        finally:
            client.close()
        return
    if workers is None:
        workers = default_workers()
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ParameterError(f"workers must be a positive integer, got {workers!r}")
    # processes, one thread each: the work holds the GIL in places (Python glue)
    with distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                  dashboard_address=None, silence_logs=50) as cluster:
        with distributed.Client(cluster) as client:
            yield client
