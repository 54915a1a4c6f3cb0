"""Photo motion: one frame pair, and whole dives.

- :mod:`.pair`: :func:`estimate_motion`, the one way to measure a pair (and
  :func:`measure_motion`: the same, with why there is no motion)
- :mod:`.result`: :class:`Motion`, :class:`MotionResult`
- :mod:`.odometry`: :func:`run_odometry`, a whole sequence, row by row to a CSV
- :mod:`.odometer`: :class:`Odometer`, one frame at a time (a camera's stream), and the
  keyframe / prior / fallback policy both follow
- :mod:`.state`: what the next frame needs (rebuilt from the rows on resume)
- :mod:`.track`: the CSV rows, the summary, :class:`OdometryResult`
- :mod:`.runfiles`: the output folder: one run at a time, what ``resume`` checks
- :mod:`.mosaic`: frames placed by the trajectory
"""

from ..config import MOTION_CONFIG, ODOMETRY_CONFIG, OdometryTuning
from .odometer import Odometer
from .odometry import run_odometry
from .pair import Motion, estimate_motion, measure_motion
from .result import MotionResult
from .track import OdometryResult, read_odometry_csv

__all__ = ["MOTION_CONFIG", "ODOMETRY_CONFIG", "OdometryTuning", "Motion", "MotionResult",
           "estimate_motion", "measure_motion",
           "OdometryResult", "Odometer", "read_odometry_csv", "run_odometry"]
