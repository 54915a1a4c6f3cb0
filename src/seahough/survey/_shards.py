"""The output folder of ``survey detect``: results in shards, a manifest, and
the two Parquet files made from them.

Layout of ``OUT``::

    survey.json          the manifest: settings, the inputs' count and hash,
                         state ("running", "stopped" or "complete") and counts
    images.parquet       one row per input image  (written when all are done)
    detections.parquet   one row per detection    (written when all are done)
    parts/inputs.parquet the input list (index, path), to name a difference
    parts/images-NNNNNN.parquet, parts/detections-NNNNNN.parquet
                         the results, a shard at a time as they come

A shard is written whole or not at all (a temporary file renamed), its
detections first and its images last: the images shard is the mark that
the shard is done. The images done are those of the images shards, so a
rerun searches only the others (none when the survey is complete), and a
killed run loses at most the results not yet in a shard. One run at a time
writes a folder (the lock of :class:`~seahough.motion.runfiles.RunFolder`).

>>> import tempfile
>>> with tempfile.TemporaryDirectory() as d:
...     with SurveyFolder(d) as f:
...         f.start({"a": 1}, ["x.png", "y.png"])
...         f.write_part([image_row(0, "x.png", "error", error="no such file")], [])
...         sorted(f.done())
set()
[0]
"""

from __future__ import annotations

import datetime
import hashlib
import json
import math
import os
from pathlib import Path

from .. import __version__
from ..errors import ParameterError, WriteError

try:
    import pyarrow as pa
    import pyarrow.compute as pc
    import pyarrow.parquet as pq
except ImportError:   # (a ParameterError: one line from the CLI, as for a missing Dask)
    raise ParameterError("the survey commands need pyarrow: pip install 'seahough[survey]'") \
        from None
from ..io.frames import printable
from ..motion.runfiles import RunFolder, check_kind, settings_changes, settings_hash

__all__ = ["SurveyFolder", "IMAGES_SCHEMA", "DETECTIONS_SCHEMA", "image_row", "FORMAT"]

#: Bumped when the files' layout or columns change (2: detections get
#: ``nfa``, and the settings ``max_nfa``; a survey of format 1 was made
#: without either and is not continued; 3: detections get ``pattern``, the
#: name of the pattern of a Detector of several; 4: images get ``left_out``
#: and the best candidate not reported, ``best_score``, ``best_nfa``,
#: ``declined``; 5: detections get ``segment``, a line's visible extent; 6:
#: and ``stretches``, the stretches of it seen, and ``width``, its band's).
FORMAT = 6
MANIFEST = "survey.json"
IMAGES = "images.parquet"
DETECTIONS = "detections.parquet"
PARTS = "parts"

#: images.parquet: one row per input image, in input order.
IMAGES_SCHEMA = pa.schema([
    ("index", pa.int64()),          # position in the input list (0-based)
    ("path", pa.string()),          # as given (folders expanded)
    ("status", pa.string()),        # "found", "not found" or "error"
    ("n_detections", pa.int32()),
    ("ms", pa.float64()),           # reading and searching it, on its worker
    ("width", pa.int32()),          # null when unreadable
    ("height", pa.int32()),
    ("note", pa.string()),          # why the search could not run ("" when it ran)
    ("error", pa.string()),         # why the image could not be read (null when it could)
    ("left_out", pa.int32()),       # candidates over min_score cut by max_results
    # nothing found: the best candidate not reported, and why (else null)
    ("best_score", pa.float64()), ("best_nfa", pa.float64()), ("declined", pa.string()),
])

