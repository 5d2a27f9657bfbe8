"""Issue 19: the sweep's reference at the cost of a continuation, ``--reference none``, streaming, throughput.

* continuation segments are fixed by the grid alone;
* the warm-started references equal the per-point cold solves (same verdicts, normal forces to the solver's
  tolerance) on lines that cross the hold/drop boundary of every grip; a warm walk that reaches another
  branch is solved cold and says so (``bvp_warning``);
* ``--jobs 1`` and ``--jobs 2`` write the same ``sweep.csv`` bytes but for the timing columns;
* ``--reference none`` solves no BVP and leaves its columns empty;
* the runner streams: a generator of items is consumed at most a bounded number of batches ahead of the
  results, whatever its length (counted, not timed), and ``sweep.json`` reports points/s/core.
"""

from __future__ import annotations

import csv
import io
import json
import math

import numpy as np
import pytest

from simgrip.cli import main
from simgrip.parallel.runner import IN_FLIGHT_PER_WORKER, RunnerOptions, run_tasks
from simgrip.sweep import point as sweep_point
from simgrip.sweep import reference as sweep_reference
from simgrip.sweep.grid import SEGMENT_POINTS, make_grid
from simgrip.sweep.point import TIME_COLUMNS, evaluate_point, evaluate_segment
from simgrip.sweep.run import run_sweep
from simgrip.sweep.store import LogHistogram, read_csv

LINKS = 8
ONE = RunnerOptions(jobs=1, progress=False)
#: Two converged solves (tolerance 1e-8 on the collocation residual, relative) of one equilibrium: the normal
#: force is an unknown parameter of the BVP, fixed by the residual to ~tol times the problem's conditioning;
#: 1e-6 relative is 100 x the tolerance (warm and cold solves measured 1e-12..5e-10 apart on these lines).
FORCE_RTOL = 1e-6


def _no_simulation(point):
    """The simulation is not under test here: the BVP columns alone are compared."""
    return {**{c: None for c in sweep_point.SIM_COLUMNS}, "wall_time_s": None, "message": ""}


# segments -------------------------------------------------------------------------------------

def test_segments_follow_the_fastest_swept_axis():
    assert list(make_grid("I", kappa=(-7, -3, 80), links=LINKS).segments()) == [(0, 32), (32, 64), (64, 80)]
    assert SEGMENT_POINTS == 32
    # kappa x M: the M line (2 values) at each kappa
    assert list(make_grid("I", kappa=(-7, -3, 3), M=(2, 8, 2), links=LINKS).segments()) == [(0, 2), (2, 4), (4, 6)]
    assert list(make_grid("I", kappa=-5, links=LINKS).segments()) == [(0, 1)]
    assert list(make_grid("I", kappa=(-7, -3, 5), links=LINKS).segments(2)) == [(0, 2), (2, 4), (4, 5)]
    with pytest.raises(ValueError, match="max_points"):
        list(make_grid("I", kappa=-5, links=LINKS).segments(0))


# continuation = cold -------------------------------------------------------------------------------

@pytest.mark.parametrize("grip, kappa, D, crosses", [
    ("I", (-7, -2, 33), 1.0, True),     # Grip I across the hold/drop boundary (kappa ~ -4.8 at M = 5)
    ("II", (1, 6, 33), 1.0, True),      # Grip II from dropped to held (kappa ~ 4.5)
    ("II", (3, 5, 17), 0.5, False),     # the sweep tests' Grip II corner
    ("III", (-6, -1, 33), 1.0, None),   # Grip III (two segments of the rod)
])
def test_warm_references_equal_the_cold_ones(monkeypatch, grip, kappa, D, crosses):
    monkeypatch.setattr(sweep_point, "_simulation", _no_simulation)
    grid = make_grid(grip, kappa=kappa, D=D, links=LINKS)
    (a, b), = list(grid.segments(64))  # one segment: the longest walk
    points = [grid.point(i) for i in range(a, b)]
    warm = evaluate_segment(points)
    cold = [evaluate_point(p) for p in points]
    assert [r["bvp_feasible"] for r in warm] == [r["bvp_feasible"] for r in cold]
    assert [r["bvp_message"] for r in warm] == [r["bvp_message"] for r in cold]
    if crosses is not None:  # the line crosses the hold/drop boundary (or not): verdicts of both kinds checked
        assert len({r["bvp_feasible"] for r in cold}) == (2 if crosses else 1)
    for w, c in zip(warm, cold):
        assert w["bvp_normal_force"] == pytest.approx(c["bvp_normal_force"], rel=FORCE_RTOL, abs=FORCE_RTOL)
        assert w["bvp_warning"] == ""


