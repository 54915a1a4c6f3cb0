"""seahough.plot: every picture is a PNG of a fixed size that shows something."""

from __future__ import annotations

import types

import cv2
import numpy as np
import pytest

import seahough
from seahough import plot
from seahough import simulate as sim


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
    assert count_colour(im, plot.COLOURS[0]) > 300          # the outline is drawn


def test_plot_detections_empty_and_colour(tmp_path):
    scene = sim.negative_scene((120, 160), seed=1, source="procedural")
    plot.plot_detections(scene, [], tmp_path / "none.png")
    im = read_png(tmp_path / "none.png")
    assert (im.shape[1], im.shape[0]) == plot.detections_size((120, 160))
    assert count_colour(im, "#b00020", tol=60) > 500         # the red "not found" box


def test_plot_detections_line(tmp_path):
    rope, truth = sim.rope_scene((240, 320), seed=4, source="procedural")
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
    a = plot._display_angles(res.planes.angles)
    assert np.all(np.diff(a) > 0) and a[0] < 0 < a[-1]


def test_plot_edges(tmp_path, box_search):
    img, _, res = box_search
    plot.plot_edges(img, res.features, tmp_path / "edges.png")
    im = read_png(tmp_path / "edges.png")
    assert im.shape[:2] == (560, 1300)
    assert count_colour(im, "#00e5ff") > 100               # segments drawn
    plot.plot_edges(img, None, tmp_path / "edges2.png")    # features computed on the spot
    assert read_png(tmp_path / "edges2.png").shape[:2] == (560, 1300)


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


def test_save_mosaic(tmp_path):
    mosaic = np.zeros((50, 80, 3), np.uint8)
    mosaic[10:40, 20:60] = (0, 200, 255)
    p = plot.save_mosaic(mosaic, tmp_path / "sub" / "mosaic.png")
    back = cv2.imread(str(p))
    assert back is not None and np.array_equal(back, mosaic)
