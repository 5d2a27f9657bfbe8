"""``simgrip sweep --resume`` with damaged saved results (issue 16, section 4).

Each saved batch in ``OUT/.partial`` is verified; a damaged one (empty, cut
mid-row, random bytes, an unknown status, a point that is not the grid's) is
set aside in ``.partial/rejected/`` with one line naming it and why, and its
points are computed again: the final table equals an uninterrupted run's.
``OUT/.partial`` that is a file and ``OUT/sweep.csv`` that is a folder are
refused before any work; ``--resume`` on a finished sweep computes nothing.
The saved batches are written with the store's own code from one reference
run (6 points at n = 8 links), so each test computes at most a few points.
"""

from __future__ import annotations

import json
import random

import pytest

from simgrip.cli import main
from simgrip.parallel.runner import RunnerOptions
from simgrip.sweep.grid import make_grid
from simgrip.sweep.run import run_sweep
from simgrip.sweep.store import PARTIAL, REJECTED, PartialStore, read_csv, same_results, verify_batch

LINKS = 8
ONE = RunnerOptions(jobs=1, progress=False)
ARGS = ["sweep", "I", "--kappa", "-7", "-3", "3", "--M", "2", "8", "2", "--links", str(LINKS), "--jobs", "1",
        "--no-progress", "--no-map"]


def grid():
    return make_grid("I", kappa=(-7, -3, 3), M=(2, 8, 2), links=LINKS)


@pytest.fixture(scope="module")
def reference():
    return run_sweep(grid(), options=ONE)


def save(out, records, ranges):
    """An interrupted sweep in ``out``: ``.partial`` with one batch per ``(first, last)`` range; returns the files."""
    store = PartialStore(out, grid())
    store.open(False)
    files = []
    for first, last in ranges:
        store.buffer = [dict(r) for r in records[first:last + 1]]
        store.flush()
        files.append(store.batches[-1][2])
    return files


def resume(out):
    """``run_sweep(..., resume=True)``: (result, points computed, notes)."""
    computed, notes = [], []
    res = run_sweep(grid(), out=out, options=ONE, resume=True, write_map=False,
                    on_record=lambda r: computed.append(r["index"]), note=notes.append)
    return res, sorted(computed), notes


def check_final(out, reference):
    assert same_results(read_csv(out / "sweep.csv"), reference.records)
    assert not (out / PARTIAL).exists()


def test_intact_batches_are_taken_over(tmp_path, reference):
    out = tmp_path / "o"
    files = save(out, reference.records, [(0, 1), (2, 3)])
    assert [verify_batch(f, grid()) for f in files] == [(0, 1), (2, 3)]
    res, computed, notes = resume(out)
    assert computed == [4, 5] and notes == [] and res.resumed == 4 and res.computed == 2
    assert res.counts == reference.counts
    check_final(out, reference)


def _cut(data: bytes) -> bytes:  # what `head -c N` leaves: the last row cut mid-way
    return data[: data.rindex(b"\n", 0, len(data) - 1) + 40]


@pytest.mark.parametrize("damage, why", [
    (lambda d: b"", "empty"),
    (_cut, "cut short"),
    (lambda d: random.Random(0).randbytes(300) + b"\xff\xfe\n", "not UTF-8"),
    (lambda d: d.replace(b",settled,", b",foo,", 1), "unknown status 'foo'"),
    (lambda d: d.replace(b"\n1,", b"\n7,", 1), "point 7 where point 1 belongs"),
    (lambda d: d.replace(b"-7.0,", b"-6.5,", 1), "the grid's is -7.0"),
    (lambda d: d.replace(b"index,", b"idx,", 1), "header"),
    (lambda d: d.replace(b"true", b"maybe", 1), "expected true/false"),
    (lambda d: d + b"2,1,2\n", "fields"),
])
def test_a_damaged_batch_is_set_aside_and_recomputed(tmp_path, reference, damage, why):
    out = tmp_path / "o"
    bad, good = save(out, reference.records, [(0, 1), (2, 3)])
    damaged = damage(bad.read_bytes())
    bad.write_bytes(damaged)
    res, computed, notes = resume(out)
    assert computed == [0, 1, 4, 5] and res.resumed == 2  # the bad batch's points and the missing ones
    assert len(notes) == 1 and bad.name in notes[0] and why in notes[0], notes
    assert res.counts == reference.counts  # 6 of 6 statuses known: nothing copied from the bad file
    check_final(out, reference)
    # the set-aside file outlives .partial (it was deleted with it, while the note pointed to it)
    kept = out / "rejected-batches" / bad.name
    assert str(kept.parent) in notes[0] and kept.read_bytes() == damaged, notes


def test_damaged_batch_moved_aside_then_later_resumes_work(tmp_path, reference):
    """The bad file leaves the batches (in rejected/), so a second interruption and --resume do not trip on it."""
    out = tmp_path / "o"
    bad, _ = save(out, reference.records, [(0, 1), (2, 3)])
    bad.write_bytes(b"")
    store = PartialStore(out, grid())
    notes = []
    assert store.open(True, notes.append) == 2
    assert not bad.exists() and (out / PARTIAL / REJECTED / bad.name).exists() and len(notes) == 1
    notes.clear()
    assert PartialStore(out, grid()).open(True, notes.append) == 2 and notes == []  # the same again: quiet


def test_overlapping_batches_keep_one(tmp_path, reference):
    out = tmp_path / "o"
    save(out, reference.records, [(0, 2), (1, 3)])
    res, computed, notes = resume(out)
    assert computed == [3, 4, 5]  # 0..2 (first in order) kept, 1..3 set aside
    assert len(notes) == 1 and "already in another saved batch" in notes[0]
    check_final(out, reference)


