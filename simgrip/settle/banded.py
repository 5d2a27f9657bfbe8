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
The small system in ``S`` is solved by Gaussian elimination with partial
pivoting (:func:`solve_small`: Python floats up to :data:`SMALL_K`, else
LAPACK ``gesv``), and by the least-squares solution (``lstsq``, singular
values below ``1e-14`` of the largest dropped) wherever that elimination finds
``S`` singular or the answer so large that ``S`` may be (issue 19: ``lstsq``'s
SVD and argument handling were ~20 us of a ~25 us solve at ``k = 3``).

LAPACK is :mod:`simgrip.lapack`'s (SciPy's wrappers without ``scipy.linalg``'s import cost).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.linalg import _umath_linalg

from simgrip.lapack import dgtsv, dpttrf, dpttrs

__all__ = ["dgtsv", "dpttrf", "dpttrs", "lstsq_vector", "solve_bordered", "solve_small", "solve_tridiagonal"]

#: ``ndarray.max``, ``.all`` and ``.any`` as the reductions they call, without their Python wrappers (the same
#: answers, NaN included; ``axis=None`` for more than 1-D), numpy's float64 dtype (one object, told by identity)
#: and a read-only row of ones (the chain Newton's stick rows' scale)
_MAX, _ALL, _ANY, _F64 = np.maximum.reduce, np.logical_and.reduce, np.logical_or.reduce, np.dtype(float)
_ONES = np.ones(4)
_ONES.setflags(write=False)
#: Border sizes up to this are eliminated on Python floats (numpy's per-call cost is most of a 3 x 3 solve).
SMALL_K = 4
#: :func:`solve_small` trusts an eliminated answer ``y`` only when ``max|y| max|S| <= SMALL_TRUST max|b|``
#: (``|S|`` the largest row sum): a larger one means ``S`` is within ~1e-10 of singular, where the
#: least-squares answer (rank cut at ``1e-14``) is the one the Newton step takes, as it always did.
SMALL_TRUST = 1e10


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
    y = solve_small(S, b)
    return X[:, k] - X[:, :k] @ y, y


def _eliminate(S, b):
    """``S y = b`` by Gaussian elimination with partial pivoting on Python floats (``S`` a list of rows, ``b`` a
    list; both consumed); None where a pivot is exactly zero or the answer is not finite."""
    k = len(b)
    for c in range(k):
        p, big = c, abs(S[c][c])  # (the first row of the largest magnitude, as max() would pick it)
        for r in range(c + 1, k):
            v = abs(S[r][c])
            if v > big:
                p, big = r, v
        piv = S[p][c]
        if piv == 0.0:
            return None
        if p != c:
            S[c], S[p] = S[p], S[c]
            b[c], b[p] = b[p], b[c]
        rc = S[c]
        for r in range(c + 1, k):
            row = S[r]
            f = row[c] / piv
            if f != 0.0:
                for j in range(c + 1, k):
                    row[j] -= f * rc[j]
                b[r] -= f * b[c]
    y = [0.0] * k
    for c in range(k - 1, -1, -1):
        rc = S[c]
        acc = b[c]
        for j in range(c + 1, k):
            acc -= rc[j] * y[j]
        v = acc / rc[c]
        if not math.isfinite(v):
            return None
        y[c] = v
    return y


def lstsq_vector(A, b, rcond: float) -> np.ndarray:
    """``np.linalg.lstsq(A, b, rcond=rcond)[0]`` of a float64 2-D ``A`` and 1-D ``b``: the same gufunc
    (``numpy.linalg._umath_linalg.lstsq``, LAPACK ``gelsd``) on the same arrays, so the same bits, without
    ``lstsq``'s argument handling and ``errstate`` (~9 of its ~16 us at ``33 x 2``).  Where an input is not
    finite, ``lstsq`` itself (its ``LinAlgError``; the bare gufunc would only warn).  One difference is left:
    an SVD that fails to converge on finite input (LAPACK's ``info > 0``) warns here instead of raising."""
    if _ALL(np.isfinite(A), axis=None) and _ALL(np.isfinite(b)):
        return _umath_linalg.lstsq(A, b[:, None], rcond, signature="ddd->ddid")[0][:, 0]
    return np.linalg.lstsq(A, b, rcond=rcond)[0]


def solve_small(S, b, *, least_squares: bool = True) -> np.ndarray | None:
    """``y`` with ``S y = b`` for a small square ``S`` (float64): elimination with partial pivoting, or, where ``S``
    is singular or nearly so (:data:`SMALL_TRUST`), ``lstsq``'s least-squares answer with singular values below
    ``1e-14`` of the largest cut, as the bordered solve always took (``least_squares=False``: None there).  Both
    are the exact solution of a non-singular ``S`` up to round-off (``cond(S) eps``)."""
    k = b.size
    y = None
    if k <= SMALL_K:
        rows = S.tolist()
        bl = b.tolist()
        snorm = bnorm = 0.0
        for r, v in zip(rows, bl):  # (largest row sum of |S| and largest |b|, NaN kept: it fails the trust test)
            t = 0.0
            for x in r:
                t += abs(x)
            if not t <= snorm:
                snorm = t
            if not abs(v) <= bnorm:
                bnorm = abs(v)
        got = _eliminate(rows, bl)
        if got is not None:
            ymax = 0.0
            for v in got:
                if abs(v) > ymax:
                    ymax = abs(v)
            if ymax * snorm <= SMALL_TRUST * bnorm:
                y = np.array(got)
    else:
        try:
            got = np.linalg.solve(S, b)
        except np.linalg.LinAlgError:
            got = None
        if got is not None and np.isfinite(got).all() and (
                float(np.abs(got).max()) * float(np.abs(S).sum(axis=1).max()) <= SMALL_TRUST * float(np.abs(b).max())):
            y = got
    if y is None and least_squares:
        y = lstsq_vector(S, b, 1e-14)
    return y
