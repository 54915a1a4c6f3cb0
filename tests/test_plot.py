"""seahough.viz: every picture is a PNG of a fixed size that shows something."""

from __future__ import annotations

import math
import types
from pathlib import Path

import cv2
import numpy as np
import pytest

import seahough
from seahough import viz as plot
from seahough.viz._figure import COLOURS, TRUTH_COLOUR
from seahough.viz.accumulator import _VOTES, _display_angles
from seahough.viz.detections import _det_label
from seahough import sim as sim


@pytest.fixture(scope="module")
def box_search():
    """A grey scene with a bright turned box, and its search result."""
    img = np.full((240, 320), 40, np.uint8)
    box = cv2.boxPoints(((200.0, 110.0), (90.0, 50.0), -30.0))
    cv2.fillPoly(img, [np.round(box).astype(np.int32)], 220)
    pattern = seahough.Pattern.rectangle(90, 50)
    res = seahough.Detector(pattern, max_results=1).search(img)
    assert res.detections, "the box must be found for these tests to mean anything"
    return img, pattern, res


def read_png(path):
    im = cv2.imread(str(path), cv2.IMREAD_COLOR)
    assert im is not None, path
    assert path.stat().st_size > 5000
    assert im.std() > 5, "the picture is (almost) blank"
    return im


def count_colour(im_bgr, hex_rgb, tol=40):
    r, g, b = (int(hex_rgb[i:i + 2], 16) for i in (1, 3, 5))
    d = np.abs(im_bgr.astype(int) - [b, g, r]).max(axis=2)
    return int((d < tol).sum())


def test_detections_size_rule():
    assert plot.detections_size((480, 640)) == (1000, 775)
    assert plot.detections_size((240, 320)) == (1000, 775)
    w, h = plot.detections_size((1080, 1920))
    assert (w, h) == (1000, round(1080 * 900 / 1920) + 100)
    assert plot.detections_size((400, 40))[0] == 560      # narrow images keep room for the title


def test_plot_detections_object(tmp_path, box_search):
    img, pattern, res = box_search
    fig = plot.plot_detections(img, res.detections, tmp_path / "det.png", pattern=pattern,
                               title="box")
    im = read_png(tmp_path / "det.png")
    assert (im.shape[1], im.shape[0]) == plot.detections_size(img.shape) == (1000, 775)
    assert tuple(fig.get_size_inches() * fig.dpi) == (1000, 775)
    assert count_colour(im, COLOURS[0]) > 300               # the outline is drawn


def test_plot_detections_empty_and_colour(tmp_path):
    scene = sim.negative_scene((120, 160), seed=1, source="procedural")
    plot.plot_detections(scene, [], tmp_path / "none.png")
    im = read_png(tmp_path / "none.png")
    assert (im.shape[1], im.shape[0]) == plot.detections_size((120, 160))
    assert count_colour(im, "#b00020", tol=60) > 500         # the red "not found" box


def test_plot_detections_line(tmp_path):
    # (seed 1: a rope found at NFA 1e-18; the seed 4 rope, narrower than the
    # pattern, is found at NFA 5e3 and declined at the default max_nfa)
    rope, truth = sim.rope_scene((240, 320), seed=1, source="procedural")
    dets = seahough.Detector(seahough.Pattern.line(120, 8), angle_range=(0, 180),
                             max_results=1).detect(rope)
    assert dets and dets[0].kind == "line"
    plot.plot_detections(rope, dets, tmp_path / "rope.png")
    im = read_png(tmp_path / "rope.png")
    assert (im.shape[1], im.shape[0]) == (1000, 775)
    # a line across the whole image (900 x 675 px of the PNG): red pixels
    # from border to border
    red = np.abs(im.astype(int) - [45, 45, 255]).max(axis=2) < 40
    cols, rows = np.flatnonzero(red.any(axis=0)), np.flatnonzero(red.any(axis=1))
    assert cols.size and max(np.ptp(cols), np.ptp(rows)) > 600


def test_plot_accumulator(tmp_path, box_search):
    img, pattern, res = box_search
    fig = plot.plot_accumulator(res.planes, res.detections, tmp_path / "acc.png")
    im = read_png(tmp_path / "acc.png")
    assert im.shape[:2] == (560, 1300)
    assert tuple(fig.get_size_inches() * fig.dpi) == (1300, 560)
    plot.plot_accumulator(res.planes, [], tmp_path / "acc_empty.png")
    assert read_png(tmp_path / "acc_empty.png").shape[:2] == (560, 1300)
    plot.plot_accumulator(None, [], tmp_path / "acc_none.png")
    assert cv2.imread(str(tmp_path / "acc_none.png")).shape[:2] == (560, 1300)


def test_plot_accumulator_known_scale_and_wrapped_angles(tmp_path, box_search):
    img, pattern, _ = box_search
    res = seahough.Detector(pattern, scale_range=(1, 1), angle_range=(-40, 40)).search(img)
    plot.plot_accumulator(res.planes, res.detections, tmp_path / "acc.png")
    assert read_png(tmp_path / "acc.png").shape[:2] == (560, 1300)
    # rotation bins around 0 are shown as -40..40, not 320..40
    a = _display_angles(res.planes.angles)
    assert np.all(np.diff(a) > 0) and a[0] < 0 < a[-1]


def test_plot_edges(tmp_path, box_search):
    img, _, res = box_search
    plot.plot_edges(img, res.features, tmp_path / "edges.png")
    im = read_png(tmp_path / "edges.png")
    assert im.shape[:2] == (560, 1300)
    assert count_colour(im, "#00e5ff") > 100               # segments drawn
    # the right panel's title ends left of the colour bar (a seabed's 18,721 edge
    # points: it ran under it, its end lost)
    sea = seahough.sim.seabed((480, 640), seed=2)
    res = seahough.Detector(seahough.Pattern.rectangle(40, 30)).search(sea)
    assert len(res.features.edges) >= 10_000
    fig = plot.plot_edges(sea, res.features)
    ax2, cax = fig.axes[1], fig.axes[2]
    bb = ax2.title.get_window_extent(fig.canvas.get_renderer())
    assert bb.x1 < cax.get_position().x0 * fig.bbox.width, bb
    with pytest.raises(seahough.ParameterError, match="features"):   # pictures never run the search
        plot.plot_edges(img, None, tmp_path / "edges2.png")
    # the whole result, or its planes, given for the features (or the other
    # way round): a SeahoughError naming what to pass (an AttributeError
    # 'SearchResult' object has no attribute 'xy': a new user's trial)
    with pytest.raises(seahough.ParameterError, match=r"SearchResult\.features.*got SearchResult"):
        plot.plot_edges(sea, res)
    with pytest.raises(seahough.ParameterError, match=r"SearchResult\.planes.*got SearchResult"):
        plot.plot_accumulator(res, res.detections)


def test_plot_trajectory(tmp_path):
    t = np.linspace(0, np.pi, 12)
    rows = [{"index": i, "x": 100 * np.cos(a), "y": 60 * np.sin(a), "heading": float(np.degrees(a)),
             "flags": ["lost"] if i == 5 else []} for i, a in enumerate(t)]
    fig = plot.plot_trajectory(rows, tmp_path / "traj.png", unit="m",
                               truth=np.c_[100 * np.cos(t), 60 * np.sin(t) + 2])
    im = read_png(tmp_path / "traj.png")
    assert im.shape[:2] == (800, 900)
    assert tuple(fig.get_size_inches() * fig.dpi) == (900, 800)
    assert count_colour(im, "#e0001b") > 20                 # the flagged frame
    result = types.SimpleNamespace(rows=rows[:1])
    plot.plot_trajectory(result, tmp_path / "one.png")
    assert cv2.imread(str(tmp_path / "one.png")).shape[:2] == (800, 900)
    plot.plot_trajectory([], tmp_path / "none.png")
    assert cv2.imread(str(tmp_path / "none.png")).shape[:2] == (800, 900)


