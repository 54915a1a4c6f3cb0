"""The picture of the accumulator (the paper's Fig. 4): its dx-dy and
scale-rotation planes, with each detection ringed and numbered."""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure

from ..errors import ParameterError
from ..geometry import wrap_angle
from ._figure import _TEXT_OUTLINE, _figure, _finish
from .detections import colours

#: What the accumulator planes' heights are (see :func:`plot_accumulator`):
#: votes over the number of pattern points, pooled over 2 x 2 position bins,
#: so a peak is often above 1; not the 0-1 score of a detection.
_VOTES = "votes per pattern point (2x2 bins pooled: can exceed 1)"


def _ring(ax, x, y, colour, ms=22):
    """A hollow circle around (x, y) that leaves the peak inside visible."""
    ax.plot([x], [y], "o", ms=ms, mfc="none", mec="black", mew=4.0, clip_on=False)
    ax.plot([x], [y], "o", ms=ms, mfc="none", mec=colour, mew=2.0, clip_on=False)


def _edges_from_centres(c, log=False, single_half=1.0):
    """Bin edges around the bin centres ``c`` (midway between them, on a log
    scale when ``log``); a single bin is ``single_half`` wide each side."""
    c = np.asarray(c, float)
    if log:
        c = np.log(c)
    if c.size == 1:
        e = np.array([c[0] - single_half, c[0] + single_half])
    else:
        mid = 0.5 * (c[1:] + c[:-1])
        e = np.concatenate([[c[0] - (mid[0] - c[0])], mid, [c[-1] + (c[-1] - mid[-1])]])
    return np.exp(e) if log else e


def _display_angles(angles_deg):
    """Rotation bin centres made increasing (wrap-around removed) and centred
    on the searched range, e.g. -17.5..17.5 rather than 342.5..17.5."""
    a = np.degrees(np.unwrap(np.radians(np.asarray(angles_deg, float))))
    if a.size and np.mean(a) > 180.0 + 1e-9:
        a = a - 360.0
    return a


def _rotation_edges(planes) -> np.ndarray:
    """Bin edges of the scale-rotation plane's rotation axis, as displayed."""
    return _edges_from_centres(_display_angles(planes.angles), single_half=2.5)


def scale_angle_marker(planes, scale, angle) -> tuple[float, float]:
    """``(rotation, scale)`` at which a detection is marked on the
    scale-rotation plane: the centre of the cell it refers to.

    That is the cell the refined ``scale`` and ``angle`` (degrees) fall in,
    or, when a neighbouring cell across the nearer border (in rotation, in
    scale, or both) holds more votes, that one: the refinement moves a pose
    by up to a cell from its accumulator peak. The rotation axis of a full
    turn wraps around, so a detection at 359.998 from a peak in the first
    cell is marked there, at the plane's left edge, not half outside its
    right edge. On a partial span an angle outside it goes to the nearer
    end. The rotation returned is in displayed degrees (the plane's x axis,
    e.g. -17.5..17.5 for a search of -20..20) and is a cell centre, so a
    marker is never cut by the plane's border.

    Parameters
    ----------
    planes : AccumulatorPlanes
    scale, angle : float
        The detection's refined scale and rotation (degrees).

    Returns
    -------
    (float, float)

    Examples
    --------
    A plane of 72 rotation cells of 5 degrees and three scales, its peak
    in the first cell (0-5 degrees) at scale 1.0; a detection refined to
    just below 360 degrees is marked on that cell, not on the last one:

    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> from seahough.viz import scale_angle_marker
    >>> planes = SimpleNamespace(angles=np.arange(2.5, 360.0, 5.0),
    ...                          scales=np.array([0.9, 1.0, 1.1]), scale_angle=np.zeros((3, 72)))
    >>> planes.scale_angle[1, 0] = 2.0
    >>> scale_angle_marker(planes, 1.0, 359.998), scale_angle_marker(planes, 1.05, 100.0)
    ((2.5, 1.0), (102.5, 1.1))
    """
    centres = _display_angles(planes.angles)
    edges = _rotation_edges(planes)
    lo, hi = float(edges[0]), float(edges[-1])
    n = centres.size
    full = n > 1 and hi - lo >= 360.0 - 1e-6
    a = wrap_angle(angle, 360.0, lo)                      # in [lo, lo + 360)
    if not full and a > hi and (a - hi) > (lo - (a - 360.0)):
        a -= 360.0                                       # nearer the low end
    j0 = int(np.clip(np.searchsorted(edges, a, side="right") - 1, 0, n - 1))
    dj = -1 if a < centres[j0] else 1                    # towards the nearer border
    log_s = np.log(np.asarray(planes.scales, float))
    ls = math.log(max(float(scale), 1e-9))
    k0 = int(np.argmin(np.abs(log_s - ls)))
    dk = -1 if ls < log_s[k0] else 1
    sa = np.asarray(planes.scale_angle, float)
    best, cell = -np.inf, (k0, j0)
    for k, j in ((k0, j0), (k0, j0 + dj), (k0 + dk, j0), (k0 + dk, j0 + dj)):
        if full:
            j %= n                                       # own cell first: it wins ties
        if 0 <= k < log_s.size and 0 <= j < n and sa[k, j] > best:
            best, cell = sa[k, j], (k, j)
    k, j = cell
    return float(centres[j]), float(planes.scales[k])


