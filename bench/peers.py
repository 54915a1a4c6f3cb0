"""Peer methods for the benchmark suite (bench/run.py), all from OpenCV / numpy.

Every peer returns a :class:`PeerResult` in the suite's conventions: a 2x3
matrix mapping pattern-image (or previous-frame) pixels to scene
(current-frame) pixels, as ``cv2.warpAffine`` takes it, or ``None`` when the
method gives no answer, plus the method's own confidence number.

Peers and the settings used (the documentation each follows is named):

- :class:`FeatureLocator` / :func:`feature_pair` -- SIFT or ORB key points,
  k=2 matching (SIFT: FLANN k-d trees, 5 trees, 50 checks, as in OpenCV's
  FLANN matching tutorial; ORB: brute force, Hamming) with Lowe's ratio test
  (0.75), then
  ``cv2.estimateAffinePartial2D`` (RANSAC, reprojection threshold 3 px, OpenCV
  defaults otherwise: 2000 iterations, confidence 0.99, 10 refinement
  iterations). SIFT: ``cv2.SIFT_create()`` defaults. ORB:
  ``cv2.ORB_create(nfeatures=1500)`` (the default 500 is too few for a small
  marker among seabed clutter). Pattern images are padded
  by 32 px (border replicated, key points only inside the original) so ORB's
  31 px ``edgeThreshold`` does not leave a small pattern without key points.
  Confidence: the RANSAC inlier count. "Detected" (for false alarms) follows
  OpenCV's feature-homography tutorial: at least ``MIN_MATCH_COUNT = 10``
  ratio-test matches and a model.
- :class:`GHTGuil` -- ``cv2.createGeneralizedHoughGuil`` with the settings of
  OpenCV's "Object detection with Generalized Ballard and Guil Hough
  Transform" tutorial (MinDist 10, Levels 360, MaxBufferSize 1000, angle
  0-360 step 1, AngleThresh 1500, ScaleThresh 50, PosThresh 10) except scale
  step 0.025 (the tutorial's 0.05 leaves ~4 px corner error) and Canny 60/180
  (the tutorial's 30/110 times out more often on seabed clutter), the scale
  range set to cover the task, run on images
  downscaled by 2 with Dp 1 (so 2 full-resolution px per position bin): at
  full resolution one 640x480 search takes 1-3 s on this machine. The
  template is the pattern's Canny edges (inside its dilated mask) with Sobel
  gradients, exactly as ``setTemplate(image)`` computes them internally. Each
  search runs in a worker process killed after ``timeout`` seconds (a
  time-out is a failure). Confidence: the position votes of the best
  candidate.
- :func:`phase_correlation` -- ``cv2.phaseCorrelate`` on grey float frames
  with a Hann window (``cv2.createHanningWindow``), translation only.
- :func:`fourier_mellin` -- log-polar FFT registration (Reddy & Chatterji
  1996), implemented here with numpy FFT + ``cv2.warpPolar``: magnitude
  spectra of Hann-windowed centre squares, high-pass emphasis, log-polar
  resampling, ``cv2.phaseCorrelate`` for rotation and scale (both 180 degree
  solutions tried), then ``cv2.phaseCorrelate`` for the translation of the
  de-rotated, de-scaled frame.
- :func:`hough_rope` -- ``cv2.HoughLinesWithAccumulator`` (rho 1 px, theta
  0.5 degree) or ``cv2.HoughLinesP`` on ``cv2.Canny`` edges (50/150 after a
  sigma-1 Gaussian blur, as in OpenCV's Hough line tutorial), the two rope
  borders paired (parallel within 2 degrees, 0.5-1.6 rope widths apart), the
  strongest line as fallback.
- RoboSub props (bench/bench_robosub.py; each function's docstring gives
  its settings, which that benchmark tunes): :func:`hough_circles`
  (``cv2.HoughCircles``, HOUGH_GRADIENT or HOUGH_GRADIENT_ALT, after OpenCV's
  Hough circle tutorial), :func:`hough_posts` (``cv2.HoughLinesP`` segments
  near vertical grouped into posts), :func:`match_template_multiscale`
  (``cv2.matchTemplate`` TM_CCOEFF_NORMED over scales, either polarity,
  non-maximum suppression) and :class:`GHTGuilOpts` (:class:`GHTGuil` with
  its Canny and vote thresholds set per instance).
"""

from __future__ import annotations

import math
import multiprocessing as mp
import time
from dataclasses import dataclass

import cv2
import numpy as np

RATIO = 0.75
RANSAC_PX = 3.0
MIN_MATCH_COUNT = 10


@dataclass
class PeerResult:
    """A peer's answer: ``matrix`` (2x3, or None), its confidence number,
    whether it counts as a detection by the method's own rule, and (for
    methods timed inside a worker) its own time in seconds."""

    matrix: np.ndarray | None
    confidence: float = 0.0
    detected: bool = False
    seconds: float | None = None
    timed_out: bool = False


def grey(img) -> np.ndarray:
    img = np.asarray(img)
    if img.ndim == 3:
        img = cv2.cvtColor(img, cv2.COLOR_BGRA2GRAY if img.shape[2] == 4 else cv2.COLOR_BGR2GRAY)
    if img.dtype != np.uint8:
        img = np.clip(img, 0, 255).astype(np.uint8)
    return img


