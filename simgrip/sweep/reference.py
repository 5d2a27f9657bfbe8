"""The BVP references of one sweep segment at the cost of a continuation, equal to the per-point cold solves.

Along a segment (:meth:`simgrip.sweep.grid.SweepGrid.segments`) of points
``0..m-1`` the references are solved as follows:

1. the first point is solved by its cold path without the final polish
   (:func:`sized_start`: :func:`cold` at ``TOL_MID``, the branch of the full
   cold solve, what :func:`simgrip.sweep.point.evaluate_point` does at every
   point), finished by Newton on that solve's mesh or a refinement of it, the
   first whose discretisation error is within :data:`TOL` (:func:`walk_error`);
   where that fails, or the segment is one BVP, it is solved cold in full;
2. from it a walk warm-starts each next point from the previous ones
   (:func:`warm`: the quadratic predictor of the three before it, then chord Newton
   steps with the previous point's Jacobian factorisation, stopped by
   ``solve_bvp``'s own Newton test at the final tolerance) on the first point's
   mesh (:func:`on_sized_mesh`: ``N1`` and ``theta`` within :data:`TOL` of a 1e-8
   ``solve_bvp`` solve at 1/3-1/5 of its nodes), the walk's last point checked by
   the same error estimate (else the walk is run again on ``solve_bvp``'s
   meshes: the neighbour's, accepted by its residual test, else one
   ``solve_bvp`` run from the same start) up to the last point;
3. where the segment ends before its line, the walk takes one more warm step,
   to the next segment's first point, whose cold path without its final
   polish is run (:meth:`_Segment.ahead_checked`; kept, :data:`_AHEAD`: it is
   the next segment's start, so a segment run next in the same process does
   not solve it again); where the step arrives on its branch (``theta`` within
   :data:`SAME_BRANCH_RAD`) the whole walk is kept; otherwise, or at a line's
   end, the last point's cold path is run without its final polish
   (:meth:`_Segment.end_checked`), and where the walk arrives on its branch the
   whole walk is kept;
4. otherwise the last point is solved cold, and where the walk is not on its
   branch the interval is bisected: the midpoint is solved cold, the left
   half is checked against it with the same walk, the right half walked again
   from it.  A point whose walk was not on the cold branch ends up cold, with a
   warning (``bvp_warning``) saying so; a point whose warm step did not
   converge is solved cold.

Points of a segment with the same BVP (:func:`problem_key`: a line along
``mu``, which enters only the verdict) share one solution: the cold solve of
one is the cold solve of all (it is a deterministic function of the problem).

Why the check: a cold start chooses its branch by its own path (from the
unloaded arc, :func:`simgrip.reference.continuation.cold_start`), and which
branch that path reaches can change along a grid line where the warm walk
carries on along one branch without any jump between neighbours (found on
Grip I at kappa -9..-1 and Grip II at 1..9: normal forces 3x apart and
verdicts that differ).  The per-point verdicts are the definition, so the walk
is kept only where it is verified to end on the cold solve's branch.  What is
assumed: between two verified ends the cold branch does not leave and come
back (the tests compare every point with its cold solve on grids that cross
the switches).
"""

from __future__ import annotations

import math
import threading
import time

import numpy as np

__all__ = ["SAME_BRANCH_RAD", "Reference", "cold", "warm", "segment_references"]

#: Two converged references (tolerance 1e-8) whose ``theta`` differ by less than this [rad] are one equilibrium:
#: the same branch solved twice agrees to ~1e-8 rad (the collocation tolerance carried through the mesh), while
#: the distinct equilibria met along the grids differ by O(0.1-1) rad; 1e-3 sits far from both.
SAME_BRANCH_RAD = 1e-3
#: A warm start may reuse its predecessor's mesh up to this many nodes (solve_bvp only adds nodes; above it the
#: mesh is thinned as the solver's own continuation does, so meshes do not grow along a segment).
_WARM_NODES = 1200
#: The tolerance of :func:`simgrip.reference.elastica.solve` (its default): warm and cold solves meet it alike.
TOL = 1e-8
#: Thinnings of a cold reference's mesh tried for a walk (:func:`walk_mesh`), coarsest first, and the fewest nodes
#: a walk's mesh may have (below it the fourth-order asymptotics the error estimate assumes are not trusted).
WALK_THINNING = (4, 2)
WALK_MIN_NODES = 41