def test_plot_trajectory_draws_a_runs_metres_in_the_unit_asked_for(tmp_path):
    """A run's rows hold x, y in pixels and x_m, y_m in metres: unit="m"
    draws the metres (it drew the pixels labelled as metres), "cm" the same
    x 100; a run without metres refuses a metric unit; an assumed pose's
    steps are not counted as travelled."""
    rows = [{"x": 100.0 * i, "y": 0.0, "x_m": 0.25 * i, "y_m": 0.0, "heading": 0.0,
             "flags": [], "status": "measured"} for i in range(4)]
    result = types.SimpleNamespace(rows=rows)
    title = lambda fig: fig.axes[0].get_title()  # noqa: E731
    assert "0.8 m measured" in title(plot.plot_trajectory(result, unit="m"))
    assert "75.0 cm measured" in title(plot.plot_trajectory(result, unit="cm"))
    assert "300.0 px measured" in title(plot.plot_trajectory(result))
    with pytest.raises(seahough.ParameterError, match="unit='m': this run has no metric"):
        plot.plot_trajectory(types.SimpleNamespace(rows=[dict(r, x_m=None, y_m=None)
                                                         for r in rows]), unit="m")
    rows[2].update(x=900.0, x_m=2.25, status="assumed", flags=["pose_assumed"])
    assert "300.0 px measured" in title(plot.plot_trajectory(rows))   # (1500 counted)
    # the rows of a pixel run's CSV (read_odometry_csv: no x_m, a settings hash) are
    # pixels too: refused in metres (a trial drew "171.6 m measured" from pixels)
    csv_rows = [{k: v for k, v in r.items() if k not in ("x_m", "y_m")}
                | {"settings_hash": "abc"} for r in rows]
    with pytest.raises(seahough.ParameterError, match="unit='m': this run has no metric"):
        plot.plot_trajectory(csv_rows, unit="m")


def test_save_mosaic(tmp_path):
    mosaic = np.zeros((50, 80, 3), np.uint8)
    mosaic[10:40, 20:60] = (0, 200, 255)
    p = plot.save_mosaic(mosaic, tmp_path / "sub" / "mosaic.png")
    back = cv2.imread(str(p))
    assert back is not None and np.array_equal(back, mosaic)


# ------------------------------------------------------------ labels and markers
def _planes(n_angles=64, scales=(0.8, 0.9, 1.0, 1.1, 1.25), a0=0.0, span=360.0):
    """Synthetic accumulator planes: a flat 2-D grid, no votes yet."""
    from seahough.core.accumulator import AccumulatorPlanes

    w = span / n_angles
    angles = (a0 + (np.arange(n_angles) + 0.5) * w) % 360.0
    sa = np.zeros((len(scales), n_angles), np.float32)
    xy = np.zeros((20, 30), np.float32)
    z = np.zeros(xy.shape, np.int32)
    return AccumulatorPlanes(xy, z, z, sa, np.asarray(scales, float), angles,
                             np.arange(30) * 10.0, np.arange(20) * 10.0)


def test_a_detections_label_on_the_picture_has_its_nfa_and_flags():
    """A colour trial: a wrong answer flagged ambiguous looked like a good one on the
    overlay, whose label had only score, confidence, scale and angle."""
    d = seahough.Detection(436.0, 144.0, 1.0, 12.0, 0.52, 0.05, np.eye(2, 3),
                           flags=("ambiguous",), nfa=3.5e-10)
    assert _det_label(d) == "score 0.52 · conf 0.05 · s 1.00 · 12.0° · nfa 3e-10 · ambiguous"
    line = seahough.Detection(1.0, 2.0, 1.0, 0.0, 0.9, 0.8, np.eye(2, 3), kind="line",
                              line_angle=10.0, line_offset=3.0, nfa=1e-20,
                              flags=("position_along_line_undetermined",))
    assert _det_label(line).endswith("px · nfa 1e-20"), _det_label(line)   # (a line's own flag left out)


@pytest.mark.parametrize("x", [8.0, 55.0, 81.0, 104.0])
def test_a_detections_label_beside_it_stays_inside_the_image(x):
    """A sonar user's overlay of a 111x97 crop: the label of a detection at
    x 81 ran off the image's right edge ("... outside_search_ra")."""
    img = np.random.default_rng(0).uniform(40, 200, (97, 111)).astype(np.uint8)
    t = np.linspace(0, 2 * np.pi, 40)
    d = seahough.Detection(x, 50.0, 0.45, 337.6, 0.92, 0.79, np.eye(2, 3), nfa=2.5e-7,
                           outline=[np.c_[x + 6 * np.cos(t), 50 + 3 * np.sin(t)]],
                           flags=("outside_search_range",))
    fig = plot.plot_detections(img, [d])
    fig.canvas.draw()
    ax, r = fig.axes[0], fig.canvas.get_renderer()
    labels = [t for t in ax.texts if "outside_search_range" in t.get_text()]
    assert len(labels) == 1
    bb, box = labels[0].get_window_extent(r), ax.get_window_extent(r)
    assert box.x0 - 1 <= bb.x0 and bb.x1 <= box.x1 + 1, (bb, box)


def test_det_label_wraps_rounded_angles():
    obj = types.SimpleNamespace(kind="object", score=0.9, confidence=0.8, scale=1.0,
                                angle=359.98)
    assert _det_label(obj).endswith(" · 0.0°"), _det_label(obj)
    obj.angle = 359.94
    assert _det_label(obj).endswith(" · 359.9°")
    line = types.SimpleNamespace(kind="line", score=0.9, confidence=0.8, scale=1.0, angle=0.0,
                                 line_angle=179.97, line_offset=2.0)
    assert " · line 0.0° · " in _det_label(line), _det_label(line)
    # written as 0 degrees, the offset is measured along that direction's normal
    assert _det_label(line).endswith("offset -2.0 px"), _det_label(line)


def test_a_horizontal_band_is_a_line_at_0_degrees_above_or_below_the_centre():
    """A band above the image centre: direction 0 (not 179.9999999999999),
    offset negative (the normal (sin a, cos a) points down), scale 1 (the
    line pattern is drawn by its area: cv2's anti-aliased fill made it
    1.4 px wider, so a 10 px band was found at 0.88)."""
    img = np.full((480, 640), 30, np.uint8)
    img[200:210] = 230                       # centre row 204.5, image centre 239.5
    d = seahough.Detector(seahough.Pattern.line(200, 10), (0.5, 2.0), (0.0, 180.0)).detect(img)[0]
    assert d.line_angle == pytest.approx(0.0, abs=0.05) and d.line_angle < 179.0
    assert d.line_offset == pytest.approx(-35.0, abs=0.3)
    assert d.scale == pytest.approx(1.0, abs=0.02)
    assert "offset -35.1 px" in _det_label(d) or "offset -35.0 px" in _det_label(d)


def test_scale_angle_marker_sits_on_the_cell_it_refers_to():
    p = _planes()                                  # 64 cells of 5.625 degrees, 0..360
    k = 2                                          # the scale 1.0 row
    p.scale_angle[k, 0] = 2.0                      # the peak: first cell
    p.scale_angle[k, -1] = 0.5
    x, s = plot.scale_angle_marker(p, 1.0, 359.998)
    assert 0.0 < x < 5.625 and x == pytest.approx(2.8125) and s == 1.0
    # the same angle, the peak in the last cell: marked there, inside the plane
    p.scale_angle[k, 0], p.scale_angle[k, -1] = 0.5, 2.0
    x, _ = plot.scale_angle_marker(p, 1.0, 359.998)
    assert 354.375 < x < 360.0 and x == pytest.approx(357.1875)
    # away from the seam: the angle's own cell, even next to a brighter one farther off
    p.scale_angle[:] = 0
    p.scale_angle[k, 17] = 1.0                     # 95.6..101.25
    p.scale_angle[k, 19] = 3.0
    x, _ = plot.scale_angle_marker(p, 1.0, 100.0)
    assert 95.625 < x < 101.25
    # a refined angle just across a border from its peak goes to the peak's cell
    x, _ = plot.scale_angle_marker(p, 1.0, 101.5)
    assert 95.625 < x < 101.25
    # scale too: the nearer neighbouring row when it holds the peak
    p.scale_angle[:] = 0
    p.scale_angle[3, 10] = 2.0                     # scale 1.1
    x, s = plot.scale_angle_marker(p, 1.04, 10.0 * 5.625 + 1.0)
    assert s == 1.1
    # a search of -40..40: shown as -40..40, an angle of 350 is -10
    q = _planes(16, a0=320.0, span=80.0)
    x, _ = plot.scale_angle_marker(q, 1.0, 350.0)
    assert -15.0 < x < -5.0
    x, _ = plot.scale_angle_marker(q, 1.0, 100.0)  # outside: the nearer end's cell
    assert x == pytest.approx(37.5)