# --------------------------------------------------------------------------
# SIFT / ORB + RANSAC
# --------------------------------------------------------------------------

def _make(kind: str):
    if kind == "sift":
        # FLANN k-d trees, as in OpenCV's "Feature Matching with FLANN" tutorial (a
        # brute-force matcher takes 8 s on a pair of 1280x720 pool frames, FLANN 0.5 s)
        return cv2.SIFT_create(), cv2.FlannBasedMatcher(dict(algorithm=1, trees=5),
                                                         dict(checks=50))
    if kind == "sift-lowc":
        # the same with a lower contrast threshold (default 0.04): many more key points
        # in murky, low-contrast water, at about twice the time
        return cv2.SIFT_create(contrastThreshold=0.01), cv2.FlannBasedMatcher(
            dict(algorithm=1, trees=5), dict(checks=50))
    if kind == "orb":
        return cv2.ORB_create(nfeatures=1500), cv2.BFMatcher(cv2.NORM_HAMMING)
    raise ValueError(kind)


_PAD = 32


def _pattern_features(det, img, mask=None):
    """Key points of a (small) pattern image, padded so ORB can use its borders."""
    g = grey(img)
    h, w = g.shape
    big = cv2.copyMakeBorder(g, _PAD, _PAD, _PAD, _PAD, cv2.BORDER_REPLICATE)
    m = np.zeros(big.shape, np.uint8)
    if mask is None:
        m[_PAD:_PAD + h, _PAD:_PAD + w] = 255
    else:
        mk = (grey(mask) > 0).astype(np.uint8) * 255
        m[_PAD:_PAD + h, _PAD:_PAD + w] = cv2.dilate(mk, np.ones((5, 5), np.uint8))
    kp, des = det.detectAndCompute(big, m)
    pts = np.array([k.pt for k in kp], np.float32).reshape(-1, 2) - _PAD
    return pts, des


def _ratio_matches(matcher, des_a, des_b):
    if des_a is None or des_b is None or len(des_a) < 2 or len(des_b) < 2:
        return []
    good = []
    for pair in matcher.knnMatch(des_a, des_b, k=2):
        if len(pair) == 2 and pair[0].distance < RATIO * pair[1].distance:
            good.append(pair[0])
    return good


def _ransac(pts_a, pts_b, good) -> PeerResult:
    if len(good) < 3:
        return PeerResult(None, 0.0, False)
    src = np.float32([pts_a[m.queryIdx] for m in good]).reshape(-1, 1, 2)
    dst = np.float32([pts_b[m.trainIdx] for m in good]).reshape(-1, 1, 2)
    M, inl = cv2.estimateAffinePartial2D(src, dst, method=cv2.RANSAC,
                                         ransacReprojThreshold=RANSAC_PX)
    if M is None:
        return PeerResult(None, 0.0, False)
    n_in = int(inl.sum()) if inl is not None else 0
    return PeerResult(M.astype(float), float(n_in), len(good) >= MIN_MATCH_COUNT)


class FeatureLocator:
    """SIFT or ORB + ratio test + RANSAC partial affine: pattern -> scene."""

    def __init__(self, kind: str, pattern_img, mask=None):
        self.kind = kind
        self.det, self.matcher = _make(kind)
        self.pts, self.des = _pattern_features(self.det, pattern_img, mask)

    def locate(self, scene) -> PeerResult:
        kp, des = self.det.detectAndCompute(grey(scene), None)
        pts = np.array([k.pt for k in kp], np.float32).reshape(-1, 2)
        return _ransac(self.pts, pts, _ratio_matches(self.matcher, self.des, des))


def matched_points(kind: str, prev, cur, _cache={}):
    """(points of prev, points of cur, ratio-test matches) of SIFT/ORB."""
    if kind not in _cache:
        _cache[kind] = _make(kind)
    det, matcher = _cache[kind]
    kp1, d1 = det.detectAndCompute(grey(prev), None)
    kp2, d2 = det.detectAndCompute(grey(cur), None)
    p1 = np.array([k.pt for k in kp1], np.float32).reshape(-1, 2)
    p2 = np.array([k.pt for k in kp2], np.float32).reshape(-1, 2)
    return p1, p2, _ratio_matches(matcher, d1, d2)


def feature_pair(kind: str, prev, cur) -> PeerResult:
    """SIFT/ORB + RANSAC motion, previous frame -> current frame."""
    return _ransac(*matched_points(kind, prev, cur))


#: other robust similarity fits of the same matches (:func:`similarity_fits`):
#: RANSAC with these reprojection thresholds (px) and least median of squares
OTHER_FITS_PX = (1.0, 2.0, 5.0)


