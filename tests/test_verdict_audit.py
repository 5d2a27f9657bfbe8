"""Issue 16 §6: the Newton settle, the dynamics and the BVP give one hold/drop verdict, or the state says why not.

Runs the audit's representative subset (:func:`simgrip.harness.verdict_audit.quick_points`: each grip's
standard case and the box's corners that have answered differently, wrong-way curls, the issue's
reproductions) through every variant (planar, K = 2, 3, 4) and requires zero silent disagreements; the
full audit is ``python -m simgrip.harness.verdict_audit --out DIR --jobs N``.
"""

from __future__ import annotations

import json

import pytest

from simgrip.harness import verdict_audit as va

# Points of the subset whose silent disagreement lay in the planar dynamics (settle/dynamics.py, sim/scene.py),
# each settled on its own: now held as the Newton settle and the BVP hold it, or the dynamics' drop warned.
PLANAR_DYNAMICS = {
    ("III", -4.0, 1e-2, 0.0, 100.0): "a weightless workpiece was dropped (M = 0: the planar scene's 1e-12 rho l "
                                     "mass floor made MuJoCo's soft contact sink without bound); now its inertia "
                                     "is floored, its weight kept at M: held",
    ("III", -4.0, 1.0, 1e4, 100.0): "the heavy workpiece falls off the finger with MuJoCo's surface contact (the "
                                    "static settle with contact='surface' drops it too), the point contact holds: "
                                    "the dynamics' drop carries a warning that says so",
}


def _key(p):
    return (p["grip"], p["kappa"], p["D"], p["M"], p["mu_s"])


@pytest.fixture(scope="module")
def quick():
    points = [p for p in va.quick_points() if _key(p) not in PLANAR_DYNAMICS]
    return va.run_audit(points, jobs=1)


@pytest.mark.slow
def test_no_silent_disagreement_in_the_subset(quick):
    s = quick["summary"]
    assert s["silent"] == 0, [va._brief(r) for r in s["silent_rows"]]
    assert s["crashed"] == 0, [va._brief(r) for r in s["no_verdict_rows"] if r["crashed"]]
    # the default answers wherever another method does (issue 16 §6, third bullet)
    assert s["default_failed_where_another_answered"] == 0, [va._brief(r) for r in s["no_verdict_rows"]]
    assert s["cases"] == s["agree"] + s["warned"] + s["silent"] + s["no_verdict"]
    assert s["agree"] > s["cases"] // 2  # most of the box agrees outright: the audit compares real verdicts
    variants = {(r["grip"], r["variant"]) for r in quick["rows"] if r["outcome"] != "refused"}
    assert variants == {(g, v[0]) for g, vs in va.VARIANTS.items() for v in vs}
    # Grip III with three fingers is refused by the builder, naming the input
    refused = [r for r in quick["rows"] if r["outcome"] == "refused"]
    assert refused and all(r["grip"] == "III" and r["fingers"] == 3 and "fingers" in r["default_error"]
                           for r in refused)


@pytest.mark.slow
def test_wrong_way_curls_agree_not_held(quick):
    # issue 16 §6, third bullet: the default failed ("symmetric settle did not converge"); now every method
    # drops it: the settles in the other grip's shape (warned), the BVP on the grip's own branch (N < 0)
    rows = [r for r in quick["rows"] if (r["grip"], r["kappa"]) in (("I", 5.0), ("II", -5.0))]
    assert len(rows) == 8
    for r in rows:
        assert r["outcome"] == "agree" and r["default"] == "dropped", va._brief(r)
        assert r["default_warnings"][0].startswith("wrong grip:")


@pytest.mark.slow
def test_frictionless_weightless_boundary_is_warned(quick):
    rows = [r for r in quick["rows"] if r["outcome"] != "refused" and r["M"] == 0.0 and r["mu_s"] == 0.0
            and r["workpiece"] != "planar"]
    assert rows
    for r in rows:
        assert any("friction cone's boundary" in w for w in r["default_warnings"]), va._brief(r)
        assert r["outcome"] in ("agree", "warned")


