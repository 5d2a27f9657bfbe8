"""simgrip.harness.bench_overhead (issue 19): the ratios around the settle, on tiny cases.

Each ratio divides a time by a part of itself (a call by the settle inside it, a sweep point by its settle),
so it is at least 1 whatever the machine's load: a ratio below 1 would be a measurement of the wrong thing.
"""

from __future__ import annotations

import json

from simgrip.harness import bench_overhead as bo


def test_ratios_are_times_over_their_own_parts(tmp_path, monkeypatch):
    rows = bo._settle_over_chain((16,), 1)
    assert rows[0]["case"] == "free n=16: settle/chain" and rows[0]["ratio"] == rows[0]["settle_s"] / rows[0]["chain_s"]
    call = bo._call_over_settle(2, links=16)
    assert call["ratio"] >= 1.0 and call["call_s"] >= call["settle_s"] > 0
    sweep = bo._sweep_over_settle(3, "none")  # the command, in a fresh process, at 3 points
    assert sweep["case"].startswith("simgrip sweep I --kappa -7 -3 3 --links 32 --jobs 1 --reference none")
    assert sweep["ratio"] >= 1.0 and sweep["point/settle"] >= 1.0 and sweep["points_per_s_per_core"] > 0

    # the record and its files: one row per ratio, checks only for the targets of the table
    monkeypatch.setattr(bo, "_settle_over_chain", lambda ns, reps: [{"case": f"free n={n}: settle/chain",
                                                                     "ratio": 2.0} for n in ns])
    monkeypatch.setattr(bo, "_call_over_settle", lambda calls: {"case": "simulate free n=256 x2: call/settle",
                                                                "ratio": 4.0})
    monkeypatch.setattr(bo, "_sweep_over_settle", lambda pts, ref: {"case": f"sweep --reference {ref}: point/settle",
                                                                    "ratio": 1.5 if ref == "none" else 3.0})
    rec = bo.write_overhead_bench(tmp_path, quick=True)
    assert len(rec["rows"]) == 5 + 1 + 2
    met = rec["checks"]
    # both sweeps are checked (the command runs the BVP by default): the call's 4.0 > 3 and the BVP
    # sweep's 3.0 > 2 are not met
    assert sum(met.values()) == 6 and len(met) == 8
    assert met["sweep --reference bvp: point/settle <= 2.0"] is False
    assert json.loads((tmp_path / "overhead.json").read_text())["checks"] == met
    assert "| simulate free n=256 x2: call/settle <= 3.0 | NO |" in (tmp_path / "overhead.md").read_text()