def similarity_fits(pts_a, pts_b, good) -> list:
    """The similarity of the same matches fitted by other robust criteria than
    :func:`_ransac`'s (RANSAC at :data:`OTHER_FITS_PX` px, LMEDS): where the
    motion is not a similarity (3-D relief, an oblique camera) each keeps
    other points and lands elsewhere; their spread is how far "the"
    similarity of the pair is defined."""
    if len(good) < 3:
        return []
    src = np.float32([pts_a[m.queryIdx] for m in good]).reshape(-1, 1, 2)
    dst = np.float32([pts_b[m.trainIdx] for m in good]).reshape(-1, 1, 2)
    fits = [cv2.estimateAffinePartial2D(src, dst, method=cv2.RANSAC, ransacReprojThreshold=t)[0]
            for t in OTHER_FITS_PX]
    fits.append(cv2.estimateAffinePartial2D(src, dst, method=cv2.LMEDS)[0])
    return [m.astype(float) for m in fits if m is not None]


# --------------------------------------------------------------------------
# Generalized Hough (Guil), in a worker process with a time cap
# --------------------------------------------------------------------------

GHT_DOWNSCALE = 0.5
GHT_CANNY = (60, 180)
GHT_SCALE_STEP = 0.025


def _ght_make(scale_range, angle_range):
    g = cv2.createGeneralizedHoughGuil()
    g.setMinDist(10)
    g.setLevels(360)
    g.setDp(1)
    g.setMaxBufferSize(1000)
    g.setMinAngle(float(angle_range[0]))
    g.setMaxAngle(float(angle_range[1]))
    g.setAngleStep(1.0)
    g.setAngleThresh(1500)
    g.setMinScale(float(scale_range[0]))
    g.setMaxScale(float(scale_range[1]))
    g.setScaleStep(GHT_SCALE_STEP)
    g.setScaleThresh(50)
    g.setPosThresh(10)
    g.setCannyLowThresh(GHT_CANNY[0])
    g.setCannyHighThresh(GHT_CANNY[1])
    return g


def _ght_template(img, mask, f):
    g = grey(img)
    if f != 1.0:
        g = cv2.resize(g, None, fx=f, fy=f, interpolation=cv2.INTER_AREA)
    edges = cv2.Canny(g, GHT_CANNY[0], GHT_CANNY[1])
    if mask is not None:
        m = (grey(mask) > 0).astype(np.uint8)
        if f != 1.0:
            m = cv2.resize(m, (g.shape[1], g.shape[0]), interpolation=cv2.INTER_NEAREST)
        m = cv2.dilate(m, np.ones((5, 5), np.uint8))
        edges[m == 0] = 0
    dx = cv2.Sobel(g, cv2.CV_32F, 1, 0)
    dy = cv2.Sobel(g, cv2.CV_32F, 0, 1)
    return edges, dx, dy, g.shape