def cold(point, tol: float = TOL):
    """``point``'s reference solved cold: :func:`simgrip.reference.elastica.solve` at its parameters, uniform
    curvature (raises what it raises).  With ``tol = TOL_MID`` it is the same cold path without its final
    polish (:func:`simgrip.reference.continuation.polish`): the branch check of a segment's far end."""
    from simgrip.profiles import Uniform
    from simgrip.reference import elastica

    return elastica.solve(point.grip, point.params(), Uniform(point.kappa), tol=tol)


def warm(point, guess, before=(), newton=None):
    """``point``'s reference from the converged ``guess`` (an
    :class:`~simgrip.reference.elastica.ElasticaSolution` of a neighbouring point: its mesh, states and
    unknown parameters) at tolerance :data:`TOL`; ``None`` when it does not converge.

    ``before``: the solutions of the points before ``guess`` on the same line, nearest first, each the same
    spacing from the next.  From ``guess`` and one of them the start is the secant predictor
    ``2 y1 - y2``, from two the quadratic one ``3 y1 - 3 y2 + y3``, from three the cubic one
    ``4 y1 - 6 y2 + 4 y3 - y4`` (states and parameters, each read on the mesh solved on): its error is fourth
    order in the step; on the 300-point Grip I line it takes 1.2 chord steps a point against 2.1 for the
    quadratic one (a quartic one saves 10% more in the first segments, with twice the amplification of the
    neighbours' round-off: not taken).

    With ``newton["mesh"]`` (the walk's mesh, :func:`on_sized_mesh`) Newton runs on that mesh by chord steps
    with the Jacobian factorisation ``newton["factor"]`` of the walk's last solve (updated here), stopped by
    ``solve_bvp``'s own Newton test at :data:`TOL` (:func:`simgrip.reference.bvp.mesh_bvp`); where it does
    not converge, or without a mesh, on ``guess``'s mesh, accepted only by ``solve_bvp``'s own Newton and
    residual tests at :data:`TOL`; otherwise (or without ``newton``) one ``solve_bvp`` run from the same start
    (:func:`simgrip.reference.bvp.warm_bvp`).
    """
    from simgrip.profiles import Uniform
    from simgrip.reference import elastica
    from simgrip.reference.bvp import mesh_bvp, run_bvp, warm_bvp
    from simgrip.reference.continuation import _mesh_guess

    grip, params, P = elastica.checked_problem(point.grip, point.params(), Uniform(point.kappa))
    raw = guess._raw
    mesh = None if newton is None else newton.get("mesh")
    if mesh is not None and _same_layout(raw.prob, P):
        x, y, p = _predicted(mesh, guess, before, P)
        r, factor = mesh_bvp(P, x, y, p, TOL, newton.get("factor"))
        if r is not None:
            newton["factor"] = factor
            return Reference(grip, params, r)
        newton["factor"] = None  # not converged on the walk's mesh: solve_bvp's way from the neighbour below
    on_mesh = _same_layout(raw.prob, P) and raw.x.size <= _WARM_NODES
    if on_mesh:
        x, y, p = _predicted(raw.x, guess, before, P)
    else:
        x, y, p = _mesh_guess(raw, P)
    if newton is None:
        r = run_bvp(P, x, y, p, TOL)
    else:
        r, newton["factor"] = warm_bvp(P, x, y, p, TOL, newton.get("factor") if on_mesh else None)
    return None if r is None else Reference(grip, params, r)


class Reference:
    """A reference as the sweep reads it: :meth:`ElasticaSolution.from_bvp
    <simgrip.reference.elastica.ElasticaSolution.from_bvp>`'s ``N1``, ``normal_force``, ``required_mu`` and
    ``feasible`` (the same values: the same operations on the same numbers, the tip read at ``s = 1`` alone
    instead of on the 201-point grid, where each value is computed elementwise alike; tested against it), and
    the BVP solution ``_raw``; any other attribute of the ``ElasticaSolution`` is built on first access.
    Saves the sampling of every walked point on the fine grid (~1/6 of a warm step)."""

    __slots__ = ("grip", "params", "_raw", "_full", "N1", "normal_force", "required_mu", "feasible")

    def __init__(self, grip: str, params, raw):
        self.grip, self.params, self._raw, self._full = grip, params, raw, None
        P = raw.prob
        tip_y = _tip_y(raw)
        N1 = N2 = n = f = req = 0.0
        feas = {}
        if grip != "free":
            N1, N2 = raw.N1, P.N2
            if grip == "III":
                cs = raw.contact_state()
                thg = cs[0]
                f = N1 * math.cos(thg) + N2 * math.sin(thg)
                n = -N1 * math.sin(thg) + N2 * math.cos(thg)
            else:
                n, f = N1, N2
            req = abs(f) / n if n > 0 else math.inf
            feas = {"contact": bool(n > 0), "friction": bool(n > 0 and abs(f) <= params.mu_s * n)}
            if grip == "III":
                feas["tip_clear"] = bool(tip_y < cs[3])
            else:
                feas["grip_shape"] = bool((-1.0 if grip == "I" else 1.0) * tip_y > 0.0)
        self.N1, self.normal_force, self.required_mu = float(N1), float(n), float(req)
        self.feasible = all(feas.values())

    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        from simgrip.reference import elastica

        if self._full is None:
            self._full = elastica.ElasticaSolution.from_bvp(self.grip, self.params, self._raw)
        return getattr(self._full, name)


