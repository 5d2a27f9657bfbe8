"""simgrip sweep: grid parsing, the per-point record, the files, and the sweep on real Dask clusters.

Equal rows (every column but the times) for ``--jobs 1``, a LocalCluster of 2
workers and a ``dask scheduler`` + ``dask worker`` cluster, at several batch
sizes; a worker killed mid-sweep; ``--resume`` after Ctrl-C without
recomputing saved points; bad grids and outputs rejected with the parameter
named (exit 2).  Small grids at n = 8 links keep each test to seconds.
"""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from simgrip.cli import main
from simgrip.parallel.dask_cluster import descendants
from simgrip.parallel.runner import RunnerOptions
from simgrip.sweep.run import run_sweep
from simgrip.sweep.grid import AXES, make_grid, parse_axis
from simgrip.sweep.point import COLUMNS, evaluate_point, evaluate_segment
from simgrip.sweep.store import PARTIAL, read_csv, same_results

LINKS = 8
ONE = RunnerOptions(jobs=1, progress=False)


def small_grid():
    """6 points of Grip I across the hold/drop boundary (held at kappa -7, dropped at -3 for M = 8)."""
    return make_grid("I", kappa=(-7, -3, 3), M=(2, 8, 2), links=LINKS)


@pytest.fixture(scope="module")
def reference():
    """The plain in-process loop's rows of :func:`small_grid`."""
    return run_sweep(small_grid(), options=ONE)


# grid -----------------------------------------------------------------------------------------

def test_axis_values():
    assert parse_axis("kappa", -5) == (-5.0,)
    assert parse_axis("kappa", ["-5"]) == (-5.0,)
    assert parse_axis("D", ("0.5", "2", "4")) == tuple(np.linspace(0.5, 2.0, 4))
    vals = parse_axis("M", (1, 3, 3))
    assert vals == (1.0, 2.0, 3.0)  # inclusive
    assert parse_axis("mu", (0.5, 0.5, 1)) == (0.5,)


@pytest.mark.parametrize("name, values, words", [
    ("kappa", (-7, -3, 0), "NUM"),
    ("kappa", (-7, -3, 2.5), "NUM"),
    ("kappa", (-3, -7, 3), "STOP"),
    ("kappa", (-3, -7, 1), "NUM = 1 is START alone"),  # a reversed range with NUM = 1 computed START
    ("kappa", (-7, 1e308, 1), "NUM = 1 is START alone"),  # a STOP far out of range, never checked
    ("M", ("nan",), "finite"),
    ("M", (1, "nan", 3), "STOP"),
    ("D", ("inf",), "finite"),
    ("b", (0.2, 0.4), "START STOP NUM"),
    ("D", (-1,), "positive"),
    ("gamma", (0.5, 1.5, 3), "gamma"),
    ("mu", ("x",), "number"),
])
def test_bad_axis_is_named(name, values, words):
    with pytest.raises(ValueError) as exc:
        parse_axis(name, values)
    assert str(exc.value).startswith(name) and words in str(exc.value)


def test_grid_order_and_points():
    g = make_grid("II", kappa=(3, 5, 3), D=(0.5, 1, 2), mu=0.7, links=LINKS)
    assert g.shape == (3, 2, 1, 1, 1, 1) and g.size == 6 and g.swept == ("kappa", "D")
    pts = list(g.points())
    assert [(p.kappa, p.D) for p in pts] == [(3, 0.5), (3, 1), (4, 0.5), (4, 1), (5, 0.5), (5, 1)]  # kappa slowest
    assert all(g.point(i) == p for i, p in enumerate(pts))
    assert pts[0].mu == 0.7 and pts[0].M == 5.0 and pts[0].b == 0.6 and pts[0].gamma == 0.8  # CLI defaults
    with pytest.raises(ValueError, match="grip"):
        make_grid("free", kappa=0, links=LINKS)
    with pytest.raises(ValueError, match="links"):
        make_grid("I", kappa=-5, links=0)
    with pytest.raises(ValueError, match="method"):
        make_grid("I", kappa=-5, links=LINKS, method="magic")


# one point ------------------------------------------------------------------------------------

def test_point_record_matches_the_library():
    """The record is simulate + settled_record and elastica.solve at the same point, nothing else."""
    from simgrip import Uniform
    from simgrip.compare import settled_record, simulate
    from simgrip.reference import elastica

    p = make_grid("I", kappa=-6, links=LINKS).point(0)
    rec = evaluate_point(p)
    assert list(rec) == ["index", *COLUMNS] and tuple(COLUMNS[: len(AXES)]) == AXES
    state = settled_record(simulate("I", p.params(), Uniform(-6.0), LINKS), p.params())
    sol = elastica.solve("I", p.params(), Uniform(-6.0))
    assert rec["status"] == "settled" and rec["held"] is True and rec["feasible"] is True
    assert rec["normal_force"] == state["normal_force"] and rec["tip_x"] == state["tip"][0]
    assert rec["tip_z"] == state["tip"][1] and rec["required_mu"] == state["required_mu"]
    assert rec["bvp_normal_force"] == sol.normal_force and rec["bvp_feasible"] is sol.feasible
    assert rec["agree"] is True


