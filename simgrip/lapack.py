"""LAPACK's tridiagonal routines (``dgtsv``, ``dpttrf``, ``dpttrs``) without ``scipy.linalg``'s import cost.

They are SciPy's own wrappers (``scipy.linalg._flapack``), loaded without
``scipy.linalg``'s namespace (:func:`_flapack`): importing that package costs
~0.16 s of CPU (SciPy cloning NumPy's namespace for its array API layer, which
imports ``numpy.f2py``), more than a whole 300-point ``n = 32`` sweep's worth
of settle set-up; the extension alone ~7 ms.  The routines are the same
compiled code either way (bit-identical results), with the same signatures as
``scipy.linalg.lapack``'s.  Used by the chain's Newton
(:mod:`simgrip.settle.banded`) and its hinge-chain start
(:mod:`simgrip.reference.chain_start`).
"""

from __future__ import annotations

import importlib.machinery
import importlib.util
import os

__all__ = ["dgtsv", "dpttrf", "dpttrs"]


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
