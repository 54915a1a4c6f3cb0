"""All tuning parameters of the pipeline, on one documented object."""

from __future__ import annotations

import dataclasses
import inspect
import math
from dataclasses import dataclass

import numpy as np

from ._validate import check_max_nfa, number
from .errors import ParameterError

#: Largest Config.local_window (working pixels).
MAX_WINDOW = 1001

VOTING_MODES = ("oriented", "points", "segments")

#: Default of Config.max_memory_mb and of read_image's limit (MB).
MAX_MEMORY_MB = 4096.0


def _check_fields(obj, prefix: str, *, shares=(), counts=(), pixels=(), min_count: int = 0):
    """ParameterError naming ``prefix.field`` for a share outside [0, 1], a
    count that is not a whole number >= ``min_count``, or a size in pixels
    outside [0, 1000]."""
    for name in shares:
        number(f"{prefix}.{name}", getattr(obj, name), lo=0.0, hi=1.0)
    for name in counts:
        number(f"{prefix}.{name}", getattr(obj, name), lo=min_count, hi=100_000, integer=True)
    for name in pixels:
        number(f"{prefix}.{name}", getattr(obj, name), lo=0.0, hi=1000.0)


class UnknownParameter(ParameterError, TypeError):
    """A keyword a constructor does not take: a ParameterError, and the
    TypeError Python gives for it (``except TypeError`` keeps working)."""


def _named(cls):
    """A dataclass whose constructor refuses an unknown keyword with a
    ParameterError naming it (a TypeError before: a user's trial)."""
    init = cls.__init__
    names = {f.name for f in dataclasses.fields(cls)}

    def __init__(self, *args, **kw):
        unknown = [k for k in kw if k not in names]
        if unknown:
            raise UnknownParameter(f"{cls.__name__} has no parameter {unknown[0]!r} (its "
                                 f"parameters: help(seahough.{cls.__name__}))")
        init(self, *args, **kw)

    __init__.__doc__, __init__.__signature__ = init.__doc__, inspect.signature(init)
    cls.__init__ = __init__
    return cls


@_named
@dataclass(frozen=True)
class SearchTuning:
    """Fixed choices of the candidate and ranking stages (``Config.search``).

    Measured values, kept together so that a search's every number lives on
    :class:`Config`; ``docs/method.md`` says how each was chosen. Change them
    to experiment, not to tune a data set.

    Parameters
    ----------
    peak_radius : int
        Largest radius (translation bins) of a local maximum of the dx-dy plane.
    overlap : float
        Two detections are one object when the smaller one's footprint lies
        more than this share inside the other's.
    good_fit : float
        A candidate refined from its best scale seed that scores this much is
        not tried from its second seed.
    full_treatment : int
        The first this many candidates get a short ICP from each scale seed.
    icp_points : int
        Pattern points the candidate ICPs iterate on (all score at the end).
    icp_iterations : int
        Iterations of each stage of a candidate's main ICP (the short ICPs
        that pick a scale seed run 3).
    max_radius : float
        Largest first match radius of a candidate ICP (working px).
    look_radius : float
        Match radius of the single pass that orders the seeds (working px).
    top_votes : int
        The strongest accumulator peaks, refined first whatever their look.
    neighbour_seeds : int
        Peaks whose 5x5 neighbourhood is searched for a second seed (a
        self-similar shape's smaller copy in its own corner).
    screen : float
        A whole frame's rival whose first short ICP fits below this share of
        the best candidate so far is scored there and not refined further
        (only its scale seeds are screened: a tile-shifted look-alike on the
        pool, 0.51 against 0.78 refined, was found only from its second scale).
    min_finish_points : int
        Fewer full-resolution finishing points than this: the working-scale
        pose is the answer (a frame too faint or blurred at full resolution).
    band_slack : float
        How far (px) the full-resolution refinement may move the pose beyond
        its first match radius, when its edges are limited to a band.
    hole_support : float
        A pattern with a hole (a ring's inner circle) is not reported where
        the hole's points match less than this share of what the whole
        pattern matches (a disc is not a ring: :mod:`seahough.core.parts`);
        0: not checked.

    Examples
    --------
    >>> Config(search=SearchTuning(screen=0.0)).search.screen
    0.0
    """

    peak_radius: int = 1
    overlap: float = 0.3
    good_fit: float = 0.7
    full_treatment: int = 4
    icp_points: int = 100
    icp_iterations: int = 4
    max_radius: float = 6.0
    look_radius: float = 3.0
    top_votes: int = 3
    neighbour_seeds: int = 6
    screen: float = 0.5
    min_finish_points: int = 8
    band_slack: float = 2.0
    hole_support: float = 0.4

    def __post_init__(self) -> None:
        _check_fields(self, "Config.search", shares=("overlap", "good_fit", "screen",
                                                     "hole_support"),
                      counts=("full_treatment", "top_votes", "neighbour_seeds",
                              "min_finish_points"),
                      pixels=("max_radius", "look_radius", "band_slack"))
        _check_fields(self, "Config.search", counts=("peak_radius", "icp_points",
                                                     "icp_iterations"), min_count=1)


