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
    # an image given to load: what to call instead, not numpy's words about pickles
    import cv2
    cv2.imwrite(str(tmp_path / "buoy.png"), np.zeros((20, 20), np.uint8))
    with pytest.raises(seahough.PatternError, match="not an .npz archive.*Pattern.from_image") \
            as info:
        seahough.Pattern.load(tmp_path / "buoy.png")
    assert "pickle" not in str(info.value)
    np.savez(tmp_path / "other.npz", x=np.zeros(3))
    with pytest.raises(seahough.PatternError, match="other.npz: not a saved seahough pattern"):
        seahough.Pattern.load(tmp_path / "other.npz")
    (tmp_path / "dir.npz").mkdir()
    with pytest.raises(seahough.SeahoughError, match="dir.npz"):
        seahough.Pattern.rectangle(40, 30).save(tmp_path / "dir.npz")
    for folder in (".", "/", tmp_path):     # (a name without one: no ".npz" to add)
        with pytest.raises(seahough.SeahoughError, match="is a folder"):
            seahough.Pattern.load(folder)


def test_a_name_without_npz_loads_what_save_wrote_and_the_command_line_reads_it(tmp_path,
                                                                                  capsys):
    """A Python user's trial: ``save("marker")`` wrote marker.npz, which
    ``load("marker")`` did not find; ``save(folder)`` wrote folder.npz beside
    it; ``seahough detect marker.npz`` took the file for an image."""
    from seahough.cli import main

    pattern = seahough.Pattern.from_image(*S.marker("board", 120))
    assert pattern.save(tmp_path / "marker") == tmp_path / "marker.npz"
    again = seahough.Pattern.load(tmp_path / "marker")
    assert again.kind == pattern.kind and np.array_equal(again.image, pattern.image)
    (tmp_path / "out").mkdir()
    with pytest.raises(seahough.WriteError, match="out: is a folder"):
        pattern.save(tmp_path / "out")
    assert not (tmp_path / "out.npz").exists()
    scene = S.marker_scene("board", seed=3, source="procedural")[0]
    import cv2
    cv2.imwrite(str(tmp_path / "scene.png"), scene)
    with pytest.raises(SystemExit) as ex:
        main(["detect", str(tmp_path / "marker.npz"), str(tmp_path / "scene.png"), "--json"])
    assert ex.value.code == 0
    import json
    got = json.loads(capsys.readouterr().out)["detections"][0]
    want = seahough.Detector(pattern).detect(scene)[0]
    assert (got["x"], got["y"], got["score"]) == (want.x, want.y, want.score)
    with pytest.raises(SystemExit) as ex:
        main(["detect", str(tmp_path / "marker.npz"), str(tmp_path / "scene.png"),
              "--polarity", "either"])
    assert ex.value.code == 2 and "keeps its own polarity" in capsys.readouterr().err


def test_a_dim_pattern_loads_as_it_was_saved(tmp_path):
    # a frame whose grey levels all lie within 0-1 (a very dark frame, made
    # searchable by a low min_gradient): to_gray would take such levels for a
    # 0-1 image and stretch them by 255; a saved pattern comes back as it was
    cfg = seahough.Config(min_gradient=4)
    img = np.zeros((120, 160), np.float32)
    img[30:90, 40:120] = 1.0
    p = seahough.Pattern.__new__(seahough.Pattern)
    p._setup(img, None, None, "bright", "frame", None, True, None, cfg)
    q = seahough.Pattern.load(p.save(tmp_path / "dim.npz"), config=cfg)
    np.testing.assert_array_equal(q._gray, p._gray)
    assert float(q._gray.max()) == 1.0


@pytest.mark.parametrize("damage", ["truncated", "npy", "kind", "line", "outline", "version"])
def test_damaged_pattern_files_are_pattern_errors(tmp_path, damage):
    good = seahough.Pattern.line(120, 8).save(tmp_path / "good.npz")
    bad = tmp_path / "bad.npz"
    if damage == "truncated":
        bad.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    elif damage == "npy":
        with open(bad, "wb") as f:
            np.save(f, np.zeros(3))
    else:
        with np.load(good) as z:
            data = {k: z[k] for k in z.files}
        if damage == "kind":
            data["kind"] = np.array("bogus")
        elif damage == "line":
            del data["line"]
        elif damage == "outline":
            data["n_outline"] = np.array(5)
        elif damage == "version":
            data["version"] = np.array([1, 2])
        np.savez(bad, **data)
    with pytest.raises(seahough.PatternError, match="bad.npz: not a saved seahough pattern"):
        seahough.Pattern.load(bad)


def test_one_detector_shared_by_threads_gives_the_same_answers():
    # nothing of a search is kept on the Detector (nor lost in the pattern's
    # feature cache, filled concurrently from cold here)
    from concurrent.futures import ThreadPoolExecutor
    img, mask = S.marker("board", 120)
    scenes = [S.marker_scene("board", seed=s, source="procedural")[0] for s in range(6)]
    expected = [seahough.Detector(seahough.Pattern.from_image(img, mask=mask)).detect(s)
                for s in scenes]
    shared = seahough.Detector(seahough.Pattern.from_image(img, mask=mask))
    with ThreadPoolExecutor(3) as pool:
        got = list(pool.map(shared.detect, scenes * 2))
    for a, b in zip(expected * 2, got):
        _same_detections(a, b)
