"""Small numerical stress run: every case ends settled or with a named error."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from simgrip.harness.stress import (
    GRIPS,
    make_cases,
    names_an_input,
    run_stress,
    self_intersects,
    PHYSICAL_FLAGS,
)


@pytest.fixture(scope="module")
def stress(tmp_path_factory):
    out = tmp_path_factory.mktemp("stress")
    # n <= 64 keeps this under half a minute on two cores; the 60 s guard per case only
    # catches hangs (a case takes well under a second), so a loaded machine cannot fail it
    return run_stress(out, cases=40, seed=1, jobs=1, progress=False, timeout_s=60.0, grid_cases=16, max_links=64), out


def test_no_failures(stress):
    res, _ = stress
    assert res.counts["total"] == 40
    assert res.counts["failed"] == 0, res.failures
    assert sum(res.counts[k] for k in ("settled", "rejected", "unsettled", "failed")) == 40
    assert {c["grip"] for c in res.cases} == set(GRIPS)
    assert sum(c["source"] == "random" for c in res.cases) == 24


def test_rejections_name_a_parameter(stress):
    res, _ = stress
    for c in res.rejected:
        assert c["error_type"] == "ValueError"
        assert names_an_input(c["error"]), c["error"]


def test_rejection_names():
    assert names_an_input("gamma (contact arc length over l) must lie in (0, 1), got 2")
    assert names_an_input("profile: no Grip III starting shape with gamma = 0.8")
    assert not names_an_input("11 is not in list")


def test_settled_states_are_finite_and_converged(stress):
    res, _ = stress
    settled = [c for c in res.cases if c["outcome"] == "settled"]
    # every case that is not a named rejection settles (README: 500 of 500 in the full run), so the checks
    # below see every one of them: none can pass by nothing settling (issue 22, item 7)
    assert len(settled) == res.counts["settled"] == 40 - res.counts["rejected"]
    assert res.counts["rejected"] == 0  # the box's inputs are all valid (seed 1: 40 settled)
    for c in res.cases:
        if c["outcome"] == "settled":
            # settle's tol is 1e-10; it may stop at its noise floor (reported to the lead), never far above
            assert math.isfinite(c["residual"]) and c["residual"] <= 1e-6
            assert set(c["flags"]) >= {"self_intersection", "penetration", "tip_touches_workpiece"}


def test_files(stress):
    res, out = stress
    data = json.loads((out / "stress.json").read_text())
    assert data["counts"]["total"] == 40 and len(data["cases"]) == 40
    assert (out / "stability_map.png").read_bytes()[:4] == b"\x89PNG"


def test_cases_are_deterministic():
    a, b = make_cases(120, seed=3), make_cases(120, seed=3)
    assert a == b and len(a) == 120
    assert make_cases(120, seed=4) != a


def test_self_intersection_check():
    s = np.linspace(0, 1, 65)
    half = np.stack([np.cos(np.pi * s), np.sin(np.pi * s)], axis=1)  # half circle: no crossing
    assert not self_intersects(half)
    # a chain curled uniformly through 1.2 turns passes through itself
    phi = np.cumsum(np.full(64, 2.4 * np.pi / 64))
    nodes = np.vstack([[0, 0], np.cumsum(np.stack([np.cos(phi), np.sin(phi)], axis=1) / 64, axis=0)])
    assert self_intersects(nodes)
    assert not self_intersects(nodes[:50])  # less than a full turn
    zigzag = np.array([[0, 0], [1, 0], [1, 1], [0.5, -0.5]])
    assert self_intersects(zigzag)
    assert not self_intersects(np.array([[0, 0], [1, 0], [2, 0]]))


def test_small_runs_spread_over_the_box():
    from simgrip.harness.stress_cases import BOX

    cs = make_cases(20)
    assert {c["grip"] for c in cs} == set(GRIPS)
    assert min(c["kappa"] for c in cs) < 0 < max(c["kappa"] for c in cs)
    logs = {"D", "mu_s", "n"}
    for key in ("D", "kappa", "M", "mu_s", "b", "n"):
        lo, hi = BOX[key]
        f = (lambda v: np.log10(v)) if key in logs else (lambda v: v)  # noqa: E731
        vals = [(f(c[key]) - f(lo)) / (f(hi) - f(lo)) for c in cs]
        assert min(vals) < 0.25 and max(vals) > 0.75, (key, vals)  # both ends of every range, not one row
    assert len({c["D"] for c in cs}) >= 5


def test_bad_inputs_and_out_are_refused_before_any_work(tmp_path, capsys, monkeypatch):
    from simgrip.cli import main
    from simgrip.parallel import runner

    def never(*a, **k):
        raise AssertionError("work started before the inputs were checked")

    monkeypatch.setattr(runner, "run_tasks", never)
    (tmp_path / "file").write_text("x")
    assert main(["stress", "--cases", "2", "--jobs", "1", "--no-progress", "--out", str(tmp_path / "file")]) == 2
    assert "--out" in capsys.readouterr().err
    assert main(["stress", "--cases", "2", "--seed", "-1", "--out", str(tmp_path / "o")]) == 2
    assert "seed" in capsys.readouterr().err
    with pytest.raises(ValueError, match="out_dir"):
        run_stress(tmp_path / "file", cases=2, jobs=1, progress=False)


def test_a_hang_is_a_named_failure_in_any_thread():
    import threading

    from simgrip.harness.stress import run_case

    case = dict(make_cases(1)[0], n=256)
    out = {}
    for where in ("main", "worker"):
        if where == "main":
            out[where] = run_case(case, timeout_s=0.02)
        else:  # a Dask worker runs tasks outside its main thread: no SIGALRM there
            t = threading.Thread(target=lambda: out.__setitem__(where, run_case(case, timeout_s=0.02)))
            t.start()
            t.join()
        assert out[where]["outcome"] == "failed" and out[where]["error_type"] == "Timeout", out[where]


def test_runs_on_an_existing_dask_cluster(tmp_path):
    """``--scheduler``: the same outcomes on a cluster reached by address (workers in threads here)."""
    from distributed import LocalCluster

    from simgrip.parallel.runner import RunnerOptions

    kw = dict(cases=6, seed=2, timeout_s=60.0, max_links=16)
    local = run_stress(tmp_path / "local", jobs=1, progress=False, **kw)
    # tcp on 127.0.0.1: the runner refuses inproc:// addresses (they exist only inside one process)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp", host="127.0.0.1",
                      dashboard_address="127.0.0.1:0", scheduler_kwargs={"dashboard": False}) as cluster:
        remote = run_stress(tmp_path / "remote", options=RunnerOptions(scheduler=cluster.scheduler_address,
                                                                       progress=False), **kw)
    strip = ("time_s",)
    assert [{k: v for k, v in c.items() if k not in strip} for c in remote.cases] == \
           [{k: v for k, v in c.items() if k not in strip} for c in local.cases]
    assert remote.jobs is None and local.jobs == 1


def test_no_invalid_state_is_returned_as_valid(stress):
    """Issue 17: every settled state the geometric checks find impossible (recomputed from its geometry by
    simgrip.validity.state_violations) was returned with valid False."""
    res, _ = stress
    assert res.counts["invalid_returned_as_valid"] == 0
    for c in res.cases:
        if c["outcome"] == "settled" and any(c["flags"][k] for k in PHYSICAL_FLAGS):
            assert c["valid"] is False and c["held"] is False
