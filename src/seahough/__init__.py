"""seahough: find objects in underwater photos by the shape of their edges.

A pattern (a marker, a rope, a seabed photo...) is found at unknown
position, scale and rotation by voting pattern/image edge pairs into a 4-D
accumulator over offset, scale and rotation (Hough-like); the peak is the
object and its height the evidence. With the previous frame as the pattern,
the peak is the vehicle's motion (photo dead reckoning).

>>> import seahough
>>> pattern = seahough.Pattern.rectangle(60, 40)
>>> detector = seahough.Detector(pattern, scale_range=(0.5, 2.0))

The public names are loaded on first use (PEP 562), so that ``import
seahough`` and ``seahough --help`` load neither Numba, OpenCV nor
matplotlib; ``from seahough import Detector`` and ``seahough.Detector``
work as usual, and so do the subpackages (``seahough.survey.detect``).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

__version__ = "0.1.0"

#: Public name -> the module (relative to this package) that defines it.
_WHERE = {
    "Config": ".config", "OdometryTuning": ".config", "SearchTuning": ".config",
    "Detection": ".core.detector", "Detector": ".core.detector", "SearchResult": ".core.detector",
    "Pattern": ".core.pattern",
    "Curve": ".core.curves", "find_curves": ".core.curves",
    "Motion": ".motion", "estimate_motion": ".motion", "run_odometry": ".motion",
    "OdometryResult": ".motion", "Odometer": ".motion", "measure_motion": ".motion",
    "MotionResult": ".motion",
    "list_frames": ".io.frames", "iter_frames": ".io.frames", "read_image": ".io.images",
    "to_gray": ".io.images",
    "Similarity": ".geometry", "pose_to_matrix": ".geometry", "matrix_to_pose": ".geometry",
    "solve_segment_pair": ".geometry",
    "SeahoughError": ".errors", "ImageError": ".errors", "ImageReadError": ".errors",
    "ImageSizeError": ".errors", "ImageValueError": ".errors", "ParameterError": ".errors",
    "PatternError": ".errors", "WriteError": ".errors", "BitDepthWarning": ".errors",
    "LevelsWarning": ".errors",
}

#: Subpackages and modules reachable as attributes without importing them
#: first (``seahough.survey.detect(...)`` after a bare ``import seahough``).
_SUBMODULES = ("cli", "config", "core", "demo", "errors", "geometry", "io", "motion", "sim",
               "survey", "viz")

__all__ = [
    "Config", "Detection", "Detector", "SearchResult", "Pattern", "Motion", "estimate_motion",
    "measure_motion", "MotionResult", "run_odometry", "Odometer", "list_frames", "iter_frames", "OdometryResult", "OdometryTuning",
    "SearchTuning",
    "Similarity", "pose_to_matrix", "matrix_to_pose", "solve_segment_pair", "read_image", "to_gray",
    "SeahoughError", "ImageError", "ImageReadError", "ImageSizeError", "ImageValueError",
    "ParameterError", "PatternError", "WriteError", "BitDepthWarning", "LevelsWarning",
    "__version__",
    "Curve", "find_curves",
]


def __getattr__(name: str):
    """A public name or a subpackage, imported on first access and kept."""
    where = _WHERE.get(name)
    if where is not None:
        value = getattr(importlib.import_module(where, __name__), name)
    elif name in _SUBMODULES:
        value = importlib.import_module(f".{name}", __name__)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    # kept as a plain attribute: later accesses do not come back here. (No
    # public name is also a submodule's name, so importing a submodule never
    # overwrites a public name with the module.)
    globals()[name] = value
    return value


#: This module's own helpers, not the package's API (left out of ``dir()``).
_PLUMBING = frozenset({"TYPE_CHECKING", "annotations", "importlib"})


def __dir__() -> list[str]:
    own = {n for n in globals() if not n.startswith("_") and n not in _PLUMBING}
    return sorted(own | set(__all__) | set(_SUBMODULES) | {"__version__"})


if TYPE_CHECKING:  # pragma: no cover - for type checkers and IDEs only
    from .config import Config, OdometryTuning, SearchTuning
    from .core.detector import Detection, Detector, SearchResult
    from .core.pattern import Pattern
    from .core.curves import Curve, find_curves
    from .errors import (BitDepthWarning, ImageError, ImageReadError, ImageSizeError,
                         ImageValueError, LevelsWarning, ParameterError, PatternError,
                         SeahoughError, WriteError)
    from .geometry import Similarity, matrix_to_pose, pose_to_matrix, solve_segment_pair
    from .io.frames import iter_frames, list_frames
    from .io.images import read_image, to_gray
    from .motion import (Motion, MotionResult, Odometer, OdometryResult, estimate_motion,
                         measure_motion, run_odometry)
