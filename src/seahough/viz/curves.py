"""The picture of the curved ropes, cables or pipes :func:`seahough.find_curves`
found: each centre line with the rope's two borders, numbered, and a list of
their length, width and evidence."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from ._figure import COLOURS, _OUTLINE, _finish, _items, _line_ends, _set_title
from .detections import _free_corners, _image_figure, _notes, _place_label


def _borders(points: np.ndarray, half: float) -> tuple[np.ndarray, np.ndarray]:
    """The polyline ``points`` offset by ``half`` px to either side (normals
    from the neighbouring points)."""
    p = np.asarray(points, float).reshape(-1, 2)
    if len(p) < 2:
        return p, p
    t = np.gradient(p, axis=0)
    t /= np.maximum(np.hypot(t[:, 0], t[:, 1]), 1e-9)[:, None]
    n = np.stack([-t[:, 1], t[:, 0]], axis=1)
    return p + half * n, p - half * n


def _curve_label(c) -> str:
    nfa = f"{c.nfa:.0e}" if np.isfinite(c.nfa) else "-"
    flags = f" · {', '.join(c.flags)}" if c.flags else ""
    return f"length {c.length:.0f} px · width {c.width:.1f} px · score {c.score:.2f} · nfa {nfa}" \
        + flags


def plot_curves(image, curves, path=None, *, title=None, max_width=None,
                bit_depth=None, best=None) -> Figure:
    """The image with each curve's centre line and borders.

    Parameters
    ----------
    image : ndarray or path
        The searched image (BGR/BGRA shown in colour, or grey).
    curves : list of Curve
        From :func:`seahough.find_curves`, best first: each drawn as two
        dashed lines 3 px outside the rope's borders (``width / 2 + 3`` px
        to either side of the centre line, which is drawn thin), so that the
        rope shows between them, numbered at its first point, and listed with its length,
        width, score and NFA in the image corner farthest from them (beside
        an image too small to hold it, or its lines broken), as
        :func:`~seahough.viz.plot_detections` places its list; "not found"
        in its top left corner when the list is empty.
    path : str or Path, optional
        Where to save the PNG.
    title : str, optional
        Default: how many curves were found.
    max_width, bit_depth : optional
        As :func:`~seahough.viz.plot_detections` takes them.
    best : Candidate, optional
        When no curve was found: the best line the search started from
        (``find_curves(..., declined=[])``'s first), drawn dotted across
        the image and labelled, so that one sees where it looked.

    Returns
    -------
    matplotlib.figure.Figure
        :func:`~seahough.viz.detections_size` px.

    Examples
    --------
    >>> import numpy as np
    >>> from seahough.core.curves import Curve
    >>> img = np.full((120, 160), 40, np.uint8)
    >>> c = Curve(np.array([[10.0, 60.0], [80.0, 50.0], [150.0, 70.0]]), 6.0, 0.8, 1e-6, 0.5)
    >>> fig = plot_curves(img, [c])
    >>> tuple(int(v) for v in fig.get_size_inches() * fig.dpi)
    (1000, 775)
    """
    curves = _items("curves", curves, "Curve", ("points", "width"), "from find_curves")
    best = (_items("best", [best], "Candidate", ("pose",), "find_curves(declined=[])'s first")[0]
            if best is not None else None)
    fig, ax, _, _, (w, h), box = _image_figure(image, max_width, bit_depth)
    ax.set_xlabel("x (px)")
    ax.set_ylabel("y (px)")
    items, anchors = [], []
    for i, c in enumerate(curves):
        col = COLOURS[i % len(COLOURS)]
        p = np.asarray(c.points, float).reshape(-1, 2)
        # the borders drawn just outside the rope and the centre line thin, so
        # that the rope itself stays visible between them
        for b in _borders(p, 0.5 * c.width + 3.0):
            ax.plot(b[:, 0], b[:, 1], color=col, lw=1.6, ls="--", path_effects=_OUTLINE)
        ax.plot(p[:, 0], p[:, 1], color=col, lw=0.8, alpha=0.7)
        anchors.append(p)
        _place_label(ax, f"#{i + 1}", p[0, 0], p[0, 1], col, w, h)
        items.append((f"#{i + 1}  " + _curve_label(c), col))
    if best is not None and not curves:
        q = best.pose
        ends = _line_ends(q.tx, q.ty, q.angle, w, h)
        if ends is not None:
            (x0, y0), (x1, y1) = ends
            ax.plot([x0, x1], [y0, y1], color="0.9", lw=1.2, ls=":", path_effects=_OUTLINE)
            _place_label(ax, "best line, no curve", 0.5 * (x0 + x1), 0.5 * (y0 + y1), "0.9",
                         w, h)
            anchors.append(np.array([[x0, y0], [x1, y1]]))
    # the list placed as plot_detections places its own: in the image corner
    # farthest from the curves, beside an image too small to hold it (a
    # sonar crop drawn pixel for pixel was a third covered), or its lines
    # broken; "not found" in a corner (the middle is where the rope was looked for)
    corners = _free_corners(np.vstack(anchors) if anchors else np.empty((0, 2)), w, h)
    _notes(fig, ax, items, None, corners, (w, h), box, listed=True)
    if title is None:
        n = len(curves)
        title = "no curve found" if n == 0 else f"{n} curve{'s' if n > 1 else ''}"
    _set_title(fig, ax, title)
    return _finish(fig, path)
