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

LAPACK comes from SciPy's own wrappers (``scipy.linalg._flapack``), loaded
without ``scipy.linalg``'s namespace (:func:`_flapack`): importing that
package costs ~0.16 s of CPU (SciPy cloning NumPy's namespace for its array
API layer, which imports ``numpy.f2py``), more than a whole 300-point
``n = 32`` sweep's worth of settle set-up; the extension alone ~7 ms.  The
routines are the same compiled code either way (bit-identical results).
"""

from __future__ import annotations

import importlib.machinery
import importlib.util
import os

import numpy as np

__all__ = ["dgtsv", "dpttrf", "dpttrs", "solve_bordered", "solve_tridiagonal"]


def _flapack():
    """SciPy's LAPACK extension module ``scipy.linalg._flapack``, loaded from its file without importing
    ``scipy.linalg`` (see the module docstring); the ordinary import where that file is not found or does not
    load (another SciPy layout).  Not put in ``sys.modules``: a later ``import scipy.linalg`` loads its own."""
    try:
        import scipy

        folder = os.path.join(os.path.dirname(scipy.__file__), "linalg")
        for suffix in importlib.machinery.EXTENSION_SUFFIXES:
            path = os.path.join(folder, "_flapack" + suffix)
            if os.path.isfile(path):
                spec = importlib.util.spec_from_file_location("scipy.linalg._flapack", path)
                mod = importlib.util.module_from_spec(spec)
                spec.loader.exec_module(mod)
                if all(callable(getattr(mod, k, None)) for k in ("dgtsv", "dpttrf", "dpttrs")):
                    return mod
                break
    except Exception:  # noqa: BLE001 - any failure of the shortcut: the ordinary import below
        pass
    from scipy.linalg import lapack

    return lapack


_LAPACK = _flapack()
#: LAPACK's general tridiagonal solve (partial pivoting), the symmetric positive definite tridiagonal
#: factorisation and its solve: ``scipy.linalg.lapack``'s wrappers of the same names (same signatures).
dgtsv, dpttrf, dpttrs = _LAPACK.dgtsv, _LAPACK.dpttrf, _LAPACK.dpttrs


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
