"""A sweep's files: the CSV table, and the partial results that make an interrupted sweep resumable.

``sweep.csv`` holds one row per point with the columns of
:data:`simgrip.sweep.point.COLUMNS`; floats are written with ``repr``
(they read back bit for bit), flags as ``true``/``false``, a missing value as
an empty field.  :func:`read_csv` reads it back (no pandas needed),
:func:`iter_csv` one row at a time.

While a sweep runs, finished points are saved in ``DIR/.partial/``: a
``spec.json`` with the sweep's definition and batch files
``batch-START-STOP-ID.csv``, each holding exactly the points ``START..STOP``
(9-digit indices, inclusive) in grid order, in the same format plus the point
``index``, each written atomically (:func:`simgrip.io.atomic_write`), so
whatever stops the sweep (Ctrl-C, a lost scheduler, a killed machine) leaves
only whole files.  Nothing of a point is kept in memory once it is saved but
one byte saying that it is done.

``--resume`` checks that ``spec.json`` describes the same sweep and verifies
every batch file (:func:`verify_batch`): UTF-8 text ending with a newline,
parseable CSV, the header of a batch, every value of its column's type, known
statuses, indices inside the grid and exactly the file's declared range, the
parameters those of the grid's points, no point already in another batch.  A
file that fails is set aside in ``.partial/rejected/`` with one line naming it
and why, and its points are computed again.  When every point is saved,
:meth:`PartialStore.merge` streams the batches in grid order into
``sweep.csv`` (one batch open at a time) and counts the table on the way
(:class:`Tally`); the folder is deleted once the final files are written.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import math
import os
import stat
import re
import shutil
import time
import uuid
from array import array
from pathlib import Path

from simgrip.io import atomic_write, write_json
from simgrip.sweep.point import COLUMNS, STATUSES, TIME_COLUMNS

__all__ = ["PARTIAL", "REJECTED", "BatchError", "LogHistogram", "PartialStore", "Tally", "counts", "format_csv",
           "iter_csv",
           "read_csv", "same_results", "verify_batch", "write_csv"]

#: Folder (inside ``--out``) of an unfinished sweep's saved points.
PARTIAL = ".partial"
#: Sub-folder of :data:`PARTIAL` where damaged batch files are set aside on ``--resume``.
REJECTED = "rejected"
_BOOL = ("held", "feasible", "valid", "bvp_feasible", "agree")
_TEXT = ("status", "message", "bvp_message", "bvp_warning")
#: Header of a batch file.
BATCH_COLUMNS = ("index",) + COLUMNS
#: ``batch-START-STOP-ID.csv``; files of earlier versions, ``batch-START-ID.csv``, declare no end.
_BATCH_NAME = re.compile(r"^batch-(\d{9})-(?:(\d{9})-)?([0-9a-f]{8})\.csv$")
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
        if not re.fullmatch(r"\d+", text):
            raise ValueError(f"column index: expected a point number, got {text!r}")
        return int(text)
    if col in _TEXT:
        return text
    if text == "":
        return None
    if col in _BOOL:
        if text not in ("true", "false"):
            raise ValueError(f"column {col}: expected true/false, got {text!r}")
        return text == "true"
    try:
        v = float(text)
    except ValueError:
        raise ValueError(f"column {col}: expected a number, got {text!r}") from None
    if math.isnan(v):  # never written (a NaN is an empty field)
        raise ValueError(f"column {col}: NaN")
    return v


def format_csv(rows, columns=COLUMNS) -> str:
    """The CSV text of ``rows`` (dicts) in ``columns``."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(columns)
    for r in rows:
        w.writerow([_cell(r[c]) for c in columns])
    return buf.getvalue()


def write_csv(path, rows, columns=COLUMNS) -> None:
    """Write ``rows`` (any iterable of dicts, streamed) as CSV atomically."""
    with atomic_write(path) as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(columns)
        for r in rows:
            w.writerow([_cell(r[c]) for c in columns])


