"""simgrip.lapack: SciPy's LAPACK wrappers loaded without scipy.linalg's namespace (the settle path's import)."""

import subprocess
import sys

import numpy as np
import scipy.linalg.lapack as sla

from simgrip import lapack


def test_the_loaded_routines_give_scipys_results_bit_for_bit():
    rng = np.random.default_rng(3)
    for n in (2, 7, 64):
        d = 4.0 + rng.random(n)
        e = rng.standard_normal(n - 1)
        b = rng.standard_normal((n, 3))
        for ours, theirs in ((lapack.dgtsv(e, d, e, b), sla.dgtsv(e, d, e, b)),
                             (lapack.dpttrf(d, e), sla.dpttrf(d, e))):
            for x, y in zip(ours, theirs):
                assert np.array_equal(np.asarray(x), np.asarray(y))
        df, ef, _ = lapack.dpttrf(d, e)
        assert np.array_equal(lapack.dpttrs(df, ef, b)[0], sla.dpttrs(df, ef, b)[0])


def test_the_settle_and_sweep_path_does_not_import_scipy_linalg():
    # scipy.linalg costs ~0.16 s of CPU to import: more than a 300-point sweep's settle set-up
    code = ("import sys, simgrip.settle, simgrip.sweep.run, simgrip.reference.chain_start; "
            "print('scipy.linalg' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "False"
