"""simgrip stress's full-contact cases (contact='full'): drawn past the onset, settled, checked for validity."""

import json
import subprocess
import sys

import pytest

from simgrip.harness.stress import PENETRATION_TOL, _counts, default_full_cases, run_stress
from simgrip.harness.stress_cases import FULL_BOX, make_full_cases


def test_full_cases_drawn_past_the_onset():
    """Grips I/II curled onto the box, |kappa| past the onset bounds of FULL_BOX, n <= 16; deterministic."""
    cases = make_full_cases(24, seed=3)
    assert cases == make_full_cases(24, seed=3)
    assert {c["grip"] for c in cases} == {"I", "II", "free"}
    for c in cases:
        lo, hi = FULL_BOX["abs_kappa"][c["grip"]]
        assert lo <= abs(c["kappa"]) <= hi
        assert c["contact"] == "full" and 8 <= c["n"] <= 16
        if c["grip"] == "I":
            assert c["kappa"] < 0  # the standard Grip I onset is -8.27 (tests/test_free_boundary.py); I at D=0.5: -9.38
        if c["grip"] == "II":
            assert c["kappa"] > 0
    assert {c["kappa"] > 0 for c in cases if c["grip"] == "free"} == {True, False}
    assert make_full_cases(3, max_links=10)[0]["n"] <= 10
    with pytest.raises(ValueError, match="full_cases"):
        make_full_cases(-1)
    assert default_full_cases(500) == 5 and default_full_cases(10) == 1


def test_invalid_returned_as_valid_counts_a_full_case():
    """The counter sees a full-contact record whose state says valid but whose geometry is impossible."""
    base = dict(outcome="settled", grip="I", held=True, contact="full",
                flags={"self_intersection": False, "workpiece_entry": False, "fingers_cross": False})
    bad = dict(base, valid=True, flags=dict(base["flags"], workpiece_entry=True))
    honest = dict(bad, valid=False)
    assert _counts([base, bad, honest])["invalid_returned_as_valid"] == 1


def test_stress_runs_full_contact_cases(tmp_path):
    """Three full-contact cases alongside one point case: every one settles, none impossible yet called valid,
    penetration within the issue's 1e-3 l (the settle's own limit is 1e-4 l: FULL_PEN_LIMIT)."""
    res = run_stress(tmp_path / "s", cases=1, seed=0, jobs=1, progress=False, gripper_cases=0, full_cases=3)
    full = res.full
    assert full["counts"]["total"] == 3 and len(full["cases"]) == 3
    assert full["counts"]["failed"] == 0, full["failures"]
    assert full["counts"]["settled"] == 3
    assert full["counts"]["invalid_returned_as_valid"] == 0
    assert all(c["contact"] == "full" and "valid" in c for c in full["cases"])
    assert full["max_penetration"] <= PENETRATION_TOL
    data = json.loads((tmp_path / "s" / "stress.json").read_text())
    assert data["full"]["counts"] == full["counts"]
    assert res.counts["total"] == 1  # the point-contact counts are the point cases only


def test_cli_full_cases_refused(tmp_path):
    r = subprocess.run([sys.executable, "-m", "simgrip.cli", "stress", "--cases", "2", "--full-cases", "-1",
                        "--out", str(tmp_path / "o")], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "--full-cases" in r.stderr and "Traceback" not in r.stderr
