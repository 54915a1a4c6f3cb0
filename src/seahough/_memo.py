"""A bounded, thread-safe memo of computed values (a pattern's features per
working scale, a Detector's edge gap per working scale).

A pattern searched in images of ever new sizes (a docking tracker's region
of interest, cropped around the marker's last place) gets a new working
scale each time: kept without bound, their features grew a long-lived
Detector's memory by about 13 kB a frame (470 MB an hour at 10 Hz). The
least recently used values beyond :data:`MAX_ENTRIES` are dropped (and
computed again if asked for).
"""

from __future__ import annotations

import threading
from collections import OrderedDict

__all__ = ["Memo", "MAX_ENTRIES"]

#: Values a :class:`Memo` keeps by default (a search of one image size uses
#: a handful: features, finishing points, the edge gap at its scale).
MAX_ENTRIES = 48

_MISSING = object()


class Memo:
    """``key -> value``, at most ``max_entries`` of them, least recently used
    dropped first.

    Examples
    --------
    >>> m = Memo(2)
    >>> m.get_or_compute("a", lambda: 1), m.get_or_compute("b", lambda: 2)
    (1, 2)
    >>> m.get_or_compute("a", lambda: 99)      # kept: not computed again
    1
    >>> _ = m.get_or_compute("c", lambda: 3)   # "b", the least recently used, goes
    >>> sorted(m.keys()), len(m)
    (['a', 'c'], 2)
    """

    def __init__(self, max_entries: int = MAX_ENTRIES):
        self.max_entries = int(max_entries)
        self._d: OrderedDict = OrderedDict()
        self._lock = threading.Lock()

    def get_or_compute(self, key, compute):
        """The value of ``key``, computed by ``compute()`` when not kept.
        (Two threads may both compute it: the same value, the first kept.)"""
        with self._lock:
            v = self._d.get(key, _MISSING)
            if v is not _MISSING:
                self._d.move_to_end(key)
                return v
        v = compute()
        with self._lock:
            kept = self._d.setdefault(key, v)
            self._d.move_to_end(key)
            while len(self._d) > self.max_entries:
                self._d.popitem(last=False)
        return kept

    def __getstate__(self):      # (a lock is not pickled: a Pattern sent to a worker)
        with self._lock:
            return self.max_entries, list(self._d.items())

    def __setstate__(self, state):
        self.max_entries, items = state
        self._d = OrderedDict(items)
        self._lock = threading.Lock()

    def __copy__(self):
        new = Memo(self.max_entries)
        with self._lock:
            new._d = OrderedDict(self._d)
        return new

    def __contains__(self, key) -> bool:
        with self._lock:
            return key in self._d

    def __len__(self) -> int:
        return len(self._d)

    def keys(self) -> list:
        with self._lock:
            return list(self._d)

    def clear(self) -> None:
        with self._lock:
            self._d.clear()