_TIP = np.array([1.0])


def _tip_y(raw) -> float:
    """``Y`` of the rod's end (``s = 1``) as ``raw.states`` reads it: its spline's ``Y`` component at ``t = 1``
    (the last interval's cubic, :meth:`~simgrip.reference.collocation.Spline.end_component`: the same value;
    Grip III's outer segment maps ``s = 1`` to ``(1 - gamma) / (1 - gamma) = 1`` exactly); ``states`` itself
    for any other ``sol``."""
    from simgrip.reference.collocation import Spline

    if isinstance(raw.sol, Spline):
        return raw.sol.end_component(1.0, 7 if raw.prob.two_seg else 3)
    return float(raw.states(_TIP)[3, 0])


def _predicted(x, guess, before, P):
    """``(x, y, p)``: the predictor of :func:`warm` on the mesh ``x`` from ``guess`` and the solutions
    ``before`` it (states read on ``x``: the arrays themselves where a solution lives on ``x``)."""
    def on_x(b):
        return b.y if b.x is x or (b.x.size == x.size and np.array_equal(b.x, x)) else b.sol(x)

    raw = guess._raw
    y, p = on_x(raw), (raw.p if P.constrained else None)
    hist = []
    for b in before[:3]:
        if b is None or not _same_layout(b._raw.prob, P):
            break
        hist.append((on_x(b._raw), b._raw.p))
    if hist:
        coef = _PREDICTOR[len(hist)]
        sy = sp = 0  # summed as sum() sums: from 0, in order
        for c, h in zip(coef[1:], hist):
            sy = sy + c * h[0]
            if P.constrained:
                sp = sp + c * h[1]
        y = coef[0] * y + sy
        if P.constrained:
            p = coef[0] * p + sp
    return x, y, p


#: The predictor's coefficients by the number of solutions before the guess (:func:`warm`).
_PREDICTOR = {1: (2.0, -1.0), 2: (3.0, -3.0, 1.0), 3: (4.0, -6.0, 4.0, -1.0)}


def _thinned(x: np.ndarray, f: int) -> np.ndarray:
    """Every ``f``-th node of ``x``, its last node kept."""
    idx = np.arange(0, x.size, f)
    return idx if idx[-1] == x.size - 1 else np.append(idx, x.size - 1)


def _gap(a, b, idx) -> float:
    """Discretisation gap between ``a`` (a solution on ``b``'s nodes ``idx``) and ``b``: the largest of the
    difference of ``theta`` [rad] at ``a``'s nodes and (constrained problems) that of ``N1`` over
    ``max(|N1|, 1)``: relative to the force, or to the rod's own weight (``rho g l = 1``) where the force is
    smaller (a force through zero, where the verdict's sign test needs it absolute)."""
    n = a.y.shape[0]
    out = float(np.max(np.abs(a.y[0:n:4] - b.y[0:n:4, idx])))
    if a.prob.constrained:
        out = max(out, abs(float(a.p[0]) - float(b.p[0])) / max(abs(float(b.p[0])), 1.0))
    return out if np.isfinite(out) else np.inf


def _doubled(x: np.ndarray) -> np.ndarray:
    """``x`` with a node in the middle of each interval."""
    out = np.empty(2 * x.size - 1)
    out[0::2] = x
    out[1::2] = 0.5 * (x[:-1] + x[1:])
    return out


