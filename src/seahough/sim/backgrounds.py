"""Seabed backgrounds: the procedural seabed, and crops of the real photos of
the shared data folder."""

from __future__ import annotations

import functools
import math
from pathlib import Path
from typing import Union

import cv2
import numpy as np

from .._data import shared_data_dir
from ..errors import ImageReadError, ParameterError
from ._util import Shape, _check_shape, _fast_normal, _noise, _seed_of, _to_bgr, _to_uint8

__all__ = ["seabed", "tiled_floor", "background"]

# Folders of the shared data that ``source="auto"`` never picks: the pool's
# tiles are long straight lines and clean rectangles, i.e. marker look-alikes.
_EXCLUDED_AUTO = ("subvo_pool_chain",)


class _ImageFileNotFound(ImageReadError, FileNotFoundError):
    """An image file that cannot be read (both ImageReadError and FileNotFoundError)."""


# ----------------------------------------------------------------------------
# procedural seabed
# ----------------------------------------------------------------------------

def _blob_polygons(rng: np.random.Generator, cx: np.ndarray, cy: np.ndarray, r: np.ndarray,
                   rough: float = 0.22, n: int = 48) -> np.ndarray:
    """Irregular closed outlines (pebbles, rocks), (N, n, 2) fixed-point (3 bits) int32."""
    k = len(r)
    t = np.linspace(0, 2 * math.pi, n, endpoint=False)[None, :]
    rad = np.ones((k, n))
    for harm in range(2, 6):
        amp = rough / harm * rng.standard_normal((k, 1))
        rad += amp * np.cos(harm * t + rng.uniform(0, 2 * math.pi, (k, 1)))
    rad = np.clip(rad, 0.45, 1.6) * r[:, None]
    aspect = rng.uniform(0.55, 1.0, (k, 1))
    phi = rng.uniform(0, math.pi, (k, 1))
    px, py = rad * np.cos(t), aspect * rad * np.sin(t)
    c, s = np.cos(phi), np.sin(phi)
    x = cx[:, None] + c * px - s * py
    y = cy[:, None] + s * px + c * py
    return np.round(np.stack([x, y], axis=2) * 8).astype(np.int32)


