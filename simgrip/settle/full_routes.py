"""The routes of the full-contact static settle: where :class:`~simgrip.settle.full_newton.FullNewton` starts,
what it solves, and when it hands over to the dynamics.

1. **Where point contact applies** (the chain's point-contact equilibrium,
   :func:`~simgrip.reference.hinge_chain.solve_chain`, touches the box with its tip alone; the free chain,
   :func:`~simgrip.reference.hinge_chain.chain_angles`, touches nothing): start there -- the box at the depth
   the dynamics' frictionless closing leaves the tip at (the chain with ``M = 0``), or at ``box_depth`` -- and
   polish in the full scene (:meth:`~simgrip.settle.full_newton.FullNewton.solve`, then the bordered form if
   the polish does not converge).  It stands when MuJoCo's collision detection finds no contact but the tip's:
   the constrained problem's solution with the extra constraints inactive.  A tip force outside the friction
   cone (the chain's by :data:`FN_CONE_PRECHECK`, then MuJoCo's by :data:`FN_CONE_MARGIN`) drops the box: the
   finger alone.
2. **Past the onset**, Grips I/II grasped at ``box_depth`` with every other contact frictionless (the
   free-boundary problem of :mod:`simgrip.reference.free_boundary`): continuation in the rest curvature from
   the point-contact state at :data:`FN_START` rad of total rest rotation, :data:`FN_STAGE` rad per stage,
   each stage the bordered Newton (:meth:`~simgrip.settle.full_newton.FullNewton.solve_kkt`).  Where the tip's
   friction cannot carry the box at ``box_depth``, the box slides quasi-statically (:func:`_slide`) to the first
   depth where it can (held there; the theory's :func:`~simgrip.reference.hold_full.slip_depth`: Grip I kappa
   -10, mu_s 0.7088 at n = 32: 0.3956 against the theory's 0.3904, inside the hold band of
   :mod:`tests.test_hold_full`).  A box that finds none drops and leaves the finger alone to the dynamics,
   from the held shape (``settled = False``).

Not routed (``(None, None)``: the dynamics settles): two fingers; friction at several contacts (``box_depth``
None or ``extra_friction``: the load's split between sticking contacts depends on the path); the free rod past
its self-contact onset (the turns of a spiral lie along each other, where MuJoCo's capsule--capsule collision
switches between one and two contacts with the angle between them: its rest balance jumps there; measured: the
bordered solve converged, MuJoCo's balance at its state 3 rho g l^2 off, free rod kappa -9, n = 32).
"""

from __future__ import annotations

import numpy as np

from simgrip.settle.full_newton import FN_ITERS, FullNewton, NewtonResult

__all__ = ["FN_CONE_MARGIN", "FN_CONE_PRECHECK", "FN_SLIDE_STEP", "FN_STAGE", "FN_START", "FN_TOL_SHARE", "newton_full"]

#: Continuation: total rest rotation added per stage [rad].
FN_STAGE = 1.0
#: Continuation: the total rest rotation [rad] of its first stage, each tried in turn where the chain's start
#: there touches the box elsewhere than at the tip (inside the point-contact range of each problem: Grip I
#: [-8.2, 0], Grip II [0, 5.5]; near its end first: Grip I kappa -10 at n = 32 took 0.23 CPU s from 7, 0.12 from
#: 7.5, the same state).
FN_START = {"I": (7.5, 5.0), "II": (4.0, 2.5), "free": (4.0,)}
#: A tip force within this fraction of the friction cone's edge is left to the dynamics (its creep decides).
FN_CONE_MARGIN = 1e-3
#: The point-contact chain's tip force outside its friction cone by more than this fraction drops the box at
#: once (MuJoCo's surface contact moves N by ~r_tip / l relative, 2e-3: far inside it).
FN_CONE_PRECHECK = 0.05
#: The quasi-static slide (:func:`_slide`): its march in the grasp depth [over l] (as the theory's
#: :func:`~simgrip.reference.hold_full.slip_depth`), the depth [over l] to which its re-stick is found, and the
#: depths [over l] past which the box has slid off the tip (the theory's valid range).
FN_SLIDE_STEP = 0.01
FN_SLIDE_TOL = 1e-6
FN_SLIDE_RANGE = (0.05, 1.95)
#: The solve's own stopping residual over the settle's tolerance (MuJoCo's judge then checks the settle's).
FN_TOL_SHARE = 1e-2
#: Balance residual (over rho g l, rho g l^2) of the continuation's intermediate stages (each only starts the
#: next; the last is solved to the settle's tolerance).
FN_STAGE_TOL = 1e-6
#: Iterations of the point route's polish before the bordered form takes over (chord steps, one evaluation each:
#: ~10 from the chain's start, contracting ~0.13 a step at Grip I kappa -6, n = 32).
FN_POLISH_ITERS = 30
#: Fresh Jacobians the point route's polish may take (1-2 from the chain's start; more means contacts the chain
#: does not have: the bordered form's, or another route's).
FN_POLISH_JACOBIANS = 3