def on_sized_mesh(sol, meshes):
    """``(solution, factor)``: ``sol``'s problem solved on the first of ``meshes`` (node arrays in ``[0, 1]``)
    whose discretisation error (:func:`walk_error`) is within :data:`TOL`, from ``sol`` read on it, with the
    Jacobian factorisation there; ``(None, None)`` where none is.

    Why a mesh coarser than ``solve_bvp``'s at 1e-8 is as accurate for the comparison: ``solve_bvp`` sizes
    its mesh by its rms residual test on the cubic spline between nodes (third order in the spacing: 400-1200
    nodes at 1e-8 on n = 32's grids), while the nodal states and ``N1`` are fourth order, far more accurate,
    and the comparison reads ``N1`` and ``theta`` only (the verdict, the branch check).  Measured on the
    300-point Grip I line at n = 32 against the 1e-8 solve: its mesh thinned to every 4th node leaves
    1.4e-9..6e-9 in ``N1`` (relative), every 8th 2e-8..9e-8 (x16 per doubling of the spacing), the 1e-6
    solve's mesh (82-307 nodes) 8e-11..4e-9; the Richardson estimate of :func:`walk_error` matched each within
    a factor 1.5.  ``TOL`` (1e-8) is 100x inside the 1e-6 at which two 1e-8 solves of one equilibrium are
    taken as equal (``tests/test_sweep_stream.py``) and 6e4x inside the chain's own discretisation error at
    n = 32 (~6e-4), what the reference is compared with."""
    from simgrip.reference.bvp import mesh_bvp

    raw = sol._raw
    for x in meshes:
        if x.size < WALK_MIN_NODES or x.size > _WARM_NODES:
            continue
        same = x.size == raw.x.size and np.array_equal(x, raw.x)
        y = raw.y if same else raw.sol(x)
        r, factor = mesh_bvp(raw.prob, x, y, raw.p if raw.prob.constrained else None, TOL)
        if r is not None and walk_error(r) <= TOL:
            return r, factor
    return None, None


def walk_mesh(sol):
    """``(x, factor)``: the mesh a walk from the :data:`TOL` reference ``sol`` (a cold solve) solves on, and
    the Jacobian factorisation there: ``sol``'s mesh thinned to every ``f``-th node (its node density kept),
    ``f`` in :data:`WALK_THINNING`, the first accurate enough (:func:`on_sized_mesh`); ``(None, None)``
    where none is (the walk then runs on ``solve_bvp``'s meshes, as a cold solve refines them)."""
    raw = sol._raw
    r, factor = on_sized_mesh(sol, (raw.x[_thinned(raw.x, f)] for f in WALK_THINNING))
    return (None, None) if r is None else (r.x, factor)


def sized_start(point):
    """``(reference, factor)`` of the first point of a walked segment: its cold path at ``TOL_MID`` (the cold
    solve's own steps but the final polish, which is Newton from a 1e-6 solution and cannot leave its
    equilibrium: the same branch, see :meth:`_Segment.end_checked`), finished on that solve's mesh, or that
    mesh doubled, the first within :data:`TOL` (:func:`on_sized_mesh`: the polish's accuracy at ~1/4 of its
    cost); ``(None, None)`` where either step fails (the caller solves the point cold).  As for the walk's end
    (:meth:`_Segment.end_checked`), the one difference from the full cold solve: where its polish would fail
    (met only on hostile stiff inputs) and send it to its next strategy, this keeps the 1e-6 solve's branch."""
    from simgrip.reference import elastica
    from simgrip.reference.bvp import TOL_MID

    key = problem_key(point)
    kept = _AHEAD.get(key, _MISSING)  # one lookup: another thread may drop the entry meanwhile
    if kept is not _MISSING:  # this process solved it as the previous segment's check ahead: the same solve
        if kept is None:
            return None, None
        mid = _repackaged(point, kept)
    else:
        try:
            mid = cold(point, TOL_MID)
        except Exception:  # noqa: BLE001 - the full cold solve decides (and records the failure)
            return None, None
    x = mid._raw.x
    r, factor = on_sized_mesh(mid, (x, _doubled(x), _doubled(_doubled(x))))
    if r is None:
        return None, None
    return elastica.ElasticaSolution.from_bvp(point.grip, point.params(), r), factor