def _ring_xs(ax):
    return [float(ln.get_xdata()[0]) for ln in ax.lines if ln.get_marker() == "o"]


def test_accumulator_ring_near_360_is_inside_the_plane(box_search, tmp_path):
    _, _, res = box_search
    planes = res.planes
    d = res.detections[0]
    # the detection as if refined to just below 360, its peak in the first cell
    k = int(np.argmin(np.abs(np.log(planes.scales) - np.log(d.scale))))
    planes = _planes(len(planes.angles), planes.scales)
    planes.scale_angle[k, 0] = 2.0
    det = types.SimpleNamespace(x=100.0, y=100.0, scale=d.scale, angle=359.998)
    fig = plot.plot_accumulator(planes, [det], tmp_path / "seam.png")
    ax2 = fig.axes[2]
    lo, hi = ax2.get_xlim()
    xs = _ring_xs(ax2)
    assert xs and all(lo < x < lo + 360.0 / len(planes.angles) for x in xs), (xs, lo, hi)


def test_accumulator_labels_of_coinciding_peaks_do_not_overlap(box_search, tmp_path):
    _, _, res = box_search
    d = res.detections[0]
    dets = [types.SimpleNamespace(x=d.x + dx, y=d.y, scale=d.scale, angle=a)
            for dx, a in ((0, 350.0), (1, 359.99), (2, 0.5), (3, 351.0), (150, 350.5))]
    fig = plot.plot_accumulator(res.planes, dets, tmp_path / "many.png")
    renderer = fig.canvas.get_renderer()
    for ax in (fig.axes[0], fig.axes[2]):
        labels = [t for t in ax.texts if t.get_text().startswith("#")]
        assert sorted(t.get_text() for t in labels) == [f"#{i}" for i in range(1, 6)]
        boxes = [t.get_window_extent(renderer) for t in labels]
        for i in range(len(boxes)):
            for j in range(i + 1, len(boxes)):
                assert not boxes[i].overlaps(boxes[j]), (labels[i].get_text(),
                                                         labels[j].get_text())
    assert read_png(tmp_path / "many.png").shape[:2] == (560, 1300)


def test_vote_colour_bars_say_that_heights_can_exceed_one(box_search):
    _, _, res = box_search
    assert res.planes.xy.max() > 1.0            # why the old "1.0 = one vote..." misled
    fig = plot.plot_accumulator(res.planes, res.detections)
    labels = [a.get_ylabel() for a in fig.axes if "vote" in a.get_ylabel()]
    assert len(labels) == 2 and all(lab == _VOTES for lab in labels)
    assert "exceed 1" in _VOTES and "1.0 = one vote" not in _VOTES
    assert "not a\n    detection's ``score``" in plot.plot_accumulator.__doc__


def _narrow_scene():
    img = np.full((600, 80), 40, np.uint8)
    cv2.rectangle(img, (30, 100), (49, 119), 220, -1)
    cv2.rectangle(img, (25, 400), (44, 419), 220, -1)
    return img


def _check_notes_layout(path, img, dets, pattern):
    """plot_detections' notes (list, "not found", the pattern) lie inside the
    figure, on the image or clear of it, and off its ticks and axis labels."""
    from matplotlib.offsetbox import AnchoredOffsetbox

    n = len(dets)
    fig = plot.plot_detections(img, dets, path, pattern=pattern, title=f"{path.name}: {n}")
    im = read_png(path)
    assert (im.shape[1], im.shape[0]) == plot.detections_size(img.shape)
    renderer = fig.canvas.get_renderer()
    ax = fig.axes[0]
    fig_box = fig.bbox
    ticks = [t.get_window_extent(renderer) for t in ax.get_xticklabels() + ax.get_yticklabels()
             if t.get_text()]
    ticks += [ax.xaxis.label.get_window_extent(renderer),
              ax.yaxis.label.get_window_extent(renderer)]
    notes = [a for a in ax.artists if isinstance(a, AnchoredOffsetbox)]
    notes += [t for t in fig.texts + ax.texts
              if t.get_text() == "not found" or "score" in t.get_text()]
    assert notes                                      # the labels or the note are drawn
    image = ax.get_window_extent(renderer)            # the image as drawn
    insets = [a for a in fig.axes[1:]] + [a for a in ax.child_axes]
    assert len(insets) == 1                           # the pattern is shown
    boxes = [a.get_window_extent(renderer) for a in notes] + [
        a.get_tightbbox(renderer) for a in insets]
    for bb in boxes:
        assert (bb.x0 >= fig_box.x0 - 0.5 and bb.x1 <= fig_box.x1 + 0.5 and
                bb.y0 >= fig_box.y0 - 0.5 and bb.y1 <= fig_box.y1 + 0.5), bb
        # on the image, or clear of it, its ticks and its axis labels
        inside = (bb.x0 >= image.x0 - 0.5 and bb.x1 <= image.x1 + 0.5 and
                  bb.y0 >= image.y0 - 0.5 and bb.y1 <= image.y1 + 0.5)
        assert inside or not bb.overlaps(image), (bb, image)
        for t in ticks:
            assert not bb.overlaps(t), (bb, t)
    for i, a in enumerate(boxes):                     # and off each other
        for b in boxes[i + 1:]:
            assert not a.overlaps(b), (a, b)
    for t in ax.texts + fig.texts:
        if t.get_text():
            assert t.get_fontsize() >= 10                    # readable
    return fig


@pytest.mark.parametrize("n", [2, 1, 0])
def test_narrow_image_labels_stay_inside_the_figure_and_off_the_axes(tmp_path, n):
    img = _narrow_scene()
    pattern = seahough.Pattern.rectangle(20, 20)
    dets = seahough.Detector(pattern, max_results=2).detect(img)[:n] if n else []
    assert len(dets) == n
    _check_notes_layout(tmp_path / "tall.png", img, dets, pattern)


@pytest.mark.parametrize("n", [3, 1, 0])
def test_short_strip_notes_go_under_it(tmp_path, n):
    # a 900 x 60 strip: its list of three labels once overflowed the image,
    # over the third marker, with the pattern inset on top of the list
    img = np.full((60, 900), 40, np.uint8)
    for x in (100, 400, 700):
        cv2.rectangle(img, (x, 20), (x + 19, 39), 220, -1)
    pattern = seahough.Pattern.rectangle(20, 20)
    dets = seahough.Detector(pattern, max_results=3).detect(img)[:n] if n else []
    assert len(dets) == n
    fig = _check_notes_layout(tmp_path / "strip.png", img, dets, pattern)
    # all of them below the image (nothing crammed into its 60 px)
    renderer = fig.canvas.get_renderer()
    image = fig.axes[0].get_window_extent(renderer)
    for a in fig.axes[1:]:
        assert a.get_tightbbox(renderer).y1 < image.y0
    assert plot.detections_size(img.shape) == (1000, 340)