def newton_full(scene, tol: float, budget: int) -> tuple[NewtonResult | None, str | None]:
    """The full-contact rest state of ``scene`` by Newton (module docstring): ``(result, None)``, or ``(None,
    why)`` where it was tried and failed, or ``(None, None)`` where it does not apply (the caller's dynamics then
    settles).  The model must be configured as the dynamics configures it (contact softness; friction off); the
    workpiece's geoms are parked (no contact) when the box is dropped (the caller restores them); ``scene.data``
    is left untouched.  ``budget`` bounds the Newton iterations; ``tol`` is the settle's (MuJoCo's judge is the
    caller's)."""
    sc = scene
    if sc.fingers != 1 or tuple(sc.workpiece_joints) not in ((), ("z",)):
        return None, None
    held = sc.has_workpiece
    if held and sc.grip not in ("I", "II"):
        return None, None
    m = sc.model
    rest = np.array(m.qpos_spring[sc.joint_qpos[0]])
    run = FullNewton(sc)
    q0 = np.array(sc.data.qpos)
    try:
        if held:
            res, why = _held(run, q0, rest, FN_TOL_SHARE * tol, budget)
            if res is None or res.held:
                return res, why
            q0 = res.qpos  # dropped: the finger alone, the box parked where it was
            for g in run.wgeoms:
                m.geom_contype[g] = m.geom_conaffinity[g] = 0
        alone, why = _alone(run, q0, rest, FN_TOL_SHARE * tol, budget)
        if alone is not None:
            alone.held = False
            return alone, None
        if held:  # dropped, the finger alone past the onset: the caller's dynamics settles it from here
            res.settled = False
            return res, None
        return None, why
    finally:
        m.qpos_spring[sc.joint_qpos[0]] = rest


def _routes(run: FullNewton, rest):
    """``[(curvature factor, route)]``: the point-contact start at full curvature, then (past each rotation of
    :data:`FN_START`) the continuation's first stages."""
    total = max(abs(float(np.sum(rest))), 1e-300)
    starts = [r / total for r in FN_START.get(run.sc.grip, ()) if r < total]
    return [(1.0, "point")] + [(t, "continuation") for t in starts]


