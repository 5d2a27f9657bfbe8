"""The modes' section of ``simgrip bench`` (simgrip.harness.bench_modes): what it measured, never timings."""

import json

import numpy as np

from simgrip.harness.bench_modes import CASES, N_QUICK, write_modes_bench


def test_quick_modes_bench(tmp_path):
    rec = write_modes_bench(tmp_path, quick=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["modes.json", "modes.md", "modes.png"]
    assert json.loads((tmp_path / "modes.json").read_text())["rows"] == rec["rows"]
    assert (tmp_path / "modes.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    for name in CASES:
        rows = [r for r in rec["rows"] if r["case"] == name]
        assert [r["n"] for r in rows] == list(N_QUICK) and all("error" not in r for r in rows)
        err = np.abs([r["relative_error"] for r in rows])
        assert np.all(err[-1] < 1e-2)  # n = 32: C_k (1/32)^2 with C_3 <= 5 (tests/test_modes.py)
        # second order (simgrip.modes): 2 + O((beta_k ds)^2); at n = 8 -> 16 mode 3's (7.85/8)^2 / 12 ~ 8 %
        orders = np.array([r["order"] for r in rows[1:]])
        assert np.all(np.abs(orders - 2.0) < 0.25), (name, orders)
        assert all(r["modes_cpu_s"] > 0 for r in rows)
    assert "| grip I | 32 |" in (tmp_path / "modes.md").read_text()
