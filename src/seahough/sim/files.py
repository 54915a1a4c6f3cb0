"""Simulated scenes written to a folder, with their ground truth in ``truth.json``.

:func:`write_simulation` is what ``seahough simulate`` runs: it renders
scenes with the simulator (:mod:`seahough.sim`) and writes them as PNG files
beside a ``truth.json`` that holds the exact poses, rope lines or camera
motions, so that settings can be tested on files.
"""

from __future__ import annotations

import dataclasses
import json
import os
import sys
from pathlib import Path

import numpy as np

from .._validate import number
from ..errors import ParameterError, WriteError
from ..geometry import apply_matrix, compose, invert_matrix, wrap_angle
from ..io.images import read_image, to_bgr8, write_image
from .markers import MARKERS, marker
from .scenes import frame_pair, marker_scene, negative_scene, rope_scene
from .sequences import sequence
from .water import PRESETS

__all__ = ["write_simulation", "KINDS", "WATERS", "PATHS"]

#: What :func:`write_simulation` can write.
KINDS: tuple[str, ...] = ("marker", "rope", "pair", "sequence", "negative")
#: Water conditions: the presets of :class:`seahough.sim.Water`, or "none"
#: (no degradation).
WATERS: tuple[str, ...] = (*PRESETS, "none")
#: Camera paths of a sequence (see :func:`seahough.sim.sequence`).
PATHS: tuple[str, ...] = ("line", "turn", "loop")

_CONVENTION = ("pixels (x right, y down), (0, 0) = centre of the top-left pixel; angles in "
               "degrees counter-clockwise as displayed, a pose's in [0, 360) as Detection.angle, "
               "a pair's turn in [-180, 180) as Motion.angle; matrices are 2x3, pattern (or "
               "previous-frame) pixel -> scene pixel")


def _choice(name: str, value, choices) -> None:
    if value not in choices:
        raise ParameterError(f"{name}={value!r}: must be one of "
                             + ", ".join(repr(c) for c in choices))


def _truth_dict(truth) -> dict:
    """The fields of a :class:`~seahough.sim.Truth` that apply, as JSON values."""
    d = {}
    for f in dataclasses.fields(truth):
        v = getattr(truth, f.name)
        if v is None:
            continue
        d[f.name] = np.asarray(v).tolist() if isinstance(v, np.ndarray) else (
            float(v) if isinstance(v, (float, np.floating)) else v)
    return d