def _held(run: FullNewton, q0, rest, tol: float, budget: int):
    """Grips I/II with the box held by the tip's friction (:func:`newton_full`)."""
    from simgrip.reference import DiscreteError, hinge_chain
    from simgrip.settle.chain_model import gravity_factor
    from simgrip.sim.full_contact import grasp_depth

    sc = run.sc
    p, grav = sc.params, gravity_factor(sc)
    tight = p.replace(b=p.b - 2e-6)  # the tip a hair inside the face (as the point-contact start)
    tips = {run.tip, int(sc.index.link_geom[0][-1])}
    why = None
    for t, route in _routes(run, rest):
        # friction at several contacts splits the load by the path (indeterminate): the tip's contacts alone, or
        # the depth's problem with every other contact frictionless
        tip_only = sc.box_depth is None or sc.extra_friction
        if route != "point" and tip_only:
            return None, why
        prof = sc.profile.scaled(t)
        q = q0.copy()
        try:
            ch = hinge_chain.solve_chain(sc.grip, tight, prof, sc.n, gravity=grav, stability="none")
            if not ch.success:
                continue
            q[run.hinges] = ch.joint_angles
            if route == "point" and p.M > p.mu_s * ch.N1 * (1.0 + FN_CONE_PRECHECK):
                # the tip's friction cannot carry the box even where point contact applies: it slides off
                return NewtonResult(q0.copy(), False, -p.M, run.iterations, run.evaluations, route), None
            depth = sc.box_depth
            if depth is None:  # the dynamics' frictionless closing leaves the tip where the box was built
                c0 = hinge_chain.solve_chain(sc.grip, tight.replace(M=0.0), prof, sc.n, gravity=grav,
                                             guess=ch.link_angles, stability="none")
                qc = q0.copy()
                qc[run.hinges] = c0.joint_angles
                depth = grasp_depth(sc, qc)
        except (DiscreteError, ValueError):
            continue
        qb = q.copy()
        qb[run.wz[0]] = 0.0
        q[run.wz[0]] = (1.0 if sc.grip == "I" else -1.0) * (depth - grasp_depth(sc, qb)) * sc.length
        if not _only(run.contacts(q), tips, run.wgeoms):
            continue  # the point-contact start already touches elsewhere (past the onset)
        free = np.concatenate([run.hinges, run.wz])
        q, lam, why = _stages(run, q, free, rest, t, tol, budget, -p.M, depth, route == "point", not tip_only,
                              (lambda pairs: _only(pairs, tips, run.wgeoms)) if tip_only else None)
        if q is None:
            continue
        if tip_only and not _only(run.contacts(q), tips, run.wgeoms):
            why = why or "more contacts than the tip's"
            continue
        N = run.tip_normal(q)
        margin = abs(abs(lam) - p.mu_s * N)
        if margin <= FN_CONE_MARGIN * p.mu_s * N:
            return None, f"tip friction {abs(lam):.6g} at the cone's edge mu N = {p.mu_s * N:.6g}"
        if abs(lam) >= p.mu_s * N and not tip_only:
            slid = _slide(run, q, free, lam, depth, tol, budget, p.mu_s)
            if slid is not None:  # the tip slid and stuck again, the box at another depth: held there
                q, lam = slid
                return NewtonResult(q, True, lam, run.iterations, run.evaluations, route + "+slide"), None
        return NewtonResult(q, abs(lam) < p.mu_s * N, lam, run.iterations, run.evaluations, route), None
    return None, why


def _slide(run: FullNewton, q, free, lam, depth: float, tol: float, budget: int, mu: float):
    """The quasi-static slide of a box whose tip cannot stick at ``depth``: ``(q, lam)`` where it sticks again,
    or ``None`` where it does not within the box (it falls: the caller drops it).

    The box slides down relative to the tip (Grip I's depth below the top edge shrinks, Grip II's above the
    bottom edge grows) through rests at each depth with every contact but the tip's frictionless (the
    free-boundary problem at that depth); it stops at the first depth where the tip's friction demand falls
    inside the cone, ``|lam| <= mu N``.  Marched in :data:`FN_SLIDE_STEP` from ``depth`` (each rest warm from
    the last), the crossing then found by ``brentq`` to :data:`FN_SLIDE_TOL` on ``|lam| - mu N (1 -
    2 FN_CONE_MARGIN)`` (the state returned is inside the cone by twice the margin the judge leaves to the
    dynamics: ~5e-4 l of depth past the crossing at Grip I kappa -10).  The theory's counterpart is
    :func:`simgrip.reference.hold_full.slip_depth`."""
    from scipy.optimize import brentq

    sign = -1.0 if run.sc.grip == "I" else 1.0
    near = {}  # depth -> (q, lam): warm starts

    def at(d):
        d0 = min(near, key=lambda x: abs(x - d))
        left = budget - run.iterations
        if left <= 0:
            raise _SlideLost(f"Newton iteration budget {budget} spent")
        ok, q1, l1 = run.solve_kkt(near[d0][0], free, tol, lam=near[d0][1], target=d, max_iter=min(FN_ITERS, left),
                                   polish=True)
        if not ok:
            raise _SlideLost(f"no rest at depth {d:.6g}")
        near[d] = (q1, l1)
        return abs(l1) - mu * run.tip_normal(q1) * (1.0 - 2.0 * FN_CONE_MARGIN)

    near[depth] = (q, lam)
    a, d = depth, depth
    try:
        while True:
            d = a + sign * FN_SLIDE_STEP
            if not FN_SLIDE_RANGE[0] < d < FN_SLIDE_RANGE[1]:
                return None
            if at(d) < 0.0:
                break
            a = d
        root = brentq(at, min(a, d), max(a, d), xtol=FN_SLIDE_TOL)
        # the side of the root inside the cone
        for x in (root, root + sign * FN_SLIDE_TOL):
            if at(x) < 0.0:
                return near[x]
        return near[d]
    except _SlideLost:
        return None


