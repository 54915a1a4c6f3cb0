"""Kernels of the refinement stage: matching pattern points to image edge
points, snapping them, the ICP that fits a similarity (or a homography) to
the matches, and the local vote over a pose's shifts."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._cache import CACHE
from ._common import TWO_PI, _placed, _same_direction


@njit(cache=CACHE, nogil=True, inline="always")
def _nearest(x, y, want, ex, ey, eang, index, radius, ang_tol, either):
    """The nearest edge point to (x, y) of direction compatible with ``want``
    (in [0, 2 pi)) within ``radius``: ``(id, squared distance)``, id -1 when
    there is none."""
    h, w = index.shape
    r = int(math.ceil(radius))
    bestd = radius * radius + 1e-9
    best = -1
    cx = int(math.floor(x + 0.5))
    cy = int(math.floor(y + 0.5))
    if cx < -r or cy < -r or cx >= w + r or cy >= h + r:
        return best, bestd
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
    return best, bestd


@njit(cache=CACHE, nogil=True)
def match_points(px, py, pang, a, b, tx, ty, ex, ey, eang, index, radius, ang_tol, either):
    """For each pattern point mapped by the pose, the nearest image edge point
    with a compatible gradient direction within ``radius`` pixels.

    The pose is ``x'' = tx + a x' + b y'``, ``y'' = ty - b x' + a y'`` (a =
    rho cos phi, b = rho sin phi). ``index`` maps pixels to edge point ids
    (-1: none). Returns the matched edge id per pattern point (-1: none) and
    the distance.
    """
    n = px.shape[0]
    out = -np.ones(n, np.int64)
    dist = np.full(n, np.inf)
    phi = math.atan2(b, a)
    for i in range(n):
        x, y, want = _placed(px[i], py[i], pang[i], a, b, tx, ty, phi)
        best, bestd = _nearest(x, y, want, ex, ey, eang, index, radius, ang_tol, either)
        if best >= 0:
            out[i] = best
            dist[i] = math.sqrt(bestd)
    return out, dist


@njit(cache=CACHE, nogil=True)
def shift_votes(px, py, pang, a, b, tx, ty, ex, ey, eang, index, radius, ang_tol, either):
    """A local vote over shifts of a pose: for each pattern point mapped by the
    pose (as :func:`match_points`), every image edge point of compatible
    direction within ``radius`` pixels (an integer; a square: each of x and y
    within it) votes for the shift that
    would put the point on it, once per point and 1-px cell of shift.

    Returns the votes, ``(2 radius + 1, 2 radius + 1)``, cell ``[radius + dy,
    radius + dx]`` for the shift ``(dx, dy)`` rounded to the pixel: the peak
    is the shift that most points agree on (a straight edge votes along a
    line of shifts; edges of other directions cross it there).
    """
    n = px.shape[0]
    h, w = index.shape
    r = int(radius)
    side = 2 * r + 1
    votes = np.zeros((side, side), np.float64)
    seen = -np.ones((side, side), np.int64)   # the last point that voted in a cell
    phi = math.atan2(b, a)
    for i in range(n):
        x, y, want = _placed(px[i], py[i], pang[i], a, b, tx, ty, phi)
        cx = int(math.floor(x + 0.5))
        cy = int(math.floor(y + 0.5))
        for yy in range(max(cy - r - 1, 0), min(cy + r + 2, h)):
            for xx in range(max(cx - r - 1, 0), min(cx + r + 2, w)):
                j = index[yy, xx]
                if j < 0:
                    continue
                sx = int(math.floor(ex[j] - x + 0.5))
                sy = int(math.floor(ey[j] - y + 0.5))
                if sx < -r or sx > r or sy < -r or sy > r:
                    continue
                if seen[sy + r, sx + r] == i:
                    continue
                if not _same_direction(eang[j], want, ang_tol, either):
                    continue
                seen[sy + r, sx + r] = i
                votes[sy + r, sx + r] += 1.0
    return votes


@njit(cache=CACHE, nogil=True)
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


@njit(cache=CACHE, nogil=True)
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
    if not _solve(ata, atb, out):
        out[0] = np.nan
    return out


@njit(cache=CACHE, nogil=True)
def _solve(m, v, out):
    """Solve the small square system ``m x = v`` into ``out`` by Gaussian
    elimination with partial pivoting (Numba's np.linalg would need SciPy).
    Returns False when the system is singular. ``m`` and ``v`` are
    overwritten."""
    n = v.shape[0]
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


@njit(cache=CACHE, nogil=True)
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


@njit(cache=CACHE, nogil=True, inline="always")
def _map_point(hom, x, y, w, ang):
    """Point (x, y) mapped by the homography ``hom`` (``w``: its divisor
    there, > 0), and the gradient direction ``ang`` turned by the inverse
    transpose of its Jacobian, in [0, 2 pi): ``(u, v, direction)``."""
    u = (hom[0, 0] * x + hom[0, 1] * y + hom[0, 2]) / w
    v = (hom[1, 0] * x + hom[1, 1] * y + hom[1, 2]) / w
    j11 = (hom[0, 0] - u * hom[2, 0]) / w
    j12 = (hom[0, 1] - u * hom[2, 1]) / w
    j21 = (hom[1, 0] - v * hom[2, 0]) / w
    j22 = (hom[1, 1] - v * hom[2, 1]) / w
    ca = math.cos(ang)
    sa = math.sin(ang)
    sg = 1.0 if j11 * j22 - j12 * j21 >= 0 else -1.0
    d = math.atan2(sg * (-j12 * ca + j11 * sa), sg * (j22 * ca - j21 * sa))
    return u, v, d - TWO_PI * math.floor(d / TWO_PI)


@njit(cache=CACHE, nogil=True)
def homography_icp(px, py, pang, hom, ex, ey, eang, enx, eny, index, radii, iterations,
                   ang_tol, stride, score_radius):
    """Refine a homography (3x3 ``hom``: point (x, y) -> image pixel) of the
    points ``px, py`` (gradient directions ``pang``) on the image's edge
    points, with shrinking match radii, then score it.

    Each iteration maps every point (every ``stride``-th while the radius
    exceeds 2 px) and its gradient direction (turned by the inverse
    transpose of the homography's Jacobian there), matches it to the
    nearest edge point of compatible direction within the radius, and
    solves the weighted least squares of the point-to-edge distances along
    the edge normals (Huber weights, half the radius) for the homography's
    8 parameters, in coordinates normalised to the points' spread. Returns
    ``(hom, score, inside)``: the refined homography (``hom[2, 2] = 1``),
    the share of the points with a compatible edge within ``score_radius``,
    and the share that it maps inside the image.
    """
    n = px.shape[0]
    if n == 0:
        return hom.copy(), 0.0, 0.0
    ih, iw = index.shape
    cx = px.mean()
    cy = py.mean()
    sc = max(math.sqrt(((px - cx) ** 2).mean()), math.sqrt(((py - cy) ** 2).mean()), 1.0)
    # hn = hom @ inverse(normalisation): normalised point -> image pixel
    hn = np.empty((3, 3))
    for r in range(3):
        hn[r, 0] = hom[r, 0] * sc
        hn[r, 1] = hom[r, 1] * sc
        hn[r, 2] = hom[r, 0] * cx + hom[r, 1] * cy + hom[r, 2]
    hn /= hn[2, 2]
    A = np.empty((8, 8))
    g = np.empty(8)
    jr = np.empty(8)
    dh = np.empty(8)
    for ri in range(radii.shape[0]):
        rad = radii[ri]
        step = stride if rad > 2.0 else 1
        c = max(0.5 * rad, 1.0)
        for _ in range(iterations):
            A[:] = 0.0
            g[:] = 0.0
            m = 0
            for i in range(0, n, step):
                x = (px[i] - cx) / sc
                y = (py[i] - cy) / sc
                w = hn[2, 0] * x + hn[2, 1] * y + hn[2, 2]
                if w <= 1e-9:
                    continue
                u, v, want = _map_point(hn, x, y, w, pang[i])
                j, _ = _nearest(u, v, want, ex, ey, eang, index, rad, ang_tol, False)
                if j < 0:
                    continue
                nx = enx[j]
                ny = eny[j]
                res = nx * (u - ex[j]) + ny * (v - ey[j])
                t = nx * u + ny * v
                jr[0] = nx * x / w
                jr[1] = nx * y / w
                jr[2] = nx / w
                jr[3] = ny * x / w
                jr[4] = ny * y / w
                jr[5] = ny / w
                jr[6] = -t * x / w
                jr[7] = -t * y / w
                wt = 1.0 if abs(res) <= c else c / abs(res)
                for k in range(8):
                    g[k] -= wt * jr[k] * res
                    for l in range(k, 8):
                        A[k, l] += wt * jr[k] * jr[l]
                m += 1
            if m < 12:
                break
            tr = 0.0
            for k in range(8):
                tr += A[k, k]
                for l in range(k):
                    A[k, l] = A[l, k]
            for k in range(8):
                A[k, k] += 1e-6 * tr / 8.0
            if not _solve(A, g, dh):
                break
            moved = 0.0
            for k in range(8):
                hn[k // 3, k % 3] += dh[k]
                moved = max(moved, abs(dh[k]))
            if not np.all(np.isfinite(hn)) or abs(hn[2, 2]) < 1e-12:
                return hom.copy(), 0.0, 0.0
            hn /= hn[2, 2]
            if moved < 0.02:   # (pixels, about: the parameters move points by that)
                break
    # back to pixel coordinates: hom = hn @ normalisation
    out = np.empty((3, 3))
    for r in range(3):
        out[r, 0] = hn[r, 0] / sc
        out[r, 1] = hn[r, 1] / sc
        out[r, 2] = hn[r, 2] - (hn[r, 0] * cx + hn[r, 1] * cy) / sc
    out /= out[2, 2]
    matched = 0
    inside = 0
    for i in range(n):
        ww = out[2, 0] * px[i] + out[2, 1] * py[i] + out[2, 2]
        if ww <= 1e-9:
            continue
        u, v, want = _map_point(out, px[i], py[i], ww, pang[i])
        if u >= 0 and v >= 0 and u <= iw - 1 and v <= ih - 1:
            inside += 1
        j, _ = _nearest(u, v, want, ex, ey, eang, index, score_radius, ang_tol, False)
        if j >= 0:
            matched += 1
    return out, matched / n, inside / n
