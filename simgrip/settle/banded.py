"""Bordered tridiagonal linear systems, solved in ``O(n k^2)``.

The static solve in link angles has a Jacobian that is tridiagonal in the link
angles (hinge springs couple neighbours, gravity and point loads are
separable) plus a border of ``k`` rows and columns (workpiece dofs, contact
and stick multipliers, and the auxiliary unknowns of low-rank curvature terms).
For::

    [ T  P ] [x]   [r1]
    [ Q  E ] [y] = [r2]

block elimination gives ``X = T^{-1} [P | r1]`` (one tridiagonal solve with
``k + 1`` right-hand sides, LAPACK ``gtsv``), the Schur complement
``S = E - Q X_P`` (``k x k``), ``y = S^{-1} (r2 - Q X_r)`` and
``x = X_r - X_P y``.  ``T`` need not be definite (partial pivoting).

LAPACK is :mod:`simgrip.lapack`'s (SciPy's wrappers without ``scipy.linalg``'s import cost).
"""

from __future__ import annotations

import numpy as np

from simgrip.lapack import dgtsv, dpttrf, dpttrs

__all__ = ["dgtsv", "dpttrf", "dpttrs", "solve_bordered", "solve_tridiagonal"]


def solve_tridiagonal(diag, off, rhs) -> np.ndarray:
    """Solve ``T x = rhs`` for the symmetric tridiagonal ``T`` (``diag``, off-diagonal ``off``; float64).

    LAPACK ``gtsv`` (partial pivoting) called directly: exactly what
    ``scipy.linalg.solve_banded((1, 1), ...)`` calls for a tridiagonal band, without
    its argument handling (~10 us a call, the cost of a whole ``O(n)`` solve at
    ``n = 32``).  ``rhs`` is ``(n,)`` or ``(n, k)``.  Raises ``numpy.linalg.LinAlgError``
    when ``T`` is singular.
    """
    diag = np.asarray(diag, dtype=float)
    rhs = np.asarray(rhs, dtype=float)
    if diag.size == 1:  # (solve_banded's 1 x 1 case)
        return rhs / diag[0]
    off = np.asarray(off, dtype=float)
    _, _, _, x, info = dgtsv(off, diag, off, rhs)
    if info > 0:
        raise np.linalg.LinAlgError("singular matrix")
    if info < 0:
        raise ValueError(f"illegal value in {-info}-th argument of gtsv")
    return x


def solve_bordered(diag, off, P, Q, E, r1, r2) -> tuple[np.ndarray, np.ndarray]:
    """Solve the bordered system above; ``off`` is the symmetric off-diagonal of ``T`` (length ``n - 1``).

    ``P`` is ``(n, k)``, ``Q`` ``(k, n)``, ``E`` ``(k, k)``, ``r1`` ``(n,)``, ``r2`` ``(k,)``;
    ``k = 0`` is allowed.  Raises ``numpy.linalg.LinAlgError`` when ``T`` is singular.
    """
    n = diag.size
    k = r2.size
    rhs = np.empty((n, k + 1))
    rhs[:, :k] = P
    rhs[:, k] = r1
    X = solve_tridiagonal(diag, off, rhs)
    if k == 0:
        return X[:, 0], np.zeros(0)
    S = E - Q @ X[:, :k]
    b = r2 - Q @ X[:, k]
    y, *_ = np.linalg.lstsq(S, b, rcond=1e-14)
    return X[:, k] - X[:, :k] @ y, y
