"""Patterns: what to look for, built once and searched for many times.

A pattern is an image of the object (a photo crop, a previous frame, or a
primitive shape rendered anti-aliased) with an origin. Its edges are found by
the same stages as the image's, so both are described the same way.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from . import kernels as K
from ..config import Config
from .._validate import number
from ..errors import ParameterError, PatternError
from .._memo import Memo
from .features import extract_features
from ..io.images import to_gray
from . import pattern_io as _pio
from .keypoints import chain_share, edge_points_near_image, spread_points
from .preprocess import choose_factor
from . import shapes as _shapes

POLARITIES = ("bright", "dark", "either")
#: What a pattern can be (``Pattern.kind``).
KINDS = ("image", "frame", "rectangle", "line", "polygon", "circle", "ring", "ellipse",
         "polyline")
#: Share of an image pattern's edge points on long chains above which it is a
#: shape with borders rather than texture (:meth:`Pattern.has_long_borders`).
LONG_BORDERS = 0.9
#: Primitive shapes are drawn at most this many pixels a side.
MAX_SHAPE_SIDE = 8192
#: ... and at least this many pixels across: anything thinner is drawn alike
#: (a rectangle 1e-9 px wide came out as a line about 1.8 px wide).
MIN_SHAPE_SIZE = 1.0
#: The origin may lie outside the pattern image, by at most this many times
#: the image's longer side.
MAX_ORIGIN_OUTSIDE = 10
_IMAGE_POLARITIES = {"same": "bright", "inverted": "dark", "either": "either",
                     "bright": "bright", "dark": "dark", None: None}


@dataclass
class PatternFeatures:
    """A pattern's points at one working scale, relative to its origin.

    ``x, y, angle, weight`` vote; ``x2, y2`` are the other ends of their
    segments (for equation-5 voting); ``vx, vy, vangle`` are the denser points
    used to score and refine a pose. Units: working pixels at scale 1.
    """

    x: np.ndarray
    y: np.ndarray
    angle: np.ndarray
    weight: np.ndarray
    x2: np.ndarray
    y2: np.ndarray
    vx: np.ndarray
    vy: np.ndarray
    vangle: np.ndarray

    @functools.cached_property
    def radius(self) -> float:
        """Root-mean-square distance of the voting points from the origin."""
        return float(np.sqrt(np.mean(self.x.astype(float) ** 2 + self.y.astype(float) ** 2)))

    @functools.cached_property
    def spacing(self) -> float:
        """Median distance from a scoring point to its nearest neighbour."""
        x, y = self.vx.astype(float), self.vy.astype(float)
        if x.size < 2:
            return 1.0
        # 16 of them: the points are spread evenly, and this runs for
        # every frame pattern of a dead reckoning
        idx = np.arange(0, x.size, max(1, x.size // 16))
        dx, dy = x[idx, None] - x[None, :], y[idx, None] - y[None, :]
        d = dx * dx + dy * dy
        d[np.arange(idx.size), idx] = np.inf
        return float(np.sqrt(np.median(d.min(axis=1))))


def _check_positive(**kw):
    """Sizes of a primitive shape: positive, at least MIN_SHAPE_SIZE and at
    most MAX_SHAPE_SIDE px."""
    for k, v in kw.items():
        if number(k, v, hi=MAX_SHAPE_SIDE) < MIN_SHAPE_SIZE:   # (0 and negatives alike)
            raise ParameterError(f"{k}={v!r}: must be at least {MIN_SHAPE_SIZE:g} px (a shape "
                                 "thinner than a pixel has no two borders to find)")


def _check_polarity(polarity, allowed=POLARITIES):
    if polarity not in allowed:
        raise ParameterError(f"polarity={polarity!r}: must be one of {', '.join(allowed)}")


class Pattern:
    """The object to find.

    Build it with one of the constructors: :meth:`from_image`,
    :meth:`from_frame`, :meth:`rectangle`, :meth:`line`, :meth:`polygon`,
    :meth:`circle`, :meth:`ellipse`, :meth:`polyline`. Then hand it to
    :class:`~seahough.Detector`.

    Attributes
    ----------
    image : ndarray
        The pattern image (uint8 grey); :attr:`Detection.matrix` maps its
        pixels into the searched image. A colour pattern image also keeps
        its colours, whose edges a search in colour uses
        (:meth:`in_colour`).
    painted : bool
        Whether the pattern is painted in colour: a colour image of which
        a fifth of the pixels (of its mask's) at least are as saturated as
        paint (:func:`seahough.core.pattern_io.painted`: an orange or a
        green marker, not a crop of a seabed photo). A painted pattern is
        searched by its colour edges unless ``Config.colour`` says
        otherwise.
    mask : ndarray or None
        Which pattern pixels belong to the object.
    origin : tuple of float
        Pattern origin in pattern-image pixels: what ``Detection.x, y`` report.
    polarity : str
        ``"bright"`` (edges as in the pattern image; for shapes: a bright
        object on a dark background), ``"dark"`` (inverted) or ``"either"``.
    outline : list of ndarray
        Polylines (pattern-image pixels) drawn to show a detection.
    kind : str
        ``"image"``, ``"frame"``, ``"rectangle"``, ``"line"``, ``"polygon"``,
        ``"circle"``, ``"ring"``, ``"ellipse"`` or ``"polyline"``.

    Examples
    --------
    >>> p = Pattern.rectangle(60, 40)
    >>> p.image.shape, p.origin
    ((53, 73), (36.0, 26.0))
    """

    def __init__(self, image, mask=None, origin=None, *, polarity="bright", kind="image",
                 outline=None, closed=True, edge_mask=None, config: Config | None = None):
        gray, colour, alpha, path = _pio.grey_and_colour(
            image, bit_depth=None if config is None else config.bit_depth)
        cut_out = mask is None and kind == "image" and alpha is not None
        if cut_out:
            mask = alpha      # (a cut-out: its transparent pixels are not the object)
        if polarity is None:  # (a cut-out's border is against pixels no one sees: either)
            polarity = "either" if cut_out else "bright"
        try:
            self._setup(gray, mask, origin, polarity, kind, outline, closed, edge_mask, config,
                        colour)
        except PatternError as e:   # (a script making patterns of many files: which one)
            if path is None or str(e).startswith(path):
                raise
            raise PatternError(f"{path}: {e}") from None

    def _setup(self, gray, mask, origin, polarity, kind, outline, closed, edge_mask, config,
               colour=None):
        """Build the pattern from a checked float32 grey image (levels 0-255)
        and, for a colour one, its BGR levels (float32 HxWx3)."""
        if kind not in KINDS:
            raise ParameterError(f"kind={kind!r}: must be one of {', '.join(KINDS)}")
        self._colour = colour
        # (by strips of rows: a 12 MP frame's float temporary would be 46 MB)
        self.image = np.empty(gray.shape, np.uint8)
        for r in range(0, gray.shape[0], 256):
            self.image[r:r + 256] = np.clip(gray[r:r + 256], 0, 255)
        # a frame of whole grey levels (every 8-bit photo) keeps them once, as
        # 8 bits: a 12 MP frame's float copy is 46 MB, held by every keyframe
        whole = kind == "frame" and np.array_equal(self.image, gray)
        if not whole and gray.base is not None:
            gray = gray.copy()   # (a view of the caller's array: to_gray does not copy)
        self._gray_f = None if whole else gray
        h, w = gray.shape
        if mask is not None:
            mask = to_gray(mask, name="pattern mask") > 0
            if mask.shape != gray.shape:
                raise ParameterError(f"the pattern mask is {mask.shape[1]}x{mask.shape[0]} px, the "
                                     f"pattern image {w}x{h} (width x height)")
            if not mask.any():
                raise PatternError("pattern mask is empty: no pixel belongs to the object")
        self.mask = mask
        self.painted = _pio.painted(colour, mask)
        if origin is None:
            origin = ((w - 1) / 2.0, (h - 1) / 2.0)
        try:   # (exactly two numbers: (1, 2, 3) was taken as (1, 2))
            xy = tuple(float(v) for v in origin) if len(origin) == 2 else ()
            origin = (xy[0], xy[1])
        except (TypeError, ValueError, IndexError):
            raise ParameterError(f"origin={origin!r}: must be an (x, y) pair") from None
        lim = MAX_ORIGIN_OUTSIDE * max(h, w)
        if not all(math.isfinite(v) for v in origin) or not (
                -lim <= origin[0] <= w - 1 + lim and -lim <= origin[1] <= h - 1 + lim):
            raise ParameterError(f"origin={origin!r}: must be finite and within "
                                 f"{MAX_ORIGIN_OUTSIDE} pattern sizes of the {w}x{h} pattern image")
        self.origin = origin
        _check_polarity(polarity)
        self.polarity = polarity
        self.kind = kind
        #: A rope, tether or pipe: the position along it is not measured.
        self.is_line = kind == "line"
        #: A whole camera frame: no symmetry, its rivals screened, searched
        #: at a working scale and finished on snapped points.
        self.is_frame = kind == "frame"
        #: A crop of a clear photo, searched through water: blurred first
        #: (Config.pattern_blur).
        self.is_photo = kind == "image"
        if outline is None:
            outline = _pio.outline_from_mask(self.mask, gray.shape)
        self.outline = [np.asarray(o, float).reshape(-1, 2) for o in outline]
        self.closed = closed
        self._edge_mask = edge_mask if edge_mask is not None else (
            None if mask is None else cv2.dilate(mask.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0)
        self._cache = Memo()   # (bounded: one per working scale, which image sizes set)
        # fails now, not at the first search, if it has no edges. A frame is
        # searched at its working scale (only finishing points are needed at
        # full resolution, see finish_points): check it there, at the scale a
        # search of a frame of its own size chooses (as estimate_motion and
        # run_odometry do; another image size or config computes its own)
        self.features(choose_factor(gray.shape, config or Config()) if self.is_frame else 1.0,
                      config)

    # ------------------------------------------------------------ constructors
    @classmethod
    def from_image(cls, image, mask=None, origin=None, *, polarity=None,
                   config: Config | None = None) -> "Pattern":
        """A pattern from a photo of the object (a path or an array).

        Parameters
        ----------
        image : path or ndarray
            The object's picture; grey, BGR or BGRA (searched by its colour
            edges when :attr:`painted` or with ``Config(colour=True)``, by its
            grey ones otherwise: :meth:`in_colour`).
        mask : path or ndarray, optional
            Non-zero on the object's pixels; edges outside it (dilated by two
            pixels, so the object's border counts) are ignored. Default: a
            BGRA image's alpha, when some pixels are transparent (a cut-out).
        origin : (x, y), optional
            Pattern origin in its pixel coordinates; default the image centre.
        polarity : {"same", "inverted", "either"}, optional
            Whether the object appears with the same contrast as in the
            pattern image, inverted, or either way. Default: "same"; for a
            cut-out, "either" (its border's contrast is against the pixels
            under its transparent ones, black often, not against the ground
            it will lie on: a dark object cut out on black was not found).
        config : Config, optional
            The configuration it will be searched with: the pattern must have
            edges under it (an object told from its surroundings by colour
            alone has edges only when searched in colour: :meth:`in_colour`).
        """
        if polarity not in _IMAGE_POLARITIES:
            raise ParameterError(f"polarity={polarity!r}: must be one of same, inverted, either "
                                 "(or bright, dark: same, inverted)")
        return cls(image, mask, origin, polarity=_IMAGE_POLARITIES[polarity], kind="image",
                   config=config)

    @classmethod
    def from_frame(cls, frame, origin=None, *, config: Config | None = None) -> "Pattern":
        """A previous camera frame as the pattern (photo dead reckoning).

        ``config`` is the configuration it will be searched with (its
        features are prepared for it at once).
        """
        return cls(frame, None, origin, polarity="bright", kind="frame", config=config)

    @staticmethod
    def _canvas(w, h, margin):
        number("margin", margin, lo=0.0, hi=1000.0)
        if max(w, h) > MAX_SHAPE_SIDE:
            raise ParameterError(f"shape of {w:g}x{h:g} px: at most {MAX_SHAPE_SIDE} px a side "
                                 "(draw it smaller and search over larger scales)")
        m = int(math.ceil(margin))
        cw, ch = int(math.ceil(w)) + 2 * m + 1, int(math.ceil(h)) + 2 * m + 1
        return np.full((ch, cw), 30, np.uint8), m

    @classmethod
    def _shape(cls, polys, w, h, margin, polarity, kind, outline=None, edge_mask=None,
               closed=True, holes=()):
        img, m = cls._canvas(w, h, margin)
        polys = [np.asarray(p, float) + m for p in polys]
        _shapes.fill(img, polys, 230)
        for hole in holes:
            _shapes.fill(img, [np.asarray(hole, float) + m], 30)
        if outline is None:
            outline = polys + [np.asarray(hh, float) + m for hh in holes]
        else:
            outline = [np.asarray(o, float) + m for o in outline]
        origin = ((img.shape[1] - 1) / 2.0, (img.shape[0] - 1) / 2.0)
        _check_polarity(polarity)
        return cls(img, None, origin, polarity=polarity, kind=kind, outline=outline,
                   edge_mask=edge_mask, closed=closed)

    @classmethod
    def rectangle(cls, width, height, *, polarity="bright", margin=6.0) -> "Pattern":
        """A filled rectangle, ``width`` x ``height`` pixels (the paper's marker).

        ``polarity="bright"`` is a bright rectangle on a darker background.
        """
        _check_positive(width=width, height=height)
        w, h = float(width), float(height)
        poly = [(0, 0), (w, 0), (w, h), (0, h)]
        return cls._shape([poly], w, h, margin, polarity, "rectangle")

    @classmethod
    def polygon(cls, points, *, polarity="bright", margin=6.0) -> "Pattern":
        """A filled polygon given by its vertices [(x1, y1), (x2, y2), ...]."""
        pts = _shapes.vertices(points, MIN_SHAPE_SIZE)
        w, h = pts.max(axis=0)
        return cls._shape([pts], w, h, margin, polarity, "polygon")

    circle = classmethod(_shapes.circle)
    ellipse = classmethod(_shapes.ellipse)
    line = classmethod(_shapes.line)
    polyline = classmethod(_shapes.polyline)

    # ------------------------------------------------------------ description
    @functools.cached_property
    def extent(self) -> float:
        """Size of the object in pattern pixels (diagonal of its outline's box)."""
        pts = np.vstack(self.outline)
        span = pts.max(axis=0) - pts.min(axis=0)
        return float(max(np.hypot(*span), 1.0))

    @functools.cached_property
    def reach(self) -> float:
        """Largest distance (pattern pixels) from the origin to the outline."""
        pts = np.vstack(self.outline) - np.asarray(self.origin)
        return float(max(np.sqrt((pts ** 2).sum(axis=1)).max(), 1.0))

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) of the pattern image."""
        return self.image.shape[1], self.image.shape[0]

    @property
    def either(self) -> bool:
        return self.polarity == "either"

    def features(self, factor: float, config: Config | None = None) -> PatternFeatures:
        """The pattern's voting and scoring points at a working scale (cached)."""
        config = config or Config()   # (two threads may both compute them: the first kept)
        return self._cache.get_or_compute(self._features_key(factor, config),
                                          lambda: self._compute_features(factor, config))

    def _features_key(self, factor: float, config: Config) -> tuple:
        """What :meth:`_compute_features` depends on."""
        return (round(factor, 6), config.n_keypoints, config.n_pattern_points,
                config.n_verify_points, config.min_gradient, config.segment_steps,
                config.segment_angle_tol, config.max_segments, config.equalize,
                config.local_contrast, config.local_window,
                config.photo_blur if self.is_photo else 0.0,
                3 if self.in_colour(config) else 2)

    def grey_levels(self) -> np.ndarray:
        """The grey levels the pattern's edges come from, as it holds them:
        the 8-bit image when that holds them exactly (a frame of whole
        levels: no float copy is made), else float32.

        >>> p = Pattern.from_frame(np.tile(np.arange(64, dtype=np.uint8), (48, 1)) * 3)
        >>> p.grey_levels().dtype
        dtype('uint8')
        """
        g = self.__dict__.get("_gray_f")
        return self.image if g is None else g

    @property
    def _gray(self) -> np.ndarray:
        """The float32 grey levels (made from the 8-bit image when that holds
        them exactly)."""
        g = self.__dict__.get("_gray_f")
        return self.image.astype(np.float32) if g is None else g

    def in_colour(self, config: Config | None = None) -> bool:
        """Whether a search with ``config`` takes its edges from colours:
        ``Config.colour`` when set, else (None, the default) when the
        pattern is :attr:`painted`; never for a grey pattern.

        >>> bgr = np.full((40, 60, 3), 30, np.uint8)
        >>> bgr[10:30, 15:45] = (0, 120, 255)                  # an orange board
        >>> p = Pattern.from_image(bgr)
        >>> p.painted, p.in_colour(), p.in_colour(Config(colour=False))
        (True, True, False)
        >>> Pattern.rectangle(60, 40).in_colour(Config(colour=True))   # no colour in it
        False
        """
        if getattr(self, "_colour", None) is None:
            return False
        colour = (config or Config()).colour
        return bool(self.painted if colour is None else colour)

    def _edges_from(self, config: Config) -> np.ndarray:
        """The image whose edges are the pattern's: its colours with
        ``config.colour`` (when it has any), else its grey levels."""
        return self._colour if self.in_colour(config) else self._gray

    def has_long_borders(self, config: Config | None = None) -> bool:
        """Do the pattern's edges lie on long chains (a shape, a marker) rather
        than texture (a patch of seabed, a camera frame)? Then a search weights
        the image's key points by their edge chains (``Config.chain_length``);
        texture is matched by texture and keeps contrast alone. An image
        pattern has long borders when at least 90 % of its edge points lie on
        chains of ``chain_length`` points or more (markers: 98 %; seabed
        patches: 50-77 %).

        >>> Pattern.rectangle(60, 40).has_long_borders()
        True
        """
        config = config or Config()
        if not self.is_photo:
            return not self.is_frame
        key = ("long borders", config.chain_length, config.min_gradient, self.in_colour(config),
               config.photo_blur, config.equalize)
        return self._cache.get_or_compute(key, lambda: self._long_borders(config))

    def _long_borders(self, config: Config) -> bool:
        """:meth:`has_long_borders` of a photo pattern, computed."""
        img = np.ascontiguousarray(self._edges_from(config), np.float32)
        if config.photo_blur > 0:   # (as its features see it: a crisp staircase is not)
            img = cv2.GaussianBlur(img, (0, 0), config.photo_blur,
                                   borderType=cv2.BORDER_REPLICATE)
        f = extract_features(img, 1.0, config.replace(chain_length=0.0),
                             mask=self._edge_mask)
        share = chain_share(f.edges, max(config.chain_length, 1.0), f.index)
        return share >= LONG_BORDERS

    def near_turns(self, config: Config | None = None) -> tuple:
        """The quarter and half turns that map most, not all, of the pattern's
        edges onto its own (:func:`.symmetry.near_turns`; a marker board's
        frame): ``((theta, cx, cy), ...)`` in radians and full-resolution
        pattern pixels (cached; none for frames and lines)."""
        if self.is_frame or self.is_line:
            return ()
        config = config or Config()
        key = ("near turns",) + self._features_key(1.0, config) + (config.angle_tolerance,)
        return self._cache.get_or_compute(key, lambda: self._near_turns(config))

    def _near_turns(self, config: Config) -> tuple:
        """:meth:`near_turns`, computed."""
        from .symmetry import EXACT, NEAR, pattern_turn_shares
        return tuple((th, cx, cy) for share, th, cx, cy in pattern_turn_shares(self, config)
                     if NEAR <= share < EXACT)

    def finish_points(self, factor: float, config: Config | None = None):
        """``(vx, vy, vangle)``: the points that refine a pose found at working
        scale ``factor`` on the full-resolution image (full-resolution pixels
        relative to the origin; cached).

        These are the verify points of :meth:`features` at scale 1, except for
        frames searched below full resolution: a whole frame's features at
        full resolution cost about as much as the rest of a search, so its
        working-scale verify points are moved onto the full-resolution edge
        point of the same direction within half a working pixel (and half a
        pixel) that is strongest for its distance (points with none are left
        out). Measured on the benchmark's frame pairs as accurate as the full
        features (mean corner error 0.39 against 0.50 px) at a fraction of
        their time. When fewer than half of them find one (a frame faint or
        blurred at full resolution), the full features at scale 1 are used,
        and when those have no edges either, no points (the search then
        keeps its working-scale pose).
        """
        config = config or Config()
        if not self.is_frame or factor >= 0.999:
            f = self.features(1.0, config)
            return f.vx, f.vy, f.vangle
        key = ("finish",) + self._features_key(factor, config) + (config.angle_tolerance,)
        return self._cache.get_or_compute(key, lambda: self._finish_points(factor, config))

    def _finish_points(self, factor: float, config: Config):
        """:meth:`finish_points` of a frame below full resolution, computed."""
        pts = self._snap_to_full(factor, config)
        if pts[0].size < max(8, 0.5 * self.features(factor, config).vx.size):
            try:
                f = self.features(1.0, config)
                pts = (f.vx, f.vy, f.vangle)
            except PatternError:
                pass
        return pts

    def _snap_to_full(self, factor: float, config: Config):
        f = self.features(factor, config)
        ox, oy = self.origin
        x = f.vx.astype(np.float64) / factor + ox  # full-resolution pixels
        y = f.vy.astype(np.float64) / factor + oy
        # half a working pixel (where the coarse edge may lie) and half a pixel
        r = 0.5 / factor + 0.5
        gray = self._edges_from(config)
        gray = 255.0 - gray if self.polarity == "dark" else gray
        edges = edge_points_near_image(np.asarray(gray, np.float32), x, y, r, config.min_gradient,
                                       self._edge_mask, config.equalize)
        f32 = lambda a: np.ascontiguousarray(a, np.float32)
        ids = K.snap_points(x, y, f.vangle.astype(np.float64), edges.x, edges.y, edges.angle,
                            edges.magnitude, edges.index_map(), float(r),
                            math.radians(config.angle_tolerance), self.either, 1.0)
        got = ids >= 0
        return (f32(edges.x[ids[got]] - ox), f32(edges.y[ids[got]] - oy), f32(edges.angle[ids[got]]))

    def _prepared(self, config: Config) -> np.ndarray:
        """The image whose edges are the pattern's features: grey or colour
        (:meth:`_edges_from`), inverted for ``dark`` polarity, blurred for a
        photo crop."""
        gray = self._edges_from(config)
        gray = 255.0 - gray if self.polarity == "dark" else gray
        if self.is_photo and config.photo_blur > 0:
            # a crop of a clear photo, searched through water: its finest
            # texture would not be there to match (Config.pattern_blur)
            gray = cv2.GaussianBlur(np.ascontiguousarray(gray, np.float32), (0, 0),
                                    config.photo_blur, borderType=cv2.BORDER_REPLICATE)
        return gray

    def _compute_features(self, factor: float, config: Config) -> PatternFeatures:
        gray = self._prepared(config)
        em, mask_w = self._edge_mask, None
        if em is not None and factor < 0.999:
            h, w = gray.shape[:2]
            nw, nh = max(int(round(w * factor)), 1), max(int(round(h * factor)), 1)
            mask_w = cv2.resize(em.astype(np.uint8), (nw, nh), interpolation=cv2.INTER_NEAREST) > 0
        elif em is not None:
            mask_w = em
        # the pattern's own edges: the most contrasted, eight times more than
        # it keeps (a small pattern keeps all of them). Fewer (4x-6x) measured
        # as accurate on synthetic pairs and fragments and a little faster,
        # but on the tiled pool sequence they answered wrong pairs with
        # confidence, where 8x declines them.
        n_edges = max(config.n_keypoints, 8 * config.n_verify_points)
        # (all its edges, by contrast: chain_length is for the searched image)
        f = extract_features(gray, factor, config.replace(chain_length=0.0), n_keypoints=n_edges,
                             mask=mask_w)
        seg = f.segments
        if len(seg) < 8:
            raise PatternError(
                f"the pattern has too few edges to be found ({len(seg)} edge segments at "
                f"scale {factor:.2f}; need at least 8): give it more contrast or size")
        g = f.gradients
        # faint texture is not the object's shape: keep the clearly contrasted edges
        strong = seg.magnitude >= 0.2 * np.percentile(seg.magnitude, 90)
        seg = seg.take(strong)
        fx_, fy_ = g.to_full(seg.x, seg.y)
        ox, oy = self.origin
        to_rel = lambda xx, yy: ((np.asarray(xx) - ox) * factor, (np.asarray(yy) - oy) * factor)
        x, y = to_rel(fx_, fy_)
        x2, y2 = to_rel(*g.to_full(seg.x2, seg.y2))
        order = np.argsort(-seg.magnitude, kind="stable")
        vote_ids = spread_points(x, y, order, config.n_pattern_points)
        verify_ids = spread_points(x, y, order, config.n_verify_points)
        w = np.full(vote_ids.size, 1.0 / max(vote_ids.size, 1), np.float32)
        f32 = lambda a: np.ascontiguousarray(a, np.float32)
        return PatternFeatures(
            f32(x[vote_ids]), f32(y[vote_ids]), f32(seg.angle[vote_ids]), w,
            f32(x2[vote_ids]),
            f32(y2[vote_ids]), f32(x[verify_ids]), f32(y[verify_ids]), f32(seg.angle[verify_ids]))

    # ------------------------------------------------------------------ files
    #: Version of the file format written by :meth:`save`.
    FILE_VERSION = _pio.FILE_VERSION

    def save(self, path) -> Path:
        """Write the pattern to ``path`` (a ``.npz`` file, the suffix added
        when the name lacks it; numpy arrays and plain values, no pickled
        code; returns the path written), to be read by :meth:`load` (which
        finds it by either name), ``seahough detect FILE.npz`` and
        searched again without its source image: prepare a model once, use
        it on other machines or in later runs.

        Examples
        --------
        >>> import tempfile, os
        >>> p = Pattern.circle(20, inner_radius=12)
        >>> with tempfile.TemporaryDirectory() as d:
        ...     q = Pattern.load(p.save(os.path.join(d, "ring.npz")))
        >>> q.kind, q.origin == p.origin, bool((q.image == p.image).all())
        ('ring', True, True)
        """
        return _pio.save(self, path)

    @classmethod
    def load(cls, path, *, config: Config | None = None) -> "Pattern":
        """A pattern written by :meth:`save` (see there). ``config``: the
        configuration it will be searched with (a frame's features are
        prepared for it at once, as :meth:`from_frame` does)."""
        return _pio.load(cls, path, config)

    def __repr__(self) -> str:
        h, w = self.image.shape
        return f"Pattern(kind={self.kind!r}, size={w}x{h}, origin={self.origin}, polarity={self.polarity!r})"