def test_cli_names_the_file_and_exits_0(tmp_path, reference, capsys):
    out = tmp_path / "o"
    bad, _ = save(out, reference.records, [(0, 1), (2, 3)])
    bad.write_bytes(_cut(bad.read_bytes()))
    rc = main([*ARGS, "--out", str(out), "--resume"])
    err = capsys.readouterr().err
    assert rc == 0, err
    lines = [ln for ln in err.splitlines() if bad.name in ln]
    assert len(lines) == 1 and "cut short" in lines[0] and "computed again" in lines[0]
    assert "Traceback" not in err and "6 points (4 computed, 2 resumed)" in err
    check_final(out, reference)


def test_partial_that_is_a_file_is_refused_before_work(tmp_path, capsys):
    out = tmp_path / "o"
    out.mkdir()
    (out / PARTIAL).write_text("not a folder")
    for extra in ([], ["--resume"]):
        rc = main([*ARGS, "--out", str(out), *extra])
        err = capsys.readouterr().err
        assert rc == 2 and PARTIAL in err and "--out" in err and "Traceback" not in err, err
    assert (out / PARTIAL).read_text() == "not a folder" and not (out / "sweep.csv").exists()


@pytest.mark.parametrize("make", ["fifo", "zeros", "huge"])
def test_a_spec_json_that_is_not_a_small_regular_file_is_refused_at_once(tmp_path, capsys, make):
    """``.partial/spec.json`` as a FIFO blocked the resume for ever, as a link to /dev/zero read without end; each
    is now a damaged spec (one line, exit 2), as is a regular file too large to be a spec."""
    import os

    out = tmp_path / "o"
    (out / PARTIAL).mkdir(parents=True)
    spec = out / PARTIAL / "spec.json"
    if make == "fifo":
        os.mkfifo(spec)
    elif make == "zeros":
        os.symlink("/dev/zero", spec)
    else:
        with open(spec, "wb") as fh:
            fh.truncate((1 << 20) + 1)
    rc = main([*ARGS, "--out", str(out), "--resume"])
    err = capsys.readouterr().err
    assert rc == 2 and "--resume" in err and "spec.json is damaged" in err and "Traceback" not in err, err
    assert not (out / "sweep.csv").exists()


def test_sweep_csv_that_is_a_folder_is_refused_before_work(tmp_path, capsys):
    out = tmp_path / "o"
    (out / "sweep.csv").mkdir(parents=True)
    computed = []
    with pytest.raises(ValueError, match="sweep.csv"):
        run_sweep(grid(), out=out, options=ONE, on_record=computed.append, write_map=False)
    assert computed == [] and not (out / PARTIAL).exists()
    rc = main([*ARGS, "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 2 and "sweep.csv" in err and "Traceback" not in err
    assert (out / "sweep.csv").is_dir()


def test_resume_on_a_finished_sweep_computes_nothing(tmp_path, reference, capsys):
    out = tmp_path / "o"
    assert main([*ARGS, "--out", str(out)]) == 0
    before = (out / "sweep.csv").read_bytes()
    capsys.readouterr()
    computed = []
    res = run_sweep(grid(), out=out, options=ONE, resume=True, write_map=False, on_record=computed.append,
                    note=None)
    assert computed == [] and res.computed == 0 and res.resumed == 6 and res.counts == reference.counts
    assert same_results(res.rows, reference.records)
    rc = main([*ARGS, "--out", str(out), "--resume"])
    err = capsys.readouterr().err
    assert rc == 0 and "nothing to compute" in err and "0 computed" in err, err
    assert (out / "sweep.csv").read_bytes() == before
    # another grid in the same folder: refused, naming --resume, the files left alone
    rc = main([*ARGS[:5], "3", "--M", "2", "8", "3", *ARGS[10:], "--out", str(out), "--resume"])
    err = capsys.readouterr().err
    assert rc == 2 and "--resume" in err and "different grid" in err
    meta = json.loads((out / "sweep.json").read_text())
    assert meta["counts"]["points"] == 6 and (out / "sweep.csv").read_bytes() == before


def test_every_point_saved_resume_only_writes_the_table(tmp_path, reference):
    """Interrupted while writing sweep.csv: every point is in .partial, so --resume computes none."""
    out = tmp_path / "o"
    save(out, reference.records, [(0, 2), (3, 5)])
    res, computed, notes = resume(out)
    assert computed == [] and notes == [] and res.resumed == 6 and res.computed == 0
    check_final(out, reference)


def test_an_interrupted_sweep_says_so_in_one_line_with_the_resume_hint(tmp_path, capsys, monkeypatch):
    """The hint where the finished points are used to be a line of its own before the CLI's "interrupted"."""
    from pathlib import Path

    import simgrip.sweep.run as run

    out = tmp_path / "o"

    def interrupted(grid, *, out, **kw):
        (Path(out) / PARTIAL).mkdir(parents=True)
        (Path(out) / PARTIAL / "batch-000000000-000000001-00000000.csv").write_text("")
        raise KeyboardInterrupt

    monkeypatch.setattr(run, "run_sweep", interrupted)
    assert main([*ARGS, "--out", str(out)]) == 130
    lines = capsys.readouterr().err.strip().splitlines()
    assert lines == [f"simgrip sweep: interrupted; finished points are saved in {out / PARTIAL}; run the same "
                     "command with --resume to complete the sweep"], lines
