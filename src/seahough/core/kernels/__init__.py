"""The hot loops, compiled with Numba. Everything else is numpy/OpenCV.

Conventions: angles in radians; a gradient angle is ``atan2(gy, gx)`` in
[0, 2 pi); equation 1 maps a pattern point p to ``t + rho R(phi) p`` with
``R(phi) = [[cos, sin], [-sin, cos]]``, which turns a pattern gradient of
angle ``a`` into an image gradient of angle ``a - phi``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

TWO_PI = 2.0 * math.pi

MODE_ORIENTED = 0
MODE_POINTS = 1
MODE_SEGMENTS = 2


@njit(cache=True, inline="always")
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


# --------------------------------------------------------------------------- edges
#: tan(22.5 deg), the edge direction's quantisation threshold. float32: in
#: float64 edge_points took 1.5x as long (the kernel before compared in
#: float64, which classes a gradient within an ulp of it differently; on the
#: real sequences' images no pixel was affected).
_T22 = np.float32(0.41421356)


@njit(cache=True, inline="always")
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


@njit(cache=True)
def edge_points(mag, gx, gy, phase, floor, mask):
    """Non-maximum suppression across the edge, with sub-pixel position.

    ``phase`` is the gradient direction image (radians, [0, 2 pi)).
    Returns ``(x, y, angle, magnitude, ix, iy, index, nx, ny)`` of every pixel whose gradient
    magnitude is at least ``floor`` and is a local maximum along its gradient
    direction (quantised to 4 directions, as Canny does). The sub-pixel offset
    along that direction comes from a parabola through the three magnitudes.
    ``index`` holds each point's id at its pixel (-1 elsewhere); ``nx, ny``
    the exact unit gradient (``phase`` agrees with it to about 0.3 degrees). ``mask``
    (uint8, the image's shape) limits the points to its non-zero pixels; any
    other shape (e.g. 0x0) means the whole image. The magnitudes must be
    finite (neighbours are chosen by multiplying with 0 or 1).
    """
    h, w = mag.shape
    masked = mask.shape[0] == h and mask.shape[1] == w
    fm = np.ascontiguousarray(mag).ravel()
    fgx = np.ascontiguousarray(gx).ravel()
    fgy = np.ascontiguousarray(gy).ravel()
    fph = np.ascontiguousarray(phase).ravel()
    fmask = np.ascontiguousarray(mask).ravel()
    uw = np.uint64(w)
    # first the kept pixels, compacted without a branch (whether a pixel of
    # textured seabed is kept is a coin toss: as a branch, the loop took over
    # twice as long)
    pos = np.empty(max(h * w, 1), np.int64)
    k = 0
    for y in range(1, h - 1):
        row = np.uint64(y) * uw
        for x in range(1, w - 1):
            i = row + np.uint64(x)
            if masked and fmask[i] == 0:  # (a band around points: long runs either way)
                continue
            m = fm[i]
            m1, m2 = _across(fm, i, uw, fgx[i], fgy[i])
            pos[k] = i
            k += np.int64((m >= floor) & (m >= m1) & (m > m2))
    index = np.full((h, w), -1, np.int32)
    findex = index.ravel()
    xs = np.empty(k, np.float32)
    ys = np.empty(k, np.float32)
    an = np.empty(k, np.float32)
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
        ys[j] = y + off * sy
        an[j] = fph[i]
        mg[j] = m
        ix[j] = x
        iy[j] = y
        inv = np.float32(1.0) / m
        nxs[j] = ggx * inv
        nys[j] = ggy * inv
        findex[i] = j
    return xs, ys, an, mg, ix, iy, index, nxs, nys


@njit(cache=True)
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


@njit(cache=True)
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


# --------------------------------------------------------------------------- voting
@njit(cache=True, fastmath=True)
def vote(px, py, pang, pw, p2x, p2y,
         qx, qy, qang, q2x, q2y, qstart, n_abins,
         phis, phi_half, rhos, log_rho0, log_step, mode,
         tx0, ty0, tbin, nw, nh,
         best_val, best_k, best_d, proj_sr):
    """Fill the 4-D accumulator (phi, rho, dy, dx), one rotation slice at a time.

    Pattern points ``p`` (relative to the pattern origin, working pixels) are
    paired with image segments ``q`` whose edge direction is compatible with
    the slice's rotation ``phis[d]`` (within ``phi_half``); image segments are
    sorted by angle bin (``qstart``: CSR offsets of ``n_abins`` bins).

    ``mode`` MODE_ORIENTED: the pair's own rotation (pattern angle minus image
    angle) and a cycle over ``rhos``; MODE_POINTS: the slice's rotation and a
    cycle over ``rhos`` (the paper's point voting); MODE_SEGMENTS: equation 5
    on the pattern segment (p, p2) and image segment (q, q2), one vote.

    Each slice is a small 3-D array (rho, dy, dx) that stays in cache; after
    filling it, every 2x2 block of translation bins is summed and reduced
    into ``best_val/best_k/best_d`` (the dx-dy plane: best height over scale
    and rotation, and where) and ``proj_sr`` (the rho-phi plane: best height
    over translation). Votes are weighted by ``pw``, and each pattern point
    counts at most once in a cell.
    """
    n_rho = rhos.shape[0]
    n_phi = phis.shape[0]
    np_ = px.shape[0]
    nq = qx.shape[0]
    abin = TWO_PI / n_abins
    inv = 1.0 / tbin
    # image side in bin units, and unit direction vectors
    qxs = np.empty(nq, np.float64)
    qys = np.empty(nq, np.float64)
    qc = np.empty(nq, np.float64)
    qs = np.empty(nq, np.float64)
    for j in range(nq):
        qxs[j] = (qx[j] - tx0) * inv
        qys[j] = (qy[j] - ty0) * inv
        qc[j] = math.cos(qang[j])
        qs[j] = math.sin(qang[j])
    rr = np.empty(n_rho, np.float64)
    for k in range(n_rho):
        rr[k] = rhos[k] * inv
    acc = np.zeros((n_rho, nh, nw), np.float32)
    # who voted last in each cell: a pattern point counts once per cell, so a
    # cell's height is the number of pattern points supporting it, not the
    # number of pairs (a straight edge would otherwise pile up votes)
    stamp = np.full((n_rho, nh, nw), -1, np.int32)
    fnw = float(nw)
    fnh = float(nh)
    for d in range(n_phi):
        phi_d = phis[d]
        cphi = math.cos(phi_d)
        sphi = math.sin(phi_d)
        acc[:] = 0.0
        for i in range(np_):
            ai = pang[i]
            tag = d * np_ + i
            pci = math.cos(ai)
            psi = math.sin(ai)
            pxi = px[i]
            pyi = py[i]
            wi = pw[i]
            # image angle expected for this pattern point: a - phi
            centre = ai - phi_d
            b_lo = int(math.floor((centre - phi_half) / abin))
            b_hi = int(math.floor((centre + phi_half) / abin))
            for bb in range(b_lo, b_hi + 1):
                b = bb % n_abins
                for j in range(qstart[b], qstart[b + 1]):
                    dphi = ai - qang[j] - phi_d
                    while dphi >= math.pi:
                        dphi -= TWO_PI
                    while dphi < -math.pi:
                        dphi += TWO_PI
                    if dphi < -phi_half or dphi >= phi_half:
                        continue
                    if mode == MODE_SEGMENTS:
                        aa = pxi - p2x[i]
                        bq = pyi - p2y[i]
                        cc = qx[j] - q2x[j]
                        dd = qy[j] - q2y[j]
                        nn = aa * aa + bq * bq
                        if nn <= 0.0:
                            continue
                        rc = (aa * cc + bq * dd) / nn
                        rs = (bq * cc - aa * dd) / nn
                        rho = math.sqrt(rc * rc + rs * rs)
                        if rho <= 0.0:
                            continue
                        k = int(math.floor((math.log(rho) - log_rho0) / log_step + 0.5))
                        if k < 0 or k >= n_rho:
                            continue
                        fx = qxs[j] - (rc * pxi + rs * pyi) * inv
                        fy = qys[j] - (-rs * pxi + rc * pyi) * inv
                        if fx < 0.0 or fy < 0.0 or fx >= fnw or fy >= fnh:
                            continue
                        iy = int(fy)
                        ix = int(fx)
                        if stamp[k, iy, ix] != tag:
                            stamp[k, iy, ix] = tag
                            acc[k, iy, ix] += wi
                        continue
                    if mode == MODE_ORIENTED:
                        # rotation of the pair: cos/sin of (a_p - a_q)
                        c = pci * qc[j] + psi * qs[j]
                        s = psi * qc[j] - pci * qs[j]
                    else:
                        c = cphi
                        s = sphi
                    ux = c * pxi + s * pyi
                    uy = -s * pxi + c * pyi
                    fx0 = qxs[j]
                    fy0 = qys[j]
                    # (the cell update below is written out twice on purpose: an
                    # inlined helper measured ~40 % slower in this loop)
                    for k in range(n_rho):
                        fx = fx0 - rr[k] * ux
                        fy = fy0 - rr[k] * uy
                        if fx < 0.0 or fy < 0.0 or fx >= fnw or fy >= fnh:
                            continue
                        iy = int(fy)
                        ix = int(fx)
                        # (without a branch: about 13 % faster)
                        first = np.float32(stamp[k, iy, ix] != tag)
                        stamp[k, iy, ix] = tag
                        acc[k, iy, ix] += wi * first
        # reduce the slice: 2x2 translation blocks (written without branches
        # so that the compiler vectorises the rows)
        for k in range(n_rho):
            top = np.float32(0.0)
            for yy in range(nh - 1):
                a0 = acc[k, yy]
                a1 = acc[k, yy + 1]
                bv = best_val[yy]
                bk = best_k[yy]
                bd = best_d[yy]
                for xx in range(nw - 1):
                    v = a0[xx] + a0[xx + 1] + a1[xx] + a1[xx + 1]
                    up = v > bv[xx]
                    bv[xx] = v if up else bv[xx]
                    bk[xx] = k if up else bk[xx]
                    bd[xx] = d if up else bd[xx]
                    top = max(top, v)
            if top > proj_sr[k, d]:
                proj_sr[k, d] = top


@njit(cache=True)
def local_maxima(plane, radius):
    """Row-major (ys, xs) of the positive cells that no cell within
    ``radius`` (a square window, clipped at the border) exceeds: what
    ``plane >= cv2.dilate(plane) & plane > 0`` marks, without a pass over the
    empty cells' windows."""
    h, w = plane.shape
    ys = np.empty(h * w, np.int64)
    xs = np.empty(h * w, np.int64)
    k = 0
    for y in range(h):
        for x in range(w):
            v = plane[y, x]
            if v <= 0:
                continue
            top = True
            for yy in range(max(y - radius, 0), min(y + radius + 1, h)):
                for xx in range(max(x - radius, 0), min(x + radius + 1, w)):
                    if plane[yy, xx] > v:
                        top = False
                        break
                if not top:
                    break
            if top:
                ys[k] = y
                xs[k] = x
                k += 1
    return ys[:k].copy(), xs[:k].copy()


# --------------------------------------------------------------------------- matching
@njit(cache=True)
def match_points(px, py, pang, a, b, tx, ty, ex, ey, eang, index, radius, ang_tol, either):
    """For each pattern point mapped by the pose, the nearest image edge point
    with a compatible gradient direction within ``radius`` pixels.

    The pose is ``x'' = tx + a x' + b y'``, ``y'' = ty - b x' + a y'`` (a =
    rho cos phi, b = rho sin phi). ``index`` maps pixels to edge point ids
    (-1: none). Returns the matched edge id per pattern point (-1: none) and
    the distance.
    """
    n = px.shape[0]
    h, w = index.shape
    out = -np.ones(n, np.int64)
    dist = np.full(n, np.inf)
    phi = math.atan2(b, a)
    r = int(math.ceil(radius))
    r2 = radius * radius
    for i in range(n):
        x = tx + a * px[i] + b * py[i]
        y = ty - b * px[i] + a * py[i]
        cx = int(math.floor(x + 0.5))
        cy = int(math.floor(y + 0.5))
        if cx < -r or cy < -r or cx >= w + r or cy >= h + r:
            continue
        # the wanted direction in [0, 2 pi), as the edges' are (_same_direction)
        want = pang[i] - phi
        want -= TWO_PI * math.floor(want / TWO_PI)
        bestd = r2 + 1e-9
        best = -1
        # rings of pixels around (cx, cy), nearest first. An edge point lies
        # within half a pixel of its pixel and (x, y) within half a pixel of
        # (cx, cy), so everything in ring k and beyond is at least k - 1 away:
        # once a match closer than that is found, the outer rings cannot win.
        for k in range(r + 1):
            if k >= 1 and bestd < (k - 1) * (k - 1):
                break
            for yy in range(cy - k, cy + k + 1):
                if yy < 0 or yy >= h:
                    continue
                edge_row = yy == cy - k or yy == cy + k
                step = 1 if edge_row else 2 * k
                for xx in range(cx - k, cx + k + 1, max(step, 1)):
                    if xx < 0 or xx >= w:
                        continue
                    j = index[yy, xx]
                    if j < 0:
                        continue
                    # nearer than the best so far (cheap) before the direction
                    ddx = ex[j] - x
                    ddy = ey[j] - y
                    d2 = ddx * ddx + ddy * ddy
                    if d2 >= bestd:
                        continue
                    if not _same_direction(eang[j], want, ang_tol, either):
                        continue
                    bestd = d2
                    best = j
        if best >= 0:
            out[i] = best
            dist[i] = math.sqrt(bestd)
    return out, dist


@njit(cache=True)
def snap_points(x, y, ang, ex, ey, eang, emag, index, radius, ang_tol, either, pen):
    """For each point (x, y) of direction ``ang``, the edge point of compatible
    direction within ``radius`` pixels with the largest ``emag / (1 + pen
    d^2)`` (d: its distance), -1 when there is none: where a blurred edge
    seen at a coarser scale lies at full resolution (the nearest edge point
    may be faint texture beside it, the strongest another edge)."""
    n = x.shape[0]
    h, w = index.shape
    out = -np.ones(n, np.int64)
    r = int(math.ceil(radius))
    r2 = radius * radius
    for i in range(n):
        cx = int(math.floor(x[i] + 0.5))
        cy = int(math.floor(y[i] + 0.5))
        best = -1
        bestm = -1.0
        for yy in range(max(cy - r, 0), min(cy + r + 1, h)):
            for xx in range(max(cx - r, 0), min(cx + r + 1, w)):
                j = index[yy, xx]
                if j < 0:
                    continue
                ddx = ex[j] - x[i]
                ddy = ey[j] - y[i]
                if ddx * ddx + ddy * ddy > r2:
                    continue
                if not _same_direction(eang[j], ang[i], ang_tol, either):
                    continue
                q = emag[j] / (1.0 + (ddx * ddx + ddy * ddy) * pen)
                if q > bestm:
                    bestm = q
                    best = j
        out[i] = best
    return out


@njit(cache=True)
def _solve_pose(px, py, ex, ey, enx, eny, w, m, a, b, fix, along):
    """Weighted least squares for (a, b, tx, ty): point-to-edge distances
    plus ``along`` times point-to-point ones (keeps straight edges
    determined). ``fix``: keep (a, b) and fit the translation only."""
    ata = np.zeros((4, 4))
    atb = np.zeros(4)
    row = np.empty(4)
    for i in range(m):
        wi = w[i]
        nx = enx[i]
        ny = eny[i]
        for rep in range(3):
            if rep == 0:
                row[0] = nx * px[i] + ny * py[i]
                row[1] = nx * py[i] - ny * px[i]
                row[2] = nx
                row[3] = ny
                t = nx * ex[i] + ny * ey[i]
                ww = wi
            elif rep == 1:
                row[0] = px[i]
                row[1] = py[i]
                row[2] = 1.0
                row[3] = 0.0
                t = ex[i]
                ww = wi * along
            else:
                row[0] = py[i]
                row[1] = -px[i]
                row[2] = 0.0
                row[3] = 1.0
                t = ey[i]
                ww = wi * along
            if ww == 0.0:
                continue
            if fix:
                t -= row[0] * a + row[1] * b
            for r in range(4):
                atb[r] += ww * row[r] * t
                for c in range(4):
                    ata[r, c] += ww * row[r] * row[c]
    out = np.empty(4)
    if fix:
        det = ata[2, 2] * ata[3, 3] - ata[2, 3] * ata[3, 2]
        if abs(det) < 1e-12:
            out[0] = np.nan
            return out
        out[0] = a
        out[1] = b
        out[2] = (atb[2] * ata[3, 3] - ata[2, 3] * atb[3]) / det
        out[3] = (ata[2, 2] * atb[3] - ata[3, 2] * atb[2]) / det
        return out
    for r in range(4):
        ata[r, r] += 1e-9
    if not _solve4(ata, atb, out):
        out[0] = np.nan
    return out


@njit(cache=True)
def _solve4(m, v, out):
    """Solve the 4x4 system ``m x = v`` into ``out`` by Gaussian elimination
    with partial pivoting (Numba's np.linalg would need SciPy). Returns False
    when the system is singular. ``m`` and ``v`` are overwritten."""
    n = 4
    for c in range(n):
        p = c
        for r in range(c + 1, n):
            if abs(m[r, c]) > abs(m[p, c]):
                p = r
        if abs(m[p, c]) < 1e-12:
            return False
        if p != c:
            for k in range(n):
                t = m[c, k]
                m[c, k] = m[p, k]
                m[p, k] = t
            t = v[c]
            v[c] = v[p]
            v[p] = t
        for r in range(c + 1, n):
            f = m[r, c] / m[c, c]
            for k in range(c, n):
                m[r, k] -= f * m[c, k]
            v[r] -= f * v[c]
    for r in range(n - 1, -1, -1):
        acc = v[r]
        for k in range(r + 1, n):
            acc -= m[r, k] * out[k]
        out[r] = acc / m[r, r]
    return True


@njit(cache=True)
def icp(px, py, pang, a, b, tx, ty, ex, ey, eang, enx, eny, index, radii, iterations, ang_tol,
        either, fix_scale, fix_angle, along, score_radius, min_scale):
    """Refine a similarity pose on matched edge points (iteratively re-weighted
    least squares with shrinking match radii), then score it.

    Returns ``(a, b, tx, ty, score, matched, rms, inside)``: the share of
    pattern points with a compatible image edge within ``score_radius``, how
    many, their rms distance, and the share of points inside the image.
    """
    n = px.shape[0]
    h, w = index.shape
    mpx = np.empty(n)
    mpy = np.empty(n)
    mex = np.empty(n)
    mey = np.empty(n)
    mnx = np.empty(n)
    mny = np.empty(n)
    mw = np.empty(n)
    scale0 = math.sqrt(a * a + b * b)
    ang0 = math.atan2(b, a)
    rr = 0.0  # rms radius of the points: how far a change of a, b moves them
    for i in range(n):
        rr += px[i] * px[i] + py[i] * py[i]
    rr = math.sqrt(rr / n) if n > 0 else 0.0
    for ri in range(radii.shape[0]):
        r = radii[ri]
        for _ in range(iterations):
            ids, dist = match_points(px, py, pang, a, b, tx, ty, ex, ey, eang, index, r,
                                     ang_tol, either)
            m = 0
            for i in range(n):
                j = ids[i]
                if j < 0:
                    continue
                mpx[m] = px[i]
                mpy[m] = py[i]
                mex[m] = ex[j]
                mey[m] = ey[j]
                mnx[m] = enx[j]
                mny[m] = eny[j]
                mw[m] = 1.0 / max(1.0, dist[i] / (0.5 * r))
                m += 1
            if m < 6:
                break
            fix = fix_scale and fix_angle
            sol = _solve_pose(mpx, mpy, mex, mey, mnx, mny, mw, m, a, b, fix, along)
            if np.isnan(sol[0]):
                break
            na, nb, ntx, nty = sol[0], sol[1], sol[2], sol[3]
            if (fix_scale or fix_angle) and not fix:
                s = scale0 if fix_scale else math.sqrt(na * na + nb * nb)
                an = ang0 if fix_angle else math.atan2(nb, na)
                na = s * math.cos(an)
                nb = s * math.sin(an)
                sol = _solve_pose(mpx, mpy, mex, mey, mnx, mny, mw, m, na, nb, True, along)
                if np.isnan(sol[0]):
                    break
                ntx, nty = sol[2], sol[3]
            if math.sqrt(na * na + nb * nb) < min_scale:
                break
            moved = abs(ntx - tx) + abs(nty - ty) + (abs(na - a) + abs(nb - b)) * rr
            a, b, tx, ty = na, nb, ntx, nty
            if moved < 0.02:
                break
    ids, dist = match_points(px, py, pang, a, b, tx, ty, ex, ey, eang, index, score_radius,
                             ang_tol, either)
    matched = 0
    ss = 0.0
    inside = 0
    for i in range(n):
        if ids[i] >= 0:
            matched += 1
            ss += dist[i] * dist[i]
        x = tx + a * px[i] + b * py[i]
        y = ty - b * px[i] + a * py[i]
        if x >= 0 and y >= 0 and x <= w - 1 and y <= h - 1:
            inside += 1
    rms = math.sqrt(ss / matched) if matched > 0 else np.inf
    score = matched / n if n > 0 else 0.0
    ins = inside / n if n > 0 else 0.0
    return a, b, tx, ty, score, matched, rms, ins
