"""The recognition core: image -> features -> votes -> poses -> detections.

Numpy arrays in (or image paths, read through :mod:`seahough.io`), dataclasses
out; no plotting, odometry or command line here.
One module a stage, in the order the data flows:

``preprocess`` (working scale, Scharr gradients) -> ``keypoints`` (edge points,
the most contrasted key points) -> ``segments`` (short edge segments) ->
``features`` (all three in one call) ; ``pattern`` (the prepared model) ->
``accumulator`` (voting, its planes) -> ``candidates`` (peaks, refined
candidate poses) -> ``refine`` (sub-bin ICP and score) -> ``ranking``
(full-resolution finish, runner-up, confidence) -> ``detector`` (the search
that runs them). The Numba hot loops live in ``kernels``.
"""

import importlib as _importlib

#: The stages, importable as attributes (``seahough.core.detector``) on first access.
_STAGES = ("preprocess", "keypoints", "segments", "features", "pattern", "accumulator",
           "candidates", "refine", "ranking", "detector", "kernels")


def __getattr__(name: str):
    if name in _STAGES:
        return _importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
