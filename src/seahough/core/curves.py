"""Curved ropes and cables: a chain of short straight pieces, reported as a polyline.

A rope, tether, cable or pipe lying on the seabed bends. A long
:meth:`Pattern.line <seahough.Pattern.line>` fits only where it is straight;
a short piece of it, ``piece_length`` px long, fits wherever the rope's
radius of curvature is a few times that length. :func:`find_curves` finds a
curve with the ordinary search of a line pattern (:class:`~seahough.Detector`:
segment voting, peaks, refinement, the a-contrario decision; no new voting is
written here), in two stages:

1. **Seed.** A piece twice as long (stronger evidence, which a search of the
   whole image needs) is searched at any position and rotation and at the
   widths of ``width_range`` (the pattern's scale); when that finds no
   curve, the piece itself is, on the same features (a tight bend of a
   thick rope). Each accepted line detection is a seed: its refined pose
   says where along its line it fitted (the detection's own ``x, y`` is only
   the line's point nearest the image centre). The seed is moved onto the
   middle between the rope's two borders, found on its grey-level profile
   across (whose width, measured along the curve, is ``Curve.width``).
2. **Follow.** From the seed the rope is followed both ways. Each step
   searches the piece at the predicted point, half a piece ahead, within a
   small ``search_region`` and a narrow ``angle_range`` (the current
   direction, ``max_turn`` either side), at the seed's width (scale known;
   a band's scale is loosely fixed by its refinement, since its length is
   not seen, but it is the width its edges show at the working scale);
   where that finds nothing, a piece twice as long (a faint but straight
   stretch). The found piece's centre line, at its point nearest the
   prediction, moved to the middle between the borders there (a straight
   piece is a chord of a bend), is the polyline's next point, and its
   direction the new direction; where the profile shows no rope there (a
   piece that fits with its back half, beyond the rope's end), the step
   failed. After a miss, one to three steps further are tried (a stretch
   buried in silt, or one too faint or too bent for a piece: the polyline
   crosses it on a cubic through the two ends and their directions, flagged
   ``gap_bridged``, whatever the reason was). The following ends where
   that fails too, or where the rope leaves the image; each end is then
   carried on along the rope, a few pixels at a time, for as long as its two
   borders are still seen, at most half a piece.

The image's features (edge points, segments) are computed once, by the
first seed search, and handed to every other search; the steps of a curve
share its two piece patterns, whose voting points are prepared once (cached
per working scale): a step costs only its small vote, refinement and finish.

Evidence. Each piece is a detection with its own number of false alarms
(:attr:`Detection.nfa <seahough.Detection.nfa>`), counted over the poses its
own search tried. The seed's search tried every position, rotation and width
in the image, so its NFA is the curve's: the number of chance curves a
search of an image like this one is expected to report (a curve exists only
if its seed passes ``nfa <= max_nfa``; the chances of the two seed searches
add up, so the curve's NFA is its seed's times 2). A continuation piece is
accepted when its NFA, counted over its own small search, is at most
``max_nfa * STEP_NFA_SHARE``: the expected
number of chance pieces added to a curve is at most that per search tried
(``Curve.steps``). The curve's NFA does not grow with its continuations:
they extend a curve and cannot create one. ``Curve.piece_nfa`` keeps them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import cv2
import numpy as np

from .._validate import _a_list, check_max_nfa, number, pair
from .._values import ValueEquality
from ..config import Config
from ..errors import ParameterError
from ..geometry import clip_polyline_ends
from ..io.images import to_gray
from .detector import FLAG_AMBIGUOUS, Detection, Detector
from .pattern import Pattern
from .preprocess import prepare_image

__all__ = ["Curve", "find_curves", "FLAG_LEAVES_IMAGE", "FLAG_GAP", "FLAG_MAX_PIECES",
           "STEP_NFA_SHARE"]

#: Flag: an end of the curve is where the rope leaves the image.
FLAG_LEAVES_IMAGE = "leaves_image"
#: Flag: the curve crosses a stretch where no piece was found (buried,
#: hidden): the polyline is interpolated there.
FLAG_GAP = "gap_bridged"
#: Flag: the following stopped at the most pieces allowed, not at an end.
FLAG_MAX_PIECES = "max_pieces_reached"
#: A continuation piece is accepted when its NFA is at most this share of ``max_nfa``.
STEP_NFA_SHARE = 0.01

_MAX_PIECES = 200        # per curve, each way: 200 half pieces of 40 px = 4000 px
_GAP_STEPS = 3           # after a miss: 1, 2 and 3 steps further
_STEP_CANDIDATES = 3     # accumulator peaks examined in a step's search (small region)
_STEP_MIN_SCORE = 0.5    # a continuation piece's min_score
_PIECE_WIDTHS, _PIECE_MIN = 4.0, 48.0   # default piece_length: max(4 * width, 48)
_SEED_TIMES = 2.0        # the seed piece is this many pieces long
_FOLLOW_TIMES = (1.0, 2.0)   # a step tries a piece, then one twice as long
_MIN_PIECES = 2.0        # default min_length: this many pieces
_SHORT_SEEDS = True      # no curve from the long seeds: seed with the piece itself
_STEP_PROFILE = True     # a step's point must show the rope's two borders
#: The seed's point must show the rope's two borders too, the weaker at least
#: this share of the stronger (None: no check). A rope is one material against
#: one seabed on both sides; a dark cable searched for as a bright rope shows
#: its own strong border on one side of a "bright band" beside it and only the
#: seabed's texture on the other. Tune part of bench/bench_curves.py (100
#: scenes, each also searched at the other polarity; docs/curves.md): curves at
#: the wrong polarity 0.58 a scene without the check, 0.18 at 0.3, 0.03 at 0.5,
#: 0.02 at 0.7; ropes found 94 % without, 93 % at 0.5, 91 % at 0.7 (its first
#: 60 scenes, where 0.5 was chosen: 97 % either way, 93 % at 0.7).
_SEED_BALANCE = 0.5


@dataclass(eq=False)
class Curve(ValueEquality):
    """A curved rope, cable or pipe found in an image.

    Attributes
    ----------
    points : ndarray (N, 2)
        Its centre line (x, y) in full-resolution image pixels, from one end
        to the other, a point every half piece or so (N >= 2).
    width : float
        Its width as seen, px: the median of the distances between its two
        borders measured along it.
    score : float
        Mean score of its pieces: the share of a piece's edge points found
        in the image (0-1).
    nfa : float
        Number of false alarms of the curve: its seed's (see the module
        docstring).
    confidence : float
        The seed detection's confidence (0-1).
    flags : tuple of str
        ``leaves_image``, ``gap_bridged``, ``max_pieces_reached``, and the
        seed's ``ambiguous``.
    pieces : int
        Pieces found, the seed included.
    steps : int
        Continuation searches tried.
    piece_nfa : tuple of float
        Each point's piece NFA, in the order of ``points`` (NaN for an end
        carried on beyond its last piece and for points interpolated across
        a gap).
    """

    points: np.ndarray
    width: float
    score: float
    nfa: float
    confidence: float
    flags: tuple = ()
    pieces: int = 1
    steps: int = 0
    piece_nfa: tuple = field(default_factory=tuple)
    #: (not a field) what it is, as :attr:`Detection.kind` says for detections
    kind = "curve"

    @property
    def length(self) -> float:
        """Length of the polyline, px.

        >>> Curve(np.array([[0.0, 0.0], [3.0, 4.0], [3.0, 10.0]]), 8.0, 0.9, 1e-6, 0.5).length
        11.0
        """
        p = np.asarray(self.points, float)
        return float(np.hypot(*np.diff(p, axis=0).T).sum()) if len(p) > 1 else 0.0

    def to_dict(self) -> dict:
        """Plain-Python form for JSON (``"kind": "curve"``; NaN and inf as None).

        >>> import json
        >>> c = Curve(np.array([[0.0, 0.0], [3.0, 4.0]]), 8.0, 0.9, 1e-6, 0.5, ("leaves_image",))
        >>> d = json.loads(json.dumps(c.to_dict()))
        >>> d["kind"], d["points"], d["length"], d["flags"]
        ('curve', [[0.0, 0.0], [3.0, 4.0]], 5.0, ['leaves_image'])
        """
        fin = lambda v: float(v) if math.isfinite(v) else None
        return {"kind": "curve", "points": np.asarray(self.points, float).tolist(),
                "width": float(self.width), "length": self.length, "score": float(self.score),
                "nfa": fin(self.nfa), "confidence": float(self.confidence),
                "flags": list(self.flags), "pieces": int(self.pieces), "steps": int(self.steps),
                "piece_nfa": [fin(v) for v in self.piece_nfa]}


@dataclass
class _Piece:
    """A point of a curve (full-resolution px), its unit direction and evidence
    (NaN: interpolated across a gap, or an end)."""

    x: float
    y: float
    d: np.ndarray
    score: float = math.nan
    nfa: float = math.nan


def _check(width, width_range, polarity, piece_length, max_turn, max_curves, config):
    w = number("width", width, lo=1.0, hi=500.0)
    lo, hi = pair("width_range", width_range)
    if not (0.2 <= lo and hi <= 5.0):
        raise ParameterError(f"width_range={width_range!r}: must lie within [0.2, 5] "
                             "(the widths searched, relative to width)")
    if polarity not in ("bright", "dark", "either"):
        raise ParameterError(f"polarity={polarity!r}: must be one of bright, dark, either")
    if piece_length is None:
        length = max(_PIECE_WIDTHS * w, _PIECE_MIN)
    else:
        length = number("piece_length", piece_length, lo=2.0 * w, hi=2000.0)
    turn = number("max_turn", max_turn, lo=1.0, hi=90.0)
    n = int(number("max_curves", max_curves, lo=1, hi=100, integer=True))
    if config is not None and not isinstance(config, Config):
        raise ParameterError(f"config must be a seahough.Config, got {type(config).__name__}")
    return w, (lo, hi), length, turn, n


def _direction(angle_deg: float) -> np.ndarray:
    """Unit direction of a line at ``angle_deg`` (counter-clockwise as displayed)."""
    a = math.radians(angle_deg)
    return np.array([math.cos(a), -math.sin(a)])


def _seed_position(result, det: Detection) -> tuple[float, float]:
    """Where along its line a seed fitted: the origin of the refined pose
    the detection was made from."""
    best, where = math.inf, (det.x, det.y)
    for c in result.candidates:
        if c.full is None:
            continue
        p = c.full.pose
        err = abs(p.scale - det.scale) + abs(((p.angle - det.angle) + 90.0) % 180.0 - 90.0)
        if err < best:
            best, where = err, (float(p.tx), float(p.ty))
    return where


def _profile(gray, x, y, d, stretch, lo, hi, polarity):
    """``(width, shift, strength)`` of the rope at (x, y) along ``d``, from
    its grey-level profile across (the median over ``stretch`` px along):
    the distance between its two borders (the strongest steps across it, of
    the signs ``polarity`` gives, one each side), how far the middle between
    them lies from (x, y) along the normal ``(-d[1], d[0])``, and the weaker
    border's step (grey levels per px); None when no two borders ``lo`` to
    ``hi`` px apart are found.

    Examples
    --------
    >>> img = np.full((60, 80), 40, np.float32)
    >>> img[27:34, :] = 200                                  # 7 px wide, centre y = 30
    >>> w, shift, step, balance = _profile(img, 40.0, 28.0, np.array([1.0, 0.0]), 15, 3, 12, "bright")
    >>> round(w, 1), round(shift, 1), round(step)            # normal (0, 1): down
    (7.0, 2.0, 160)
    """
    n = np.array([-d[1], d[0]])
    reach = 0.5 * hi + 3.0
    t = np.arange(-0.5 * stretch, 0.5 * stretch + 0.5, 1.0, dtype=np.float32)
    s = np.arange(-reach, reach + 0.125, 0.25, dtype=np.float32)
    mx = (x + t[None, :] * d[0] + s[:, None] * n[0]).astype(np.float32)
    my = (y + t[None, :] * d[1] + s[:, None] * n[1]).astype(np.float32)
    strip = cv2.remap(np.ascontiguousarray(gray, np.float32), mx, my, cv2.INTER_LINEAR,
                      borderMode=cv2.BORDER_REPLICATE)
    prof = np.median(strip, axis=1)
    g = np.zeros_like(prof)
    g[2:-2] = prof[4:] - prof[:-4]               # grey levels per px (rows 0.25 px apart)
    sign = {"bright": 1.0, "dark": -1.0}.get(polarity)
    best = None
    for sg in ((sign,) if sign is not None else (1.0, -1.0)):
        a = sg * g                               # rising into the rope, then falling
        i = int(np.argmax(np.where(s < 0.25 * lo, a, -np.inf)))
        j = int(np.argmin(np.where(s > -0.25 * lo, a, np.inf)))
        if not (0 < i < len(s) - 1 and 0 < j < len(s) - 1):
            continue
        # sub-pixel: the parabola's top through the three samples
        sub = lambda k, v: float(s[k]) + 0.125 * (v[k - 1] - v[k + 1]) / min(
            v[k - 1] - 2 * v[k] + v[k + 1], -1e-6)
        si, sj = sub(i, a), sub(j, -a)
        strength = float(min(a[i], -a[j]))
        if lo <= sj - si <= hi and strength > 0 and (best is None or strength > best[2]):
            best = (float(sj - si), float(0.5 * (si + sj)), strength,
                    strength / float(max(a[i], -a[j])))
    return best


def _near(polylines, x: float, y: float, tol: float) -> bool:
    """Is (x, y) within ``tol`` px of one of the polylines?"""
    q = np.array([x, y])
    def near(a, ab):   # (of one polyline: its segments a -> a + ab)
        t = np.clip(np.einsum("ij,ij->i", q - a, ab) / np.maximum((ab ** 2).sum(1), 1e-12), 0, 1)
        return (np.hypot(*(a + t[:, None] * ab - q).T) < tol).any()
    return any(near(p[:-1], np.diff(p, axis=0)) for p in polylines)


def _bridge(a: _Piece, b: _Piece, n: int) -> list:
    """``n`` points across a gap from ``a`` to ``b``: the cubic (Hermite)
    through both with their directions, which follows an even bend."""
    p0, p1 = np.array([a.x, a.y]), np.array([b.x, b.y])
    m = np.hypot(*(p1 - p0))
    out = []
    for t in np.arange(1, n + 1) / (n + 1):
        h = (2 * t ** 3 - 3 * t ** 2 + 1, t ** 3 - 2 * t ** 2 + t, -2 * t ** 3 + 3 * t ** 2,
             t ** 3 - t ** 2)
        q = h[0] * p0 + h[1] * m * a.d + h[2] * p1 + h[3] * m * b.d
        out.append(_Piece(float(q[0]), float(q[1]), b.d))
    return out


class _Follower:
    """The continuation searches of one curve: its piece patterns (shortest
    first), the image's features and the limits shared by every step."""

    def __init__(self, patterns, gray, features, cfg, max_turn, step_nfa, others, polarity,
                 seen):
        self.patterns, self.gray, self.features = patterns, gray, features
        self.seen = seen                      # the width measured across the seed
        self.cfg, self.max_turn, self.step_nfa = cfg, max_turn, step_nfa
        self.others, self.polarity = others, polarity   # others: curves found before
        self.length, self.width = patterns[0].line_length, patterns[0].line_width
        self.step = 0.5 * self.length
        self.steps = 0
        self.widths: list = []
        self.strengths: list = []

    def inside(self, x: float, y: float) -> bool:
        h, w = self.gray.shape
        return 0.0 <= x <= w - 1 and 0.0 <= y <= h - 1

    def floor(self) -> float:
        """Half the median contrast of the rope's borders so far."""
        return 0.5 * float(np.median(self.strengths)) if self.strengths else 0.0

    def measure(self, x, y, d, stretch):
        """The profile across the rope at (x, y), or None when its borders
        are not where they should be."""
        m = _profile(self.gray, x, y, d, stretch, 0.6 * self.seen, 1.6 * self.seen,
                     self.polarity)
        return m if m is not None and abs(m[1]) <= 0.75 * self.seen else None

    def next_piece(self, x, y, d, jump):
        """The piece ``jump`` px ahead of (x, y) along ``d`` (None: not found)."""
        px, py = x + jump * d[0], y + jump * d[1]
        # the rope may bend by at most max_turn over the jump: jump * sin(max_turn) across
        r = max(0.5 * self.width, 2.0) + jump * math.sin(math.radians(self.max_turn))
        a = math.degrees(math.atan2(-d[1], d[0])) % 180.0
        found = []
        for pattern in self.patterns:
            det = Detector(pattern, (1.0, 1.0), (a - self.max_turn, a + self.max_turn),
                           config=self.cfg, max_results=1, min_score=_STEP_MIN_SCORE,
                           max_nfa=self.step_nfa, search_region=(px - r, py - r, px + r, py + r))
            self.steps += 1
            det._line_extent = False   # (a piece of a bend: its line's extent is no measure)
            found = det.search(self.gray, features=self.features).detections
            if found:
                break
        if not found:
            return None
        f = found[0]
        nd = _direction(f.line_angle)
        if nd @ d < 0:
            nd = -nd
        t = (px - f.x) * nd[0] + (py - f.y) * nd[1]
        qx, qy = f.x + t * nd[0], f.y + t * nd[1]
        m = self.measure(qx, qy, nd, max(2.0 * self.seen, 12.0))
        if _STEP_PROFILE and (m is None or m[2] < self.floor()):
            return None                      # the piece's line, but no rope at this point
        if m is not None:
            qx, qy = qx - m[1] * nd[1], qy + m[1] * nd[0]
            self.widths.append(m[0])
            self.strengths.append(m[2])
        if math.hypot(qx - px, qy - py) > r + 1.0 or _near(self.others, qx, qy,
                                                           max(self.width, 3.0)):
            return None                      # off the prediction, or onto a curve found before
        return _Piece(qx, qy, nd, f.score, f.nfa)

    def follow(self, seed: _Piece, sign: float):
        """The points after ``seed`` going ``sign`` (+1: along its direction),
        and what stopped the following: ``(points, gap, leaves, full)``."""
        out, cur = [], _Piece(seed.x, seed.y, seed.d * sign)
        gap = leaves = full = False
        while not (leaves or full):
            piece = None
            for k in range(1, _GAP_STEPS + 2):
                px, py = cur.x + k * self.step * cur.d[0], cur.y + k * self.step * cur.d[1]
                if not self.inside(px, py):   # (after a miss: the rope ended before)
                    leaves = k == 1
                    break
                piece = self.next_piece(cur.x, cur.y, cur.d, k * self.step)
                if piece is not None:
                    if k > 1:
                        gap = True
                        out += _bridge(cur, piece, k - 1)
                    break
            if piece is None or np.hypot(piece.x - cur.x, piece.y - cur.y) < 0.25 * self.step:
                break                         # not found, or no progress
            out.append(piece)
            cur = piece
            full = len(out) >= _MAX_PIECES
        return out, gap, leaves, full

    def end(self, last: _Piece, d: np.ndarray) -> _Piece:
        """The end beyond ``last`` (direction ``d``, outwards): a few px at a
        time, each point moved onto the middle of the rope's profile there,
        for as long as its two borders are seen (at least half as contrasted
        as along the curve), at most half a piece, never out of the image."""
        floor, step = self.floor(), max(2.0, 0.5 * self.seen)
        p, d = np.array([last.x, last.y]), np.asarray(d, float)
        for _ in range(int(0.5 * self.length / step)):
            q = p + step * d
            if not self.inside(*q):               # on to the image border
                h, w = self.gray.shape
                t = min([(lim - p[i]) / d[i] for i, lim in ((0, w - 1.0), (1, h - 1.0),
                                                            (0, 0.0), (1, 0.0))
                         if d[i] * (lim - p[i]) > 0] or [0.0])
                p = p + max(0.0, min(t, step)) * d
                break
            m = self.measure(q[0], q[1], d, max(0.5 * self.seen, 4.0))
            if m is None or m[2] < floor or abs(m[1]) > 0.5 * self.seen:
                break
            p = q + m[1] * np.array([-d[1], d[0]])      # onto the middle (d is kept:
        return _Piece(float(p[0]), float(p[1]), d)     # a shift is a noisy direction)


