"""The output folder of a dead-reckoning run, kept safe: one run at a time
(a lock), nothing left of a previous run, the run's settings beside its
rows, and ``resume`` continuing only the run it belongs to.

What a row of ``odometry.csv`` is checked against on ``resume``: the hash of
the settings that change rows (``settings_hash`` column, and ``run.json``
beside the CSV naming them), the frame's name resolved to a full path, and
a fingerprint of the frame's content (``frame_hash``).

>>> import tempfile
>>> with tempfile.TemporaryDirectory() as d:
...     with RunFolder(d) as run:
...         sorted(p.name for p in run.path.iterdir())
['.seahough.lock']
"""

from __future__ import annotations

import errno
import hashlib
import json
import math
import os
import stat
from dataclasses import asdict
from pathlib import Path

from ..config import config_record
from ..errors import ParameterError, SeahoughError, WriteError
from ..io.frames import split_video_ref, printable

try:                                  # POSIX; elsewhere runs are not locked
    import fcntl
except ImportError:                   # pragma: no cover
    fcntl = None

__all__ = ["RunFolder", "run_settings", "settings_hash", "settings_changes", "same_frame",
           "format_change", "check_kept_row", "open_track", "write_row", "write_output"]

#: Bumped when the rows a run writes change for the same settings (2: a pair
#: that cannot be measured gets a ``wide`` last try, and an assumed pose
#: carries the last velocity on; format 1 assumed zero motion; 3: the frames
#: of several videos are on one time line): a run of another format is not
#: continued by ``resume``.
SETTINGS_FORMAT = 3
#: What changed in the rows at each format (for the message refusing to
#: resume a run of an earlier one).
FORMAT_CHANGES = {2: "frames whose motion could not be measured now get a wider last search, "
                     "and their assumed pose carries the last velocity on instead of zero "
                     "motion",
                  3: "the frames of a second video are timed after the first's, not from 0 "
                     "again"}
LOCK_NAME = ".seahough.lock"
OUTPUTS = ("summary.json", "mosaic.png", "trajectory.png")


def run_settings(scale_range, angle_range, metres_per_pixel, config, tuning) -> dict:
    """Everything that changes a run's rows, as plain JSON values.

    >>> from seahough.config import ODOMETRY_CONFIG, OdometryTuning
    >>> s = run_settings((0.9, 1.1), (-20, 20), None, ODOMETRY_CONFIG, OdometryTuning())
    >>> s["scale_range"], s["angle_range"], s["metres_per_pixel"], s["format"]
    ([0.9, 1.1], [-20.0, 20.0], None, 3)
    """
    cfg = config_record(config)
    tune = asdict(tuning)
    if tune.get("max_nfa") == math.inf:   # (added later: runs made before can be resumed)
        tune.pop("max_nfa")
    return {"format": SETTINGS_FORMAT,
            "scale_range": [float(v) for v in scale_range],
            "angle_range": [float(v) for v in angle_range],
            "metres_per_pixel": None if metres_per_pixel is None else float(metres_per_pixel),
            "config": cfg, "tuning": tune}


def settings_hash(settings: dict) -> str:
    """16 hex digits naming ``settings`` (the same for equal settings).

    >>> settings_hash({"a": 1, "b": [0.5]}) == settings_hash({"b": [0.5], "a": 1})
    True
    """
    text = json.dumps(settings, sort_keys=True, separators=(",", ":"))
    return hashlib.blake2b(text.encode(), digest_size=8).hexdigest()


def _flat(d, prefix=""):
    for k, v in d.items():
        if isinstance(v, dict):
            yield from _flat(v, f"{prefix}{k}.")
        else:
            yield f"{prefix}{k}", v


