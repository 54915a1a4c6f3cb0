"""A tour that needs no files and no network: simulate, detect, dead-reckon.

:func:`run_demo` is what ``seahough demo`` runs: it makes an underwater
scene with a board marker, one with a rope and a short seabed sequence,
finds the marker (from its clean image) and the rope (a line pattern),
dead-reckons the sequence, writes every picture to a folder and returns
what was found against the truth.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from . import sim
from . import viz as plot
from .core.detector import Detection, Detector
from .core.pattern import Pattern
from .errors import WriteError
from .geometry import apply_matrix, format_angle, invert_matrix
from .motion.odometry import run_odometry
from .io.images import write_image

__all__ = ["run_demo", "DemoResult"]

_FRAME_SIZE = (240, 320)     # (h, w) of the sequence's frames
_N_FRAMES = 8


@dataclass
class DemoResult:
    """What :func:`run_demo` found and wrote.

    Attributes
    ----------
    out : pathlib.Path
        The folder written.
    rows : list of (str, str, str, str)
        The found-vs-truth table: ``(what, found, truth, error)`` per line,
        e.g. ``("marker position", "(185.2, 252.9) px", "(185.2, 252.9) px",
        "0.02 px")``.
    files : list of str
        The pictures written, relative to ``out`` (the sequence's frames as
        one entry ``"sequence/frame_000.png ... frame_007.png"``).
    ok : bool
        The marker and the rope were found and the last frame of the
        sequence has a position.
    marker, rope : Detection or None
        The best marker and rope detections (None: not found).
    drift_percent : float or None
        Distance between the dead-reckoned and the true end point, in
        percent of the true path length (None: no position for the last
        frame).
    """

    out: Path
    rows: list = field(default_factory=list)
    files: list = field(default_factory=list)
    ok: bool = True
    marker: Detection | None = None
    rope: Detection | None = None
    drift_percent: float | None = None


def _angle_err(a, b, period=360.0):
    return abs((a - b + period / 2) % period - period / 2)


def _search(o: Path, stem: str, scene, pattern: Pattern, what: str, written: list, *,
            edges: bool = False, **search) -> Detection | None:
    """Write ``<stem>_scene.png``, search it for ``pattern`` and draw the
    result (``_overlay``, ``_accumulator`` and with ``edges`` ``_edges``);
    the names go to ``written``. The best detection, or None."""
    write_image(o / f"{stem}_scene.png", scene)
    res = Detector(pattern, **search).search(scene)
    plot.plot_detections(scene, res.detections, o / f"{stem}_overlay.png", pattern=pattern,
                         title=f"{stem}: {what}")
    plot.plot_accumulator(res.planes, res.detections, o / f"{stem}_accumulator.png",
                          title=f"{stem}: accumulator planes")
    written += [f"{stem}_scene.png", f"{stem}_overlay.png", f"{stem}_accumulator.png"]
    if edges:
        plot.plot_edges(scene, res.features, o / f"{stem}_edges.png",
                        title=f"{stem} scene: edges")
        written.append(f"{stem}_edges.png")
    return res.detections[0] if res.detections else None


def _add_rows(result: DemoResult, found: list | None, missing: tuple) -> None:
    """The found-vs-truth rows of one object, or its NOT FOUND row."""
    if found is None:
        result.ok = False
        result.rows.append(missing)
    else:
        result.rows += found


def run_demo(out="seahough-demo", *, progress: bool = False,
             note: Callable[[str], None] | None = None) -> DemoResult:
    """Simulate, detect and dead-reckon, writing every picture to ``out``.

    Parameters
    ----------
    out : str or path-like
        The folder (created if needed): ``marker_scene.png``,
        ``marker_pattern.png``, ``marker_overlay.png``,
        ``marker_accumulator.png``, ``marker_edges.png``, ``rope_scene.png``,
        ``rope_overlay.png``, ``rope_accumulator.png``,
        ``sequence/frame_000.png`` ... ``frame_007.png``, ``trajectory.png``
        and the dead reckoning's own files in ``odometry/``.
    progress : bool
        The dead reckoning's progress bar on stderr (drawn only when it is a
        terminal).
    note : callable, optional
        Called with the name of each stage as it starts ("marker scene",
        "rope scene", "seabed sequence and dead reckoning").

    Returns
    -------
    DemoResult
        The found-vs-truth table, the files written, and whether everything
        was found.

    Raises
    ------
    WriteError
        The folder or a picture cannot be written (an ``OSError``).

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as d:
    ...     result = run_demo(d)
    >>> result.ok, [row[0] for row in result.rows][:3]
    (True, ['marker position', 'marker angle', 'marker scale'])
    >>> result.files[:2]
    ['marker_scene.png', 'marker_overlay.png']
    """
    say = note if note is not None else (lambda stage: None)
    o = Path(out)
    try:
        o.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise WriteError(f"{o}: {e.strerror or e}") from None
    outcome = DemoResult(out=o)
    written = outcome.files

    # 1. the marker
    say("marker scene")
    scene, pat_img, tr = sim.marker_scene("board", water="moderate", seed=11, source="procedural")
    write_image(o / "marker_pattern.png", pat_img)
    d = outcome.marker = _search(o, "marker", scene, Pattern.from_image(pat_img),
                                 "Pattern.from_image(clean marker), scale 0.5-2, any rotation",
                                 written, edges=True, scale_range=(0.5, 2.0))
    written.append("marker_pattern.png")
    _add_rows(outcome, None if d is None else [
        ("marker position", f"({d.x:.1f}, {d.y:.1f}) px", f"({tr.x:.1f}, {tr.y:.1f}) px",
         f"{math.hypot(d.x - tr.x, d.y - tr.y):.2f} px"),
        ("marker angle", f"{format_angle(d.angle)}°", f"{format_angle(tr.angle)}°",
         f"{_angle_err(d.angle, tr.angle):.2f}°"),
        ("marker scale", f"{d.scale:.3f}", f"{tr.scale:.3f}",
         f"{100 * abs(d.scale / tr.scale - 1):.2f} %"),
    ], ("marker", "NOT FOUND", f"({tr.x:.1f}, {tr.y:.1f}) px", "-"))

    # 2. the rope
    say("rope scene")
    rope, rtr = sim.rope_scene(width=8, water="moderate", seed=5, source="procedural")
    rd = outcome.rope = _search(o, "rope", rope, Pattern.line(200, 8),
                                "Pattern.line(200, 8), any direction", written,
                                scale_range=(0.5, 2.0), angle_range=(0.0, 180.0), max_results=1)
    true_angle = f"{format_angle(rtr.line_angle, 2, 180.0)}°"
    _add_rows(outcome, None if rd is None else [
        ("rope angle", f"{format_angle(rd.line_angle, 2, 180.0)}°", true_angle,
         f"{_angle_err(rd.line_angle, rtr.line_angle, 180.0):.2f}°"),
        ("rope offset", f"{rd.line_offset:+.1f} px", f"{rtr.line_offset:+.1f} px",
         f"{abs(rd.line_offset - rtr.line_offset):.2f} px"),
    ], ("rope", "NOT FOUND", true_angle, "-"))

    # 3. dead reckoning
    say("seabed sequence and dead reckoning")
    frames, mats = sim.sequence(n_frames=_N_FRAMES, frame_size=_FRAME_SIZE, path="turn",
                                step=24.0, water="moderate", seed=3, source="procedural")
    seq_dir = o / "sequence"
    seq_dir.mkdir(exist_ok=True)
    for i, f in enumerate(frames):
        write_image(seq_dir / f"frame_{i:03d}.png", f)
    written.append(f"sequence/frame_000.png ... frame_{_N_FRAMES - 1:03d}.png")
    h, w = _FRAME_SIZE
    c = np.array([(w - 1) / 2.0, (h - 1) / 2.0])
    true_xy = np.array([apply_matrix(invert_matrix(m), [c])[0] for m in mats])
    odo = run_odometry([str(seq_dir)], str(o / "odometry"), scale_range=(0.9, 1.1),
                       angle_range=(-20.0, 20.0), progress=progress, mosaic=True)
    track = list(odo.rows)
    # x, y: where each frame's centre lies in frame-0 pixels, as the truth
    est = np.array([[np.nan if r.get("x") is None else float(r["x"]),
                     np.nan if r.get("y") is None else float(r["y"])] for r in track], float)
    plot.plot_trajectory(track, o / "trajectory.png", truth=true_xy,
                         title=f"dead reckoning over {_N_FRAMES} simulated frames "
                         "(grey band: truth)")
    written.append("trajectory.png")
    for name in ("mosaic_path", "trajectory_path", "csv_path"):
        p = getattr(odo, name, None)
        if p:
            written.append(os.path.relpath(str(p), str(o)))
    length = float(np.hypot(*np.diff(true_xy, axis=0).T).sum())
    flagged = sum(1 for r in track[1:] if r.get("flags"))
    end = est[-1] - est[0]
    true_end = true_xy[-1] - true_xy[0]
    if np.all(np.isfinite(end)):
        outcome.drift_percent = 100 * float(np.hypot(*(end - true_end))) / max(length, 1e-9)
        err = f"drift {outcome.drift_percent:.2f} % of {length:.0f} px"
    else:
        outcome.ok, err = False, "no position for the last frame"
    outcome.rows.append(("odometry end point", f"({end[0]:+.1f}, {end[1]:+.1f}) px",
                         f"({true_end[0]:+.1f}, {true_end[1]:+.1f}) px",
                         err + (f", {flagged} flagged" if flagged else "")))
    return outcome
