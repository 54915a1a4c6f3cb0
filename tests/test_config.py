"""Every number of a search and of the dead reckoning is validated where it is set."""

import dataclasses

import pytest

import seahough
from seahough.config import ODOMETRY_CONFIG, Config, OdometryTuning, SearchTuning
from seahough.errors import ParameterError


@pytest.mark.parametrize("field, value", [("screen", 1.5), ("icp_points", 2.5), ("peak_radius", -1),
                                          ("max_radius", float("nan")), ("overlap", "a lot")])
def test_bad_search_tuning_names_the_field(field, value):
    with pytest.raises(seahough.ParameterError, match=rf"Config\.search\.{field}"):
        SearchTuning(**{field: value})


@pytest.mark.parametrize("field, value", [("min_confidence", 2.0), ("prior_bins", 0),
                                          ("prior_scale", 0.9), ("prior_angle", -1.0),
                                          ("agree_px", float("inf"))])
def test_bad_odometry_tuning_names_the_field(field, value):
    with pytest.raises(seahough.ParameterError, match=rf"OdometryTuning\.{field}"):
        OdometryTuning(**{field: value})


@pytest.mark.parametrize("value", ["x", 1, "True", "auto"])
def test_config_colour_is_true_false_or_none(value):
    assert seahough.Config().colour is None       # colour for a painted pattern, else grey
    assert seahough.Config(colour=True).colour is True
    assert seahough.Config(colour=False).colour is False
    with pytest.raises(seahough.ParameterError, match=r"Config\.colour=.*True or False"):
        seahough.Config(colour=value)


def test_config_search_is_a_search_tuning():
    with pytest.raises(seahough.ParameterError, match="Config.search"):
        seahough.Config(search={"screen": 0.0})


def test_the_tuning_reaches_the_run(tmp_path):
    # a policy that refuses every pair: each frame after the first is flagged,
    # and the summary records the policy that was followed
    from seahough import sim
    frames, _ = sim.sequence(n_frames=4, seed=2, source="procedural")
    strict = OdometryTuning(min_confidence=1.0)
    res = seahough.run_odometry(frames, tmp_path, tuning=strict, progress=False, mosaic=False)
    assert res.summary["measured_pairs"] == 0 and res.summary["flagged_pairs"] == 3
    assert res.summary["settings"]["tuning"] == dataclasses.asdict(strict)
    assert res.summary["settings"]["config"] == dataclasses.asdict(ODOMETRY_CONFIG)
    with pytest.raises(seahough.ParameterError, match="tuning"):
        seahough.run_odometry(frames, tmp_path, tuning={"min_confidence": 1.0}, progress=False)


def test_config_max_memory_mb_reaches_every_reader(tmp_path):
    # a plain 2000x1500 PNG needs far more than 1 MB to read and search: refused
    # from its header by the detector, estimate_motion and the dead reckoning
    import cv2
    import numpy as np
    path = tmp_path / "big.png"
    cv2.imwrite(str(path), np.zeros((1500, 2000), np.uint8))
    small = seahough.Config(max_memory_mb=1)
    with pytest.raises(seahough.ImageSizeError, match="big.png.*max_memory_mb"):
        seahough.Detector(seahough.Pattern.rectangle(40, 30), config=small).detect(path)
    with pytest.raises(seahough.ImageSizeError, match="big.png.*max_memory_mb"):
        seahough.estimate_motion(path, path, config=small)
    res = seahough.run_odometry([path, path], tmp_path / "o", config=small, progress=False,
                                mosaic=False)
    assert all("max_memory_mb" in r["flags"] for r in res.rows)
    with pytest.raises(seahough.ParameterError, match="max_memory_mb"):
        seahough.Config(max_memory_mb=0)


def test_smooth_is_a_sigma_that_photo_patterns_share():
    import math

    from seahough.errors import ParameterError

    assert Config().smooth == 0.0 and Config().photo_blur == Config().pattern_blur
    assert math.isclose(Config(smooth=2.0).photo_blur, math.hypot(1.0, 2.0))
    for bad in (-1.0, float("nan"), 1000.0):
        with pytest.raises(ParameterError, match="smooth"):
            Config(smooth=bad)


@pytest.mark.parametrize("bad", ["0,0,10,10", [(0, 0, 10)], [(5, 0, 2, 10)], [(0, -1, 10, 10)],
                                 [(0, 0, float("nan"), 10)], [("a", 0, 1, 1)], 3])
def test_ignore_refuses_what_is_not_boxes_by_name(bad):
    with pytest.raises(ParameterError, match="Config.ignore"):
        Config(ignore=bad)


def test_ignore_is_kept_as_whole_pixel_boxes_and_recorded_only_when_set():
    from seahough.config import config_record
    c = Config(ignore=[[10, 20.4, 30, 40]])
    assert c.ignore == ((10, 20, 30, 40),) and hash(c) == hash(Config(ignore=((10, 20, 30, 40),)))
    assert config_record(c)["ignore"] == [[10, 20, 30, 40]]
    assert "ignore" not in config_record(Config())


def test_an_unknown_keyword_is_a_parameter_error_naming_it():
    """A user's trial: Config(bogus=1) raised a TypeError; the constructors
    of Config, SearchTuning and OdometryTuning now say which name is not one
    of theirs, as Config.replace did."""
    import inspect

    for cls in (seahough.Config, seahough.SearchTuning, seahough.OdometryTuning):
        with pytest.raises(seahough.ParameterError, match=f"{cls.__name__} has no parameter 'bogus'"):
            cls(bogus=1)
        with pytest.raises(TypeError):      # (what Python raised: except TypeError still works)
            cls(bogus=1)
        assert "bogus" not in inspect.signature(cls).parameters and cls() == cls()
    assert seahough.Config(smooth=2.0).smooth == 2.0          # (known names as before)