def test_rejected_and_failing_points_are_recorded(monkeypatch):
    g = make_grid("I", kappa=(-6, -5, 2), b=(0.001, 0.6, 2), links=LINKS)
    import simgrip.compare as compare

    real = compare.simulate

    def flaky(grip, params, profile, links, **kw):
        if profile.kappa == -5.0:
            raise ZeroDivisionError("boom")
        return real(grip, params, profile, links, **kw)

    monkeypatch.setattr(compare, "simulate", flaky)
    res = run_sweep(g, options=ONE)
    status = [(r["kappa"], r["b"], r["status"]) for r in res.rows]
    assert status == [(-6, 0.001, "rejected"), (-6, 0.6, "settled"), (-5, 0.001, "error"), (-5, 0.6, "error")]
    assert "b" in res.rows[0]["message"] and res.rows[0]["held"] is None and res.rows[0]["agree"] is None
    assert res.rows[2]["message"] == "ZeroDivisionError: boom"
    assert res.counts["rejected"] == 1 and res.counts["error"] == 2 and res.counts["settled"] == 1


# files ----------------------------------------------------------------------------------------

def test_cli_writes_csv_json_map(tmp_path, reference, capsys):
    out = tmp_path / "s"
    rc = main(["sweep", "I", "--kappa", "-7", "-3", "3", "--M", "2", "8", "2", "--links", str(LINKS),
               "--out", str(out), "--jobs", "1", "--no-progress"])
    assert rc == 0
    assert sorted(p.name for p in out.iterdir()) == ["map.png", "sweep.csv", "sweep.json"]  # no .partial left
    rows = read_csv(out / "sweep.csv")
    assert same_results(rows, reference.rows)
    header = (out / "sweep.csv").read_text().splitlines()[0].split(",")
    assert tuple(header) == COLUMNS
    meta = json.loads((out / "sweep.json").read_text())
    assert meta["arguments"]["axes"]["kappa"] == [-7.0, -5.0, -3.0] and meta["arguments"]["links"] == LINKS
    assert meta["counts"]["points"] == 6 and meta["counts"]["computed"] == 6 and meta["counts"]["resumed"] == 0
    assert meta["counts"]["feasible"] == reference.counts["feasible"] and "dask" in meta["versions"]
    assert (out / "map.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # both verdicts occur, so the map has something to show
    assert 0 < reference.counts["feasible"] < 6 and reference.counts["disagree"] == 0


@pytest.mark.parametrize("args, words", [
    (["--kappa", "-7", "-3", "0"], "kappa: NUM"),
    (["--kappa", "-3", "-7", "3"], "kappa: STOP"),
    (["--kappa", "-5", "--M", "nan"], "M"),
    (["--kappa", "-5", "--D", "1", "2"], "D takes one value or START STOP NUM"),
    (["--kappa", "-5", "--frobnicate", "1"], "frobnicate"),
    (["--kappa", "-5", "--jobs", "0"], "jobs"),
    (["--kappa", "-5", "--batch-size", "0"], "batch-size"),
])
def test_cli_bad_grid_exit_2_naming_the_parameter(tmp_path, capsys, args, words):
    out = tmp_path / "o"
    rc = main(["sweep", "I", *args, "--links", str(LINKS), "--out", str(out), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 2 and words in err, err
    assert not (out / "sweep.csv").exists()


def test_cli_bad_out_exit_2_before_work(tmp_path, capsys):
    f = tmp_path / "file"
    f.write_text("x")
    rc = main(["sweep", "I", "--kappa", "-5", "--links", str(LINKS), "--out", str(f), "--jobs", "1"])
    assert rc == 2 and "--out" in capsys.readouterr().err
    if os.geteuid() != 0:  # root writes anywhere
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o500)
        rc = main(["sweep", "I", "--kappa", "-5", "--links", str(LINKS), "--out", str(ro / "x"), "--jobs", "1"])
        assert rc == 2 and "--out" in capsys.readouterr().err


# Dask -----------------------------------------------------------------------------------------

def test_local_cluster_equals_the_loop(reference):
    res = run_sweep(small_grid(), options=RunnerOptions(jobs=2, progress=False), batch_size=1)
    assert same_results(res.rows, reference.rows)  # (other batch sizes: the dask-CLI cluster's test)
    assert [r["index"] for r in res.rows] == list(range(6))


@pytest.fixture(scope="module")
def cli_cluster():
    from simgrip.parallel.cli_cluster import dask_cli_cluster

    with dask_cli_cluster(2) as running:
        yield running


def _worker_processes(worker_cmd_pid: int) -> list[int]:
    """The worker processes of a ``dask worker`` command (spawned by its nannies)."""
    out = []
    for pid in descendants(worker_cmd_pid):
        try:
            cmd = Path(f"/proc/{pid}/cmdline").read_bytes()
        except OSError:
            continue
        if b"resource_tracker" not in cmd:
            out.append(pid)
    return out


def test_dask_cli_cluster_equals_the_loop(cli_cluster, reference):
    address, scheduler_file, _ = cli_cluster
    res = run_sweep(small_grid(), options=RunnerOptions(scheduler=address, progress=False), batch_size=2)
    assert same_results(res.rows, reference.rows)
    res = run_sweep(small_grid(), options=RunnerOptions(scheduler_file=scheduler_file, progress=False), batch_size=5)
    assert same_results(res.rows, reference.rows)


def test_points_stream_to_the_cluster_rows_unchanged(cli_cluster, reference, tmp_path, monkeypatch):
    """A sweep reaches Dask as a generator of segments, in one runner call that keeps no results (bounded
    client memory: tests/test_sweep_stream.py bounds what is in flight); rows unchanged."""
    import simgrip.sweep.run as sweep_run

    address, _, _ = cli_cluster
    calls = []
    real = sweep_run.run_tasks
    monkeypatch.setattr(sweep_run, "run_tasks", lambda fn, items, **kw: calls.append((hasattr(items, "__len__"),
                                                                                     kw["collect"], kw["total"]))
                        or real(fn, items, **kw))
    res = run_sweep(small_grid(), out=tmp_path / "c", options=RunnerOptions(scheduler=address, progress=False),
                    batch_size=1)
    assert calls == [(False, False, 3)] and res.computed == 6  # 3 segments: the M line (2 values) at each kappa
    assert same_results(read_csv(tmp_path / "c" / "sweep.csv"), reference.rows)


def test_a_worker_killed_mid_sweep_loses_and_doubles_nothing(cli_cluster, tmp_path):
    address, _, worker = cli_cluster
    grid = make_grid("I", kappa=(-7, -3, 6), M=(2, 8, 2), links=LINKS)
    victims = _worker_processes(worker.pid)
    assert len(victims) == 2
    seen, killed = [], []

    def on_record(rec):
        seen.append(rec["index"])
        if len(seen) == 2 and not killed:  # work is still in flight on both workers
            os.kill(victims[0], signal.SIGKILL)
            killed.append(victims[0])

    res = run_sweep(grid, out=tmp_path / "k", options=RunnerOptions(scheduler=address, progress=False),
                    batch_size=1, on_record=on_record)
    assert killed and len(seen) < grid.size + 2
    assert sorted(seen) == list(range(grid.size))  # each point arrived exactly once
    ref = run_sweep(grid, options=ONE)
    assert same_results(res.rows, ref.rows)
    assert same_results(read_csv(tmp_path / "k" / "sweep.csv"), ref.rows)
    # the nanny replaced the killed worker: the cluster still has two (30 s only guards a hang; the nanny
    # restarts a worker in ~1 s), the killed one not among them
    deadline = time.monotonic() + 30
    while len(_worker_processes(worker.pid)) < 2 and time.monotonic() < deadline:
        time.sleep(0.1)
    now = _worker_processes(worker.pid)
    assert len(now) == 2 and killed[0] not in now, now


# interrupt and resume -------------------------------------------------------------------------

def test_resume_after_ctrl_c_recomputes_nothing_saved(tmp_path):
    out = tmp_path / "r"
    cmd = [sys.executable, "-m", "simgrip.cli", "sweep", "I", "--kappa", "-7", "-3", "80", "--links", str(LINKS),
           "--out", str(out), "--jobs", "1", "--no-progress"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while not list((out / PARTIAL).glob("batch-*.csv")):
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline
            time.sleep(0.02)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=10)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 130, err
    assert "--resume" in err and "Traceback" not in err
    assert not (out / "sweep.csv").exists() and not (out / "sweep.json").exists()
    saved = {}
    for f in (out / PARTIAL).glob("batch-*.csv"):
        for r in read_csv(f):
            saved[r["index"]] = r
    assert 0 < len(saved) < 80  # 3 segments (32, 32, 16 points): stopped in the 2nd

    grid = make_grid("I", kappa=(-7, -3, 80), links=LINKS)
    # without --resume the unfinished sweep is refused, naming --resume; a different grid is refused too
    with pytest.raises(ValueError, match="--resume"):
        run_sweep(grid, out=out, options=ONE)
    with pytest.raises(ValueError, match="different sweep"):
        run_sweep(make_grid("I", kappa=(-7, -3, 81), links=LINKS), out=out, options=ONE, resume=True)
    computed = []
    res = run_sweep(grid, out=out, options=ONE, resume=True, on_record=lambda r: computed.append(r["index"]))
    assert not set(computed) & set(saved)  # nothing saved was recomputed ...
    assert sorted(computed + list(saved)) == list(range(80))  # ... and nothing is missing
    assert res.resumed == len(saved) and res.computed == 80 - len(saved)
    for i, r in saved.items():
        assert res.rows[i] == {"index": i, **{c: r[c] for c in COLUMNS}}  # saved rows, times included
    # the resumed rows are the points' own answers (their segment's: the BVP warm-started along it)
    for i in (min(saved), max(saved), min(computed), max(computed)):
        a, b = next((a, b) for a, b in grid.segments() if a <= i < b)
        fresh = evaluate_segment([grid.point(k) for k in range(a, b)])[i - a]
        assert same_results([res.rows[i]], [fresh])
    assert not (out / PARTIAL).exists()
    meta = json.loads((out / "sweep.json").read_text())
    assert meta["counts"]["resumed"] == len(saved) and meta["counts"]["points"] == 80
    assert all(math.isfinite(r["kappa"]) for r in read_csv(out / "sweep.csv"))


def test_scheduler_gone_leaves_a_resumable_sweep(tmp_path):
    from simgrip.parallel.cli_cluster import dask_cli_cluster
    from simgrip.parallel.runner import RunnerError

    grid = make_grid("I", kappa=(-7, -3, 3), M=(2, 8, 2), links=LINKS)
    out = tmp_path / "g"
    with dask_cli_cluster(1) as (address, scheduler_file, worker):
        sched = [int(p) for p in os.listdir("/proc") if p.isdigit() and _cmdline_has(int(p), b"scheduler", scheduler_file)]
        assert len(sched) == 1
        got = []

        def on_record(rec):
            got.append(rec["index"])
            if len(got) == 1:
                os.kill(sched[0], signal.SIGKILL)

        with pytest.raises(RunnerError):
            run_sweep(grid, out=out, options=RunnerOptions(scheduler=address, progress=False), batch_size=1,
                      on_record=on_record)
    assert not (out / "sweep.csv").exists()
    saved = [r["index"] for f in (out / PARTIAL).glob("batch-*.csv") for r in read_csv(f)]
    assert sorted(saved) == sorted(got) and len(saved) >= 1
    res = run_sweep(grid, out=out, options=ONE, resume=True)
    assert res.resumed == len(saved) and res.computed == grid.size - len(saved)
    assert same_results(res.rows, run_sweep(grid, options=ONE).rows)


def _cmdline_has(pid: int, word: bytes, scheduler_file: str) -> bool:
    try:
        cmd = Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return False
    return word in cmd and scheduler_file.encode() in cmd and b"worker" not in cmd


def test_profile_runs_every_way_with_identical_rows():
    from simgrip.sweep.profile import format_profile, profile_sweep

    prof = profile_sweep(make_grid("I", kappa=(-7, -5, 2), links=LINKS), workers=2, cli_cluster=False)
    assert [r["run"] for r in prof["runs"]] == ["loop", "dask_1_worker", "local_2_workers"]
    assert all(r["identical_to_loop"] for r in prof["runs"])
    assert all(r["points_per_s"] > 0 and math.isfinite(r["runner_overhead_per_point_s"]) for r in prof["runs"])
    assert "overhead_vs_loop_fraction" in prof["runs"][1] and "points/s" in format_profile(prof)
    json.dumps(prof, allow_nan=False)


def test_links_above_the_maximum_are_refused_before_any_work(tmp_path, capsys):
    """``sweep --links 1001`` computed (1030: every point rejected, exit 0); simulate refused both: one bound."""
    from simgrip.cli import main
    from simgrip.params import MAX_LINKS

    for links in (MAX_LINKS + 1, 1030, 100000):
        assert main(["sweep", "I", "--kappa", "-5", "--links", str(links), "--jobs", "1", "--no-progress",
                     "--out", str(tmp_path / "o")]) == 2
        err = capsys.readouterr().err
        assert f"links must be at most {MAX_LINKS}" in err and "Traceback" not in err, err
    assert not (tmp_path / "o").exists()
