"""The recognition core: image -> features -> votes -> poses -> detections.

Numpy arrays in (or image paths, read through :mod:`seahough.io`), dataclasses
out; no plotting, odometry or command line here.
One module a stage, in the order the data flows:

``blanks`` (letterbox bars, captions: not the scene) -> ``preprocess``
(working scale, Scharr gradients) -> ``keypoints`` (edge points, the most
contrasted key points) -> ``segments`` (short edge segments) -> ``features``
(all three in one call) ; ``pattern`` (the prepared model; ``shapes``,
``pattern_io``, ``symmetry``: drawn shapes, files, near turns) ->
``accumulator`` (voting, its planes) -> ``candidates`` (peaks, refined
candidate poses) -> ``refine`` (sub-bin ICP and score) -> ``ranking``
(full-resolution finish, runner-up, confidence; ``nfa``: the number of false
alarms) -> ``detector`` (the search that runs them; ``parts``: several
patterns at once); ``curves`` follows ropes piece by piece. The Numba hot
loops live in ``kernels``.
"""

import importlib as _importlib

#: The stages, importable as attributes (``seahough.core.detector``) on first access.
_STAGES = ("blanks", "preprocess", "keypoints", "segments", "features", "pattern", "shapes",
           "pattern_io", "symmetry", "accumulator", "candidates", "refine", "ranking", "nfa",
           "detector", "parts", "curves", "kernels")


def __getattr__(name: str):
    if name in _STAGES:
        return _importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