def iter_csv(path):
    """Rows of a ``sweep.csv`` (or a batch file) one at a time, as dicts of floats, bools, strings and ``None``.

    Raises ``ValueError`` naming the file for a table that is not a sweep's.
    """
    with open(path, newline="", encoding="utf-8") as fh:
        reader = csv.reader(fh)
        header = next(reader, None)
        if header is None:
            raise ValueError(f"{path}: empty, not a sweep table")
        unknown = [c for c in header if c != "index" and c not in COLUMNS]
        if unknown:
            raise ValueError(f"{path}: not a sweep table (unknown columns {unknown})")
        for k, row in enumerate(reader, start=2):
            if len(row) != len(header):
                raise ValueError(f"{path}: line {k} has {len(row)} fields, the header {len(header)}")
            yield {c: _parse(c, t) for c, t in zip(header, row)}


def read_csv(path) -> list[dict]:
    """Every row of a ``sweep.csv`` (or a batch file) as a list (see :func:`iter_csv`)."""
    return list(iter_csv(path))


class LogHistogram:
    """Positive numbers counted in :data:`BINS_PER_DECADE` logarithmic bins per decade (memory fixed whatever
    the count): :meth:`median` is the geometric middle of the median's bin, within a factor
    ``10 ** (0.5 / BINS_PER_DECADE)`` (0.6 %) of the exact median."""

    BINS_PER_DECADE = 200

    def __init__(self):
        self.bins: dict[int, int] = {}  # at most ~200 bins a decade over the values' range (times: ~6 decades)
        self.n = 0

    def add(self, v) -> None:
        if v is None or not (v > 0) or math.isinf(v):
            return
        k = math.floor(math.log10(v) * self.BINS_PER_DECADE)
        self.bins[k] = self.bins.get(k, 0) + 1
        self.n += 1

    def median(self) -> float | None:
        """The median (see the class docstring), ``None`` when nothing was counted."""
        if self.n == 0:
            return None
        seen, half = 0, (self.n + 1) / 2
        for k in sorted(self.bins):
            seen += self.bins[k]
            if seen >= half:
                return 10.0 ** ((k + 0.5) / self.BINS_PER_DECADE)
        return None  # pragma: no cover - the counts add up to n


class Tally:
    """Counts of a sweep table accumulated one row at a time (:meth:`add`); :meth:`as_dict` gives :func:`counts`,
    :meth:`timing` the medians of the settle's time and of the point's over its settle (fixed memory)."""

    def __init__(self):
        self.c = {"points": 0, **{s: 0 for s in STATUSES}, "held": 0, "feasible": 0, "bvp_feasible": 0, "agree": 0,
                  "disagree": 0, "bvp_failed": 0, "bvp_jumped": 0}
        self.settle = LogHistogram()
        self.ratio = LogHistogram()

    def add(self, r: dict) -> None:
        c = self.c
        c["points"] += 1
        if r["status"] in STATUSES:
            c[r["status"]] += 1
        c["held"] += r["held"] is True
        c["feasible"] += r["feasible"] is True
        c["bvp_feasible"] += r["bvp_feasible"] is True
        c["agree"] += r["agree"] is True
        c["disagree"] += r["agree"] is False
        c["bvp_failed"] += r["bvp_feasible"] is None and bool(r["bvp_message"])  # none: no BVP, no message
        c["bvp_jumped"] += bool(r.get("bvp_warning"))
        settle, point = r.get("wall_time_s"), r.get("point_time_s")
        self.settle.add(settle)
        if settle and point:
            self.ratio.add(point / settle)

    def as_dict(self) -> dict:
        return dict(self.c)

    def timing(self) -> dict:
        """``{"settle_median_s", "point_over_settle_median"}`` over the rows with both times (``None``: none)."""
        return {"settle_median_s": self.settle.median(), "point_over_settle_median": self.ratio.median()}


class BatchError(ValueError):
    """A saved batch file that cannot be trusted; the message says why."""


def _batch_name(first: int, last: int, ident: int) -> str:
    """``batch-FIRST-LAST-ID.csv`` (9-digit point numbers, an 8-hex-digit id)."""
    return f"batch-{first:09d}-{last:09d}-{ident:08x}.csv"


