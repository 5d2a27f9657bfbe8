"""Resources (issue 16, section 2): what cannot finish is refused before any work, what cannot help is capped.

* grid sizes are estimated from the option values alone (no array): ``1e10``,
  ``1e300``, inf, NaN, a non-integer NUM, a 10^9-point grid end in one line
  naming the option(s) and the estimate (exit 2), fast and without allocating;
* the estimate's bounds (points, memory, disk, time) each refuse, on a stated
  machine (:class:`simgrip.sweep.budget.Machine`);
* ``--jobs`` above the bound is refused, above the tasks or 2 per core capped
  with a note; ``stress --cases 1000000000`` is refused;
* a running sweep streams its rows: the client's memory does not grow with
  the number of points (measured with tracemalloc on a fast stand-in for the
  point's physics), and a map too big to show is refused before the work.
"""

from __future__ import annotations

import time
import tracemalloc

import pytest

from simgrip.cli import main
from simgrip.parallel.runner import RunnerOptions
from simgrip.sweep import budget, run as sweep_run
from simgrip.sweep.budget import JOBS_PER_CORE, MAX_JOBS, MAX_POINTS, Machine, cap_jobs, check_stress, check_sweep
from simgrip.sweep.grid import AXES, make_grid
from simgrip.sweep.point import COLUMNS
from simgrip.sweep.store import PARTIAL, read_csv

LINKS = 8
ONE = RunnerOptions(jobs=1, progress=False)
SMALL = Machine(memory=8 * 2**30, cores=2, disk=100 * 2**30)


@pytest.mark.parametrize("num, words", [
    ("1e10", "10000000000 (1e+10) points would need"),
    ("1e300", "~1e+300 points would need"),
    ("inf", "kappa: NUM must be finite"),
    ("nan", "kappa: NUM must be finite"),
    ("2.5", "kappa: NUM must be an integer"),
    ("100000000", "100000000 (1e+08) values on one axis"),
])
def test_huge_or_bad_num_refused_before_allocating(tmp_path, capsys, num, words):
    out = tmp_path / "o"
    tracemalloc.start()
    t0 = time.perf_counter()
    try:
        rc = main(["sweep", "I", "--kappa", "-7", "-3", num, "--links", "16", "--out", str(out), "--jobs", "1"])
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    err = capsys.readouterr().err
    assert rc == 2 and words in err and err.startswith("simgrip sweep: error: kappa"), err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert peak < 50 * 2**20  # nothing of the grid's size was allocated (10^8 floats would be 800 MB)
    assert time.perf_counter() - t0 < 30 and not out.exists()


def test_billion_point_grid_names_every_swept_option_and_the_estimate(capsys):
    rc = main(["sweep", "I", "--kappa", "-7", "-3", "1000", "--M", "1", "10", "1000", "--mu", "0.5", "1", "1000",
               "--links", "16", "--out", "unused", "--jobs", "1"])
    err = capsys.readouterr().err
    assert rc == 2, err
    assert "kappa (1000) x M (1000) x mu (1000): 1000000000 (1e+09) points" in err
    assert "MB of memory" in err and "GB of disk" in err and "years" in err and f"at most {MAX_POINTS} points" in err


def test_each_bound_refuses_on_a_stated_machine():
    counts = {a: 1 for a in AXES}
    # time: 10^7 points of the dynamics at 1000 links, one worker: 1.8 s a point = 208 days > 7
    with pytest.raises(ValueError, match=r"at most \d+ points here \(7 days on 1 worker\)"):
        check_sweep({**counts, "kappa": 10**7}, 1000, "dynamics", workers=1, here=SMALL)
    # disk: 10^6 rows x 2 x 400 bytes = 0.8 GB on a disk with 0.1 GB free
    tiny_disk = Machine(memory=8 * 2**30, cores=2, disk=10**8)
    with pytest.raises(ValueError, match="free disk of --out"):
        check_sweep({**counts, "kappa": 1000, "M": 1000}, 8, workers=2, here=tiny_disk)
    # memory: rows kept in memory (no --out) at 2 kB a point, 10^6 points on 1 GB available
    with pytest.raises(ValueError, match="memory available"):
        check_sweep({**counts, "kappa": 1000, "M": 1000}, 8, workers=2, to_disk=False,
                    here=Machine(memory=2**30, cores=2))
    # the same grid streamed to disk fits: one byte a point
    est = check_sweep({**counts, "kappa": 1000, "M": 1000}, 8, workers=2, here=SMALL)
    assert est.points == 10**6 and est.memory_bytes < 30 * 2**20 and est.disk_bytes == 8e8
    assert est.seconds == pytest.approx(10**6 * (0.025 + 0.0005 * 8) / 2)


