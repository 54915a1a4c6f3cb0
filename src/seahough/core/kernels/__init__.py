"""The hot loops, compiled with Numba (``cache=True`` wherever a cache can be
written), one module a stage. Everything else in the package is numpy/OpenCV.

- :mod:`.edges`: gradients in a band, edge points, their chains, segment tracing, spreading points
- :mod:`.voting`: the accumulator's votes and its local maxima
- :mod:`.matching`: point matching, snapping, ICP, the local vote over shifts
- :mod:`.evidence`: the a-contrario background model and a pose's counts
- :mod:`._common`: the direction test they share, and the conventions
- :mod:`._cache`: where the compiled kernels are cached (a private temporary
  folder when neither the package folder nor HOME can be written), seeded
  with the compiled kernels a wheel ships (``seahough._warmup``, run when
  ``pip install .`` builds the wheel)
"""

from ._cache import kernel_cache

with kernel_cache():
    from .edges import band_gradients, chain_lengths, edge_points, spread_points, trace_segments
    from .evidence import chance_coverage, evidence_counts
    from .matching import homography_icp, icp, match_points, shift_votes, snap_points
    from .voting import MODE_ORIENTED, MODE_POINTS, MODE_SEGMENTS, local_maxima, vote

__all__ = ["band_gradients", "chain_lengths", "edge_points", "spread_points", "trace_segments", "chance_coverage", "evidence_counts", "homography_icp", "icp",
           "match_points", "shift_votes",
           "snap_points", "MODE_ORIENTED", "MODE_POINTS", "MODE_SEGMENTS", "local_maxima", "vote"]
