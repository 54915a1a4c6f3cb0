"""The exceptions seahough raises.

Every error a user can cause is one of these, so a script can catch
:class:`SeahoughError` and know it was given bad input rather than hit a bug.
The classes also derive from the matching built-in (``ValueError``,
``OSError``) so that generic handlers keep working.

Hierarchy::

    SeahoughError
    ├── ImageError                (ValueError)  the image is unusable
    │   ├── ImageReadError        (OSError)     missing, unreadable or corrupt file
    │   ├── ImageSizeError                      empty, too small, or too large
    │   └── ImageValueError                     wrong shape/dtype, NaN or inf
    ├── PatternError              (ValueError)  the pattern cannot be searched for
    ├── ParameterError            (ValueError)  a parameter is out of range
    └── WriteError                (OSError)     a file or folder cannot be written

and two warnings (``UserWarning``): :class:`BitDepthWarning`, a 16-bit image
whose values fit in fewer bits, read as 16-bit data; :class:`LevelsWarning`, a
float image whose values look like another scale than 0-1 or 0-255.
"""

from __future__ import annotations


class SeahoughError(Exception):
    """Base class of every error seahough raises on bad input."""


class ImageError(SeahoughError, ValueError):
    """The image cannot be used (see the subclasses)."""


class ImageReadError(ImageError, OSError):
    """The file is missing, unreadable, not an image, or corrupt."""


class ImageSizeError(ImageError):
    """The image is empty, too small to hold edges, or larger than the pixel limit."""


class ImageValueError(ImageError):
    """The array has an unsupported shape or dtype, or holds NaN/inf."""


class PatternError(SeahoughError, ValueError):
    """The pattern cannot be searched for (no edges, degenerate shape...)."""


class ParameterError(SeahoughError, ValueError):
    """A parameter is out of range or contradicts another one."""


class WriteError(SeahoughError, OSError):
    """A file or folder cannot be written (unwritable folder, a folder in the way...)."""


class BitDepthWarning(UserWarning):
    """A uint16 image whose values all fit in fewer bits (a 10 or 12-bit
    camera's samples in 16-bit files), read as 16-bit data: 16 or 64 times
    too dark to show edges. Give ``Config(bit_depth=...)`` (CLI
    ``--bit-depth``). Said once a process for each number of bits."""


class LevelsWarning(UserWarning):
    """A float image whose values are taken as levels 0-255 but look like
    another scale: values under -0.5 (a -1..1 image), over 1024, or, for a
    float64 (or float16) image, at most 10 (too dark to show edges; a 0-1
    image with too many values over 1). Said once a process for each."""


def without_name(exc: BaseException, name) -> str:
    """The message of ``exc`` without a leading copy of the file ``name``
    (for a line that already starts with it), nor of ``image``, the name an
    array read from it was checked under.

    >>> without_name(ImageReadError("a.png: not an image"), "a.png")
    'not an image'
    >>> without_name(ImageSizeError("image: 968x5 is too small"), "strip.png")
    '968x5 is too small'
    """
    from pathlib import Path

    msg = str(exc)
    for prefix in (f"{name}: ", f"{Path(name)}: ", "image: "):
        if msg.startswith(prefix):
            return msg[len(prefix):]
    return msg


def warn_at_caller(message: str, category) -> None:
    """Warn as from the caller's own line: the first frame of the stack
    outside seahough (and outside the threads of the standard library that
    run its workers), as ``warnings.warn(stacklevel=...)`` would, whatever
    the depth of the call (a warning filed under "seahough:0" pointed at no
    line of the user's script); "seahough", line 0 when there is none (a
    worker thread's). Filter them by category (``warnings.filterwarnings(
    "ignore", category=seahough.BitDepthWarning)``): their module is the
    caller's."""
    import os
    import sys
    import warnings

    def where(path: str) -> str:
        return os.path.normcase(os.path.abspath(path))

    here = where(os.path.dirname(__file__)) + os.sep
    stdlib = getattr(warnings, "__file__", None)   # (None in some frozen builds)
    skip = (here,) if stdlib is None else (
        here, where(os.path.dirname(stdlib)) + os.sep + "threading.py",
        where(os.path.dirname(stdlib)) + os.sep + "concurrent")
    f = sys._getframe(1)
    while f is not None and where(f.f_code.co_filename).startswith(skip):
        f = f.f_back
    if f is None:
        warnings.warn_explicit(message, category, "seahough", 0, module="seahough")
        return
    g = f.f_globals
    name = f.f_code.co_filename
    kw = dict(module=g.get("__name__", "seahough"),
              registry=g.setdefault("__warningregistry__", {}))
    try:   # (the globals let the line be shown from a zipped module's source)
        warnings.warn_explicit(message, category, name, f.f_lineno, **kw,
                               module_globals=None if name.startswith("<") else g)
    except ImportError:   # (a loader that cannot give the source: python -c, the prompt)
        warnings.warn_explicit(message, category, name, f.f_lineno, **kw)


def interrupted(exc: BaseException, kind=KeyboardInterrupt) -> bool:
    """Is a ``kind`` (a KeyboardInterrupt) among the causes and contexts of ``exc``?

    Ctrl-C inside a compiled (Numba) kernel surfaces as a SystemError caused
    by the KeyboardInterrupt (raised while the kernel's results are converted).

    >>> try:
    ...     try:
    ...         raise KeyboardInterrupt
    ...     except KeyboardInterrupt as ki:
    ...         raise SystemError("returned a result with an exception set") from ki
    ... except SystemError as e:
    ...     interrupted(e), interrupted(e, OSError)
    (True, False)
    """
    seen = set()
    todo = [exc]
    while todo:
        e = todo.pop()
        if e is None or id(e) in seen:
            continue
        if isinstance(e, kind):
            return True
        seen.add(id(e))
        todo += [e.__cause__, e.__context__]
    return False


__all__ = [
    "SeahoughError",
    "ImageError",
    "ImageReadError",
    "ImageSizeError",
    "ImageValueError",
    "PatternError",
    "ParameterError",
    "WriteError",
]