@_named
@dataclass(frozen=True)
class Config:
    """Parameters of every stage, with defaults that suit 640x480 photos.

    Parameters
    ----------
    downscale : float or None
        Factor applied to the frame before anything else (0 < f <= 1).
        ``None`` picks it from ``target_size``, raised when needed so that the
        pattern at the smallest searched scale keeps ``min_pattern_size`` px.
    target_size : int
        Longest side of the working image when ``downscale`` is None.
    n_keypoints : int
        N, the number of most contrasted edge points kept in the image
        (the paper uses 1000-2000; 1200 measured as accurate as 1500 on the
        benchmark's markers, and faster).
    n_keypoints_2d : int or None
        N in the paper's 2-D case, when scale and rotation are both known:
        each pair then votes for a single cell, so fewer key points give as
        sharp a peak (800 measured as accurate as 1200 on the benchmark's
        markers, and 10 % faster). None: ``n_keypoints``.
    n_pattern_points : int
        Key points kept on the pattern for voting (the paper: about 100).
        256: on the coloured markers' tune part (bench_colour.py), searched
        grey, 128 found 332 of 576, 192 363, 256 364, 384 380; the right
        pose was more often among the accumulator's peaks. Voting costs
        in proportion to it.
    n_verify_points : int
        Pattern edge points used to score and refine a candidate pose.
    min_pattern_size : float
        Smallest pattern extent, in working pixels, at the smallest scale.
    min_gradient : float
        Gradient magnitude (Scharr units; a step of 1 grey level gives 16)
        below which a pixel is never an edge point.
    local_contrast : bool
        Rank edge points by their gradient relative to the mean gradient of
        their neighbourhood (a window of ``local_window`` working pixels)
        rather than by the raw gradient, so that the key points are spread
        over the frame instead of piling up on the few strongest edges (dark
        rocks, the lit centre of a strobe) and faint objects on smooth sand
        keep theirs.
    local_window : int
        Side of that window, working pixels (3 to 1001; odd or even).
    chain_length : float
        Favour key points on long coherent borders over texture: an edge
        point's rank is multiplied by ``min(1, L / chain_length)``, where L
        is the number of edge points of its chain (8-neighbours whose edge
        directions differ by at most 30 degrees). An object's border is one
        long chain; algae, shells and sand ripples break into short ones.
        0 turns it off (rank by contrast alone). 8, chosen on the tune part
        of ``bench/bench_keypoints.py`` (docs/keypoints.md), puts 10-40 %
        more key points on markers' borders in hard water. Dead reckoning's
        configurations keep 0: a frame pair matches the seabed's texture.
    equalize : bool
        Apply CLAHE (local contrast equalisation) before the gradients; helps
        with uneven strobe light and haze (a colour image: each channel).
    colour : bool or None
        Edges from every channel of a colour (BGR or BGRA) image and pattern:
        the Di Zenzo colour gradient (the largest eigenvalue of the channels'
        structure tensor and its direction, ``docs/method.md``, "Colour
        edges"), so that an object differing from its background in hue
        rather than brightness (an orange marker on green sand, once the
        water has taken the red) still has a border. Grey images, and colour
        ones whose channels are all equal, are searched as before (the same
        results, bit for bit). Camera frames in dead reckoning stay grey.
        None (the default): in colour when the pattern is painted in colour
        (:attr:`Pattern.painted <seahough.Pattern.painted>`: an orange or a
        green marker; not a grey pattern, a shape or a crop of a seabed
        photo), then at either polarity (a colour edge's sign depends on
        the ground) and, in a grey image, by the pattern's grey edges (in a
        colour image too when its colour search finds nothing: a crop of a
        real video frame is painted, and the video's coarser colour may not
        show it where its grey does; such detections are flagged
        ``found_in_grey``, their NFA doubled for the two searches); in grey
        otherwise (:meth:`seahough.Pattern.in_colour`). A Detector of
        several patterns decides for each (without that second search).
    colour_boost : float
        With ``colour``: the searched image's channels are weighed by its
        own gradient statistics (:func:`seahough.core.preprocess.colour_metric`):
        the direction in colour space along which the image changes most
        (on a seabed, brightness: its texture) keeps its units, the others
        are amplified to the same spread, by at most this gain. An edge that
        changes colour where the texture changes brightness (a painted
        marker that the water has made as grey as the sand) then counts as
        much as the texture's strongest edges. 1 turns it off (plain Di
        Zenzo). 4, chosen on the tune part of ``bench/bench_colour.py``
        (docs/colour.md): 82 -> 90 % of coloured markers found there, false
        alarms 0.014 -> 0.002 per search (3: 89 %, 6: 90 %). Patterns'
        edges are measured as they are.
    pattern_blur : float
        Gaussian sigma (pattern-image pixels) applied to an image pattern
        (:meth:`Pattern.from_image`) before its edges are found. Such a
        pattern is usually cut from a clear photo while the searched view
        comes through water (blur, scatter, resampling): fine texture that
        the view cannot show would count against a true match. 1.0 measured
        best on the fragment benchmark (80 % found at 0, 96 % at 1.0); 0
        turns it off. Shapes and previous frames (which pass through the
        same water as the searched image) are never blurred.
    smooth : float
        Gaussian sigma (image pixels) applied to a searched image before
        its edges are found: speckle (sonar), grain, marine snow that makes
        edges of its own. 0 (the default): none. A pattern cut from such an
        image (:meth:`Pattern.from_image`) gets it too, on top of
        ``pattern_blur`` (their root sum of squares: :attr:`photo_blur`).
        Photo motion (a frame matched to the next) does not use it.
    ignore : tuple of (x0, y0, x1, y1)
        Regions of every searched image not to search (image pixels, end
        exclusive; clipped to each image): the vehicle's own parts in view
        (a manipulator, a skid), an overlay's fixed readouts, a
        picture-in-picture inset. Each is filled from the picture around
        it before the edges are found (its edges, and an object under it,
        are not seen). Default: none. Photo motion does not use it, nor a
        search given its features (the caller prepared the image).
    segment_steps : int
        How many pixels a segment is traced along the edge on each side of
        its key point.
    segment_angle_tol : float
        Largest change of gradient direction (degrees) between neighbouring
        points of one segment.
    max_segments : int
        At most this many image segments vote.
    voting : str
        ``"oriented"`` (default): each pattern point / image segment pair
        takes its rotation from the difference of their edge directions and
        votes over a small cycle of scales. ``"points"``: the paper's point
        voting with cycles over scale and rotation, pairs pruned by gradient
        direction. ``"segments"``: segment pairs solved directly with
        equation 5. See ``docs/method.md`` for the measurements.
    translation_bin, angle_bin, scale_step : float or None
        Accumulator bin sizes (working px, at least 0.25; degrees, at least
        0.1; log-scale step, at least 0.001). ``None`` derives them from the
        pattern's size. A search whose bins, ranges and counts would make
        the accumulator too large or the voting too long (over the limits of
        :mod:`seahough.core.accumulator`: about 10 s on a 640x480 photo) is
        refused with a ParameterError naming the fields to change.
    angle_tolerance : float
        Largest difference (degrees) between an image edge direction and the
        rotated pattern edge direction for a pair to vote when the rotation is
        known, and for a pattern point to count as found.
    match_radius : float
        A pattern edge point counts as found when an image edge point lies
        within this distance (full-resolution px) after refinement.
    n_candidates : int
        Accumulator peaks examined (scored and refined) per search; when a
        Detector asks for more results than this, ``max_results + 2``. The
        confidence is measured against the best of the others, so fewer
        peaks make it too high on look-alikes (see ``docs/method.md``).
    refine : bool
        Refine poses below one accumulator bin by least squares on the matched
        edge points (point-to-edge distances), finishing at full resolution.
    max_pixels : int
        Images with more pixels are refused (decompression-bomb guard).
    max_memory_mb : float
        Image files whose reading and search would need more memory than
        this (MB, as :func:`seahough.io.images.memory_needed` models it from
        the header) are refused before decoding.
    bit_depth : int or None
        Significant bits of 16-bit images (9-16): a camera that stores 10-
        or 12-bit samples in 16-bit files gives values up to 1023 or 4095,
        which read as 16-bit data are 64 or 16 times too dark to show edges
        (levels are divided by ``(2**bit_depth - 1) / 255``; values beyond
        ``2**bit_depth - 1`` are clipped, or the image is refused,
        ImageValueError, when they are more than 1 % of it: wider samples). None: 16 bits. Images of other types are not
        affected. Fixed for a whole run, so that every frame is read alike.
    search : SearchTuning
        Fixed choices of the candidate and ranking stages.
    """

    downscale: float | None = None
    target_size: int = 320
    n_keypoints: int = 1200
    n_keypoints_2d: int | None = 800
    n_pattern_points: int = 256
    n_verify_points: int = 400
    min_pattern_size: float = 24.0
    min_gradient: float = 48.0
    local_contrast: bool = True
    local_window: int = 31
    chain_length: float = 8.0
    equalize: bool = False
    colour: bool | None = None
    colour_boost: float = 4.0
    pattern_blur: float = 1.0
    smooth: float = 0.0
    segment_steps: int = 2
    segment_angle_tol: float = 30.0
    max_segments: int = 10000
    voting: str = "oriented"
    translation_bin: float | None = None
    angle_bin: float | None = None
    scale_step: float | None = None
    angle_tolerance: float = 15.0
    match_radius: float = 1.5
    n_candidates: int = 7
    refine: bool = True
    max_pixels: int = 200_000_000
    max_memory_mb: float = MAX_MEMORY_MB
    bit_depth: int | None = None
    search: SearchTuning = SearchTuning()
    ignore: tuple = ()      # (last: added after the others, their order kept)

    def __post_init__(self) -> None:
        def check(name, **limits):
            try:
                number(f"Config.{name}", getattr(self, name), **limits)
            except ParameterError as e:
                raise ParameterError(str(e)) from None

        if self.downscale is not None:
            check("downscale", lo=0.0, lo_open=True, hi=1.0)
        for name in ("n_keypoints", "n_verify_points", "max_segments", "max_pixels"):
            check(name, lo=1, integer=True)
        if self.n_keypoints_2d is not None:
            check("n_keypoints_2d", lo=1, integer=True)
        check("target_size", lo=32, hi=100_000, integer=True)
        check("max_memory_mb", lo=0.0, lo_open=True)
        check("n_pattern_points", lo=8, hi=100_000, integer=True)
        check("n_candidates", lo=1, hi=1000, integer=True)
        check("local_window", lo=3, hi=MAX_WINDOW, integer=True)
        check("segment_steps", lo=1, hi=20, integer=True)
        check("min_pattern_size", lo=1.0, hi=10_000.0)
        check("match_radius", lo=0.0, lo_open=True, hi=100.0)
        check("min_gradient", lo=0.0)
        check("pattern_blur", lo=0.0, hi=100.0)
        check("smooth", lo=0.0, hi=100.0)
        object.__setattr__(self, "ignore", _boxes("ignore", self.ignore))
        check("colour_boost", lo=1.0, hi=100.0)
        check("chain_length", lo=0.0, hi=10_000.0)
        for name in ("segment_angle_tol", "angle_tolerance"):
            check(name, lo=0.0, lo_open=True, hi=90.0)
        for name in ("local_contrast", "equalize", "refine", "colour"):
            v = getattr(self, name)
            if not isinstance(v, (bool, np.bool_)) and not (name == "colour" and v is None):
                raise ParameterError(f"Config.{name}={v!r}: must be True or False"
                                     + (" (or None: colour for a painted pattern)"
                                        if name == "colour" else ""))
        if self.bit_depth is not None:
            check("bit_depth", lo=9, hi=16, integer=True)
        if not isinstance(self.search, SearchTuning):
            raise ParameterError(f"Config.search={self.search!r}: must be a "
                                 "seahough.config.SearchTuning")
        if self.voting not in VOTING_MODES:
            raise ParameterError(f"Config.voting={self.voting!r}: must be one of "
                                 f"{', '.join(VOTING_MODES)}")
        # bins finer than these would size the accumulator without bound
        if self.translation_bin is not None:
            check("translation_bin", lo=0.25, hi=1000.0)
        if self.angle_bin is not None:
            check("angle_bin", lo=0.1, hi=360.0)
        if self.scale_step is not None:
            check("scale_step", lo=0.001, hi=1.0)

    @property
    def photo_blur(self) -> float:
        """The Gaussian sigma a photo pattern is blurred by: ``pattern_blur``
        and ``smooth`` (root sum of squares)."""
        return math.hypot(self.pattern_blur, self.smooth)

    def replace(self, **changes) -> "Config":
        """A copy with some fields changed (validated again)."""
        names = {f.name for f in dataclasses.fields(self)}
        for k in changes:
            if k not in names:
                raise ParameterError(f"Config has no parameter {k!r}")
        return dataclasses.replace(self, **changes)


