"""The search: image -> features -> votes -> candidates -> detections.

:class:`Detector` holds a prepared pattern and the search ranges (create it
once, search many images); each call to :meth:`Detector.search` runs the
stages, each in its own module: :mod:`.features`, :mod:`.accumulator`,
:mod:`.candidates`, :mod:`.ranking`. Nothing of one search is kept on the
Detector, so one Detector can be shared by threads.
"""

from __future__ import annotations

import copy
import math
import os
import time
from collections.abc import Mapping
from dataclasses import dataclass, field

from ..config import Config
from .._memo import Memo
from .._validate import check_max_nfa, number
from ..errors import ParameterError, PatternError
from ..io.images import read_image, to_image
from .accumulator import (AccumulatorPlanes, accumulate, check_ranges, edge_gap, make_bins,
                          planes)
from .candidates import PoseComparison, SearchContext, find_candidates
from .features import Features, extract_features
from .pattern import Pattern
from .blanks import Blanks, find_blanks
from .preprocess import MIN_BAND_PX, choose_factor, factor_hint, prepare_image
from .ranking import (FLAG_ALONG_LINE, FLAG_AMBIGUOUS, FLAG_GREY, FLAG_OUTSIDE_RANGE,
                      FLAG_PARTIAL, FLAG_RANGE_EDGE, Detection, confidence, line_parameters, rank)

__all__ = ["Detector", "SearchResult", "SEARCH_NOTES", "Detection", "confidence",
           "line_parameters", "FLAG_ALONG_LINE", "FLAG_AMBIGUOUS", "FLAG_OUTSIDE_RANGE",
           "FLAG_RANGE_EDGE", "FLAG_PARTIAL", "FLAG_GREY"]

#: A texture pattern small in a large image: the key points taken put this
#: many times its own voting points on its area (``Detector._n_keypoints``)
#: ... (0.5 of 128 voting points until ``Config.n_pattern_points`` became 256:
#: 0.25 of them takes as many key points as before, and the voting cost doubles
#: rather than quadruples; a Config with 128 of them takes half as many).
TEXTURE_DENSITY = 0.25
#: ... up to this many (the voting cost grows with them), whenever the default
#: puts fewer there; MIN_ON_PATTERN, if set, only under that many (16 until
#: 2026-12-07: a 96 px patch of a 384x288 frame, 25 there, was missed in that
#: very frame; bench/bench_small_patch.py's medium patches, fragments 94 -> 98 %).
MAX_KEYPOINTS = 20_000
MIN_ON_PATTERN: int | None = None
#: A search for more than 5 results takes this many key points for each (the
#: default's 1,200 are 240 for each of 5), up to :data:`MAX_KEYPOINTS`, unless
#: its Config sets ``n_keypoints``: a seabed's texture holds most of the
#: strongest edges, and with 1,200 the fainter of 20-60 rings or squares drawn
#: on it had none (a scientist counting tags: 31 of 60 found, no word). Chosen
#: on two seabed photos, recall and time: bench/bench_counting.py, docs/counting.md.
KEYPOINTS_PER_RESULT = 240
#: Why a search ended early with no detections ("" when it ran to the end).
SEARCH_NOTES = ("", "no edges", "pattern larger than the image",
                "search_region is outside the image")


@dataclass(eq=False)
class SearchResult:
    """Everything one search produced: the detections and how it got there.

    ``note`` says why a search stopped before voting (its detections are
    then empty): one of :data:`SEARCH_NOTES`; ``planes`` and ``features``
    may then be None. ``candidates`` are the refined candidate poses
    (:class:`~.candidates.Candidate`: ``pose``, ``score``, ``nfa``) in the
    order of their working-scale score (the full-resolution finish, which
    ranks the detections, may order them otherwise), at most
    ``Config.n_candidates`` (7; ``max_results + 2`` when more; over 5
    results, every seed's) per pattern; one not reported says why in its
    ``declined`` ("NFA 1.08 over max_nfa 1"; a disc's pose for a ring: "its
    hole is not in the image"). An object in view that is no candidate had
    too few votes (``Config(n_candidates=30)`` may bring it in). Of several
    patterns, ``parts`` holds each one's result by name (``planes`` and
    ``features``: the best detection's pattern's, else the first's;
    ``planes.pattern`` names it).
    ``blanks`` is what was filled in the image before the search
    (:class:`~.blanks.Blanks`: letterbox border, burned-in captions,
    ``Config.ignore``'s regions, no data beyond the picture); None when
    searched as given (features given, a frame pattern).
    """

    detections: list
    planes: AccumulatorPlanes | None
    features: Features | None
    factor: float
    candidates: list
    timings: dict             # seconds, by stage
    note: str = ""
    parts: dict = field(default_factory=dict)
    blanks: Blanks | None = None

    @property
    def left_out(self) -> int:
        """Candidates over ``min_score`` left out by ``max_results``: more objects may be there."""
        return sum(1 for c in self.candidates if c.declined.startswith("max_results"))


