"""Kernels of the a-contrario decision (:mod:`seahough.core.nfa`): the
background model's chance of a match, and a pose's counts."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._cache import CACHE
from ._common import TWO_PI, _placed


@njit(cache=CACHE, nogil=True)
def chance_coverage(ex, ey, eang, index, ox, oy, h, w, radius, tol, nbins, cell, stride):
    """The a-contrario background model (:mod:`seahough.core.nfa`): how
    much of each place a chance match can hit, in the box of ``h`` x ``w``
    pixels whose top-left pixel is (ox, oy) (coordinates below are relative
    to it). The edge points are found through ``index`` (pixel -> edge id,
    -1: none), so that the cost follows the box, not the image.

    Sample positions are the pixel centres whose coordinates are multiples
    of ``stride``. The ``nbins`` directions (<= 32) are the centres of as
    many equal bins of [0, 2 pi). For each cell of ``cell`` x ``cell``
    pixels (a multiple of ``stride``) and each direction, the share of the
    sample positions of the 3 x 3 cells around it that lie within ``radius``
    of an edge point whose direction is within ``tol`` of it: the chance
    that a point placed there at random, wanting that direction, finds a
    match. Returned as ``(gy, gx, nbins)``.
    """
    gy = (h + cell - 1) // cell
    gx = (w + cell - 1) // cell
    sh = (h + stride - 1) // stride
    sw = (w + stride - 1) // stride
    per = cell // stride
    mask = np.zeros((sh, sw), np.uint32)
    hits = np.zeros((gy, gx, nbins), np.float64)
    r2 = radius * radius
    scale = nbins / TWO_PI
    inv = 1.0 / stride
    ih, iw = index.shape
    m = int(math.ceil(radius)) + 1
    for py in range(max(oy - m, 0), min(oy + h + m, ih)):
        for px in range(max(ox - m, 0), min(ox + w + m, iw)):
            j = index[py, px]
            if j < 0:
                continue
            # the directions within tol of this edge's
            b0 = int(math.ceil((eang[j] - tol) * scale - 0.5))
            b1 = int(math.floor((eang[j] + tol) * scale - 0.5))
            bit = np.uint32(0)
            for bb in range(b0, b1 + 1):
                bit |= np.uint32(1) << np.uint32(bb % nbins)
            if bit == 0:
                continue
            x = ex[j] - ox
            y = ey[j] - oy
            # the sample rows and columns within the radius
            y0 = max(int(math.ceil((y - radius) * inv)), 0)
            y1 = min(int(math.floor((y + radius) * inv)), sh - 1)
            x0 = max(int(math.ceil((x - radius) * inv)), 0)
            x1 = min(int(math.floor((x + radius) * inv)), sw - 1)
            for sy in range(y0, y1 + 1):
                dy = sy * stride - y
                for sx in range(x0, x1 + 1):
                    dx = sx * stride - x
                    if dx * dx + dy * dy <= r2:
                        mm = mask[sy, sx]
                        new = bit & ~mm
                        if new:
                            mask[sy, sx] = mm | new
                            for bb in range(b0, b1 + 1):  # (this edge's directions only)
                                q = bb % nbins
                                if new & (np.uint32(1) << np.uint32(q)):
                                    hits[sy // per, sx // per, q] += 1.0
    # sample positions per cell (the last row and column may be cut)
    ny = np.empty(gy)
    for i in range(gy):
        ny[i] = min(per, sh - i * per)
    nx = np.empty(gx)
    for i in range(gx):
        nx[i] = min(per, sw - i * per)
    out = np.zeros((gy, gx, nbins), np.float64)
    for cy in range(gy):
        for cx in range(gx):
            area = 0.0
            for yy in range(max(cy - 1, 0), min(cy + 2, gy)):
                for xx in range(max(cx - 1, 0), min(cx + 2, gx)):
                    area += ny[yy] * nx[xx]
                    for b in range(nbins):
                        out[cy, cx, b] += hits[yy, xx, b]
            for b in range(nbins):
                out[cy, cx, b] /= area
    return out


@njit(cache=CACHE, nogil=True, inline="always")
def _chance_at(cover, cy, cx, phi, nb):
    """Chance of a match in cell (cx, cy) for a point wanting direction
    ``phi`` (any real): linear between the two nearest bin centres."""
    u = phi * nb / TWO_PI - 0.5
    j = math.floor(u)
    f = u - j
    j0 = int(j) % nb
    return (1.0 - f) * cover[cy, cx, j0] + f * cover[cy, cx, (j0 + 1) % nb]


@njit(cache=CACHE, nogil=True)
def evidence_counts(px, py, pang, a, b, tx, ty, ids, cover, ox, oy, cell, h, w, border,
                    either, step, ell):
    """The a-contrario counts of a pose (:func:`seahough.core.nfa.evidence`):
    ``(n, m, k, p)``. Pattern points farther than ``border`` from the edges
    of an ``h`` x ``w`` image count; ``n`` sums, for each, the image edge
    points its stretch of edge covers (``step``: the distance between
    neighbouring points, px; a thinned edge is 4-connected: it has
    ``|cos| + |sin|`` points a pixel of its length), ``m`` the independent
    observations it makes (one per ``ell`` pixels of edge length at most:
    however the edge is drawn in pixels), ``k`` the
    same sum over the points that found a match (``ids``, -1: none): the
    edge points that agree, each once however many pattern points fall on
    it; ``p`` the mean chance of a match at the points (``cover``: the
    background model, its cell (0, 0) at pixel (ox, oy))."""
    gy, gx, nb = cover.shape
    phi = math.atan2(b, a)
    n_eff = 0.0
    m_eff = 0.0
    psum = 0.0
    cnt = 0
    k_eff = 0.0
    for i in range(px.shape[0]):
        x, y, want = _placed(px[i], py[i], pang[i], a, b, tx, ty, phi)
        if x < border or y < border or x > w - 1 - border or y > h - 1 - border:
            continue
        covers = step * (abs(math.cos(want)) + abs(math.sin(want)))
        n_eff += min(1.0, covers)
        m_eff += min(1.0, step / ell)
        cx = min(max(int(math.floor((x - ox) / cell)), 0), gx - 1)
        cy = min(max(int(math.floor((y - oy) / cell)), 0), gy - 1)
        p = _chance_at(cover, cy, cx, want, nb)
        if either:
            p = min(1.0, p + _chance_at(cover, cy, cx, want + math.pi, nb))
        psum += p
        cnt += 1
        if ids[i] >= 0:
            k_eff += min(1.0, covers)
    return n_eff, m_eff, k_eff, psum / cnt if cnt > 0 else 0.0