def test_trajectory_truth_and_estimate_both_show(tmp_path):
    """Where the estimate lies on the truth, both show: the estimate's line
    on top, the truth's band on both sides of it."""
    t = np.linspace(0, np.pi, 12)
    xy = np.c_[100 * np.cos(t), 60 * np.sin(t)]
    rows = [{"index": i, "x": x, "y": y, "heading": None, "flags": []}
            for i, (x, y) in enumerate(xy)]
    fig = plot.plot_trajectory(rows, tmp_path / "same.png", truth=xy)
    im = read_png(tmp_path / "same.png")
    ax = fig.axes[0]
    pts = ax.transData.transform(xy)                  # display px, y up
    pts[:, 1] = im.shape[0] - pts[:, 1]               # image rows, y down
    truth_rgb = np.array([int(TRUTH_COLOUR[i:i + 2], 16) for i in (5, 3, 1)])
    blue = np.array([0xbf, 0x5f, 0x1f])
    n_band = n_line = 0
    for a, b in zip(pts[:-1], pts[1:]):
        mid = (a + b) / 2                             # between two frames' rings
        d = (b - a) / np.hypot(*(b - a))
        normal = np.array([-d[1], d[0]])
        c = np.round(mid).astype(int)
        n_line += np.abs(im[c[1], c[0]].astype(int) - blue).max() < 60
        for side in (-1, 1):
            q = np.round(mid + side * 4.5 * normal).astype(int)
            n_band += np.abs(im[q[1], q[0]].astype(int) - truth_rgb).max() < 30
    assert n_line >= 9, n_line                        # of 11 segments: the estimate on top
    assert n_band >= 18, n_band                       # of 22 sides: the truth around it


# ------------------------------------------------------------- README pictures
ROOT = Path(__file__).resolve().parents[1]


def test_every_picture_the_readme_shows_exists():
    import re

    text = (ROOT / "README.md").read_text()
    links = re.findall(r"!\[[^\]]*\]\(([^)\s]+)", text) + re.findall(r"<img[^>]+src=\"([^\"]+)\"",
                                                                     text)
    assert links, "the README shows no pictures?"
    for link in links:
        if "://" in link:
            continue
        p = ROOT / link
        assert p.is_file(), f"README links {link}, which does not exist"
        im = cv2.imread(str(p))
        assert im is not None and im.std() > 5, link
        assert p.stat().st_size < 150_000, f"{link} is {p.stat().st_size} bytes"
        assert im.shape[1] <= 1000, link
    assert sum(f.stat().st_size for f in (ROOT / "docs" / "images").iterdir()) < 1_000_000


def test_make_images_regenerates_the_readme_pictures(tmp_path):
    import importlib.util

    spec = importlib.util.spec_from_file_location("make_images", ROOT / "docs" / "make_images.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    made = mod.make_images(tmp_path)
    assert sorted(made) == ["demo_accumulator.jpg", "demo_overlay.jpg"]
    for name, (w, h, size) in made.items():
        im = cv2.imread(str(tmp_path / name))
        assert im is not None and (im.shape[1], im.shape[0]) == (w, h)
        assert w <= mod.README_WIDTH and size < 150_000 and im.std() > 5
        # the names the README links
        assert f"docs/images/{name}" in (ROOT / "README.md").read_text()
    # the planes are stacked at full size (not shrunk), so their text stays readable
    w, h, _ = made["demo_accumulator.jpg"]
    assert 500 <= w <= mod.README_WIDTH and h > 1.5 * w * 560 / 1300


def test_accumulator_without_planes_says_why():
    fig = plot.plot_accumulator(None, [], note="pattern larger than the image")
    assert [t.get_text() for t in fig.axes[0].texts] == [
        "no accumulator: pattern larger than the image"]
    fig = plot.plot_accumulator(None, [])
    assert "no edges" in fig.axes[0].texts[0].get_text()


# ------------------------------------------------- large photos, PNGs, threads
def _big_photo():
    """A 2400 x 1350 colour photo: a blue-brown left half, an orange right
    half and a light grey box turned by 30 degrees in the left half; the box
    as a detection (its true corners)."""
    img = np.empty((1350, 2400, 3), np.uint8)
    img[:, :1200] = (90, 60, 30)
    img[:, 1200:] = (30, 160, 200)
    box = cv2.boxPoints(((600.0, 700.0), (500.0, 300.0), -30.0))
    cv2.fillPoly(img, [np.round(box).astype(np.int32)], (235, 235, 235))
    det = types.SimpleNamespace(kind="object", outline=[box.astype(float)], x=600.0, y=700.0,
                                score=0.9, confidence=0.8, scale=1.0, angle=30.0,
                                line_angle=None, line_offset=None)
    return img, det


def _png_xy(fig, ax, x, y):
    """The PNG pixel (column, row) where ``ax`` draws the data point (x, y)."""
    px, py = ax.transData.transform((x, y))
    return int(round(px - 0.5)), int(round(fig.bbox.height - py - 0.5))


def test_a_large_photo_is_drawn_shrunk_to_its_size_on_the_picture(tmp_path):
    img, det = _big_photo()
    fig = plot.plot_detections(img, [det], tmp_path / "big.png", title="big")
    im = read_png(tmp_path / "big.png")
    assert (im.shape[1], im.shape[0]) == plot.detections_size(img.shape) == (1000, 606)
    ax = fig.axes[0]
    # the figure keeps the photo at the size it is drawn (900 x 506 px),
    # not the 2400 x 1350 array
    assert ax.images[0].get_array().shape == (506, 900, 3)
    # drawn in place: the two halves' colours each side of x = 1199.5, the
    # box inside its outline, the red outline on its corners
    c, r = _png_xy(fig, ax, 1199.5, 300)
    assert np.abs(im[r, c - 2].astype(int) - (90, 60, 30)).max() < 12, im[r, c - 2]
    assert np.abs(im[r, c + 2].astype(int) - (30, 160, 200)).max() < 12, im[r, c + 2]
    for x, y in ((300, 300), (2000, 1200), (600, 700)):
        c, r = _png_xy(fig, ax, x, y)
        want = img[y, x] if (x, y) != (600, 700) else (235, 235, 235)
        if (x, y) == (600, 700):          # the centre: under the origin's "+"; beside it
            c += 15
        assert np.abs(im[r, c].astype(int) - want).max() < 12, (x, y, im[r, c], want)
    red = np.abs(im.astype(int) - [45, 45, 255]).max(axis=2) < 40
    for x, y in det.outline[0]:
        c, r = _png_xy(fig, ax, x, y)
        assert red[r - 4:r + 5, c - 4:c + 5].any(), (x, y)


def test_a_small_image_is_not_resampled_before_drawing(box_search):
    img, pattern, res = box_search
    fig = plot.plot_detections(img, res.detections, pattern=pattern)
    assert fig.axes[0].images[0].get_array().shape == img.shape   # 320 x 240: drawn as it is


def test_a_large_pattern_is_drawn_shrunk_to_its_inset(tmp_path):
    big = np.full((1600, 1600), 30, np.uint8)
    cv2.rectangle(big, (200, 200), (1399, 1399), 220, -1)
    pattern = seahough.Pattern.from_image(big)
    for shape in ((480, 640), (600, 80)):            # in a corner; beside a narrow image
        fig = plot.plot_detections(np.full(shape, 60, np.uint8), [], tmp_path / "p.png",
                                   pattern=pattern)
        inset = (fig.axes[0].child_axes or fig.axes[1:])[0]
        box = inset.get_window_extent(fig.canvas.get_renderer())
        a = inset.images[0].get_array()
        assert max(a.shape) <= max(box.width, box.height) + 1 < 200, (a.shape, box)
        assert a.max() > 200 and a.min() < 40           # the pattern, not a blur of it
        assert inset.get_xlim() == (-0.5, 1599.5)        # its outline's coordinates kept


def test_edges_of_a_full_resolution_working_image(tmp_path):
    from seahough.core.features import extract_features

    gray = np.full((1200, 1600), 40, np.float32)
    gray[400:800, 500:1100] = 220
    feats = extract_features(gray, 1.0, seahough.Config())
    assert feats.gradients.magnitude.shape == (1200, 1600)
    fig = plot.plot_edges(gray.astype(np.uint8), feats, tmp_path / "edges.png")
    im = read_png(tmp_path / "edges.png")
    assert im.shape[:2] == (560, 1300)
    ax1, ax2 = fig.axes[0], fig.axes[1]
    for ax in (ax1, ax2):                   # both drawn at 520 x 390 px, not 1600 x 1200
        assert ax.images[0].get_array().shape == (390, 520)
    c, r = _png_xy(fig, ax1, 800, 600)      # the box, bright, in the working image
    assert im[r, c].min() > 200 and im[r, 20 + c - 130].max() < 60
    # the box's top edge: strong gradients, key points and segments; nothing above it
    c, r = _png_xy(fig, ax2, 800, 399.5)
    assert (im[r - 3:r + 4, c - 40:c + 40].max(axis=2) > 150).sum() > 80
    c, r = _png_xy(fig, ax2, 800, 200)
    assert im[r - 3:r + 4, c - 40:c + 40].max() < 30


def test_png_is_what_savefig_draws_and_other_formats_still_save(tmp_path, box_search):
    import io

    img, pattern, res = box_search
    fig = plot.plot_detections(img, res.detections, tmp_path / "det.png", pattern=pattern)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=plot.DPI)
    want = cv2.imdecode(np.frombuffer(buf.getvalue(), np.uint8), cv2.IMREAD_COLOR)
    assert np.array_equal(cv2.imread(str(tmp_path / "det.png"), cv2.IMREAD_COLOR), want)
    plot.plot_accumulator(res.planes, res.detections, tmp_path / "acc.pdf")
    assert (tmp_path / "acc.pdf").read_bytes().startswith(b"%PDF")
    plot.plot_edges(img, res.features, tmp_path / "edges")          # no extension: a PNG
    assert cv2.imread(str(tmp_path / "edges")).shape[:2] == (560, 1300)