def _place_peak_labels(ax, marks, ring_px=22):
    """``#k`` labels beside markers, moved up or down so that none covers
    another (markers of detections at the same place coincide).

    ``marks``: ``(text, x, y, colour)`` in data coordinates, best first.
    Returns the annotations."""
    fig = ax.figure
    renderer = fig.canvas.get_renderer()
    ax.apply_aspect()
    x0, x1 = sorted(ax.get_xlim())
    placed, out = [], []
    step = 15.0                                  # points between stacked labels
    for text, px, py, colour in marks:
        right = (px - x0) > 0.8 * (x1 - x0)
        dx = -14 if right else 14
        ann = ax.annotate(text, (px, py), xytext=(dx, 12), textcoords="offset points",
                          color=colour, fontsize=11, fontweight="bold",
                          ha="right" if right else "left", path_effects=_TEXT_OUTLINE,
                          annotation_clip=False)
        for k in range(1, 4 * len(marks) + 2):
            bb = ann.get_window_extent(renderer).expanded(1.0, 1.1)
            if not any(bb.overlaps(o) for o in placed):
                break
            # 12 + 15, 12 - 15 - ring, 12 + 30, ...: above first, then below the ring
            j = (k + 1) // 2
            dy = 12 + j * step if k % 2 else 12 - j * step - ring_px
            ann.set_position((dx, dy))
        placed.append(ann.get_window_extent(renderer))
        out.append(ann)
    return out


