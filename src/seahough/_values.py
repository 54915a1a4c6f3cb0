"""Equality of the result dataclasses whose fields hold numpy arrays.

A dataclass's own ``==`` compares its fields as a tuple, and a numpy array
field makes that raise ("The truth value of an array with more than one
element is ambiguous"): ``detection_a == detection_b`` failed for equal
detections. :class:`ValueEquality` compares field by field, arrays by
value (NaN equal to NaN, as in a result compared with itself).
"""

from __future__ import annotations

import math
from dataclasses import fields

import numpy as np

__all__ = ["ValueEquality", "same_value", "json_safe"]


def same_value(a, b) -> bool:
    """Whether two field values are equal: arrays by value, lists and tuples
    item by item, floats with NaN equal to NaN.

    >>> same_value(np.eye(2), np.eye(2)), same_value([np.zeros(2)], [np.ones(2)])
    (True, False)
    >>> same_value(float("nan"), float("nan")), same_value((1, "a"), (1, "a"))
    (True, True)
    """
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        if a.shape != b.shape:
            return False
        nan_ok = a.dtype.kind in "fc" and b.dtype.kind in "fc"
        return bool(np.array_equal(a, b, equal_nan=nan_ok))
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(same_value(x, y) for x, y in zip(a, b))
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return bool(a == b)


class ValueEquality:
    """Mixin of a ``@dataclass(eq=False)``: ``==`` field by field
    (:func:`same_value`), only between objects of one class; unhashable, as
    a mutable dataclass with ``==`` is.

    >>> from dataclasses import dataclass
    >>> @dataclass(eq=False)
    ... class Pose(ValueEquality):
    ...     name: str
    ...     matrix: np.ndarray
    >>> Pose("a", np.eye(2)) == Pose("a", np.eye(2)), Pose("a", np.eye(2)) == Pose("b", np.eye(2))
    (True, False)
    """

    __hash__ = None  # type: ignore[assignment]

    def __eq__(self, other):
        if other.__class__ is not self.__class__:
            return NotImplemented
        return all(same_value(getattr(self, f.name), getattr(other, f.name))
                   for f in fields(self))


def json_safe(obj):
    """``obj`` with every float that is not finite (an NFA not judged, an
    unlimited ``max_nfa``) as None, through dicts, lists and tuples: JSON has
    no Infinity or NaN (Python writes them, and ``jq``, JavaScript's
    ``JSON.parse`` and most other readers refuse the file).

    >>> json_safe({"max_nfa": float("inf"), "x": [1.5, float("nan")], "n": np.float32(2)})
    {'max_nfa': None, 'x': [1.5, None], 'n': 2.0}
    """
    if isinstance(obj, dict):
        return {k: json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, set, frozenset)):
        return [json_safe(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return json_safe(obj.tolist())
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj

