"""A prepared pattern saved to a file and read back finds the same things."""

import numpy as np
import pytest

import seahough
from seahough import sim as S


def _same_detections(a, b):
    assert len(a) == len(b) and a
    for d, e in zip(a, b):
        assert (d.x, d.y, d.scale, d.angle, d.score, d.confidence, d.flags) == \
               (e.x, e.y, e.scale, e.angle, e.score, e.confidence, e.flags)
        np.testing.assert_array_equal(d.matrix, e.matrix)


@pytest.mark.parametrize("make", [
    lambda: seahough.Pattern.from_image(*S.marker("board", 120)),          # photo with a mask
    lambda: seahough.Pattern.line(200, 8),                                  # line: its width kept
    lambda: seahough.Pattern.circle(30, inner_radius=18, polarity="either"),
])
def test_saved_pattern_finds_the_same(tmp_path, make):
    p = make()
    q = seahough.Pattern.load(p.save(tmp_path / "p"))                       # ".npz" added
    assert (tmp_path / "p.npz").is_file()
    assert (q.kind, q.origin, q.polarity, q.is_line, q.is_frame) == \
           (p.kind, p.origin, p.polarity, p.is_line, p.is_frame)
    scene, truth = S.marker_scene("board", seed=3, source="procedural")[:2]
    if p.is_line:
        scene = S.rope_scene(seed=1)[0]
    elif p.kind == "ring":
        scene = np.full((240, 320), 40, np.uint8)
        import cv2
        cv2.circle(scene, (150, 120), 45, 220, -1)
        cv2.circle(scene, (150, 120), 27, 40, -1)
    a = seahough.Detector(p, angle_range=(0, 180) if p.is_line else (0, 360)).detect(scene)
    b = seahough.Detector(q, angle_range=(0, 180) if p.is_line else (0, 360)).detect(scene)
    _same_detections(a, b)


def test_saved_frame_measures_the_same_motion(tmp_path):
    prev, cur, _ = S.frame_pair(seed=4, source="procedural")[:3]
    p = seahough.Pattern.from_frame(seahough.to_gray(prev))
    q = seahough.Pattern.load(p.save(tmp_path / "frame.npz"))
    from seahough.motion.pair import motion_from_pattern
    m1, m2 = motion_from_pattern(p, cur), motion_from_pattern(q, cur)
    assert m1 is not None
    np.testing.assert_array_equal(m1.matrix, m2.matrix)
    assert m1.confidence == m2.confidence


def test_bad_pattern_files_say_what_is_wrong(tmp_path):
    with pytest.raises(seahough.ImageReadError, match="no such file"):
        seahough.Pattern.load(tmp_path / "missing.npz")
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(seahough.PatternError, match="junk.npz: not a saved seahough pattern"):
        seahough.Pattern.load(tmp_path / "junk.npz")
    np.savez(tmp_path / "other.npz", x=np.zeros(3))
    with pytest.raises(seahough.PatternError, match="other.npz: not a saved seahough pattern"):
        seahough.Pattern.load(tmp_path / "other.npz")
    (tmp_path / "dir.npz").mkdir()
    with pytest.raises(seahough.SeahoughError, match="dir.npz"):
        seahough.Pattern.rectangle(40, 30).save(tmp_path / "dir.npz")