#: the largest coordinate of a box of ``Config.ignore`` (beyond any image)
MAX_COORD = 1_000_000


def _boxes(name: str, value) -> tuple:
    """``Config.ignore``'s boxes as a tuple of (x0, y0, x1, y1) whole
    pixels, or a ParameterError that names it.

    >>> _boxes("ignore", [(10, 20.5, 30.4, 40)])
    ((10, 20, 31, 40),)
    """
    bad = ParameterError(f"Config.{name}={value!r}: must be boxes (x0, y0, x1, y1) in image "
                         f"pixels, 0 <= x0 < x1 <= {MAX_COORD:,} and 0 <= y0 < y1 <= {MAX_COORD:,}")
    if isinstance(value, (str, bytes, dict)):
        raise bad
    out = []
    try:
        for b in value:
            if isinstance(b, (str, bytes)) or len(b) != 4:
                raise bad
            v = [float(c) for c in b]
            if not all(math.isfinite(c) for c in v):
                raise bad
            # (whole pixels that cover it: a part-covered pixel is left out too)
            x0, y0 = math.floor(v[0]), math.floor(v[1])
            x1, y1 = math.ceil(v[2]), math.ceil(v[3])
            if not (0 <= x0 < x1 <= MAX_COORD and 0 <= y0 < y1 <= MAX_COORD):
                raise bad
            out.append((x0, y0, x1, y1))
    except (TypeError, ValueError, OverflowError):
        raise bad from None
    return tuple(out)