def walk_astray(monkeypatch) -> None:
    """Force the warm walk of points 4-6 onto another equilibrium (the cold solution at kappa + 3)."""
    real = sweep_reference.warm

    def astray(point, guess, *walk):
        if 4 <= point.index <= 6:  # the walk leaves the cold branch at point 4 and stays off until then
            from dataclasses import replace

            return sweep_reference.cold(replace(point, kappa=point.kappa + 3.0))
        return real(point, guess, *walk)

    monkeypatch.setattr(sweep_reference, "warm", astray)


def assert_astray_solved_cold(points) -> None:
    """Under :func:`walk_astray`: the segment ``points``' references are the cold ones, and only points 4-6
    (some of them) say they reached another branch and were solved cold."""
    warm = evaluate_segment(points)
    cold = [evaluate_point(p) for p in points]
    for w, c in zip(warm, cold):
        assert w["bvp_normal_force"] == pytest.approx(c["bvp_normal_force"], rel=FORCE_RTOL)
        assert w["bvp_feasible"] is c["bvp_feasible"]
    warned = [r["index"] for r in warm if r["bvp_warning"]]
    assert warned and set(warned) <= {4, 5, 6}, warned
    assert all("another branch" in warm[i]["bvp_warning"] and "solved cold" in warm[i]["bvp_warning"] for i in warned)


def test_a_walk_on_another_branch_is_solved_cold_and_says_so(monkeypatch):
    """A warm start that lands on another equilibrium (here: forced, the solution at kappa + 3) is found at the
    next cold check, the interval bisected, and every reference is the cold one; the points checked say so."""
    monkeypatch.setattr(sweep_point, "_simulation", _no_simulation)
    walk_astray(monkeypatch)  # the walk leaves the cold branch at point 4 and stays off until the end
    grid = make_grid("I", kappa=(-7, -5, 9), links=LINKS)
    assert_astray_solved_cold([grid.point(i) for i in range(grid.size)])


# determinism ------------------------------------------------------------------------------------

def _without_times(path) -> str:
    rows = list(csv.reader(io.StringIO(path.read_text(encoding="utf-8"))))
    keep = [k for k, c in enumerate(rows[0]) if c not in TIME_COLUMNS]
    return "\n".join(",".join(r[k] for k in keep) for r in rows)


def test_jobs_1_and_2_write_the_same_csv_but_times(tmp_path):
    grid = make_grid("I", kappa=(-7, -3, 34), links=LINKS)  # 2 segments: 32 + 2 points
    run_sweep(grid, out=tmp_path / "one", options=ONE, write_map=False, note=None)
    run_sweep(grid, out=tmp_path / "two", options=RunnerOptions(jobs=2, progress=False), batch_size=1,
              write_map=False, note=None)
    one, two = _without_times(tmp_path / "one" / "sweep.csv"), _without_times(tmp_path / "two" / "sweep.csv")
    assert one == two and one.count("\n") == 34
    meta = json.loads((tmp_path / "two" / "sweep.json").read_text())
    assert meta["throughput"]["cores"] == 2 and meta["arguments"]["reference"] == "bvp"


# --reference none -------------------------------------------------------------------------------

