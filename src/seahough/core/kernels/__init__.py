"""The hot loops, compiled with Numba (``cache=True``), one module a stage.
Everything else in the package is numpy/OpenCV.

- :mod:`.edges`: edge points, segment tracing, spreading points
- :mod:`.voting`: the accumulator's votes and its local maxima
- :mod:`.matching`: point matching, snapping, ICP
- :mod:`._common`: the direction test they share, and the conventions
"""

from .edges import edge_points, spread_points, trace_segments
from .matching import icp, match_points, snap_points
from .voting import MODE_ORIENTED, MODE_POINTS, MODE_SEGMENTS, local_maxima, vote

__all__ = ["edge_points", "spread_points", "trace_segments", "icp", "match_points",
           "snap_points", "MODE_ORIENTED", "MODE_POINTS", "MODE_SEGMENTS", "local_maxima", "vote"]