#: An image with fewer edge segments than this at the working scale has no
#: edges to search (``SearchResult.note`` "no edges").
MIN_SEGMENTS = 4
#: Config's own number of key points: another one is a user's choice
#: (:meth:`Detector._n_keypoints` keeps it).
_DEFAULT_KEYPOINTS = Config().n_keypoints
_DEFAULT_2D = Config().n_keypoints_2d
#: Detector's own number of results (:data:`KEYPOINTS_PER_RESULT` above it).
_DEFAULT_RESULTS = 5

class Detector:
    """Find a pattern at unknown position, scale and rotation.

    Create it once per pattern and search range, then call :meth:`detect`
    on as many images as needed.

    Parameters
    ----------
    pattern : Pattern, or dict or list of Pattern or Detector
        What to look for. Several patterns (a dict name -> pattern, or a
        list, named ``"0"``, ``"1"``, ...) are searched in each image with
        the image's features computed once; each :class:`Detection` names
        its pattern (``d.pattern``), and they come strongest evidence first
        (lowest NFA). A pattern given as a :class:`Detector` keeps its own
        ranges and thresholds (its Config must be the same as the others');
        a plain Pattern takes this Detector's. ``max_results`` is per
        pattern.
    scale_range : (float, float)
        Smallest and largest size relative to the pattern. Equal values mean
        a known scale.
    angle_range : (float, float)
        Rotations to search, degrees (counter-clockwise as displayed). Equal
        values mean a known rotation; the default is any rotation.
    config : Config, optional
        Tuning of every stage.
    max_results : int
        At most this many detections. Each detection's confidence is
        measured against the best candidate left out (docs/method.md), so
        it depends on this number: with two buoys in view and
        ``max_results=1``, the one reported is measured against the other
        (``ambiguous`` when that one is as good); ask for as many as there
        may be objects. Over 5, the search takes more key points (240 for
        each result, up to 20,000, unless ``Config.n_keypoints`` is set), so
        that each object may have its own: counting 60 rings on a seabed
        photo found 31 with 1,200.
    min_score : float
        A detection must have at least this share of the pattern's edges (of
        those in view when ``partly_outside_image``: its ``score`` is of all).
    min_confidence : float
        ... and at least this confidence.
    max_nfa : float
        ... and a number of false alarms (:attr:`Detection.nfa`) of at most
        this: the expected number of chance detections per image that the
        caller accepts (1.0: one in an image at most, on average).
    search_region : (x0, y0, x1, y1), optional
        Where the pattern origin may lie, in full-resolution image pixels.
        Default: the image, plus a margin of a tenth of the pattern's size.

    Examples
    --------
    >>> import numpy as np, cv2
    >>> img = np.full((240, 320), 40, np.uint8)
    >>> box = cv2.boxPoints(((200.0, 110.0), (90.0, 60.0), -30.0))  # a 90 x 60 box
    >>> _ = cv2.fillPoly(img, [np.round(box).astype(np.int32)], 220)
    >>> found = Detector(Pattern.rectangle(60, 40)).detect(img)
    >>> d = found[0]
    >>> round(d.x), round(d.y), round(d.scale, 1), round(d.angle), d.flags   # (the same at 210)
    (200, 110, 1.5, 30, ('same_turned_180',))
    """

    def __init__(self, pattern, scale_range=(0.5, 2.0), angle_range=(0.0, 360.0), *,
                 config: Config | None = None, max_results: int = 5, min_score: float = 0.5,
                 min_confidence: float = 0.0, max_nfa: float = 1.0, search_region=None):
        self.parts: dict = {}
        if not isinstance(pattern, Pattern):
            items = _named_items(pattern)
            kw = dict(config=config, max_results=max_results, min_score=min_score,
                      min_confidence=min_confidence, max_nfa=max_nfa, search_region=search_region)
            self.parts = {name: _part(name, item, scale_range, angle_range, kw)
                          for name, item in items}
            pattern = next(iter(self.parts.values())).pattern
        self.pattern = pattern
        (self.scale_range, self.angle_range) = check_ranges(scale_range, angle_range)
        self.config = Config() if config is None else config
        if not isinstance(self.config, Config):
            raise ParameterError("config must be a seahough.Config")
        # Config.colour None: in colour when painted, a marker (long borders) at either polarity
        # (the ground decides), a photo's crop at its own; a grey image: grey edges (self._grey)
        self._grey = None
        auto = self.config.colour is None and not self.parts
        if auto:
            self.config = self.config.replace(colour=pattern.in_colour(self.config))
        self.max_results = int(number("max_results", max_results, lo=1, integer=True))
        self._counting, self._line_extent = self.max_results > _DEFAULT_RESULTS, True  # (see rank)
        self.min_score = number("min_score", min_score, lo=0.0, hi=1.0)
        self.min_confidence = number("min_confidence", min_confidence, lo=0.0, hi=1.0)
        self.max_nfa = check_max_nfa(max_nfa)
        if search_region is not None:
            try:
                sr = tuple(float(v) for v in search_region)
            except (TypeError, ValueError):
                sr = ()
            if len(sr) != 4 or not all(map(math.isfinite, sr)) or sr[2] <= sr[0] or sr[3] <= sr[1]:
                raise ParameterError(f"search_region={search_region!r}: expected (x0, y0, x1, y1) "
                                     "with x1 > x0 and y1 > y0")
            search_region = sr
        self.search_region = search_region
        self._gaps = Memo()   # working scale -> the pattern's edge gap (see _edge_gap)
        if auto and self.config.colour:
            self._grey = copy.copy(self)
            self._grey.config = self.config.replace(colour=False)
            self._grey._gaps = Memo()
            if pattern.polarity != "either" and pattern.has_long_borders(self.config):
                self.pattern = copy.copy(pattern)
                self.pattern.polarity, self.pattern._cache = "either", Memo()
        if self.parts:   # one Config for all: they share the image's features
            ref = self.config if config is not None else next(iter(self.parts.values())).config
            # (but for colour: each pattern is searched in the image it needs)
            if any(d.config.replace(colour=None) != ref.replace(colour=None)
                   for d in self.parts.values()):
                raise ParameterError("config: the patterns of one Detector share the image's "
                                     "features, so their Detectors must have the same Config "
                                     "(but for colour)")
            colours = {d.config.colour for d in self.parts.values()}
            self.config = ref.replace(colour=colours.pop() if len(colours) == 1 else None)

    def detect(self, image) -> list:
        """Detections of the pattern in ``image`` (path or array), best first.

        An empty list means the pattern was not found.
        """
        return self.search(image).detections

    def search(self, image, features: Features | None = None, *,
               name: str | None = None) -> SearchResult:
        """Like :meth:`detect`, also returning the accumulator planes, all
        scored candidates and the stage timings.

        ``features`` may pass the image's already computed features (from a
        previous search at the same working scale), e.g. in dead reckoning.
        ``name``: what a warning about the image calls it (default: its path, or "image").
        """
        cfg = self.config
        t0 = time.perf_counter()
        if self.parts:
            return self._search_parts(image, features, t0, name)
        label = name or (str(image) if isinstance(image, (str, os.PathLike)) else "image")
        if self._grey is not None and isinstance(image, (str, os.PathLike)):
            # (decoded once: a colour search that finds nothing is done again in grey)
            image = read_image(image, max_pixels=cfg.max_pixels, max_memory_mb=cfg.max_memory_mb)
        gray = to_image(image, cfg.colour, name=label, max_pixels=cfg.max_pixels,
                        max_memory_mb=cfg.max_memory_mb, bit_depth=cfg.bit_depth)
        blanks = None
        if features is None and not self.pattern.is_frame:
            # (given features: the caller prepared the image; a frame pattern, in
            # photo motion, is matched to the next frame as both come)
            blanks = find_blanks(gray, cfg.ignore)
            gray = prepare_image(gray, cfg, blanks)
        if self._grey is not None and gray.ndim == 2:
            res = self._grey._search_in_grey(gray, features, t0)
        else:
            res = self._search_pattern(gray, features, t0)
            if self._grey is not None and not res.detections and features is None:
                res = self._grey_after_colour(image, label, res, t0)
        res.blanks = blanks
        return res

    def _grey_after_colour(self, image, label: str, res: SearchResult,
                           t0: float) -> SearchResult:
        """A painted pattern's colour search (``Config.colour`` None) that
        found nothing, searched again by its grey edges in the grey image:
        a crop of a real video frame is painted (saturated water, a green
        buoy), and the video's colour edges (chroma subsampled, compressed)
        may not show it where its grey ones do. The grey search's number of
        false alarms counts both searches (its candidates', its detections',
        and ``max_nfa`` is judged on them); its detections are flagged
        :data:`~.ranking.FLAG_GREY`. Nothing found this way either: the
        colour search's result, with the grey search's candidates after its
        own (their reasons)."""
        if res.note and res.note != "no edges":    # (the pattern larger than the image...)
            return res
        cfg = self.config
        # (the grey image as a grey search makes it: the image's grey levels, then
        # prepared; half a level of rounding moved NFAs 8-fold)
        gray = prepare_image(to_image(image, False, name=label, max_pixels=cfg.max_pixels,
                                      max_memory_mb=cfg.max_memory_mb, bit_depth=cfg.bit_depth),
                             cfg)
        try:
            alt = self._grey._search_pattern(gray, None, t0, searches=2)
        except PatternError:                       # (no grey edges in the pattern)
            return res
        if not alt.detections:
            res.candidates = list(res.candidates) + list(alt.candidates)
            return res
        for d in alt.detections:
            d.flags = tuple(d.flags) + (FLAG_GREY,)
        return alt

    def _search_in_grey(self, gray, features, t0, name: str = "", factor=None) -> SearchResult:
        """The search of a painted pattern's grey twin in a grey image: a
        pattern told from its ground by colour alone has no grey edges, and
        the image no colour to find it by: not found, and said."""
        try:
            return self._search_pattern(gray, features, t0, name, factor)
        except PatternError as e:   # (the reason kept: it is what the note says)
            return SearchResult([], None, features, 1.0 if factor is None else factor, [],
                                {"total": time.perf_counter() - t0},
                                note=f"grey image, pattern edges in colour only: {e}")

    def _search_pattern(self, gray, features: Features | None, t0: float,
                        name: str = "", factor: float | None = None,
                        searches: int = 1) -> SearchResult:
        """The search of this Detector's one pattern in a working image
        (``features`` and their ``factor`` given: already computed)."""
        cfg = self.config
        timings = {}
        p = self.pattern
        s0, s1 = self.scale_range
        angles = self._angles()
        # a pattern more than twice the image's diagonal at every searched scale is
        # not there (up to that, an object larger than the frame may be partly in
        # view: it is searched); larger scales than that are not searched (they
        # would only size the accumulator)
        fit = 2.0 * math.hypot(*gray.shape[:2]) / p.extent
        s1 = min(s1, max(fit, s0))
        if factor is None:
            factor = (features.gradients.factor if features is not None
                      else self.working_factor(gray.shape))
        if features is None:
            features = extract_features(gray, factor, self._features_config(),
                                        n_keypoints=self._n_keypoints(gray.shape, factor),
                                        weigh_colours=True)
        t1 = time.perf_counter()
        timings["features"] = t1 - t0
        if len(features.segments) < MIN_SEGMENTS:
            return SearchResult([], None, features, factor, [], timings, note="no edges")
        if s0 > fit:
            return SearchResult([], None, features, factor, [], timings,
                                note="pattern larger than the image")
        try:
            pf = p.features(factor, cfg)
        except PatternError as e:   # (a large image brought down: the pattern with it)
            raise PatternError(f"{e}{factor_hint(gray.shape, factor, cfg, s0)}") from None
        region = self._region(features, factor, s1)
        if region is None:
            return SearchResult([], None, features, factor, [], timings,
                                note="search_region is outside the image")
        bins = make_bins(pf, (s0, s1), angles, region, cfg, self._edge_gap(pf, factor))
        votes = accumulate(pf, features.segments, bins, p.either)
        t2 = time.perf_counter()
        timings["voting"] = t2 - t1
        ctx = SearchContext(p, pf, features, bins, factor, cfg, self.scale_range,
                            angles, self.max_results, self.min_score,
                            PoseComparison(p, pf, bins.step, self.scale_range,
                                           angles, cfg.search.overlap),
                            self.max_nfa, self._counted_angles(angles), searches,
                            self._counting, self._line_extent)
        cands = find_candidates(ctx, votes)
        t3 = time.perf_counter()
        timings["peaks_refine"] = t3 - t2
        dets = rank(ctx, cands, gray, self.min_confidence)
        for d in dets:
            d.pattern = name
        timings["full_resolution"] = time.perf_counter() - t3
        timings["total"] = time.perf_counter() - t0
        return SearchResult(dets, planes(votes, bins, features.gradients), features, factor,
                            cands, timings)

    def working_factor(self, shape) -> float:
        """The downscale factor of a search of an image of ``shape``
        (:func:`~.preprocess.choose_factor`: the pattern at its smallest
        scale kept large enough). A line whose band at its smallest scale
        is under :data:`~.preprocess.MIN_BAND_PX` across in an image brought
        down more than 4 times, or has no edges left at all (its two borders
        merged: a 690 x 33 px post in a 4000 px photo was an error, "0 edge
        segments"), is searched where the band keeps that much."""
        p, cfg, s0 = self.pattern, self.config, self.scale_range[0]
        f = choose_factor(shape, cfg, p.extent, s0)
        if p.is_line and cfg.downscale is None:
            # (else only with no edges at all: thin ropes in 640 px images as before)
            thin = f < 0.25 and p.line_width * s0 * f < MIN_BAND_PX
            if not thin:
                try:
                    p.features(f, cfg)
                except PatternError:
                    thin = True
            if thin:
                f = max(f, choose_factor(shape, cfg, p.extent, s0, band_width=p.line_width))
        return f

    def _edge_gap(self, pf, factor: float) -> float | None:
        """The pattern's :func:`.accumulator.edge_gap` at working scale
        ``factor`` (its features ``pf``) when it is drawn with borders (a
        shape, a marker: judged at the default chain length, also when the
        search's is 0), else None (a texture, a line). Kept per scale: the
        pattern does not change between searches."""
        p, cfg = self.pattern, self.config

        def gap():
            drawn = not p.is_line and p.has_long_borders(
                cfg if cfg.chain_length > 0 else cfg.replace(chain_length=Config().chain_length))
            return edge_gap(pf, p.either) if drawn else None
        return self._gaps.get_or_compute(factor, gap)

    def _features_config(self) -> Config:
        """The Config of the image's features: key points weighted by their
        edge chains for a pattern with long borders (a shape, a marker), by
        contrast alone for texture (a seabed patch, a frame)."""
        cfg = self.config
        if cfg.chain_length > 0 and not self.pattern.has_long_borders(cfg):
            return cfg.replace(chain_length=0.0)
        return cfg

    def _n_keypoints(self, shape=None, factor: float | None = None) -> int | None:
        """How many key points a search of an image of ``shape`` at working
        scale ``factor`` takes (None: the Config's default).

        The key points are the image's most contrasted edge points, so a
        texture pattern (a seabed patch) that covers a small share of a large
        image gets few of them: a 96 px patch in a 1280x720 frame about 12
        of the 1,200, and it was found 1 time in 6. Such a search takes
        enough for :data:`TEXTURE_DENSITY` times the pattern's own points to
        fall on its area, at most :data:`MAX_KEYPOINTS`, when the default
        would put fewer there (shapes keep the
        default: their borders are among the most contrasted edges). A
        Config whose ``n_keypoints`` is not the default's is the user's
        choice, and is kept (a texture patch found less often, faster).
        A search asked for more than 5 results takes
        :data:`KEYPOINTS_PER_RESULT` for each (many objects to count).
        """
        cfg, p = self.config, self.pattern
        many = None     # (many results asked for: key points for each, KEYPOINTS_PER_RESULT)
        if self._counting and cfg.n_keypoints == _DEFAULT_KEYPOINTS \
                and not p.is_frame:
            many = int(min(MAX_KEYPOINTS, KEYPOINTS_PER_RESULT * self.max_results))
        n = cfg.n_keypoints_2d
        a0, a1 = self._angles()
        known = self.scale_range[0] == self.scale_range[1] and a0 == a1
        if known and n is not None:   # (a Config's own 2-D count is the user's choice)
            return n if many is None or n != _DEFAULT_2D else max(n, many)
        if shape is None or factor is None or p.is_frame or p.is_line or not p.is_photo \
                or cfg.n_keypoints != _DEFAULT_KEYPOINTS or p.has_long_borders(cfg):
            return many
        ph, pw = p.image.shape[:2]
        h, w = shape[:2]
        share = (pw * ph * self.scale_range[0] ** 2) / float(w * h)
        if MIN_ON_PATTERN is not None and cfg.n_keypoints * share >= MIN_ON_PATTERN:
            return None
        want = TEXTURE_DENSITY * cfg.n_pattern_points / max(share, 1e-9)
        if want <= cfg.n_keypoints:
            return many
        return int(min(max(want, many or 0), MAX_KEYPOINTS))

    def _angles(self) -> tuple:
        """The rotations searched: a disc or a ring looks the same at every
        rotation, so it is searched at one (its detections report the range's
        first angle; the fast path of a known rotation), and a line the same
        turned by 180 degrees, so at most half a turn of it is searched."""
        a0, a1 = self.angle_range
        if self.pattern.kind in ("circle", "ring"):
            return (a0, a0)
        if self.pattern.is_line and a1 - a0 > 180.0:   # a band turned by 180 degrees is itself
            return (a0, a0 + 180.0)
        return (a0, a1)

    def _counted_angles(self, searched: tuple) -> tuple | None:
        """The rotations the number of false alarms counts, when not those
        searched: those asked for; a disc's or a ring's a whole turn whatever
        was asked (its every rotation is one pose, searched once: its NFA
        must not depend on the angle range; a user trial found a disc 370
        times stronger at ``angle_range=(0, 0)``)."""
        a0, a1 = self.angle_range
        if self.pattern.kind in ("circle", "ring"):
            return (a0, a0 + 360.0)
        return self.angle_range if searched != self.angle_range else None

    def _search_parts(self, image, features: Features | None, t0: float,
                      name: str | None = None) -> SearchResult:
        """Every pattern searched in one image. The image's features are
        computed once per working scale (patterns of similar size share
        one) and per kind of edges (grey, colour: each pattern's own
        ``Config.colour``), so each pattern finds what it would find
        searched alone (but a painted pattern whose colour search finds
        nothing is not searched again by its grey edges, as alone it is)."""
        cfg = self.config
        parts = self.parts
        kinds = sorted({bool(d.config.colour) for d in parts.values()})
        label = name or (str(image) if isinstance(image, (str, os.PathLike)) else "image")
        if len(kinds) > 1 and isinstance(image, (str, os.PathLike)):   # (decoded once)
            image = read_image(image, max_pixels=cfg.max_pixels, max_memory_mb=cfg.max_memory_mb)
        images = {c: to_image(image, c, name=label, max_pixels=cfg.max_pixels,
                              max_memory_mb=cfg.max_memory_mb, bit_depth=cfg.bit_depth)
                  for c in kinds}
        blanks = None
        if features is None:
            # (the grey and the colour copy filled alike: as the grey one's blanks)
            blanks = find_blanks(images[min(images)], cfg.ignore)
            images = {c: prepare_image(img, cfg, blanks) for c, img in images.items()}
        # each pattern, and the image it is searched in (a grey image has no colour
        # to see: a painted pattern's grey edges then, as searched alone)
        work = {}
        for name, d in parts.items():
            img = images[bool(d.config.colour)]
            work[name] = (d._grey if d._grey is not None and img.ndim == 2 else d, img)
        if features is not None and len({img.ndim for _, img in work.values()}) > 1:
            raise ParameterError("features: this Detector's patterns are searched in a grey and "
                                 "a colour image, so one set of features cannot serve them all")
        shared = {}
        keys = {}
        for name, (d, gray) in work.items():
            if features is not None:
                keys[name] = None
                shared[None] = features
                continue
            fcfg = d._features_config()
            f = d.working_factor(gray.shape)
            key = (f, d._n_keypoints(gray.shape, f), fcfg.chain_length, gray.ndim)
            keys[name] = key
            if key not in shared:
                shared[key] = extract_features(gray, key[0], fcfg, n_keypoints=key[1],
                                               weigh_colours=True)
        t1 = time.perf_counter()
        results = {name: (d._search_in_grey if d is not parts[name] else d._search_pattern)(
                       gray, shared[keys[name]], time.perf_counter(), name,
                       None if keys[name] is None else keys[name][0])
                   for name, (d, gray) in work.items()}
        timings = {"features": t1 - t0}
        for r in results.values():
            for k, v in r.timings.items():
                if k not in ("features", "total"):
                    timings[k] = timings.get(k, 0.0) + v
        timings["total"] = time.perf_counter() - t0
        # the NFA means the same thing for every pattern: the strongest evidence first
        dets = sorted((d for r in results.values() for d in r.detections),
                      key=lambda d: (d.nfa if math.isfinite(d.nfa) else math.inf, -d.score))
        for name, r in results.items():
            if r.planes is not None:
                r.planes.pattern = name
            for c in r.candidates:
                c.pattern = name
        # the planes and features shown: the best detection's pattern's (else the first's)
        first = results[dets[0].pattern] if dets else next(iter(results.values()))
        notes = {r.note for r in results.values()}
        note = "" if "" in notes else first.note
        return SearchResult(dets, first.planes, first.features, first.factor,
                            [c for r in results.values() for c in r.candidates], timings,
                            note, results, blanks)

    def _region(self, features: Features, factor: float, s1: float):
        """Where the pattern origin may lie, (x0, y0, x1, y1) in working
        pixels, or None when the search region misses the image."""
        p = self.pattern
        g = features.gradients
        h, w = features.shape
        if self.search_region is not None:
            # the origin cannot lie farther out than the pattern reaches
            m = p.reach * s1 * factor + 2.0
            x0, y0 = g.to_work(self.search_region[0], self.search_region[1])
            x1, y1 = g.to_work(self.search_region[2], self.search_region[3])
            x0, y0 = max(x0, -m), max(y0, -m)
            x1, y1 = min(x1, w - 1 + m), min(y1, h - 1 + m)
            if x1 <= x0 or y1 <= y0:
                return None
        else:
            m = 0.1 * p.extent * s1 * factor
            x0, y0, x1, y1 = -m, -m, w - 1 + m, h - 1 + m
        return (float(x0), float(y0), float(x1), float(y1))