def _ght_worker(conn):
    cv2.setNumThreads(1)
    ght, centre, f = None, None, 1.0
    while True:
        msg = conn.recv()
        if msg is None:
            break
        if msg[0] == "template":
            _, img, mask, scale_range, angle_range, f = msg
            ght = _ght_make(scale_range, angle_range)
            edges, dx, dy, (h, w) = _ght_template(img, mask, f)
            # OpenCV's default template centre: (cols / 2, rows / 2), integer division
            centre = (w // 2, h // 2)
            ght.setTemplate(edges, dx, dy, centre)
            conn.send(("ok", centre))
        else:
            _, scene = msg
            t = time.perf_counter()
            g = grey(scene)
            if f != 1.0:
                g = cv2.resize(g, None, fx=f, fy=f, interpolation=cv2.INTER_AREA)
            pos, votes = ght.detect(g)
            dt = time.perf_counter() - t
            conn.send((pos, votes, dt))


class GHTGuil:
    """OpenCV's Generalized Hough (Guil) with a per-search time cap."""

    def __init__(self, timeout: float = 5.0, downscale: float = GHT_DOWNSCALE):
        self.timeout = float(timeout)
        self.f = float(downscale)
        self._ctx = mp.get_context("fork")
        self._proc = None
        self._conn = None
        self._template = None

    def _start(self):
        a, b = self._ctx.Pipe()
        self._proc = self._ctx.Process(target=_ght_worker, args=(b,), daemon=True)
        self._proc.start()
        self._conn = a
        if self._template is not None:
            self._send_template()

    def _send_template(self):
        img, mask, sr, ar = self._template
        self._conn.send(("template", img, mask, sr, ar, self.f))
        _, self._centre = self._conn.recv()
        self._shape = grey(img).shape

    def set_template(self, img, mask, scale_range, angle_range):
        self._template = (np.ascontiguousarray(grey(img)), None if mask is None else grey(mask),
                          tuple(scale_range), tuple(angle_range))
        if self._proc is None or not self._proc.is_alive():
            self._start()
        else:
            self._send_template()

    def locate(self, scene) -> PeerResult:
        if self._proc is None or not self._proc.is_alive():
            self._start()
        self._conn.send(("detect", np.ascontiguousarray(scene)))
        if not self._conn.poll(self.timeout):
            self.close()  # kill the stuck search; the next call starts a fresh worker
            return PeerResult(None, 0.0, False, self.timeout, True)
        pos, votes, dt = self._conn.recv()
        if pos is None or len(pos) == 0:
            return PeerResult(None, 0.0, False, dt)
        pos = pos.reshape(-1, 4)
        votes = votes.reshape(-1, 3)
        i = int(np.argmax(votes[:, 0]))
        x, y, s, a = (float(v) for v in pos[i])
        f = self.f
        # Guil's angle is clockwise as displayed (x right, y down)
        th = math.radians(a)
        c, sn = math.cos(th), math.sin(th)
        # full-res pattern px q -> working px f*q (+ (f-1)/2 pixel-centre shift)
        # -> rotate/scale about the working template centre -> full-res scene px
        off = 0.5 * (f - 1.0) if f != 1.0 else 0.0
        A = s * np.array([[c, -sn], [sn, c]])
        # scene_work = A (f q + off - centre) + pos; scene_full = (scene_work - off) / f
        lin = A  # (f q) scaled by 1/f cancels f
        tr = (A @ (np.array([off, off]) - np.asarray(self._centre, float)) + [x, y] - off) / f
        M = np.hstack([lin, tr[:, None]])
        return PeerResult(M, float(votes[i, 0]), True, dt)

    def close(self):
        if self._proc is not None:
            if self._proc.is_alive():
                self._proc.kill()
            self._proc.join(timeout=2)
        self._proc = None
        self._conn = None


# --------------------------------------------------------------------------
# Phase correlation and Fourier-Mellin
# --------------------------------------------------------------------------

def _float_grey(img) -> np.ndarray:
    return grey(img).astype(np.float64)


def phase_correlation(prev, cur) -> PeerResult:
    """Translation only: ``cv2.phaseCorrelate`` with a Hann window."""
    a, b = _float_grey(prev), _float_grey(cur)
    win = cv2.createHanningWindow((a.shape[1], a.shape[0]), cv2.CV_64F)
    (dx, dy), resp = cv2.phaseCorrelate(a, b, win)
    M = np.array([[1.0, 0.0, dx], [0.0, 1.0, dy]])
    return PeerResult(M, float(resp), True)


_FM_SIZE = 256


def _highpass(n: int) -> np.ndarray:
    """Reddy-Chatterji emphasis filter for a centred (fftshift) spectrum."""
    f = np.fft.fftshift(np.fft.fftfreq(n))
    x = np.cos(np.pi * f[None, :]) * np.cos(np.pi * f[:, None])
    return (1.0 - x) * (2.0 - x)


def _logpolar_spectrum(g: np.ndarray, n: int) -> tuple[np.ndarray, float]:
    h, w = g.shape
    s = min(h, w)
    y0, x0 = (h - s) // 2, (w - s) // 2
    sq = cv2.resize(g[y0:y0 + s, x0:x0 + s], (n, n), interpolation=cv2.INTER_AREA)
    win = cv2.createHanningWindow((n, n), cv2.CV_64F)
    spec = np.abs(np.fft.fftshift(np.fft.fft2((sq - sq.mean()) * win)))
    spec *= _highpass(n)
    radius = n / 2.0
    lp = cv2.warpPolar(spec, (n, n), (n / 2.0, n / 2.0), radius,
                       cv2.WARP_POLAR_LOG | cv2.INTER_LINEAR)
    return lp, radius


def fourier_mellin(prev, cur) -> PeerResult:
    """Rotation + scale + translation by log-polar FFT registration."""
    a, b = _float_grey(prev), _float_grey(cur)
    h, w = a.shape
    n = _FM_SIZE
    la, radius = _logpolar_spectrum(a, n)
    lb, _ = _logpolar_spectrum(b, n)
    # rows of the warpPolar output = angle (0..360 over n rows), columns = log radius
    win = cv2.createHanningWindow((n, n), cv2.CV_64F)
    (sx, sy), _ = cv2.phaseCorrelate(la, lb, win)
    # the spectrum of the current frame is turned like the image and shrunk by the scale
    angle = -360.0 * sy / n          # degrees, counter-clockwise as displayed
    scale = math.exp(-sx * math.log(radius) / n)
    c = np.array([(w - 1) / 2.0, (h - 1) / 2.0])
    win_full = cv2.createHanningWindow((w, h), cv2.CV_64F)
    best = None
    for ang in (angle, angle + 180.0):
        th = math.radians(ang)
        R = scale * np.array([[math.cos(th), math.sin(th)], [-math.sin(th), math.cos(th)]])
        A = np.hstack([R, (c - R @ c)[:, None]])      # rotation/scale about the centre
        # b'(y) = b(A y): b' is the previous frame shifted by u = R^-1 t
        bw = cv2.warpAffine(b, A, (w, h), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP)
        (ux, uy), resp = cv2.phaseCorrelate(a, bw, win_full)
        t = R @ np.array([ux, uy])
        M = np.hstack([R, (c - R @ c + t)[:, None]])
        if best is None or resp > best.confidence:
            best = PeerResult(M, float(resp), True)
    return best


# --------------------------------------------------------------------------
# Ropes: Hough lines on Canny edges
# --------------------------------------------------------------------------

def _edges(scene) -> np.ndarray:
    g = cv2.GaussianBlur(grey(scene), (0, 0), 1.0)
    return cv2.Canny(g, 50, 150)


def line_from_normal(theta: float, rho: float, shape) -> tuple[float, float]:
    """(line_angle, line_offset) in the simulator's convention from a Hough
    line ``x cos(theta) + y sin(theta) = rho``."""
    h, w = shape[:2]
    c = np.array([(w - 1) / 2.0, (h - 1) / 2.0])
    a = (90.0 - math.degrees(theta)) % 180.0
    n = np.array([math.sin(math.radians(a)), math.cos(math.radians(a))])
    p0 = rho * np.array([math.cos(theta), math.sin(theta)])
    return a, float(n @ (p0 - c))


def _pair(lines, width):
    """First pair (by rank) of near-parallel lines 0.5-1.6 widths apart: their mid-line."""
    best = None
    k = min(len(lines), 12)
    for i in range(k):
        for j in range(i + 1, k):
            t1, r1 = lines[i][:2]
            t2, r2 = lines[j][:2]
            # bring both to a common normal orientation
            d = (math.degrees(t2 - t1) + 90.0) % 180.0 - 90.0
            if abs(d) > 2.0:
                continue
            if abs(math.degrees(t2 - t1)) > 90.0:  # normals opposite: flip the second
                r2 = -r2
                t2 = t2 - math.pi if t2 > t1 else t2 + math.pi
            gap = abs(r1 - r2)
            if 0.5 * width <= gap <= 1.6 * width and (best is None or i + j < best[0]):
                best = (i + j, 0.5 * (t1 + t2), 0.5 * (r1 + r2), lines[i][2] + lines[j][2])
    return best


def hough_rope(scene, width: float, probabilistic: bool = False):
    """(line_angle, line_offset, confidence) of a rope, or None."""
    e = _edges(scene)
    shape = e.shape
    if not probabilistic:
        out = cv2.HoughLinesWithAccumulator(e, 1, math.pi / 360, 80)
        if out is None or len(out) == 0:
            return None
        # (rho, theta, votes) -> (theta, rho, votes), strongest first
        lines = [(float(t), float(r), float(v)) for r, t, v in out.reshape(-1, 3)]
    else:
        segs = cv2.HoughLinesP(e, 1, math.pi / 360, 50, minLineLength=50, maxLineGap=10)
        if segs is None or len(segs) == 0:
            return None
        segs = segs.reshape(-1, 4).astype(float)
        length = np.hypot(segs[:, 2] - segs[:, 0], segs[:, 3] - segs[:, 1])
        lines = []
        for i in np.argsort(-length):
            x1, y1, x2, y2 = segs[i]
            th = math.atan2(x2 - x1, -(y2 - y1))  # normal direction (cos th, sin th)
            if th < 0:
                th += math.pi
            if th >= math.pi:
                th -= math.pi
            rho = x1 * math.cos(th) + y1 * math.sin(th)
            lines.append((th, rho, float(length[i])))
    pr = _pair(lines, width)
    if pr is not None:
        _, th, rho, conf = pr
    else:
        th, rho, conf = lines[0]
    a, off = line_from_normal(th, rho, shape)
    return a, off, float(conf)


# --------------------------------------------------------------------------
# AKAZE + RANSAC (bench/bench_real_pairs.py)
# --------------------------------------------------------------------------

def _make_akaze():
    """``cv2.AKAZE_create()`` (defaults: MLDB binary descriptors, threshold
    0.001, 4 octaves) with a brute-force Hamming matcher, as in OpenCV's
    "AKAZE local features matching" tutorial."""
    return cv2.AKAZE_create(), cv2.BFMatcher(cv2.NORM_HAMMING)


_AKAZE: list = []


def feature_pair_akaze(prev, cur) -> PeerResult:
    """AKAZE + ratio test (0.75) + RANSAC similarity, previous -> current frame
    (the same matching and RANSAC as :func:`feature_pair`)."""
    if not _AKAZE:
        _AKAZE.append(_make_akaze())
    det, matcher = _AKAZE[0]
    kp1, d1 = det.detectAndCompute(grey(prev), None)
    kp2, d2 = det.detectAndCompute(grey(cur), None)
    p1 = np.array([k.pt for k in kp1], np.float32).reshape(-1, 2)
    p2 = np.array([k.pt for k in kp2], np.float32).reshape(-1, 2)
    return _ransac(p1, p2, _ratio_matches(matcher, d1, d2))


# --------------------------------------------------------------------------
# KLT + RANSAC (bench/bench_real_pairs.py: the second reference fit where
# OpenCV has no AKAZE, as OpenCV 5.0, whose main modules dropped it)
# --------------------------------------------------------------------------

KLT_HIGHPASS = 8.0      # px: sigma of the Gaussian blur subtracted before tracking
KLT_COARSE_SIDE = 192   # px: longer side of the images of the coarse shift search


def _highpass_u8(g: np.ndarray, sigma: float = KLT_HIGHPASS) -> np.ndarray:
    """``g`` minus its Gaussian blur, stretched to a fixed contrast (uint8):
    the slow brightness gradients of lights and vignetting, which move with
    the camera and break Lucas-Kanade's brightness constancy, left out."""
    g = g.astype(np.float32)
    d = g - cv2.GaussianBlur(g, (0, 0), sigma)
    return np.clip(128.0 + d * (40.0 / (float(d.std()) + 1e-6)), 0, 255).astype(np.uint8)


def coarse_shift(a: np.ndarray, b: np.ndarray, side: int = KLT_COARSE_SIDE, grid: int = 3):
    """(shift (dx, dy), score): the translation from grey ``a`` to ``b`` by
    template matching at low resolution: each of a ``grid`` x ``grid`` tiling
    of ``a`` (shrunk to ``side`` px) is sought in the whole of ``b``
    (``cv2.matchTemplate``, TM_CCOEFF_NORMED) and the best-matching tile's
    shift is kept (a tile can be found however far the frame moved, as long
    as it stays in view)."""
    h, w = a.shape
    f = min(1.0, side / max(h, w))
    if f < 1.0:
        a = cv2.resize(a, None, fx=f, fy=f, interpolation=cv2.INTER_AREA)
        b = cv2.resize(b, None, fx=f, fy=f, interpolation=cv2.INTER_AREA)
    hh, ww = a.shape
    ph, pw = hh // grid, ww // grid
    best, shift = -2.0, np.zeros(2, np.float32)
    for i in range(grid):
        for j in range(grid):
            y0, x0 = i * ph, j * pw
            tile = a[y0:y0 + ph, x0:x0 + pw]
            if tile.std() < 1e-3:
                continue
            _, v, _, (bx, by) = cv2.minMaxLoc(cv2.matchTemplate(b, tile, cv2.TM_CCOEFF_NORMED))
            if v > best:
                best, shift = v, np.array([(bx - x0) / f, (by - y0) / f], np.float32)
    return shift, float(best)


def klt_pair(prev, cur) -> PeerResult:
    """Corners tracked by pyramidal Lucas-Kanade, then a RANSAC similarity,
    previous -> current frame.

    Both frames high-passed (:func:`_highpass_u8`); the translation found by
    :func:`coarse_shift` (on the frames as they are) seeds the tracking;
    ``cv2.goodFeaturesToTrack`` (2000 corners, quality 0.005, 7 px apart,
    block 7); ``cv2.calcOpticalFlowPyrLK`` (21x21 window, 3 pyramid levels,
    30 iterations / 0.01 px) forwards and back, a track kept when both
    succeed, it ends inside the frame and comes back within 1 px of its
    start; ``cv2.estimateAffinePartial2D`` as :func:`feature_pair` (RANSAC,
    3 px). Confidence: the RANSAC inlier count."""
    ra, rb = grey(prev), grey(cur)
    a, b = _highpass_u8(ra), _highpass_u8(rb)
    h, w = a.shape
    p0 = cv2.goodFeaturesToTrack(a, maxCorners=2000, qualityLevel=0.005, minDistance=7,
                                 blockSize=7)
    if p0 is None or len(p0) < 3:
        return PeerResult(None, 0.0, False)
    shift, _ = coarse_shift(ra, rb)
    crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 0.01)
    lk = {"winSize": (21, 21), "maxLevel": 3, "criteria": crit,
          "flags": cv2.OPTFLOW_USE_INITIAL_FLOW}
    p1, st1, _ = cv2.calcOpticalFlowPyrLK(a, b, p0, p0 + shift, **lk)
    back, st2, _ = cv2.calcOpticalFlowPyrLK(b, a, p1, p1 - shift, **lk)
    q = p1.reshape(-1, 2)
    ok = ((st1.ravel() == 1) & (st2.ravel() == 1)
          & (q[:, 0] >= 0) & (q[:, 1] >= 0) & (q[:, 0] <= w - 1) & (q[:, 1] <= h - 1)
          & (np.hypot(*(back - p0).reshape(-1, 2).T) < 1.0))
    if ok.sum() < 3:
        return PeerResult(None, 0.0, False)
    M, inl = cv2.estimateAffinePartial2D(p0[ok], p1[ok], method=cv2.RANSAC,
                                         ransacReprojThreshold=RANSAC_PX)
    if M is None:
        return PeerResult(None, 0.0, False)
    n_in = int(inl.sum()) if inl is not None else 0
    return PeerResult(M.astype(float), float(n_in), int(ok.sum()) >= MIN_MATCH_COUNT)