def seabed(shape: Shape = (480, 640), seed: int = 0) -> np.ndarray:
    """Procedural seabed photo: rippled sand, pebbles, rocks and algae.

    Multi-scale texture (grain, ripples, stones from 1 to ~50 px, rock rims
    lit from one side, soft cast shadows, dark algae patches) gives plenty of
    short curved edges but no long straight lines nor rectangles, so it holds
    nothing that looks like a docking marker. Feature sizes are in pixels,
    independent of ``shape``: a larger seabed shows a larger area.

    Parameters
    ----------
    shape : (int, int)
        ``(height, width)`` in pixels.
    seed : int
        Seed of ``numpy.random.default_rng``; same seed, same image.

    Returns
    -------
    numpy.ndarray
        ``(height, width, 3)`` uint8 BGR image (the clear scene, before water).

    Examples
    --------
    >>> img = seabed((60, 80), seed=3)
    >>> img.shape, str(img.dtype)
    ((60, 80, 3), 'uint8')
    >>> bool((img == seabed((60, 80), seed=3)).all())
    True
    """
    h, w = _check_shape(shape)
    rng = np.random.default_rng(seed)
    area = h * w / (480.0 * 640.0)
    q = 4  # low-frequency fields are made at 1/q resolution
    lh, lw = max(2, -(-h // q)), max(2, -(-w // q))

    # --- low-frequency fields at 1/4 resolution ----------------------------
    lum_low = 0.10 * _noise(rng, (lh, lw), 110 / q) + 0.06 * _noise(rng, (lh, lw), 28 / q)
    phi = rng.uniform(0, math.pi)
    lam = rng.uniform(20, 38)
    yy, xx = np.mgrid[0:lh, 0:lw].astype(np.float32)
    # low-res pixel j covers full-res pixels [q j, q j + q): its centre is q j + (q - 1) / 2
    xs, ys = xx * q + (q - 1) / 2.0, yy * q + (q - 1) / 2.0
    phase_low = ((xs * math.cos(phi) + ys * math.sin(phi)) * np.float32(2 * math.pi / lam)
                 + 2.8 * _noise(rng, (lh, lw), 130 / q) + 0.9 * _noise(rng, (lh, lw), 40 / q))
    amp_low = np.clip(0.55 + 0.5 * _noise(rng, (lh, lw), 160 / q), 0.0, 1.0) * np.float32(0.075)
    algae_low = _noise(rng, (lh, lw), 95 / q) + 0.45 * _noise(rng, (lh, lw), 30 / q)
    lum_l, phase, amp, algae_field = (
        cv2.resize(f.astype(np.float32), (lw * q, lh * q), interpolation=cv2.INTER_LINEAR)[:h, :w]
        for f in (lum_low, phase_low, amp_low, algae_low))

    # --- sand: colour, brightness, grain, ripples ---------------------------
    sand_choices = np.array([[150, 178, 196], [140, 156, 166], [118, 160, 186],
                             [128, 146, 150]], dtype=np.float32)
    base = sand_choices[rng.integers(len(sand_choices))] * np.float32(rng.uniform(0.85, 1.1))
    n6, n2, n1 = _noise(rng, (h, w), 6), _noise(rng, (h, w), 2), _fast_normal(rng, (h, w))
    grain = 0.05 * n6 + 0.035 * n2 + 0.05 * n1
    ripple = np.sin(phase)
    ripple += 0.35 * np.sin(2 * phase + 1.0)
    lum = 1.0 + lum_l + grain + amp * ripple

    # --- stones: power-law sizes, drawn big first --------------------------
    n_stones = int(rng.poisson(260 * area))
    u = rng.uniform(0, 1, n_stones)
    rmin, rmax = 1.5, 48.0
    radii = np.sort(rmin / (1 - u * (1 - rmin / rmax)))[::-1]  # density ~ r^-2
    cxs = rng.uniform(-radii, w + radii)
    cys = rng.uniform(-radii, h + radii)
    grey_v = rng.uniform(55, 200, n_stones)
    palette = np.array([[1.0, 1.0, 1.0], [0.86, 0.95, 1.06], [0.92, 0.98, 1.02],
                        [0.97, 1.02, 0.98], [0.80, 0.90, 1.08]])
    tints = palette[rng.integers(len(palette), size=n_stones)]
    tints = tints * (1.0 + 0.03 * rng.standard_normal((n_stones, 3)))
    cols = np.clip(grey_v[:, None] * tints, 0, 255)
    hvs = np.clip(60 + 3.5 * radii, 60, 255)
    big = radii >= 3.0
    polys = _blob_polygons(rng, cxs[big], cys[big], radii[big])
    stone = np.zeros((h, w, 4), np.uint8)   # B, G, R, alpha
    height = np.zeros((h, w), np.uint8)
    pi = 0
    for i in range(n_stones):
        colour = (float(cols[i, 0]), float(cols[i, 1]), float(cols[i, 2]), 255.0)
        if big[i]:
            pts = [polys[pi]]
            pi += 1
            cv2.fillPoly(stone, pts, colour, cv2.LINE_AA, 3)
            cv2.fillPoly(height, pts, float(hvs[i]), cv2.LINE_AA, 3)
        else:
            c8 = (int(round(cxs[i] * 8)), int(round(cys[i] * 8)))
            rr = int(round(radii[i] * 8))
            cv2.circle(stone, c8, rr, colour, -1, cv2.LINE_AA, 3)
            cv2.circle(height, c8, rr, float(hvs[i]), -1, cv2.LINE_AA, 3)
    a = stone[:, :, 3].astype(np.float32) * np.float32(1.0 / 255.0)
    # soft cast shadow of the stones on the sand (light from the upper left)
    sh = np.zeros_like(a)
    sh[3:, 3:] = a[:-3, :-3]
    sh = cv2.GaussianBlur(sh, (0, 0), 3.0)
    lum *= 1.0 - 0.38 * sh * (1.0 - a)
    stone_tex = 1.0 + 0.12 * n2 + 0.08 * n6 + 0.04 * n1
    # rim lighting and rounded tops from the stones' height map
    dome = cv2.distanceTransform((stone[:, :, 3] > 127).astype(np.uint8), cv2.DIST_L2, 3)
    hmap = height.astype(np.float32) + 6.0 * np.sqrt(np.minimum(dome, 30.0))
    hb = cv2.GaussianBlur(hmap, (0, 0), 1.6)
    gx = cv2.Sobel(hb, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(hb, cv2.CV_32F, 0, 1, ksize=3)
    shade = np.clip(1.0 - 0.0022 * (gx + gy), 0.55, 1.45)

    # --- algae: dark, fuzzy patches ---------------------------------------
    thr = rng.uniform(1.2, 1.6)
    fuzz = np.clip(0.6 + 0.3 * n2 + 0.25 * n6, 0.0, 1.0)
    alg = np.clip((algae_field - thr) * 2.5, 0.0, 1.0) * fuzz * np.float32(0.85)
    algae_cols = np.array([[38, 70, 48], [34, 56, 72], [52, 74, 60]], dtype=np.float32)
    acol = algae_cols[rng.integers(len(algae_cols))]

    # --- compose: sand * (1 - a) + stone * a, shading, algae ---------------
    ws = (1.0 - a) * lum
    wt = a * stone_tex
    keep = (1.0 - alg) * shade
    planes = []
    for c in range(3):  # planar arithmetic: much faster than (h, w, 3) broadcasting
        plane = stone[:, :, c].astype(np.float32)
        plane *= wt
        plane += ws * base[c]
        plane *= keep
        plane += alg * acol[c]
        planes.append(_to_uint8(plane))
    return cv2.GaussianBlur(cv2.merge(planes), (0, 0), 0.6)


def tiled_floor(shape: Shape = (480, 640), seed: int = 0, tile: float = 16.0) -> np.ndarray:
    """Procedural pool floor: square tiles with light grout lines, a chain and
    bricks lying on it, stains of silt.

    The repeated texture of a pool (the shared data's ``subvo_pool_chain``)
    is the trap for motion measurement: every tile looks like the next, so
    a shift by one tile matches almost as well as the true motion. The
    chain, the bricks and the stains are what tells one place from the next.

    Parameters
    ----------
    shape : (int, int)
        ``(height, width)`` in pixels.
    seed : int
    tile : float
        The tiles' period in pixels (>= 6).

    Returns
    -------
    numpy.ndarray
        ``(height, width, 3)`` uint8 BGR image.

    Examples
    --------
    >>> img = tiled_floor((64, 96), seed=1, tile=12)
    >>> img.shape, str(img.dtype)
    ((64, 96, 3), 'uint8')
    >>> bool((img == tiled_floor((64, 96), seed=1, tile=12)).all())
    True
    """
    h, w = _check_shape(shape)
    if not tile >= 6:
        raise ParameterError(f"tile must be at least 6 pixels, got {tile!r}")
    rng = np.random.default_rng(seed)
    hues = np.array([[150, 70, 30], [140, 110, 40], [120, 120, 110], [90, 130, 60]], np.float32)
    base = hues[rng.integers(len(hues))] * np.float32(rng.uniform(0.8, 1.15))
    grout = np.array([200, 205, 205], np.float32) * np.float32(rng.uniform(0.75, 1.0))
    phi = math.radians(float(rng.uniform(-3, 3)))      # the lattice is laid a little askew
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    u = (xx * math.cos(phi) + yy * math.sin(phi)) / tile + rng.uniform(0, 1)
    v = (-xx * math.sin(phi) + yy * math.cos(phi)) / tile + rng.uniform(0, 1)
    # each tile a little lighter or darker; grout lines about 1/8 of the period
    iu, iv = np.floor(u).astype(np.int64), np.floor(v).astype(np.int64)
    jitter = rng.uniform(0.85, 1.12, 4096).astype(np.float32)
    lum = jitter[(iu * 73 + iv * 151) % 4096]
    fu, fv = u - iu, v - iv
    half = np.float32(rng.uniform(0.05, 0.08))
    line = np.clip(1.0 - np.minimum(np.minimum(fu, 1 - fu), np.minimum(fv, 1 - fv)) / half,
                   0.0, 1.0)
    img = (1 - line)[..., None] * (base * lum[..., None]) + line[..., None] * grout
    # silt stains: soft light or dark patches
    stain = 0.18 * _noise(rng, (h, w), 12 * tile) + 0.08 * _noise(rng, (h, w), 2 * tile)
    img *= (1.0 + stain)[..., None]
    # bricks and a chain: what is not repeated
    area = h * w / (tile * tile)
    for _ in range(int(rng.poisson(max(area / 1500, 1)))):
        cx, cy = rng.uniform(0, w), rng.uniform(0, h)
        bw, bh = rng.uniform(3, 6) * tile, rng.uniform(1.5, 3) * tile
        box = cv2.boxPoints(((cx, cy), (bw, bh), rng.uniform(0, 180)))
        col = np.array([60, 90, 110], np.float32) * np.float32(rng.uniform(0.6, 1.2))
        cv2.fillPoly(img, [np.round(box * 8).astype(np.int32)], col.tolist(), cv2.LINE_AA, 3)
    pts = [(rng.uniform(0, w), rng.uniform(0, h))]
    for _ in range(6):
        a = rng.uniform(0, 2 * math.pi)
        d = rng.uniform(0.15, 0.4) * max(h, w)
        pts.append((pts[-1][0] + d * math.cos(a), pts[-1][1] + d * math.sin(a)))
    link = max(2.0, 0.35 * tile)
    for (x0, y0), (x1, y1) in zip(pts, pts[1:]):
        n = max(int(math.hypot(x1 - x0, y1 - y0) / link), 1)
        for t in np.linspace(0, 1, n, endpoint=False):
            c = (int(round((x0 + t * (x1 - x0)) * 8)), int(round((y0 + t * (y1 - y0)) * 8)))
            col = np.array([50, 70, 90], np.float32) * np.float32(rng.uniform(0.5, 1.6))
            cv2.circle(img, c, int(link * 4), col.tolist(), -1, cv2.LINE_AA, 3)
    img += (4.0 * _fast_normal(rng, (h, w)))[..., None]
    return cv2.GaussianBlur(_to_uint8(img), (0, 0), 0.6)


# ----------------------------------------------------------------------------
# real photos
# ----------------------------------------------------------------------------

@functools.lru_cache(maxsize=8)
def _real_photo_groups(root: str) -> tuple[tuple[str, ...], ...]:
    """Image files of the shared data, grouped by folder (sequences' and seabed/)."""
    base = Path(root)
    groups = []
    folders = sorted(p for p in (base / "sequences").glob("*") if p.is_dir())
    folders.append(base / "seabed")
    for folder in folders:
        if folder.name in _EXCLUDED_AUTO or not folder.is_dir():
            continue
        files = sorted(str(p) for p in folder.iterdir()
                       if p.suffix.lower() in (".png", ".jpg", ".jpeg"))
        if files:
            groups.append(tuple(files))
    return tuple(groups)


@functools.lru_cache(maxsize=24)
def _load_cached(path: str) -> np.ndarray:
    img = cv2.imread(path, cv2.IMREAD_COLOR)
    if img is None:
        err = _ImageFileNotFound(f"cannot read image file: {path}")
        err.filename = path
        raise err
    img.setflags(write=False)
    return img


def _load_image(path: Union[str, Path]) -> np.ndarray:
    """BGR uint8 image of a file (read-only, cached); FileNotFoundError naming the path."""
    return _load_cached(str(Path(path)))


def _random_real_photo(rng: np.random.Generator) -> np.ndarray | None:
    root = shared_data_dir()
    if root is None:
        return None
    groups = _real_photo_groups(str(root))
    if not groups:
        return None
    group = groups[int(rng.integers(len(groups)))]
    return _load_image(group[int(rng.integers(len(group)))])


def _source_photo(rng: np.random.Generator, source) -> np.ndarray | None:
    """The photo for ``source`` ("auto", "procedural", path or array), None = procedural."""
    if isinstance(source, np.ndarray):
        return _to_bgr(source)
    if isinstance(source, str) and source == "procedural":
        return None
    if isinstance(source, str) and source == "auto":
        return _random_real_photo(rng)
    if isinstance(source, str) and source == "tiles":
        return tiled_floor((720, 960), _seed_of(rng), tile=float(rng.uniform(14, 28)))
    if isinstance(source, (str, Path)):
        return _load_image(source)
    raise ParameterError(f"source must be 'auto', 'procedural', 'tiles', a path or an image, "
                         f"got {source!r}")


def background(shape: Shape = (480, 640), seed: int = 0,
               source: Union[str, Path] = "auto") -> np.ndarray:
    """A seabed background: a random real photo crop, or the procedural seabed.

    Parameters
    ----------
    shape : (int, int)
        ``(height, width)`` of the result.
    seed : int
        Chooses the photo, the crop and its flips (or the procedural seabed).
    source : {"auto", "procedural"} or path
        ``"auto"``: a photo of the shared data folder (a frame of one of the
        sequences, or ``seabed/*``; the tiled pool sequence is left out since
        tiles look like markers), picked at random, randomly cropped to the
        aspect of ``shape``, flipped and resized; :func:`seabed` when the
        shared data is absent. ``"procedural"``: always :func:`seabed`.
        ``"tiles"``: a pool floor (:func:`tiled_floor`). A path:
        that file, cropped and resized the same way.

    Returns
    -------
    numpy.ndarray
        ``(height, width, 3)`` uint8 BGR image.

    Raises
    ------
    FileNotFoundError
        ``source`` is a path that cannot be read as an image.

    Examples
    --------
    >>> bg = background((60, 80), seed=2, source="procedural")
    >>> bg.shape
    (60, 80, 3)
    >>> bool((bg == seabed((60, 80), seed=2)).all())  # procedural: the seabed of that seed
    True
    """
    h, w = _check_shape(shape)
    rng = np.random.default_rng(seed)
    photo = _source_photo(rng, source)
    if photo is None:
        return seabed((h, w), seed)
    ph, pw = photo.shape[:2]
    ar = w / h
    if pw / ph > ar:
        ch, cw = ph, ph * ar
    else:
        ch, cw = pw / ar, pw
    f = rng.uniform(0.6, 1.0)
    ch, cw = max(2, int(ch * f)), max(2, int(cw * f))
    y0 = int(rng.integers(0, ph - ch + 1))
    x0 = int(rng.integers(0, pw - cw + 1))
    crop = photo[y0:y0 + ch, x0:x0 + cw]
    interp = cv2.INTER_AREA if cw > w else cv2.INTER_LINEAR
    out = cv2.resize(crop, (w, h), interpolation=interp)
    if rng.uniform() < 0.5:
        out = out[:, ::-1]
    if rng.uniform() < 0.5:
        out = out[::-1]
    return np.ascontiguousarray(out)


def net(shape: Shape = (480, 640), seed: int = 0, mesh: float = 40.0, twine: float = 3.0,
        jitter: float = 0.0, holes: float = 0.0) -> np.ndarray:
    """A fish-farm net seen flat: bright twine in a square mesh of one
    shade over dark water, the trap of a repeated texture at its purest
    (every mesh cell like the next, nothing to tell one place from the next
    but ``jitter`` and ``holes``; :func:`tiled_floor`'s tiles come in
    shades and carry a chain and stains).

    Parameters
    ----------
    shape : (int, int)
        ``(height, width)`` in pixels.
    seed : int
    mesh : float
        The mesh's period in pixels (>= 8).
    twine : float
        The twine's thickness in pixels (0.5 to half the mesh).
    jitter : float
        Standard deviation of the knots' places, pixels (0: a perfect lattice).
    holes : float
        Share (0-1) of the twine's bars left out.

    Returns
    -------
    numpy.ndarray
        ``(height, width)`` uint8 grey image.

    Examples
    --------
    >>> img = net((64, 96), mesh=16)
    >>> img.shape, str(img.dtype), bool(img.max() > 150 and img.min() < 80)
    ((64, 96), 'uint8', True)
    """
    h, w = _check_shape(shape)
    if not mesh >= 8:
        raise ParameterError(f"mesh must be at least 8 pixels, got {mesh!r}")
    if not 0.5 <= twine <= mesh / 2:
        raise ParameterError(f"twine must be 0.5 to mesh / 2 pixels, got {twine!r}")
    if not (0 <= jitter and 0 <= holes <= 1):
        raise ParameterError(f"jitter must be >= 0 and holes in [0, 1], got {jitter!r}, "
                             f"{holes!r}")
    rng = np.random.default_rng(seed)
    ny, nx = int(h / mesh) + 3, int(w / mesh) + 3
    o = rng.uniform(0, mesh, 2)
    gy, gx = np.mgrid[0:ny, 0:nx].astype(np.float64)
    kx = (gx - 1) * mesh + o[0] + rng.normal(0, jitter, gx.shape) * (jitter > 0)
    ky = (gy - 1) * mesh + o[1] + rng.normal(0, jitter, gy.shape) * (jitter > 0)
    layer = np.zeros((h, w), np.float32)
    for dj, di in ((0, 1), (1, 0)):
        for j in range(ny - dj):
            for i in range(nx - di):
                if holes and rng.random() < holes:
                    continue
                p1 = (int(round(kx[j, i] * 16)), int(round(ky[j, i] * 16)))
                p2 = (int(round(kx[j + dj, i + di] * 16)), int(round(ky[j + dj, i + di] * 16)))
                cv2.line(layer, p1, p2, 1.0, max(1, int(round(twine))), cv2.LINE_AA, shift=4)
    layer = cv2.GaussianBlur(layer, (0, 0), 0.7)
    return np.clip(60.0 + 110.0 * layer, 0, 255).astype(np.uint8)
