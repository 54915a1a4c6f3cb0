"""The picture of what the detector saw: the working image, its gradient
magnitude, the key points and the edge segments traced from them, drawn
in the image's own (full-resolution) pixels."""

from __future__ import annotations

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure

from ..errors import ParameterError
from ._figure import _figure, _finish, _imshow


def plot_edges(image, features, path=None, *, title=None) -> Figure:
    """What the detector saw: the working image, and its gradient magnitude
    with the chosen key points and the edge segments traced from them
    (the paper's Figs. 1-3). For tuning ``Config.n_keypoints``,
    ``min_gradient``, ``downscale`` and ``equalize``.

    The search runs on a working image (the photo scaled down, e.g. to 0.5x);
    the picture draws it, its gradient magnitude, the key points and the
    segments in the photo's own pixels (axes from 0 to its width and
    height; points mapped by ``features.gradients.to_full``), so that a
    place reads the same as on the overlay. The titles give the working
    scale and size, and how many key points and segments the search used.

    Parameters
    ----------
    image : ndarray or path
        The photo the features were computed from (not read again: the
        working image is in ``features``).
    features : Features
        ``SearchResult.features`` (or :func:`seahough.core.features.extract_features`).
        A working image larger than drawn (520 x 426 px at most) is shrunk
        to that size by an area average before it is drawn.
    path : str or Path, optional
        Where to save the PNG.
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        1300 x 560 px.

    Raises
    ------
    ParameterError
        When ``features`` is None or not a search's features: the picture
        never runs the search.

    Examples
    --------
    The features come from the search; the picture does not compute them.

    >>> import numpy as np, seahough
    >>> from seahough.viz import plot_edges
    >>> disc = np.zeros((90, 120), np.uint8)
    >>> disc[np.hypot(*np.mgrid[-45:45, -60:60]) < 30] = 255
    >>> res = seahough.Detector(seahough.Pattern.rectangle(40, 40)).search(disc)
    >>> fig = plot_edges(disc, res.features, title="a disc")   # path=...: also a PNG
    >>> tuple(int(v) for v in fig.get_size_inches() * fig.dpi)
    (1300, 560)
    >>> [float(v) for v in fig.axes[1].get_xlim() + fig.axes[1].get_ylim()]   # image px
    [-0.5, 119.5, 89.5, -0.5]
    >>> plot_edges(disc, None)
    Traceback (most recent call last):
    ...
    seahough.errors.ParameterError: plot_edges needs the search's features (SearchResult.features), got NoneType
    """
    if getattr(features, "gradients", None) is None:
        raise ParameterError("plot_edges needs the search's features (SearchResult.features), "
                             f"got {type(features).__name__}")
    g = features.gradients
    mag = np.asarray(g.magnitude, float)
    h, w = mag.shape
    H, W = (int(v) for v in g.full_shape)
    # a working pixel i covers image px i / f - 0.5 to (i + 1) / f - 0.5 (to_full)
    extent = (-0.5, W - 0.5, H - 0.5, -0.5)
    fig = _figure(1300, 560)
    top = 0.86
    ax1 = fig.add_axes([0.05, 0.1, 0.40, top - 0.1])
    ax2 = fig.add_axes([0.52, 0.1, 0.40, top - 0.1])
    cax = fig.add_axes([0.93, 0.1, 0.012, top - 0.1])
    box = (0.40 * 1300, (top - 0.1) * 560)     # px of each image's axes
    _imshow(ax1, np.asarray(g.image), box, extent=extent, cmap="gray", vmin=0, vmax=255)
    scale = _scale(g.factor)
    ax1.set_title(f"working image: {w:,} x {h:,} px ({scale} of {W:,} x {H:,})", fontsize=11)
    vmax = float(np.percentile(mag, 99.5)) if mag.size else 1.0
    # a flat image: a plain 0-1 scale rather than a 1e-6 one
    im = _imshow(ax2, mag, box, extent=extent, cmap="gray", vmin=0,
                 vmax=vmax if vmax >= 1.0 else 1.0)
    cb = fig.colorbar(im, cax=cax)
    cb.set_label("Scharr gradient magnitude (clipped at 99.5 %)")
    seg = features.segments
    n_seg = len(seg)
    if n_seg:
        p1 = np.stack(g.to_full(seg.x1, seg.y1), 1)
        p2 = np.stack(g.to_full(seg.x2, seg.y2), 1)
        ax2.add_collection(LineCollection(np.stack([p1, p2], 1), colors="#00e5ff",
                                          linewidths=2.4, zorder=3, label=f"segments ({n_seg:,})"))
    kp = np.asarray(features.keypoints)
    if kp.size:
        kx, ky = g.to_full(features.edges.x[kp], features.edges.y[kp])
        ax2.scatter(kx, ky, s=3, c="#ff2d2d", lw=0, label=f"key points ({kp.size:,})", zorder=4)
    for ax in (ax1, ax2):
        ax.set_xlim(-0.5, W - 0.5)
        ax.set_ylim(H - 0.5, -0.5)
        ax.set_xlabel("x (image px)")
        ax.set_ylabel("y (image px)")
    # (on two lines: on one it ran under the colour bar, its end lost: a user trial)
    ax2.set_title(f"edges at {scale}: {kp.size:,} key points, {n_seg:,} segments\n"
                  f"({len(features.edges):,} edge points)", fontsize=11)
    if n_seg or kp.size:
        leg = ax2.legend(loc="upper right", fontsize=9, framealpha=0.8, markerscale=3)
        leg.get_frame().set_facecolor("white")
    if title:
        fig.suptitle(title, fontsize=12, x=0.01, ha="left")
    return _finish(fig, path)


def _scale(factor: float) -> str:
    """The working scale as the titles write it.

    >>> _scale(0.5), _scale(1.0), _scale(0.41666), _scale(0.1666)
    ('0.5x', '1x', '0.42x', '0.17x')
    """
    return f"{float(f'{factor:.2f}'):g}x"