def _declared(path: Path, size: int) -> tuple[int, int | None]:
    m = _BATCH_NAME.match(path.name)
    if m is None:
        raise BatchError("its name is not batch-START-STOP-ID.csv")
    start = int(m.group(1))
    stop = None if m.group(2) is None else int(m.group(2))
    if stop is not None and stop < start:
        raise BatchError(f"its name declares points {start}..{stop}, an empty range")
    if start >= size or (stop is not None and stop >= size):
        raise BatchError(f"its name declares points beyond the grid's {size}")
    return start, stop


def verify_batch(path, grid) -> tuple[int, int]:
    """Check one saved batch file against ``grid``; returns the points ``(first, last)`` it holds.

    Raises :class:`BatchError` saying what is wrong (see the module
    docstring); reads the file once, one row at a time.
    """
    from simgrip.sweep.grid import AXES

    path = Path(path)
    start, stop = _declared(path, grid.size)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise BatchError(f"unreadable ({exc.strerror or exc})") from None
    if not data:
        raise BatchError("empty")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise BatchError(f"not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start})") from None
    if not text.endswith("\n"):
        raise BatchError("cut short: its last row has no end of line")
    reader = csv.reader(io.StringIO(text, newline=""))
    try:
        header = next(reader)
        if tuple(header) != BATCH_COLUMNS:
            raise BatchError("its header is not a sweep batch's (index and the sweep's columns)")
        expect = start
        for line, row in enumerate(reader, start=2):
            if len(row) != len(BATCH_COLUMNS):
                raise BatchError(f"line {line} has {len(row)} fields, not {len(BATCH_COLUMNS)}")
            try:
                rec = {c: _parse(c, t) for c, t in zip(BATCH_COLUMNS, row)}
            except ValueError as exc:
                raise BatchError(f"line {line}: {exc}") from None
            if rec["status"] not in STATUSES:
                raise BatchError(f"line {line}: unknown status {rec['status']!r} (known: {', '.join(STATUSES)})")
            i = rec["index"]
            if i != expect:
                raise BatchError(f"line {line}: point {i} where point {expect} belongs "
                                 f"(a batch holds consecutive points from {start})")
            if i >= grid.size or (stop is not None and i > stop):
                raise BatchError(f"line {line}: point {i} is beyond "
                                 + (f"the grid's {grid.size} points" if i >= grid.size else f"the declared {stop}"))
            point = grid.point(i)
            for a in AXES:
                if rec[a] != getattr(point, a):
                    raise BatchError(f"line {line}: point {i} has {a} = {rec[a]!r}, the grid's is {getattr(point, a)!r}")
            expect += 1
    except csv.Error as exc:
        raise BatchError(f"not CSV ({exc})") from None
    if expect == start:
        raise BatchError("no rows")
    if stop is not None and expect != stop + 1:
        raise BatchError(f"holds points {start}..{expect - 1}, its name declares {start}..{stop}")
    return start, expect - 1


