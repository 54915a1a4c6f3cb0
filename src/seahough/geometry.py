"""Pose conventions: equation 1 of the paper, its 2x3 matrix, and equation 5.

Equation 1 maps pattern coordinates ``(x', y')`` (relative to the pattern
origin) to image coordinates ``(x'', y'')``::

    [x'', y'']^T = [dx, dy]^T + rho * [[cos phi,  sin phi],
                                       [-sin phi, cos phi]] @ [x', y']^T

Both frames have x to the right and y down, so a positive ``phi`` turns the
pattern counter-clockwise as the image is displayed.
"""

from __future__ import annotations

import cmath
import math
from dataclasses import dataclass

import numpy as np

from .errors import ParameterError


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


def wrap_angle(angle_deg: float, period: float = 360.0, low: float = 0.0) -> float:
    """An angle in degrees brought into ``[low, low + period)``.

    ``x % 360`` alone gives 360.0 for a tiny negative ``x`` (rounding); this
    never leaves the interval. ``low=-180`` gives the signed form used for
    motions, ``period=180`` the direction of a line.

    Examples
    --------
    >>> wrap_angle(-1e-20), wrap_angle(370.0), wrap_angle(190.0, low=-180.0)
    (0.0, 10.0, -170.0)
    >>> wrap_angle(200.0, period=180.0)
    20.0
    """
    a = (float(angle_deg) - low) % period
    if a >= period:
        a = 0.0
    return a + low


def wrap360(angle_deg: float) -> float:
    """:func:`wrap_angle` into [0, 360).

    Examples
    --------
    >>> wrap360(-1e-20), wrap360(370.0)
    (0.0, 10.0)
    """
    return wrap_angle(angle_deg)


def matrix_to_pose(matrix: np.ndarray, origin: tuple[float, float] = (0.0, 0.0)
                   ) -> tuple[float, float, float, float]:
    """Inverse of :func:`pose_to_matrix` for a similarity matrix.

    Returns ``(x, y, scale, angle_deg)`` with the angle in [0, 360).

    >>> [round(v, 6) for v in matrix_to_pose(pose_to_matrix(3, 4, 2.0, 30.0))]
    [3.0, 4.0, 2.0, 30.0]
    """
    m = np.asarray(matrix, dtype=float)
    a, b = 0.5 * (m[0, 0] + m[1, 1]), 0.5 * (m[0, 1] - m[1, 0])
    scale = math.hypot(a, b)
    angle = wrap360(math.degrees(math.atan2(b, a)))
    x, y = m[:, :2] @ np.asarray(origin, dtype=float) + m[:, 2]
    return float(x), float(y), float(scale), float(angle)


def apply_matrix(matrix: np.ndarray, points) -> np.ndarray:
    """Map an (N, 2) array of (x, y) points through a 2x3 matrix.

    >>> apply_matrix([[2, 0, 1], [0, 2, 0]], [[1, 1]])
    array([[3., 2.]])
    """
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    m = np.asarray(matrix, dtype=float)
    return p @ m[:, :2].T + m[:, 2]


def invert_matrix(matrix: np.ndarray) -> np.ndarray:
    """Inverse of a 2x3 affine matrix (as ``cv2.invertAffineTransform``).

    >>> invert_matrix([[2, 0, 4], [0, 2, 0]])
    array([[ 0.5,  0. , -2. ],
           [ 0. ,  0.5,  0. ]])
    """
    m = np.asarray(matrix, dtype=float)
    a_inv = np.linalg.inv(m[:, :2])
    return np.hstack([a_inv, (-a_inv @ m[:, 2])[:, None]])


def compose(second: np.ndarray, first: np.ndarray) -> np.ndarray:
    """The 2x3 matrix of applying ``first`` then ``second``.

    >>> compose([[1, 0, 5], [0, 1, 0]], [[2, 0, 0], [0, 2, 0]])
    array([[2., 0., 5.],
           [0., 2., 0.]])
    """
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
        raise ParameterError("degenerate pattern segment: both ends coincide")
    rc = (a * c + b * d) / n
    rs = (b * c - a * d) / n
    rho = math.hypot(rc, rs)
    phi = wrap360(math.degrees(math.atan2(rs, rc)))
    dx = q1[0] - (rc * p1[0] + rs * p1[1])
    dy = q1[1] - (-rs * p1[0] + rc * p1[1])
    return float(dx), float(dy), float(rho), float(phi)