class _SlideLost(Exception):
    """The slide's march found no rest (the box falls)."""


def _alone(run: FullNewton, q0, rest, tol: float, budget: int):
    """The finger alone (free rod, or a dropped box parked), frictionless with itself (:func:`newton_full`)."""
    from simgrip.reference import DiscreteError, hinge_chain
    from simgrip.settle.chain_model import gravity_factor

    sc = run.sc
    why = None
    # the point route only: past the onset the turns of a spiral lie along each other, where MuJoCo's
    # capsule-capsule collision switches between one and two contacts with the angle between them (its rest
    # balance jumps there; measured: the bordered solve converges, MuJoCo's balance at its state is 3 rho g l^2
    # off, free rod kappa -9, n = 32), so the dynamics settles those
    for t, route in _routes(run, rest)[:1]:
        q = q0.copy()
        try:
            phi = hinge_chain.chain_angles("free", sc.params, sc.profile.scaled(t), sc.n, gravity=gravity_factor(sc))
        except (DiscreteError, ValueError):
            continue
        q[run.hinges] = np.diff(phi, prepend=0.0)
        if run.contacts(q):
            continue  # the free chain touches itself: past the onset
        q, _, why = _stages(run, q, run.hinges, rest, t, tol, budget, 0.0, None, True, False, lambda pairs: not pairs)
        if q is None:
            continue
        if route == "point" and run.contacts(q):
            continue
        return NewtonResult(q, False, 0.0, run.iterations, run.evaluations, route), None
    return None, why


def _only(pairs, tips, wgeoms) -> bool:
    """Every contact in ``pairs`` is a tip geom's with the workpiece."""
    return all({g1, g2} & tips and {g1, g2} & wgeoms for g1, g2 in pairs)


def _stages(run: FullNewton, q, free, rest, t: float, tol: float, budget: int, lam: float, depth, polish_first,
            bordered=True, allowed=None):
    """Newton at the curvature factors ``t, t + FN_STAGE / |total|, ..., 1``: ``(q, lam, None)`` or ``(None,
    None, why)``; ``polish_first``: try MuJoCo's own balance (:data:`FN_POLISH_ITERS`) before the bordered form;
    ``bordered`` False: the polish alone (a point route whose answer must keep the tip's contact alone: where the
    polish from the chain's start fails, more contacts are active, and the route does not apply: ``(None, None,
    None)``); ``allowed(pairs)``: the polish stops (fails) once a step leaves a contact it does not allow."""
    sc, m = run.sc, run.m
    total = max(abs(float(np.sum(rest))), 1e-300)
    s = t
    prev = None  # the last stage's (s, q, lam): the secant predictor
    while True:
        m.qpos_spring[sc.joint_qpos[0]] = rest * s
        left = budget - run.iterations
        if left <= 0:
            return None, None, f"Newton iteration budget {budget} spent"
        last = s >= 1.0
        ok = False
        if polish_first:  # the point route's start is the chain's equilibrium: the polish alone, first
            stop = None if allowed is None else (lambda pairs: not allowed(pairs))
            ok, qp, lp = run.solve(q, free, tol, lam=lam, target=depth, max_iter=min(FN_POLISH_ITERS, left),
                                   stop=stop, max_jacobians=FN_POLISH_JACOBIANS)
            if ok:
                q, lam = qp, lp
        if not ok and not bordered:
            return None, None, None
        if not ok:  # intermediate stages only lead to the last: solved to FN_STAGE_TOL, not polished
            ok, q, lam = run.solve_kkt(q, free, tol if last else max(tol, FN_STAGE_TOL), lam=lam, target=depth,
                                       max_iter=min(FN_ITERS, left), polish=last)
        if not ok:
            return None, None, f"Newton did not converge at {s:.4g} of the rest curvature"
        if last:
            return q, lam, None
        s_next = min(1.0, s + FN_STAGE / total)
        if prev is not None:  # secant predictor along the path, guarded like a step
            c = (s_next - s) / (s - prev[0])
            dq = c * (q - prev[1])
            a = run.guarded(q, dq)
            prev, q, lam = (s, q, lam), q + a * dq, lam + a * c * (lam - prev[2])
        else:
            prev = (s, q, lam)
        s = s_next
