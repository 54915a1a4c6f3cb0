"""What the kernels share: the direction test, a pattern point placed by a
pose, and 2 pi.

Conventions of every kernel: angles in radians; a gradient angle is
``atan2(gy, gx)`` in [0, 2 pi); equation 1 maps a pattern point p to
``t + rho R(phi) p`` with ``R(phi) = [[cos, sin], [-sin, cos]]``, which turns
a pattern gradient of angle ``a`` into an image gradient of angle ``a - phi``.
"""

from __future__ import annotations

import math

from numba import njit

from ._cache import CACHE

TWO_PI = 2.0 * math.pi


@njit(cache=CACHE, nogil=True, inline="always")
def _same_direction(a, b, tol, either):
    """Do directions ``a`` and ``b`` (radians, both in [0, 2 pi)) differ by at
    most ``tol`` (``either``: or by pi plus at most ``tol``)? Their difference
    wraps with one comparison (``fmod`` was a fifth of the ICP's time)."""
    da = a - b
    if da >= math.pi:
        da -= TWO_PI
    elif da < -math.pi:
        da += TWO_PI
    if either:
        if da > 0.5 * math.pi:
            da -= math.pi
        elif da < -0.5 * math.pi:
            da += math.pi
    return abs(da) <= tol


@njit(cache=CACHE, nogil=True, inline="always")
def _placed(px, py, pang, a, b, tx, ty, phi):
    """A pattern point (``px, py``, gradient ``pang``) mapped by the pose
    (equation 1; ``phi = atan2(b, a)``): ``(x, y, want)``, ``want`` the image
    gradient direction it wants, in [0, 2 pi) as the edges' are
    (_same_direction)."""
    want = pang - phi
    want -= TWO_PI * math.floor(want / TWO_PI)
    return tx + a * px + b * py, ty - b * px + a * py, want
