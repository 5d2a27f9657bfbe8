"""LAPACK's tridiagonal and band routines (``dgtsv``, ``dpttrf``, ``dpttrs``, ``dgbtrf``, ``dgbtrs``) without ``scipy.linalg``'s import cost.

They are SciPy's own wrappers (``scipy.linalg._flapack``), loaded without
``scipy.linalg``'s namespace (:func:`_flapack`): importing that package costs
~0.16 s of CPU (SciPy cloning NumPy's namespace for its array API layer, which
imports ``numpy.f2py``), more than a whole 300-point ``n = 32`` sweep's worth
of settle set-up; the extension alone ~7 ms.  The routines are the same
compiled code either way (bit-identical results), with the same signatures as
``scipy.linalg.lapack``'s.  Used by the chain's Newton
(:mod:`simgrip.settle.banded`), its hinge-chain start
(:mod:`simgrip.reference.chain_start`) and the BVP's collocation
(:mod:`simgrip.reference.collocation`, through :mod:`simgrip.reference.extensions`).
"""

from __future__ import annotations

import importlib.machinery
import importlib.util
import os

__all__ = ["dgbtrf", "dgbtrs", "dgtsv", "dpttrf", "dpttrs", "scipy_extension"]


def scipy_extension(package: str, name: str, needed: tuple):
    """SciPy's extension module ``scipy.<package>.<name>`` loaded from its file without importing
    ``scipy.<package>`` (not put in ``sys.modules``: a later ordinary import loads its own), or by the ordinary
    import where that file is not found, does not load or lacks one of ``needed`` (another SciPy layout)."""
    try:
        import scipy

        folder = os.path.join(os.path.dirname(scipy.__file__), package)
        for suffix in importlib.machinery.EXTENSION_SUFFIXES:
            path = os.path.join(folder, name + suffix)
            if os.path.isfile(path):
                spec = importlib.util.spec_from_file_location(f"scipy.{package}.{name}", path)
                mod = importlib.util.module_from_spec(spec)
                spec.loader.exec_module(mod)
                if all(callable(getattr(mod, k, None)) for k in needed):
                    return mod
                break
    except Exception:  # noqa: BLE001 - any failure of the shortcut: the ordinary import below
        pass
    return importlib.import_module(f"scipy.{package}.{name}")


_LAPACK = scipy_extension("linalg", "_flapack", ("dgtsv", "dpttrf", "dpttrs", "dgbtrf", "dgbtrs"))
#: LAPACK's general tridiagonal solve (partial pivoting), the symmetric positive definite tridiagonal
#: factorisation and its solve, the general band LU and its solve: ``scipy.linalg.lapack``'s wrappers of the
#: same names (same signatures).
dgtsv, dpttrf, dpttrs = _LAPACK.dgtsv, _LAPACK.dpttrf, _LAPACK.dpttrs
dgbtrf, dgbtrs = _LAPACK.dgbtrf, _LAPACK.dgbtrs
