"""Kernels of the feature stages: edge points (non-maximum suppression),
segments traced along edges, and points spread evenly over a pattern."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._cache import CACHE
from ._common import TWO_PI, _same_direction


#: tan(22.5 deg), the edge direction's quantisation threshold. float32: in
#: float64 edge_points took 1.5x as long (the kernel before compared in
#: float64, which classes a gradient within an ulp of it differently; on the
#: real sequences' images no pixel was affected).
_T22 = np.float32(0.41421356)


@njit(cache=CACHE, nogil=True, inline="always")
def _across(mag, i, w, ggx, ggy):
    """The magnitudes on either side of flat pixel ``i`` (image width ``w``,
    unsigned) across its edge, the gradient's direction quantised to 4 (as
    Canny does)."""
    one = np.uint64(1)
    agx = abs(ggx)
    agy = abs(ggy)
    # chosen arithmetically: as selects the compiler made branches of them,
    # and an edge's directions are unpredictable (the loop took 1.7x as long)
    fh = np.float32(agy <= _T22 * agx)
    fv = np.float32(agx <= _T22 * agy)
    fs = np.float32((ggx > 0) == (ggy > 0))
    o = np.float32(1.0)
    d1 = fs * mag[i - w - one] + (o - fs) * mag[i + w - one]
    d2 = fs * mag[i + w + one] + (o - fs) * mag[i - w + one]
    m1 = fh * mag[i - one] + (o - fh) * (fv * mag[i - w] + (o - fv) * d1)
    m2 = fh * mag[i + one] + (o - fh) * (fv * mag[i + w] + (o - fv) * d2)
    return m1, m2


@njit(cache=CACHE, nogil=True)
def edge_points(mag, gx, gy, floor, mask, row0=0):
    """Non-maximum suppression across the edge, with sub-pixel position.

    Returns ``(x, y, magnitude, ix, iy, index, nx, ny)`` of every pixel whose gradient
    magnitude is at least ``floor`` and is a local maximum along its gradient
    direction (quantised to 4 directions, as Canny does). The sub-pixel offset
    along that direction comes from a parabola through the three magnitudes.
    ``index`` holds each point's id at its pixel (-1 elsewhere); ``nx, ny``
    the exact unit gradient (the caller takes the points' directions). ``mask``
    (uint8, the image's shape) limits the points to its non-zero pixels; any
    other shape (e.g. 0x0) means the whole image. The magnitudes must be
    finite (neighbours are chosen by multiplying with 0 or 1).
    """
    h, w = mag.shape
    masked = mask.shape[0] == h and mask.shape[1] == w
    fm = np.ascontiguousarray(mag).ravel()
    fgx = np.ascontiguousarray(gx).ravel()
    fgy = np.ascontiguousarray(gy).ravel()
    fmask = np.ascontiguousarray(mask).ravel()
    uw = np.uint64(w)
    # first the kept pixels, compacted without a branch (whether a pixel of
    # textured seabed is kept is a coin toss: as a branch, the loop took over
    # twice as long)
    pos = np.empty(max(h * w, 1), np.int64)
    k = 0
    if masked:
        for y in range(1, h - 1):
            row = np.uint64(y) * uw
            for x in range(1, w - 1):
                i = row + np.uint64(x)
                if fmask[i] == 0:  # (a band around points: long runs either way)
                    continue
                m = fm[i]
                m1, m2 = _across(fm, i, uw, fgx[i], fgy[i])
                pos[k] = i
                k += np.int64((m >= floor) & (m >= m1) & (m > m2))
    else:
        # the whole image: a row's tests first, then its kept pixels
        # compacted (two loops: in one, the kernel took 1.5-1.8x as long)
        flag = np.zeros(w, np.uint8)
        for y in range(1, h - 1):
            row = np.uint64(y) * uw
            for x in range(1, w - 1):
                i = row + np.uint64(x)
                m = fm[i]
                m1, m2 = _across(fm, i, uw, fgx[i], fgy[i])
                flag[x] = (m >= floor) & (m >= m1) & (m > m2)
            base = y * w
            for x in range(1, w - 1):
                pos[k] = base + x
                k += np.int64(flag[x])
    index = np.full((h, w), -1, np.int32)
    findex = index.ravel()
    xs = np.empty(k, np.float32)
    ys = np.empty(k, np.float32)
    mg = np.empty(k, np.float32)
    ix = np.empty(k, np.int32)
    iy = np.empty(k, np.int32)
    nxs = np.empty(k, np.float32)
    nys = np.empty(k, np.float32)
    for j in range(k):
        i = np.uint64(pos[j])
        y = np.int64(i // uw)
        x = np.int64(i) - y * w
        m = fm[i]
        ggx = fgx[i]
        ggy = fgy[i]
        m1, m2 = _across(fm, i, uw, ggx, ggy)
        agx = abs(ggx)
        agy = abs(ggy)
        horiz = agy <= _T22 * agx  # (as _across decided)
        vert = agx <= _T22 * agy
        same = (ggx > 0) == (ggy > 0)
        sx = 0 if (vert and not horiz) else 1
        sy = 0 if horiz else (1 if (vert or same) else -1)
        den = m1 - 2.0 * m + m2
        off = 0.0
        if den < 0.0:
            off = 0.5 * (m1 - m2) / den
            if off > 0.5:
                off = 0.5
            elif off < -0.5:
                off = -0.5
        xs[j] = x + off * sx
        ys[j] = (y + row0) + off * sy   # (row0: the image's row of this one's 0)
        mg[j] = m
        ix[j] = x
        iy[j] = y
        inv = np.float32(1.0) / m
        nxs[j] = ggx * inv
        nys[j] = ggy * inv
        findex[i] = j
    return xs, ys, mg, ix, iy, index, nxs, nys


@njit(cache=CACHE, nogil=True)
def band_gradients(img, need):
    """Scharr gradients of the float32 grey ``img`` at the pixels where
    ``need`` (uint8, its shape) is set, zero elsewhere: ``(gx, gy, mag)``,
    as cv2.Scharr (``BORDER_REPLICATE``) and ``sqrt(gx^2 + gy^2)`` compute
    them, in the order of OpenCV's separable passes (derivative along a row,
    then the smoothing across, and the other way round): the same numbers on
    integer grey levels, within float rounding on fractional ones (OpenCV's
    vector code fuses some of its multiplications and additions). A band's
    worth of work instead of an image's."""
    h, w = img.shape
    gx = np.zeros((h, w), np.float32)
    gy = np.zeros((h, w), np.float32)
    mag = np.zeros((h, w), np.float32)
    three = np.float32(3.0)
    ten = np.float32(10.0)
    for y in range(h):
        ym = max(y - 1, 0)
        yp = min(y + 1, h - 1)
        for x in range(w):
            if need[y, x] == 0:
                continue
            xm = max(x - 1, 0)
            xp = min(x + 1, w - 1)
            # d/dx: [-1, 0, 1] along each row, then [3, 10, 3] across them
            r0 = img[ym, xp] - img[ym, xm]
            r1 = img[y, xp] - img[y, xm]
            r2 = img[yp, xp] - img[yp, xm]
            a = r1 * ten + (r0 + r2) * three
            # d/dy: [3, 10, 3] along each row, then [-1, 0, 1] across them
            s0 = img[ym, x] * ten + (img[ym, xm] + img[ym, xp]) * three
            s2 = img[yp, x] * ten + (img[yp, xm] + img[yp, xp]) * three
            b = s2 - s0
            gx[y, x] = a
            gy[y, x] = b
            m = a * a
            m += b * b
            mag[y, x] = np.sqrt(m)
    return gx, gy, mag


@njit(cache=CACHE, nogil=True)
def trace_segments(seeds, ix, iy, ang, nxs, nys, mag, index, steps, tol):
    """Trace a short segment along the edge from each seed edge point.

    From a key point, step to the 8-neighbour that lies along the edge
    (perpendicular to the gradient), is an edge point with about the same
    gradient direction (within ``tol``) and has the highest magnitude; repeat
    ``steps`` times on each side. ``nxs, nys`` are the points' unit gradients
    (``ang`` agrees with them to about 0.3 degrees).

    Returns ``(seed, end1, end2, mean_angle, length)`` for the seeds from
    which at least two steps could be taken; ``end1``/``end2`` are edge point
    ids, ``length`` the number of steps.
    """
    n = seeds.shape[0]
    h, w = index.shape
    out_seed = np.empty(n, np.int32)
    out_e1 = np.empty(n, np.int32)
    out_e2 = np.empty(n, np.int32)
    out_ang = np.empty(n, np.float32)
    out_len = np.empty(n, np.int32)
    diag = 0.38 * math.sqrt(2.0)
    k = 0
    for si in range(n):
        s = seeds[si]
        sc = nxs[s]
        ss = nys[s]
        e1 = s
        e2 = s
        total = 0
        for side in range(2):
            # the second side starts along the gradients summed over the first
            # side's walk, a vector longer than 1: its cone of steps is wider
            # (cos > 0.38 / length). A unit start on both sides was measured
            # (2026-12-08): real pairs alike (docs/real_pairs.md: wreck steps
            # 0.20 -> 0.22 % of the diagonal), but a frame after a bad one
            # measured 1 of 5 times in place of 5 (tests/test_odometer.py) and
            # oblique pool pairs answered wrong: kept as it is
            sign = 1.0 if side == 0 else -1.0
            tx = -ss * sign
            ty = sc * sign
            cur = s
            for _ in range(steps):
                cx = ix[cur]
                cy = iy[cur]
                acur = ang[cur]
                best = -1
                bestm = -1.0
                for dy in range(-1, 2):
                    for dx in range(-1, 2):
                        if dx == 0 and dy == 0:
                            continue
                        if dx * tx + dy * ty <= (diag if dx != 0 and dy != 0 else 0.38):
                            continue
                        qx = cx + dx
                        qy = cy + dy
                        if qx < 0 or qy < 0 or qx >= w or qy >= h:
                            continue
                        j = index[qy, qx]
                        if j < 0:
                            continue
                        if not _same_direction(ang[j], acur, tol, False):
                            continue
                        if mag[j] > bestm:
                            bestm = mag[j]
                            best = j
                if best < 0:
                    break
                # keep walking the same way along the (possibly curving) edge
                ntx = -nys[best]
                nty = nxs[best]
                if ntx * tx + nty * ty < 0:
                    ntx = -ntx
                    nty = -nty
                tx = ntx
                ty = nty
                sc += nxs[best]
                ss += nys[best]
                cur = best
                total += 1
            if side == 0:
                e1 = cur
            else:
                e2 = cur
        if total >= 2:
            out_seed[k] = s
            out_e1[k] = e1
            out_e2[k] = e2
            a = math.atan2(ss, sc)
            if a < 0.0:
                a += TWO_PI
            out_ang[k] = a
            out_len[k] = total
            k += 1
    return out_seed[:k], out_e1[:k], out_e2[:k], out_ang[:k], out_len[:k]


@njit(cache=CACHE, nogil=True)
def spread_points(x, y, order, min_dist, max_count):
    """Greedy Poisson-disc thinning: visit points in ``order`` and keep one
    when no kept point lies within ``min_dist``. Returns kept indices."""
    n = x.shape[0]
    if n == 0:
        return np.empty(0, np.int64)
    cell = max(min_dist, 1e-3)
    x0 = x.min()
    y0 = y.min()
    gw = int((x.max() - x0) / cell) + 3
    gh = int((y.max() - y0) / cell) + 3
    head = -np.ones(gw * gh, np.int64)
    nxt = np.empty(n, np.int64)
    kept = np.empty(min(n, max_count), np.int64)
    nk = 0
    d2 = min_dist * min_dist
    for oi in range(n):
        if nk >= max_count:
            break
        i = order[oi]
        cx = int((x[i] - x0) / cell) + 1
        cy = int((y[i] - y0) / cell) + 1
        ok = True
        for gy in range(cy - 1, cy + 2):
            for gx in range(cx - 1, cx + 2):
                j = head[gy * gw + gx]
                while j >= 0:
                    ddx = x[j] - x[i]
                    ddy = y[j] - y[i]
                    if ddx * ddx + ddy * ddy < d2:
                        ok = False
                        break
                    j = nxt[j]
                if not ok:
                    break
            if not ok:
                break
        if ok:
            c = cy * gw + cx
            nxt[i] = head[c]
            head[c] = i
            kept[nk] = i
            nk += 1
    return kept[:nk]


@njit(cache=CACHE, nogil=True)
def _root(parent, i):
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@njit(cache=CACHE, nogil=True)
def chain_lengths(ix, iy, angle, index, tol):
    """For each edge point, how many edge points its chain holds: the points
    joined through 8-neighbours whose directions differ by at most ``tol``
    radians (union-find; a long smooth border is one chain, texture breaks
    into short ones). ``index``: the edge points' id image (-1 elsewhere)."""
    n = ix.size
    h, w = index.shape
    parent = np.arange(n, dtype=np.int32)
    for i in range(n):
        x = ix[i]
        y = iy[i]
        for k in range(4):   # the four forward neighbours: each pair seen once
            dx = 1 if k == 0 else (k - 2)
            dy = 0 if k == 0 else 1
            xx = x + dx
            yy = y + dy
            if xx < 0 or xx >= w or yy >= h:
                continue
            j = index[yy, xx]
            if j < 0 or not _same_direction(angle[i], angle[j], tol, False):
                continue
            a = _root(parent, i)
            b = _root(parent, j)
            if a != b:
                if a < b:
                    parent[b] = a
                else:
                    parent[a] = b
    size = np.zeros(n, np.int32)
    for i in range(n):
        size[_root(parent, i)] += 1
    out = np.empty(n, np.int32)
    for i in range(n):
        out[i] = size[_root(parent, i)]
    return out
