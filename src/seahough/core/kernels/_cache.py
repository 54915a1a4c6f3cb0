"""Where Numba keeps the compiled kernels, wherever seahough is installed.

Numba caches a ``cache=True`` function in the first writable place of: the
folder in ``NUMBA_CACHE_DIR`` (``numba.config.CACHE_DIR``), the
``__pycache__`` beside its source, the user's cache folder under HOME
(``~/.cache/numba``); with none writable, defining the function raises
``RuntimeError: cannot cache function ...: no locator available``. That is
the case of a system or container install run by a service user, so
:func:`kernel_cache` picks the place before the kernels are defined:

1. Numba's own choice when it has one (a ``NUMBA_CACHE_DIR`` the user set
   is kept as it is);
2. else a folder of this user's own under :func:`tempfile.gettempdir`
   (``seahough-numba-<uid>``, mode 0700), said once with a
   :class:`KernelCacheWarning`;
3. else no cache: the kernels are compiled in every process (about 10 s),
   said once too.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
import warnings

import numba
from numba.core.caching import FunctionCache


#: Whether the kernels are defined with ``cache=True`` (set by :func:`kernel_cache`).
CACHE = True


class KernelCacheWarning(UserWarning):
    """The compiled kernels cannot be cached where Numba looks: they are
    cached in a private temporary folder, or not at all."""


def _probe():  # pragma: no cover - never called, only located
    """A function beside the kernels: Numba finds its cache as theirs."""


def cache_path() -> str | None:
    """Where Numba, as configured now, would cache a function defined beside
    the kernels: the same search as for a kernel, without compiling anything.

    Returns
    -------
    str or None
        The folder, or None when Numba finds no writable place (defining a
        ``cache=True`` kernel would then raise "no locator available").
    """
    try:
        return FunctionCache(_probe).cache_path
    except (RuntimeError, OSError):
        return None


def private_dir(base: str | None = None) -> str | None:
    """A folder of this user's own for the cache, created if needed.

    Numba unpickles what it finds in its cache, so the folder is used only
    when it is a real folder (not a link), owned by this user and writable
    by no one else.

    Parameters
    ----------
    base : str, optional
        Where to make it; default :func:`tempfile.gettempdir`.

    Returns
    -------
    str or None
        ``<base>/seahough-numba-<uid>``, or None when it cannot be made or is
        not private.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as base:
    ...     private_dir(base) == private_dir(base) != None
    True
    """
    try:
        uid = os.getuid() if hasattr(os, "getuid") else None
        if uid is None:  # pragma: no cover - Windows
            import getpass

            uid = getpass.getuser()
        path = os.path.join(base or tempfile.gettempdir(), f"seahough-numba-{uid}")
        try:
            os.mkdir(path, 0o700)
        except FileExistsError:
            pass
        st = os.lstat(path)
    except (OSError, KeyError, ImportError):
        return None
    if not stat.S_ISDIR(st.st_mode):
        return None
    if hasattr(os, "getuid") and (st.st_uid != os.getuid() or st.st_mode & 0o022):
        return None
    return path


def _say(message: str) -> None:
    # filed under "seahough" with no source line: one line on stderr
    warnings.warn_explicit(message, KernelCacheWarning, "seahough", 0, module="seahough")


@contextlib.contextmanager
def kernel_cache():
    """Choose where the kernels defined in this context are cached.

    Numba's own choice (a ``NUMBA_CACHE_DIR`` the user set, the package
    folder, HOME) is kept. Without one, :func:`private_dir` is set as
    ``numba.config.CACHE_DIR`` for the context and the setting restored
    after, so that other libraries keep theirs; without that either, the
    kernels are not cached. Either fallback is said once, with a
    :class:`KernelCacheWarning`.

    Yields
    ------
    str or None
        The folder the kernels' cache goes to, or None (no cache); the
        kernels read :data:`CACHE` for their ``cache=``.
    """
    global CACHE
    before = numba.config.CACHE_DIR
    try:
        where = _locate(before)
        CACHE = where is not None
        yield where
    finally:
        numba.config.CACHE_DIR = before


def _locate(before: str) -> str | None:
    where = cache_path()
    if where is not None:
        return where
    here = os.path.dirname(os.path.abspath(__file__))
    why = (f"cannot write Numba's cache beside the package ({here})"
           f"{', in NUMBA_CACHE_DIR' if before else ''} or under HOME")
    folder = private_dir()
    if folder is not None:
        numba.config.CACHE_DIR = folder
        where = cache_path()
        if where is not None:
            _say(f"{why}; caching the compiled kernels in {folder} "
                 "(set NUMBA_CACHE_DIR to choose)")
            return where
        numba.config.CACHE_DIR = before
    _say(f"{why}, nor in the temporary folder: the kernels are compiled anew in every "
         "process, about 10 s (set NUMBA_CACHE_DIR to a writable folder)")
    return None