def _named_items(patterns) -> list:
    """``(name, Pattern or Detector)`` pairs of a mapping, or of a list
    (named by position: ``"0"``, ``"1"``, ...)."""
    if isinstance(patterns, Mapping):
        items = [(k, v) for k, v in patterns.items()]
        bad = [k for k, _ in items if not isinstance(k, str) or not k]
        if bad:
            raise ParameterError(f"pattern names must be non-empty strings, got {bad[0]!r}")
    elif isinstance(patterns, (list, tuple)):
        items = [(str(i), v) for i, v in enumerate(patterns)]
    else:
        raise ParameterError("pattern must be a seahough.Pattern, or a dict or list of them, "
                             f"got {type(patterns).__name__}")
    if not items:
        raise ParameterError("pattern: no patterns given")
    return items


def _part(name: str, item, scale_range, angle_range, kw: dict) -> "Detector":
    """The Detector of one named pattern of a multi-pattern Detector."""
    if isinstance(item, Detector):
        if item.parts:
            raise ParameterError(f"pattern {name!r}: a Detector of several patterns cannot be "
                                 "one pattern of another")
        return item
    if not isinstance(item, Pattern):
        raise ParameterError(f"pattern {name!r}: expected a seahough.Pattern or Detector, got "
                             f"{type(item).__name__}")
    return Detector(item, scale_range, angle_range, **kw)
