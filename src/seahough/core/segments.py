"""Stage 3: short edge segments traced along object borders from the key points."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import kernels as K
from .keypoints import EdgePoints


@dataclass
class Segments:
    """Short pieces of object borders.

    Each segment starts at a key point (``x``, ``y``) and runs along the edge
    to the ends (``x1``, ``y1``) and (``x2``, ``y2``). ``angle`` is the mean
    gradient direction along it (radians), which is more stable than one
    pixel's; ``length`` the number of steps traced; ``magnitude`` the key
    point's gradient; ``ids`` the key points' edge-point ids.
    """

    x: np.ndarray
    y: np.ndarray
    angle: np.ndarray
    x1: np.ndarray
    y1: np.ndarray
    x2: np.ndarray
    y2: np.ndarray
    length: np.ndarray
    magnitude: np.ndarray
    ids: np.ndarray

    def __len__(self) -> int:
        return int(self.x.shape[0])

    def take(self, sel) -> "Segments":
        """The segments at the indices or mask ``sel``."""
        return Segments(*(getattr(self, f)[sel] for f in self.__dataclass_fields__))


def trace_segments(edges: EdgePoints, keypoint_ids: np.ndarray, steps: int = 2,
                   angle_tol_deg: float = 30.0, max_segments: int = 10000,
                   index: np.ndarray | None = None) -> Segments:
    """Trace a segment along the edge from every key point.

    A key point from which the edge cannot be followed for at least two
    pixels (an isolated speck, noise) makes no segment, so only points on
    object borders vote. When there are more than ``max_segments``, the most
    contrasted are kept.

    Parameters
    ----------
    edges : EdgePoints
        All thinned edge points of the image.
    keypoint_ids : ndarray
        Ids of the key points to start from.
    steps : int
        Pixels traced on each side.
    angle_tol_deg : float
        Largest gradient-direction change between neighbouring points.
    index : ndarray, optional
        ``edges.index_map()`` if already computed.
    """
    if index is None:
        index = edges.index_map()
    seed, e1, e2, ang, ln = K.trace_segments(
        np.ascontiguousarray(keypoint_ids, np.int32), edges.ix, edges.iy, edges.angle,
        edges.nx, edges.ny, edges.magnitude, index, int(steps), math.radians(angle_tol_deg))
    mag = edges.magnitude[seed]
    if seed.size > max_segments:
        keep = np.sort(np.argpartition(-mag, max_segments - 1)[:max_segments])
        seed, e1, e2, ang, ln, mag = seed[keep], e1[keep], e2[keep], ang[keep], ln[keep], mag[keep]
    return Segments(edges.x[seed], edges.y[seed], ang, edges.x[e1], edges.y[e1],
                    edges.x[e2], edges.y[e2], ln, mag, seed)
