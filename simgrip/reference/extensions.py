"""SciPy's compiled routines that the BVP reference calls, without the import cost of their packages (issue 19).

The reference's ``solve_bvp`` steps (:mod:`simgrip.reference.collocation`) need LAPACK's band LU
(``dgbtrf``, ``dgbtrs``) and its cold starts (:mod:`simgrip.reference.continuation`) one Brent root; importing
``scipy.linalg`` and ``scipy.optimize`` for them costs ~0.1 s and ~0.22 s of CPU (SciPy's array API layer,
``scipy.sparse``, ``scipy.spatial``), about 1 ms a point of a 300-point sweep, more than the whole
reference's work there.  The compiled extension modules themselves (``scipy.linalg._flapack``,
``scipy.optimize._zeros``) load in a few ms and are the same code either way: bit-identical results.

* :data:`dgbtrf`, :data:`dgbtrs`: :mod:`simgrip.lapack`'s (the same wrappers as ``scipy.linalg.lapack``'s, same
  signatures);
* :func:`brentq`: ``scipy.optimize.brentq(f, a, b)`` with its default tolerances, calling the same compiled
  routine (``scipy.optimize._zeros._brentq``) as that function does.
"""

from __future__ import annotations

import functools

import numpy as np

from simgrip.lapack import dgbtrf, dgbtrs, scipy_extension

__all__ = ["brentq", "dgbtrf", "dgbtrs"]

#: ``scipy.optimize.brentq``'s default tolerances and iteration limit (its signature, SciPy 1.x).
BRENTQ_XTOL, BRENTQ_RTOL, BRENTQ_MAXITER = 2e-12, 4 * np.finfo(float).eps, 100


@functools.cache
def _zeros():
    """``scipy.optimize._zeros`` (loaded once, at the first root)."""
    return scipy_extension("optimize", "_zeros", ("_brentq",))


def brentq(f, a: float, b: float) -> float:
    """``scipy.optimize.brentq(f, a, b)``: the root of ``f`` in ``[a, b]`` (a sign change required) by Brent's
    method at SciPy's default tolerances, by the same compiled routine; ``ValueError`` where ``f`` returns NaN
    (as ``brentq``) or the signs do not differ (raised by that routine)."""
    def checked(x, *args):
        fx = f(x, *args)
        if np.isnan(fx):
            raise ValueError(f"The function value at x={x} is NaN; solver cannot continue.")
        return fx

    return _zeros()._brentq(checked, a, b, BRENTQ_XTOL, BRENTQ_RTOL, BRENTQ_MAXITER, (), False, True)