def write_simulation(kind: str, out, *, n: int | None = None, seed: int = 0,
                     water: str = "moderate", marker_name: str = "board",
                     size: tuple[int, int] | None = None, path: str = "line",
                     procedural: bool = False, photo=None, progress: bool = False) -> dict:
    """Write ``n`` simulated scenes of ``kind`` and their ``truth.json`` into ``out``.

    Parameters
    ----------
    kind : {"marker", "rope", "pair", "sequence", "negative"}
        ``marker``: seabed photos with a docking marker (``marker_000.png``
        ...) plus the clean marker (``pattern.png``, ``pattern_mask.png``);
        ``rope``: a rope across the frame; ``pair``: two overlapping camera
        frames a known motion apart (``pair_000_a.png``, ``pair_000_b.png``);
        ``sequence``: frames along a camera path (``frame_000.png`` ...);
        ``negative``: seabed photos with no marker.
    out : str or path-like
        The folder (created if needed).
    n : int, optional
        Number of scenes or pairs (default 1), or of frames of a sequence
        (default 10).
    seed : int
        Seed of the first scene (scene ``i`` uses ``seed + i``; a sequence
        uses ``seed``).
    water : {"clear", "moderate", "hard", "none"}
        Water conditions (:data:`seahough.sim.PRESETS`); "none": no degradation.
    marker_name : {"board", "rectangle", "L", "cross"}
        Marker drawn in marker scenes (:data:`seahough.sim.MARKERS`).
    size : (int, int), optional
        Scene width and height in px (default 640 x 480; sequence 320 x 240).
    path : {"line", "turn", "loop"}
        Camera path of a sequence.
    procedural : bool
        Procedural seabed backgrounds only (default: real photos when the
        shared data folder is present).
    photo : str or path-like, optional
        A seabed photo of one's own to render every scene from (not with
        ``procedural``; a photo taken underwater has its water already:
        ``water="none"`` keeps it as it is): a sequence or a pair is a camera's views of it, a
        marker or a rope lies on crops of it. A photo larger than the views
        need is not magnified (a sequence along a long path spans more than
        its frames: a photo magnified more than 2x to hold them is said so on
        the ``"seahough.sim"`` logger).
    progress : bool
        A progress bar on stderr (drawn only when it is a terminal) for more
        than one scene or frame.

    Returns
    -------
    dict
        The truth, as written to ``out/truth.json``: the settings (``source``:
        "auto", "procedural", or the photo's absolute path), and
        ``scenes`` (one entry per scene or pair: its file names, seed and
        the :class:`~seahough.sim.Truth` fields that apply) or, for a
        sequence, ``frames`` (per frame: ``matrix_from_first``,
        ``centre_in_first`` and ``motion_from_previous``).

    Raises
    ------
    ParameterError
        A parameter is not one of its choices or out of range.
    ImageReadError, ImageSizeError
        ``photo`` cannot be read as an image, or is too large to be read.
    WriteError
        The folder or a file cannot be written (an ``OSError``).

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> with tempfile.TemporaryDirectory() as d:
    ...     truth = write_simulation("marker", d, size=(160, 120), water="none",
    ...                              procedural=True)
    ...     files = sorted(p.name for p in Path(d).iterdir())
    >>> files
    ['marker_000.png', 'pattern.png', 'pattern_mask.png', 'truth.json']
    >>> truth["scenes"][0]["file"], len(truth["scenes"][0]["matrix"])
    ('marker_000.png', 2)
    """
    _choice("kind", kind, KINDS)
    _choice("water", water, WATERS)
    _choice("marker_name", marker_name, MARKERS)
    _choice("path", path, PATHS)
    seed = int(number("seed", seed, lo=0, integer=True))
    if n is not None:
        n = int(number("n", n, lo=1, integer=True))
    if size is None:
        size = (320, 240) if kind == "sequence" else (640, 480)
    if len(size) != 2:
        raise ParameterError(f"size={size!r}: expected (width, height)")
    w, h = (int(number(f"size[{i}]", v, lo=1, integer=True)) for i, v in enumerate(size))
    source = "procedural" if procedural else "auto"
    if photo is not None:
        if procedural:
            raise ParameterError("photo and procedural: give one of them (a photo of one's own "
                                 "or the procedural seabed)")
        # (read first: a photo that cannot be read says so before anything is written)
        image = _photo(photo)
    out = Path(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise WriteError(f"{out}: cannot create the folder ({e.strerror or e})") from None
    truth: dict = {"kind": kind, "seed": seed, "water": water, "width": w, "height": h,
                   "source": source if photo is None else os.path.abspath(photo),
                   "convention": _CONVENTION}
    count = n if n is not None else (10 if kind == "sequence" else 1)
    bar = None
    if progress and count > 1:
        from tqdm import tqdm

        unit = "frame" if kind == "sequence" else ("pair" if kind == "pair" else "scene")
        bar = tqdm(None, total=count, desc="simulate", unit=unit, file=sys.stderr,
                   disable=None, leave=False, dynamic_ncols=True)
    try:
        _simulate_into(kind, out, truth, count, bar, seed=seed,
                       water=None if water == "none" else water,
                       source=source if photo is None else image,
                       marker_name=marker_name, size=(w, h), path=path)
    finally:
        if bar is not None:
            bar.close()
    target = out / "truth.json"
    try:
        target.write_text(json.dumps(truth, indent=1) + "\n")
    except OSError as e:
        raise WriteError(f"{target}: {e.strerror or e}") from None
    return truth


def _photo(path) -> np.ndarray:
    """A user's seabed photo as 8-bit BGR (read-only). A 16-bit one holding
    fewer bits (a 10- or 12-bit camera's samples) is stretched by the bits
    its brightest level needs, not darkened by 257."""
    img = read_image(path)
    depth = None
    if img.dtype == np.uint16:
        depth = min(16, max(8, int(img.max()).bit_length()))
    out = to_bgr8(img, depth)
    if float(out.std()) < 2.0:   # (no texture: every view would be blank)
        raise ParameterError(f"photo {path}: a flat picture (grey levels {int(out.min())}-"
                             f"{int(out.max())}): no seabed to render views of")
    out.setflags(write=False)
    return out


def _simulate_into(kind, out: Path, truth: dict, count: int, bar, *, seed, water, source,
                   marker_name, size, path) -> None:
    """The scenes of :func:`write_simulation`, written one by one (``bar``
    ticks per scene or frame written)."""
    tick = (lambda: None) if bar is None else (lambda: bar.update(1))
    w, h = size
    if kind == "sequence":
        if bar is not None:
            bar.set_description("simulate (rendering)")
        frames, mats = sequence(n_frames=count, frame_size=(h, w), path=path, water=water,
                                seed=seed, source=source)
        if bar is not None:
            bar.set_description("simulate")
        c = np.array([(w - 1) / 2.0, (h - 1) / 2.0])
        rows = []
        for i, (f, m) in enumerate(zip(frames, mats)):
            name = f"frame_{i:03d}.png"
            write_image(out / name, f)
            centre = apply_matrix(invert_matrix(m), [c])[0]
            row = {"file": name, "matrix_from_first": np.asarray(m).tolist(),
                   "centre_in_first": centre.tolist()}
            if i:
                row["motion_from_previous"] = compose(m, invert_matrix(mats[i - 1])).tolist()
            rows.append(row)
            tick()
        truth.update(path=path, frames=rows)
        return
    scenes = []
    if kind == "marker":
        pat, mask = marker(marker_name)
        write_image(out / "pattern.png", pat)
        write_image(out / "pattern_mask.png", mask)
        truth.update(marker=marker_name, pattern="pattern.png", pattern_mask="pattern_mask.png")
    for i in range(count):
        s = seed + i
        if kind == "marker":
            scene, _, tr = marker_scene(marker_name, (h, w), water=water, seed=s, source=source)
            name = f"marker_{i:03d}.png"
            write_image(out / name, scene)
            scenes.append({"file": name, "seed": s, **_truth_dict(tr)})
        elif kind == "negative":
            scene = negative_scene((h, w), water=water, seed=s, source=source)
            name = f"negative_{i:03d}.png"
            write_image(out / name, scene)
            scenes.append({"file": name, "seed": s, "marker": False})
        elif kind == "rope":
            width = 8.0
            scene, tr = rope_scene((h, w), width=width, water=water, seed=s, source=source)
            name = f"rope_{i:03d}.png"
            write_image(out / name, scene)
            scenes.append({"file": name, "seed": s, "width": width, **_truth_dict(tr)})
        else:  # pair
            a, b, tr = frame_pair(frame_size=(h, w), water=water, seed=s, source=source)
            na, nb = f"pair_{i:03d}_a.png", f"pair_{i:03d}_b.png"
            write_image(out / na, a)
            write_image(out / nb, b)
            rec = _truth_dict(tr)
            if "angle" in rec:   # (as estimate_motion reports a turn: [-180, 180))
                rec["angle"] = wrap_angle(rec["angle"], low=-180.0)
            scenes.append({"previous": na, "current": nb, "seed": s, **rec})
        tick()
    truth["scenes"] = scenes
