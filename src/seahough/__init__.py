"""seahough: find objects in underwater photos by the shape of their edges.

A pattern (a marker, a rope, a seabed photo...) is found at unknown
position, scale and rotation by voting pattern/image edge pairs into a 4-D
accumulator over offset, scale and rotation (Hough-like); the peak is the
object and its height the evidence. With the previous frame as the pattern,
the peak is the vehicle's motion (photo dead reckoning).

>>> import seahough
>>> pattern = seahough.Pattern.rectangle(60, 40)
>>> detector = seahough.Detector(pattern, scale_range=(0.5, 2.0))
"""

from .config import Config
from .core.detector import Detection, Detector, SearchResult
from .errors import (ImageError, ImageReadError, ImageSizeError, ImageValueError,
                     ParameterError, PatternError, SeahoughError, WriteError)
from .geometry import Similarity, matrix_to_pose, pose_to_matrix, solve_segment_pair
from .io.frames import list_frames
from .io.images import read_image, to_gray
from .motion import Motion, OdometryResult, estimate_motion, run_odometry
from .core.pattern import Pattern

__version__ = "0.1.0"

__all__ = [
    "Config", "Detection", "Detector", "SearchResult", "Pattern", "Motion", "estimate_motion",
    "run_odometry", "list_frames", "OdometryResult",
    "Similarity", "pose_to_matrix", "matrix_to_pose", "solve_segment_pair", "read_image", "to_gray",
    "SeahoughError", "ImageError", "ImageReadError", "ImageSizeError", "ImageValueError",
    "ParameterError", "PatternError", "WriteError", "__version__",
]