def test_pictures_drawn_from_several_threads_are_those_drawn_one_by_one(tmp_path, box_search):
    """For ``detect --workers N``: figures share no state, so threads drawing
    at once make the same pictures as one thread."""
    from concurrent.futures import ThreadPoolExecutor

    img, pattern, res = box_search
    rope, _ = sim.rope_scene((240, 320), seed=4, source="procedural")

    def draw(k, folder):
        folder.mkdir()
        if k % 2:
            plot.plot_detections(img, res.detections, folder / "o.png", pattern=pattern)
            plot.plot_accumulator(res.planes, res.detections, folder / "a.png")
            plot.plot_edges(img, res.features, folder / "e.png")
        else:
            plot.plot_detections(rope, [], folder / "o.png", title="rope")
        return sorted(p.name for p in folder.iterdir())

    alone = [draw(k, tmp_path / f"one{k}") for k in range(2)]
    with ThreadPoolExecutor(4) as pool:
        together = list(pool.map(lambda k: draw(k, tmp_path / f"many{k}"), range(4)))
    assert together == alone * 2
    for k in range(4):
        for name in together[k]:
            a = cv2.imread(str(tmp_path / f"one{k % 2}" / name))
            b = cv2.imread(str(tmp_path / f"many{k}" / name))
            assert a is not None and np.array_equal(a, b), (k, name)


