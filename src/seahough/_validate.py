"""Parameter checks shared by the public entry points.

Every check raises :class:`~seahough.errors.ParameterError` with a message
that names the parameter, its value and what it must be.
"""

from __future__ import annotations

import math
import numbers
import os

from .errors import ParameterError


def number(name: str, value, *, lo: float | None = None, hi: float | None = None,
           lo_open: bool = False, hi_open: bool = False, integer: bool = False) -> float:
    """``value`` as a finite float (or int) within [lo, hi]; ParameterError if not.

    Python and numpy numbers are accepted; bools, strings and None are not.

    Examples
    --------
    >>> number("min_score", 0.5, lo=0, hi=1)
    0.5
    """
    kind = "an integer" if integer else "a number"
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ParameterError(f"{name}={value!r}: must be {kind}")
    if integer and not isinstance(value, numbers.Integral):
        raise ParameterError(f"{name}={value!r}: must be {kind}")
    v = int(value) if integer else float(value)
    if not math.isfinite(v):
        raise ParameterError(f"{name}={value!r}: must be finite")
    too_low = lo is not None and (v <= lo if lo_open else v < lo)
    too_high = hi is not None and (v >= hi if hi_open else v > hi)
    if too_low or too_high:
        if hi is None:
            want = f"{'>' if lo_open else '>='} {lo:g}"
        elif lo is None:
            want = f"{'<' if hi_open else '<='} {hi:g}"
        else:
            want = f"in {'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"
        raise ParameterError(f"{name}={value!r}: must be {want}")
    return v


def pair(name: str, value) -> tuple[float, float]:
    """A (low, high) pair of finite numbers with low <= high."""
    if isinstance(value, (str, bytes)):
        raise ParameterError(f"{name}={value!r}: expected a (low, high) pair")
    try:
        items = list(value)
    except TypeError:
        raise ParameterError(f"{name}={value!r}: expected a (low, high) pair") from None
    if len(items) != 2:
        raise ParameterError(f"{name}={value!r}: expected a (low, high) pair, "
                             f"got {len(items)} values")
    a = number(f"{name}[0]", items[0])
    b = number(f"{name}[1]", items[1])
    if b < a:
        raise ParameterError(f"{name}={value!r}: low must be <= high{_turn_hint(name, a, b)}")
    return a, b


def _turn_hint(name: str, a: float, b: float, form: str = "({}, {})") -> str:
    """For a rotation range given across 0 (350, 10: more than half a turn
    back): how to say it (each pair in ``form``); a plain swap (10, 5) gets
    none."""
    if "angle" not in name or not (0 <= b < a < 360) or a - b <= 180:
        return ""
    return (f" (the turns from {a:g} through 0 to {b:g} degrees are "
            f"{form.format(f'{a:g}', f'{b + 360:g}')} or {form.format(f'{a - 360:g}', f'{b:g}')})")


def default_workers() -> int:
    """All the cores this process may use (its CPU affinity mask where the
    OS has one): the default number of workers of every command and function
    that takes ``workers``.

    >>> default_workers() >= 1
    True
    """
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - macOS, Windows
        return max(1, os.cpu_count() or 1)


def check_workers(workers) -> int:
    """``workers`` as a positive int (None: :func:`default_workers`); a
    ParameterError naming it otherwise.

    >>> check_workers(2), check_workers(None) == default_workers()
    (2, True)
    """
    if workers is None:
        return default_workers()
    return int(number("workers", workers, lo=1, integer=True))


def check_max_nfa(value) -> float:
    """``max_nfa`` as a float > 0 (``math.inf``: no limit); ParameterError if not.

    >>> check_max_nfa(1), check_max_nfa(float("inf"))
    (1.0, inf)
    """
    if isinstance(value, numbers.Real) and not isinstance(value, bool) and value == math.inf:
        return math.inf
    return number("max_nfa", value, lo=0.0, lo_open=True)


def _a_list(name: str, value) -> None:
    """``value`` is None or a list (filled by the call: ``declined=[]``).

    >>> _a_list("declined", 5)
    Traceback (most recent call last):
    ...
    seahough.errors.ParameterError: declined=5: expected a list to fill (e.g. declined=[]), or None
    """
    if value is not None and not isinstance(value, list):
        raise ParameterError(f"{name}={value!r}: expected a list to fill (e.g. {name}=[]), or None")