# --------------------------------------------------------------------------
# RoboSub props (bench/bench_robosub.py): circles, posts, multi-scale templates
# --------------------------------------------------------------------------

def hough_circles(scene, method: str = "gradient", dp: float = 1.0, param1: float = 100.0,
                  param2: float = 30.0, radius=(5, 100), min_dist: float | None = None,
                  blur: int = 5) -> list[tuple[float, float, float]]:
    """Circles ``(x, y, r)`` in full-resolution pixels, in the order
    ``cv2.HoughCircles`` returns them (strongest first), as in OpenCV's
    "Hough Circle Transform" tutorial: the grey image median-blurred
    (``blur`` px; 0: none), ``method`` "gradient" (``cv2.HOUGH_GRADIENT``:
    ``param1`` the upper Canny threshold, ``param2`` the accumulator
    threshold) or "alt" (``cv2.HOUGH_GRADIENT_ALT``: ``param2`` the
    "perfectness" in (0, 1]), radii in ``radius``, centres at least
    ``min_dist`` apart (default: the tutorial's rows / 16).

    >>> import numpy as np, cv2
    >>> img = np.full((200, 240), 40, np.uint8)
    >>> _ = cv2.circle(img, (120, 90), 30, 220, -1)
    >>> [round(v) for v in hough_circles(img, "alt", 1.5, 300, 0.9, radius=(10, 60))[0]]
    [120, 90, 30]
    """
    g = grey(scene)
    if blur:
        g = cv2.medianBlur(g, int(blur))
    kind = cv2.HOUGH_GRADIENT_ALT if method == "alt" else cv2.HOUGH_GRADIENT
    md = g.shape[0] / 16.0 if min_dist is None else float(min_dist)
    out = cv2.HoughCircles(g, kind, float(dp), md, param1=float(param1), param2=float(param2),
                           minRadius=int(radius[0]), maxRadius=int(radius[1]))
    if out is None:
        return []
    return [(float(x), float(y), float(r)) for x, y, r in out.reshape(-1, out.shape[-1])[:, :3]]