def walk_error(sol) -> float:
    """The discretisation error of a reference on its own mesh (an ``ElasticaSolution`` or its
    ``BvpSolution``), estimated by Richardson: its problem solved on every other node of its mesh from its
    nodal values, the gap (:func:`_gap`: ``N1`` relative to ``max(|N1|, 1)``, ``theta`` in rad) over ``2^4 - 1`` (fourth order at
    the nodes, as measured, see :func:`on_sized_mesh`); ``inf`` where that does not converge."""
    from simgrip.reference.bvp import mesh_bvp

    raw = getattr(sol, "_raw", sol)
    idx = _thinned(raw.x, 2)
    r, _ = mesh_bvp(raw.prob, raw.x[idx], raw.y[:, idx], raw.p if raw.prob.constrained else None, TOL)
    return np.inf if r is None else _gap(r, raw, idx) / 15.0


def _same_layout(Q, P) -> bool:
    """Whether a solution of ``Q`` is a start for ``P`` as it is: the same states (one or two segments, the
    same contact ``gamma``) and parameters."""
    return Q.two_seg == P.two_seg and Q.constrained == P.constrained and (not P.two_seg or Q.gamma == P.gamma)


def theta_gap(a, b) -> float:
    """Largest difference of ``theta`` between two references on the solver's branch-jump grid [rad]."""
    from simgrip.reference.continuation import _JUMP_GRID

    return float(np.max(np.abs(a._raw.states(_JUMP_GRID)[0] - b._raw.states(_JUMP_GRID)[0])))


def problem_key(point) -> tuple:
    """What ``point``'s BVP depends on: the grip, ``kappa``, ``D``, ``M``, ``b`` and (Grip III) ``gamma``; not
    ``mu`` (friction only enters the verdict, :meth:`~simgrip.reference.elastica.ElasticaSolution.from_bvp`)."""
    return (point.grip, point.kappa, point.D, point.M, point.b, point.gamma if point.grip == "III" else None)


def _repackaged(point, raw):
    """The BVP solution ``raw`` of ``point``'s problem as ``point``'s reference (its own ``mu`` in the verdict)."""
    return Reference(point.grip, point.params(), raw)


def _message(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}".replace("\n", " ")


