"""Kernels of the voting stage: the accumulator's slices and its peaks."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._cache import CACHE
from ._common import TWO_PI

MODE_ORIENTED = 0
MODE_POINTS = 1
MODE_SEGMENTS = 2


@njit(cache=CACHE, nogil=True, fastmath=True)
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
    # each cell holds its height (cell[..., 0]) and who voted last in it
    # (cell[..., 1], exact in float32 up to 2**24): a pattern point counts
    # once per cell, so a cell's height is the number of pattern points
    # supporting it, not the number of pairs (a straight edge would otherwise
    # pile up votes). The two side by side: a vote touches one cache line, not
    # two (the accumulator of a search outgrows the cache; two separate arrays
    # measured about 1.5-2x slower, same heights)
    cell = np.zeros((n_rho, nh, nw, 2), np.float32)
    cell[:, :, :, 1] = -1.0
    fnw = float(nw)
    fnh = float(nh)
    for d in range(n_phi):
        phi_d = phis[d]
        cphi = math.cos(phi_d)
        sphi = math.sin(phi_d)
        cell[:, :, :, 0] = 0.0
        for i in range(np_):
            ai = pang[i]
            tag = np.float32(d * np_ + i)
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
                        if cell[k, iy, ix, 1] != tag:
                            cell[k, iy, ix, 1] = tag
                            cell[k, iy, ix, 0] += wi
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
                        first = np.float32(cell[k, iy, ix, 1] != tag)
                        cell[k, iy, ix, 1] = tag
                        cell[k, iy, ix, 0] += wi * first
        # reduce the slice: 2x2 translation blocks (written without branches
        # so that the compiler vectorises the rows)
        for k in range(n_rho):
            top = np.float32(0.0)
            for yy in range(nh - 1):
                a0 = cell[k, yy, :, 0]
                a1 = cell[k, yy + 1, :, 0]
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


@njit(cache=CACHE, nogil=True)
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
