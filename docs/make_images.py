"""Regenerate the README's demo pictures from what ``seahough demo`` draws today.

Usage (from the repository root, with the package installed)::

    python docs/make_images.py              # docs/images/demo_overlay.jpg, demo_accumulator.jpg
    python docs/make_images.py --out DIR    # the same two files into DIR

It runs the demo (the code path of ``seahough demo --out TMP --quiet``) into
a temporary folder, prints the demo's table, and turns two of its pictures
into small JPEGs (each well under 150 KB) for a README about 760 px wide:

- ``demo_overlay.jpg``: ``marker_overlay.png`` (the marker found in the
  simulated scene, with its label), scaled to 760 px wide.
- ``demo_accumulator.jpg``: ``marker_accumulator.png``'s two planes cut
  apart at the white gap between them and stacked, each at full resolution
  (about 620 px wide), so that the axis text stays as readable as in the
  PNG; shrinking the 1300 px wide figure to README width would make its
  10-point text 6 px tall.

Run it after any change that alters what the demo finds or draws (a label, a
colour bar, a detector change that moves a number) and commit the JPEGs with
that change. ``docs/images/mosaic_amphorae.jpg`` comes from real data and is
not touched.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np

README_WIDTH = 760          # px: what the README shows at most
JPEG_QUALITY = 85
WHITE = 250                 # a pixel at least this bright in every channel is background
HERE = Path(__file__).resolve().parent


def run_demo(folder: Path) -> None:
    """``seahough demo --out folder --quiet``, in this process."""
    from seahough.cli import cli

    rv = cli.main(args=["demo", "--out", str(folder), "--quiet"], prog_name="seahough",
                  standalone_mode=False)
    if rv not in (0, None):
        raise SystemExit(f"make_images: the demo failed (exit status {rv})")


def _read(path: Path) -> np.ndarray:
    im = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if im is None:
        raise SystemExit(f"make_images: the demo did not write {path}")
    return im


def trim(im: np.ndarray, margin: int = 8) -> np.ndarray:
    """``im`` without its white border, keeping ``margin`` px of it."""
    ink = (im < WHITE).any(axis=2)
    rows, cols = np.flatnonzero(ink.any(axis=1)), np.flatnonzero(ink.any(axis=0))
    if rows.size == 0:
        return im
    y0, y1 = max(rows[0] - margin, 0), min(rows[-1] + margin + 1, im.shape[0])
    x0, x1 = max(cols[0] - margin, 0), min(cols[-1] + margin + 1, im.shape[1])
    return im[y0:y1, x0:x1]


def split_panels(im: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The two side-by-side panels of an accumulator picture, cut at the
    widest all-white column run in the middle third."""
    w = im.shape[1]
    blank = ~(im < WHITE).any(axis=2).any(axis=0)
    best, run, start, cut = 0, 0, 0, w // 2
    for x in range(w // 3, 2 * w // 3):
        if blank[x]:
            if run == 0:
                start = x
            run += 1
            if run > best:
                best, cut = run, start + run // 2
        else:
            run = 0
    if best < 4:
        raise SystemExit("make_images: no gap between the accumulator's panels")
    return im[:, :cut], im[:, cut:]


def stack(images, gap: int = 12) -> np.ndarray:
    """Images one above the other on white, left-aligned."""
    width = max(im.shape[1] for im in images)
    parts = []
    for i, im in enumerate(images):
        pad = np.full((im.shape[0], width - im.shape[1], 3), 255, np.uint8)
        parts.append(np.hstack([im, pad]))
        if i < len(images) - 1:
            parts.append(np.full((gap, width, 3), 255, np.uint8))
    return np.vstack(parts)


def fit_width(im: np.ndarray, width: int = README_WIDTH) -> np.ndarray:
    """``im`` scaled down (never up) to at most ``width`` px wide."""
    h, w = im.shape[:2]
    if w <= width:
        return im
    return cv2.resize(im, (width, round(h * width / w)), interpolation=cv2.INTER_AREA)


def write_jpeg(path: Path, im: np.ndarray) -> int:
    ok = cv2.imwrite(str(path), im, [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY,
                                      cv2.IMWRITE_JPEG_OPTIMIZE, 1])
    if not ok:
        raise SystemExit(f"make_images: cannot write {path}")
    return path.stat().st_size


def make_images(out: Path) -> dict:
    """Run the demo and write the README pictures into ``out``; returns
    ``{file name: (width, height, bytes)}``."""
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="seahough-images-") as tmp:
        demo = Path(tmp)
        run_demo(demo)
        overlay = fit_width(_read(demo / "marker_overlay.png"))
        planes = [trim(p) for p in split_panels(_read(demo / "marker_accumulator.png"))]
        accumulator = fit_width(stack(planes))
    made = {}
    for name, im in (("demo_overlay.jpg", overlay), ("demo_accumulator.jpg", accumulator)):
        size = write_jpeg(out / name, im)
        made[name] = (im.shape[1], im.shape[0], size)
    return made


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=HERE / "images",
                    help="folder for the JPEGs (default: docs/images)")
    args = ap.parse_args(argv)
    for name, (w, h, size) in make_images(args.out).items():
        print(f"wrote {args.out / name}  {w}x{h}  {size / 1024:.0f} KB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