class _Segment:
    """The bookkeeping of :func:`segment_references` (one segment, one call)."""

    def __init__(self, points):
        self.points = points
        self.sol = [None] * len(points)  # the kept reference of each point
        self.error = [""] * len(points)  # its cold solve's failure
        self.warning = [""] * len(points)
        self.seconds = [0.0] * len(points)  # every solve charged to the point it was for
        self.colds = {}  # problem_key -> (raw BVP solution or None, error): the segment's cold solves

    def cold(self, k: int) -> None:
        """Solve point ``k`` cold, or take the cold solve of an identical problem (:func:`problem_key`) in
        this segment: a cold solve is a deterministic function of the problem, so both are the same."""
        t = time.perf_counter()
        point, key = self.points[k], problem_key(self.points[k])
        if key in self.colds:
            raw, self.error[k] = self.colds[key]
            self.sol[k] = None if raw is None else _repackaged(point, raw)
        else:
            try:
                self.sol[k] = cold(point)
            except Exception as exc:  # noqa: BLE001 - ElasticaError, ValueError, ...: recorded with the point
                self.sol[k], self.error[k] = None, _message(exc)
            self.colds[key] = (None if self.sol[k] is None else self.sol[k]._raw, self.error[k])
        self.seconds[k] += time.perf_counter() - t

    def start(self):
        """Point 0 of a walked segment by :func:`sized_start`; returns the walk's ``(mesh, factor)``, or ``None``
        (nothing kept: point 0 is then solved cold).  A segment that is one BVP (a line along ``mu``) walks
        nothing: its point 0 is solved cold, as every point of the line then is."""
        if all(problem_key(p) == problem_key(self.points[0]) for p in self.points[1:]):
            return None
        t = time.perf_counter()
        sol, factor = sized_start(self.points[0])
        self.seconds[0] += time.perf_counter() - t
        if sol is None:
            return None
        self.sol[0] = sol
        return sol._raw.x, factor

    def walk(self, lo: int, hi: int, sized=None) -> dict:
        """Warm solves of ``lo+1..hi``, each from the previous (from the kept ``lo``; from the second on with
        the predictor of the ones before it); ``None`` once one fails.  On the walk's mesh
        (:func:`walk_mesh`) where one is found and the walk's end meets its error estimate
        (:func:`walk_error`), else on the neighbours' ``solve_bvp`` meshes.  ``sized``: ``(x, factor)``, the
        mesh ``lo``'s reference was solved on (:func:`sized_start`), else :func:`walk_mesh` finds one."""
        if sized is not None:
            mesh, factor = sized
        else:
            t = time.perf_counter()
            mesh, factor = (None, None) if self.sol[lo] is None else walk_mesh(self.sol[lo])
            if lo + 1 <= hi:
                self.seconds[lo + 1] += time.perf_counter() - t
        self.newton = {} if mesh is None else {"mesh": mesh, "factor": factor}
        out = self._walk(lo, hi, self.newton)
        end = out.get(hi)
        if mesh is not None and end is not None and end._raw.x is mesh:
            t = time.perf_counter()
            ok = walk_error(end) <= TOL
            self.seconds[hi] += time.perf_counter() - t
            if not ok:
                self.newton = {}
                out = self._walk(lo, hi, self.newton)
        return out

    def ahead_checked(self, last: int, walk: dict) -> bool:
        """Keep the whole walk ``1..last`` when one more warm step, to the point after the segment on its line
        (:attr:`~simgrip.sweep.grid.SweepPoint.after`), arrives on that point's cold branch (its cold path at
        ``TOL_MID``, as :meth:`end_checked`); ``False`` (nothing kept) otherwise, or where the segment ends its
        line.  That cold path is the next segment's start (:func:`sized_start`) and is kept for it
        (:data:`_AHEAD`): a segment run next in this process does not solve it again.

        What it changes against :meth:`end_checked`: the walk's verified ends are the segment's first point
        and the next segment's first (33 points apart) instead of the segment's last (32), so the check of the
        segment's last point is saved (its cold path is one of two per segment).  Where the check ahead fails,
        the caller checks the last point as before (every cold solve, bisection and warning as without it).
        Assumed, as between any walk's verified ends: the cold branch does not leave and come back between
        them; a cold branch left at the segment's last point alone, back at the next point, is not seen."""
        from dataclasses import replace

        from simgrip.reference.bvp import TOL_MID

        point = self.points[last]
        if point.after is None or any(walk[k] is None for k in range(1, last + 1)):
            return False
        axis, value = point.after
        nxt = replace(point, index=point.index + 1, after=None, **{axis: value})
        key = problem_key(nxt)
        if key == problem_key(point):
            return False
        t = time.perf_counter()
        steps = [self.sol[0]] + [walk[k] for k in range(1, last + 1)]
        try:
            ext = warm(nxt, steps[-1], tuple(reversed(steps[-4:-1])), self.newton)
        except Exception:  # noqa: BLE001 - a warm step that cannot: the last point is checked instead
            ext = None
        raw = _AHEAD.get(key, _MISSING)
        if raw is _MISSING:
            try:
                raw = cold(nxt, TOL_MID)._raw
            except Exception:  # noqa: BLE001 - the next segment's cold solve decides (and records the failure)
                raw = None
            _keep_ahead(key, raw)
        self.seconds[last] += time.perf_counter() - t
        if ext is None or raw is None or theta_gap(ext, _repackaged(nxt, raw)) > SAME_BRANCH_RAD:
            return False
        for k in range(1, last + 1):
            self.sol[k] = walk[k]
        return True

    def _walk(self, lo: int, hi: int, newton: dict) -> dict:
        out, prev, before = {}, self.sol[lo], ()
        for k in range(lo + 1, hi + 1):
            s = None
            if prev is not None and problem_key(self.points[k]) == problem_key(self.points[k - 1]):
                s = _repackaged(self.points[k], prev._raw)  # the same BVP (a mu axis): the same solution
            elif prev is not None:
                t = time.perf_counter()
                try:
                    s = warm(self.points[k], prev, before, newton)
                except Exception:  # noqa: BLE001 - a warm start that cannot: the cold solve decides
                    s = None
                self.seconds[k] += time.perf_counter() - t
            out[k], before, prev = s, (prev,) + before[:2], s
        return out

    def end_checked(self, last: int, walk: dict) -> bool:
        """Keep the whole walk, ``last`` included, when it arrives on the branch of ``last``'s cold path
        solved without its final polish (at ``TOL_MID``, ~0.45x a full cold solve: the polish from 1e-6 to
        1e-8 refines the mesh twice); ``False`` (nothing kept) otherwise, and the full cold solve decides.

        Why that is the cold solve's check: :func:`~simgrip.reference.continuation.cold_start` at ``TOL_MID``
        takes exactly the steps it takes at 1e-8 but the last (the polish, Newton runs from a 1e-6 solution,
        which cannot leave its equilibrium: the others are >= 0.1 rad away), so its branch is the cold
        solve's; a 1e-6 and a 1e-8 solution of one equilibrium differ by ~1e-6 rad, far inside
        :data:`SAME_BRANCH_RAD`.  The one difference: a polish that fails (its mesh past the node limit, met
        only on hostile stiff inputs) sends the cold solve to its next strategy; here the walk, converged at
        1e-8 on that branch, is kept."""
        from simgrip.reference.bvp import TOL_MID

        if any(walk[k] is None for k in range(1, last + 1)):
            return False
        key = problem_key(self.points[last])
        t = time.perf_counter()
        if key in self.colds:
            raw = self.colds[key][0]
            check = None if raw is None else _repackaged(self.points[last], raw)
        else:
            try:
                check = cold(self.points[last], TOL_MID)
            except Exception:  # noqa: BLE001 - the full cold solve decides (and records the failure)
                check = None
        self.seconds[last] += time.perf_counter() - t
        if check is None or theta_gap(walk[last], check) > SAME_BRANCH_RAD:
            return False
        for k in range(1, last + 1):
            self.sol[k] = walk[k]
        return True

    def same(self, walked, k: int) -> bool:
        return walked is not None and self.sol[k] is not None and theta_gap(walked, self.sol[k]) <= SAME_BRANCH_RAD

    def settle(self, lo: int, hi: int, walk: dict) -> None:
        """Keep or replace the interior of ``lo..hi`` (both ends kept cold); ``walk`` from ``lo``."""
        if hi - lo <= 1:
            return
        if self.same(walk[hi], hi) and all(walk[k] is not None for k in range(lo + 1, hi)):
            for k in range(lo + 1, hi):
                self.sol[k] = walk[k]
            return
        mid = (lo + hi) // 2
        self.cold(mid)
        if walk[mid] is not None and not self.same(walk[mid], mid):
            self.warning[mid] = (f"the warm-started BVP reached another branch (theta "
                                 + (f"{theta_gap(walk[mid], self.sol[mid]):.3g} rad from the cold solve"
                                    if self.sol[mid] is not None else "where the cold solve fails")
                                 + "): solved cold")
        self.settle(lo, mid, walk)
        self.settle(mid, hi, self.walk(mid, hi))