def settings_changes(old: dict, new: dict) -> list[str]:
    """``"name old (now new)"`` for each setting that differs.

    >>> settings_changes({"scale_range": [0.9, 1.1], "tuning": {"min_score": 0.2}},
    ...                  {"scale_range": [0.8, 1.2], "tuning": {"min_score": 0.2}})
    ['scale_range [0.9, 1.1] (now [0.8, 1.2])']
    >>> settings_changes({"metres_per_pixel": 0.0025}, {"metres_per_pixel": 0.00375})
    ['metres_per_pixel 0.0025 (now 0.00375; given, or altitude / focal length in pixels)']
    >>> settings_changes({"fps": None}, {"fps": 5.0})
    ['fps not given (now 5.0)']
    >>> [c.split()[0] for c in settings_changes({"angle_range": [0, 1], "pattern": {"kind": "a"}},
    ...                                         {"angle_range": [0, 2], "pattern": {"kind": "b"}})]
    ['pattern.kind', 'angle_range']
    """
    a, b = dict(_flat(old)), dict(_flat(new))
    # (the pattern first: a survey of another pattern said "angle_range null (now
    # [0.0, 360.0]); ...; and 151 more", the pattern among the 151)
    keys = sorted(set(a) | set(b), key=lambda k: (not k.startswith("pattern"), k))
    def said(v):   # (JSON's "null" said "fps null (now 5.0)": not given)
        return "not given" if v is None else json.dumps(v)

    return [f"{k} {said(a.get(k))} (now {said(b.get(k))}{_HOW.get(k, '')})"
            for k in keys if a.get(k) != b.get(k)]


#: Where a recorded setting comes from, when the user gave it another way.
_HOW = {"metres_per_pixel": "; given, or altitude / focal length in pixels"}


def same_frame(old_name: str, old_cwd: str | None, new_name: str) -> bool:
    """Do two frame names (paths, ``video#k`` or an array's ``frame_00007``)
    name one frame? Paths are compared resolved: ``old_name`` from the folder
    ``old_cwd`` its run was started in (None: this one), ``new_name`` from here.

    >>> same_frame("a/b.png", os.getcwd(), os.path.abspath("a/b.png"))
    True
    >>> same_frame("a/b.png", "/elsewhere", "a/b.png")
    False
    """
    if old_name == new_name and (old_cwd is None or old_cwd == os.getcwd()):
        return True

    def resolved(name, cwd):
        ref = split_video_ref(name)
        base, k = ref if ref is not None else (name, None)
        return os.path.realpath(os.path.join(cwd or os.getcwd(), base)), k

    return resolved(old_name, old_cwd) == resolved(new_name, None)


def _reason(e: OSError) -> str:
    text = e.strerror or str(e)
    return text[:1].lower() + text[1:]


#: What each kind of run writes that no other kind does: a folder holding
#: one of another kind's is refused (``check_kind``).
_KIND_FILES = {"odometry": ("odometry.csv", "run.json"),
               "survey detect": ("survey.json", "images.parquet")}


def check_kind(path, kind: str) -> None:
    """ParameterError when the folder ``path`` holds another kind of run's
    results (a dead reckoning's odometry.csv, a survey's survey.json):
    nothing of two runs is mixed in one output folder.

    >>> import tempfile, pathlib
    >>> with tempfile.TemporaryDirectory() as d:
    ...     _ = (pathlib.Path(d) / "survey.json").write_text("{}")
    ...     check_kind(d, "survey detect")
    ...     try:
    ...         check_kind(d, "odometry")
    ...     except ParameterError as e:
    ...         print(str(e)[-60:])
    ...     
    results of a survey detect (survey.json): give another --out
    """
    for other, names in _KIND_FILES.items():
        if other == kind:
            continue
        found = next((n for n in names if (Path(path) / n).exists()), None)
        if found is not None:
            article = "an" if other[0] in "aeiou" else "a"
            raise ParameterError(f"{path}: holds the results of {article} {other} ({found}): "
                                 "give another --out")


