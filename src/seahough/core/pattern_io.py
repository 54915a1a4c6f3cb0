"""A pattern's image in (grey, and its colours when it has some) and the
pattern's file out and back (:meth:`Pattern.save`, :meth:`Pattern.load`)."""

from __future__ import annotations

import os
import zipfile
import zlib
from pathlib import Path

import cv2
import numpy as np

from ..config import Config
from ..errors import ImageReadError, PatternError, WriteError
from ..io.images import read_image, to_gray, to_image

#: Version of the file format written by :func:`save`.
FILE_VERSION = 1


def grey_and_colour(image, name: str = "pattern", bit_depth: int | None = None):
    """``(grey, colour, alpha, name)``: a pattern image (path or array) as
    :func:`to_gray` makes it, as BGR float32 levels (:func:`to_image`) when
    it has colour (else None), the pixels its alpha channel keeps (a BGRA
    image with some transparent pixels: alpha > 0; else None), and the
    file's name (None for an array); a 16-bit one read as ``bit_depth``-bit
    data (:attr:`Config.bit_depth`). A file is read once."""
    path = None
    if isinstance(image, (str, os.PathLike)):
        name = path = str(image)
        image = read_image(image)
    # (its alpha is its mask, read below; its transparent pixels are not filled, as a
    # searched image's are: the step to them is its outline, a reviewer's find)
    rgb = image[..., :3] if isinstance(image, np.ndarray) and image.shape[2:] == (4,) else image
    colour = to_image(rgb, True, name=name, bit_depth=bit_depth)
    grey = to_gray(rgb, name=name, bit_depth=bit_depth)      # (both check the image first)
    alpha = None
    if isinstance(image, np.ndarray) and image.ndim == 3 and image.shape[2] == 4:
        a = np.nan_to_num(image[..., 3].astype(np.float64))
        if a.max() <= 0:
            raise PatternError(f"{name}: its alpha channel is 0 everywhere: every pixel is "
                               "transparent (give its pixels an alpha, or drop the channel)")
        if a.min() < a.max():
            alpha = a > 0
    return grey, (colour if colour.ndim == 3 else None), alpha, path


def outline_from_mask(mask, shape) -> list:
    """A pattern's outline: the largest outer contours of its ``mask`` (up to
    4), or its image's frame when it has none."""
    h, w = shape
    box = [np.array([(0, 0), (w - 1, 0), (w - 1, h - 1), (0, h - 1)], float)]
    if mask is None:
        return box
    cs, _ = cv2.findContours(mask.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    cs = sorted(cs, key=cv2.contourArea, reverse=True)
    return [c.reshape(-1, 2).astype(float) for c in cs[:4]] or box


def save(p, path) -> Path:
    """:meth:`Pattern.save` (see there)."""
    path = Path(path)
    if path.is_dir():   # (not "folder.npz" beside it)
        raise WriteError(f"{path}: is a folder; give the pattern file's name (a .npz file)")
    if path.suffix != ".npz":
        path = path.with_name(path.name + ".npz")
    arrays = {"version": np.array(FILE_VERSION), "gray": p._gray,
              "origin": np.array(p.origin, float), "polarity": np.array(p.polarity),
              "kind": np.array(p.kind), "closed": np.array(bool(p.closed)),
              "n_outline": np.array(len(p.outline))}
    for i, o in enumerate(p.outline):
        arrays[f"outline_{i}"] = o
    if p.mask is not None:
        arrays["mask"] = p.mask
    if p._edge_mask is not None:
        arrays["edge_mask"] = p._edge_mask
    if p._colour is not None:
        arrays["colour"] = p._colour
    if p.is_line:
        arrays["line"] = np.array([p.line_length, p.line_width], float)
    if p.kind == "polyline":   # its width, then its centre line
        arrays["polyline"] = np.r_[p.polyline_width, p.polyline_points.ravel()]
    try:
        with open(path, "wb") as f:
            np.savez_compressed(f, **arrays)
    except OSError as e:
        raise WriteError(f"{path}: cannot write the pattern ({e.strerror or e})") from None
    return path


def load(cls, path, config: Config | None = None):
    """:meth:`Pattern.load` (see there)."""
    path = Path(path)
    if path.name and not path.exists() and path.suffix != ".npz":
        npz = path.with_name(path.name + ".npz")
        if npz.is_file():
            path = npz   # (save added it, as numpy's savez does)
    bad = f"{path}: not a saved seahough pattern"
    try:
        z = np.load(path, allow_pickle=False)
    except FileNotFoundError:
        raise ImageReadError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise ImageReadError(f"{path}: is a folder") from None
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error) as e:
        # (numpy says "pickled data ... allow_pickle" of any file that is not an
        # .npy or .npz archive, e.g. an image: not what the user needs to read)
        why = "not an .npz archive" if "pickle" in str(e) else e
        raise PatternError(f"{bad} ({why}; Pattern.load reads what Pattern.save wrote, "
                           f"Pattern.from_image reads an image)") from None
    if not isinstance(z, np.lib.npyio.NpzFile):
        raise PatternError(f"{bad} (a single array, not a .npz archive)")
    try:
        with z:
            data = {k: z[k] for k in z.files}
        if int(data["version"]) != FILE_VERSION:
            raise ValueError(f"format version {int(data['version'])}, "
                             f"{FILE_VERSION} expected")
        kind = str(data["kind"])
        if kind == "line" and "line" not in data:
            raise ValueError("a line without its length and width")
        gray = np.ascontiguousarray(data["gray"], np.float32)
        if gray.ndim != 2 or gray.dtype != np.float32 or not np.isfinite(gray).all():
            raise ValueError("its image is not a finite grey image")
        colour = data.get("colour")
        if colour is not None:
            colour = np.ascontiguousarray(colour, np.float32)
            if colour.shape != gray.shape + (3,) or not np.isfinite(colour).all():
                raise ValueError("its colour image is not a finite BGR image of its size")
        mask = data.get("mask")
        outline = [data[f"outline_{i}"] for i in range(int(data["n_outline"]))]
        p = cls.__new__(cls)
        p._setup(gray, None if mask is None else mask.astype(bool),
                 tuple(float(v) for v in data["origin"]), str(data["polarity"]), kind,
                 outline, bool(data["closed"]), data.get("edge_mask"), config, colour)
        if kind == "line":
            p.line_length, p.line_width = (float(v) for v in data["line"])
        if kind == "polyline":
            v = np.asarray(data["polyline"], float)
            p.polyline_width, p.polyline_points = float(v[0]), v[1:].reshape(-1, 2)
    except (KeyError, TypeError, ValueError, IndexError, zipfile.BadZipFile,
            zlib.error, EOFError, OSError) as e:
        raise PatternError(f"{bad} ({e})") from None
    return p


