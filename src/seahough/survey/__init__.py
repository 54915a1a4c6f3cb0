"""Surveys: thousands of photos over every core of a machine or a Dask cluster.

- :func:`seahough.survey.detect`: one pattern in many photos; results in
  Parquet, written in shards with a manifest (a rerun redoes nothing, an
  interrupted run continues).
- :func:`seahough.survey.odometry`: dead reckoning over a long sequence,
  pairs measured in parallel chunks and chained after.

Both need Dask (``pip install 'seahough[survey]'``) and run on a local
cluster of processes by default, or on a running cluster (``scheduler=``).
"""

from __future__ import annotations

__all__ = ["detect", "odometry"]


def __getattr__(name):
    # the two entry points load Dask and the search only when used
    if name == "detect":
        from .detect import detect
        return detect
    if name == "odometry":
        from .odometry import odometry
        return odometry
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
