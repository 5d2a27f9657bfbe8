"""A sweep's files: the CSV table, and the partial results that make an interrupted sweep resumable.

``sweep.csv`` holds one row per point with the columns of
:data:`simgrip.sweep.point.COLUMNS`; floats are written with ``repr``
(they read back bit for bit), flags as ``true``/``false``, a missing value as
an empty field.  :func:`read_csv` reads it back (no pandas needed).

While a sweep runs, finished points are saved in ``DIR/.partial/``: a
``spec.json`` with the sweep's definition and ``batch-*.csv`` files (the same
format plus the point ``index``), each written atomically
(:func:`simgrip.io.atomic_write`), so whatever stops the sweep (Ctrl-C, a lost
scheduler, a killed machine) leaves only whole files.  ``--resume`` reads
them, checks that ``spec.json`` describes the same sweep, and computes only the
points missing; the folder is deleted once the final files are written.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import shutil
import time
import uuid
from pathlib import Path

from simgrip.sweep.point import COLUMNS, STATUSES
from simgrip.io import atomic_write, write_json

__all__ = ["PARTIAL", "PartialStore", "counts", "format_csv", "read_csv", "same_results", "write_csv"]

#: Folder (inside ``--out``) of an unfinished sweep's saved points.
PARTIAL = ".partial"
_BOOL = ("held", "feasible", "bvp_feasible", "agree")
_TEXT = ("status", "message", "bvp_message")
#: Saved points are written at least this often (seconds) while results arrive (the first at once) ...
FLUSH_SECONDS = 1.0
#: ... or when this many are waiting.
FLUSH_POINTS = 256


def _cell(v) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(v)
    return str(v)


def _parse(col: str, text: str):
    if col == "index":
        return int(text)
    if col in _TEXT:
        return text
    if text == "":
        return None
    if col in _BOOL:
        if text not in ("true", "false"):
            raise ValueError(f"column {col}: expected true/false, got {text!r}")
        return text == "true"
    return float(text)


def format_csv(rows, columns=COLUMNS) -> str:
    """The CSV text of ``rows`` (dicts) in ``columns``."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(columns)
    for r in rows:
        w.writerow([_cell(r[c]) for c in columns])
    return buf.getvalue()


def write_csv(path, rows, columns=COLUMNS) -> None:
    """Write ``rows`` as CSV atomically."""
    text = format_csv(rows, columns)
    with atomic_write(path) as fh:
        fh.write(text)


def read_csv(path) -> list[dict]:
    """Rows of a ``sweep.csv`` (or a partial batch file) as dicts of floats, bools, strings and ``None``."""
    with open(path, newline="") as fh:
        reader = csv.reader(fh)
        header = next(reader)
        unknown = [c for c in header if c != "index" and c not in COLUMNS]
        if unknown:
            raise ValueError(f"{path}: not a sweep table (unknown columns {unknown})")
        return [{c: _parse(c, t) for c, t in zip(header, row)} for row in reader]


class PartialStore:
    """Saved points of one sweep in ``out/.partial`` (see the module docstring).

    ``spec`` is the sweep's JSON-able definition; :meth:`open` creates the
    folder (or, ``resume=True``, checks an existing one against ``spec``).
    """

    def __init__(self, out: str | os.PathLike, spec: dict):
        self.dir = Path(out) / PARTIAL
        self.spec = spec
        self.buffer: list[dict] = []
        self.last_flush = -math.inf  # the first point is saved at once: resumable from the start
        self.saved = 0

    def exists(self) -> bool:
        return self.dir.is_dir()

    def open(self, resume: bool) -> dict[int, dict]:
        """Prepare the folder; returns the saved points ``{index: record}`` (empty unless ``resume``).

        Raises ``ValueError`` naming ``--resume`` when an unfinished sweep is found
        without it, or when the saved one is a different sweep.
        """
        done: dict[int, dict] = {}
        if self.exists():
            if not resume:
                raise ValueError(f"--out {str(self.dir.parent)!r} holds an unfinished sweep ({PARTIAL}/): "
                                 f"add --resume to complete it, or delete {str(self.dir)!r}")
            spec_path = self.dir / "spec.json"
            try:
                saved_spec = json.loads(spec_path.read_text())
            except (OSError, ValueError):
                saved_spec = None
            if saved_spec != json.loads(json.dumps(self.spec)):
                raise ValueError(f"--resume: {str(self.dir)!r} was written for a different sweep "
                                 "(grip, axes, links or method differ); delete it to start afresh")
            for path in sorted(self.dir.glob("batch-*.csv")):
                for rec in read_csv(path):
                    done.setdefault(int(rec["index"]), rec)
            return done
        self.dir.mkdir(parents=True, exist_ok=True)
        write_json(self.dir / "spec.json", self.spec)
        return done

    def add(self, record: dict) -> None:
        """Queue a finished point; saves the queue when it is large or old enough."""
        self.buffer.append(record)
        if len(self.buffer) >= FLUSH_POINTS or time.monotonic() - self.last_flush >= FLUSH_SECONDS:
            self.flush()

    def flush(self) -> None:
        """Save the queued points as one batch file (atomically)."""
        self.last_flush = time.monotonic()
        if not self.buffer:
            return
        rows, self.buffer = self.buffer, []
        name = f"batch-{min(r['index'] for r in rows):09d}-{uuid.uuid4().hex[:8]}.csv"
        write_csv(self.dir / name, rows, ("index",) + COLUMNS)
        self.saved += len(rows)

    def remove(self) -> None:
        """Delete the folder (after the final files are written)."""
        shutil.rmtree(self.dir, ignore_errors=True)


def counts(rows) -> dict:
    """Counts of a sweep table: points per status, held, feasible, agreeing, disagreeing, BVP failures."""
    out = {"points": len(rows)}
    for s in STATUSES:
        out[s] = sum(1 for r in rows if r["status"] == s)
    out["held"] = sum(1 for r in rows if r["held"] is True)
    out["feasible"] = sum(1 for r in rows if r["feasible"] is True)
    out["bvp_feasible"] = sum(1 for r in rows if r["bvp_feasible"] is True)
    out["agree"] = sum(1 for r in rows if r["agree"] is True)
    out["disagree"] = sum(1 for r in rows if r["agree"] is False)
    out["bvp_failed"] = sum(1 for r in rows if r["bvp_feasible"] is None)
    return out


def same_results(a: list[dict], b: list[dict], ignore=("wall_time_s",)) -> bool:
    """True when two tables are equal in every column but ``ignore`` (NaN-free by construction)."""
    if len(a) != len(b):
        return False
    for ra, rb in zip(a, b):
        for c in COLUMNS:
            if c in ignore:
                continue
            if ra[c] != rb[c]:
                return False
    return True