def config_record(config: Config) -> dict:
    """``config`` as plain values for a run's settings (what resuming a run
    compares). Fields added after runs were made are left out while unset
    or at their default (``bit_depth`` None, ``search.hole_support`` 0.4,
    ``smooth`` 0, ``ignore`` none), so
    that those runs can still be continued.

    >>> "bit_depth" in config_record(Config()), config_record(Config(bit_depth=12))["bit_depth"]
    (False, 12)
    >>> "hole_support" in config_record(Config())["search"]
    False
    >>> "smooth" in config_record(Config()), config_record(Config(smooth=2.0))["smooth"]
    (False, 2.0)
    """
    rec = dataclasses.asdict(config)
    if rec.get("bit_depth") in (None, 16):    # (16 bits: read as unset)
        rec.pop("bit_depth", None)
    if rec["search"].get("hole_support") == SearchTuning.hole_support:
        rec["search"].pop("hole_support")
    if rec.get("smooth") == 0.0:
        rec.pop("smooth")
    if rec.get("ignore") == ():
        rec.pop("ignore")
    elif "ignore" in rec:                         # (as JSON keeps it: lists)
        rec["ignore"] = [list(b) for b in rec["ignore"]]
    return rec


#: The configuration :func:`~seahough.estimate_motion` uses unless given one:
#: more pattern points, since a whole frame has far more edges than a marker.
#: (Fewer candidates, 4 instead of 7, measured as accurate on synthetic pairs
#: and faster, but on a real Sparus pair one frame apart the true peak was not
#: among them and a wrong motion came back at confidence 0.17, where 7 declines
#: the pair.)
MOTION_CONFIG = Config(n_pattern_points=256, n_verify_points=600, target_size=320,
                       chain_length=0.0)   # (a frame pair matches the seabed's texture)

