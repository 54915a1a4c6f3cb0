"""The images of a survey: files, folders and ``@LIST`` files, expanded in order.

A survey of 100,000 photos cannot pass them on a command line (a shell's
argument limit is far lower), hence ``@LIST.txt``: a file of paths, one a
line.

>>> import tempfile, os
>>> with tempfile.TemporaryDirectory() as d:
...     for name in ("f10.png", "f2.png", "notes.txt"):
...         _ = open(os.path.join(d, name), "w").close()
...     _ = open(os.path.join(d, "list.txt"), "w").write("a.jpg\\n\\nb.jpg\\n")
...     found = expand_inputs([d, "x.jpg", "@" + os.path.join(d, "list.txt")])
>>> [os.path.basename(p) for p in found]
['f2.png', 'f10.png', 'x.jpg', 'a.jpg', 'b.jpg']
"""

from __future__ import annotations

import os
from pathlib import Path

from ..errors import ParameterError
from ..io.frames import IMAGE_EXTENSIONS, VIDEO_EXTENSIONS, list_frames, printable

__all__ = ["expand_inputs"]


def _read_list(spec: str) -> list[str]:
    """The paths of a ``@LIST`` file: one a line, blank lines skipped."""
    path = spec[1:]
    if not path:
        raise ParameterError("'@': give a list file after the @ (@LIST.txt: one path a line)")
    try:
        # (any bytes: a name that is not UTF-8 comes back as the OS spells it)
        with open(path, encoding="utf-8", errors="surrogateescape", newline=None) as f:
            lines = f.read().split("\n")
    except FileNotFoundError:
        raise ParameterError(f"{printable(spec)}: no such list file") from None
    except OSError as e:
        raise ParameterError(f"{printable(spec)}: cannot read the list file "
                             f"({e.strerror or e})") from None
    return [line for line in lines if line.strip()]


def _expand_one(entry: str, out: list[str]) -> None:
    suffix = Path(entry).suffix.lower()
    if suffix in VIDEO_EXTENSIONS:
        raise ParameterError(f"{printable(entry)}: a video; a survey reads image files "
                             "(extract the frames first, e.g. with ffmpeg)")
    # only a name without an image extension can be a folder to expand (no
    # file-system call for each of 100,000 photos); a missing or unreadable
    # image is reported in its row, not here
    if suffix not in IMAGE_EXTENSIONS and os.path.isdir(entry):
        out.extend(list_frames(entry))
    else:
        out.append(entry)


def expand_inputs(inputs) -> list[str]:
    """The image paths of a survey, in order.

    Parameters
    ----------
    inputs : path or list of paths
        Image files (kept as given, in the order given: one that is missing
        or unreadable gets an ``error`` row in the results), folders (their
        image files, in :func:`~seahough.io.frames.list_frames` order: by the
        timestamps in their names when every name has one, else natural
        name order) and ``@LIST`` files (``@dive/list.txt``: one image or
        folder path a line, relative paths from the current folder, blank
        lines skipped). A path starting with ``@`` is always a list file:
        write ``./@name.jpg`` for an image so named.

    Returns
    -------
    list of str
        One entry per image; the same file given twice is two entries.

    Raises
    ------
    ParameterError
        No images at all, a list file that cannot be read, a folder
        without images, or a video.
    """
    if isinstance(inputs, (str, os.PathLike)):
        inputs = [inputs]
    try:
        items = [os.fspath(i) for i in inputs]
    except TypeError:
        raise ParameterError(f"images: expected paths, folders or @LIST files, "
                             f"got {inputs!r:.80}") from None
    out: list[str] = []
    for item in items:
        if item.startswith("@"):
            for line in _read_list(item):
                _expand_one(line, out)
        else:
            _expand_one(item, out)
    if not out:
        raise ParameterError("no input images (give image files, folders or @LIST.txt files)")
    return out
