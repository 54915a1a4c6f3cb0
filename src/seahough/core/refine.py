"""Stage 6: score a candidate pose and refine it below one accumulator bin.

The pose is fitted by iteratively re-weighted least squares on matched edge
points: each pattern edge point, mapped by the pose, is paired with the
nearest image edge point of compatible direction, and the distance along the
image gradient (point-to-edge) is minimised. The similarity transform is
linear in (a, b, tx, ty) with a = scale cos(angle), b = scale sin(angle).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import kernels as K
from ..geometry import Similarity
from .keypoints import EdgePoints


#: A pose is a similarity: equation 1 as ``x'' = tx + a x' + b y'``,
#: ``y'' = ty - b x' + a y'`` (see :class:`seahough.geometry.Similarity`).
Pose = Similarity


@dataclass
class Fit:
    """A refined pose and how well the pattern's edges agree with the image."""

    pose: Pose
    score: float          # share of the pattern points matched within the radius
    matched: int
    rms: float            # rms point-to-edge distance of the matches (px)
    inside: float         # share of the pattern points that fall inside the image


def match(pose: Pose, vx, vy, vang, edges: EdgePoints, index: np.ndarray, radius: float,
          angle_tol: float, either: bool):
    """Matched edge id (-1 if none) and distance for each pattern point."""
    return K.match_points(vx, vy, vang, float(pose.a), float(pose.b), float(pose.tx),
                          float(pose.ty), edges.x, edges.y, edges.angle, index,
                          float(radius), float(angle_tol), bool(either))


def refine(pose: Pose, vx, vy, vang, edges: EdgePoints, index: np.ndarray, *,
           radii=(3.0, 2.0, 1.5), iterations: int = 8, angle_tol: float = math.radians(20),
           either: bool = False, fix_scale: bool = False, fix_angle: bool = False,
           score_radius: float = 1.5, min_scale: float = 1e-3, along: float = 0.02) -> Fit:
    """Refine ``pose`` with shrinking match radii, then score it.

    Each iteration matches every pattern point to the nearest image edge
    point of compatible direction within the radius and solves weighted
    least squares (Huber-like weights) for the similarity. The score is the
    share of the pattern points with such an edge within ``score_radius`` at
    the final pose. ``fix_scale``/``fix_angle`` keep a known quantity.
    The defaults are a call's of its own; a search passes its settings
    (``Config.angle_tolerance``, 15 degrees; ``SearchTuning.icp_iterations``,
    4 a radius; radii from about one bin to 1.25 px: docs/method.md).
    """
    a, b, tx, ty, score, matched, rms, inside = K.icp(
        vx, vy, vang, float(pose.a), float(pose.b), float(pose.tx), float(pose.ty),
        edges.x, edges.y, edges.angle, edges.nx, edges.ny, index, np.asarray(radii, np.float64),
        int(iterations), float(angle_tol), bool(either), bool(fix_scale), bool(fix_angle), float(along),
        float(score_radius), float(min_scale))
    return Fit(Pose(float(a), float(b), float(tx), float(ty)), float(score), int(matched),
               float(rms), float(inside))
