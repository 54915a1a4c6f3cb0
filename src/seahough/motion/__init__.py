"""Photo motion: one frame pair (:mod:`.pair`) and whole dives (:mod:`.odometry`)."""

from .pair import MOTION_CONFIG, Motion, estimate_motion
from .odometry import OdometryResult, run_odometry

__all__ = ["MOTION_CONFIG", "Motion", "estimate_motion", "OdometryResult", "run_odometry"]