def segment_angle(x1: float, y1: float, x2: float, y2: float) -> float:
    """Direction of a segment in degrees [0, 180), counter-clockwise from +x
    as displayed (y down), seahough's ``line_angle`` convention.

    >>> segment_angle(0, 10, 0, 0), segment_angle(0, 0, 10, 0), round(segment_angle(0, 0, 10, -10))
    (90.0, 0.0, 45)
    """
    return math.degrees(math.atan2(-(y2 - y1), x2 - x1)) % 180.0


def hough_posts(scene, canny=(50, 150), threshold: int = 50, min_length: float = 40.0,
                max_gap: float = 10.0, max_tilt: float = 30.0, merge_px: float = 30.0,
                merge_angle: float = 5.0) -> list[tuple[float, float, float, float]]:
    """Upright posts from ``cv2.HoughLinesP``: ``(angle, x, y, strength)``,
    strongest first, each a line through ``(x, y)`` at ``angle`` (degrees,
    :func:`segment_angle`'s convention).

    Canny on the grey image after a sigma-1 Gaussian blur (as in OpenCV's
    Hough line tutorial and :func:`hough_rope`), ``cv2.HoughLinesP`` (1 px,
    1 degree, ``threshold`` votes, ``min_length``, ``max_gap``); segments
    within ``max_tilt`` degrees of vertical are kept and grouped, longest
    first: a segment joins a group when its direction is within
    ``merge_angle`` degrees and its line passes within ``merge_px`` pixels
    of the group's (at the group's mean height) -- the two borders of one
    post become one candidate. A group's line: the length-weighted mean of
    its segments' midpoints and directions; its strength: their total length.

    >>> import numpy as np, cv2
    >>> img = np.full((240, 320), 40, np.uint8)
    >>> _ = cv2.rectangle(img, (150, 20), (165, 220), 220, -1)
    >>> a, x, y, s = hough_posts(img)[0]
    >>> round(a), round(x), len(hough_posts(img))
    (90, 157, 1)
    """
    g = cv2.GaussianBlur(grey(scene), (0, 0), 1.0)
    e = cv2.Canny(g, float(canny[0]), float(canny[1]))
    segs = cv2.HoughLinesP(e, 1, math.pi / 180, int(threshold), minLineLength=float(min_length),
                           maxLineGap=float(max_gap))
    if segs is None:
        return []
    segs = segs.reshape(-1, 4).astype(float)
    length = np.hypot(segs[:, 2] - segs[:, 0], segs[:, 3] - segs[:, 1])
    groups: list[list] = []     # [sum_len, sum_len*mx, sum_len*my, sum_len*unit vector (dx, dy)]
    for i in np.argsort(-length):
        x1, y1, x2, y2 = segs[i]
        a = segment_angle(x1, y1, x2, y2)
        if abs(a - 90.0) > max_tilt:
            continue
        L = float(length[i])
        mx, my = 0.5 * (x1 + x2), 0.5 * (y1 + y2)
        u = np.array([math.cos(math.radians(a)), -math.sin(math.radians(a))])
        for grp in groups:
            ga = segment_angle(0.0, 0.0, grp[3][0], grp[3][1])
            gx, gy = grp[1] / grp[0], grp[2] / grp[0]
            # this segment's line at the group's height
            xa = mx + (gy - my) * (u[0] / u[1]) if abs(u[1]) > 1e-9 else math.inf
            if abs(ga - a) <= merge_angle and abs(xa - gx) <= merge_px:
                grp[0] += L
                grp[1] += L * mx
                grp[2] += L * my
                grp[3] = grp[3] + L * (u if u @ grp[3] >= 0 else -u)
                break
        else:
            groups.append([L, L * mx, L * my, L * u])
    out = [(segment_angle(0.0, 0.0, g_[3][0], g_[3][1]), float(g_[1] / g_[0]),
            float(g_[2] / g_[0]), float(g_[0])) for g_ in groups]
    return sorted(out, key=lambda t: -t[3])


