"""The full-contact settle as a static solve: Newton on MuJoCo's own rest balance in the full scene.

The guarded over-damped dynamics (:mod:`.full_contact`) flows to rest; :class:`FullNewton` solves for the rest
state instead, and MuJoCo judges it as it judges the dynamics' (:func:`.full_contact.settle_full`).  Unknowns:
the free dofs (hinge angles; the box's ``z`` once released) and, for a held box, the tip's friction force
``lambda``.  Equations::

    r(q) + lambda Q(q) = 0        r: MuJoCo's rest balance (mj_inverse at qvel = qacc = 0, every contact the
                                     broad phase finds, frictionless); Q: the tip friction's generalised force
                                     along z at MuJoCo's tip contact point (tip minus box Jacobian)
    depth(q) - depth* = 0         the grasp depth (:func:`~simgrip.settle.full_contact.grasp_depth`): the box
                                     hangs on the sticking tip

MuJoCo's velocity friction is zero at rest, so the tip's sticking is the constraint row and its multiplier
``lambda``; every other contact is frictionless here.  Two forms of the same equations:

* :meth:`FullNewton.solve`: MuJoCo's soft contacts as they are (``K_c p``, the contact set MuJoCo's collision
  finds at each evaluation).  Exact, but the contacts' stiffness (``K_c ~ 1e5..1e6 rho g``) times the
  geometry's curvature leaves it a quadratic basin of ``~1e-6 l``: the polish.
* :meth:`FullNewton.solve_kkt`: the active set bordered by the contacts as compliant constraints (each pair's
  normal force ``N`` an unknown, its row ``dist + N / K = 0``, ``K`` read back from MuJoCo), as
  :mod:`~simgrip.settle.chain_newton` borders its chain; full steps from ``~1e-1 l`` away.  Pairs join when
  MuJoCo finds them overlapping and leave when their force turns negative; the polish finishes.

The Jacobian is MuJoCo's forces differenced (:data:`FN_FD_STEP`; ``n + 2`` ``mj_inverse`` calls: measured 1.7
ms at n = 32, 41 ms at n = 128 on the shared development machine), kept as a chord while it contracts
(:data:`FN_CHORD`).  Steps are guarded pairwise (:meth:`FullNewton.step_bound`): two link capsules (or a link and
the box) approach by at most their gap plus half a capsule radius in one step, so no link passes through another
between two iterates (MuJoCo sees a contact only once geoms overlap).  The routes that use it (the point-contact
start, the continuation past the onset) are :mod:`.full_routes`'.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from simgrip.settle.full_guard import GuardedSteps
from simgrip.settle.statics import dof_scales

__all__ = ["FN_CHORD", "FN_FD_STEP", "FN_ITERS", "FN_SAMPLES", "FullNewton", "NewtonResult"]

#: Forward-difference step of the Jacobian (rad; times l for a slide).  The contacts' stiffness ``K_c ~ 1e6``
#: (over rho g) times the curvature of a distance (~1/l) makes the truncation error ``~1e-7`` relative.
FN_FD_STEP = 1e-7
#: Newton iterations of one solve (one continuation stage; the guarded steps of a contact that slides count).
FN_ITERS = 200
#: Samples per link of the step guard (:meth:`FullNewton.step_bound`).
FN_SAMPLES = 4
#: The bordered solve hands over to the polish on MuJoCo's balance when its line search stalls below this
#: many tolerances (the contact rows' round-off, ~1e-16 l times K, is then all that is left).
FN_STALL = 100.0
#: Passes of the step guard's measurement (:meth:`FullNewton.guarded`).
FN_GUARD_PASSES = 20
#: Chord steps: the Jacobian is kept while a full step shrinks the residual at least this much.
FN_CHORD = 0.25
#: The bordered solve hands a polished state over at this balance residual (over rho g l, rho g l^2): the
#: polish's quadratic basin is ~1e-6 l of position (module docstring), a residual 1e-6 off moves the state
#: ~1e-6 / EI-stiffness, ~1e-6 l at D = 1.
FN_HANDOVER = 1e-6
#: Relative change of a pair's read-back ``K`` that sends the bordered solve round again (the polish on
#: MuJoCo's own balance absorbs the rest: N 1e-6 relative off is ~1e-10 l of depth).
FN_KC_RTOL = 1e-6
#: A trial state whose deepest contact exceeds this fraction of the capsule radius is rejected (tunnelled).
FN_DEEP = 0.5


class NewtonResult:
    """What :func:`~simgrip.settle.full_routes.newton_full` found: the state ``qpos``, ``held``, ``lam`` (tip friction over rho g l),
    ``iterations``, ``evaluations`` (``mj_inverse`` calls), ``route`` (``"point"`` or ``"continuation"``) and
    ``settled``."""

    def __init__(self, qpos, held, lam, iterations, evaluations, route):
        self.qpos, self.held, self.lam = qpos, held, lam
        self.iterations, self.evaluations, self.route = iterations, evaluations, route
        #: False: the box was dropped and the finger alone is left to the dynamics, from ``qpos`` (the held
        #: state's shape, the box parked)
        self.settled = True


class FullNewton:
    """Newton on the full scene's rest balance (module docstring); state in its own scratch ``MjData``."""

    def __init__(self, scene):
        m = scene.model
        if m.nq != m.nv or not np.array_equal(m.jnt_qposadr, m.jnt_dofadr):
            raise ValueError("scene: the full-contact Newton needs hinge and slide joints only")
        self.sc, self.m = scene, m
        self.d = mujoco.MjData(m)
        self.fscale = dof_scales(scene)[0]
        self._geo = None  # the step guard's geometry (GuardedSteps: nodes, the workpiece's signed distance)
        self.hinges = np.asarray(scene.joint_dof, dtype=int).ravel()
        self.wz = [int(a) for name, a in zip(scene.workpiece_joints, scene.workpiece_qpos) if name == "z"]
        self.tip = int(scene.index.tip_geom[0]) if scene.grip in ("I", "II") else -1
        self.wgeoms = set(int(g) for g in scene.workpiece_geoms)
        self.evaluations = 0
        self.iterations = 0
        self._far = None  # sample pairs on links that may touch (two apart or more), built on first use
        self._jf = np.zeros((3, m.nv))
        self._jw = np.zeros((3, m.nv))
        self._normal = {}
        self._active = {}  # the bordered solve's last set: {pair: (N over rho g l, K [N/m])}
        self._depth0 = None

    # -- evaluation -------------------------------------------------------------------------------------
    def forces(self, q) -> np.ndarray:
        """MuJoCo's rest balance ``qfrc_applied - qfrc_inverse`` at ``q`` (dimensional, applied 0)."""
        d = self.d
        d.qpos[:] = q
        d.qvel[:] = 0.0
        d.qacc[:] = 0.0
        d.qfrc_applied[:] = 0.0
        mujoco.mj_inverse(self.m, d)
        self.evaluations += 1
        return -np.array(d.qfrc_inverse)

    def friction_column(self) -> np.ndarray:
        """The generalised force of a unit upward (``+z``) friction force on the tip at its contact point with the
        box (MuJoCo's, in the scratch data; the sphere's point facing the box if it does not touch), the box
        taking the opposite, times ``rho g l``."""
        m, d, sc = self.m, self.d, self.sc
        p = None
        for i in range(d.ncon):
            g1, g2 = int(d.contact.geom1[i]), int(d.contact.geom2[i])
            if (g1 == self.tip and g2 in self.wgeoms) or (g2 == self.tip and g1 in self.wgeoms):
                p = np.array(d.contact.pos[i])
                break
        if p is None:
            p = np.array(d.geom_xpos[self.tip])
            p[0] -= sc.mirror[0] * sc.r_tip * sc.length
        mujoco.mj_jac(m, d, self._jf, None, p, int(m.geom_bodyid[self.tip]))
        mujoco.mj_jac(m, d, self._jw, None, p, int(sc.workpiece_body))
        return (self._jf[2] - self._jw[2]) * sc.force_scale

    def deepest(self) -> float:
        """Deepest contact in the scratch data, over the capsule radius."""
        d = self.d
        deep = max((-float(d.contact.dist[i]) for i in range(d.ncon)), default=0.0)
        return deep / (self.sc.r_link * self.sc.length)

    def system(self, q, free, lam, target):
        """``F`` (scaled residual rows of the free dofs, then the depth row) at ``(q, lam)``."""
        r = self.forces(q)
        if target is not None:
            r = r + lam * self.friction_column()
        out = r[free] / self.fscale[free]
        if target is None:
            return out
        return np.append(out, self.depth(q) - target)

    def depth(self, q) -> float:
        """:func:`~simgrip.sim.full_contact.grasp_depth` at ``q`` (the same sums, without its checks: the
        depth row is evaluated at every difference)."""
        if self._depth0 is None:
            from simgrip.sim.full_contact import grasp_depth

            q0 = np.zeros(self.m.nq)
            self._depth0 = grasp_depth(self.sc, q0)  # box at its built height, the finger straight along x
        sc = self.sc
        y = float(np.sum(np.sin(np.cumsum(q[self.hinges])))) / sc.n
        up = 1.0 if sc.grip == "I" else -1.0
        return self._depth0 + up * (float(q[self.wz[0]]) / sc.length - y)

    def jacobian(self, q, free, lam, target, F0) -> np.ndarray:
        """Forward differences of :meth:`system` in the free dofs (and the exact ``lambda`` column)."""
        k = F0.size
        J = np.zeros((k, k))
        scale = np.where(np.isin(free, self.wz), self.sc.length, 1.0)
        for c, j in enumerate(free):
            h = FN_FD_STEP * scale[c]
            qq = q.copy()
            qq[j] += h
            J[:, c] = (self.system(qq, free, lam, target) - F0) / h
        if target is not None:
            self.forces(q)
            col = self.friction_column()
            J[:free.size, -1] = col[free] / self.fscale[free]
        return J

    # -- the guard --------------------------------------------------------------------------------------
    def step_bound(self, q0, q1) -> float:
        """The largest fraction ``<= 1`` of the step ``q0 -> q1`` that keeps every link pair (two apart or more)
        and every link--box pair from approaching by more than its gap plus half a capsule radius.

        Each link is sampled at :data:`FN_SAMPLES` points ``(k + 1/2) / S`` along it: every point of the link lies
        within ``ds / 2S`` of a sample, so samples ``D`` apart bound their links' gap by ``D - ds/S - 2 r`` and a
        sample ``s`` from the box (its exact signed distance) by ``s - ds/2S - r`` (the guard of
        :class:`~simgrip.settle.full_guard.GuardedSteps`, per pair and finer).  A rigid link's points move as the
        affine interpolation of its nodes' moves, so the samples' moves are exact for the step; the fraction
        scales them linearly to first order (the trial is measured again before it is taken)."""
        sc, geo = self.sc, self.geo
        S = FN_SAMPLES
        ds, r = sc.length / sc.n, sc.r_link * sc.length
        # a node moves by at most ds sum |d phi| (each link turns by d phi_k about its start); the box translates
        box = float(np.sum(np.abs(q1[self.wz] - q0[self.wz]))) if self.wz else 0.0
        if ds * float(np.sum(np.abs(np.cumsum(q1[self.hinges] - q0[self.hinges])))) + box <= 0.25 * r:
            return 1.0  # every point moves a quarter radius at most: no pair approaches by more than half of one
        a, b = geo.nodes(q0)[0], geo.nodes(q1)[0]
        t = (np.arange(S) + 0.5) / S
        pa = (a[:-1, None, :] + t[None, :, None] * (a[1:] - a[:-1])[:, None, :]).reshape(-1, 3)
        pb = (b[:-1, None, :] + t[None, :, None] * (b[1:] - b[:-1])[:, None, :]).reshape(-1, 3)
        move = pb - pa
        # the finger's plane (x, z): pairwise distances from two outer differences each (O((S n)^2), no 3-D cube)
        D = np.hypot(np.subtract.outer(pa[:, 0], pa[:, 0]), np.subtract.outer(pa[:, 2], pa[:, 2]))
        rel = np.hypot(np.subtract.outer(move[:, 0], move[:, 0]), np.subtract.outer(move[:, 2], move[:, 2]))
        allow = np.maximum(D - (ds / S + 2.0 * r), 0.0)
        allow += 0.5 * r
        rel[~self.far] = 0.0
        with np.errstate(divide="ignore", invalid="ignore"):
            out = float(np.min(np.where(rel > 0, allow / rel, np.inf)))
        if sc.has_workpiece and self._box_on(q0):
            c0, _ = geo.pose(q0)
            c1, _ = geo.pose(q1)
            s = geo.workpiece_distance(pa, q0)
            relw = np.linalg.norm(move - (c1 - c0)[None, :], axis=-1)
            alloww = 0.5 * r + np.maximum(s - 0.5 * ds / S - r, 0.0)
            with np.errstate(divide="ignore", invalid="ignore"):
                out = min(out, float(np.min(np.where(relw > 0, alloww / relw, np.inf))))
        return min(1.0, out)

    @property
    def geo(self) -> GuardedSteps:
        if self._geo is None:
            self._geo = GuardedSteps(self.sc, None)
        return self._geo

    @property
    def far(self) -> np.ndarray:
        if self._far is None:
            link = np.repeat(np.arange(self.sc.n), FN_SAMPLES)
            self._far = np.abs(link[:, None] - link[None, :]) >= 2
        return self._far

    def guarded(self, q, dq) -> float:
        """The step fraction the guard allows from ``q`` along ``dq``: :meth:`step_bound` measured again at each
        shortened step (a link's motion is not linear in the fraction: a turning chain sweeps ahead of its
        chord) until it allows the whole of it (at most :data:`FN_GUARD_PASSES` passes, each cutting at least
        10 %; the last fraction stands)."""
        alpha = 1.0
        for _ in range(FN_GUARD_PASSES):
            f = self.step_bound(q, q + alpha * dq)
            if f >= 1.0:
                break
            alpha *= 0.9 * f
        return alpha

    def _box_on(self, q) -> bool:
        return any(int(self.m.geom_contype[g]) or int(self.m.geom_conaffinity[g]) for g in self.wgeoms)

    # -- Newton -----------------------------------------------------------------------------------------
    def solve(self, q, free, tol, *, lam=0.0, target=None, max_iter=FN_ITERS, stop=None, max_jacobians=None):
        """Newton from ``q`` in the ``free`` dofs (and ``lam`` with a depth ``target``): ``(ok, q, lam)``.

        Stops when the scaled balance rows are below ``tol`` and the depth row below ``1e-12``; fails (False)
        on a singular system, a line search without descent, ``max_iter`` iterations, more than
        ``max_jacobians`` fresh Jacobians or ``stop(pairs)`` true of the contact pairs after a step."""
        free = np.asarray(free, dtype=int)
        q = np.array(q, dtype=float)
        F = self.system(q, free, lam, target)
        nf = free.size
        J, ratio, jacobians = None, 1.0, 0
        for _ in range(max_iter):
            if not np.all(np.isfinite(F)):
                return False, q, lam
            if float(np.max(np.abs(F[:nf]))) < tol and (target is None or abs(float(F[-1])) < 1e-12):
                return True, q, lam
            self.iterations += 1
            if J is None or ratio > FN_CHORD:  # the last Jacobian again while it contracts fast (chord steps)
                if max_jacobians is not None and jacobians >= max_jacobians:
                    return False, q, lam
                J = self.jacobian(q, free, lam, target, F)
                jacobians += 1
            try:
                step = np.linalg.solve(J, -F)
            except np.linalg.LinAlgError:
                return False, q, lam
            if not np.all(np.isfinite(step)):
                return False, q, lam
            dq = np.zeros_like(q)
            dq[free] = step[:nf]
            dl = float(step[-1]) if target is not None else 0.0
            alpha = self.guarded(q, dq)
            merit = float(np.linalg.norm(F))
            for _ in range(40):
                qt = q + alpha * dq
                lt = lam + alpha * dl
                Ft = self.system(qt, free, lt, target)
                if (np.all(np.isfinite(Ft)) and self.deepest() <= FN_DEEP
                        and float(np.linalg.norm(Ft)) <= (1.0 - 1e-4 * alpha) * merit):
                    break
                alpha *= 0.5
            else:
                if ratio <= FN_CHORD:  # a stale Jacobian: a fresh one before giving up
                    ratio = 1.0
                    continue
                return False, q, lam
            ratio = _chord_ratio(float(np.linalg.norm(Ft)), merit, alpha)
            q, lam, F = qt, lt, Ft
            if stop is not None and stop(self.contact_pairs()):
                return False, q, lam
        return False, q, lam

    def contact_pairs(self) -> list[tuple[int, int]]:
        """The geom pairs in contact in the scratch data (its last evaluation's)."""
        d = self.d
        return [(int(d.contact.geom1[i]), int(d.contact.geom2[i])) for i in range(d.ncon)]

    # -- the bordered form: contacts as compliant constraints ---------------------------------------------
    def touching(self) -> dict:
        """``{(g1, g2): (depth [m], normal force [N])}`` of the pairs MuJoCo's collision finds at the scratch
        data's kinematics (its contact forces need a preceding ``mj_inverse`` with contacts on)."""
        d, m = self.d, self.m
        out = {}
        fc = np.zeros(6)
        for i in range(d.ncon):
            key = (int(d.contact.geom1[i]), int(d.contact.geom2[i]))
            mujoco.mj_contactForce(m, d, i, fc)
            dep, f = out.get(key, (0.0, 0.0))
            out[key] = (max(dep, -float(d.contact.dist[i])), f + float(fc[0]))
        return out

    def pair_terms(self, pairs):
        """Per pair ``(g1, g2)``: signed distance [m] and the generalised force of a unit normal force pushing
        them apart (``nv``), at the scratch data's kinematics (``mj_geomDistance``'s nearest points; the normal
        ``(to - from) / dist`` points from ``g1`` to ``g2`` whether they overlap or not)."""
        m, d, L = self.m, self.d, self.sc.length
        dist = np.zeros(len(pairs))
        G = np.zeros((len(pairs), m.nv))
        ft = np.zeros(6)
        for k, (g1, g2) in enumerate(pairs):
            dist[k] = mujoco.mj_geomDistance(m, d, g1, g2, L, ft)
            v = ft[3:] - ft[:3]
            if abs(dist[k]) > 1e-12 * L:
                self._normal[(g1, g2)] = v / dist[k]
            nv = self._normal.get((g1, g2))
            if nv is None:
                continue
            pt = 0.5 * (ft[:3] + ft[3:])
            mujoco.mj_jac(m, d, self._jf, None, pt, int(m.geom_bodyid[g1]))
            mujoco.mj_jac(m, d, self._jw, None, pt, int(m.geom_bodyid[g2]))
            G[k] = nv @ (self._jw - self._jf)
        return dist, G

    def kkt_system(self, q, free, lam, target, pairs, N, K):
        """The bordered rows: balance with contacts off plus ``N_k G_k`` (scaled), the depth row, and per pair
        ``(dist + N W / K) / l``; also the pairs' ``G`` (for the multipliers' columns)."""
        sc, m = self.sc, self.m
        W, L = sc.force_scale, sc.length
        flags = int(m.opt.disableflags)
        m.opt.disableflags = flags | int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
        try:
            r = self.forces(q)
        finally:
            m.opt.disableflags = flags
        if target is not None:
            r = r + lam * self.friction_column()
        dist, G = self.pair_terms(pairs)
        if len(pairs):
            r = r + (N * W) @ G
        rows = [r[free] / self.fscale[free]]
        if target is not None:
            rows.append([self.depth(q) - target])
        rows.append((dist + N * W / K) / L)
        return np.concatenate(rows), G

    def solve_kkt(self, q, free, tol, *, lam=0.0, target=None, max_iter=FN_ITERS, polish=True):
        """Newton on the bordered form (module docstring) with MuJoCo's contact set, then (``polish``)
        :meth:`solve`'s polish on MuJoCo's own balance: ``(ok, q, lam)``.  The set: the pairs MuJoCo finds
        touching join (after every step), a pair whose force turns negative leaves; each pair's ``K`` is read
        back from MuJoCo's contact force over its depth (:data:`~simgrip.settle.statics.CONTACT_STIFFNESS`
        ``rho g`` until it touches).  With the polish to follow, the bordered solve stops at
        :data:`FN_HANDOVER` (inside the polish's basin); the Jacobian is kept as a chord while the set stays and
        a full step contracts by :data:`FN_CHORD`."""
        from simgrip.settle.statics import CONTACT_STIFFNESS

        sc, m = self.sc, self.m
        W, L = sc.force_scale, sc.length
        k0 = CONTACT_STIFFNESS * sc.physical.rho * sc.physical.g
        free = np.asarray(free, dtype=int)
        nf = free.size
        nt = 1 if target is not None else 0
        q = np.array(q, dtype=float)
        self.forces(q)
        touch = self.touching()
        # the set: the last solve's pairs (a continuation's predictor may have lifted one a hair off) and those
        # touching now; forces and stiffness carried over, else read from MuJoCo
        pairs = list(dict.fromkeys(list(self._active) + list(touch)))
        N = np.array([self._active[p][0] if p in self._active else touch[p][1] / W for p in pairs])
        K = np.array([self._active[p][1] if p in self._active else
                      (touch[p][1] / touch[p][0] if touch[p][0] > 0 and touch[p][1] > 0 else k0) for p in pairs])
        start = self.iterations
        final_tol = tol
        if polish:
            tol = max(tol, FN_HANDOVER)
        # a pair joins once deeper than this: a pair the solve let go (N < 0) that sits a round-off inside
        # carries at most 0.1 tol (MuJoCo's K is ~k0 or below), and the polish on MuJoCo's balance takes it
        eps = 0.1 * tol * W / k0
        for _outer in range(12):
            F, G = self.kkt_system(q, free, lam, target, pairs, N, K)
            J, ratio = None, 1.0
            while True:
                if not np.all(np.isfinite(F)):
                    return False, q, lam
                # a contact row's error e moves its force by K l e: below tol in force units (the depth row: 1e-13)
                ctol = np.concatenate([[1e-13] * nt, tol * W / (K * L)])
                if float(np.max(np.abs(F[:nf]))) < tol and bool(np.all(np.abs(F[nf:]) < ctol)):
                    break
                if self.iterations - start >= max_iter:
                    return False, q, lam
                self.iterations += 1
                if J is None or ratio > FN_CHORD or J.shape[0] != F.size:
                    J = self._kkt_jacobian(q, free, lam, target, pairs, N, K, F, G)
                try:
                    step = np.linalg.solve(J, -F)
                except np.linalg.LinAlgError:
                    return False, q, lam
                if not np.all(np.isfinite(step)):
                    return False, q, lam
                dq = np.zeros_like(q)
                dq[free] = step[:nf]
                dl = float(step[nf]) if nt else 0.0
                dN = step[nf + nt:]
                alpha = self.guarded(q, dq)
                merit = float(np.linalg.norm(F))
                for _ in range(40):
                    Ft, Gt = self.kkt_system(q + alpha * dq, free, lam + alpha * dl, target, pairs, N + alpha * dN, K)
                    if np.all(np.isfinite(Ft)) and float(np.linalg.norm(Ft)) <= (1.0 - 1e-4 * alpha) * merit:
                        break
                    alpha *= 0.5
                else:
                    if ratio <= FN_CHORD:  # a stale chord: a fresh Jacobian before giving up
                        ratio = 1.0
                        continue
                    if float(np.max(np.abs(F[:nf]))) < FN_STALL * tol:
                        break  # at the difference Jacobian's round-off: MuJoCo's own balance polishes (below)
                    return False, q, lam
                ratio = _chord_ratio(float(np.linalg.norm(Ft)), merit, alpha)
                q, lam, N, F, G = q + alpha * dq, lam + alpha * dl, N + alpha * dN, Ft, Gt
                new = [p for p in self._touching_now(q, eps) if p not in pairs]
                if new:  # a pair that starts touching joins at once
                    pairs += new
                    N = np.append(N, np.zeros(len(new)))
                    K = np.append(K, np.full(len(new), k0))
                    F, G = self.kkt_system(q, free, lam, target, pairs, N, K)
            # the set and the stiffness against MuJoCo
            keep = N >= 0.0
            self.forces(q)
            touch = self.touching()
            changed = not bool(np.all(keep))
            pairs, N, K = [p for p, k in zip(pairs, keep) if k], N[keep], K[keep]
            for i, p in enumerate(pairs):
                dep, f = touch.get(p, (0.0, 0.0))
                if dep > 0 and f > 0 and abs(f / dep - K[i]) > FN_KC_RTOL * K[i]:
                    K[i] = f / dep
                    changed = True
            for p in touch:
                if p not in pairs and touch[p][0] > eps:
                    pairs.append(p)
                    N = np.append(N, touch[p][1] / W)
                    K = np.append(K, touch[p][1] / touch[p][0] if touch[p][0] > 0 and touch[p][1] > 0 else k0)
                    changed = True
            if not changed:
                break
        self._active = {p: (float(N[i]), float(K[i])) for i, p in enumerate(pairs) if N[i] > 0.0}
        if not polish:
            return True, q, lam
        return self.solve(q, free, final_tol, lam=lam, target=target,
                          max_iter=max(1, max_iter - (self.iterations - start)))

    def _kkt_jacobian(self, q, free, lam, target, pairs, N, K, F, G) -> np.ndarray:
        """The bordered Jacobian at ``q``: forward differences in the free dofs, the multipliers' columns exact."""
        sc = self.sc
        W, L = sc.force_scale, sc.length
        nf = free.size
        nt = 1 if target is not None else 0
        k = F.size
        J = np.zeros((k, k))
        scale = np.where(np.isin(free, self.wz), L, 1.0)
        for c, j in enumerate(free):
            h = FN_FD_STEP * scale[c]
            qq = q.copy()
            qq[j] += h
            J[:, c] = (self.kkt_system(qq, free, lam, target, pairs, N, K)[0] - F) / h
        if target is not None:
            self.kkt_system(q, free, lam, target, pairs, N, K)
            J[:nf, nf] = self.friction_column()[free] / self.fscale[free]
        for i in range(len(pairs)):
            J[:nf, nf + nt + i] = W * G[i][free] / self.fscale[free]
            J[nf + nt + i, nf + nt + i] = W / (K[i] * L)
        return J

    def _touching_now(self, q, eps: float) -> list[tuple[int, int]]:
        """Pairs MuJoCo's collision finds overlapping deeper than ``eps`` [m] at ``q`` (kinematics and collision)."""
        d = self.d
        d.qpos[:] = q
        mujoco.mj_kinematics(self.m, d)
        mujoco.mj_collision(self.m, d)
        return sorted({(int(d.contact.geom1[i]), int(d.contact.geom2[i])) for i in range(d.ncon)
                       if -float(d.contact.dist[i]) > eps})

    def contacts(self, q) -> list[tuple[int, int]]:
        """The geom pairs MuJoCo finds in contact at ``q``."""
        self.forces(q)
        d = self.d
        return [(int(d.contact.geom1[i]), int(d.contact.geom2[i])) for i in range(d.ncon)]

    def tip_normal(self, q) -> float:
        """Normal force [over rho g l] of the tip's contacts (the sphere and the last capsule) with the box."""
        self.forces(q)
        m, d, sc = self.m, self.d, self.sc
        tips = {self.tip, int(sc.index.link_geom[0][-1])}
        fc = np.zeros(6)
        out = 0.0
        for i in range(d.ncon):
            g = {int(d.contact.geom1[i]), int(d.contact.geom2[i])}
            if g & tips and g & self.wgeoms:
                mujoco.mj_contactForce(m, d, i, fc)
                out += float(fc[0])
        return out / sc.force_scale


def _chord_ratio(after: float, before: float, alpha: float) -> float:
    """How far a step of ``alpha`` of the Newton step fell short of its linear model, as the chord test reads it:
    the merit left over the merit the model leaves, ``after / ((1 - alpha) before + alpha FN_CHORD before)`` times
    :data:`FN_CHORD`.  A full step (``alpha = 1``) gives ``after / before``; a step the guard shortened keeps the
    Jacobian when it did what the model says (the approach to a contact, a few radii per step, needs no new one)."""
    return FN_CHORD * after / max((1.0 - alpha * (1.0 - FN_CHORD)) * before, 1e-300)

