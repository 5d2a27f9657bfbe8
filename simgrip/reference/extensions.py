"""SciPy's compiled routines that the BVP reference calls, without the import cost of their packages (issue 19).

The reference's ``solve_bvp`` steps (:mod:`simgrip.reference.collocation`) need LAPACK's band LU
(``dgbtrf``, ``dgbtrs``) and its cold starts (:mod:`simgrip.reference.continuation`) one Brent root; importing
``scipy.linalg`` and ``scipy.optimize`` for them costs ~0.1 s and ~0.22 s of CPU (SciPy's array API layer,
``scipy.sparse``, ``scipy.spatial``), about 1 ms a point of a 300-point sweep, more than the whole
reference's work there.  The compiled extension modules themselves (``scipy.linalg._flapack``,
``scipy.optimize._zeros``) load in a few ms and are the same code either way: bit-identical results.

* :data:`dgbtrf`, :data:`dgbtrs`: from the LAPACK extension :mod:`simgrip.lapack` has already loaded (the same
  wrappers as ``scipy.linalg.lapack``'s, same signatures);
* :func:`brentq`: ``scipy.optimize.brentq(f, a, b)`` with its default tolerances, calling the same compiled
  routine (``scipy.optimize._zeros._brentq``) as that function does.
"""

from __future__ import annotations

import importlib
import importlib.machinery
import importlib.util
import os

import numpy as np

from simgrip import lapack as _lapack

__all__ = ["brentq", "dgbtrf", "dgbtrs", "scipy_extension"]

#: ``scipy.optimize.brentq``'s default tolerances and iteration limit (its signature, SciPy 1.x).
BRENTQ_XTOL, BRENTQ_RTOL, BRENTQ_MAXITER = 2e-12, 4 * np.finfo(float).eps, 100


def scipy_extension(package: str, name: str, needed: tuple):
    """SciPy's extension module ``scipy.<package>.<name>`` loaded from its file without importing
    ``scipy.<package>`` (not put in ``sys.modules``), or by the ordinary import where that file is not found,
    does not load or lacks one of ``needed`` (another SciPy layout)."""
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


def _band_lu():
    lib = _lapack._LAPACK
    if callable(getattr(lib, "dgbtrf", None)) and callable(getattr(lib, "dgbtrs", None)):
        return lib.dgbtrf, lib.dgbtrs
    from scipy.linalg.lapack import dgbtrf, dgbtrs

    return dgbtrf, dgbtrs


#: LAPACK's general band LU factorisation and its solve (``scipy.linalg.lapack``'s wrappers, same signatures).
dgbtrf, dgbtrs = _band_lu()
_ZEROS = None


def brentq(f, a: float, b: float) -> float:
    """``scipy.optimize.brentq(f, a, b)``: the root of ``f`` in ``[a, b]`` (a sign change required) by Brent's
    method at SciPy's default tolerances, by the same compiled routine; ``ValueError`` where ``f`` returns NaN
    (as ``brentq``) or the signs do not differ (raised by that routine)."""
    global _ZEROS
    if _ZEROS is None:
        _ZEROS = scipy_extension("optimize", "_zeros", ("_brentq",))

    def checked(x, *args):
        fx = f(x, *args)
        if np.isnan(fx):
            raise ValueError(f"The function value at x={x} is NaN; solver cannot continue.")
        return fx

    return _ZEROS._brentq(checked, a, b, BRENTQ_XTOL, BRENTQ_RTOL, BRENTQ_MAXITER, (), False, True)