def test_run_sweep_checks_the_disk_of_out_before_work(tmp_path, monkeypatch):
    monkeypatch.setattr(sweep_run, "machine", lambda out=None: Machine(memory=8 * 2**30, cores=2, disk=4000))
    grid = make_grid("I", kappa=(-7, -3, 6), links=LINKS)  # 6 rows x 800 bytes > 4000
    computed = []
    with pytest.raises(ValueError, match="free disk of --out"):
        sweep_run.run_sweep(grid, out=tmp_path / "o", options=ONE, on_record=computed.append)
    assert computed == [] and not (tmp_path / "o").exists()


def test_jobs_capped_with_a_note_or_refused():
    assert cap_jobs(1000, 3, here=SMALL) == (3, "jobs 1000 lowered to 3 (3 tasks to run)")
    jobs, note = cap_jobs(1000, 10**6, here=SMALL)
    assert jobs == 2 * JOBS_PER_CORE and f"{JOBS_PER_CORE} per core on 2 cores" in note
    jobs, note = cap_jobs(64, 10**6, here=Machine(memory=2 * 2**30, cores=64))
    assert jobs == 3 and "memory" in note  # 1 GB of the 2 GB available at 300 MB a worker
    assert cap_jobs(2, 100, here=SMALL) == (2, None)
    assert cap_jobs(None, 100, here=SMALL) == (None, None) and cap_jobs(None, 1, here=SMALL) == (1, None)
    with pytest.raises(ValueError, match=f"jobs: 100000 worker processes is above the bound of {MAX_JOBS}"):
        cap_jobs(100000, 10, here=SMALL)
    for bad in (0, -3, 2.5, True):
        with pytest.raises(ValueError, match="jobs must be a positive integer"):
            cap_jobs(bad, 10, here=SMALL)


def test_cli_jobs_above_the_bound_exit_2_before_work(tmp_path, capsys):
    for cmd in (["sweep", "I", "--kappa", "-7", "-3", "3", "--links", str(LINKS)], ["stress", "--cases", "2"],
                ["bench", "--quick"]):
        out = tmp_path / cmd[0]
        t0 = time.perf_counter()
        rc = main([*cmd, "--out", str(out), "--jobs", "100000", "--no-progress"])
        err = capsys.readouterr().err
        assert rc == 2 and "jobs: 100000 worker processes is above the bound" in err, (cmd, err)
        assert time.perf_counter() - t0 < 30 and not any(out.glob("*")) if out.exists() else True


def _fake_point(point):
    """A stand-in for the point's physics: a record of the right shape, at once."""
    rec = {"index": point.index, **point.values(), "status": "settled", "held": True, "feasible": point.kappa < -5,
           "valid": True, "normal_force": 1.0, "required_mu": 0.5, "tip_x": 0.3, "tip_z": -0.5, "penetration": 1e-6,
           "bvp_normal_force": 1.0, "bvp_feasible": point.kappa < -5, "bvp_required_mu": 0.5, "agree": True,
           "wall_time_s": 0.01, "point_time_s": 0.02, "message": "", "bvp_message": "", "bvp_warning": ""}
    return {"index": rec["index"], **{c: rec[c] for c in COLUMNS}}


def _fake_segment(points):
    return [_fake_point(p) for p in points]