def test_reference_none_solves_no_bvp(tmp_path, monkeypatch, capsys):
    def no_bvp(point):
        raise AssertionError("a BVP was solved with reference none")

    monkeypatch.setattr(sweep_reference, "cold", no_bvp)
    rc = main(["sweep", "I", "--kappa", "-7", "-3", "3", "--links", str(LINKS), "--jobs", "1", "--out",
               str(tmp_path / "n"), "--no-progress", "--no-map", "--reference", "none"])
    err = capsys.readouterr().err
    assert rc in (0, None) and "no BVP reference" in err, err
    rows = read_csv(tmp_path / "n" / "sweep.csv")
    assert len(rows) == 3 and all(r["status"] == "settled" for r in rows)
    for r in rows:
        assert r["bvp_normal_force"] is None and r["bvp_feasible"] is None and r["bvp_required_mu"] is None
        assert r["agree"] is None and r["bvp_message"] == "" and r["bvp_warning"] == ""
    meta = json.loads((tmp_path / "n" / "sweep.json").read_text())
    assert meta["arguments"]["reference"] == "none" and meta["counts"]["bvp_failed"] == 0
    # a saved sweep of the other reference is another sweep: --resume refuses it
    rc = main(["sweep", "I", "--kappa", "-7", "-3", "3", "--links", str(LINKS), "--jobs", "1", "--out",
               str(tmp_path / "n"), "--no-progress", "--no-map", "--resume"])
    assert rc == 2 and "different grid" in capsys.readouterr().err


def test_bad_reference_exit_2_naming_it(tmp_path, capsys):
    rc = main(["sweep", "I", "--kappa", "-5", "--links", str(LINKS), "--out", str(tmp_path / "x"),
               "--reference", "chain"])
    err = capsys.readouterr().err
    assert rc == 2 and "reference must be one of ('bvp', 'none')" in err and "Traceback" not in err
    assert not (tmp_path / "x").exists()


# streaming ---------------------------------------------------------------------------------------

class _Counted:
    """A generator of ``n`` items that counts how many were taken."""

    def __init__(self, n):
        self.n, self.taken = n, 0

    def __iter__(self):
        for i in range(self.n):
            self.taken += 1
            yield i


@pytest.mark.parametrize("jobs", [1, 2])
def test_runner_takes_items_a_bounded_way_ahead_and_keeps_no_results(jobs):
    """``collect=False``: the items taken but not yet returned never exceed the in-flight bound (in-process:
    one), for 200 and for 2000 items alike -- what the client holds does not grow with the items."""
    for n in ((200, 2000) if jobs == 1 else (2000,)):  # one local cluster start is enough: the bound is fixed
        items = _Counted(n)
        ahead, done = [], [0]

        def seen(i, r):
            done[0] += 1
            ahead.append(items.taken - done[0])

        batch = 10
        out = run_tasks(abs, iter(items), options=RunnerOptions(jobs=jobs, progress=False), batch_size=batch,
                        on_result=seen, collect=False, total=n)
        assert out is None and done[0] == n and items.taken == n
        bound = 0 if jobs == 1 else IN_FLIGHT_PER_WORKER * jobs * batch
        assert max(ahead) <= bound, (n, max(ahead), bound)
    with pytest.raises(ValueError, match="total"):
        run_tasks(abs, iter(range(3)), options=ONE, collect=False)


def test_sweep_json_reports_throughput(tmp_path, monkeypatch):
    monkeypatch.setattr(sweep_point, "_simulation", lambda p: {**_no_simulation(p), "status": "settled",
                                                               "wall_time_s": 0.01})
    grid = make_grid("I", kappa=(-7, -3, 5), links=LINKS, reference="none")
    res = run_sweep(grid, out=tmp_path / "t", options=ONE, write_map=False, note=None)
    t = json.loads((tmp_path / "t" / "sweep.json").read_text())["throughput"]
    assert t == res.throughput and t["points"] == 5 and t["cores"] == 1
    assert t["points_per_s"] > 0 and t["points_per_s_per_core"] == t["points_per_s"]
    assert t["settle_median_s"] == pytest.approx(0.01, rel=0.006)  # the histogram's bin: 10**(0.5/200) - 1
    assert t["wall_per_point_over_settle"] == pytest.approx(t["wall_per_point_s"] / t["settle_median_s"])
    assert math.isfinite(t["point_over_settle_median"])


def test_log_histogram_median_within_its_bin():
    rng = np.random.default_rng(1)
    for v in (rng.lognormal(-4, 1, 1001), rng.uniform(1e-3, 2e-3, 20), np.array([3.0])):
        h = LogHistogram()
        for x in v:
            h.add(float(x))
        assert h.median() == pytest.approx(float(np.median(v)), rel=10 ** (1 / LogHistogram.BINS_PER_DECADE) - 1)
    assert LogHistogram().median() is None