#: detections.parquet: one row per detection, best first within an image.
DETECTIONS_SCHEMA = pa.schema([
    ("index", pa.int64()),
    ("path", pa.string()),
    ("rank", pa.int32()),           # 1 = the image's best
    ("x", pa.float64()), ("y", pa.float64()), ("scale", pa.float64()),
    ("angle", pa.float64()), ("score", pa.float64()), ("confidence", pa.float64()),
    ("nfa", pa.float64()),          # number of false alarms (Detection.nfa; null: not known)
    ("matrix", pa.list_(pa.float64(), 6)),   # 2x3 row-major: m00 m01 m02 m10 m11 m12
    ("votes", pa.float64()),
    ("kind", pa.string()),          # "object" or "line"
    ("line_angle", pa.float64()),   # lines only (else null)
    ("line_offset", pa.float64()),
    ("flags", pa.list_(pa.string())),
    ("pattern", pa.string()),       # the pattern's name ("" for a Detector of one pattern)
    ("segment", pa.list_(pa.float64(), 4)),  # a line's visible extent: x0 y0 x1 y1 (else null)
    ("stretches", pa.list_(pa.list_(pa.float64(), 4))),  # a line's stretches seen, each x0 y0 x1 y1
    ("width", pa.float64()),        # a line's band width, px (else null)
])


def image_row(index: int, path: str, status: str, n: int = 0, ms: float = 0.0,
              width=None, height=None, note: str = "", error=None, left_out: int = 0,
              best=None) -> tuple:
    """One row of images.parquet, in :data:`IMAGES_SCHEMA` order (``best``:
    the best candidate not reported, a :class:`~seahough.core.candidates.Candidate`)."""
    if best is None:
        b = (None, None, None)
    else:
        b = (float(best.score), float(best.nfa) if math.isfinite(best.nfa) else None,
             (f"{best.pattern}: " if best.pattern else "") + best.declined)
    return (index, path, status, n, ms, width, height, note, error, left_out, *b)


def _text(s):
    """``s`` as Parquet can store it: a name that is not UTF-8 (bytes the OS
    gave as surrogates) with those bytes escaped."""
    if s is None:
        return None
    try:
        s.encode("utf-8")
        return s
    except UnicodeEncodeError:
        return s.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")


def _table(rows: list, schema: pa.Schema) -> pa.Table:
    cols = list(zip(*rows)) if rows else [()] * len(schema)
    arrays = []
    for col, f in zip(cols, schema):
        if pa.types.is_string(f.type):
            col = [_text(v) for v in col]
        elif pa.types.is_list(f.type) and pa.types.is_string(f.type.value_type):
            col = [[_text(v) for v in vs] for vs in col]
        arrays.append(pa.array(col, type=f.type))
    return pa.Table.from_arrays(arrays, schema=schema)


def _reason(e: OSError) -> str:
    text = e.strerror or str(e)
    return text[:1].lower() + text[1:]


def _digest(paths: list[str]) -> str:
    h = hashlib.blake2b(digest_size=16)
    for p in paths:
        h.update(os.fsencode(p) + b"\0")
    return h.hexdigest()


