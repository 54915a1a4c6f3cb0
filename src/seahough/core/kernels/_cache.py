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

A wheel built by ``pip install .`` carries the kernels compiled (``setup.py``
runs :mod:`seahough._warmup` in the build), in the ``__pycache__`` beside
them. When Numba's cache is elsewhere (a read-only install: HOME or the
private folder above; or a ``NUMBA_CACHE_DIR``), :func:`seed_cache` first
copies those files there, once, so that such an install starts without
compiling too.
"""

from __future__ import annotations

import contextlib
import glob
import hashlib
import os
import pickle
import shutil
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
        if where is not None:
            seed_cache(where)
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


# --------------------------------------------------------------------------- shipped cache
def _index_stamp(path: str):
    """``(numba version, source stamp)`` of a Numba cache index, or None
    when it cannot be read."""
    try:
        with open(path, "rb") as f:
            version = pickle.load(f)
            stamp = pickle.loads(f.read())[0]
    except Exception:  # noqa: BLE001 - a missing, partial or foreign file: not usable
        return None
    return version, stamp


def _copy(src: str, dst: str) -> None:
    """``src`` to ``dst``, atomically (a process reading ``dst`` meanwhile
    sees the old file or the new one)."""
    fd, tmp = tempfile.mkstemp(dir=os.path.dirname(dst), prefix=".seed-")
    try:
        with os.fdopen(fd, "wb") as out, open(src, "rb") as inp:
            shutil.copyfileobj(inp, out)
        os.replace(tmp, dst)
    except BaseException:
        with contextlib.suppress(OSError):
            os.remove(tmp)
        raise


def seed_cache(cache_dir: str, kernels_dir: str | None = None) -> int:
    """Copy the compiled kernels shipped in ``<kernels_dir>/__pycache__``
    into ``cache_dir``, the folder Numba caches those kernels in now.

    A kernel's files are copied when the shipped index is valid for its
    source file as it is (Numba's version, the sha256 of the source, as
    Numba stamps them) and ``cache_dir`` has no valid index of its own for
    it; so it happens once, and never replaces what Numba compiled there.
    Nothing to copy, or a folder that cannot be written, is not an error.

    Parameters
    ----------
    cache_dir : str
        Where Numba looks for the kernels' cache (see :func:`cache_path`).
    kernels_dir : str, optional
        The folder of the kernels' sources; default this one.

    Returns
    -------
    int
        The number of kernels whose cache files were copied.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as nothing_shipped, \\
    ...      tempfile.TemporaryDirectory() as cache:
    ...     seed_cache(cache, nothing_shipped)
    0
    """
    here = os.path.abspath(kernels_dir or os.path.dirname(__file__))
    shipped = os.path.join(here, "__pycache__")
    if os.path.abspath(cache_dir) == shipped:
        return 0
    copied = 0
    hashes: dict[str, bytes | None] = {}
    for index in sorted(glob.glob(os.path.join(glob.escape(shipped), "*.nbi"))):
        name = os.path.basename(index)
        source = os.path.join(here, name.partition(".")[0] + ".py")
        if source not in hashes:
            try:
                with open(source, "rb") as f:
                    hashes[source] = hashlib.sha256(f.read()).digest()
            except OSError:
                hashes[source] = None
        valid = (numba.__version__, hashes[source])
        if hashes[source] is None or _index_stamp(index) != valid:
            continue
        target = os.path.join(cache_dir, name)
        if _index_stamp(target) == valid:
            continue
        base = name[:-len(".nbi")]
        try:
            for data in glob.glob(os.path.join(glob.escape(shipped), base + ".*.nbc")):
                _copy(data, os.path.join(cache_dir, os.path.basename(data)))
            _copy(index, target)        # last: the index names the data files
        except OSError:
            return copied
        copied += 1
    return copied