def test_client_memory_does_not_grow_with_the_points(tmp_path, monkeypatch):
    """Peak traced memory of a 500- and a 5000-point sweep (jobs 1): the difference is ~1 byte a point, where
    keeping the rows would cost ~1.3 kB a point (~6 MB for the 4500 more); 1 MiB allows for allocator noise."""
    monkeypatch.setattr(sweep_run, "evaluate_segment", _fake_segment)
    peaks = {}
    for n in (100, 500, 5000):  # the first warms up (imports, matplotlib's caches), not measured
        grid = make_grid("I", kappa=(-7, -3, n // 10), M=(1, 10, 10), links=LINKS)
        tracemalloc.start()
        try:
            res = sweep_run.run_sweep(grid, out=tmp_path / str(n), options=ONE, note=None, write_map=False)
            peaks[n] = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        assert res.computed == n and res.counts["points"] == n and res.records is None
        assert res.counts["feasible"] == sum(1 for r in res.iter_rows() if r["kappa"] < -5)
        assert not (tmp_path / str(n) / PARTIAL).exists()
    rows = read_csv(tmp_path / "5000" / "sweep.csv")
    assert [r["kappa"] for r in rows[:11:10]] == [-7.0, grid.axes["kappa"][1]] and len(rows) == 5000
    assert peaks[5000] - peaks[500] < 2**20, peaks


def test_map_too_big_to_show_is_refused_before_work(tmp_path):
    grid = make_grid("I", kappa=(-7, -3, 600), M=(1, 10, 600), links=LINKS)
    computed = []
    with pytest.raises(ValueError, match="map: 600 \\(kappa\\) x 600 \\(M\\) = 360000 cells .*--no-map"):
        sweep_run.run_sweep(grid, out=tmp_path / "o", options=ONE, on_record=computed.append)
    assert computed == [] and not (tmp_path / "o" / PARTIAL).exists()


def test_stress_case_count_bounded_before_any_case(tmp_path, capsys):
    t0 = time.perf_counter()
    rc = main(["stress", "--cases", "1000000000", "--out", str(tmp_path / "s"), "--jobs", "1"])
    err = capsys.readouterr().err
    assert rc == 2 and err.startswith("simgrip stress: error: cases: 1000000000 (1e+09) cases"), err
    assert "at most 1000000 cases" in err and "Traceback" not in err and time.perf_counter() - t0 < 30
    assert check_stress(500, 10, workers=2, here=SMALL) == pytest.approx(510 * 0.15 / 2)
    with pytest.raises(ValueError, match="gripper_cases"):
        check_stress(1, 10**7, workers=2, here=SMALL)
    with pytest.raises(ValueError, match="memory"):  # 10^5 cases x 10 kB = 1 GB > half of 1 GB
        check_stress(10**5, 0, workers=2, here=Machine(memory=2**30, cores=2))
    # full-contact cases, 20 cases each, named as themselves (they were counted into gripper_cases' message)
    assert check_stress(10, 0, full_cases=2, workers=1, here=SMALL) == pytest.approx(50 * 0.15)
    with pytest.raises(ValueError, match=r"^full_cases: 2 cases \+ 1000000 \(1e\+06\) full-contact cases"):
        check_stress(2, 0, full_cases=10**6, workers=2, here=SMALL)


def test_machine_is_read():
    here = budget.machine(".")
    assert here.memory > 0 and here.cores >= 1 and here.disk is not None and here.disk > 0


def test_a_default_sweep_too_small_for_a_cluster_runs_in_process(monkeypatch):
    """Default ``--jobs`` (all cores) on a few fast points: a local cluster would cost more to start than it
    saves (``worth_a_cluster``), so the runner gets ``jobs=1``; an explicit ``--jobs 2`` is honoured."""
    seen = []

    def fake_run_tasks(fn, items, *, options, **kw):
        seen.append(options.jobs)
        out = [fn(x) for x in items]
        for i, r in enumerate(out):
            if kw.get("on_result"):
                kw["on_result"](i, r)
        return out

    monkeypatch.setattr(sweep_run, "run_tasks", fake_run_tasks)
    monkeypatch.setattr(sweep_run, "evaluate_segment", _fake_segment)
    monkeypatch.setattr(sweep_run, "machine", lambda out=None: Machine(memory=8 * 2**30, cores=2, disk=4000))
    grid = make_grid("I", kappa=(-7, -3, 3), links=LINKS)
    sweep_run.run_sweep(grid, options=RunnerOptions(jobs=None, progress=False))
    sweep_run.run_sweep(grid, options=RunnerOptions(jobs=2, progress=False))
    assert seen == [1, 2]
    per_point = budget.seconds_per_point(LINKS)
    assert not budget.worth_a_cluster(3, LINKS, "newton", 2)
    # worth it once the saved half of the work exceeds the start: T/2 > LOCAL_CLUSTER_START_S
    n = int(2 * budget.LOCAL_CLUSTER_START_S / per_point) + 2
    assert budget.worth_a_cluster(n, LINKS, "newton", 2) and not budget.worth_a_cluster(n, LINKS, "newton", 1)
