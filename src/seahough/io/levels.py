"""What a search makes of an image's levels, and the warnings when they
look like another scale than the one they are read as.

Float images in [0, 1] are scaled to 0-255 (:func:`_unit_levels`), other
floats are levels 0-255 as they are; a uint16 image is 16-bit data unless
its bit depth is given. Levels that are too dark to show most edges, or of
another scale (a -1..1 image, dB), are said once a process for each kind
(:class:`~seahough.errors.LevelsWarning`,
:class:`~seahough.errors.BitDepthWarning`), with the image's name.
"""

from __future__ import annotations

import numpy as np

from ..errors import BitDepthWarning, LevelsWarning, warn_at_caller


#: Float images in [0, 1] are scaled to 0-255; so are those within 1 of it (up
#: to :data:`OVERSHOOT`) with at most :data:`OVERSHOOT_SHARE` of their values
#: outside it, not whole numbers (colour correction's overshoot: saturated;
#: whole numbers are a dark 8-bit frame's levels), and those with a few hot
#: pixels far over it (at most :data:`HOT_SHARE` of the values, or 16) when
#: most of their values that are not 0 lie between 0 and 1 (a glint: one
#: pixel at 3 made a 0-1 frame levels 0-3 of 255, "not found" without a
#: word). A rope or a lit patch is more than a few pixels: a dark frame of
#: levels 0-255 with one is not taken for 0-1, nor read so twice. Values over
#: 1 saturate, as 1 does. Others are levels 0-255.
OVERSHOOT = 2.0
OVERSHOOT_SHARE = 0.05
HOT_SHARE = 0.001


def _unit_levels(a: np.ndarray, lo: float, hi: float) -> bool:
    """Whether float image ``a`` (its least and largest values ``lo``,
    ``hi``) holds 0-1 levels (see :data:`OVERSHOOT`).

    >>> img = np.full((10, 10), 0.5, np.float32); img[0, 0] = 1.02; img[1, 1] = -0.01
    >>> _unit_levels(img, -0.01, 1.02), _unit_levels(img * 255, -2.55, 260.1)
    (True, False)
    >>> dark = np.zeros((10, 10), np.float32); dark[0, :3] = 2.0   # (8-bit levels 0-2)
    >>> _unit_levels(dark, 0.0, 2.0)
    False
    >>> img[2, 2] = 3.0                                 # (a hot pixel)
    >>> _unit_levels(img, -0.01, 3.0), _unit_levels(dark + np.eye(10)[0] * 3, 0.0, 3.0)
    (True, False)
    """
    if lo < 1.0 - OVERSHOOT:
        return False
    if lo >= 0.0 and hi <= 1.0:
        return True
    flat = a.reshape(-1)
    # (levels 0-255, the usual case: most values over 1, seen in a sample, no copy)
    step = max(1, flat.size // 4096)
    if np.count_nonzero(flat[::step] > 1.0) > 2 * OVERSHOOT_SHARE * flat[::step].size:
        return False
    n_out = np.count_nonzero((a > 1.0) | (a < 0.0))
    if n_out > OVERSHOOT_SHARE * a.size:
        return False
    if hi <= OVERSHOOT:
        out = a[(a > 1.0) | (a < 0.0)]
        return bool(np.any(out != np.round(out)))
    if np.count_nonzero(a > OVERSHOOT) > max(16, HOT_SHARE * a.size):
        return False
    return bool(np.count_nonzero((a > 0.0) & (a < 1.0)) >= 0.5 * np.count_nonzero(a))


#: The kinds of float levels :class:`~seahough.errors.LevelsWarning` was given for.
_SAID_LEVELS: set = set()


#: A 0-1 float image whose largest value is under this (16 of 255 levels, as
#: a 16-bit file's 12-bit data: :func:`say_bits`) is too dark to show most
#: edges: linear sonar backscatter of 0-0.05 was "not found", without a word.
DIM_UNIT = 16.0 / 255.0


def say_levels(lo: float, hi: float, label: str, dim: bool = True,
               unit: bool = False) -> None:
    """Warn, once a process for each kind, that a float image taken as levels
    0-255 (values ``lo`` to ``hi``) looks like another scale: values under
    -0.5 (a -1..1 image), over 1024, or (``dim``: not for float32, the
    package's own levels) a largest value of at most 10 (a dark frame, or a
    0-1 image with too many values over 1 to be read as one); ``unit``: a
    0-1 image read so, whose values reach only ``hi`` (under :data:`DIM_UNIT`),
    or with values far over 1 (over :data:`OVERSHOOT`)."""
    if unit and hi > OVERSHOOT:
        if "hot 0-1" not in _SAID_LEVELS:
            _SAID_LEVELS.add("hot 0-1")
            warn_at_caller(f"{label}: a 0-1 float image with a few values far over 1 (up to "
                           f"{hi:.3g}: hot pixels, a glint?), read as 0-1 (those saturate, as 1 "
                           "does)", LevelsWarning)
        return
    if unit:
        if "dim 0-1" in _SAID_LEVELS:
            return
        _SAID_LEVELS.add("dim 0-1")
        warn_at_caller(f"{label}: a 0-1 float image whose values reach only {hi:.3g} (levels up "
                       f"to {255.0 * hi:.3g} of 255: too dark to show most edges); stretch it "
                       "to 0-1 (numpy: image / image.max())", LevelsWarning)
        return
    if lo < -0.5:
        kind, why = "negative", f"values down to {lo:.3g}: below 0 is black"
    elif hi <= 10.0 and dim:
        kind, why = "dim", (f"values only up to {hi:.3g} of 255: too dark to show most edges "
                            f"(a 0-1 image is scaled only when at most "
                            f"{100 * OVERSHOOT_SHARE:g} % of its values are over 1, up to "
                            f"{OVERSHOOT:g})")
    elif hi > 1024.0:
        kind, why = "large", f"values up to {hi:.3g}: far over 255, every edge is strong"
    else:
        return
    if kind in _SAID_LEVELS:
        return
    _SAID_LEVELS.add(kind)
    warn_at_caller(f"{label}: a float image read as levels 0-255, {why}; scale it to 0-1 or "
                   "0-255", LevelsWarning)


#: The numbers of bits :class:`~seahough.errors.BitDepthWarning` was given for.
_SAID_BITS: set = set()


def say_bits(top: int, label: str) -> None:
    """Warn, once a process for each number of bits, that a uint16 image read as
    16-bit data has values of fewer bits (``top``: its largest, 1-4095)."""
    if not 0 < top < 4096:
        return
    bits = top.bit_length()
    if bits in _SAID_BITS:
        return
    _SAID_BITS.add(bits)
    if bits <= 8:
        what = "8-bit data in a 16-bit file? convert it to uint8 (numpy: .astype(np.uint8))"
    else:   # (a guess from its brightest value: a dark frame needs fewer bits)
        what = (f"a camera's 10-14-bit samples ({bits} bits hold these)? give its bit depth: "
                f"Config(bit_depth={max(bits, 10)}), CLI --bit-depth {max(bits, 10)} (a "
                f"12-bit camera: 12)")
    warn_at_caller(f"{label}: a 16-bit image whose values reach only {top}, read as 16-bit data "
                   f"(levels up to {top / 257.0:.3g} of 255: too dark to show most edges); {what}",
                   BitDepthWarning)
