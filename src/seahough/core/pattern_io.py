"""A pattern's image in (grey, and its colours when it has some) and the
pattern's file out and back (:meth:`Pattern.save`, :meth:`Pattern.load`)."""

from __future__ import annotations

import os
import zipfile
import zlib
from pathlib import Path

import numpy as np

from ..config import Config
from ..errors import ImageReadError, PatternError, WriteError
from ..io.images import read_image, to_gray, to_image

#: Version of the file format written by :func:`save`.
FILE_VERSION = 1


def grey_and_colour(image, name: str = "pattern"):
    """``(grey, colour)``: a pattern image (path or array) as :func:`to_gray`
    makes it, and as BGR float32 levels (:func:`to_image`) when it has colour
    (else None). A file is read once."""
    if isinstance(image, (str, os.PathLike)):
        name = str(image)
        image = read_image(image)
    colour = to_image(image, True, name=name)
    return to_gray(image, name=name), (colour if colour.ndim == 3 else None)


def save(p, path) -> Path:
    """:meth:`Pattern.save` (see there)."""
    path = Path(path)
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
    bad = f"{path}: not a saved seahough pattern"
    try:
        z = np.load(path, allow_pickle=False)
    except FileNotFoundError:
        raise ImageReadError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise ImageReadError(f"{path}: is a folder") from None
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error) as e:
        raise PatternError(f"{bad} ({e})") from None
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