def test_pictures_do_not_use_pyplot():
    """No pyplot (its global current figure is not thread-safe, and it would
    pick a GUI backend): checked in a fresh process."""
    import subprocess
    import sys

    code = ("import sys, numpy as np\n"
            "from seahough import viz\n"
            "fig = viz.plot_detections(np.zeros((48, 64), np.uint8), [])\n"
            "viz.plot_accumulator(None, [])\n"
            "viz.plot_trajectory([])\n"
            "fig.canvas.draw()\n"
            "print('matplotlib.pyplot' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False", out.stdout + out.stderr


# ------------------------------------------------------- overlays at native size
def _checkerboard(h, w):
    """One-pixel squares of 20 and 220: kept only when drawn pixel for pixel."""
    return (np.indices((h, w)).sum(0) % 2 * 200 + 20).astype(np.uint8)


def _image_area(fig):
    """``(x0, y0, width, height)`` in whole PNG px of the image's axes."""
    bb = fig.axes[0].get_window_extent()
    return (int(round(bb.x0)), int(round(fig.bbox.height - bb.y1)), int(round(bb.width)),
            int(round(bb.height)))


def test_overlay_at_native_size_is_drawn_pixel_for_pixel(tmp_path):
    img = _checkerboard(1200, 1600)
    fig = plot.plot_detections(img, [], tmp_path / "native.png", max_width=0)
    im = read_png(tmp_path / "native.png")
    assert (im.shape[1], im.shape[0]) == plot.detections_size(img.shape, max_width=0) \
        == (1700, 1300)
    x0, y0, iw, ih = _image_area(fig)
    assert iw >= 1600 and ih >= 1200
    # every pixel of the photo is in the PNG: the checkerboard is intact, not a grey blur
    # (a patch in the middle: "not found" is in a corner)
    patch = im[y0 + ih // 2:y0 + ih // 2 + 40, x0 + iw // 2:x0 + iw // 2 + 40, 0].astype(int)
    assert np.abs(np.diff(patch, axis=1)).min() > 150, patch[:3, :6]
    # "native" is 0; by default the same photo is drawn 900 px wide (blurred)
    assert plot.detections_size(img.shape, max_width="native") == (1700, 1300)
    fig = plot.plot_detections(img, [], tmp_path / "default.png")
    im = read_png(tmp_path / "default.png")
    assert (im.shape[1], im.shape[0]) == plot.detections_size(img.shape) == (1000, 775)
    x0, y0, iw, ih = _image_area(fig)
    assert iw == 900
    patch = im[y0 + ih // 2:y0 + ih // 2 + 40, x0 + iw // 2:x0 + iw // 2 + 40, 0].astype(int)
    assert np.abs(np.diff(patch, axis=1)).max() < 60


def test_overlay_max_width_shrinks_a_wider_photo_and_never_enlarges(tmp_path):
    img = _checkerboard(1200, 1600)
    fig = plot.plot_detections(img, [], tmp_path / "1200.png", max_width=1200)
    assert _image_area(fig)[2] == 1200 and fig.axes[0].images[0].get_array().shape == (900, 1200)
    assert read_png(tmp_path / "1200.png").shape[:2] == (900 + 100, 1200 + 100)
    # a photo narrower than max_width: drawn at its own width, not enlarged
    assert plot.detections_size((480, 640), max_width=4000) == (740, 580)
    assert plot.detections_size((480, 640), max_width=0) == (740, 580)
    # a huge photo at native size: at most 8192 px on its longer side
    assert plot.detections_size((5000, 20000), max_width=0) == (8292, 2148)
    for bad in (-1, 2.5, "wide", True, float("nan")):
        with pytest.raises(seahough.ParameterError, match="max_width="):
            plot.plot_detections(img[:10, :10], [], max_width=bad)


def test_detect_out_max_width_on_the_command_line(tmp_path):
    import subprocess

    from conftest import seahough_command

    img = np.full((1200, 1600), 40, np.uint8)
    cv2.rectangle(img, (500, 400), (1099, 799), 220, -1)
    cv2.imwrite(str(tmp_path / "box.png"), img)

    def run(*args):
        return subprocess.run([str(seahough_command()), "detect", "rect:600,400",
                               str(tmp_path / "box.png"), "--quiet", *map(str, args)],
                              capture_output=True, text=True, timeout=180)

    for opt, folder in (("0", "native"), ("native", "native2"), (None, "default")):
        proc = run("--out", tmp_path / folder, *(("--max-width", opt) if opt else ()))
        assert proc.returncode == 0, proc.stderr
        im = cv2.imread(str(tmp_path / folder / "box_overlay.png"))
        want = plot.detections_size(img.shape, max_width=0 if opt else None)
        assert (im.shape[1], im.shape[0]) == want, (opt, im.shape)
        assert want[0] >= (1700 if opt else 1000)
    for bad in ("-3", "wide", "1.5"):
        proc = run("--out", tmp_path / "bad", "--max-width", bad)
        err = proc.stderr.strip().splitlines()
        assert proc.returncode == 2 and len(err) == 1 and "--max-width" in err[0], proc.stderr
        assert "Traceback" not in proc.stderr
    proc = run("--max-width", "800")               # without --out: nothing to size
    assert proc.returncode == 2 and "--out" in proc.stderr.strip().splitlines()[0]
    assert not (tmp_path / "bad").exists()


# ------------------------------------------- a line drawn along its visible part
def _red_extent_along(fig, im, a_deg, cx, cy, band):
    """The x range (image px) of the red pixels of the PNG ``im`` within
    ``band`` image px of the line through (cx, cy) at ``a_deg``, leaving out
    the labels' boxes."""
    ax = fig.axes[0]
    red = np.abs(im.astype(int) - [45, 45, 255]).max(axis=2) < 40
    H = im.shape[0]
    for t in ax.texts:                                   # the label (text and box)
        bb = t.get_window_extent(fig.canvas.get_renderer())
        p = t.get_bbox_patch()
        if p is not None:
            bb = bb.union([bb, p.get_window_extent(fig.canvas.get_renderer())])
        red[int(H - bb.y1) - 2:int(H - bb.y0) + 3, int(bb.x0) - 2:int(bb.x1) + 3] = False
    rows, cols = np.nonzero(red)
    xy = ax.transData.inverted().transform(np.c_[cols + 0.5, H - rows - 0.5])
    a = np.radians(a_deg)
    dist = (xy[:, 0] - cx) * np.sin(a) + (xy[:, 1] - cy) * np.cos(a)
    x = xy[np.abs(dist) <= band, 0]
    assert x.size > 100
    return np.percentile(x, 0.5), np.percentile(x, 99.5)


@pytest.mark.parametrize("seed", [1, 2])
def test_a_line_is_drawn_along_the_part_of_the_rope_the_image_shows(tmp_path, seed):
    shape, a = (240, 320), 20.0
    rope, truth = sim.rope_scene(shape, angle=a, offset=10.0, seed=seed, source="procedural")
    # the same scene without the rope (same background and water), for its right half
    empty, _ = sim.rope_scene(shape, angle=a, offset=1e4, seed=seed, source="procedural")
    part = rope.copy()
    part[:, 160:] = empty[:, 160:]
    det = seahough.Detector(seahough.Pattern.line(120, 8), angle_range=(0, 180), max_results=1)
    for scene, visible in ((part, (0, 160)), (rope, (0, 320))):
        dets = det.detect(scene)
        assert dets and dets[0].kind == "line"
        assert abs(dets[0].line_angle - a) < 2
        fig = plot.plot_detections(scene, dets, tmp_path / "rope.png")
        im = read_png(tmp_path / "rope.png")
        x0, x1 = _red_extent_along(fig, im, a, truth.x, truth.y, 8)
        assert abs(x0 - visible[0]) < 32 and abs(x1 - visible[1]) < 32, (visible, x0, x1)
        # the detection says that extent too (a sonar user's JSON box lay 85-167 px
        # along a pipe the overlay drew over 0-72): its segment, and its box there
        seg = dets[0].segment
        assert seg is not None and seg.shape == (2, 2)
        assert abs(seg[:, 0].min() - visible[0]) < 32 and abs(seg[:, 0].max() - visible[1]) < 32
        # (the overlay draws the detection's own: the picture and the JSON agree)
        assert abs(seg[:, 0].min() - x0) < 4 and abs(seg[:, 0].max() - x1) < 4, (seg, x0, x1)
        rec = dets[0].to_dict()
        assert np.allclose(rec["segment"], seg, atol=1e-3)
        assert abs(rec["box"][0] - seg[:, 0].min()) < 4 and abs(rec["box"][2] - seg[:, 0].max()) < 4


def test_a_line_without_a_visible_extent_is_drawn_across_the_image(tmp_path):
    # a detection on an image that does not show it (a flat grey): the old
    # picture, both borders across the whole image
    flat = np.full((240, 320), 90, np.uint8)
    det = types.SimpleNamespace(kind="line", x=159.5, y=119.5, line_angle=20.0, line_offset=0.0,
                                scale=1.0, angle=20.0, score=0.9, confidence=0.8,
                                outline=[np.array([[120.0, 130.0], [200.0, 100.0]]) + o
                                         for o in ((0, -3), (0, 3))])
    fig = plot.plot_detections(flat, [det], tmp_path / "flat.png")
    x0, x1 = _red_extent_along(fig, read_png(tmp_path / "flat.png"), 20.0, 159.5, 119.5, 8)
    assert x0 < 10 and x1 > 310


# ------------------------------------------- the pattern inset: shapes from their outline
GATE = [(0, 80), (0, 0), (60, 0), (60, 80)]


def _inset(fig):
    """The pattern's axes: an inset of the image's, or beside a narrow image."""
    insets = fig.axes[0].child_axes or fig.axes[1:]
    assert len(insets) == 1
    return insets[0]


@pytest.mark.parametrize("make", [
    lambda: seahough.Pattern.polyline(GATE, 6),                                   # open shape
    lambda: seahough.Pattern.polygon([(0, 0), (3, 0), (300, 297), (300, 300), (297, 300),
                                      (0, 3)]),                                  # thin, diagonal
    lambda: seahough.Pattern.circle(30, 22),                                      # a ring
    lambda: seahough.Pattern.line(200, 8),
    lambda: seahough.Pattern.rectangle(60, 20)])
def test_a_shape_pattern_inset_is_drawn_from_its_outline(tmp_path, make):
    from matplotlib.lines import Line2D
    from matplotlib.patches import PathPatch

    pattern = make()
    fig = plot.plot_detections(np.full((480, 640), 60, np.uint8), [], tmp_path / "p.png",
                               pattern=pattern)
    ins = _inset(fig)
    assert not ins.images                             # not the pattern's raster image
    ph, pw = pattern.image.shape
    assert ins.get_xlim() == (-0.5, pw - 0.5) and ins.get_ylim() == (ph - 0.5, -0.5)
    # every polygon of the outline stroked, in pattern-image pixels
    drawn = [np.asarray(ln.get_xydata()) for ln in ins.lines if isinstance(ln, Line2D)]
    for o in pattern.outline:
        assert any(len(d) >= len(o) and np.allclose(d[:len(o)], o) for d in drawn), o
    # and the shape filled: one patch whose path runs along the outline
    patches = [p for p in ins.patches if isinstance(p, PathPatch)]
    assert len(patches) == 1
    verts = patches[0].get_path().vertices
    for o in pattern.outline:
        gap = np.abs(verts[:, None, :] - np.asarray(o)[None, :, :]).max(axis=2).min(axis=0)
        assert gap.max() < 1e-9, gap.max()
    assert fig.axes[0].get_window_extent().contains(*ins.get_window_extent().min)


def _inset_px(fig, ins, im, x, y):
    """The PNG's BGR pixel where the inset ``ins`` draws pattern pixel (x, y)."""
    c, r = _png_xy(fig, ins, x, y)
    return im[r, c].astype(int)


def test_a_gate_inset_shows_its_strips_filled_and_its_gap_empty(tmp_path):
    gate = seahough.Pattern.polyline(GATE, 6)
    fig = plot.plot_detections(np.full((480, 640, 3), (90, 70, 30), np.uint8), [],
                               tmp_path / "gate.png", pattern=gate)
    im = read_png(tmp_path / "gate.png")
    ins = _inset(fig)
    (x0, y0), (x1, _) = gate.polyline_points[0], gate.polyline_points[2]   # the posts' feet
    post = _inset_px(fig, ins, im, x0, 0.5 * (y0 + gate.polyline_points[1][1]))
    gap = _inset_px(fig, ins, im, 0.5 * (x0 + x1), y0 - 10)
    assert post.min() > gap.max() + 60, (post, gap)   # a light strip on a dark ground
    assert np.ptp(gap) < 10 and gap.max() < 60        # the gap: the dark ground, not the photo
    red = count_colour(im[int(fig.bbox.height - ins.get_window_extent().y1):
                          int(fig.bbox.height - ins.get_window_extent().y0),
                          int(ins.get_window_extent().x0):int(ins.get_window_extent().x1)],
                       COLOURS[0])
    assert red > 200                                   # the outline stroked in the first colour


def test_a_ring_inset_leaves_its_hole_unfilled(tmp_path):
    ring = seahough.Pattern.circle(30, 18)
    fig = plot.plot_detections(np.full((480, 640), 60, np.uint8), [], tmp_path / "ring.png",
                               pattern=ring)
    im = read_png(tmp_path / "ring.png")
    ins = _inset(fig)
    cx, cy = ring.origin
    band = _inset_px(fig, ins, im, cx + 24, cy)        # between the radii
    hole = _inset_px(fig, ins, im, cx - 9, cy + 9)     # inside the hole, off the "+"
    outside = _inset_px(fig, ins, im, 1, 1)            # the corner, outside the ring
    assert band.min() > hole.max() + 60
    assert np.abs(hole - outside).max() < 6


def test_an_image_pattern_inset_keeps_its_image_and_its_mask_outline(tmp_path):
    img = np.full((80, 80), 30, np.uint8)
    cv2.circle(img, (40, 40), 30, 220, -1)
    mask = np.zeros_like(img)
    cv2.circle(mask, (40, 40), 32, 255, -1)
    for m in (None, mask):
        pattern = seahough.Pattern.from_image(img, m)
        fig = plot.plot_detections(np.full((480, 640), 60, np.uint8), [], tmp_path / "i.png",
                                   pattern=pattern)
        ins = _inset(fig)
        assert len(ins.images) == 1 and np.array_equal(ins.images[0].get_array(), img)
        strokes = [ln for ln in ins.lines if len(ln.get_xydata()) > 1]
        if m is None:               # no mask: no frame drawn around the whole image
            assert strokes == []
        else:                       # the mask's outline: about 32 px from the centre
            r = np.hypot(*(strokes[0].get_xydata() - 40).T)
            assert len(strokes) == 1 and np.abs(r - 32).max() < 1.5
        # its origin marked with a "+"
        assert any(ln.get_marker() == "+" and np.allclose(ln.get_xydata(), [pattern.origin])
                   for ln in ins.lines)


# ------------------------------------------- the edges picture in image pixels
def test_edges_picture_is_in_full_resolution_pixels_at_a_working_scale(tmp_path):
    from matplotlib.collections import LineCollection, PathCollection

    photo = np.full((960, 1280, 3), (90, 70, 30), np.uint8)
    cv2.rectangle(photo, (500, 300), (899, 599), (200, 220, 230), -1)   # x 500-899, y 300-599
    res = seahough.Detector(seahough.Pattern.rectangle(400, 300), max_results=1).search(photo)
    g = res.features.gradients
    assert g.factor < 0.5 and g.magnitude.shape[1] < 1280 / 2     # searched at a working scale
    fig = plot.plot_edges(photo, res.features, tmp_path / "edges.png")
    read_png(tmp_path / "edges.png")
    ax1, ax2 = fig.axes[0], fig.axes[1]
    for ax in (ax1, ax2):        # axes, and the images across them, in the photo's pixels
        assert ax.get_xlim() == (-0.5, 1279.5) and ax.get_ylim() == (959.5, -0.5)
        assert tuple(ax.images[0].get_extent()) == (-0.5, 1279.5, 959.5, -0.5)
        assert "image px" in ax.get_xlabel() and "image px" in ax.get_ylabel()
    # key points: the photo's coordinates of the rectangle's border (not 1/4 of them)
    pts = [c for c in ax2.collections if isinstance(c, PathCollection)][0].get_offsets()
    kx, ky = np.asarray(pts, float).T
    assert len(kx) == len(res.features.keypoints) > 50
    fx, fy = g.to_full(res.features.edges.x[res.features.keypoints],
                       res.features.edges.y[res.features.keypoints])
    assert np.allclose(kx, fx) and np.allclose(ky, fy)
    near = np.minimum(np.minimum(abs(kx - 499.5), abs(kx - 899.5)),
                      np.minimum(abs(ky - 299.5), abs(ky - 599.5)))
    assert np.median(near) < 4 and kx.min() > 480 and kx.max() < 920
    segs = [c for c in ax2.collections if isinstance(c, LineCollection)][0].get_segments()
    ends = np.vstack(segs)
    assert ends[:, 0].min() > 480 and ends[:, 0].max() < 920 and ends[:, 1].max() < 620
    # the titles say the working scale and size
    assert f"{g.factor:.2f}".rstrip("0") + "x" in ax2.get_title()
    assert f"{g.magnitude.shape[1]} x {g.magnitude.shape[0]} px" in ax1.get_title()
    assert f"{len(res.features.keypoints):,} key points" in ax2.get_title()


def test_not_found_sits_in_a_corner_not_over_the_middle(tmp_path):
    """The "not found" note is in the top left corner (the pattern inset in
    the top right), so the middle of the picture, where a user looks for
    the object, stays visible."""
    img = _checkerboard(300, 400)
    fig = plot.plot_detections(img, [], tmp_path / "nf.png", pattern=seahough.Pattern.circle(20))
    ax = fig.axes[0]
    [note] = [t for t in ax.texts if t.get_text() == "not found"]
    x, y = note.get_position()
    assert note.get_transform() == ax.transAxes and (x, y) == (0.02, 0.98)
    bb = note.get_window_extent(fig.canvas.get_renderer())
    area = ax.get_window_extent()
    assert bb.x1 < area.x0 + 0.5 * area.width and bb.y0 > area.y0 + 0.7 * area.height


def test_outlines_drawn_small_are_thin_lines_and_thin_strips_their_centre_line():
    """An outline drawn large: closed, thick; drawn small (a small disc): closed,
    thin; a long strip a few px wide (a gate's post at a small scale): its
    centre line, thin (its two thick borders made one solid bar over it)."""
    from seahough.viz.detections import _OUTLINE, _THIN_OUTLINE, _outline_style

    big = np.array([[0, 0], [60, 0], [60, 40], [0, 40]], float)
    pts, lw, fx = _outline_style(big, 2.0)
    assert len(pts) == 5 and lw == 2.2 and fx is _OUTLINE
    small = 0.1 * big
    pts, lw, fx = _outline_style(small, 2.0)
    assert len(pts) == 5 and lw < 2.2 and fx is _THIN_OUTLINE
    # a strip 3 px wide and 80 long, turned by 30 degrees
    t = np.radians(30.0)
    rot = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
    strip = np.array([[0, -1.5], [80, -1.5], [80, 1.5], [0, 1.5]]) @ rot.T + [100, 50]
    pts, lw, fx = _outline_style(strip, 2.0)
    assert len(pts) == 2 and fx is _THIN_OUTLINE
    ends = sorted(map(tuple, np.round(pts, 3)))
    assert np.allclose(ends, sorted(map(tuple, np.round([[100, 50], rot @ [80, 0] + [100, 50]], 3))))


def test_a_thin_shape_that_is_no_straight_strip_keeps_its_outline():
    """An L or a U drawn small is not a strip: its thin outline, not a line
    through the empty space of its bounding box (a review found one)."""
    from seahough.viz.detections import _THIN_OUTLINE, _outline_style

    ell = np.array([[0, 0], [4, 0], [4, 36], [40, 36], [40, 40], [0, 40]], float) + 100
    pts, lw, fx = _outline_style(ell, 0.25)
    assert len(pts) == 7 and fx is _THIN_OUTLINE


def test_a_filled_caption_is_drawn_and_kept_free_of_the_labels(monkeypatch):
    """plot_detections(blanks=...): each caption's box dashed, with its note;
    its corners are among what the list and the pattern inset keep clear of."""
    from seahough.core.blanks import find_blanks
    img = np.random.default_rng(0).uniform(60, 200, (240, 320)).astype(np.float32)
    img[:16, :120] = 0
    for cx in range(8, 114, 14):
        cv2.circle(img, (cx, 8), 4, 235.0, -1)
    for x in (60, 160, 260):
        cv2.circle(img, (x, 170), 12, 250.0, -1)
    res = seahough.Detector(seahough.Pattern.circle(12), max_results=3).search(img)
    assert len(res.detections) == 3 and res.blanks.captions
    import seahough.viz.detections as V
    seen = {}
    free = V._free_corners

    def spy(points, w, h):
        seen["points"] = points
        return free(points, w, h)

    monkeypatch.setattr(V, "_free_corners", spy)
    fig = plot.plot_detections(img, res.detections, blanks=res.blanks)
    ax = fig.axes[0]
    assert any(t.get_text() == "caption, not searched" for t in ax.texts)
    dashed = [ln for ln in ax.lines if ln.get_linestyle() not in ("-", "None")]
    assert len(dashed) == 1
    # a region of Config.ignore too, marked as such
    from seahough.core.blanks import Blanks
    more = Blanks(res.blanks.border, res.blanks.captions, ((200, 20, 300, 60),))
    fig2 = plot.plot_detections(img, res.detections, blanks=more)
    assert any(t.get_text() == "ignored, not searched" for t in fig2.axes[0].texts)
    xs, ys = dashed[0].get_data()
    assert (min(xs), max(xs), min(ys), max(ys)) == (-0.5, 121.5, -0.5, 17.5)
    pts = {tuple(p) for p in seen["points"].tolist()}
    assert {(0.0, 0.0), (122.0, 18.0)} <= pts
    assert free(seen["points"], 320, 240)[0] != 0            # (not the top left corner)


def test_a_line_s_cross_is_on_the_segment_the_image_shows():
    """A short post near the top of a frame: its line's reported point (the
    line's nearest the image centre) lies in open water below it; the "+"
    of the overlay is drawn on the post's visible segment (a user trial
    found it in open water)."""
    img = np.full((240, 320), 60, np.uint8)
    cv2.rectangle(img, (150, 10), (159, 90), 220, -1)        # a post, rows 10-90
    found = seahough.Detector(seahough.Pattern.line(80, 10), angle_range=(80, 100),
                              max_results=1).detect(img)
    assert len(found) == 1 and found[0].y > 100               # (the reported point: below it)
    fig = plot.plot_detections(img, found)
    (cross,) = [ln for ln in fig.axes[0].lines if ln.get_marker() == "+"]
    x, y = (float(v[0]) for v in cross.get_data())
    assert 145 <= x <= 165 and 5 <= y <= 95, (x, y)


def test_a_list_of_other_things_is_a_parameter_error_naming_it():
    """plot_detections(img, [1, 2]) was an AttributeError deep in the drawing."""
    from seahough.errors import ParameterError
    from seahough.viz import plot_curves, plot_detections

    img = np.zeros((60, 80), np.uint8)
    with pytest.raises(ParameterError, match="detections: expected Detection objects"):
        plot_detections(img, [1, 2])
    with pytest.raises(ParameterError, match="curves: expected Curve objects"):
        plot_curves(img, [1, 2])
    res = seahough.Detector(seahough.Pattern.rectangle(40, 30)).search(img)
    with pytest.raises(ParameterError, match="a list of Detection objects .*got SearchResult"):
        plot_detections(img, res)                         # (its .detections)
    with pytest.raises(ParameterError, match="best: expected Candidate"):
        plot_curves(img, [], best=5)


def test_a_long_title_is_broken_to_fit_the_picture():
    """A not-found picture's title says why, and ran off its right edge (a
    user read "...under min_len")."""
    from seahough.viz import plot_curves, plot_detections

    img = np.zeros((480, 640), np.uint8)
    why = ("empty.png: no curve found; best line: score 0.71, the rope followed from this "
           "line is 24 px long, under min_length 96")
    for fig in (plot_curves(img, [], title=why), plot_detections(img, [], title=why)):
        ax = fig.axes[0]
        t = ax.title if ax.title.get_text() else ax._left_title
        assert "\n" in t.get_text() and t.get_text().replace("\n", " ") == why
        bb = t.get_window_extent(fig.canvas.get_renderer())
        assert bb.x1 <= fig.bbox.width and bb.y1 <= fig.bbox.height, bb
    # one far too long: three lines, the last cut; one long word (a path) cut too
    for title, lines in ((" ".join([why] * 5), 3), ("/a/very/long/path" * 20, 1)):
        fig = plot_detections(img, [], title=title)
        t = fig.axes[0]._left_title
        assert t.get_text().count("\n") == lines - 1 and t.get_text().endswith("...")
        assert t.get_window_extent(fig.canvas.get_renderer()).x1 <= fig.bbox.width


def test_a_curve_search_that_found_nothing_draws_its_best_line():
    """The README says the best line a curve search started from is shown:
    it was only named in the title."""
    from types import SimpleNamespace

    from seahough.geometry import Similarity
    from seahough.viz import plot_curves

    img = np.zeros((240, 320), np.uint8)
    best = SimpleNamespace(pose=Similarity.from_params(160.0, 120.0, 1.0, math.radians(30.0)))
    fig = plot_curves(img, [], best=best)
    [line] = [ln for ln in fig.axes[0].lines if ln.get_linestyle() == ":"]
    x, y = line.get_xdata(), line.get_ydata()
    assert math.degrees(math.atan2(-(y[1] - y[0]), x[1] - x[0])) % 180 == pytest.approx(30, abs=1)
    assert any(t.get_text() == "best line, no curve" for t in fig.axes[0].texts)
    assert not [ln for ln in plot_curves(img, []).axes[0].lines if ln.get_linestyle() == ":"]


def test_no_data_beyond_a_sonar_fan_is_outlined_dashed():
    """The black beyond a forward-looking sonar's fan is filled before a search
    (core.blanks.no_data): the overlay outlines it dashed, as it does the
    other regions the search left out."""
    from core.test_blanks import _sonar_fan

    fan = _sonar_fan(True)
    res = seahough.Detector(seahough.Pattern.line(120, 8), angle_range=(0, 180)).search(fan)
    assert res.blanks.no_data is not None
    ax = plot.plot_detections(fan, res.detections, blanks=res.blanks).axes[0]
    sets = [c for c in ax.collections if type(c).__name__ in ("QuadContourSet", "ContourSet")
            or hasattr(c, "levels")]
    assert len(sets) == 1 and list(sets[0].levels) == [0.5]
    plain = plot.plot_detections(fan, res.detections).axes[0]
    assert not [c for c in plain.collections if hasattr(c, "levels")]


@pytest.mark.parametrize("fx, fy", [(0.95, 0.5), (0.05, 0.02), (0.97, 0.98), (0.3, 0.5)])
def test_a_declined_candidates_label_stays_in_its_panel(fx, fy):
    # near the right edge the label ran into the colour bar, near the bottom
    # under the axis ("(de|clined)": a new user's trial); it now goes left / up
    from seahough.viz.accumulator import _side_label
    from seahough.viz._figure import _figure

    fig = _figure(1300, 560)
    ax = fig.add_axes([0.06, 0.1, 0.36, 0.76])
    ax.set_xlim(0, 360)
    ax.set_ylim(0.5, 2.0)
    _side_label(ax, "best candidate (declined)", 360 * fx, 0.5 + 1.5 * fy, -14)
    r = fig.canvas.get_renderer()
    box, panel = ax.texts[0].get_window_extent(r), ax.get_window_extent(r)
    assert panel.x0 <= box.x0 and box.x1 <= panel.x1 and panel.y0 <= box.y0 and box.y1 <= panel.y1
