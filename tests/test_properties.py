"""Property-based tests: whatever the image and the parameters, the API
returns a well-formed result or raises one of seahough's documented errors,
never anything else (IndexError, ZeroDivisionError, a Numba or cv2 error...).

Images are drawn as (shape, dtype, channels, content, value range, NaN/inf
sprinkles, seed) and built with numpy from the seed, so that hypothesis
shrinks a failure to a few readable numbers. Runs are derandomized (the same
examples every time); ``SEAHOUGH_HYPOTHESIS_EXAMPLES`` raises the count for
a longer local hunt.

The strategies stay inside the ranges where tests/test_robustness.py has
not already pinned a bug down (float values beyond float32, scales or
search regions that need astronomically large accumulators, rotations far
from 0, numpy scalars as thresholds); see the xfail tests there.
"""

from __future__ import annotations

import math
import os

import cv2
import numpy as np
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from seahough import (Config, Detection, Detector, ImageError, ImageSizeError, ImageValueError,
                      Motion, ParameterError, Pattern, PatternError, estimate_motion, to_gray)
from seahough.core.detector import SEARCH_NOTES
from seahough.io.images import MIN_SIDE
from seahough.motion.pair import MIN_MOTION_SIDE

N = int(os.environ.get("SEAHOUGH_HYPOTHESIS_EXAMPLES", "0"))


def _settings(n: int):
    return settings(max_examples=N or n, deadline=None, derandomize=True, database=None,
                    print_blob=True,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                           HealthCheck.filter_too_much])


DTYPES = ("uint8", "uint16", "int32", "float32", "float64", "bool")
CHANNELS = (None, 1, 3, 4, 2)


# ------------------------------------------------------------------- images
class Img:
    """A drawn image and what to_gray must make of it."""

    def __init__(self, array, spec):
        self.array, self.spec = array, spec
        h, w = array.shape[:2]
        ch = array.shape[2] if array.ndim == 3 else None
        errs = set()
        if ch not in (None, 1, 3, 4):
            errs.add(ImageValueError)
        if min(h, w) < MIN_SIDE:
            errs.add(ImageSizeError)
        if array.dtype.kind == "f" and not np.isfinite(array).all():
            errs.add(ImageValueError)
        self.errors = tuple(errs)      # an error of one of these types is due; none: must work

    def __repr__(self):
        return f"Img({self.spec}, shape={self.array.shape}, dtype={self.array.dtype})"