class SurveyFolder:
    """The output folder of one survey, created and locked.

    Parameters
    ----------
    path : path
        The folder (``--out``).

    Raises
    ------
    WriteError
        The folder cannot be created or written, or another run holds it.
    """

    def __init__(self, path):
        self._run = RunFolder(path)         # creates and locks the folder
        self.path = self._run.path
        try:
            check_kind(self.path, "survey detect")
        except ParameterError:
            self._run.release()
            raise
        self.manifest = self.path / MANIFEST
        self.images = self.path / IMAGES
        self.detections = self.path / DETECTIONS
        self.parts = self.path / PARTS
        self._record: dict = {}
        self._next = 0
        self.moved = False      # (continued from another working folder than its own)

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        try:
            if exc_type is not None:
                self._stopped(exc_type, exc)
        finally:
            self._run.release()
        return False

    def _stopped(self, exc_type, exc) -> None:
        """A run that ends by an exception (Ctrl-C, SIGTERM, a worker's
        failure) leaves its manifest saying so: state "stopped", when, why
        and how many images are done (it said "running" with no run left),
        counted from the shards' footers (fast: a second Ctrl-C comes soon).
        Nothing here may hide the exception itself."""
        if self._record.get("state") != "running" or not self.manifest.is_file():
            return
        why = ("interrupted" if issubclass(exc_type, KeyboardInterrupt) else
               "terminated" if exc_type.__name__ == "_Terminated" else
               f"stopped by an error: {exc_type.__name__}: {exc}")
        try:
            done = sum(pq.read_metadata(p).num_rows for p in self._part_names("images"))
        except Exception:      # (a shard that cannot be read: the count unknown)
            done = None
        self._record.update(state="stopped", stopped={
            "at": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "why": why, "images_done": done})
        try:
            self._write_manifest()
        except WriteError:
            pass

    # ------------------------------------------------------------- manifest
    def _read_manifest(self) -> dict | None:
        try:
            text = self.manifest.read_text()
        except FileNotFoundError:
            return None
        except OSError as e:
            raise WriteError(f"{self.manifest}: cannot read it ({_reason(e)})") from None
        try:
            rec = json.loads(text)
            assert isinstance(rec, dict) and isinstance(rec["settings"], dict)
            assert isinstance(rec["inputs"]["count"], int)
        except (ValueError, KeyError, TypeError, AssertionError):
            raise ParameterError(f"{self.manifest}: not a survey manifest (damaged?); give "
                                 "another output folder, or remove this one") from None
        if rec.get("format") != FORMAT:
            raise ParameterError(f"{self.manifest}: written by another seahough (format "
                                 f"{rec.get('format')}, {FORMAT} here); give another output "
                                 "folder")
        return rec

    def _write_manifest(self) -> None:
        tmp = self.path / (MANIFEST + ".tmp")
        try:
            with open(tmp, "w") as f:
                json.dump(self._record, f, indent=2)
                f.write("\n")
            os.replace(tmp, self.manifest)
        except OSError as e:
            raise WriteError(f"{self.manifest}: cannot write it ({_reason(e)})") from None

    def _old_inputs(self, rec: dict) -> list[str] | None:
        try:
            t = pq.read_table(self.parts / "inputs.parquet", columns=["path"])
        except (OSError, pa.ArrowException):
            return None
        cwd = rec.get("cwd") or os.getcwd()
        return [os.path.abspath(os.path.join(cwd, p)) for p in t.column("path").to_pylist()]

    def _check_inputs(self, rec: dict, paths: list[str], absolute: list[str]) -> bool:
        """Whether the survey's images are ``paths`` (False) or ``paths``
        begin with them (True: more images, e.g. a folder a dive is still
        adding to); a ParameterError when neither."""
        old = rec["inputs"]
        if old.get("hash") == _digest(absolute) and old["count"] == len(paths):
            return False
        if old["count"] < len(absolute) and _digest(absolute[:old["count"]]) == old.get("hash"):
            return True
        what = f"{old['count']} images (now {len(paths)})"
        before = self._old_inputs(rec)
        if before is not None:
            i = next((k for k, (a, b) in enumerate(zip(before, absolute)) if a != b), None)
            if i is not None:
                what += (f"; first difference: image {i} {printable(before[i])!r} "
                         f"(now {printable(absolute[i])!r})")
            else:
                what += f"; the first {min(len(before), len(absolute))} are the same"
        raise ParameterError(f"{self.path}: holds a survey of other images: {what}. Give its "
                             "images (and more after them, if any) to continue it, or another "
                             "output folder")

    def start(self, settings: dict, paths: list[str]) -> set:
        """Begin or continue the survey of ``paths`` with ``settings`` (plain
        JSON values); returns the indices already done.

        Raises
        ------
        ParameterError
            The folder holds a survey with other settings or other images.
        WriteError
            The folder cannot be written.
        """
        digest = settings_hash(settings)
        absolute = [os.path.abspath(p) for p in paths]
        rec = self._read_manifest()
        grown = False
        for p in (self.images, self.detections, self.manifest):
            self._run.check_writable(p)
        if rec is not None:
            if rec.get("settings_hash") != digest:
                changes = settings_changes(rec["settings"], settings)
                more = f"; and {len(changes) - 4} more" if len(changes) > 4 else ""
                raise ParameterError(
                    f"{self.path}: holds a survey made with other settings: "
                    f"{'; '.join(changes[:4])}{more}. Give its settings to continue it, or "
                    "another output folder")
            grown = self._check_inputs(rec, paths, absolute)
            self._record = rec
            self.moved = os.path.abspath(rec.get("cwd") or os.getcwd()) != os.getcwd()
            if grown:   # the images added are searched, the survey is running again
                rec["inputs"] = {"count": len(paths), "hash": _digest(absolute)}
            if grown or rec.get("state") == "stopped":
                self._running_again()
        else:
            self._record = {
                "format": FORMAT, "command": "survey detect", "seahough": __version__,
                "started": datetime.datetime.now(datetime.timezone.utc).isoformat(
                    timespec="seconds"),
                "cwd": os.getcwd(), "settings_hash": digest, "settings": settings,
                "inputs": {"count": len(paths), "hash": _digest(absolute)},
                "state": "running", "counts": None, "files": {}}
        self._mkparts()
        if rec is None:
            self._clear_parts()                 # a survey whose manifest was removed
            self._write_manifest()
        if rec is None or self._inputs_count() != len(paths):
            # (after the manifest: a run stopped in between leaves a list that
            # only error messages read, rewritten here by the next run; paths
            # added from another working folder than the survey's are absolute)
            listed = absolute if self.moved else paths
            self._write(self.parts / "inputs.parquet", pa.table(
                {"index": pa.array(range(len(paths)), pa.int64()),
                 "path": pa.array([_text(p) for p in listed], pa.string())}))
        self._tidy()
        return self.done()

    def discard_new(self) -> None:
        """Remove what :meth:`start` wrote for a new survey of which nothing
        was searched (its cluster could not be reached): the same command,
        corrected, then starts afresh rather than meeting "other settings"."""
        if self.done():
            return
        for p in (self.manifest, self.parts / "inputs.parquet"):
            try:
                p.unlink()
            except OSError:
                pass
        try:
            self.parts.rmdir()
        except OSError:
            pass

    def _inputs_count(self) -> int:
        try:
            return pq.read_metadata(self.parts / "inputs.parquet").num_rows
        except (OSError, pa.ArrowException):
            return -1

    def _running_again(self) -> None:
        """The survey's state back to running (images to search: added, or to
        retry), written before any shard changes; its two files, which no
        longer hold every image, removed (the shards hold every row)."""
        self._record.update(state="running", counts=None, files={})
        self._record.pop("finished", None)
        self._record.pop("stopped", None)
        self._write_manifest()
        for p in (self.images, self.detections):
            self._remove(p)

    # ---------------------------------------------------------------- parts
    def _mkparts(self) -> None:
        try:
            self.parts.mkdir(exist_ok=True)
        except OSError as e:
            raise WriteError(f"{self.parts}: cannot create the folder ({_reason(e)})") from None

    def _part_names(self, kind: str) -> list[Path]:
        try:
            return sorted(p for p in self.parts.iterdir()
                          if p.name.startswith(kind + "-") and p.suffix == ".parquet")
        except OSError as e:
            raise WriteError(f"{self.parts}: cannot list it ({_reason(e)})") from None

    def _remove(self, p: Path) -> None:
        try:
            p.unlink(missing_ok=True)
        except OSError as e:
            raise WriteError(f"{p}: cannot remove it ({_reason(e)})") from None

    def _clear_parts(self) -> None:
        """Remove a former survey's files (only those a survey writes: a
        ``parts`` folder of the user's own keeps its other files)."""
        for pattern in ("images-*.parquet", "detections-*.parquet", "inputs.parquet", "*.tmp"):
            for p in self.parts.glob(pattern):
                if p.is_file():
                    self._remove(p)

    def _tidy(self) -> None:
        """Remove what a killed run left half-written: temporary files, and
        detections shards whose images shard (the mark of a done shard) is
        missing; number the next shard after the last."""
        for p in self.parts.glob("*.tmp"):
            self._remove(p)
        done = {p.name[len("images-"):] for p in self._part_names("images")}
        for p in self._part_names("detections"):
            if p.name[len("detections-"):] not in done:
                self._remove(p)
        nums = [int(n[:-len(".parquet")]) for n in done if n[:-len(".parquet")].isdigit()]
        self._next = max(nums, default=-1) + 1

    def forget_errors(self) -> int:
        """Take the rows of the images that could not be read or searched
        (status ``error``) out of the shards, so that they are searched
        again; returns how many. (A shard is rewritten whole, or not at
        all: an interruption loses nothing.)"""
        n = 0
        for p in self._part_names("images"):
            try:
                t = pq.read_table(p, schema=IMAGES_SCHEMA)
            except (OSError, pa.ArrowException) as e:
                raise WriteError(f"{p}: cannot read this shard ({e}); remove it to search its "
                                 "images again") from None
            bad = pc.equal(t.column("status"), "error")
            k = pc.sum(bad).as_py() or 0
            if k:
                if not n and self._record.get("state") != "running":
                    self._running_again()       # (before the first shard changes)
                # (error rows have no detections: the detections shard stays)
                self._write(p, t.filter(pc.invert(bad)))
                n += k
        return n

    def done(self) -> set:
        """The indices of the images whose rows are in a shard."""
        out: set = set()
        for p in self._part_names("images"):
            try:
                out.update(pq.read_table(p, columns=["index"]).column("index").to_pylist())
            except (OSError, pa.ArrowException) as e:
                raise WriteError(f"{p}: cannot read this shard ({e}); remove it to search its "
                                 "images again") from None
        return out

    def _write(self, path: Path, table: pa.Table) -> None:
        tmp = path.with_name(path.name + ".tmp")
        try:
            pq.write_table(table, tmp)
            os.replace(tmp, path)
        except OSError as e:
            raise WriteError(f"{path}: cannot write it ({_reason(e)})") from None

    def write_part(self, image_rows: list, detection_rows: list) -> None:
        """One shard: the rows of some images (``image_row`` tuples) and of
        their detections (tuples in :data:`DETECTIONS_SCHEMA` order)."""
        if not image_rows:
            return
        name = f"{self._next:06d}.parquet"
        self._write(self.parts / f"detections-{name}", _table(detection_rows, DETECTIONS_SCHEMA))
        self._write(self.parts / f"images-{name}", _table(image_rows, IMAGES_SCHEMA))
        self._next += 1

    # --------------------------------------------------------------- finish
    def complete(self) -> bool:
        """Is the survey complete, its two files written?"""
        return (self._record.get("state") == "complete" and self.images.is_file()
                and self.detections.is_file())

    def counts(self) -> dict:
        return dict(self._record.get("counts") or {})

    def finish(self) -> dict:
        """Write images.parquet and detections.parquet from the shards (all
        images done), mark the survey complete; returns the counts."""
        if self.complete():
            return self.counts()
        parts = self._part_names("images")
        images = pq.read_table(parts, schema=IMAGES_SCHEMA) if parts else _table([], IMAGES_SCHEMA)
        images = images.sort_by("index")
        n = self._record["inputs"]["count"]
        if images.num_rows != n:                # (a bug, not a user error)
            raise RuntimeError(f"{self.parts}: {images.num_rows} image rows for {n} images")
        dparts = self._part_names("detections")
        dets = (pq.read_table(dparts, schema=DETECTIONS_SCHEMA) if dparts
                else _table([], DETECTIONS_SCHEMA))
        dets = dets.sort_by([("index", "ascending"), ("rank", "ascending")])
        self._write(self.detections, dets)
        self._write(self.images, images)
        status = images.column("status").to_pylist()
        counts = {"images": n, "found": status.count("found"),
                  "not_found": status.count("not found"), "errors": status.count("error"),
                  "detections": dets.num_rows}
        self._record.update(
            state="complete", counts=counts,
            finished=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            files={"images": IMAGES, "detections": DETECTIONS})
        self._write_manifest()
        return counts