#: The checks ahead of the last segments (:meth:`_Segment.ahead_checked`: ``problem_key -> raw TOL_MID cold
#: path, or None where it failed``), newest last: the start of the next segment (:func:`sized_start`) where it
#: runs in the same process.  A cold path is a deterministic function of its problem, so a start taken from
#: here is the one solved again: the references do not depend on which process ran which segment.
_AHEAD: dict = {}
#: Most checks kept (a sweep's segments run in line order; a few for interleaved callers), ~10-50 kB each.
_AHEAD_KEPT = 4
#: Guards :data:`_AHEAD`'s updates (a Dask worker with several threads runs segments side by side); reads are
#: single ``dict.get`` calls, atomic under the interpreter's lock.
_AHEAD_LOCK = threading.Lock()
_MISSING = object()


def _keep_ahead(key, raw) -> None:
    """Keep the check ahead ``raw`` of ``key`` in :data:`_AHEAD` (bounded: the oldest dropped)."""
    with _AHEAD_LOCK:
        _AHEAD.pop(key, None)
        _AHEAD[key] = raw
        while len(_AHEAD) > _AHEAD_KEPT:
            _AHEAD.pop(next(iter(_AHEAD)))


def segment_references(points) -> list[tuple]:
    """``(solution or None, error message, warning, seconds)`` of each of ``points`` (one segment, in order),
    each solution that of the point's cold solve to the solver's tolerance (see the module docstring)."""
    points = list(points)
    if not points:
        return []
    seg = _Segment(points)
    last = len(points) - 1
    sized = seg.start() if last > 0 else None
    if sized is None:
        seg.cold(0)
    if last > 0:
        walk = seg.walk(0, last, sized)
        if sized is not None and seg.ahead_checked(last, walk):
            return list(zip(seg.sol, seg.error, seg.warning, seg.seconds))
        if not seg.end_checked(last, walk):
            seg.cold(last)
            seg.settle(0, last, walk)
    return list(zip(seg.sol, seg.error, seg.warning, seg.seconds))
