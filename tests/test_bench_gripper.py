"""The K-finger rows of ``simgrip bench`` (simgrip.harness.bench_gripper): what is measured and written.

No timed assertions (timings are noisy on a shared machine): the ratios must be the quotients of
the times measured in the same run, and the answers compared alongside must agree.  The skip
(point contact) and the dynamics (MuJoCo's surface contact) differ by the tip couple ``C ~ -r_tip
F_f = r_tip M``: ``|dN1/dC| r_tip M / N1`` is 0.3 % (Grip I) and 0.6 % (Grip II) at the standard
cases (tests/test_gripper_symmetry's chain sensitivities), so ``N1_rel_diff`` stays below 1 %.
"""

from __future__ import annotations

import json

import pytest

from simgrip.harness.bench_gripper import SHAPES, gripper_bench, gripper_bench_md, write_gripper_bench


@pytest.fixture(scope="module")
def record():
    return gripper_bench(repeats=1, n=12)


def test_rows_and_ratios(record):
    rows = record["rows"]
    assert len(rows) == 2 * len(SHAPES) and record["n"] == 12
    for r in rows:
        K = r["fingers"]
        assert (K, r["workpiece"]) in SHAPES and r["n"] == 12
        for k in ("full_s", "skip_s", "skip_reuse_s", "single_dyn_s", "single_newton_s"):
            assert r[k] > 0.0
        assert r["full/(K single_dyn)"] == pytest.approx(r["full_s"] / (K * r["single_dyn_s"]), rel=1e-12)
        assert r["full/(K single_newton)"] == pytest.approx(r["full_s"] / (K * r["single_newton_s"]), rel=1e-12)
        assert r["full/skip"] == pytest.approx(r["full_s"] / r["skip_s"], rel=1e-12)
        assert r["full/skip_reuse"] == pytest.approx(r["full_s"] / r["skip_reuse_s"], rel=1e-12)
        assert r["held"] == [True, True] and 0.0 < r["N1_rel_diff"] < 0.01
        key = f"{r['grip']} K={K} {r['workpiece']}: full <= K x single (dynamics)"
        assert record["checks"][key] == (r["full/(K single_dyn)"] <= 1.0)


def test_markdown_and_files(tmp_path, record, monkeypatch):
    md = gripper_bench_md(record)
    assert md.count("\n| I |") == len(SHAPES) and md.count("\n| II |") == len(SHAPES)
    assert "full <= K x single" in md
    import simgrip.harness.bench_gripper as bg

    monkeypatch.setattr(bg, "gripper_bench", lambda **kw: record)
    rec = write_gripper_bench(tmp_path, quick=True)
    assert rec is record
    assert json.loads((tmp_path / "gripper.json").read_text())["rows"][0]["grip"] == "I"
    assert (tmp_path / "gripper.md").read_text() == md
