"""SciPy's ``solve_bvp``, step for step, with its collocation Jacobian factored as a band matrix.

:func:`solve_collocation` runs the algorithm of :func:`scipy.integrate.solve_bvp`
(SciPy 1.17, ``scipy/integrate/_bvp.py``) on problems whose boundary
conditions are linear, ``A y(a) + B y(b) = c`` with ``A, B, c`` constant: the
same 4th-order Lobatto IIIA collocation equations on the same mesh, the same
damped Newton iteration (affine-invariant criterion ``|J^-1 r|^2``, Armijo
constant 0.2, at most 4 Jacobians and 8 iterations, the same stopping test on
the collocation and boundary residuals), the same rms residual estimate (5-point
Lobatto quadrature of the cubic spline's relative residual), the same node
insertion and the same final test (``max rms <= tol``, boundary residual
``<= tol``), returning the same spline.  Only the linear algebra differs:
``solve_bvp`` builds a sparse matrix and factors it with SuperLU (column
reordering, ~2/3 of a warm run's time at 600 nodes); here the unknowns are
ordered node by node and the equations interval by interval, boundary rows at
their ends, so the Jacobian is a band matrix that LAPACK's ``dgbtrf`` factors
with partial pivoting in O(nodes) time.

To make the system banded: each unknown parameter ``p_j`` becomes a constant
state (equations ``p_j(i+1) - p_j(i) = 0``; the collocation rows of interval
``i`` take their ``dPhi/dp`` on node ``i``'s copy), and each boundary row that
couples both ends (``a_r . y(a) + b_r . y(b) = c_r``, Grip III's continuity at
the contact) gets a constant state ``z_r`` with the two separated rows
``a_r . y(a) - z_r = 0`` and ``b_r . y(b) + z_r = c_r``.  The augmented linear
system has the original Newton step as its unique solution (the constant
copies are equal, ``z_r = a_r . y(a)``), so the iterates are ``solve_bvp``'s up
to rounding; the tests (``tests/test_collocation.py``) compare the two.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from simgrip.reference.extensions import dgbtrf, dgbtrs  # LAPACK without scipy.linalg's import cost

__all__ = ["CollocationResult", "Spline", "solve_collocation", "continue_collocation", "MESSAGES"]

#: ``solve_bvp``'s messages by status (its ``TERMINATION_MESSAGES``).
MESSAGES = {
    0: "The algorithm converged to the desired accuracy.",
    1: "The maximum number of mesh nodes is exceeded.",
    2: "A singular Jacobian encountered when solving the collocation system.",
    3: "The solver was unable to satisfy boundary conditions tolerance on iteration 10.",
}
#: The message of a solve on a given mesh (:func:`continue_collocation` with ``refine=False``).
ON_MESH = "Newton converged on the given mesh (no residual test: its discretisation is sized by the caller)."
_EPS = np.finfo(float).eps
#: Band layouts kept (:func:`_band`, keyed on the problem's structure and the mesh size), and the most nodes
#: of a kept one: the bounded cache of this module, enough for the mesh sizes one continuation visits (the
#: 1e-8 references have 400-1200 nodes).  A layout holds its band template, ``(2 kl + ku + 1) x (n + k + q) m``
#: floats and two index arrays, ~1.5 MB at 1000 nodes for Grips I/II, ~7 MB for Grip III, ~10 MB at the
#: largest kept: at most ~80 MB in all.
_BANDS = 8
_CACHED_NODES = 1500
#: :func:`continue_collocation`: most chord steps, and the largest ratio of two successive criteria
#: ``|J^-1 r|^2`` a chord step may leave before the Jacobian is refactored.  From a secant predictor (error
#: O(step^2)) with a neighbour's Jacobian (error O(step)) a chord step gains ~2 decades in the criterion; a
#: ratio above 1e-2 (one decade in the step) means the factorisation is stale.
_CHORD_STEPS = 6
_CHORD_RATE = 1e-2


@dataclass
class CollocationResult:
    """What ``solve_bvp`` returns (the fields :mod:`simgrip.reference.bvp` reads): ``sol`` (the C1 cubic
    spline, a :class:`Spline`: ``PPoly``'s values), ``x``, ``y``, ``yp``, ``p`` (``None`` without parameters),
    ``rms_residuals``, ``niter``, ``status`` (:data:`MESSAGES`), ``message``, ``success``; and ``factor``, the
    banded LU of the last Newton Jacobian on the final mesh (:func:`continue_collocation` starts from it)."""

    sol: Spline
    p: np.ndarray | None
    x: np.ndarray
    y: np.ndarray
    yp: np.ndarray
    rms_residuals: np.ndarray
    niter: int
    status: int
    message: str
    success: bool
    factor: object = None  # the last Newton factorisation on the final mesh (a start for a neighbour's Newton)


class _Band:
    """The banded layout of the augmented collocation system on ``m`` nodes (see the module docstring).

    Unknowns: node ``i``'s block ``[y (n), p (k), z (q)]`` (``na = n + k + q``); equations: the left
    boundary rows, then interval ``i``'s ``na`` rows (``n`` collocation, ``k + q`` copies), then the right
    boundary rows.  ``(r, c)`` is stored at ``ab[kl + ku + r - c, c]`` (LAPACK's band storage with room for
    the pivoting's fill), ``ab`` in Fortran order: the order LAPACK reads, so ``dgbtrf`` factors it in place
    (from C order its wrapper first transposes a copy: ~2/3 of the factorisation's time at 300 nodes)."""

    def __init__(self, L: "_Layout", n: int, k: int, m: int):
        self.n, self.k, self.q, self.m, self.na, self.kl, self.ku = n, k, L.q, m, L.na, L.kl, L.ku
        self.left, self.right, self.both, self.nl, self.nr = L.left, L.right, L.both, L.nl, L.nr
        rows, self.N = L.rows, L.na * m
        N, self.shape = self.N, (L.rows, self.N)
        # interval i's entries sit where interval 0's do, shifted na columns per interval (r - c is the same)
        steps = L.na * rows * np.arange(m - 1)[:, None]
        self.i_d0 = (steps + L.o_d0).ravel()  # d Phi_i / d y_i
        self.i_d1 = (steps + L.o_d1).ravel()  # d Phi_i / d y_{i+1}
        self.i_dp = (steps + L.o_dp).ravel() if k else None
        t = np.zeros((N, rows))  # the transpose of the band array, C order: its memory is the array's in Fortran order
        tf = t.reshape(-1)
        tf[(steps + L.o_copy0).ravel()] = -1.0  # the copies' rows: x_{i+1} - x_i = 0
        tf[(steps + L.o_copy1).ravel()] = 1.0
        # left rows: the separated ones, then a_r . y(a) - z_r; right rows: the separated ones, then b_r . y(b) + z_r
        shift = L.na * (m - 1) * rows  # the right rows' entries sit where they would on one interval, shifted
        for pos, val in L.left_entries:
            tf[pos] = val
        for pos, val in L.right_entries:
            tf[pos + shift] = val
        self.template = t.T  # (rows, N), Fortran order

    def matrix(self, d0, d1, dp) -> np.ndarray:
        """The band array (Fortran order) with the collocation blocks ``d0, d1`` (``(m-1, n, n)``) and ``dp``
        (``(m-1, n, k)``)."""
        ab = self.template.copy(order="F")
        f = ab.T.reshape(-1)  # a view: ab's memory
        f[self.i_d0] = d0.ravel()
        f[self.i_d1] = d1.ravel()
        if self.k:
            f[self.i_dp] = dp.ravel()
        return ab

    def rhs(self, col_res, bc_res) -> np.ndarray:
        """The augmented residual: ``bc_res`` split into its left and right rows, ``col_res`` by interval."""
        out = np.zeros(self.N)
        nl, n = self.nl, self.n
        out[:self.left.size] = bc_res[self.left]
        out[nl:nl + self.na * (self.m - 1)].reshape(self.m - 1, self.na)[:, :n] = col_res.T
        tail = out[self.N - self.nr:]
        tail[:self.right.size] = bc_res[self.right]
        tail[self.right.size:] = bc_res[self.both]
        return out

    def split(self, step: np.ndarray):
        """``(y_step (n, m), p_step (k,))`` of an augmented step."""
        s = step.reshape(self.m, self.na)
        return s[:, :self.n].T, s[0, self.n:self.n + self.k].copy()


class _Layout:
    """What a :class:`_Band` of the structure ``(n, k, A, B)`` shares on any number of nodes: the boundary rows'
    split (left, right, both ends), the band widths, the positions of interval 0's entries in the band array's
    memory (interval ``i``'s are shifted ``na * rows`` per interval) and the boundary rows' entries (the right
    ones as on a one-interval mesh, shifted by the intervals before the last)."""

    def __init__(self, n: int, k: int, A: np.ndarray, B: np.ndarray):
        left = np.flatnonzero(~np.any(B != 0.0, axis=1))
        right = np.flatnonzero(~np.any(A != 0.0, axis=1) & np.any(B != 0.0, axis=1))
        both = np.setdiff1d(np.arange(A.shape[0]), np.concatenate((left, right)))
        self.q = q = both.size
        self.na = na = n + k + q
        self.left, self.right, self.both = left, right, both
        self.nl, self.nr = left.size + q, right.size + q
        if self.nl + self.nr != na:
            raise ValueError(f"boundary conditions: {A.shape[0]} rows for {n} states and {k} parameters")
        self.kl = self.nl + na - 1
        self.ku = max(2 * na - 1 - self.nl, na - 1, 0)
        self.rows = rows = 2 * self.kl + self.ku + 1

        def flat(r, c):  # the position of (r, c) in the Fortran-order band array's memory
            return c * rows + (self.kl + self.ku + r - c)

        a, b = np.arange(n)[:, None], np.arange(n)[None, :]
        self.o_d0 = flat(self.nl + a, b).ravel()[None, :]
        self.o_d1 = flat(self.nl + a, na + b).ravel()[None, :]
        self.o_dp = flat(self.nl + a, n + np.arange(k)[None, :]).ravel()[None, :] if k else None
        j = np.arange(k + q)
        self.o_copy0 = flat(self.nl + n + j, n + j).ravel()[None, :]
        self.o_copy1 = flat(self.nl + n + j, na + n + j).ravel()[None, :]
        cols = np.arange(n)
        self.left_entries = [(flat(r, cols), A[src]) for r, src in enumerate(left)]
        for s, src in enumerate(both):
            r = left.size + s
            self.left_entries += [(flat(r, cols), A[src]), (flat(r, n + k + s), -1.0)]
        # on m nodes the right rows are rows N - nr + r and columns na (m - 1) + c: flat() of those is that of
        # rows na - nr + r and columns c, plus na (m - 1) rows (r - c is the same)
        base = na - self.nr
        self.right_entries = [(flat(base + r, cols), B[src]) for r, src in enumerate(right)]
        for s, src in enumerate(both):
            r = base + right.size + s
            self.right_entries += [(flat(r, cols), B[src]), (flat(r, n + k + s), 1.0)]


@lru_cache(maxsize=_BANDS)
def _layout(key) -> _Layout:
    """The :class:`_Layout` of a structure ``key = (n, k, A bytes, B bytes)`` (cached: a few per process)."""
    n, k, a, b = key
    return _Layout(n, k, np.frombuffer(a).reshape(n + k, n), np.frombuffer(b).reshape(n + k, n))


def _band(key, m: int) -> _Band:
    """The :class:`_Band` of a structure ``key = (n, k, A bytes, B bytes)`` on ``m`` nodes: cached up to
    :data:`_CACHED_NODES` nodes (a continuation solves on the same mesh size again and again; a layout is
    read-only once built), built afresh above."""
    if m > _CACHED_NODES:
        return _new_band(key, m)
    return _cached_band(key, m)


def _new_band(key, m: int) -> _Band:
    n, k, a, b = key
    return _Band(_layout(key), n, k, m)


_cached_band = lru_cache(maxsize=_BANDS)(_new_band)


class _Factor:
    """The banded LU of one Newton Jacobian on the mesh ``x``."""

    def __init__(self, band: _Band, ab: np.ndarray, x: np.ndarray, mesh: "_Mesh | None" = None):
        self.band, self.x, self.mesh = band, x, mesh
        self.lu, self.piv, info = dgbtrf(ab, band.kl, band.ku, overwrite_ab=1)
        self.singular = info != 0

    def solve(self, res: np.ndarray):
        x, _ = dgbtrs(self.lu, self.band.kl, self.band.ku, res, self.piv)
        return self.band.split(x)


def _collocation(fun, y, p, x, h, x_middle=None, mesh=None):
    """``solve_bvp``'s ``collocation_fun``: residuals at the interval midpoints, midpoint states, ``f``
    (``x_middle``: ``x[:-1] + 0.5 h``, where the caller has it: the same array for every call on one mesh;
    ``mesh``: a :class:`_Mesh` of ``x``, its products of ``h`` computed once: the same values)."""
    x_middle, h8, h6 = (x_middle, 0.125 * h, h / 6) if mesh is None else (mesh.x_middle, mesh.h8, mesh.h6)
    f = fun(x, y, p)
    y_middle = 0.5 * (y[:, 1:] + y[:, :-1]) - h8 * (f[:, 1:] - f[:, :-1])
    f_middle = fun(x[:-1] + 0.5 * h if x_middle is None else x_middle, y_middle, p)
    col_res = y[:, 1:] - y[:, :-1] - h6 * (f[:, :-1] + f[:, 1:] + 4 * f_middle)
    return col_res, y_middle, f, f_middle


class _Mesh:
    """What a Newton run on the mesh ``x`` (spacing ``h``) computes from it alone: the midpoints, ``0.125 h`` and
    ``h / 6`` (``solve_bvp``'s products, the same values) and its Newton tolerance ``2/3 h 0.05 tol``; kept with
    the factorisation made on it (``_Factor.mesh``): a walk's chord steps on one mesh compute them once."""

    def __init__(self, x: np.ndarray, h: np.ndarray, tol: float):
        self.x, self.tol = x, tol
        self.x_middle = x[:-1] + 0.5 * h
        self.h8, self.h6 = 0.125 * h, h / 6
        self.tol_r = 2 / 3 * h * 5e-2 * tol


def _jacobian_blocks(n, k, h, df_dy, df_dy_middle, df_dp, df_dp_middle):
    """``solve_bvp``'s ``construct_global_jac`` formulas: the blocks ``d0, d1, dp`` of each interval."""
    df_dy = np.transpose(df_dy, (2, 0, 1))
    df_dy_middle = np.transpose(df_dy_middle, (2, 0, 1))
    h = h[:, None, None]
    eye = np.identity(n)
    d0 = -eye - h / 6 * (df_dy[:-1] + 2 * df_dy_middle)
    d0 -= h**2 / 12 * np.matmul(df_dy_middle, df_dy[:-1])  # solve_bvp's stacked_matmul (einsum): ~10x slower
    d1 = eye - h / 6 * (df_dy[1:] + 2 * df_dy_middle)
    d1 += h**2 / 12 * np.matmul(df_dy_middle, df_dy[1:])
    dp = None
    if k:
        df_dp = np.transpose(df_dp, (2, 0, 1))
        df_dp_middle = np.transpose(df_dp_middle, (2, 0, 1)) + 0.125 * h * np.matmul(
            df_dy_middle, df_dp[:-1] - df_dp[1:])
        dp = -h / 6 * (df_dp[:-1] + df_dp[1:] + 4 * df_dp_middle)
    return d0, d1, dp


def _spline_coefficients(y, yp, h):
    """``solve_bvp``'s ``create_spline`` coefficients, shape ``(4, n, m - 1)`` (highest power first)."""
    c = np.empty((4,) + y[:, :-1].shape)
    slope = (y[:, 1:] - y[:, :-1]) / h
    t = (yp[:, :-1] + yp[:, 1:] - 2 * slope) / h
    c[0] = t / h
    c[1] = (slope - yp[:, :-1]) / h - t
    c[2] = yp[:, :-1]
    c[3] = y[:, :-1]
    return c


class Spline:
    """The piecewise cubic ``solve_bvp`` returns as ``sol`` (``scipy.interpolate.PPoly(np.moveaxis(c, 1, 0), x,
    extrapolate=True, axis=1)``), evaluated by the same arithmetic as ``PPoly``'s compiled evaluation without
    importing ``scipy.interpolate`` (~0.24 s of CPU, ~0.8 ms a point of a 300-point sweep): values
    bit-identical to ``PPoly``'s (``tests/test_collocation.py``).

    ``c``: coefficients ``(4, m - 1, n)``, highest power first, of ``n`` cubics on each interval of the
    breakpoints ``x`` (``m``, increasing).  ``sol(t)`` has shape ``(n,) + shape(t)``: interval ``i`` with
    ``x[i] <= t < x[i+1]`` (the last one closed; extrapolated by the end polynomials), ``s = t - x[i]`` and
    ``((c3 + c2 s) + c1 s^2) + c0 s^3`` with ``s^2 = s s``, ``s^3 = s^2 s``, summed from ``0.0``: ``PPoly``'s
    order of operations (SciPy's ``evaluate_poly1``)."""

    def __init__(self, c: np.ndarray, x: np.ndarray):
        self.c, self.x = c, x

    def __call__(self, t) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        flat = t.ravel()
        i = np.searchsorted(self.x, flat, side="right") - 1
        np.clip(i, 0, self.x.size - 2, out=i)
        s = (flat - self.x[i])[:, None]
        c = self.c[:, i, :]
        s2 = s * s
        out = ((0.0 + c[3]) + c[2] * s) + c[1] * s2
        out += c[0] * (s2 * s)
        return out.T.reshape((self.c.shape[2],) + t.shape)

    def end_value(self, t: float) -> np.ndarray:
        """``self(t)[:, 0]`` for one ``t`` in the last interval (``t >= x[-2]``; the right end, ``x[-1]``): the
        same arithmetic on the last interval's coefficients alone (each value computed elementwise alike)."""
        return _cubic(self.c[:, -1, :], t - self.x[-2])

    def end_component(self, t: float, j: int) -> float:
        """``self(t)[j, 0]`` for one ``t`` in the last interval: :meth:`end_value`'s arithmetic on component
        ``j`` alone, in Python floats (IEEE double operations, each rounded as numpy's elementwise ones)."""
        c0, c1, c2, c3 = (float(v) for v in self.c[:, -1, j])
        return _cubic_scalar(c0, c1, c2, c3, float(t - self.x[-2]))


def _cubic_scalar(c0: float, c1: float, c2: float, c3: float, s: float) -> float:
    """:func:`_cubic` of one cubic."""
    s2 = s * s
    out = ((0.0 + c3) + c2 * s) + c1 * s2
    return out + c0 * (s2 * s)


def _cubic(c: np.ndarray, s) -> np.ndarray:
    """:meth:`Spline.__call__`'s evaluation of the cubics ``c`` (``(4, n)``, highest power first) at ``s``."""
    s2 = s * s
    out = ((0.0 + c[3]) + c[2] * s) + c[1] * s2
    out += c[0] * (s2 * s)
    return out


def _spline(c, x) -> Spline:
    """``solve_bvp``'s spline from the coefficients ``c`` of :func:`_spline_coefficients` (``(4, n, m - 1)``)."""
    return Spline(np.ascontiguousarray(np.transpose(c, (0, 2, 1))), np.ascontiguousarray(x, dtype=np.float64))


class _LazySpline(Spline):
    """The :class:`Spline` of states ``y`` with slopes ``yp`` on the mesh ``x`` (spacing ``h``), its coefficients
    (:func:`_spline_coefficients`, laid out as :func:`_spline` does) computed on first use: a walk's solutions
    are read on a few points, most never (``refine=False``); the same values, the last interval alone read alone."""

    def __init__(self, y, yp, h, x):
        self._y, self._yp, self._h, self.x, self._c = y, yp, h, np.ascontiguousarray(x, dtype=np.float64), None

    @property
    def c(self) -> np.ndarray:
        if self._c is None:
            self._c = np.ascontiguousarray(np.transpose(_spline_coefficients(self._y, self._yp, self._h), (0, 2, 1)))
        return self._c

    def end_value(self, t: float) -> np.ndarray:
        if self._c is not None:
            return super().end_value(t)
        c = _spline_coefficients(self._y[:, -2:], self._yp[:, -2:], self._h[-1:])[:, :, 0]  # elementwise alike
        return _cubic(c, t - self.x[-2])

    def end_component(self, t: float, j: int) -> float:
        if self._c is not None:
            return super().end_component(t, j)
        y0, y1, p0, p1, h = map(float, (self._y[j, -2], self._y[j, -1], self._yp[j, -2], self._yp[j, -1], self._h[-1]))
        slope = (y1 - y0) / h  # _spline_coefficients' operations on the last interval, in its order
        u = (p0 + p1 - 2 * slope) / h
        return _cubic_scalar(u / h, (slope - p0) / h - u, p0, y0, float(t - self.x[-2]))


def _rms_residuals(fun, c, x, h, p, r_middle, f_middle):
    """``solve_bvp``'s ``estimate_rms_residuals``; the spline evaluated on each interval directly (the two
    Lobatto points of interval ``i`` lie inside it, where ``PPoly`` evaluates the same cubic)."""
    s = 0.5 * h * (3 / 7) ** 0.5
    out = []
    for d in (0.5 * h + s, 0.5 * h - s):
        val = ((c[0] * d + c[1]) * d + c[2]) * d + c[3]
        der = (3 * c[0] * d + 2 * c[1]) * d + c[2]
        f = fun(x[:-1] + d, val, p)
        r = (der - f) / (1 + np.abs(f))
        out.append(np.sum(r * r, axis=0))
    r_middle = r_middle / (1 + np.abs(f_middle))
    r_middle = np.sum(r_middle * r_middle, axis=0)
    return (0.5 * (32 / 45 * r_middle + 49 / 90 * (out[0] + out[1]))) ** 0.5


def _newton(band, h, x, fun, fun_jac, bc, y, p, bvp_tol, bc_tol):
    """``solve_bvp``'s ``solve_newton`` (same constants, same tests), solved on the band."""
    n, k = band.n, band.k
    mesh = _Mesh(x, h, bvp_tol)
    tol_r, x_middle = mesh.tol_r, mesh.x_middle
    max_njev, max_iter, sigma, tau, n_trial = 4, 8, 0.2, 0.5, 4
    col_res, y_middle, f, f_middle = _collocation(fun, y, p, x, h, mesh=mesh)
    bc_res = bc(y[:, 0], y[:, -1])
    res = band.rhs(col_res, bc_res)
    njev, singular, recompute_jac, factor = 0, False, True, None
    for _ in range(max_iter):
        if recompute_jac:
            df_dy, df_dp = fun_jac(x, y, p)
            df_dy_m, df_dp_m = fun_jac(x_middle, y_middle, p)
            factor = _Factor(band, band.matrix(*_jacobian_blocks(n, k, h, df_dy, df_dy_m, df_dp, df_dp_m)), x, mesh)
            njev += 1
            if factor.singular:
                singular = True
                break
            y_step, p_step = factor.solve(res)
            cost = np.dot(y_step.ravel(), y_step.ravel()) + np.dot(p_step, p_step)
        alpha = 1
        for trial in range(n_trial + 1):
            y_new = y - alpha * y_step
            p_new = p - alpha * p_step
            col_res, y_middle, f, f_middle = _collocation(fun, y_new, p_new, x, h, mesh=mesh)
            bc_res = bc(y_new[:, 0], y_new[:, -1])
            res = band.rhs(col_res, bc_res)
            ys_new, ps_new = factor.solve(res)
            cost_new = np.dot(ys_new.ravel(), ys_new.ravel()) + np.dot(ps_new, ps_new)
            if cost_new < (1 - 2 * alpha * sigma) * cost:
                break
            if trial < n_trial:
                alpha *= tau
        y, p = y_new, p_new
        if njev == max_njev:
            break
        if (np.abs(col_res) < tol_r * (1 + np.abs(f_middle))).all() and (np.abs(bc_res) < bc_tol).all():
            break
        if alpha == 1:
            y_step, p_step, cost = ys_new, ps_new, cost_new
            recompute_jac = False
        else:
            recompute_jac = True
    return y, p, singular, (col_res, f, f_middle), factor


def _refined(x, rms_res, tol):
    """``solve_bvp``'s node insertion: one node in the middle of each interval whose rms residual is in
    ``(tol, 100 tol)``, two (thirds) in each at or above ``100 tol``."""
    insert_1, = np.nonzero((rms_res > tol) & (rms_res < 100 * tol))
    insert_2, = np.nonzero(rms_res >= 100 * tol)
    if insert_1.size + insert_2.size == 0:
        return x
    return np.sort(np.hstack((x, 0.5 * (x[insert_1] + x[insert_1 + 1]), (2 * x[insert_2] + x[insert_2 + 1]) / 3,
                              (x[insert_2] + 2 * x[insert_2 + 1]) / 3)))


def _checked(fun_jac, A, B, c, x, y, p, tol, bc_tol):
    """The arguments of :func:`solve_collocation` checked as ``solve_bvp`` checks them, and the pieces both
    solvers use: ``x, h, y, p, n, k, tol, bc_tol, jac, bc, key``."""
    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or x.size < 2:
        raise ValueError("`x` must be 1 dimensional with at least 2 nodes.")
    h = np.diff(x)
    if (h <= 0).any():
        raise ValueError("`x` must be strictly increasing.")
    y = np.array(y, dtype=float)
    if y.ndim != 2 or y.shape[1] != x.size:
        raise ValueError(f"`y` must have shape (n, {x.size}), got {y.shape}")
    p = np.zeros(0) if p is None else np.array(p, dtype=float).ravel()
    n, k = y.shape[0], p.size
    A, B, c = (np.asarray(v, dtype=float) for v in (A, B, c))
    if A.shape != (n + k, n) or B.shape != (n + k, n) or c.shape != (n + k,):
        raise ValueError(f"boundary conditions must be ({n + k}, {n}) matrices and a ({n + k},) vector")
    tol = max(float(tol), 100 * _EPS)
    bc_tol = tol if bc_tol is None else float(bc_tol)
    if k:
        jac = fun_jac
    else:
        def jac(t, z, q):
            return fun_jac(t, z, None), None

    def bc(ya, yb):
        return A @ ya + B @ yb - c

    return x, h, y, p, n, k, tol, bc_tol, jac, bc, (n, k, A.tobytes(), B.tobytes())


def solve_collocation(fun, fun_jac, A, B, c, x, y, p=None, *, tol: float = 1e-3, max_nodes: int = 1000,
                      bc_tol: float | None = None) -> CollocationResult:
    """``solve_bvp(fun, bc, x, y, p, fun_jac=fun_jac, bc_jac=..., tol=tol, max_nodes=max_nodes)`` for the
    linear boundary conditions ``A y(a) + B y(b) = c`` (``A, B`` of shape ``(n + k, n)``, independent of
    ``p``), with a banded LU (see the module docstring).

    ``fun(x, y, p)`` returns ``(n, m)``; ``fun_jac(x, y, p)`` returns ``df/dy`` ``(n, n, m)``, with
    parameters ``(df/dy, df/dp)``, ``df/dp`` ``(n, k, m)``.  Raises ``ValueError`` for a mesh that is
    not strictly increasing or arrays of the wrong shapes (as ``solve_bvp``).
    """
    x, h, y, p, n, k, tol, bc_tol, jac, bc, key = _checked(fun_jac, A, B, c, x, y, p, tol, bc_tol)
    status, iteration = 0, 0
    while True:
        m = x.size
        band = _band(key, m)
        y, p, singular, (col_res, f, f_middle), factor = _newton(band, h, x, fun, jac, bc, y, p, tol, bc_tol)
        iteration += 1  # the collocation residuals at the final (y, p) are the Newton's last ones
        max_bc_res = np.max(np.abs(bc(y[:, 0], y[:, -1])))
        r_middle = 1.5 * col_res / h
        coef = _spline_coefficients(y, f, h)
        rms_res = _rms_residuals(fun, coef, x, h, p, r_middle, f_middle)
        if singular:
            status = 2
            break
        x_new = _refined(x, rms_res, tol)
        if x_new.size > max_nodes:
            status = 1
            break
        if x_new.size > m:
            y = _spline(coef, x)(x_new)
            x, h = x_new, np.diff(x_new)
        elif max_bc_res <= bc_tol:
            status = 0
            break
        elif iteration >= 10:
            status = 3
            break
    return CollocationResult(sol=_spline(coef, x), p=p if k else None, x=x, y=y, yp=f, rms_residuals=rms_res,
                             niter=iteration, status=status, message=MESSAGES[status], success=status == 0,
                             factor=factor if factor is not None and not factor.singular else None)


def continue_collocation(fun, fun_jac, A, B, c, x, y, p=None, *, tol: float, factor=None,
                         max_steps: int = _CHORD_STEPS, max_nodes: int = 1000,
                         refine: bool = True) -> CollocationResult | None:
    """The collocation equations of :func:`solve_collocation` on the mesh ``x`` solved from a close start
    ``(y, p)`` (a continuation's predictor) by chord Newton steps with ``factor``, the banded LU of a
    neighbouring problem's Jacobian on the same mesh (``CollocationResult.factor``; factored here at the start
    when ``None`` or of another mesh), refactored once at the current iterate when a step contracts the
    affine-invariant criterion ``|J^-1 r|^2`` by less than :data:`_CHORD_RATE`.

    It stops by ``solve_bvp``'s own Newton test (every collocation residual below
    ``2/3 h 0.05 tol (1 + |f_middle|)``, boundary residuals below ``bc_tol``) and is accepted by its own final
    test on this mesh (every interval's rms relative residual ``<= tol``, boundary residual ``<= bc_tol``):
    what ``solve_bvp`` returns from this start, to within its Newton test.  Where the rms test asks for
    nodes, they are inserted as ``solve_bvp`` inserts them and :func:`solve_collocation` goes on from the
    converged states (as ``solve_bvp``'s next iteration does; at most ``max_nodes``).  Returns ``None`` where
    the steps do not meet the Newton test within ``max_steps`` or the run fails (the caller then runs
    :func:`solve_collocation` from its start); the result's ``factor`` is the last one used, for the next
    point.

    With ``refine=False`` the equations are solved on ``x`` as it is: the result is accepted by the Newton
    and boundary tests alone (no rms test, no node inserted) and its ``rms_residuals`` are not estimated (all
    NaN: the spline's residual between nodes is not what such a mesh is sized by, ~1/6 of a chord step's
    cost).  The caller sizes ``x`` for the accuracy it needs (the sweep's walk, :mod:`simgrip.sweep.reference`:
    the nodal discretisation error estimated by Richardson).
    """
    x, h, y, p, n, k, tol, bc_tol, jac, bc, key = _checked(fun_jac, A, B, c, x, y, p, tol, bc_tol=None)
    band = _band(key, x.size)
    fresh = factor is None or factor.band is not band or not (factor.x is x or np.array_equal(factor.x, x))
    mesh = None if fresh else factor.mesh
    if mesh is None or mesh.x is not x or mesh.tol != tol:
        mesh = _Mesh(x, h, tol)
    tol_r, x_middle = mesh.tol_r, mesh.x_middle

    def refactor(y, p):
        col_res, y_middle, f, f_middle = _collocation(fun, y, p, x, h, mesh=mesh)
        df_dy, df_dp = jac(x, y, p)
        df_dy_m, df_dp_m = jac(x_middle, y_middle, p)
        return _Factor(band, band.matrix(*_jacobian_blocks(n, k, h, df_dy, df_dy_m, df_dp, df_dp_m)), x, mesh)

    if fresh:
        factor = refactor(y, p)
    cost_before = None
    for step in range(max_steps + 1):
        col_res, _, f, f_middle = _collocation(fun, y, p, x, h, mesh=mesh)
        bc_res = bc(y[:, 0], y[:, -1])
        if (np.abs(col_res) < tol_r * (1 + np.abs(f_middle))).all() and (np.abs(bc_res) < bc_tol).all():
            break
        if step == max_steps or factor.singular:
            return None
        res = band.rhs(col_res, bc_res)
        ys, ps = factor.solve(res)
        cost = np.dot(ys.ravel(), ys.ravel()) + np.dot(ps, ps)
        if cost_before is not None and cost > _CHORD_RATE * cost_before:
            if fresh:
                return None  # a fresh Jacobian that does not contract: not a start Newton can take
            factor, fresh = refactor(y, p), True
            if factor.singular:
                return None
            ys, ps = factor.solve(res)
            cost = np.dot(ys.ravel(), ys.ravel()) + np.dot(ps, ps)
        if not math.isfinite(cost):
            return None
        y, p, cost_before = y - ys, p - ps, cost
    if not refine:
        if not np.abs(bc_res).max() <= bc_tol:
            return None
        return CollocationResult(sol=_LazySpline(y, f, h, x), p=p if k else None, x=x, y=y, yp=f,
                                 rms_residuals=np.full(x.size - 1, np.nan), niter=1, status=0, message=ON_MESH,
                                 success=True, factor=factor)
    coef = _spline_coefficients(y, f, h)
    rms_res = _rms_residuals(fun, coef, x, h, p, 1.5 * col_res / h, f_middle)
    if not np.abs(bc_res).max() <= bc_tol:
        return None
    x_new = _refined(x, rms_res, tol)
    if x_new.size > x.size:  # the mesh does not resolve this point: go on as solve_bvp goes on from here
        r = solve_collocation(fun, fun_jac, A, B, c, x_new, _spline(coef, x)(x_new), p if k else None, tol=tol,
                              max_nodes=max_nodes)
        return r if r.success else None
    return CollocationResult(sol=_spline(coef, x), p=p if k else None, x=x, y=y, yp=f, rms_residuals=rms_res,
                             niter=1, status=0, message=MESSAGES[0], success=True, factor=factor)