def angle_difference(a_deg: float, b_deg: float, period: float = 360.0) -> float:
    """Smallest signed difference ``a - b`` in degrees, modulo ``period``.

    >>> angle_difference(350.0, 10.0), angle_difference(10.0, 170.0, period=180.0)
    (-20.0, 20.0)
    """
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


def format_line(angle: float, offset: float, decimals: int = 2) -> tuple[str, float]:
    """A line's direction as text in ``[0, 180)`` (:func:`format_angle`)
    and its offset to show beside it: a direction that rounds up to 180 is
    written 0, and the offset, measured along the normal
    ``(sin a, cos a)``, which turns with it, changes sign.

    >>> format_line(179.97, 35.0, 1), format_line(12.0, 35.0, 1)
    (('0.0', -35.0), ('12.0', 35.0))
    """
    text = format_angle(angle, decimals, 180.0)
    wrapped = math.isfinite(angle) and round(float(angle) % 180.0, decimals) >= 180.0
    return text, (-float(offset) if wrapped else float(offset))


def line_parameters(x: float, y: float, angle_deg: float, shape) -> tuple[float, float, float, float]:
    """(line_angle, line_offset, foot_x, foot_y) of the line through (x, y) at
    ``angle_deg``, relative to the centre of an image of ``shape``.

    Examples
    --------
    >>> [round(v, 6) for v in line_parameters(10.0, 30.0, 180.0, (41, 61))]
    [0.0, 10.0, 30.0, 30.0]
    """
    h, w = shape[:2]
    cx, cy = (w - 1) / 2.0, (h - 1) / 2.0
    a = angle_deg % 180.0
    if a > 180.0 - 1e-6:     # (179.9999999999999: 0, its normal turned with it)
        a = 0.0
    t = math.radians(a)
    n = np.array([math.sin(t), math.cos(t)])    # normal
    off = float(n @ (np.array([x, y]) - [cx, cy]))
    fx, fy = cx + off * n[0], cy + off * n[1]
    return a, off, float(fx), float(fy)


def matrix_power(matrix, t: float) -> np.ndarray:
    """A similarity's 2x3 matrix applied ``t`` times (any real ``t``: roots
    too), taken exactly from its first column (:meth:`Similarity.from_columns`).

    >>> matrix_power([[0, 1, 0], [-1, 0, 0]], 0.5).round(6) + 0.0   # half of a quarter turn
    array([[ 0.707107,  0.707107,  0.      ],
           [-0.707107,  0.707107,  0.      ]])
    """
    return Similarity.from_columns(matrix).power(t).matrix


def nearest_similarity(matrix) -> np.ndarray:
    """The 2x3 matrix of the similarity nearest to a 2x3 matrix (averages
    out the rounding asymmetry that products of similarities pick up).

    >>> nearest_similarity([[1.0, 0.2, 5.0], [-0.2, 1.0002, 0.0]]).round(4)
    array([[ 1.0001,  0.2   ,  5.    ],
           [-0.2   ,  1.0001,  0.    ]])
    """
    return Similarity.from_matrix(matrix).matrix


def fit_similarity(p, q) -> np.ndarray:
    """The similarity (2x3, no reflection) that brings the points ``p`` onto
    ``q`` (N x 2 each) best in the least-squares sense.

    >>> m = pose_to_matrix(5.0, -2.0, 1.5, 30.0)
    >>> p = np.array([[0.0, 0.0], [10.0, 0.0], [3.0, 7.0]])
    >>> bool(np.allclose(fit_similarity(p, apply_matrix(m, p)), m))
    True
    """
    p, q = np.asarray(p, np.float64), np.asarray(q, np.float64)
    mp, mq = p.mean(0), q.mean(0)
    a, b = p - mp, q - mq
    s_xx = (a ** 2).sum()
    c = (a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1]).sum() / s_xx
    s = (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]).sum() / s_xx
    r = np.array([[c, -s], [s, c]])
    return np.hstack([r, (mq - r @ mp)[:, None]])


def shift_origin(matrix, ox: float, oy: float) -> np.ndarray:
    """A 2x3 matrix seen in coordinates whose origin is at ``(ox, oy)``:
    ``T(-o) M T(o)`` (e.g. a motion measured on crops that start at ``o``
    is ``shift_origin(m, -ox, -oy)`` in whole-frame pixels).

    >>> shift_origin([[2, 0, 0], [0, 2, 0]], 10, 0)
    array([[ 2.,  0., 10.],
           [ 0.,  2.,  0.]])
    """
    m = np.asarray(matrix, dtype=float)
    o = np.array([ox, oy], float)
    t = m[:, :2] @ o + m[:, 2] - o
    return np.hstack([m[:, :2], t[:, None]])