#: A pattern is painted (:attr:`Pattern.painted`), and searched by its colour
#: edges when ``Config.colour`` is None (the default), when at least
#: :data:`PAINTED_SHARE` of its pixels (its mask's, when it has one) have a
#: chroma (the largest of their B, G, R levels less the smallest, 0-255) of at
#: least this. Paints have 120-255 (the coloured markers of
#: bench/bench_colour.py: green 120, red 170, yellow 205, orange 255).
PAINTED_CHROMA = 80.0
#: ... the share: in 1,374 random crops (64-256 px) of the shared real photos
#: and sequences, at most 0.001 of a seabed crop's pixels reach that chroma,
#: 0.11 of a tiled pool's; RoboSub's pool photos, whose water is as saturated
#: as paint, are painted everywhere (a crop of them is searched in colour).
PAINTED_SHARE = 0.2


def painted(colour, mask) -> bool:
    """Whether a pattern's BGR levels (None: a grey pattern) are painted: at
    least :data:`PAINTED_SHARE` of them (of those in ``mask``, boolean; None:
    every pixel) have a chroma of at least :data:`PAINTED_CHROMA`.

    >>> bgr = np.full((40, 60, 3), 30, np.float32)
    >>> bgr[10:30, 15:45] = (0, 120, 255)           # an orange board on a dark ground
    >>> painted(bgr, None), painted(bgr[:, :12], None), painted(None, None)
    (True, False, False)
    """
    return paint_share(colour, mask) >= PAINTED_SHARE


def paint_share(colour, mask) -> float:
    """The share of a pattern's BGR levels (of those in ``mask``) with a
    chroma of at least :data:`PAINTED_CHROMA` (0 for a grey pattern).

    >>> bgr = np.full((40, 40, 3), 30, np.float32); bgr[:10] = (0, 120, 255)
    >>> paint_share(bgr, None), paint_share(None, None)
    (0.25, 0.0)
    """
    if colour is None:
        return 0.0
    chroma = colour.max(axis=2) - colour.min(axis=2)
    if mask is not None:
        chroma = chroma[mask]
    return float((chroma >= PAINTED_CHROMA).mean()) if chroma.size else 0.0
