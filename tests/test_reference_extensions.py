"""simgrip.reference.extensions: SciPy's band LU and Brent root without scipy.linalg / scipy.optimize (issue 19)."""

import math
import subprocess
import sys

import numpy as np
import pytest
import scipy.linalg.lapack as sla
from scipy.optimize import brentq as scipy_brentq

from simgrip.reference import extensions


def test_brentq_is_scipys_bit_for_bit():
    rng = np.random.default_rng(5)
    for r in rng.random(2000):  # the unloaded arc's equation (continuation._arc)
        def f(u, r=r):
            return math.sin(u) / u - r

        assert extensions.brentq(f, 1e-9, math.pi) == scipy_brentq(f, 1e-9, math.pi)
    for f, a, b in ((lambda x: x**3 - 2.0, 0.0, 2.0), (lambda x: math.cos(x) - x, 0.0, 1.0)):
        assert extensions.brentq(f, a, b) == scipy_brentq(f, a, b)
    with pytest.raises(ValueError):
        extensions.brentq(lambda x: x + 5.0, 0.0, 1.0)  # no sign change
    with pytest.raises(ValueError):
        extensions.brentq(lambda x: math.nan, 0.0, 1.0)


def test_band_lu_is_scipys_bit_for_bit():
    rng = np.random.default_rng(6)
    kl, ku, n = 7, 6, 60
    ab = rng.standard_normal((2 * kl + ku + 1, n))
    ab[kl + ku] += 10.0
    ours = extensions.dgbtrf(ab.copy(), kl, ku)
    theirs = sla.dgbtrf(ab.copy(), kl, ku)
    for x, y in zip(ours, theirs):
        assert np.array_equal(np.asarray(x), np.asarray(y))
    b = rng.standard_normal(n)
    assert np.array_equal(extensions.dgbtrs(ours[0], kl, ku, b, ours[1])[0], sla.dgbtrs(theirs[0], kl, ku, b, theirs[1])[0])


def test_the_sweep_reference_does_not_import_scipys_heavy_packages():
    # scipy.interpolate, .optimize, .linalg, .special: ~0.26 s of CPU together, ~0.9 ms a point of a 300-point sweep
    code = ("import sys\n"
            "from simgrip.sweep.grid import make_grid\n"
            "from simgrip.sweep.reference import segment_references\n"
            "g = make_grid('I', kappa=(-7, -6, 4), links=8)\n"
            "out = segment_references([g.point(i) for i in range(g.size)])\n"
            "assert all(o[0] is not None for o in out)\n"
            "print(sorted(m for m in ('scipy.interpolate', 'scipy.optimize', 'scipy.linalg', 'scipy.special')"
            " if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"
