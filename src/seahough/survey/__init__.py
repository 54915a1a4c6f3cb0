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

# Imported here, not on first use: importing a submodule binds its name on
# the package, so ``seahough.survey.detect`` would be the module after the
# first ``import seahough.survey.detect``; these bind the functions after it.
# (``importlib.import_module("seahough.survey.detect")`` gives the module.)
from .detect import detect
from .odometry import odometry

__all__ = ["detect", "odometry"]