def _content(kind: str, h: int, w: int, rng) -> np.ndarray:
    """Grey levels in [0, 1], float64."""
    if kind == "uniform" or h * w == 0:
        return np.full((h, w), rng.uniform(), np.float64)
    if kind == "noise":
        return rng.uniform(size=(h, w))
    if kind == "ramp":
        return np.tile(np.linspace(rng.uniform(), rng.uniform(), w), (h, 1))
    img = np.full((h, w), rng.uniform(0, 0.4), np.float64)
    for _ in range(rng.integers(1, 5)):          # filled boxes, discs and a triangle
        c = (int(rng.integers(0, max(w, 1))), int(rng.integers(0, max(h, 1))))
        v = float(rng.uniform(0.5, 1.0))
        r = int(rng.integers(2, max(3, min(h, w) // 2 + 3)))
        what = rng.integers(0, 3)
        if what == 0:
            cv2.rectangle(img, (c[0] - r, c[1] - r // 2), (c[0] + r, c[1] + r // 2), v, -1)
        elif what == 1:
            cv2.circle(img, c, r, v, -1)
        else:
            pts = np.array([c, (c[0] + 2 * r, c[1]), (c[0], c[1] + 2 * r)], np.int32)
            cv2.fillPoly(img, [pts], v)
    if rng.uniform() < 0.5:
        img += rng.normal(0, 0.03, img.shape)
    return np.clip(img, 0, 1)


def _as_dtype(g: np.ndarray, dtype: str, vrange: str) -> np.ndarray:
    if dtype == "bool":
        return g > 0.5
    if dtype == "uint8":
        return np.round(g * 255).astype(np.uint8)
    if dtype == "uint16":
        top = 65535 if vrange != "byte" else 255
        return np.round(g * top).astype(np.uint16)
    if dtype == "int32":
        scale, off = {"unit": (255, 0), "byte": (255, 0), "wide": (2e6, -1e6),
                      "negative": (255, -300)}[vrange]
        return np.round(g * scale + off).astype(np.int32)
    scale, off = {"unit": (1.0, 0.0), "byte": (255.0, 0.0), "wide": (2e4, -1e4),
                  "negative": (255.0, -300.0)}[vrange]
    return (g * scale + off).astype(dtype)


@st.composite
def images(draw, max_side: int = 300, strips: bool = True, channels=CHANNELS, dtypes=DTYPES,
           nonfinite: bool = True, min_side: int = MIN_SIDE, contents=("shapes",) * 4 + ("noise", "uniform", "ramp")):
    """An :class:`Img`; at most one deliberate defect (too small, 2 channels,
    NaN/inf), drawn about one time in four, so that most images get searched."""
    defects = [None] * 9 + ["tiny", "channels"] + (["nonfinite"] if nonfinite else [])
    defect = draw(st.sampled_from(defects))
    layout = draw(st.sampled_from(["box", "box", "box", "thin"] + (["strip"] if strips else [])))
    if defect == "tiny":
        h, w = draw(st.integers(0, MIN_SIDE - 1)), draw(st.integers(0, max_side))
    elif layout == "box":
        h, w = draw(st.integers(min_side, max_side)), draw(st.integers(min_side, max_side))
    elif layout == "thin":                      # at the smallest accepted side
        h, w = draw(st.integers(min_side, min_side + 3)), draw(st.integers(min_side, max_side))
    else:                                       # a long strip
        h, w = draw(st.integers(min_side, min_side + 4)), draw(st.integers(300, 4000))
    if draw(st.booleans()):
        h, w = w, h
    dtype = draw(st.sampled_from(("float32", "float64") if defect == "nonfinite" else dtypes))
    ch = 2 if defect == "channels" else draw(st.sampled_from([c for c in channels if c != 2]))
    content = draw(st.sampled_from(contents))
    vrange = draw(st.sampled_from(["unit", "byte", "byte", "wide", "negative"]))
    bad = draw(st.sampled_from(["nan", "inf", "-inf"])) if defect == "nonfinite" else None
    seed = draw(st.integers(0, 2 ** 16))
    rng = np.random.default_rng(seed)
    g = _as_dtype(_content(content, h, w, rng), dtype, vrange)
    if ch is not None:
        g = np.repeat(g[:, :, None], ch, axis=2)
        if ch >= 3 and content == "shapes":      # colour: the channels differ a little
            g[..., 0] = g[..., 0] // 2 if g.dtype.kind in "ui" else g[..., 0] * 0.5
    if bad is not None and g.size:
        k = int(rng.integers(1, 4))
        idx = tuple(rng.integers(0, s, k) for s in g.shape)
        g[idx] = float(bad)
    if draw(st.booleans()) and g.ndim >= 2 and g.shape[1] > 1:
        g = g[:, ::-1]                          # a non-contiguous view
    return Img(g, dict(defect=defect, layout=layout, h=h, w=w, dtype=dtype, ch=ch,
                       content=content, vrange=vrange, bad=bad, seed=seed))


# --------------------------------------------------------------- parameters
INVALID = "invalid"
finite = dict(allow_nan=False, allow_infinity=False)


@st.composite
def scale_ranges(draw):
    """(value, valid?)"""
    kind = draw(st.sampled_from(["range", "range", "range", "known", "reversed", "nonpositive",
                                 "nonfinite", "malformed", "wide"]))
    if kind == "range":
        lo = draw(st.floats(0.3, 2.0, **finite))
        return (lo, lo * draw(st.floats(1.0, 3.0, **finite))), True
    if kind == "known":
        v = draw(st.floats(0.3, 3.0, **finite))
        return (v, v), True
    if kind == "reversed":
        lo = draw(st.floats(0.3, 2.0, **finite))
        return (lo * 1.5 + 0.01, lo), False
    if kind == "nonpositive":
        return (draw(st.floats(-5.0, 0.0, **finite)), draw(st.floats(0.5, 2.0, **finite))), False
    if kind == "nonfinite":
        bad = draw(st.sampled_from([math.nan, math.inf, -math.inf]))
        return draw(st.sampled_from([(bad, 1.0), (0.5, bad), (bad, bad)])), False
    if kind == "wide":                          # more than 64x
        lo = draw(st.floats(0.001, 0.01, **finite))
        return (lo, lo * draw(st.floats(65.0, 500.0, **finite))), False
    return draw(st.sampled_from([None, "ab", (1.0,), 1.0, ("a", 2.0), [None, None]])), False


@st.composite
def angle_ranges(draw):
    kind = draw(st.sampled_from(["range", "range", "full", "known", "reversed", "nonfinite",
                                 "malformed"]))
    if kind == "range":
        a0 = draw(st.floats(-360.0, 360.0, **finite))
        return (a0, a0 + draw(st.floats(0.0, 400.0, **finite))), True
    if kind == "full":
        return (0.0, 360.0), True
    if kind == "known":
        v = draw(st.floats(-720.0, 720.0, **finite))
        return (v, v), True
    if kind == "reversed":
        a0 = draw(st.floats(-360.0, 360.0, **finite))
        return (a0, a0 - draw(st.floats(0.01, 90.0, **finite))), False
    if kind == "nonfinite":
        bad = draw(st.sampled_from([math.nan, math.inf, -math.inf]))
        return draw(st.sampled_from([(bad, 0.0), (0.0, bad)])), False
    return draw(st.sampled_from([None, "any", (0.0,), 5.0])), False


def unit_or_bad():
    return st.one_of(st.tuples(st.floats(0.0, 1.0, **finite), st.just(True)),
                     st.tuples(st.sampled_from([-0.1, 1.5, 2.0, math.nan, math.inf, "0.5", None]),
                               st.just(False)))


@st.composite
def configs(draw):
    """A valid Config inside sane ranges (the validation itself is tested below)."""
    if draw(st.booleans()):
        return Config()
    kw = {}
    maybe = lambda s: draw(st.one_of(st.none(), s))
    kw["downscale"] = maybe(st.floats(0.2, 1.0, **finite))
    kw["target_size"] = draw(st.integers(32, 800))
    kw["n_keypoints"] = draw(st.integers(1, 3000))
    kw["n_pattern_points"] = draw(st.integers(8, 256))
    kw["n_verify_points"] = draw(st.integers(1, 600))
    kw["min_pattern_size"] = draw(st.floats(1.0, 100.0, **finite))
    kw["min_gradient"] = draw(st.floats(0.0, 120.0, **finite))
    kw["local_contrast"] = draw(st.booleans())
    kw["local_window"] = draw(st.integers(3, 101))
    kw["equalize"] = draw(st.booleans())
    kw["segment_steps"] = draw(st.integers(1, 20))
    kw["segment_angle_tol"] = draw(st.floats(1.0, 90.0, **finite))
    kw["max_segments"] = draw(st.integers(1, 20000))
    kw["voting"] = draw(st.sampled_from(["oriented", "points", "segments"]))
    kw["translation_bin"] = maybe(st.floats(1.0, 10.0, **finite))
    kw["angle_bin"] = maybe(st.floats(1.0, 30.0, **finite))
    kw["scale_step"] = maybe(st.floats(0.02, 0.5, **finite))
    kw["angle_tolerance"] = draw(st.floats(1.0, 90.0, **finite))
    kw["match_radius"] = draw(st.floats(0.5, 5.0, **finite))
    kw["n_candidates"] = draw(st.integers(1, 10))
    kw["refine"] = draw(st.booleans())
    kw["colour"] = draw(st.booleans())
    kw["colour_boost"] = draw(st.floats(1.0, 8.0, **finite))
    return Config(**kw)


_PATTERNS: dict = {}


def _pattern(name: str) -> Pattern:
    if name not in _PATTERNS:
        if name == "image":
            img = np.full((48, 64), 40, np.uint8)
            cv2.rectangle(img, (8, 8), (40, 20), 210, -1)
            cv2.rectangle(img, (8, 8), (20, 40), 210, -1)
            p = Pattern.from_image(img, polarity="either")
        else:
            p = {"rectangle": lambda: Pattern.rectangle(24, 16),
                 "circle": lambda: Pattern.circle(9, polarity="dark"),
                 "ring": lambda: Pattern.circle(12, inner_radius=6),
                 "line": lambda: Pattern.line(60, 5),
                 "polygon": lambda: Pattern.polygon([(0, 0), (30, 4), (8, 26)])}[name]()
        _PATTERNS[name] = p
    return _PATTERNS[name]


PATTERNS = ("rectangle", "circle", "ring", "line", "polygon", "image")


# ---------------------------------------------------------------- checks
def _finite(*vals) -> bool:
    return all(isinstance(v, float) and math.isfinite(v) for v in vals)


def check_detections(found, det: Detector, shape):
    assert isinstance(found, list) and len(found) <= det.max_results
    scores = [d.score for d in found]
    assert scores == sorted(scores, reverse=True), "not best first"
    s0, s1 = det.scale_range
    for d in found:
        assert isinstance(d, Detection)
        assert _finite(d.x, d.y, d.scale, d.angle, d.score, d.confidence), d
        assert 0.0 <= d.score <= 1.0 and 0.0 <= d.confidence <= 1.0, d
        assert d.score >= det.min_score and d.confidence >= det.min_confidence, d
        assert 0.0 <= d.angle <= 360.0, d        # [0, 360): see the xfail in test_robustness
        assert 0.8 * s0 - 1e-9 <= d.scale <= 1.25 * s1 + 1e-9, d
        m = np.asarray(d.matrix)
        assert m.shape == (2, 3) and np.isfinite(m).all(), d
        assert all(np.isfinite(np.asarray(o)).all() for o in d.outline)
        assert isinstance(d.flags, tuple) and all(isinstance(f, str) for f in d.flags)
        if d.kind == "line":
            assert _finite(d.line_angle, d.line_offset) and 0.0 <= d.line_angle < 180.0, d
        else:
            assert d.kind == "object"


def check_motion(m, shape):
    if m is None:
        return
    assert isinstance(m, Motion)
    mat = np.asarray(m.matrix)
    assert mat.shape == (2, 3) and np.isfinite(mat).all()
    assert _finite(m.dx, m.dy, m.angle, m.scale, m.confidence, m.score, m.overlap), m
    assert -180.0 <= m.angle <= 180.0 and m.scale > 0
    for v in (m.confidence, m.score, m.overlap):
        assert 0.0 <= v <= 1.0, m


# ------------------------------------------------------------------ to_gray
@_settings(60)
@given(img=images())
def test_to_gray_returns_finite_grey_or_a_documented_image_error(img):
    try:
        g = to_gray(img.array)
    except ImageError as e:
        assert img.errors, f"refused a good image: {e!r}"
        assert isinstance(e, img.errors), f"{type(e).__name__}: {e}, due {img.errors}"
        return
    assert not img.errors, f"accepted a bad image (due {img.errors})"
    h, w = img.array.shape[:2]
    assert g.shape == (h, w) and g.dtype == np.float32 and g.flags.c_contiguous
    assert np.isfinite(g).all()
    if img.spec["vrange"] in ("unit", "byte") or img.spec["dtype"] in ("uint8", "uint16", "bool"):
        assert g.min() >= -1e-3 and g.max() <= 255.0 + 1e-3


# ------------------------------------------------------------------ Pattern
@_settings(40)
@given(img=images(max_side=120, strips=False),
       polarity=st.sampled_from(["same", "inverted", "either"]),
       with_mask=st.booleans())
def test_pattern_from_any_image_is_usable_or_a_documented_error(img, polarity, with_mask):
    mask = None
    if with_mask and img.array.ndim >= 2:
        h, w = img.array.shape[:2]
        mask = np.zeros((h, w), np.uint8)
        mask[h // 4: max(h // 4 + 1, 3 * h // 4), w // 4: max(w // 4 + 1, 3 * w // 4)] = 1
    try:
        p = Pattern.from_image(img.array, mask=mask, polarity=polarity)
    except PatternError:
        assert not img.errors             # a good image without enough edges
        event("pattern: PatternError")
        return
    except ImageError as e:
        assert img.errors and isinstance(e, img.errors), f"{type(e).__name__}: {e}"
        event(f"pattern: {type(e).__name__}")
        return
    assert not img.errors
    event("pattern: made")
    assert p.image.dtype == np.uint8 and p.image.shape == img.array.shape[:2]
    assert all(map(math.isfinite, p.origin)) and p.extent > 0
    f = p.features(1.0)
    for a in (f.x, f.y, f.angle, f.weight, f.vx, f.vy, f.vangle):
        assert a.size and np.isfinite(a).all()
    # and it can be searched for, in its own image too
    found = Detector(p, scale_range=(0.8, 1.25)).detect(img.array)
    check_detections(found, Detector(p, scale_range=(0.8, 1.25)), img.array.shape)


# ----------------------------------------------------------------- Detector
@st.composite
def detector_params(draw):
    """(keyword arguments, valid?): at most one parameter is drawn bad, one
    time in four."""
    bad = draw(st.sampled_from([None] * 15 + ["scale_range", "angle_range", "max_results",
                                              "min_score", "min_confidence"]))

    def pick(strategy, name):
        while True:      # draw until the value is as good or bad as wanted
            v, ok = draw(strategy)
            if ok == (bad != name):
                return v
    kw = dict(scale_range=pick(scale_ranges(), "scale_range"),
              angle_range=pick(angle_ranges(), "angle_range"),
              max_results=pick(st.one_of(st.tuples(st.integers(1, 6), st.just(True)),
                                         st.tuples(st.sampled_from([0, -1, 2.5, None, True]),
                                                   st.just(False))), "max_results"),
              min_score=pick(unit_or_bad(), "min_score"),
              min_confidence=pick(unit_or_bad(), "min_confidence"))
    if bad is None and draw(st.booleans()):
        kw["min_confidence"] = 0.0          # detections are rarer with a confidence threshold
        kw["min_score"] = min(kw["min_score"], 0.6)
    return kw, bad is None


@_settings(40)
@given(img=images(), pattern=st.sampled_from(PATTERNS), params=detector_params(),
       config=configs())
def test_detect_returns_well_formed_detections_or_a_documented_error(img, pattern, params,
                                                                     config):
    params, valid = params
    try:
        det = Detector(_pattern(pattern), config=config, **params)
    except ParameterError:
        assert not valid, "refused valid parameters"
        event("detect: ParameterError")
        return
    assert valid, f"accepted invalid parameters {params}"
    try:
        res = det.search(img.array)
    except ImageError as e:
        assert img.errors and isinstance(e, img.errors), f"{type(e).__name__}: {e}"
        event(f"detect: {type(e).__name__}")
        return
    except PatternError as e:
        # documented: at the working scale picked for this image (Config.target_size,
        # downscale, min_pattern_size) the pattern may keep too few edges
        assert not img.errors and "too few edges" in str(e)
        event("detect: PatternError")
        return
    assert not img.errors, "searched a bad image"
    event("detect: no edges" if res.note else
          f"detect: {'found' if res.detections else 'nothing found'}")
    check_detections(res.detections, det, img.array.shape)
    assert res.note in SEARCH_NOTES
    if res.note:
        assert res.detections == []


# ---------------------------------------------------------- estimate_motion
@st.composite
def frame_pairs(draw):
    # frames of 8-11 px: see test_motion_on_frames_of_8_to_11_px in test_robustness
    prev = draw(images(max_side=200, strips=False, channels=(None, 3, 4), nonfinite=False,
                       contents=("shapes", "shapes", "noise", "uniform"), min_side=12))
    how = draw(st.sampled_from(["shift", "shift", "same", "other", "resized", "bad"]))
    a = prev.array
    if how == "same":
        cur = a.copy()
    elif how == "shift":
        dx, dy = draw(st.integers(-20, 20)), draw(st.integers(-20, 20))
        cur = np.roll(a, (dy, dx), axis=(0, 1))
    elif how == "other":
        cur = draw(images(max_side=200, strips=False, channels=(None, 3, 4),
                          nonfinite=False, min_side=12)).array
    elif how == "resized":
        cur = a[: max(1, a.shape[0] - draw(st.integers(1, 5)))]
    else:
        cur = a.astype(np.float64)
        if cur.size:
            cur.flat[0] = np.nan
    return prev, cur, how


@_settings(30)
@given(pair=frame_pairs(), sr=scale_ranges(), ar=angle_ranges(),
       max_shift=st.one_of(st.tuples(st.floats(0.05, 1.5, **finite), st.just(True)),
                           st.tuples(st.sampled_from([0.0, -0.5, 2.0, math.nan]),
                                     st.just(False))),
       min_score=unit_or_bad())
def test_estimate_motion_returns_motion_none_or_a_documented_error(pair, sr, ar, max_shift,
                                                                   min_score):
    prev, cur, how = pair
    cur_errors = Img(cur, {}).errors
    kw = dict(scale_range=sr[0], angle_range=ar[0], max_shift=max_shift[0],
              min_score=min_score[0])
    try:
        m = estimate_motion(prev.array, cur, **kw)
    except ParameterError:
        same = cur.shape[:2] == prev.array.shape[:2]
        assert not (sr[1] and ar[1] and max_shift[1] and min_score[1]) or not same, kw
        event("motion: ParameterError")
        return
    except ImageError as e:
        due = prev.errors + cur_errors
        if not due and min(prev.array.shape[:2]) < MIN_MOTION_SIDE:
            due = (ImageSizeError,)   # a frame too small to measure motion in (motion.pair)
        assert due and isinstance(e, due), f"{type(e).__name__}: {e}"
        event(f"motion: {type(e).__name__}")
        return
    except PatternError:
        assert not prev.errors        # the previous frame has too few edges to be followed
        event("motion: PatternError")
        return
    event(f"motion: {'None' if m is None else 'Motion'}")
    assert not prev.errors and not cur_errors and cur.shape[:2] == prev.array.shape[:2]
    check_motion(m, cur.shape)


# ------------------------------------------------------------------- Config
CONFIG_FIELDS = [f for f in Config.__dataclass_fields__]


@_settings(60)
@given(field=st.sampled_from(CONFIG_FIELDS),
       value=st.one_of(st.integers(-10, 10 ** 6), st.floats(allow_nan=True, allow_infinity=True),
                       st.sampled_from([0, 1, -1, 0.5, True, False, 2 ** 40, 1e-300]),
                       st.sampled_from(["oriented", "points", "segments", "hough"])))
def test_config_accepts_or_refuses_with_parameter_error(field, value):
    if isinstance(value, str) and field != "voting":
        return                        # strings in number fields: see the xfail in test_robustness
    try:
        c = Config(**{field: value})
    except ParameterError as e:
        assert f"Config.{field}=" in str(e)
        return
    assert getattr(c, field) == value or (isinstance(value, float) and math.isnan(value))
    assert c.replace() == c


@_settings(25)
@given(config=configs(), img=images(max_side=200, strips=False, channels=(None, 3),
                                      nonfinite=False, dtypes=("uint8", "float32")),
       pattern=st.sampled_from(PATTERNS))
def test_any_valid_config_gives_a_well_formed_search(config, img, pattern):
    det = Detector(_pattern(pattern), config=config, min_score=0.3)
    try:
        res = det.search(img.array)
    except ImageError as e:
        assert img.errors and isinstance(e, img.errors)
        return
    except PatternError as e:            # the pattern, at this working scale (see above)
        assert "too few edges" in str(e)
        return
    check_detections(res.detections, det, img.array.shape)