def _trace(det, res, gray, w, s_range, length, step_cfg, max_turn, step_nfa, others, polarity):
    """The curve grown from a seed detection, or why none was (a str): its
    point does not show the rope's profile (:data:`_SEED_BALANCE`), or it
    lies on a curve found before."""
    (sx, sy), d = _seed_position(res, det), _direction(det.line_angle)
    lo, hi = s_range[0] * w, s_range[1] * w
    m = _profile(gray, sx, sy, d, 0.5 * length, lo, hi, polarity)
    if _SEED_BALANCE is not None and (m is None or m[3] < _SEED_BALANCE):
        # (no rope's profile at the seed: its borders are not both there)
        band = f"{polarity} band {lo:.3g}-{hi:.3g} px wide" if polarity != "either" \
            else f"band {lo:.3g}-{hi:.3g} px wide"
        if m is None:
            return (f"a line, but no rope across it: no {band} (the width of curve:WIDTH, "
                    "or --polarity)")
        return (f"a line, but no rope across it: one border of a {band} {m[3]:.2f} as strong "
                f"as the other (under {_SEED_BALANCE:.2g}: the edge of something wider, or a "
                "rope of the other --polarity)")
    if m is not None:
        sx, sy = sx - m[1] * d[1], sy + m[1] * d[0]
    wide = m[0] if m is not None else w * float(np.clip(det.scale, *s_range))
    if _near(others, sx, sy, max(wide, 3.0) + 2.0):
        return "on a curve found before"
    # the pieces have the seed's width as its refinement found it: the width
    # its edges show at the working scale, often under the profile's
    track = w * float(np.clip(det.scale, *s_range))
    pieces = [Pattern.line(max(k * length, 2.0 * track), track, polarity=polarity)
              for k in _FOLLOW_TIMES]
    fol = _Follower(pieces, gray, res.features, step_cfg, max_turn, step_nfa, others, polarity,
                    wide)
    if m is not None:
        fol.strengths.append(m[2])
    seed = _Piece(sx, sy, d, det.score, det.nfa)
    ahead, gap_a, out_a, full_a = fol.follow(seed, 1.0)
    back, gap_b, out_b, full_b = fol.follow(seed, -1.0)
    chain = back[::-1] + [seed] + ahead
    # a point followed backwards points backwards, i.e. outwards
    first, last = (fol.end(chain[0], back[-1].d if back else -d),
                   fol.end(chain[-1], ahead[-1].d if ahead else d))
    far = lambda a, b: math.hypot(a.x - b.x, a.y - b.y) > 0.5
    if len(chain) == 1 and not (far(first, seed) or far(last, seed)):
        first, last = (_Piece(sx + k * d[0], sy + k * d[1], d) for k in (-1.0, 1.0))
    chain = [first] * far(first, chain[0]) + chain + [last] * far(last, chain[-1])
    h, w_img = gray.shape
    edge = lambda p: min(p.x, p.y, w_img - 1 - p.x, h - 1 - p.y) < 1.5   # the end walked out
    out_a, out_b = out_a or edge(chain[-1]), out_b or edge(chain[0])
    flags = [f for f, on in ((FLAG_LEAVES_IMAGE, out_a or out_b), (FLAG_GAP, gap_a or gap_b),
                             (FLAG_MAX_PIECES, full_a or full_b),
                             (FLAG_AMBIGUOUS, FLAG_AMBIGUOUS in det.flags)) if on]
    found = [p for p in chain if math.isfinite(p.nfa)]
    return Curve(points=clip_polyline_ends([[p.x, p.y] for p in chain], w_img, h),
                 width=float(np.median([wide] + fol.widths)),
                 score=float(np.mean([p.score for p in found])), nfa=det.nfa,
                 confidence=det.confidence, flags=tuple(flags), pieces=len(found),
                 steps=fol.steps, piece_nfa=tuple(p.nfa for p in chain))