def _clip_area(poly: np.ndarray, x0: float, y0: float, x1: float, y1: float) -> float:
    """Area of a convex polygon (K, 2) clipped to the box ``x0..x1, y0..y1``
    (Sutherland-Hodgman, one box side at a time)."""
    pts = [tuple(p) for p in poly]
    for axis, bound, keep_low in ((0, x0, False), (0, x1, True), (1, y0, False), (1, y1, True)):
        out = []
        for k, p in enumerate(pts):
            q = pts[k - 1]
            p_in = p[axis] <= bound if keep_low else p[axis] >= bound
            q_in = q[axis] <= bound if keep_low else q[axis] >= bound
            if p_in != q_in:
                t = (bound - q[axis]) / (p[axis] - q[axis])
                out.append((q[0] + t * (p[0] - q[0]), q[1] + t * (p[1] - q[1])))
            if p_in:
                out.append(p)
        pts = out
        if not pts:
            return 0.0
    x, y = np.array(pts).T
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def overlap(matrix, width: int, height: int) -> float:
    """Share of a ``width`` x ``height`` frame that the 2x3 ``matrix`` maps
    inside an equally sized frame (exact: the mapped frame clipped to the
    frame, over its area; a frame covers ``-0.5 .. width - 0.5``).

    >>> overlap([[1, 0, 0], [0, 1, 0]], 64, 48), overlap([[1, 0, 32], [0, 1, 0]], 64, 48)
    (1.0, 0.5)
    >>> overlap([[1, 0, 1e-9], [0, 1, 1e-9]], 384, 288), overlap([[1, 0, 6], [0, 1, 0]], 384, 288)
    (1.0, 0.984375)
    """
    m = np.asarray(matrix, dtype=float)
    det = abs(float(np.linalg.det(m[:2, :2])))
    if not det > 0 or width <= 0 or height <= 0:
        return 0.0
    x0, y0, x1, y1 = -0.5, -0.5, width - 0.5, height - 0.5
    quad = apply_matrix(m, [[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    if not np.isfinite(quad).all():
        return 0.0
    return round(min(1.0, _clip_area(quad, x0, y0, x1, y1) / (det * width * height)), 9)


def corner_gap(a, b, shape) -> float:
    """The largest distance between where two matrices (2x3 affine or 3x3
    homographies) put the corners of a frame of ``shape`` (height, width).

    >>> corner_gap([[1, 0, 0], [0, 1, 0]], [[1, 0, 3], [0, 1, 4]], (48, 64))
    5.0
    """
    h, w = shape[:2]
    c = np.array([[0, 0, 1], [w - 1, 0, 1], [w - 1, h - 1, 1], [0, h - 1, 1]], float)

    def at(m):
        m = np.asarray(m, float)
        q = c @ (m if m.shape == (3, 3) else np.vstack([m[:2], [0.0, 0.0, 1.0]])).T
        return q[:, :2] / q[:, 2:]

    return float(np.hypot(*(at(a) - at(b)).T).max())


@dataclass(frozen=True)
class Similarity:
    """A similarity transform: equation 1 of the paper, as a value.

    ``x'' = tx + a x' + b y'`` and ``y'' = ty - b x' + a y'``, with
    ``a = scale cos(angle)``, ``b = scale sin(angle)``: a positive angle
    turns counter-clockwise as displayed (x right, y down). The same
    transform is the 2x3 matrix ``[[a, b, tx], [-b, a, ty]]`` (as OpenCV's
    ``warpAffine`` takes it) and, on ``z = x + i y``, ``z -> (a - i b) z + t``.
    This module is the only place where the arithmetic of such transforms
    is written: poses are Similarity values, and the 2x3 matrices of pair
    motions and trajectories go through its functions.

    Examples
    --------
    >>> s = Similarity.from_pose(10.0, 0.0, 2.0, 90.0)
    >>> s.apply([[1.0, 0.0]]).round(6)
    array([[10., -2.]])
    >>> s.compose(s.inverse()).matrix.round(9) + 0.0
    array([[1., 0., 0.],
           [0., 1., 0.]])
    >>> half = s.power(0.5)
    >>> round(half.scale, 6), round(half.angle, 6)
    (1.414214, 45.0)
    >>> bool(np.allclose(half.compose(half).matrix, s.matrix))
    True
    """

    a: float
    b: float
    tx: float
    ty: float

    # ------------------------------------------------------------ construction
    @classmethod
    def identity(cls) -> "Similarity":
        return cls(1.0, 0.0, 0.0, 0.0)

    @classmethod
    def from_params(cls, tx: float, ty: float, scale: float, angle_rad: float) -> "Similarity":
        """From the translation, the scale and the angle in radians."""
        return cls(scale * math.cos(angle_rad), scale * math.sin(angle_rad), tx, ty)

    @classmethod
    def from_pose(cls, x: float, y: float, scale: float, angle_deg: float,
                  origin=(0.0, 0.0)) -> "Similarity":
        """The transform that puts ``origin`` at ``(x, y)`` (see :func:`pose_to_matrix`)."""
        return cls.from_matrix(pose_to_matrix(x, y, scale, angle_deg, origin))

    @classmethod
    def from_matrix(cls, matrix) -> "Similarity":
        """The nearest similarity to a 2x3 matrix (averages out rounding
        asymmetry); its 6 numbers in a row (a Parquet table's ``matrix``) or a
        3x3 one whose last row is 0, 0, 1 are taken too.

        >>> s = Similarity.from_matrix([1.0, 0.0, 5.0, 0.0, 1.0, 7.0])
        >>> s.tx, s.ty, s.scale
        (5.0, 7.0, 1.0)
        """
        m = _matrix23(matrix)
        return cls(float(0.5 * (m[0, 0] + m[1, 1])), float(-0.5 * (m[1, 0] - m[0, 1])),
                   float(m[0, 2]), float(m[1, 2]))

    @classmethod
    def from_columns(cls, matrix) -> "Similarity":
        """The similarity whose first column is the 2x3 ``matrix``'s
        (``a = m[0, 0]``, ``b = -m[1, 0]``) and whose translation is its
        last: exact for a matrix that already is a similarity, where
        :meth:`from_matrix` would average away rounding."""
        m = _matrix23(matrix)
        return cls(float(m[0, 0]), float(-m[1, 0]), float(m[0, 2]), float(m[1, 2]))

    # ------------------------------------------------------------------ reading
    @property
    def scale(self) -> float:
        return math.hypot(self.a, self.b)

    @property
    def angle(self) -> float:
        """Degrees in [0, 360), counter-clockwise as displayed."""
        return wrap360(math.degrees(math.atan2(self.b, self.a)))

    @property
    def matrix(self) -> np.ndarray:
        """The 2x3 matrix ``[[a, b, tx], [-b, a, ty]]``."""
        return np.array([[self.a, self.b, self.tx], [-self.b, self.a, self.ty]])

    def to_pose(self, origin=(0.0, 0.0)) -> tuple[float, float, float, float]:
        """``(x, y, scale, angle_deg)``: where ``origin`` lands, and the rest."""
        x, y = self.map(float(origin[0]), float(origin[1]))
        return float(x), float(y), self.scale, self.angle

    # ---------------------------------------------------------------- applying
    def map(self, x, y):
        """Map coordinates (scalars or arrays) ``x, y`` -> ``(x'', y'')``."""
        x = np.asarray(x, float)
        y = np.asarray(y, float)
        return self.tx + self.a * x + self.b * y, self.ty - self.b * x + self.a * y

    def apply(self, points) -> np.ndarray:
        """Map an (N, 2) array of (x, y) points (one point: a pair)."""
        p = np.asarray(points, dtype=float)
        if p.ndim == 3 and p.shape[1] == 1:   # (OpenCV's contours: (N, 1, 2))
            p = p[:, 0]
        if p.size and (p.shape[-1:] != (2,) or p.ndim > 2):
            raise ParameterError(f"points: expected (x, y) points, an (N, 2) array, got an "
                                 f"array of shape {p.shape}")
        p = p.reshape(-1, 2)
        x, y = self.map(p[:, 0], p[:, 1])
        return np.stack([x, y], 1)

    def overlap(self, width: int, height: int) -> float:
        """See :func:`overlap`."""
        return overlap(self.matrix, width, height)

    # ------------------------------------------------------------------ algebra
    def _complex(self) -> tuple[complex, complex]:
        return complex(self.a, -self.b), complex(self.tx, self.ty)

    @classmethod
    def _from_complex(cls, c: complex, t: complex) -> "Similarity":
        return cls(c.real, -c.imag, t.real, t.imag)

    def compose(self, first: "Similarity") -> "Similarity":
        """Apply ``first`` (a Similarity, or its 2x3 matrix), then this one."""
        if not isinstance(first, Similarity):
            if isinstance(first, (np.ndarray, list, tuple)):
                first = Similarity.from_matrix(first)
            else:
                raise ParameterError(f"compose: expected a Similarity or a 2x3 matrix, got "
                                     f"{type(first).__name__}")
        c2, t2 = self._complex()
        c1, t1 = first._complex()
        return self._from_complex(c2 * c1, c2 * t1 + t2)

    def inverse(self) -> "Similarity":
        c, t = self._complex()
        if c == 0:
            raise ParameterError(f"{self}: a similarity of scale 0 has no inverse")
        return self._from_complex(1 / c, -t / c)

    def power(self, t: float) -> "Similarity":
        """This transform applied ``t`` times (any real ``t``: roots too)."""
        c, b = self._complex()
        if t == 1:
            return self
        ct = cmath.exp(t * cmath.log(c)) if c != 0 else 0j
        bt = b * t if abs(c - 1) < 1e-12 else b * (1 - ct) / (1 - c)
        return self._from_complex(ct, bt)

    def shifted(self, ox: float, oy: float) -> "Similarity":
        """The same transform in coordinates whose origin is at ``(ox, oy)``:
        ``T(-o) S T(o)`` (e.g. a motion measured on crops of a frame)."""
        return Similarity.from_columns(shift_origin(self.matrix, ox, oy))


def clip_polyline_ends(points, width: int, height: int) -> np.ndarray:
    """A polyline ``points`` (n x 2) with an end point outside the image
    (``width`` x ``height`` px, pixel centres 0 to w - 1) moved back along
    its last segment to where that crosses the border (a rope leaving the
    frame: clipping each coordinate alone moved the end 12 px along the
    border); any other point outside is clipped.

    >>> clip_polyline_ends([[600.0, 50.0], [620.0, 1.4], [650.0, -4.7]], 640, 480).round(1)
    array([[600. ,  50. ],
           [620. ,   1.4],
           [626.9,   0. ]])
    """
    p = np.array(points, float).reshape(-1, 2)
    hi = np.array([width - 1.0, height - 1.0])
    for end, inner in ((0, 1), (len(p) - 1, len(p) - 2)):
        if len(p) < 2 or ((p[end] >= 0).all() and (p[end] <= hi).all()):
            continue
        a, b = p[inner], p[end]
        if not ((a >= 0).all() and (a <= hi).all()):
            continue
        d = b - a
        t = 1.0
        for k in range(2):   # (the largest step along a -> b that stays inside)
            if d[k] > 0:
                t = min(t, (hi[k] - a[k]) / d[k])
            elif d[k] < 0:
                t = min(t, -a[k] / d[k])
        p[end] = a + max(t, 0.0) * d
    return np.clip(p, 0.0, hi)


def _matrix23(matrix) -> np.ndarray:
    """A 2x3 matrix from a 2x3 one, its 6 numbers in a row, or a 3x3 one
    whose last row is 0, 0, 1; a ParameterError naming the shape otherwise."""
    try:
        m = np.asarray(matrix, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"matrix: expected a 2x3 matrix of numbers, got "
                             f"{type(matrix).__name__}") from None
    if m.shape == (6,):
        m = m.reshape(2, 3)
    elif m.shape == (3, 3) and np.allclose(m[2], (0.0, 0.0, 1.0)):
        m = m[:2]
    if m.shape != (2, 3):
        raise ParameterError(f"matrix: expected a 2x3 matrix (or its 6 numbers), got an "
                             f"array of shape {m.shape}")
    return m


def frame_centre(shape) -> np.ndarray:
    """``(x, y)`` of the centre of an image of ``shape`` (height, width, ...):
    ``((w - 1) / 2, (h - 1) / 2)``, as pixel (0, 0) is the centre of the
    top-left pixel.

    >>> frame_centre((480, 640)).tolist()
    [319.5, 239.5]
    """
    h, w = shape[:2]
    return np.array([(w - 1) / 2.0, (h - 1) / 2.0])