def _local_peaks(r: np.ndarray, floor: float, k: int, cap: int):
    """(value, x, y) of the local maxima of ``r`` over a k x k window above ``floor``."""
    k = max(3, int(k) | 1)
    peak = (r >= cv2.dilate(r, np.ones((k, k), np.uint8))) & (r >= floor)
    ys, xs = np.nonzero(peak)
    if xs.size > cap:
        top = np.argpartition(-r[ys, xs], cap)[:cap]
        ys, xs = ys[top], xs[top]
    return [(float(r[y, x]), int(x), int(y)) for y, x in zip(ys, xs)]


def match_template_multiscale(scene, template, scales, *, work_width: int = 320,
                              polarity: str = "either", floor: float = 0.3,
                              max_results: int = 10, overlap: float = 0.5):
    """Multi-scale ``cv2.matchTemplate`` (TM_CCOEFF_NORMED): ``(score, x, y,
    scale)`` best first, ``(x, y)`` the template centre in full-resolution
    pixels, ``scale`` the template's size relative to ``template`` at full
    resolution.

    The grey scene is shrunk (INTER_AREA) to ``work_width`` px wide (never
    enlarged) and the template resized to each of ``scales`` times that
    factor (templates under 4 px or larger than the scene skipped).
    ``polarity``: "bright" (the template as given), "dark" (inverted: the
    negated correlation) or "either" (its absolute value). Local maxima
    above ``floor`` (at most 50 per scale), then greedy non-maximum
    suppression over all scales: a match is dropped when its centre lies
    within ``overlap`` x the smaller of the two templates' sides of a better
    one.

    >>> import numpy as np, cv2
    >>> t = np.full((41, 41), 30, np.uint8); _ = cv2.circle(t, (20, 20), 12, 230, -1)
    >>> img = np.full((240, 320), 40, np.uint8); _ = cv2.circle(img, (200, 100), 24, 220, -1)
    >>> s, x, y, sc = match_template_multiscale(img, t, [1.0, 1.5, 2.0])[0]
    >>> round(x), round(y), sc
    (200, 100, 2.0)
    """
    g = grey(scene)
    h, w = g.shape
    f = min(1.0, work_width / float(w))
    if f < 1.0:
        g = cv2.resize(g, (max(1, round(w * f)), max(1, round(h * f))),
                       interpolation=cv2.INTER_AREA)
    g = g.astype(np.float32)
    t0 = grey(template).astype(np.float32)
    th0, tw0 = t0.shape
    found = []
    for s in scales:
        tw, th = round(tw0 * s * f), round(th0 * s * f)
        if min(tw, th) < 4 or tw > g.shape[1] or th > g.shape[0]:
            continue
        t = cv2.resize(t0, (tw, th),
                       interpolation=cv2.INTER_AREA if s * f < 1 else cv2.INTER_LINEAR)
        if float(t.std()) < 1e-3:
            continue
        r = cv2.matchTemplate(g, t, cv2.TM_CCOEFF_NORMED)
        if polarity == "either":
            r = np.abs(r)
        elif polarity == "dark":
            r = -r
        side = min(tw, th)
        for v, x, y in _local_peaks(r, floor, side // 2, 50):
            cx = (x + (tw - 1) / 2.0 + 0.5) / f - 0.5
            cy = (y + (th - 1) / 2.0 + 0.5) / f - 0.5
            found.append((v, cx, cy, float(s), side / f))
    found.sort(key=lambda t_: -t_[0])
    kept = []
    for v, x, y, s, side in found:
        if all(math.hypot(x - kx, y - ky) >= overlap * min(side, ks)
               for _, kx, ky, _, ks in kept):
            kept.append((v, x, y, s, side))
            if len(kept) >= max_results:
                break
    return [(v, x, y, s) for v, x, y, s, _ in kept]


def _ght_worker_opts(conn, opts):
    """:func:`_ght_worker` with some of Guil's settings replaced (``opts``:
    canny (low, high), angle_thresh, scale_thresh, pos_thresh, scale_step)."""
    global GHT_CANNY, GHT_SCALE_STEP
    GHT_CANNY = tuple(opts.get("canny", GHT_CANNY))      # this worker process only
    GHT_SCALE_STEP = float(opts.get("scale_step", GHT_SCALE_STEP))
    make = _ght_make

    def patched(scale_range, angle_range):
        g = make(scale_range, angle_range)
        g.setAngleThresh(int(opts.get("angle_thresh", 1500)))
        g.setScaleThresh(int(opts.get("scale_thresh", 50)))
        g.setPosThresh(int(opts.get("pos_thresh", 10)))
        return g

    globals()["_ght_make"] = patched
    _ght_worker(conn)


class GHTGuilOpts(GHTGuil):
    """:class:`GHTGuil` with its Canny thresholds, vote thresholds and scale
    step set per instance (``canny=(lo, hi)``, ``angle_thresh``,
    ``scale_thresh``, ``pos_thresh``, ``scale_step``), e.g. to tune them;
    the defaults are :class:`GHTGuil`'s. The settings change only in the
    worker process.

    >>> g = GHTGuilOpts(canny=(30, 90), pos_thresh=5); g.opts["canny"]
    (30, 90)
    """

    def __init__(self, timeout: float = 5.0, downscale: float = GHT_DOWNSCALE, **opts):
        super().__init__(timeout, downscale)
        self.opts = dict(opts)

    def _start(self):
        a, b = self._ctx.Pipe()
        self._proc = self._ctx.Process(target=_ght_worker_opts, args=(b, self.opts), daemon=True)
        self._proc.start()
        self._conn = a
        if self._template is not None:
            self._send_template()
