"""Where the shared real-data folder lives (``../shared/data`` beside a checkout)."""

from __future__ import annotations

import os
from pathlib import Path


def shared_data_dir() -> Path | None:
    """The folder of real underwater photos, or None when it is absent.

    Looked for in ``$SEAHOUGH_DATA``, then ``../shared/data`` relative to the
    working directory and to each parent of this package's source tree.
    """
    env = os.environ.get("SEAHOUGH_DATA")
    if env:
        p = Path(env)
        return p if p.is_dir() else None
    starts = [Path.cwd(), *Path(__file__).resolve().parents]
    for start in starts:
        for base in (start, *start.parents[:2]):
            cand = base / ".." / "shared" / "data"
            if cand.is_dir():
                return cand.resolve()
            cand = base / "shared" / "data"
            if cand.is_dir() and (cand / "README.md").is_file():
                return cand.resolve()
    return None