@pytest.mark.slow
@pytest.mark.parametrize("key", sorted(PLANAR_DYNAMICS))
def test_known_planar_dynamics_disagreements(key):
    point = next(p for p in va.quick_points() if _key(p) == key)
    silent = [va._brief(r) for r in va.audit_point(point) if r["outcome"] == "silent"]
    assert not silent, silent


def test_classification():
    def res(verdict, warnings=(), error=None):
        return {"verdict": verdict, "warnings": list(warnings), "method": "m", "error": error,
                "refused": bool(error and error.startswith("ValueError")), "time_s": 0.0}

    assert va._classify({}, res("held"), res("held"), res("held"))["outcome"] == "agree"
    assert va._classify({}, res("held"), res("dropped"), res("held"))["outcome"] == "silent"
    assert va._classify({}, res("dropped", ["wrong grip: ..."]), res("dropped"), res("held"))["outcome"] == "warned"
    # a reference that names why (another branch, the cone's edge as the chain resolves it) warns too
    branch = res("dropped", ["the reference converged to another equilibrium branch: ..."])
    assert va._classify({}, res("held"), res("held"), branch)["outcome"] == "warned"
    assert va._classify({}, res(None, error="SettleError: x"), res("held"), res("held"))["outcome"] == "no_verdict"
    assert va._classify({}, res(None, error="ValueError: b"), res(None, error="ValueError: b"),
                        res("held"))["outcome"] == "refused"
    crash = va._run(lambda: None.N1)  # an unnamed exception is a crash, recorded, not raised
    assert crash["crashed"] and crash["error"].startswith("CRASH AttributeError") and crash["verdict"] is None
    row = va._classify({"grip": "I"}, crash, res("held"), res("held"))
    assert row["outcome"] == "no_verdict" and row["crashed"] and va.summarise([row])["crashed"] == 1
    rows = [va._classify({"grip": "I"}, res("held"), res("held"), res("held")),
            va._classify({"grip": "I"}, res(None, error="SettleError: x"), res("held"), res("held"))]
    s = va.summarise(rows)
    assert (s["cases"], s["agree"], s["no_verdict"], s["default_failed_where_another_answered"]) == (2, 1, 1, 1)


def test_points_cover_the_box():
    pts = va.audit_points()
    for grip in ("I", "II", "III"):
        grid = {(p["D"], p["M"], p["mu_s"]) for p in pts if p["grip"] == grip and p["where"] == "grid"}
        assert len(grid) == 27  # the 8 corners, 12 edge midpoints, 6 face centres and the centre
        kappas = {p["kappa"] for p in pts if p["grip"] == grip}
        assert kappas == set(va.KAPPAS[grip])
    edges = [p for p in pts if p["where"] == "edge"]
    assert {p["b"] for p in edges} >= {0.02, 1.9} and {p["gamma"] for p in edges} >= {0.31, 0.97}


def test_main_refuses_a_bad_out_and_writes_the_table(tmp_path, capsys, monkeypatch):
    f = tmp_path / "file"
    f.write_text("x")
    assert va.main(["--out", str(f), "--quick"]) == 2
    assert "--out" in capsys.readouterr().err
    assert va.main(["--out", str(tmp_path), "--jobs", "0"]) == 2
    # the command end to end on two points (the run itself is the fixture's)
    monkeypatch.setattr(va, "quick_points", lambda: [va._point("I", -6.0, 1.0, 5.0, 1.0)])
    assert va.main(["--out", str(tmp_path / "out"), "--quick", "--no-progress"]) == 0
    table = (tmp_path / "out" / "verdict_audit.md").read_text()
    assert "| cases | agreements | warned disagreements | silent disagreements |" in table
    data = json.loads((tmp_path / "out" / "verdict_audit.json").read_text())
    assert data["summary"]["cases"] == 4 and data["summary"]["agree"] == 4
