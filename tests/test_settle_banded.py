"""Bordered tridiagonal solve against a dense solve."""

from __future__ import annotations

import numpy as np
import pytest

from simgrip.settle.banded import solve_bordered


@pytest.mark.parametrize("n,k", [(5, 0), (12, 1), (40, 4)])
def test_bordered_solve_equals_the_dense_solve(n, k):
    rng = np.random.default_rng(n + k)
    diag = rng.uniform(-3.0, 3.0, n) + np.sign(rng.uniform(-1, 1, n)) * 4.0  # indefinite, well conditioned
    off = rng.uniform(-1.0, 1.0, n - 1)
    P, Q, E = rng.normal(size=(n, k)), rng.normal(size=(k, n)), rng.normal(size=(k, k))
    r1, r2 = rng.normal(size=n), rng.normal(size=k)
    A = np.zeros((n + k, n + k))
    A[:n, :n] = np.diag(diag) + np.diag(off, 1) + np.diag(off, -1)
    A[:n, n:], A[n:, :n], A[n:, n:] = P, Q, E
    x, y = solve_bordered(diag, off, P, Q, E, r1, r2)
    np.testing.assert_allclose(np.concatenate([x, y]), np.linalg.solve(A, np.concatenate([r1, r2])), rtol=1e-10,
                               atol=1e-10)
