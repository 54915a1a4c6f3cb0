"""Pictures of a camera's motion: the dead-reckoned path, and writing a mosaic."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure

from ..io.images import write_image
from ._figure import TRUTH_COLOUR, _figure, _finish


def _rows_of(rows_or_result):
    """The rows of an OdometryResult, or the list given (None: no rows)."""
    rows = getattr(rows_or_result, "rows", rows_or_result)
    return list(rows or [])


def _num(v):
    """``v`` as a float; NaN when it is missing or not a number."""
    try:
        f = float(v)
    except (TypeError, ValueError):
        return math.nan
    return f


def _assumed(row) -> bool:
    """Is the row's pose assumed (status ``"assumed"``, or a ``pose_assumed``
    flag when the rows have no status)?

    >>> _assumed({"status": "assumed"}), _assumed({"flags": "no_match; pose_assumed: x"})
    (True, True)
    >>> _assumed({"status": "measured", "flags": ""}), _assumed({"flags": ["lost"]})
    (False, False)
    """
    if row.get("status") is not None:
        return row["status"] == "assumed"
    flags = row.get("flags") or ""
    flags = [flags] if isinstance(flags, str) else list(flags)
    return any("pose_assumed" in str(f) for f in flags)


#: Metric units of :func:`plot_trajectory`: how many to a metre.
_PER_METRE = {"m": 1.0, "cm": 100.0, "mm": 1000.0}


def _positions(rows, unit: str, is_result: bool):
    """The rows' positions (NaN where missing) in ``unit``: ``x_m, y_m``
    for a metric unit when the rows have them."""
    per = _PER_METRE.get(unit)
    metric = per is not None and any(r.get("x_m") is not None for r in rows)
    # (rows of a run's CSV, read_odometry_csv's, carry its settings hash: in px)
    from_run = is_result or any("settings_hash" in r for r in rows)
    if per is not None and not metric and from_run and rows:
        from ..errors import ParameterError
        raise ParameterError(f"unit={unit!r}: this run has no metric positions (x_m, y_m); "
                             "give run_odometry metres_per_pixel, or altitude and focal_px, "
                             "or draw it in px")
    kx, ky, k = ("x_m", "y_m", per) if metric else ("x", "y", 1.0)
    xs = np.array([_num(r.get(kx)) for r in rows], float) * k
    ys = np.array([_num(r.get(ky)) for r in rows], float) * k
    return xs, ys


def plot_trajectory(rows_or_result, path=None, *, unit="px", truth=None, title=None) -> Figure:
    """The dead-reckoned path seen from above.

    Parameters
    ----------
    rows_or_result : OdometryResult or list of dict
        Rows with ``x``, ``y`` (position), ``heading`` (degrees), ``flags``
        and optionally ``status``; ``x`` right and ``y`` down as in the first
        frame (so the path looks like the mosaic).
    path : str or Path, optional
        Where to save the PNG.
    unit : str
        ``"px"``: ``x``, ``y`` are drawn. ``"m"``, ``"cm"`` or ``"mm"``: rows
        with ``x_m``, ``y_m`` (a metric run: ``run_odometry`` with metres per
        pixel, or altitude and focal length) are drawn from those, in that
        unit; rows without them are taken as already in it (a run without
        them, or its CSV's rows: ParameterError). Any other unit labels
        ``x``, ``y`` as given.
    truth : (N, 2) array, optional
        The true positions: a wide light grey band with a ring at each
        position, under the estimate (the estimate shows inside the band
        where both agree, and the band beside it where they do not).
    title : str, optional

    Notes
    -----
    The distance in the title ("measured") sums the steps between frames
    whose pose was measured (an assumed pose, carried on from the last
    measured one, would add motion that did not happen): the path drawn
    through assumed poses is longer. The start is a green circle, the end a black square; frames whose pose
    is assumed (status ``"assumed"`` or a ``pose_assumed`` flag: the motion
    of their pair could not be measured and was carried on from the last
    measured one) are hollow red circles, "pose assumed" in the legend;
    other frames with flags are red crosses; flagged frames without a pose
    (unreadable) are counted in the legend, "no pose, not drawn"; a few
    arrows show the heading, where the frame's up points (0 = up in the
    first frame, counter-clockwise positive as displayed).

    Returns
    -------
    matplotlib.figure.Figure
        900 x 800 px.

    Examples
    --------
    >>> from seahough.viz import plot_trajectory
    >>> rows = [{"x": 0.0, "y": 0.0, "heading": 0.0, "flags": []},
    ...         {"x": 3.0, "y": -4.0, "heading": 10.0, "flags": []},
    ...         {"x": 6.0, "y": -8.0, "heading": None, "flags": ["lost"]},
    ...         {"x": 9.0, "y": -12.0, "heading": None, "status": "assumed",
    ...          "flags": "no_match; pose_assumed: constant velocity since frame 1"},
    ...         {"x": None, "y": None, "flags": ["unreadable: empty file"]}]
    >>> fig = plot_trajectory(rows, unit="m")   # path=...: also a PNG
    >>> fig.axes[0].get_title()   # (the assumed pose's step not counted)
    'dead-reckoned path: 5 frames, 10.0 m measured, 3 flagged (1 pose assumed, 1 no pose)'
    >>> [t.get_text() for t in fig.axes[0].get_legend().get_texts()][-4:]
    ['flagged (1)', 'pose assumed (1)', "heading (the frame's up)", 'no pose, not drawn (1)']
    >>> tuple(int(v) for v in fig.get_size_inches() * fig.dpi)
    (900, 800)
    """
    rows = _rows_of(rows_or_result)
    xs, ys = _positions(rows, unit, is_result=hasattr(rows_or_result, "rows"))
    fig = _figure(900, 800)
    ax = fig.add_axes([0.1, 0.08, 0.86, 0.84])
    ok = np.isfinite(xs) & np.isfinite(ys)
    guessed = np.array([_assumed(r) for r in rows], bool) & ok
    known = ok & ~guessed
    dist = float(np.hypot(np.diff(xs[known]), np.diff(ys[known])).sum())
    flagged = np.array([bool(r.get("flags")) for r in rows], bool)
    if truth is not None:
        t = np.asarray(truth, float).reshape(-1, 2)
        # under the estimate, wide and light, a ring at each true position: the
        # thin estimate shows inside it where both agree, beside it where not
        ax.plot(t[:, 0], t[:, 1], "-", color=TRUTH_COLOUR, lw=9, alpha=0.85,
                solid_capstyle="round", solid_joinstyle="round", zorder=1.5)
        ax.plot(t[:, 0], t[:, 1], "o", ms=9, mfc="none", mec="#5a5a5a", mew=1.2, zorder=1.6)
        ax.plot([], [], "-o", color=TRUTH_COLOUR, lw=6, ms=9, mfc="none", mec="#5a5a5a",
                label="truth")
    if ok.any():
        # the steps to or from an assumed pose dashed: not measured (drawn solid,
        # a run through a bad frame showed a back-and-forth that never happened)
        idx = np.flatnonzero(ok)
        steps = {True: [], False: []}
        for a, b in zip(idx[:-1], idx[1:]):
            steps[bool(guessed[a] or guessed[b])].append([(xs[a], ys[a]), (xs[b], ys[b])])
        ax.add_collection(LineCollection(steps[False], colors="#1f5fbf", linewidths=2.2,
                                         capstyle="round"))
        ax.plot([], [], "-", color="#1f5fbf", lw=2.2, label="dead reckoning")
        if steps[True]:
            ax.add_collection(LineCollection(steps[True], colors="#1f5fbf", linewidths=1.6,
                                             linestyles=(0, (4, 3))))
            ax.plot([], [], "--", color="#1f5fbf", lw=1.6, label="to or from an assumed pose")
        ax.plot(xs[ok], ys[ok], ".", color="#1f5fbf", ms=6)
        i0 = int(np.flatnonzero(ok)[0]); i1 = int(np.flatnonzero(ok)[-1])
        # (start and end over the flags' markers: an assumed first or last pose hid them)
        ax.plot(xs[i0], ys[i0], "o", ms=12, color="#1aa442", mec="black", label="start", zorder=6)
        ax.plot(xs[i1], ys[i1], "s", ms=11, color="black", mec="white", label="end", zorder=6)
        bad = flagged & ok & ~guessed
        if bad.any():
            ax.plot(xs[bad], ys[bad], "x", ms=11, mew=2.5, color="#e0001b",
                    label=f"flagged ({int(bad.sum())})", zorder=5)
        if guessed.any():
            ax.plot(xs[guessed], ys[guessed], "o", ms=11, mfc="none", mec="#e0001b", mew=2.2,
                    label=f"pose assumed ({int(guessed.sum())})", zorder=5)
        hd = np.array([_num(r.get("heading")) for r in rows], float)
        sel = np.flatnonzero(ok & np.isfinite(hd))
        if sel.size:
            sel = sel[::math.ceil(sel.size / 12)]          # at most 12 arrows
            span = max(np.ptp(xs[ok]), np.ptp(ys[ok]), 1e-9)
            L = 0.06 * span
            t = np.radians(hd[sel])
            # heading 0 = up (-y); positive turns counter-clockwise as displayed
            ax.quiver(xs[sel], ys[sel], -np.sin(t) * L, -np.cos(t) * L, angles="xy",
                      scale_units="xy", scale=1, color="#ff9500", width=0.004, zorder=3,
                      label="heading (the frame's up)")
        lost = flagged & ~ok    # (unreadable frames: no pose to draw; the title counts them)
        if lost.any():
            ax.plot([], [], " ", label=f"no pose, not drawn ({int(lost.sum())})")
    else:
        ax.text(0.5, 0.5, "no positions", transform=ax.transAxes, ha="center", va="center",
                fontsize=20)
    ax.margins(0.1)       # (room for the heading arrows at the path's ends)
    ax.set_aspect("equal", adjustable="datalim")
    ax.invert_yaxis()
    ax.grid(True, alpha=0.3)
    ax.set_xlabel(f"x ({unit})")
    ax.set_ylabel(f"y ({unit}, down as in the first frame)")
    if title is None:
        # (split as the legend is: its "flagged (1)" beside a title's "2 flagged" read wrong)
        parts = [f"{n} {what}" for n, what in ((int((flagged & guessed).sum()), "pose assumed"),
                                               (int((flagged & ~ok).sum()), "no pose")) if n]
        title = (f"dead-reckoned path: {len(rows)} frames, {dist:.1f} {unit} measured, "
                 f"{int(flagged.sum())} flagged" + (f" ({', '.join(parts)})" if parts else ""))
    ax.set_title(title, fontsize=12)
    if ok.any():
        ax.legend(loc="best", fontsize=9, framealpha=0.85)
    return _finish(fig, path)


def save_mosaic(image, path) -> Path:
    """Write a mosaic (or any OpenCV image) to ``path`` (PNG, JPEG... by
    extension), creating the folder; returns the path.

    Parameters
    ----------
    image : ndarray
        Grey, BGR or BGRA, as OpenCV writes it; other than uint8 is clipped
        to 0-255 and truncated to uint8.
    path : str or Path

    Returns
    -------
    pathlib.Path

    Raises
    ------
    OSError
        When OpenCV cannot write the file.

    Examples
    --------
    >>> import tempfile, cv2, numpy as np
    >>> from pathlib import Path
    >>> from seahough.viz import save_mosaic
    >>> mosaic = np.zeros((20, 30, 3), np.uint8)
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     p = save_mosaic(mosaic, Path(tmp) / "run" / "mosaic.png")
    ...     print(p.name, cv2.imread(str(p)).shape)
    mosaic.png (20, 30, 3)
    """
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    a = np.asarray(image)
    if a.dtype != np.uint8:
        a = np.clip(a, 0, 255).astype(np.uint8)
    write_image(p, a, what="the mosaic")
    return p