def plot_accumulator(planes, detections=(), path=None, *, title=None, note=None,
                     patterns=None, best=None) -> Figure:
    """The accumulator's two planes, as in the paper's Fig. 4.

    Left, *where*: the dx-dy plane (``planes.xy``): for each position of the
    pattern origin (image px), the highest vote over scale and rotation.
    Right, *what size and which way*: the scale-rotation plane
    (``planes.scale_angle``): for each scale and rotation, the highest vote
    over position. Heights (the colour bars) are votes per pattern point:
    the pattern's voting points that support a cell (each counts once per
    translation bin) over their number, summed over a 2 x 2 block of
    translation bins. 1.0 is as many votes as the pattern has points; the
    pooling (and, with polarity ``"either"``, both contrasts voting) lets a
    cell reach 4 (8), and a clear peak is often 1.5-3. They are not a
    detection's ``score``, the share (0-1) of the pattern's edges found at
    the refined pose. Detections are circled and numbered in both (labels
    of markers at the same place are stacked); with none, the highest cell
    is marked (a rejected peak). In the scale-rotation plane a detection's
    ring sits on the centre of the cell its peak comes from (see
    :func:`scale_angle_marker`): the refined pose may lie up to a cell away.

    Parameters
    ----------
    planes : AccumulatorPlanes or None
        ``SearchResult.planes`` from :meth:`seahough.Detector.search`; None
        (the search stopped before voting) draws a note instead.
    detections : list of Detection
        Ringed and numbered in list order; of a search of several
        patterns, only those of the planes' pattern (``planes.pattern``,
        named in the panels' titles) are drawn, with their numbers in the
        whole list.
    path : str or Path, optional
        Where to save the PNG.
    title : str, optional
        A line above both panels.
    patterns : list of str, optional
        The names of a search's patterns, for each pattern's colour (as
        :func:`~seahough.viz.plot_detections` takes them).
    best : Candidate, optional
        When nothing was found: the best candidate not reported (its
        refined pose, which the table gives), ringed and labelled; the
        highest vote cell, where refinement started, is then "highest
        vote".
    note : str, optional
        Why there are no planes (``SearchResult.note``), for that note;
        default: the image has no edges.

    Returns
    -------
    matplotlib.figure.Figure
        1300 x 560 px.

    Raises
    ------
    ParameterError
        When ``planes`` is not a search's planes (e.g. the whole
        ``SearchResult``: pass ``result.planes``).

    Examples
    --------
    Two boxes: two peaks, ringed and numbered #1 and #2 in both planes.

    >>> import numpy as np, seahough
    >>> from seahough.viz import plot_accumulator
    >>> img = np.full((120, 200), 40, np.uint8)
    >>> img[20:50, 20:70] = img[70:100, 120:170] = 220
    >>> detector = seahough.Detector(seahough.Pattern.rectangle(50, 30), max_results=2)
    >>> res = detector.search(img)
    >>> fig = plot_accumulator(res.planes, res.detections, title="two boxes")
    >>> tuple(int(v) for v in fig.get_size_inches() * fig.dpi)
    (1300, 560)

    A search that stopped before voting has no planes: a note says why.

    >>> fig = plot_accumulator(None, note="pattern larger than the image")
    >>> fig.axes[0].texts[0].get_text()
    'no accumulator: pattern larger than the image'
    """
    if planes is not None and not hasattr(planes, "scale_angle"):
        raise ParameterError("plot_accumulator needs the search's accumulator planes "
                             f"(SearchResult.planes), got {type(planes).__name__}")
    fig = _figure(1300, 560)
    detections = list(detections or [])
    if title:
        fig.suptitle(title, fontsize=12, x=0.01, ha="left")
    if planes is None:
        ax = fig.add_axes([0, 0, 1, 1])
        ax.axis("off")
        why = note if note and note != "no edges" else \
            "the image has (almost) no edges to vote"
        ax.text(0.5, 0.5, f"no accumulator: {why}", ha="center", va="center", fontsize=16)
        return _finish(fig, path)
    top = 0.86 if title else 0.9
    ax1 = fig.add_axes([0.06, 0.1, 0.36, top - 0.1])
    cax1 = fig.add_axes([0.425, 0.1, 0.012, top - 0.1])
    ax2 = fig.add_axes([0.56, 0.1, 0.36, top - 0.1])
    cax2 = fig.add_axes([0.925, 0.1, 0.012, top - 0.1])
    xy = np.asarray(planes.xy, float)
    vmax = float(xy.max()) if xy.size and xy.max() > 0 else 1.0
    im = ax1.imshow(xy, extent=planes.extent, cmap="inferno", vmin=0, vmax=vmax,
                    interpolation="nearest", aspect="equal")
    cb = fig.colorbar(im, cax=cax1)
    cb.set_label(_VOTES)
    ax1.set_xlabel("x of pattern origin in the image (px)")
    ax1.set_ylabel("y of pattern origin in the image (px)")
    ax1.set_title("where: dx-dy plane (best over scale, rotation)", fontsize=11)

    sa = np.asarray(planes.scale_angle, float)
    ang = _display_angles(planes.angles)
    a_edges = _rotation_edges(planes)
    s_edges = _edges_from_centres(planes.scales, log=True, single_half=0.03)
    smax = float(sa.max()) if sa.size and sa.max() > 0 else 1.0
    mesh = ax2.pcolormesh(a_edges, s_edges, sa, cmap="inferno", vmin=0, vmax=smax, shading="flat")
    cb2 = fig.colorbar(mesh, cax=cax2)
    cb2.set_label(_VOTES)
    ax2.set_xlabel("rotation (degrees, counter-clockwise)")
    ax2.set_ylabel("scale (size relative to the pattern)")
    ax2.set_title("what size, which way: scale-rotation plane (best over position)", fontsize=11)
    ax2.set_xlim(a_edges[0], a_edges[-1])
    ax2.set_ylim(s_edges[0], s_edges[-1])

    marks1, marks2 = [], []
    name = getattr(planes, "pattern", "")
    if name:   # (several patterns: only this one's detections are in these planes)
        ax1.set_title(f"{name} - " + ax1.get_title(), fontsize=11)
        ax2.set_title(f"{name} - " + ax2.get_title(), fontsize=11)
    shown = [(i, d) for i, d in enumerate(detections)
             if not name or getattr(d, "pattern", name) == name]
    tint = colours(list(detections), patterns)   # (as the overlay: by pattern when several)
    for i, d in shown:
        c = tint[i]
        a, sc = scale_angle_marker(planes, d.scale, d.angle)
        for ax, marks, px, py in ((ax1, marks1, d.x, d.y), (ax2, marks2, a, sc)):
            _ring(ax, px, py, c)
            marks.append((f"#{i + 1}", px, py, c))
    _place_peak_labels(ax1, marks1)
    _place_peak_labels(ax2, marks2)
    if not shown and xy.size and xy.max() > 0:
        r, c = np.unravel_index(int(np.argmax(xy)), xy.shape)
        ax1.plot([planes.x[c]], [planes.y[r]], "x", ms=14, mew=2.5, color="white")
        _side_label(ax1, "highest vote" if best is not None else "highest peak (rejected)",
                    planes.x[c], planes.y[r], 8)
        k, j = np.unravel_index(int(np.argmax(sa)), sa.shape)
        # (over a ring in the same cell: a trial could not see it under one)
        ax2.plot([ang[j]], [planes.scales[k]], "x", ms=14, mew=2.5, color="white", clip_on=False,
                 zorder=6)
    if not shown and best is not None:   # (the refined candidate the table reports)
        q = best.pose
        a, sc = scale_angle_marker(planes, q.scale, q.angle)
        for ax, px, py in ((ax1, q.tx, q.ty), (ax2, a, sc)):
            ax.plot([px], [py], "o", ms=18, mfc="none", mec="white", mew=1.8, ls="none",
                    clip_on=False)
            _side_label(ax, "best candidate (declined)", px, py, -14)
    return _finish(fig, path)


def _side_label(ax, text, px, py, dy):
    """A white label beside the marker at ``(px, py)``, ``dy`` points above
    it (below if negative): to its left in the right half of the panel,
    above it near the bottom and below near the top (it ran into the
    colour bar or under the axis: a trial read "(de|clined)")."""
    fx, fy = ax.transAxes.inverted().transform(ax.transData.transform((px, py)))
    right = fx > 0.55
    dy = abs(dy) if fy < 0.12 else -abs(dy) if fy > 0.9 else dy
    ax.annotate(text, (px, py), xytext=(-12 if right else 10, dy), textcoords="offset points",
                ha="right" if right else "left", color="white", fontsize=10,
                path_effects=_TEXT_OUTLINE, annotation_clip=False, zorder=7)

