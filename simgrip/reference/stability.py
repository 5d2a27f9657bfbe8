"""Stability of a discrete equilibrium: the smallest eigenvalue of the projected Hessian, and the banded algebra.

The paper's test (Section 4, eqs. 29-31): an equilibrium ``x*`` of a discrete
energy with one constraint ``c(x) = 0`` is stable when the Hessian ``L`` of the
Lagrangian is positive definite on the constraint's tangent space
``{v : grad c . v = 0}``, i.e. when the smallest eigenvalue of ``E^T L E`` is
positive (``E`` a basis of that space).  The sign does not depend on the metric
used to measure ``v``; the magnitude does.

Normalisation (what ``min_eigenvalue`` of the solvers reports)
    A discrete energy approximates ``V[theta] = int_0^1 e ds`` by a quadrature
    ``V_h(x) = sum_i w_i e_i`` over its unknowns ``x_i ~ theta(s_i)`` (weights
    ``w_i``: the trapezoid rule for the paper's nodal scheme, ``ds`` per link for
    the hinge chain).  For a perturbation ``v_i = dtheta(s_i)`` one has
    ``v^T L v -> d2V[dtheta]`` (the second variation) and
    ``v^T W v -> int dtheta^2 ds`` with ``W = diag(w)``.  The Euclidean eigenvalue of
    ``E^T L E`` (the paper's number) is therefore ``~ ds`` times the continuous one
    and vanishes as the mesh is refined.  The solvers report instead the
    smallest eigenvalue of the pencil ``(E^T L E, E^T W E)``::

        lambda_min = min_{v : grad c . v = 0}  v^T L v / v^T W v
                  -> min_{dtheta(0) = 0, dX(s_c) = 0}  d2V[dtheta] / int dtheta^2 ds

    the smallest eigenvalue of the second variation in the ``L^2`` metric, to
    which both schemes converge at second order in ``ds``.  Units: energy
    (``rho g l^2``) per ``l``, i.e. ``rho g l``, the force scale (multiply by
    ``rho g l`` for newtons).  Check: the unloaded, gravity-free cantilever has
    ``d2V = D int dtheta'^2``, ``lambda_min = D pi^2 / 4`` (in newtons
    ``pi^2 EI / (4 l^2)``, the Euler buckling load of a cantilever).

Algebra
    The Hessians of both schemes are tridiagonal.  :func:`tridiagonal_min_eigenvalue`
    gets ``lambda_min`` in O(m) per bisection step from Sylvester inertia counts of
    ``W^{-1/2} L W^{-1/2}`` bordered by ``W^{-1/2} grad c``; :func:`min_eigenvalue`
    is the dense version (a Householder basis) for any matrix.
    :func:`tri_factor` / :func:`tri_solve` (``L D L^T`` without pivoting) serve
    the minimiser's Newton steps.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["min_eigenvalue", "null_basis", "tri_factor", "tri_solve", "tridiagonal_min_eigenvalue"]


def null_basis(a: np.ndarray) -> np.ndarray:
    """Orthonormal basis (columns) of ``{u : a . u = 0}`` from a Householder reflection."""
    m = a.size
    na = float(np.linalg.norm(a))
    if na == 0.0:
        return np.eye(m)
    v = a / na
    # reflect v onto -sign(v0) e0 (stable choice)
    sgn = 1.0 if v[0] >= 0 else -1.0
    u = v.copy()
    u[0] += sgn
    u /= np.linalg.norm(u)
    hmat = np.eye(m) - 2.0 * np.outer(u, u)
    return hmat[:, 1:]


def _weighted(weights, size: int):
    """``W^{-1/2}`` as a vector (ones when ``weights`` is None)."""
    if weights is None:
        return np.ones(size)
    w = np.asarray(weights, dtype=float)
    if w.shape != (size,) or not np.all(w > 0):
        raise ValueError(f"weights must be {size} positive numbers, got shape {w.shape}")
    return 1.0 / np.sqrt(w)


def min_eigenvalue(hessian: np.ndarray, constraint_gradient: np.ndarray | None = None, weights=None) -> float:
    """Smallest eigenvalue of ``E^T L E`` (eqs. 29-31), or of ``L`` when unconstrained.

    Parameters
    ----------
    hessian : ndarray (m, m)
        ``L``, the Hessian of the Lagrangian at the equilibrium (for the models of
        this package, the Hessian of the energy including the converged multiplier
        term ``-N1 X(s_c)``).
    constraint_gradient : ndarray (m,), optional
        ``grad c``; ``E`` spans its orthogonal complement.
    weights : ndarray (m,), optional
        The metric ``W = diag(weights)``: the eigenvalue of the pencil
        ``(E^T L E, E^T W E)`` (see the module docstring).  Default: Euclidean
        (``E`` orthonormal), the paper's number.
    """
    h = np.asarray(hessian, dtype=float)
    if h.ndim != 2 or h.shape[0] != h.shape[1] or h.shape[0] < 1 or not np.all(np.isfinite(h)):
        raise ValueError(f"hessian must be a finite square matrix, got shape {h.shape}")
    if constraint_gradient is not None and np.shape(constraint_gradient) != (h.shape[0],):
        raise ValueError(f"constraint_gradient must have shape ({h.shape[0]},), the hessian's size, got "
                         f"{np.shape(constraint_gradient)}")
    r = _weighted(weights, h.shape[0])
    h = r[:, None] * h * r[None, :]
    if constraint_gradient is None:
        import scipy.linalg as sla

        return float(sla.eigvalsh(h, subset_by_index=[0, 0])[0])
    z = null_basis(r * np.asarray(constraint_gradient, dtype=float))
    hr = z.T @ h @ z
    import scipy.linalg as sla

    return float(sla.eigvalsh(0.5 * (hr + hr.T), subset_by_index=[0, 0])[0])


def _count_below(diag, off, a, lam: float) -> int:
    """Number of eigenvalues below ``lam`` of a tridiagonal ``H`` (``a`` None) or of ``Z^T H Z``.

    One ``L D L^T`` sweep of ``H - lam I`` (Sylvester): negative pivots count the
    eigenvalues of ``H`` below ``lam``; with a constraint gradient ``a`` the
    bordered matrix ``[[H - lam, a], [a^T, 0]]`` has one more pivot,
    ``-a^T (H - lam)^{-1} a = -sum z_i^2 / d_i`` (``z = L^{-1} a``), and its inertia is
    that of ``Z^T (H - lam) Z`` plus one positive and one negative eigenvalue.
    """
    tiny = 1e-300
    neg = 0
    q = 0.0
    d = diag[0] - lam
    if d == 0.0:
        d = -tiny
    z = a[0] if a is not None else 0.0
    if d < 0:
        neg += 1
    q += z * z / d
    for i in range(1, len(diag)):
        li = off[i - 1] / d
        d = diag[i] - lam - li * off[i - 1]
        if d == 0.0:
            d = -tiny
        if d < 0:
            neg += 1
        if a is not None:
            z = a[i] - li * z
            q += z * z / d
    if a is None:
        return neg
    return neg + (1 if q > 0 else 0) - 1


def tridiagonal_min_eigenvalue(diag: np.ndarray, off: np.ndarray, a: np.ndarray | None = None, weights=None, *,
                               sign_only: bool = False) -> float:
    """Smallest eigenvalue of a tridiagonal ``H`` or of ``Z^T H Z`` (``Z`` spans ``a``'s complement).

    Unconstrained: LAPACK bisection (:func:`scipy.linalg.eigvalsh_tridiagonal`).
    Constrained: bisection on the inertia count of :func:`_count_below`, to the
    absolute accuracy ``~ eps |H|`` that a dense symmetric eigensolver also has.
    O(m) per step, about 60 steps.  ``weights``: the metric, as in :func:`min_eigenvalue`.
    ``sign_only`` (constrained): stop once zero has left the bracket and return its
    end on the eigenvalue's side: a value whose sign (``> 0`` or not) is exactly that
    of the full bisection's result (the bracket only shrinks), not the eigenvalue.
    """
    r = _weighted(weights, diag.size)
    diag, off = diag * r * r, off * r[:-1] * r[1:]
    if a is not None:
        a = r * np.asarray(a, dtype=float)
    if a is None:
        if diag.size == 1:
            return float(diag[0])
        import scipy.linalg as sla

        return float(sla.eigvalsh_tridiagonal(diag, off, select="i", select_range=(0, 0))[0])
    dl, ol, al = diag.tolist(), off.tolist(), np.asarray(a, float).tolist()
    rad = np.abs(np.concatenate([[0.0], off])) + np.abs(np.concatenate([off, [0.0]]))
    lo = float(np.min(diag - rad))
    hi = float(np.max(diag + rad))
    span = max(abs(lo), abs(hi), 1e-300)
    lo -= 1e-12 * span
    hi += 1e-12 * span
    while hi - lo > 4.0 * np.finfo(float).eps * span:
        if sign_only and (lo > 0.0 or hi <= 0.0):
            return lo if lo > 0.0 else hi
        mid = 0.5 * (lo + hi)
        if mid <= lo or mid >= hi:
            break
        if _count_below(dl, ol, al, mid) >= 1:
            hi = mid
        else:
            lo = mid
    return 0.5 * (lo + hi)


def tri_factor(diag: np.ndarray, off: np.ndarray):
    """``L D L^T`` of a symmetric tridiagonal matrix without pivoting: ``(pivots, multipliers)``.

    The signs of the pivots give the inertia (Sylvester's law).
    """
    dl = diag.tolist()
    ol = off.tolist()
    m = len(dl)
    piv = [0.0] * m
    mult = [0.0] * (m - 1)
    d = dl[0]
    piv[0] = d
    for i in range(1, m):
        li = ol[i - 1] / d if d != 0.0 else math.inf
        mult[i - 1] = li
        d = dl[i] - li * ol[i - 1]
        piv[i] = d
    return np.array(piv), np.array(mult)


def tri_solve(piv: np.ndarray, mult: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve with the factors of :func:`tri_factor`; ``b`` of shape ``(m,)`` or ``(m, k)``."""
    b = np.asarray(b, dtype=float)
    cols = [b] if b.ndim == 1 else [b[:, j] for j in range(b.shape[1])]
    ml = mult.tolist()
    pl = piv.tolist()
    m = len(pl)
    out = []
    for col in cols:
        z = col.tolist()
        for i in range(1, m):
            z[i] -= ml[i - 1] * z[i - 1]
        for i in range(m):
            z[i] /= pl[i]
        for i in range(m - 2, -1, -1):
            z[i] -= ml[i] * z[i + 1]
        out.append(z)
    res = np.array(out)
    return res[0] if b.ndim == 1 else res.T
