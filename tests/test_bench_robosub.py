"""The RoboSub benchmark's split and matching rules (bench/bench_robosub.py).

The bench module is imported in a subprocess, as tests/test_bench_smoke.py
does: importing it makes the process single-threaded (bench/_common.py).
"""

from __future__ import annotations

from conftest import run_bench_code


def _run(code: str) -> None:
    run_bench_code(code, timeout=120)


HEAD = "import math, bench_robosub as B\nfrom bench_robosub import Box, Det\n"


def test_split_by_blocks_of_frame_numbers():
    _run(HEAD + (
        "ns = (1, 99, 100, 999, 1000, 1400, 1401, 1469, 1470, 1499)\n"
        "assert [B.part_of(n) for n in ns] == [\n"
        "    'sim', 'sim', 'tune', 'tune', 'test', 'test', 'tune', 'tune', 'test', 'test']\n"
        "assert B.part_of(1500) == ''\n"))


def test_voc_boxes_and_task_truth():
    _run(HEAD + (
        "xml = ('<annotation><object><name>qual_gate</name><bndbox><xmin>10</xmin>'\n"
        "       '<ymin>20</ymin><xmax>30</xmax><ymax>200</ymax></bndbox></object>'\n"
        "       '<object><name>buoy_red</name>'\n"
        "       '<bndbox><xmin>50</xmin><ymin>60</ymin><xmax>90</xmax><ymax>110</ymax></bndbox>'\n"
        "       '</object><object><name>qual_gate</name><bndbox><xmin>300</xmin><ymin>30</ymin>'\n"
        "       '<xmax>320</xmax><ymax>190</ymax></bndbox></object><object><name>channel</name>'\n"
        "       '<bndbox><xmin>1</xmin><ymin>1</ymin><xmax>5</xmax><ymax>5</ymax></bndbox>'\n"
        "       '</object></annotation>')\n"
        "boxes = B.parse_voc(xml)\n"
        "assert [b.name for b in boxes] == ['qual_gate', 'buoy_red', 'qual_gate', 'channel']\n"
        "p = B.Photo(1450, None, (480, 640), boxes)\n"
        "assert p.part == 'tune'\n"
        "assert [b.name for b in B.truth(p, 'buoy')] == ['buoy_red']\n"
        "assert len(B.truth(p, 'post')) == 2\n"
        "g, = B.truth(p, 'gate')\n"
        "assert (g.x0, g.y0, g.x1, g.y1) == (10, 20, 320, 200)\n"
        # one post labelled: the photo is left out of the gate task
        "p1 = B.Photo(1450, None, (480, 640), boxes[:2])\n"
        "assert B.truth(p1, 'gate') is None and len(B.truth(p1, 'post')) == 1\n"
        # a post box 0 px wide is left out of the posts, still part of the gate's extent
        "p2 = B.Photo(1450, None, (480, 640), boxes[:2] + [Box('qual_gate', 640, 5, 640, 100)])\n"
        "assert len(B.truth(p2, 'post')) == 1 and B.truth(p2, 'gate')[0].x1 == 640\n"
        "assert B.truth(B.Photo(1450, None, (480, 640), boxes[1:2]), 'gate') == []\n"))


def test_disc_rule():
    _run(HEAD + (
        "shape = (480, 640)\n"
        "b = Box('buoy_red', 100, 100, 140, 150)\n"          # 40 wide, 50 high
        "assert B.disc_cost(Det(120, 120, size=40), b, shape) is not None\n"
        "assert B.disc_cost(Det(120, 120, size=59), b, shape) is not None\n"   # 40 x 1.5 = 60
        "assert B.disc_cost(Det(120, 120, size=61), b, shape) is None\n"
        "assert B.disc_cost(Det(120, 120, size=27), b, shape) is not None\n"
        "assert B.disc_cost(Det(120, 120, size=26), b, shape) is None\n"       # 40 / 1.5 = 26.7
        "assert B.disc_cost(Det(99, 120, size=40), b, shape) is None\n"        # centre outside
        "assert B.disc_cost(Det(120, 120, size=40), b, shape) < B.disc_cost(Det(120, 140, size=40),"
        " b, shape)\n"
        # cut by the left border: the box's height is the buoy's size
        "cut = Box('buoy_red', 0, 100, 20, 160)\n"
        "assert B.buoy_size(cut, shape) == 60 and B.buoy_size(b, shape) == 40\n"
        "assert B.disc_cost(Det(10, 130, size=60), cut, shape) is not None\n"))