class PartialStore:
    """Saved points of one sweep in ``out/.partial`` (see the module docstring).

    ``grid`` is the sweep (:class:`~simgrip.sweep.grid.SweepGrid`);
    :meth:`check` refuses a ``.partial`` that is not a folder, :meth:`open`
    creates the folder (or, ``resume=True``, verifies an existing one).
    ``done`` holds one byte per point: 1 once the point is saved; the good
    batch files are held as three integers each (first point, last point, the
    name's id; :attr:`batches`), ~24 bytes a file instead of ~460 for a tuple
    with a ``Path`` (a 10^6-point sweep writes ~10^4 files).
    """

    def __init__(self, out: str | os.PathLike, grid):
        self.dir = Path(out) / PARTIAL
        self.grid = grid
        self.spec = grid.spec()
        self.buffer: list[dict] = []
        self.last_flush = -math.inf  # the first point is saved at once: resumable from the start
        self.saved = 0
        self.done = bytearray(grid.size)
        self._first, self._last, self._ids = array("q"), array("q"), array("Q")  # of every good batch file
        self._odd: dict[int, Path] = {}  # the few whose name is not batch-FIRST-LAST-ID.csv (an older version's)
        self.timing: dict = {}  # medians of the times, set by merge (Tally.timing)

    def exists(self) -> bool:
        return self.dir.is_dir()

    def check(self) -> None:
        """``ValueError`` naming ``--out`` when ``out/.partial`` exists and is not a folder (before any work)."""
        if os.path.lexists(self.dir) and not (self.dir.is_dir() and not self.dir.is_symlink()):
            raise ValueError(f"--out: {str(self.dir)!r} is not the folder of an unfinished sweep (it is a "
                             f"{'link' if self.dir.is_symlink() else 'file'}); move or delete it")

    def open(self, resume: bool, note=None) -> int:
        """Prepare the folder; returns the number of saved points taken over (0 unless ``resume``).

        ``note`` receives one line for every batch file set aside.  Raises
        ``ValueError`` naming ``--resume`` when an unfinished sweep is found
        without it, or when the saved one is a different sweep.
        """
        self.check()
        if self.exists():
            if not resume:
                raise ValueError(f"--out {str(self.dir.parent)!r} holds an unfinished sweep ({PARTIAL}/): "
                                 f"add --resume to complete it, or delete {str(self.dir)!r}")
            saved_spec = _read_spec(self.dir / "spec.json")
            if saved_spec != json.loads(json.dumps(self.spec)):
                raise ValueError(f"--resume: {str(self.dir)!r} was written for a different sweep "
                                 "(grip, axes, links, method, reference, contact or box depth differ, or its "
                                 "spec.json is damaged); "
                                 "delete it to start afresh")
            return self._take_over(note)
        self.dir.mkdir(parents=True, exist_ok=True)
        write_json(self.dir / "spec.json", self.spec)
        return 0

    def _take_over(self, note) -> int:
        n = 0
        for path in sorted(p for p in self.dir.iterdir() if p.name.startswith("batch-")):
            try:
                if not path.is_file() or path.is_symlink():
                    raise BatchError("not a regular file")
                first, last = verify_batch(path, self.grid)
                if any(self.done[first:last + 1]):
                    raise BatchError("its points are already in another saved batch")
            except BatchError as why:
                self._set_aside(path, str(why), note)
                continue
            self.done[first:last + 1] = b"\x01" * (last - first + 1)
            self._keep(first, last, path)
            n += last - first + 1
        return n

    def _set_aside(self, path: Path, why: str, note) -> None:
        bin_ = self.dir / REJECTED
        bin_.mkdir(exist_ok=True)
        dest = bin_ / path.name
        k = 1
        while os.path.lexists(dest):
            dest = bin_ / f"{path.name}.{k}"
            k += 1
        os.replace(path, dest)
        if note is not None:
            note(f"set aside {path} ({why}): moved to {dest} (kept in {self.dir.parent / 'rejected-batches'} once the "
                 "sweep completes); its points are computed again")

    def add(self, record: dict) -> None:
        """Queue a finished point; saves the queue when it is large or old enough."""
        self.buffer.append(record)
        if len(self.buffer) >= FLUSH_POINTS or time.monotonic() - self.last_flush >= FLUSH_SECONDS:
            self.flush()

    def flush(self) -> None:
        """Save the queued points, one batch file (atomically) per run of consecutive points."""
        self.last_flush = time.monotonic()
        if not self.buffer:
            return
        rows, self.buffer = sorted(self.buffer, key=lambda r: r["index"]), []
        runs = [[rows[0]]]
        for r in rows[1:]:
            if r["index"] == runs[-1][-1]["index"] + 1:
                runs[-1].append(r)
            else:
                runs.append([r])
        for run in runs:
            first, last = run[0]["index"], run[-1]["index"]
            path = self.dir / _batch_name(first, last, uuid.uuid4().int & 0xFFFFFFFF)
            write_csv(path, run, BATCH_COLUMNS)
            self.done[first:last + 1] = b"\x01" * (last - first + 1)
            self._keep(first, last, path)
            self.saved += len(run)

    def _keep(self, first: int, last: int, path: Path) -> None:
        m = _BATCH_NAME.match(path.name)
        if m is None or m.group(2) is None or path.name != _batch_name(first, last, int(m.group(3), 16)):
            self._odd[len(self._ids)] = path
        self._first.append(first)
        self._last.append(last)
        self._ids.append(int(m.group(3), 16) if m is not None else 0)

    @property
    def batches(self) -> list[tuple[int, int, Path]]:
        """``(first, last, file)`` of every good batch file, in the order they were saved or taken over."""
        return [(self._first[k], self._last[k], self._odd.get(k) or self.dir / _batch_name(self._first[k],
                                                                                           self._last[k], self._ids[k]))
                for k in range(len(self._ids))]

    def merge(self, csv_path) -> dict:
        """Stream every saved point, in grid order, into ``csv_path`` (atomically); returns the table's counts.

        Raises ``RuntimeError`` when a point is missing or saved twice (a batch
        file removed or added while the sweep ran).
        """
        tally = Tally()
        order = sorted(range(len(self._ids)), key=lambda k: (self._first[k], self._last[k]))  # 8 bytes a file

        def batches():
            for k in order:
                yield self._first[k], self._last[k], self._odd.get(k) or self.dir / _batch_name(
                    self._first[k], self._last[k], self._ids[k])

        def rows():
            expect = 0
            for first, last, path in batches():
                if first != expect:
                    raise RuntimeError(f"sweep: point {expect} is not among the saved batches in {self.dir} "
                                       f"(next batch starts at {first})")
                for r in iter_csv(path):
                    if r["index"] != expect:
                        raise RuntimeError(f"sweep: {path} changed while the sweep ran (point {r['index']} where "
                                           f"{expect} belongs)")
                    tally.add(r)
                    yield r
                    expect += 1
                if expect != last + 1:
                    raise RuntimeError(f"sweep: {path} changed while the sweep ran")
            if expect != self.grid.size:
                raise RuntimeError(f"sweep: points {expect}..{self.grid.size - 1} are not among the saved batches")

        write_csv(csv_path, rows(), COLUMNS)
        self.timing = tally.timing()
        return tally.as_dict()

    def batch_files(self) -> list[Path]:
        """The saved batch files in the folder (none when it does not exist)."""
        return sorted(self.dir.glob("batch-*.csv")) if self.dir.is_dir() else []

    def remove(self) -> None:
        """Delete the folder (after the final files are written); the batch files set aside (``rejected/``), which a
        note pointed to, are kept: moved to ``OUT/rejected-batches/`` (a numbered name where one is taken)."""
        bin_ = self.dir / REJECTED
        if bin_.is_dir() and not bin_.is_symlink() and any(bin_.iterdir()):
            keep = self.dir.parent / "rejected-batches"
            with contextlib.suppress(OSError):
                keep.mkdir(exist_ok=True)
                for path in sorted(bin_.iterdir()):
                    dest, k = keep / path.name, 1
                    while os.path.lexists(dest):
                        dest, k = keep / f"{path.name}.{k}", k + 1
                    os.replace(path, dest)
        shutil.rmtree(self.dir, ignore_errors=True)


def counts(rows) -> dict:
    """Counts of a sweep table: points per status, held, feasible, agreeing, disagreeing, BVP failures."""
    tally = Tally()
    for r in rows:
        tally.add(r)
    return tally.as_dict()


def same_results(a: list[dict], b: list[dict], ignore=TIME_COLUMNS) -> bool:
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


#: the most a saved sweep's ``spec.json`` may hold [bytes]: it is a few hundred; a larger one is damaged
SPEC_MAX_BYTES = 1 << 20


def _read_spec(path: Path):
    """A saved sweep's spec (its ``spec.json``), or None when it is missing, damaged or not a regular file: a FIFO
    there would block the read for ever, a link to ``/dev/zero`` read without end (so: checked, and read at most
    :data:`SPEC_MAX_BYTES`)."""
    try:
        if not stat.S_ISREG(os.stat(path).st_mode):
            return None
        with open(path, "rb") as fh:
            raw = fh.read(SPEC_MAX_BYTES + 1)
        return None if len(raw) > SPEC_MAX_BYTES else json.loads(raw.decode("utf-8"))
    except (OSError, ValueError):
        return None
