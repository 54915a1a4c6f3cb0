"""Pose conventions: equation 1 of the paper, its 2x3 matrix, and equation 5.

Equation 1 maps pattern coordinates ``(x', y')`` (relative to the pattern
origin) to image coordinates ``(x'', y'')``::

    [x'', y'']^T = [dx, dy]^T + rho * [[cos phi,  sin phi],
                                       [-sin phi, cos phi]] @ [x', y']^T

Both frames have x to the right and y down, so a positive ``phi`` turns the
pattern counter-clockwise as the image is displayed.
"""

from __future__ import annotations

import math

import numpy as np


def rotation(angle_deg: float) -> np.ndarray:
    """The 2x2 matrix of equation 1 for ``angle_deg`` (no scale)."""
    a = math.radians(angle_deg)
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, s], [-s, c]])


def pose_to_matrix(x: float, y: float, scale: float, angle_deg: float,
                   origin: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
    """2x3 matrix mapping pattern-image pixels to image pixels.

    ``origin`` is where the pattern origin lies in the pattern image's pixel
    coordinates; ``(x, y)`` is where it lands in the image.

    Examples
    --------
    >>> m = pose_to_matrix(100, 50, 2.0, 90.0, origin=(10, 10))
    >>> apply_matrix(m, [[10, 10], [11, 10]]).round(6)
    array([[100.,  50.],
           [100.,  48.]])
    """
    a = scale * rotation(angle_deg)
    o = np.asarray(origin, dtype=float)
    t = np.array([x, y], dtype=float) - a @ o
    return np.hstack([a, t[:, None]])


def wrap360(angle_deg: float) -> float:
    """An angle in degrees brought into [0, 360).

    ``x % 360`` alone gives 360.0 for a tiny negative ``x`` (rounding).

    Examples
    --------
    >>> wrap360(-1e-20), wrap360(370.0)
    (0.0, 10.0)
    """
    a = float(angle_deg) % 360.0
    return 0.0 if a >= 360.0 else a


def matrix_to_pose(matrix: np.ndarray, origin: tuple[float, float] = (0.0, 0.0)
                   ) -> tuple[float, float, float, float]:
    """Inverse of :func:`pose_to_matrix` for a similarity matrix.

    Returns ``(x, y, scale, angle_deg)`` with the angle in [0, 360).
    """
    m = np.asarray(matrix, dtype=float)
    a, b = 0.5 * (m[0, 0] + m[1, 1]), 0.5 * (m[0, 1] - m[1, 0])
    scale = math.hypot(a, b)
    angle = wrap360(math.degrees(math.atan2(b, a)))
    x, y = m[:, :2] @ np.asarray(origin, dtype=float) + m[:, 2]
    return float(x), float(y), float(scale), float(angle)


def apply_matrix(matrix: np.ndarray, points) -> np.ndarray:
    """Map an (N, 2) array of (x, y) points through a 2x3 matrix."""
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    m = np.asarray(matrix, dtype=float)
    return p @ m[:, :2].T + m[:, 2]


def invert_matrix(matrix: np.ndarray) -> np.ndarray:
    """Inverse of a 2x3 affine matrix (as ``cv2.invertAffineTransform``)."""
    m = np.asarray(matrix, dtype=float)
    a_inv = np.linalg.inv(m[:, :2])
    return np.hstack([a_inv, (-a_inv @ m[:, 2])[:, None]])


def compose(second: np.ndarray, first: np.ndarray) -> np.ndarray:
    """The 2x3 matrix of applying ``first`` then ``second``."""
    a = np.vstack([np.asarray(first, float), [0, 0, 1]])
    b = np.vstack([np.asarray(second, float), [0, 0, 1]])
    return (b @ a)[:2]


def solve_segment_pair(p1, p2, q1, q2) -> tuple[float, float, float, float]:
    """Pose from one pattern segment (p1, p2) matched to an image segment (q1, q2).

    Equations 2-5 of the paper, with the sign of equation 5 corrected: with
    ``A = x'1 - x'2``, ``B = y'1 - y'2``, ``C = x''1 - x''2``, ``D = y''1 - y''2``::

        [rho cos phi, rho sin phi] = 1 / (A^2 + B^2) * [[A, B], [B, -A]] @ [C, D]

    (the paper prints ``-A^2 - B^2``). Returns ``(dx, dy, rho, phi_deg)``.

    Examples
    --------
    >>> solve_segment_pair((0, 0), (1, 0), (5, 5), (5, 3))
    (5.0, 5.0, 2.0, 90.0)
    """
    a, b = p1[0] - p2[0], p1[1] - p2[1]
    c, d = q1[0] - q2[0], q1[1] - q2[1]
    n = a * a + b * b
    if n == 0:
        raise ValueError("degenerate pattern segment: both ends coincide")
    rc = (a * c + b * d) / n
    rs = (b * c - a * d) / n
    rho = math.hypot(rc, rs)
    phi = wrap360(math.degrees(math.atan2(rs, rc)))
    dx = q1[0] - (rc * p1[0] + rs * p1[1])
    dy = q1[1] - (-rs * p1[0] + rc * p1[1])
    return float(dx), float(dy), float(rho), float(phi)


def angle_difference(a_deg: float, b_deg: float, period: float = 360.0) -> float:
    """Smallest signed difference ``a - b`` in degrees, modulo ``period``."""
    d = (a_deg - b_deg + period / 2) % period - period / 2
    return float(d)


def format_angle(degrees: float, decimals: int = 2, period: float = 360.0) -> str:
    """``degrees`` as text in ``[0, period)``, wrapped after rounding.

    A value that rounds up to the period is written as 0, so that a
    printed angle stays in the documented range.

    >>> format_angle(359.998), format_angle(359.998, 1), format_angle(179.97, 1, 180.0)
    ('0.00', '0.0', '0.0')
    >>> format_angle(-30.0), format_angle(12.345, 1)
    ('330.00', '12.3')
    """
    a = float(degrees)
    if not math.isfinite(a):
        return f"{a}"
    r = round(a % period, decimals)
    if r >= period:
        r -= period
    return f"{r + 0.0:.{decimals}f}"      # + 0.0: never "-0.00"