class RunFolder:
    """The output folder of one run, created and locked (``fcntl.flock`` on
    ``.seahough.lock``, released when the run ends or its process dies).

    Parameters
    ----------
    path : path
        The folder (``run_odometry``'s ``out_dir``).

    Raises
    ------
    WriteError
        The folder cannot be created or written (a file in its place, no
        permission), or another run holds it.
    """

    def __init__(self, path):
        self.path = Path(path)
        self.csv = self.path / "odometry.csv"
        self.json = self.path / "summary.json"
        self.sidecar = self.path / "run.json"
        self._fd = None
        self._make()
        self._lock()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.release()
        return False

    def _make(self):
        try:
            self.path.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            blocker = next((p for p in (self.path, *self.path.parents)
                            if p.exists() and not p.is_dir()), None)
            why = f"{blocker} is a file" if blocker is not None else _reason(e)
            raise WriteError(f"{self.path}: cannot create the output folder ({why})") from None
        if not self.path.is_dir():
            raise WriteError(f"{self.path}: cannot create the output folder (a file is in the way)")

    def _lock(self):
        lock = self.path / LOCK_NAME
        try:
            self._fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as e:
            raise WriteError(f"{self.path}: cannot write in the output folder "
                             f"({_reason(e)})") from None
        if fcntl is None:
            return
        try:
            fcntl.flock(self._fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as e:
            if e.errno not in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                return                  # no locks on this file system: run unlocked
            try:
                pid = os.pread(self._fd, 32, 0).decode(errors="replace").strip()
            except OSError:
                pid = ""
            os.close(self._fd)
            self._fd = None
            who = f" (process {pid})" if pid.isdigit() else ""
            if pid.isdigit() and int(pid) == os.getppid():
                # a worker process started by the run that holds the folder ran the
                # script's own code again: a script without the __main__ guard
                raise WriteError(
                    f"{self.path}: a worker process of this run started the run again: "
                    "put the script's code under `if __name__ == \"__main__\":` (worker "
                    "processes import the script)") from None
            raise WriteError(f"{self.path}: another seahough run{who} is writing to this "
                             "folder; wait for it to end, or give another output folder") from None
        try:        # who holds it, for the message above (fixed width: no truncation)
            os.pwrite(self._fd, f"{os.getpid():<20}\n".encode(), 0)
        except OSError:
            pass

    def release(self):
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None

    def check_writable(self, path: Path):
        """A WriteError when ``path`` exists and may not be replaced: not a
        file, or read-only. Read-only means no write permission for this
        user (``os.access``) or no owner write bit (``stat.S_IWUSR``): the
        bit counts for root too, whom permissions do not stop."""
        try:
            st = os.stat(path)
        except FileNotFoundError:
            return
        except OSError as e:
            raise WriteError(f"{path}: cannot be replaced ({_reason(e)})") from None
        if not stat.S_ISREG(st.st_mode):
            raise WriteError(f"{path}: not a file; move it away or give another output folder")
        if not (st.st_mode & stat.S_IWUSR) or not os.access(path, os.W_OK):
            raise WriteError(f"{path}: the file is read-only; make it writable (chmod u+w) to "
                             "replace or continue it, or give another output folder")

    def clear_outputs(self):
        """Remove what a previous run wrote after its rows (summary and
        pictures), so that none of it is left beside this run's CSV."""
        for name in (*OUTPUTS, self.csv.name + ".part"):
            p = self.path / name
            try:
                p.unlink(missing_ok=True)
            except OSError as e:
                raise WriteError(f"{p}: cannot remove the previous run's file "
                                 f"({_reason(e)})") from None

    def write_settings(self, settings: dict, digest: str, extra: dict | None = None):
        """``run.json``: the settings and the folder the run was started in
        (and ``extra`` keys: a survey's frames), written whole or not at all
        (a temporary file renamed over it; like the CSV's rows it is
        flushed, not synced: a killed run keeps it)."""
        tmp = self.path / (self.sidecar.name + ".tmp")
        rec = {"settings_hash": digest, "cwd": os.getcwd(), "settings": settings, **(extra or {})}
        try:
            with open(tmp, "w") as f:
                json.dump(rec, f, indent=2)
                f.write("\n")
            os.replace(tmp, self.sidecar)
        except OSError as e:
            raise WriteError(f"{self.sidecar}: cannot write the run's settings "
                             f"({_reason(e)})") from None

    def read_settings(self) -> dict | None:
        """What :meth:`write_settings` wrote, or None (none, or damaged)."""
        try:
            rec = json.loads(self.sidecar.read_text())
        except (OSError, ValueError):
            return None
        ok = isinstance(rec, dict) and isinstance(rec.get("settings"), dict)
        return rec if ok else None

    def check_settings(self, settings: dict, digest: str) -> str | None:
        """ParameterError naming the settings that differ from those of the
        run in this folder (when ``run.json`` says); returns the folder that
        run was started in (to resolve its relative frame names), or None."""
        rec = self.read_settings()
        if rec is None:
            return None
        why = format_change(rec["settings"], settings)
        if why:
            raise ParameterError(f"{self.csv}: {why}; run without --resume to measure it again")
        if rec.get("settings_hash") != digest:
            changes = settings_changes(rec["settings"], settings)
            more = f"; and {len(changes) - 4} more" if len(changes) > 4 else ""
            raise ParameterError(
                f"{self.csv}: the run was made with other settings: {'; '.join(changes[:4])}"
                f"{more}. Resume with the run's settings, or run without --resume")
        cwd = rec.get("cwd")
        return cwd if isinstance(cwd, str) else None


def format_change(old: dict, new: dict) -> str:
    """Why a run of settings ``old`` cannot be continued by one of ``new``
    because a seahough of another row format made it ("" when the format is
    the same).

    >>> why = format_change({"format": 1}, {"format": 2})
    >>> why[:58]
    'the run was made by an earlier seahough (run format 1, now'
    >>> "instead of zero motion" in why
    True
    >>> format_change({"format": 2}, {"format": 2})
    ''
    """
    a, b = old.get("format"), new.get("format")
    if a == b:
        return ""
    if isinstance(a, int) and isinstance(b, int) and a < b:
        what = "; ".join(FORMAT_CHANGES[k] for k in range(a + 1, b + 1) if k in FORMAT_CHANGES)
        return (f"the run was made by an earlier seahough (run format {a}, now {b}"
                f"{': ' + what if what else ''})")
    return f"the run was made by another seahough (run format {json.dumps(a)}, now {b})"


def check_kept_row(csv_path, pos: int, row: dict, reader, digest: str, old_cwd) -> None:
    """ParameterError unless a row kept by ``resume`` is frame ``pos`` of
    ``reader``, unchanged, measured with the settings ``digest``.

    >>> import numpy as np
    >>> from seahough.io.frames import FrameReader
    >>> reader = FrameReader([np.zeros((8, 8))], 10 ** 6)
    >>> row = {"index": 0, "file": "frame_00000", "settings_hash": "ab",
    ...        "frame_hash": reader.fingerprint(0)}
    >>> check_kept_row("odometry.csv", 0, row, reader, "ab", None)     # this run's row
    >>> try:
    ...     check_kept_row("odometry.csv", 0, row, reader, "cd", None)
    ... except ParameterError as e:
    ...     print(str(e)[:52])
    odometry.csv: row 0 was measured with other settings
    """
    name = reader.name(pos)
    same = row["file"] == name if reader.is_array(pos) else same_frame(row["file"], old_cwd, name)
    if row["index"] != pos or not same:
        raise ParameterError(f"{csv_path}: row {pos} is frame {row['index']} "
                             f"{printable(row['file'])!r}, but frame {pos} here is "
                             f"{printable(name)!r}: not the same sequence (run without resume)")
    if row.get("settings_hash") is None or row.get("frame_hash") is None:
        raise ParameterError(f"{csv_path}: written by an older seahough, without what resume "
                             "checks (frame and settings hashes); run without --resume")
    if row["settings_hash"] != digest:
        raise ParameterError(f"{csv_path}: row {pos} was measured with other settings (scale or "
                             "angle range, metres per pixel, config or tuning) or by another "
                             "seahough; resume with the run's settings, or run without --resume")
    image = None
    if reader.is_video(pos):
        try:
            image = reader.raw(pos)
        except (OSError, ValueError):
            image = None
    if reader.fingerprint(pos, image) != row["frame_hash"]:
        raise ParameterError(f"{csv_path}: frame {pos} {printable(name)!r} changed since the "
                             "run measured it (its content differs): not the same frames; run "
                             "without --resume")


def open_track(path, mode: str):
    """``open(path, mode)`` for the CSV; a WriteError naming it.

    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as d:
    ...     try:
    ...         open_track(d, "w")              # a folder in the way
    ...     except WriteError as e:
    ...         print(str(e).replace(d, "DIR"))
    DIR: cannot write the track (is a directory)
    """
    try:
        return open(path, mode, newline="")
    except OSError as e:
        raise WriteError(f"{path}: cannot write the track ({_reason(e)})") from None


def write_row(f, path, write) -> None:
    """``write()`` then flush ``f`` (a row is on disk when its frame is done);
    a WriteError naming ``path`` (a full disk...)."""
    try:
        write()
        f.flush()
    except OSError as e:
        raise WriteError(f"{path}: cannot write the track ({_reason(e)})") from None


def write_output(path, make):
    """``make()``; an OSError of it a WriteError naming ``path``.

    >>> try:
    ...     write_output("mosaic.png", lambda: open("/", "w"))
    ... except WriteError as e:
    ...     print(e)
    mosaic.png: cannot write it (is a directory)
    """
    try:
        return make()
    except SeahoughError:
        raise
    except OSError as e:
        raise WriteError(f"{path}: cannot write it ({_reason(e)})") from None