def find_curves(image, width, *, width_range=(0.5, 1.5), polarity="bright",
                piece_length=None, min_length=None, max_turn=25.0, max_curves=3,
                config=None, max_nfa=1.0, declined: list | None = None) -> list:
    """Find curved ropes, cables or pipes, each as a polyline of its centre line.

    Parameters
    ----------
    image : path or ndarray
        Grey, BGR or BGRA; uint8, uint16 or float.
    width : float
        The rope's width in pixels, about (4-20 px is typical).
    width_range : (float, float)
        Widths searched, relative to ``width`` (a round rope's shaded sides
        make it look narrower than it is).
    polarity : {"bright", "dark", "either"}
        A pale rope on a darker seabed, a dark cable, or either.
    piece_length : float, optional
        Length of the straight piece followed along the rope, px (default
        ``max(4 * width, 48)``, at least ``2 * width``). A piece L px long
        fits a bend of radius ``L * L / 16`` px within 2 px: shorter pieces
        follow sharper bends, longer ones are stronger evidence in clutter.
    min_length : float, optional
        Shorter curves are not reported, px (default: two pieces; a single
        piece is as likely a stick or a plank's edge as a rope).
    max_turn : float
        Largest turn of the rope's direction from one piece to the next
        (half a piece on), degrees.
    max_curves : int
        At most this many curves.
    config : Config, optional
        Tuning of the searches.
    max_nfa : float
        A curve's seed must have a number of false alarms of at most this
        (a continuation piece: at most ``max_nfa * STEP_NFA_SHARE``).
    declined : list, optional
        Receives the seed searches' candidates that made no curve
        (:class:`~seahough.core.candidates.Candidate`, best first), each
        saying why in its ``declined``: the seed search's own reasons (e.g.
        "NFA 3.2 over max_nfa 1"), or, for a line it found, that no rope
        lies across it, that the rope followed from it is shorter than
        ``min_length``, or that its NFA, counted over both seed searches,
        is over ``max_nfa``: what to change when no curve is found.

    Returns
    -------
    list of Curve
        Best seed first; ``[]`` when no rope is found.

    Examples
    --------
    >>> yy, xx = np.mgrid[0:240, 0:320]
    >>> r = np.hypot(xx - 160.0, yy - 460.0)         # an arc of radius 300 px, 8 px wide
    >>> img = (50 + 160 * np.clip(4.5 - np.abs(r - 300.0), 0, 1)).astype(np.uint8)
    >>> curves = find_curves(img, 8)
    >>> c = curves[0]
    >>> len(curves), c.length > 300, round(c.width), c.flags
    (1, True, 8, ('leaves_image',))
    >>> d = np.abs(np.hypot(c.points[:, 0] - 160.0, c.points[:, 1] - 460.0) - 300.0)
    >>> bool(d.max() < 1.0)                             # on its centre line
    True
    """
    w, s_range, length, max_turn, max_curves = _check(width, width_range, polarity,
                                                      piece_length, max_turn, max_curves, config)
    max_nfa, _ = check_max_nfa(max_nfa), _a_list("declined", declined)
    min_len = (_MIN_PIECES * length if min_length is None
               else number("min_length", min_length, lo=0.0))
    cfg = Config() if config is None else config
    gray = prepare_image(to_gray(image, max_pixels=cfg.max_pixels,
                                 max_memory_mb=cfg.max_memory_mb, bit_depth=cfg.bit_depth), cfg)
    cfg = cfg.replace(smooth=0.0)             # (smoothed once, above)
    # a step searches a small region: its few peaks need fewer candidates
    step_cfg = cfg.replace(n_candidates=min(cfg.n_candidates, _STEP_CANDIDATES))
    curves: list[Curve] = []
    # a few more seed lines than curves (some do not grow): those of
    # Config.n_candidates, more only when more curves are asked for
    n_seeds = max_curves + 4 if max_curves + 4 > cfg.n_candidates + 2 else min(
        max_curves + 4, cfg.n_candidates)
    seeds = [_SEED_TIMES * length] + ([length] if _SHORT_SEEDS and _SEED_TIMES != 1 else [])
    feats = None
    for seed_length in seeds:
        if curves:
            break
        seeder = Detector(Pattern.line(seed_length, w, polarity=polarity), s_range,
                          (0.0, 180.0), config=cfg, max_results=n_seeds, max_nfa=max_nfa)
        seeder._counting = seeder._line_extent = False   # (seeds to follow: not objects)
        res = seeder.search(gray, features=feats)
        feats = res.features                  # the shorter seed: on the same features
        why = {}                              # detection index -> why it made no curve
        for i, det in enumerate(res.detections):
            if len(curves) >= max_curves:
                break
            if det.nfa * len(seeds) > max_nfa:
                why[i] = (f"NFA {det.nfa * len(seeds):.3g} over max_nfa {max_nfa:.3g} (the "
                          f"line's, counted over the {len(seeds)} seed searches)")
                continue
            c = _trace(det, res, gray, w, s_range, length, step_cfg, max_turn,
                       max_nfa * STEP_NFA_SHARE, [c.points for c in curves], polarity)
            if isinstance(c, str):
                why[i] = c
            elif c.length < min_len:
                why[i] = (f"the rope followed from this line is {c.length:.0f} px long, "
                          f"under min_length {min_len:.0f}")
            else:
                c.nfa *= len(seeds)
                curves.append(c)
        if declined is not None and not curves:
            declined.extend(_declined_seeds(res, why, len(seeds)))
    return curves


def _declined_seeds(res, why: dict, seeds: int = 1) -> list:
    """The candidates of a seed search ``res`` that made no curve, best first:
    its declined ones as they are, its detections (accepted candidates) with
    ``why`` (by detection index) as their reason, and their NFA counted, as
    that reason counts it, over the ``seeds`` seed searches."""
    key = lambda c: (round(c.score, 9), round(c.nfa, 12) if math.isfinite(c.nfa) else c.nfa)
    found = {key(c): c for c in res.candidates if not c.declined}
    out = []
    for i, d in enumerate(res.detections):
        c = found.pop(key(d), None)
        if c is not None and i in why:
            ev = c.evidence if c.evidence is None or seeds == 1 else replace(
                c.evidence, log10_nfa=c.evidence.log10_nfa + math.log10(seeds))
            out.append(replace(c, declined=why[i], evidence=ev))
    return out + [c for c in res.candidates if c.declined]
