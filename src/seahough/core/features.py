"""Image -> gradients -> edge points -> key points -> segments, in one call."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..config import Config
from .keypoints import (EdgePoints, chain_weight, find_edge_points, local_contrast,
                        select_keypoints)
from .preprocess import Gradients, compute_gradients
from .segments import Segments, trace_segments


@dataclass
class Features:
    """Everything the later stages need from one image at one working scale."""

    gradients: Gradients
    edges: EdgePoints
    index: np.ndarray
    keypoints: np.ndarray
    segments: Segments

    @property
    def shape(self) -> tuple[int, int]:
        return self.gradients.magnitude.shape


def extract_features(gray: np.ndarray, factor: float, config: Config,
                     n_keypoints: int | None = None, mask: np.ndarray | None = None,
                     weigh_colours: bool = False) -> Features:
    """Run the preprocessing stages on a float32 grey (or BGR) image.

    ``mask`` (working resolution, bool) limits the edge points, e.g. to a
    pattern's own pixels. ``weigh_colours``: a colour image's channels are
    weighed by its own gradient statistics (``Config.colour_boost``,
    :func:`.preprocess.colour_metric`): for searched images, whose texture
    hides an object's colour edges; a pattern's edges are all its own.
    """
    metric = config.colour_boost if weigh_colours else None
    grad = compute_gradients(gray, factor, config.equalize, metric)
    edges = find_edge_points(grad, config.min_gradient)
    if mask is not None and len(edges):
        edges = edges.take(mask[edges.iy, edges.ix])
    index = edges.index_map()
    strength = (local_contrast(edges, grad.magnitude, config.local_window)
                if config.local_contrast and len(edges) else None)
    if config.chain_length > 0 and len(edges):
        strength = chain_weight(edges, config.chain_length, index,
                                edges.magnitude if strength is None else strength)
    kp = select_keypoints(edges, n_keypoints or config.n_keypoints, strength)
    seg = trace_segments(edges, kp, config.segment_steps, config.segment_angle_tol,
                         config.max_segments, index)
    return Features(grad, edges, index, kp, seg)