def test_line_rule():
    _run(HEAD + (
        "b = Box('qual_gate', 100, 0, 120, 180)\n"           # 20 x 180: a vertical post
        "assert B.line_cost(Det(110, 400, angle=90.0), b) < 1e-9\n"    # anywhere along the line
        "assert B.line_cost(Det(121.5, 0, angle=90.0), b) is not None\n"   # 2 px slack
        "assert B.line_cost(Det(123, 0, angle=90.0), b) is None\n"
        "assert B.line_cost(Det(110, 90, angle=0.0), b) is None\n"     # horizontal
        # tilted by 6 degrees through the box centre: inside the middle third, angle ok
        "assert B.line_cost(Det(110, 90, angle=96.0), b) is not None\n"
        # the box's diagonal is 6.3 degrees: 12 degrees is too much (and leaves the box)
        "assert B.line_cost(Det(110, 90, angle=78.0), b) is None\n"
        # a wide box (a tilted post) allows its diagonal's angle
        "w = Box('qual_gate', 100, 0, 160, 180)\n"           # diagonal: 18.4 degrees
        "assert B.line_cost(Det(130, 90, angle=75.0), w) is not None\n"
        "assert B.line_cost(Det(130, 90, angle=70.0), w) is None\n"
        # the crossing points: y = 60 and y = 120 for this box; a 6-degree tilt moves the
        # line by 30 * tan(6 deg) = 3.15 px there: x(120) = 121.2 inside (+2 px), 122.7 not
        "assert B.line_cost(Det(118.0, 90, angle=96.0), b) is not None\n"
        "assert B.line_cost(Det(119.5, 90, angle=96.0), b) is None\n"
        "assert B.angle_diff(179.0, 1.0) == 2.0 and B.angle_diff(90.0, 0.0) == 90.0\n"))


def test_gate_rule_and_assignment():
    _run(HEAD + (
        "g = Box('gate', 100, 100, 300, 200)\n"
        "assert B.iou((100, 100, 300, 200), (100, 100, 300, 200)) == 1.0\n"
        "assert abs(B.iou((100, 100, 300, 200), (200, 100, 400, 200)) - 1 / 3) < 1e-12\n"
        "assert B.frame_cost(Det(0, 0, box=(110, 100, 300, 210)), g) is not None\n"
        "assert B.frame_cost(Det(0, 0, box=(200, 100, 400, 200)), g) is None\n"
        # one detection matches at most one box; a second detection on the same box is false
        "shape = (480, 640)\n"
        "boxes = [Box('buoy_red', 100, 100, 140, 140), Box('buoy_green', 300, 100, 340, 140)]\n"
        "dets = [Det(120, 120, size=40), Det(121, 121, size=40), Det(320, 120, size=40),\n"
        "        Det(500, 300, size=40)]\n"
        "assert B.assign(dets, boxes, B.disc_cost, shape) == [True, False, True, False]\n"
        "p = B.Photo(1040, None, shape, boxes)\n"
        "s = B.score('buoy', [p], {1040: dets})\n"
        "assert (s['found'], s['objects'], s['false'], s['images']) == (2, 2, 2, 1)\n"
        "assert s['recall'] == 1.0 and s['fa'] == 2.0\n"
        "s = B.score('buoy', [p], {1040: dets}, dict(top=1))\n"
        "assert (s['found'], s['false']) == (1, 0)\n"
        # photos left out of the gate task count in neither recall nor false detections
        "one = B.Photo(1400, None, shape, [Box('qual_gate', 10, 10, 30, 200)])\n"
        "s = B.score('gate', [one], {1400: [Det(0, 0, box=(0, 0, 50, 50))]})\n"
        "assert s['images'] == 0 and s['false'] == 0\n"))


def test_tuning_rule():
    _run(HEAD + (
        "c = [dict(recall=0.9, fa=0.5, ms=1.0), dict(recall=0.7, fa=0.3, ms=9.0),\n"
        "     dict(recall=0.7, fa=0.1, ms=9.0), dict(recall=0.6, fa=0.0, ms=1.0)]\n"
        "assert B.choose(c) is c[2]\n"                      # best recall within the budget
        "c = [dict(recall=0.9, fa=0.5, ms=1.0), dict(recall=0.2, fa=0.4, ms=1.0)]\n"
        "assert B.choose(c) is c[1]\n"                      # none within: fewest false
        "ds = [Det(0, 0, strength=0.9, nfa=1e-3), Det(0, 0, strength=0.5, nfa=1e-9),\n"
        "      Det(0, 0, strength=0.8, nfa=0.5)]\n"
        "assert B.keep(ds, top=5, min_strength=0.6) == [ds[0], ds[2]]\n"
        "assert B.keep(ds, top=5, max_nfa=1e-2) == ds[:2]\n"
        "assert B.keep(ds, top=1) == ds[:1]\n"))


def test_guil_template_keeps_the_gate_outline():
    """The gate template turned for Guil's [0, 360] angles: its outline is the
    pattern's, turned by the same matrix (a synthetic gate found upright)."""
    _run(HEAD + (
        "import numpy as np\n"
        "tpl, pts, span = B.guil_template()\n"
        "assert span == (0.0, 20.0) and tpl.shape[0] > 116 and tpl.shape[1] > 229\n"
        # the outline lies on the template's bright strips
        "ij = np.round(pts).astype(int)\n"
        "ok = (ij[:, 0] >= 0) & (ij[:, 1] >= 0) & (ij[:, 0] < tpl.shape[1]) & "
        "(ij[:, 1] < tpl.shape[0])\n"
        "assert ok.all()\n"))
