"""The Dask cluster a survey runs on: a local one by default, or one already running.

Both survey commands go through :func:`open_client`, so that a run on a
laptop and a run on a SLURM/PBS cluster (dask-jobqueue, see
``docs/scale.md``) differ only by ``scheduler``.
"""

from __future__ import annotations

import contextlib
import signal
import threading

from .._validate import check_workers
from ..errors import ParameterError

#: How long to wait for a scheduler given by address to answer.
CONNECT_TIMEOUT = "10s"


def _import_distributed():
    try:
        import distributed
    except ImportError:
        raise ParameterError("the survey commands need Dask: pip install 'seahough[survey]'") \
            from None
    return distributed


def _ignore_interrupt() -> None:
    """On a local cluster's worker: Ctrl-C is the client's to handle (it
    keeps what is done and stops the cluster); the workers, in the same
    process group of the terminal, would each print a traceback."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextlib.contextmanager
def open_client(workers: int | None = None, scheduler: str | None = None):
    """A ``distributed.Client`` for the duration of the context.

    Parameters
    ----------
    workers : int, optional
        Worker processes of the local cluster, one thread each (the kernels
        are single-threaded per call); default: all cores
        (:func:`seahough._validate.default_workers`). Ignored with ``scheduler``.
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
            client = distributed.Client(scheduler, timeout=CONNECT_TIMEOUT)
        except (OSError, TimeoutError, ValueError) as e:
            raise ParameterError(f"scheduler {scheduler}: cannot connect ({e})") from None
        try:
            yield client
        finally:
            client.close()
        return
    workers = check_workers(workers)
    import dask

    # processes, one thread each: the work holds the GIL in places (Python glue).
    # Without Dask's MALLOC_TRIM_THRESHOLD_ for its workers (a variable of the
    # user's own is kept): setting it fixes glibc's mmap threshold, so every
    # image's large arrays are mapped afresh and faulted in page by page
    # (measured: 15 % more time per 640x480 photo); the workers keep nothing
    # between images, and their memory stays flat without it (bench_survey.py)
    with dask.config.set({"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}):
        cluster = distributed.LocalCluster(n_workers=workers, threads_per_worker=1,
                                           processes=True, dashboard_address=":0",
                                           silence_logs=50)
    with cluster:
        with distributed.Client(cluster) as client:
            # (workers restarted later run it too)
            client.register_worker_callbacks(setup=_ignore_interrupt)
            yield client