#: The configuration :func:`~seahough.run_odometry` uses unless given one: the
#: motion configuration with 128 voting and 400 scoring pattern points (fewer
#: than estimate_motion's: a keyframe is searched many times, from a
#: prediction; the default Config's until it took 256 voting points), and
#: its seven accumulator peaks per full search (two in the small prior
#: window, :attr:`OdometryTuning.prior_candidates`). Three peaks
#: per full search accepted tile-shifted look-alikes on the tiled pool
#: sequence (40 px jumps at confidence 0.28-0.32) that seven flag as low
#: confidence.
ODOMETRY_CONFIG = MOTION_CONFIG.replace(n_pattern_points=128, n_verify_points=400)


@_named
@dataclass(frozen=True)
class OdometryTuning:
    """The keyframe, prior and fallback policy of :func:`~seahough.run_odometry`.

    Parameters
    ----------
    min_confidence : float
        Below it a pair is not measured (``low_confidence``).
    min_relative : float
        ... nor when its edges in view match less than this share as well as
        in the last measured frames (median of up to 5: a frame of somewhere
        else, a fish, a cloud of silt).
    min_score : float
        Share of the reference frame's edges that must be found again.
    min_overlap : float
        Share of the reference frame that must still be in view.
    rekey_overlap : float
        The next frame predicted to overlap the keyframe less than this: the
        current frame becomes the keyframe ...
    rekey_match : float
        ... or when the keyframe's edges in view are found less than this
        share as often as at its first measurement (the scene's look changed).
    prior_radius : float
        Half-size of the prior window, share of the frame's longer side ...
    prior_bins : int
        ... and at least this many translation bins.
    prior_angle : float
        Rotation window around the prediction, +- degrees.
    prior_scale : float
        Scale window around the prediction, x/÷ this.
    prior_candidates : int
        Accumulator peaks examined in the prior window.
    full_shift : float
        Full search: +- this share of the frame around the last position ...
    max_span : int
        ... and the ranges widened for at most this many frames of gap.
    doubtful : float
        A keyframe measurement less confident than this (or found without
        the prior: it failed, or there was none) is checked against the
        last measured frame (nearer in time) ...
    agree_px : float
        ... which replaces it when they differ by more than this many working
        pixels at the frame's corners (beyond a measurement's noise) and it
        is the adjacent frame, or more confident.
    max_nfa : float
        A measurement whose number of false alarms (:attr:`Motion.nfa`) is
        over this is no match (flagged ``no_match``); ``math.inf``, the
        default: not judged. Real pairs measure at 1e-30 and far below;
        frames enlarged into a blur (a small photo simulated over a long
        path) at up to 1e7 for half their pairs, but there the steps over 1
        were as often right as wrong (40 frames of a procedural photo
        magnified 5.7x: 16 steps over 1, all within 3 px of the truth;
        a 300-frame turn magnified 6.5x: steps 1.16x too long, flagged at
        1, its end point then farther off), so it is a choice, not a
        default.

    Examples
    --------
    >>> OdometryTuning().prior_angle
    4.0
    """

    min_confidence: float = 0.2
    min_relative: float = 0.4
    min_score: float = 0.2
    min_overlap: float = 0.15
    rekey_overlap: float = 0.6
    rekey_match: float = 0.6
    prior_radius: float = 0.05
    prior_bins: int = 3
    prior_angle: float = 4.0
    prior_scale: float = 1.03
    prior_candidates: int = 2
    full_shift: float = 0.5
    max_span: int = 3
    doubtful: float = 0.35
    agree_px: float = 2.0
    max_nfa: float = math.inf

    def __post_init__(self) -> None:
        try:
            check_max_nfa(self.max_nfa)
        except ParameterError as e:
            raise ParameterError(f"OdometryTuning.{e}") from None
        _check_fields(self, "OdometryTuning",
                      shares=("min_confidence", "min_relative", "min_score", "min_overlap",
                              "rekey_overlap", "rekey_match", "prior_radius", "full_shift",
                              "doubtful"),
                      counts=("prior_bins", "prior_candidates", "max_span"),
                      pixels=("agree_px",), min_count=1)
        number("OdometryTuning.prior_angle", self.prior_angle, lo=0.0, hi=180.0)
        number("OdometryTuning.prior_scale", self.prior_scale, lo=1.0, hi=10.0)
