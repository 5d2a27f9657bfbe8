"""Newton-KKT on MuJoCo's static force balance, with contact and sticking-friction constraints.

Unknowns: the free dofs' positions, a normal force ``N`` per touching contact
pair and a friction force ``lambda`` per sticking contact.  Equations::

    r_free(q) + G_n(q)' N + G_s(q)' lambda (+ sliding friction) = 0
    K_c dist(q) + N = 0                (MuJoCo's soft contact law at rest)
    t . (p_f(q) - p_w(q)) = 0          (sticking)

``r_free`` is MuJoCo's generalised force with contacts off; ``dist`` comes from
``mj_geomDistance`` and its gradient is ``n'(J_2 - J_1)`` at the witness
points.  ``K_c`` is read back from MuJoCo's own contact force at the solution
and the solve repeated until they agree, so that the full MuJoCo residual
(contacts on) vanishes; writing the stiff contact as a compliant constraint
keeps Newton well conditioned.  Unilateral: a pair with ``N < 0`` leaves the
set, a penetrating one joins it.  MuJoCo's friction is velocity based (it
creeps at rest), so sticking is a constraint whose multiplier is the friction
force; the friction cone ``|lambda| <= mu N`` decides hold or slip.

``dr/dq`` comes from ``mjd_inverseFD`` and the constraints' curvature from
differences of ``G' multipliers``; the KKT step is least squares (sticking
leaves the sliding direction singular) with a backtracking line search on the
residual and a tunnelling guard for pairs not yet touching.  Contact-law rows
are accepted at their round-off floor (:data:`FLOOR_ULPS` ulps of ``K_c l``, more for a long,
much-turned chain: :meth:`Newton.floor_ulps`).
"""

from __future__ import annotations

import math
import time

import mujoco
import numpy as np

from simgrip.settle.state import SettledState, SettleError, read_state
from simgrip.settle.statics import (CONTACT_STIFFNESS, Statics, Stick, centreline_point, check_warnings,
                                    sync_scene)
from simgrip.sim.contacts import normal_force, pair_contacts
from simgrip.sim.scene import Scene

__all__ = ["FLOOR_ULPS", "Newton", "PEN_MAX", "SOLVE_ITERS", "read_newton"]

#: A Newton step may not push a pair that was not touching deeper than this (over l).
PEN_MAX = 1e-4
#: Contact-law residuals ``K_c dist + N`` below this many ulps of ``K_c l`` are round-off
#: (geom distances carry ~1e-14 l of round-off: capsule-capsule closest points).
FLOOR_ULPS = 64.0
#: ``K_c`` read back from MuJoCo is updated when it moved by more than this (relative).
KC_RTOL = 1e-13
#: Newton iterations allowed to one solve (quadratic convergence: a solve needing more is failing).
SOLVE_ITERS = 200


# ---------------------------------------------------------------------------
# Newton-KKT


class Newton:
    """Newton-KKT on the static equilibrium with contact and friction constraints.

    Unknowns: the free dofs' positions, a normal force ``N`` per touching
    contact pair and a friction force ``lambda`` per sticking contact.
    Equations (dimensional)::

        r_free(q) + G_n(q)' N + G_s(q)' lambda (+ sliding friction) = 0
        dist(q) + N / K_c = 0              (MuJoCo's contact law at rest)
        t . (p_f(q) - p_w(q)) = 0          (sticking)

    ``r_free`` is MuJoCo's generalised force with contacts off; ``K_c`` is read
    from MuJoCo's own contact force (``efc_force / penetration``) so that, at
    convergence, the full MuJoCo residual (contacts on) vanishes: that residual
    is what :func:`settle` checks and reports.  Writing the stiff contact as
    a compliant constraint keeps Newton well conditioned (a pure penalty would
    force tiny steps along the face).
    """

    def __init__(self, scene: Scene, data=None):
        self.scene = scene
        self.st = Statics(scene, data)
        self.iterations = 0
        m = scene.model
        self.pairs = [(int(m.pair_geom1[i]), int(m.pair_geom2[i])) for i in range(m.npair)]
        self.kc = np.full(m.npair, CONTACT_STIFFNESS * scene.physical.rho * scene.physical.g)
        self.normal_active: list[int] = []
        self.N = np.zeros(0)
        self.sticks: list[Stick] = []
        self.lam = np.zeros(0)
        self.sliding: dict = {}
        #: Where sticking friction acts: ``"centreline"`` (the paper's point contact) or ``"surface"``
        #: (MuJoCo's contact point on the geoms' surface: the finite-radius couple).
        self.friction_at = "centreline"
        #: Total Newton iterations allowed (all solves together); None: unlimited.
        self.budget: int | None = None

    def spent(self) -> bool:
        """The settle's Newton iteration budget is used up."""
        return self.budget is not None and self.iterations >= self.budget

    def _contacts_on(self) -> bool:
        m = self.scene.model
        return bool(self.pairs) and not (self._flags & int(mujoco.mjtDisableBit.mjDSBL_CONTACT))

    # -- geometry -------------------------------------------------------------
    def _dists(self, q) -> np.ndarray:
        """Signed distance of every pair at ``q`` (dimensional); kinematics on the scratch data."""
        m, sd = self.scene.model, self.st.d
        sd.qpos[:] = q
        mujoco.mj_kinematics(m, sd)
        L = self.scene.length
        return np.array([mujoco.mj_geomDistance(m, sd, g1, g2, L, None) for g1, g2 in self.pairs])

    def _dist_grad(self, q, pairs) -> np.ndarray:
        """Gradient of the listed pairs' signed distances over all dofs: ``n' (J_2 - J_1)``.

        ``n`` is the unit normal from geom1 to geom2 and ``J_i`` the Jacobians
        of the witness points (``mj_geomDistance``'s ``fromto``); central
        differences when the witness points coincide.
        """
        m, sd = self.scene.model, self.st.d
        L = self.scene.length
        G = np.zeros((len(pairs), m.nv))
        sd.qpos[:] = q
        mujoco.mj_kinematics(m, sd)
        mujoco.mj_comPos(m, sd)
        j1 = np.zeros((3, m.nv))
        j2 = np.zeros((3, m.nv))
        ft = np.zeros(6)
        for row, p in enumerate(pairs):
            g1, g2 = self.pairs[p]
            dist = mujoco.mj_geomDistance(m, sd, g1, g2, L, ft)
            seg = ft[3:] - ft[:3]
            if np.linalg.norm(seg) < 1e-12 * L:
                G[row] = self._dist_grad_fd(q, p)
                sd.qpos[:] = q
                mujoco.mj_kinematics(m, sd)
                mujoco.mj_comPos(m, sd)
                continue
            n = seg / np.linalg.norm(seg) * math.copysign(1.0, dist)
            mujoco.mj_jac(m, sd, j1, None, ft[:3], int(m.geom_bodyid[g1]))
            mujoco.mj_jac(m, sd, j2, None, ft[3:], int(m.geom_bodyid[g2]))
            G[row] = n @ (j2 - j1)
        return G

    def _dist_grad_fd(self, q, p) -> np.ndarray:
        m = self.scene.model
        out = np.zeros(m.nv)
        for c in range(m.nv):
            h = 1e-6 * self.st.lscale[c]
            v = np.zeros(m.nv)
            v[c] = h
            qp, qm = q.copy(), q.copy()
            mujoco.mj_integratePos(m, qp, v, 1.0)
            mujoco.mj_integratePos(m, qm, -v, 1.0)
            out[c] = (self._dists(qp)[p] - self._dists(qm)[p]) / (2 * h)
        return out

    # -- residual --------------------------------------------------------------
    def _residual(self, q, N, lam, idx):
        """Scaled KKT residual and the pieces needed for the Jacobian."""
        m = self.scene.model
        L = self.scene.length
        # MuJoCo's forces with contacts off (springs, gravity, applied)
        m.opt.disableflags = self._flags | int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
        r = self.st.forces(q)
        m.opt.disableflags = self._flags
        check_warnings(self.st.d)
        act = self.normal_active
        dist = self._dists(q)
        total = r.copy()
        Gn = Gs = None
        gs = np.zeros(0)
        if act:
            Gn = self._dist_grad_cached(q, act)
            total += Gn.T @ N
        stick_act = [i for i in range(len(self.sticks)) if i not in self.sliding]
        if self.sticks:
            self.st.d.qpos[:] = q
            mujoco.mj_kinematics(m, self.st.d)
            gs_all, Gs_all = self.st.stick_rows(self.sticks)
            gs, Gs = gs_all[stick_act], Gs_all[stick_act]
            total += Gs.T @ lam
            for i, sign in self.sliding.items():
                p = self._pair_of(self.sticks[i])
                if p not in act:  # the pair has separated: N = 0, no sliding friction
                    continue
                k = act.index(p)
                mu = float(m.pair_friction[p][0])
                total += Gs_all[i] * sign * mu * N[k]
        F = total[idx] / self.st.fscale[idx]
        W = self.scene.force_scale
        gn = (self.kc[act] * dist[act] + N) / W if act else np.zeros(0)
        self._merit_weights = np.concatenate([np.ones(F.size), W / (self.kc[act] * L) if act else np.zeros(0),
                                              np.ones(gs.size)])
        return np.concatenate([F, gn, gs]), dist, Gn, Gs

    def _dist_grad_cached(self, q, act):
        key = (q.tobytes(), tuple(act))
        if getattr(self, "_gcache_key", None) != key:
            self._gcache_key = key
            self._gcache = self._dist_grad(q, act)
        return self._gcache

    def _pair_of(self, s: Stick) -> int:
        for i, (g1, g2) in enumerate(self.pairs):
            if {g1, g2} == set(s.geoms):
                return i
        raise KeyError(s.geoms)

    # -- Newton -----------------------------------------------------------------
    def solve(self, tol: float, max_iter: int, *, frozen=()) -> tuple[bool, str]:
        """Newton-KKT until the scaled residual is below ``tol`` with a consistent contact set."""
        sc = self.scene
        m, d = sc.model, sc.data
        self._flags = int(m.opt.disableflags)
        contacts = self._contacts_on()
        free = np.ones(m.nv, bool)
        free[list(frozen)] = False
        idx = np.flatnonzero(free)
        q = d.qpos.copy()
        if not contacts:
            self.normal_active, self.N = [], np.zeros(0)
        limit = self.iterations + max_iter
        if self.budget is not None:
            limit = min(limit, self.budget)
        if contacts:  # initial contact set: touching pairs and the sticks' pairs
            dist = self._dists(q)
            need = {p for p in range(len(self.pairs)) if dist[p] <= 0.0}
            need |= {self._pair_of(s) for s in self.sticks}
            for p in sorted(need - set(self.normal_active)):
                self.normal_active.append(p)
                self.N = np.append(self.N, 0.0)
        for _outer in range(8):
            conv, why, q = self._newton(q, idx, tol, limit, contacts)
            if not conv:
                self._commit(q)
                return False, why
            if not contacts:
                self._commit(q)
                return True, "ok"
            # contact set and MuJoCo consistency
            dist = self._dists(q)
            changed = False
            keep = [k for k, p in enumerate(self.normal_active) if self.N[k] >= 0.0]
            if len(keep) != len(self.normal_active):
                self.normal_active = [self.normal_active[k] for k in keep]
                self.N = self.N[keep]
                changed = True
            for p in range(len(self.pairs)):
                if p not in self.normal_active and dist[p] < 0.0:
                    self.normal_active.append(p)
                    self.N = np.append(self.N, 0.0)
                    changed = True
            if not changed and self._update_kc(q):
                changed = True
            if not changed:
                self._commit(q)
                return True, "ok"
        self._commit(q)
        return False, "contact set did not settle"

    def noise_floor(self) -> float:
        """Round-off floor of the contact force residual: ``K_c`` times the resolution of a distance."""
        if not self.normal_active:
            return 0.0
        kc = float(np.max(self.kc[self.normal_active]))
        return self.floor_ulps() * np.finfo(float).eps * kc * self.scene.length / self.scene.force_scale

    def floor_ulps(self) -> float:
        """Round-off of a contact distance in ulps of ``l``: :data:`FLOOR_ULPS`, or the chain's bound if larger.

        A node of an ``n``-link chain is a sum of ``n`` link vectors ``ds (cos phi_k, sin phi_k)``
        with ``phi_k`` a running sum of hinge angles: the angle sums carry up to ``k eps |phi|``,
        which moves the node by up to ``sum_k ds k eps Phi ~ n eps Phi l / 2``, and the vector sum
        adds up to ``n eps l`` (``Phi = max |phi_k|``, read at the scene's current state).
        """
        sc = self.scene
        phi = np.cumsum(np.asarray(sc.data.qpos)[np.asarray(sc.joint_qpos)], axis=-1)
        big = float(np.max(np.abs(phi))) if phi.size else 0.0
        return max(FLOOR_ULPS, sc.n * (1.0 + 0.5 * big))

    def _update_kc(self, q) -> bool:
        """Read MuJoCo's contact stiffness at ``q``; True if it moved enough to matter."""
        m, sd = self.scene.model, self.st.d
        self.st.forces(q)
        moved = False
        for k, p in enumerate(self.normal_active):
            cons = pair_contacts(sd, *self.pairs[p])
            if not cons:
                continue
            pen = -min(float(sd.contact.dist[c]) for c in cons)
            fn = sum(normal_force(m, sd, c) for c in cons)
            if pen > 0 and fn > 0:
                kc = fn / pen
                if abs(kc - self.kc[p]) > KC_RTOL * kc:
                    moved = moved or abs(kc - self.kc[p]) * pen > 0.1 * self.noise_floor() * self.scene.force_scale
                    self.kc[p] = kc
        return moved

    def _newton(self, q, idx, tol, max_iter, contacts):
        sc = self.scene
        m = sc.model
        L = sc.length
        N = self.N.copy()
        stick_act = [i for i in range(len(self.sticks)) if i not in self.sliding]
        if self.lam.size != len(self.sticks):
            self.lam = np.zeros(len(self.sticks))
        lam = self.lam[stick_act].copy()
        R, dist, Gn, Gs = self._residual(q, N, lam, idx)
        while True:
            res = float(np.max(np.abs(R))) if R.size else 0.0
            if not math.isfinite(res):
                raise SettleError("settle diverged (non-finite residual)")
            nf = idx.size
            res_f = float(np.max(np.abs(R[:nf]))) if nf else 0.0
            res_c = float(np.max(np.abs(R[nf:]))) if R.size > nf else 0.0
            if res_f < tol and res_c < max(tol, self.noise_floor()):
                break
            if self.iterations >= max_iter:
                self.N, self.lam[stick_act] = N, lam
                if self.budget is not None and self.iterations >= self.budget:
                    return False, f"Newton iteration budget max_steps={self.budget} spent", q
                return False, "max_iter", q
            self.iterations += 1
            if self.sticks:
                self._reanchor(q)
                R, dist, Gn, Gs = self._residual(q, N, lam, idx)
            m.opt.disableflags = self._flags | int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
            H = self.st.jacobian(q)
            m.opt.disableflags = self._flags
            act = self.normal_active
            if act:  # curvature of the constraints: d(G' mult)/dq by FD
                H = H + self._constraint_curvature(q, N, lam, stick_act)
            fs, ls = self.st.fscale[idx], self.st.lscale[idx]
            nf, nn, ns = idx.size, len(act), len(stick_act)
            K = np.zeros((nf + nn + ns, nf + nn + ns))
            K[:nf, :nf] = H[np.ix_(idx, idx)] * ls[None, :] / fs[:, None]
            if nn:
                Gi = Gn[:, idx]
                K[:nf, nf:nf + nn] = Gi.T / fs[:, None]
                W = sc.force_scale
                K[nf:nf + nn, :nf] = Gi * ls[None, :] * self.kc[act][:, None] / W
                K[nf:nf + nn, nf:nf + nn] = np.eye(nn) / W
            if ns:
                Gi = Gs[:, idx]
                K[:nf, nf + nn:] = Gi.T / fs[:, None]
                K[nf + nn:, :nf] = Gi * ls[None, :] / L
            if self.sliding and nn:  # sliding friction sign * mu * N depends on N
                _, Gs_all = self.st.stick_rows(self.sticks)
                for i, sign in self.sliding.items():
                    p = self._pair_of(self.sticks[i])
                    if p not in act:  # separated pair: no friction (see _residual)
                        continue
                    k = act.index(p)
                    mu = float(m.pair_friction[p][0])
                    K[:nf, nf + k] += Gs_all[i][idx] * sign * mu / fs
            sol, *_ = np.linalg.lstsq(K, -R, rcond=1e-14)
            dq = sol[:nf] * ls
            dN = sol[nf:nf + nn]
            dl = sol[nf + nn:]
            wts = self._merit_weights.copy()
            merit = float(np.linalg.norm(R * wts))
            d0 = dist
            step = 1.0
            accepted = False
            for _ in range(50):
                v = np.zeros(m.nv)
                v[idx] = step * dq
                qn = q.copy()
                mujoco.mj_integratePos(m, qn, v, 1.0)
                Nn, ln = N + step * dN, lam + step * dl
                Rn, distn, Gnn, Gsn = self._residual(qn, Nn, ln, idx)
                ok = bool(np.all(np.isfinite(Rn)))
                if ok and contacts:
                    # inactive pairs: no tunnelling (move at most half their gap)
                    inact = [p for p in range(len(self.pairs)) if p not in act]
                    if inact:
                        ok = all(distn[p] > -PEN_MAX * L or d0[p] <= 0 for p in inact) and all(
                            d0[p] - distn[p] <= max(0.5 * d0[p], 0.0) + PEN_MAX * L for p in inact if d0[p] > 0
                        )
                mn = float(np.linalg.norm(Rn * wts))
                # Armijo on the weighted merit, or (near round-off) a halved max residual
                if ok and (mn < (1.0 - 1e-4 * step) * merit or (
                        float(np.max(np.abs(Rn))) < 0.5 * res and mn < max(2.0 * merit, 1e-3 * tol ** 0.5))):
                    accepted = True
                    break
                step *= 0.5
            if not accepted:
                self.N, self.lam[stick_act] = N, lam
                return False, "stalled", q
            q, N, lam, R, dist, Gn, Gs = qn, Nn, ln, Rn, distn, Gnn, Gsn
            # a pair that starts touching joins the set at once
            if contacts:
                newp = [p for p in range(len(self.pairs)) if p not in self.normal_active and dist[p] < 0.0]
                if newp:
                    self.normal_active = self.normal_active + newp
                    N = np.append(N, np.zeros(len(newp)))
                    R, dist, Gn, Gs = self._residual(q, N, lam, idx)
        self.N = N
        self.lam[stick_act] = lam
        return True, "ok", q

    def _reanchor(self, q) -> None:
        """Move every stick's anchors to its pair's current contact point."""
        m, sd = self.scene.model, self.st.d
        sd.qpos[:] = q
        mujoco.mj_kinematics(m, sd)
        ft = np.zeros(6)
        for s in self.sticks:
            mujoco.mj_geomDistance(m, sd, s.geoms[0], s.geoms[1], self.scene.length, ft)
            s.reanchor(sd, self._anchor(sd, s.geoms[0], 0.5 * (ft[:3] + ft[3:])))

    def _anchor(self, d, geom, point) -> np.ndarray:
        """Where the sticking friction acts: the contact ``point``, or (point contact) the finger's centreline there."""
        return centreline_point(self.scene.model, d, geom, point) if self.friction_at == "centreline" else point

    def _constraint_curvature(self, q, N, lam, stick_act) -> np.ndarray:
        """FD of ``G_n' N + G_s' lambda`` over q (geometric stiffness of the constraints)."""
        m = self.scene.model
        act = self.normal_active

        def gen(qq):
            out = np.zeros(m.nv)
            if act:
                out += self._dist_grad(qq, act).T @ N
            if stick_act:
                self.st.d.qpos[:] = qq
                mujoco.mj_kinematics(m, self.st.d)
                _, Gs = self.st.stick_rows(self.sticks)
                out += Gs[stick_act].T @ lam
            return out

        base = gen(q)
        C = np.zeros((m.nv, m.nv))
        for c in range(m.nv):
            h = 1e-6 * self.st.lscale[c]
            v = np.zeros(m.nv)
            v[c] = h
            qp = q.copy()
            mujoco.mj_integratePos(m, qp, v, 1.0)
            C[:, c] = (gen(qp) - base) / h
        return C

    def _commit(self, q) -> None:
        d = self.scene.data
        d.qpos[:] = q
        d.qvel[:] = 0.0
        mujoco.mj_forward(self.scene.model, d)
        self.st.forces(q)

    # -- friction bookkeeping ------------------------------------------------
    def stick_now(self) -> int:
        """Sticking constraints at every current finger-workpiece contact; returns how many."""
        sc = self.scene
        m, sd = sc.model, self.st.d
        self.st.forces(sc.data.qpos)
        self.sticks, self.sliding = [], {}
        wg = set(int(g) for g in sc.workpiece_geoms)
        for f in range(sc.fingers):
            mine = set(int(g) for g in sc.contact_geoms[f])
            best = None
            for i in range(sd.ncon):
                g1, g2 = int(sd.contact.geom1[i]), int(sd.contact.geom2[i])
                if g1 in mine and g2 in wg:
                    fn = normal_force(m, sd, i)
                    if best is None or fn > best[0]:
                        best = (fn, i, g1, g2)
            if best is None:
                continue
            _, i, g1, g2 = best
            p = self._anchor(sd, g1, np.array(sd.contact.pos[i]))
            bf, bw = int(m.geom_bodyid[g1]), int(m.geom_bodyid[g2])
            normal = np.array(sd.contact.frame[i][:3])
            t = np.cross(np.array([0.0, 1.0, 0.0]), normal)  # in-plane tangent
            if np.linalg.norm(t) < 1e-6:  # out-of-plane normal (tip deep in the box): no planar stick
                continue
            t /= np.linalg.norm(t)
            tb = bw if sc.grip in ("I", "II") else bf
            self.sticks.append(
                Stick(
                    finger=f,
                    body_f=bf,
                    local_f=sd.xmat[bf].reshape(3, 3).T @ (p - sd.xpos[bf]),
                    body_w=bw,
                    local_w=sd.xmat[bw].reshape(3, 3).T @ (p - sd.xpos[bw]),
                    t_body=tb,
                    t_local=sd.xmat[tb].reshape(3, 3).T @ t,
                    geoms=(g1, g2),
                )
            )
        self.lam = np.zeros(len(self.sticks))
        return len(self.sticks)

    def normals_of_sticks(self) -> np.ndarray:
        out = np.zeros(len(self.sticks))
        for i, s in enumerate(self.sticks):
            p = self._pair_of(s)
            if p in self.normal_active:
                out[i] = self.N[self.normal_active.index(p)]
        return out

    def cone_violations(self) -> list[tuple[int, float]]:
        """``(stick index, sign of lambda)`` for sticks whose friction exceeds ``mu N``."""
        m = self.scene.model
        normals = self.normals_of_sticks()
        out = []
        for i, s in enumerate(self.sticks):
            if i in self.sliding:
                continue
            mu = float(m.pair_friction[self._pair_of(s)][0])
            if normals[i] <= 0.0 or abs(self.lam[i]) > mu * normals[i] * (1.0 + 1e-9):
                out.append((i, math.copysign(1.0, self.lam[i])))
        return out

    def friction_forces(self) -> np.ndarray:
        """Friction force on each stick's finger along its tangent (sticking or sliding)."""
        m = self.scene.model
        normals = self.normals_of_sticks()
        out = self.lam.copy()
        for i, sign in self.sliding.items():
            out[i] = sign * float(m.pair_friction[self._pair_of(self.sticks[i])][0]) * normals[i]
        return out

    def full_residual(self, q) -> np.ndarray:
        """MuJoCo's own static residual (contacts on) plus the friction forces, scaled."""
        m = self.scene.model
        r = self.st.forces(q)
        if self.sticks:
            _, G = self.st.stick_rows(self.sticks)
            r = r + G.T @ self.friction_forces()
        return r / self.st.fscale


def read_newton(scene: Scene, run: Newton, t0: float, held: bool, converged: bool) -> SettledState:
    """The settled state of the static solve: MuJoCo's contacts plus the sticking friction forces."""
    sync_scene(scene)
    fric = run.friction_forces() if (run.sticks and held) else np.zeros(0)
    if not held:
        run.sticks, run.sliding = [], {}
    full = run.full_residual(scene.data.qpos)  # leaves the scratch data at the state, contacts on
    if not held:
        full[np.asarray(scene.workpiece_dof, dtype=int)] = 0.0  # parked
    sd = run.st.d
    normals = run.normals_of_sticks() if run.sticks else np.zeros(0)

    def friction(f):
        forces, mu = [], math.nan
        for k, s in enumerate(run.sticks):
            if s.finger == f and k < fric.size:
                forces.append((fric[k] * s.tangent(sd), s.points(sd)[0]))
                if math.isnan(mu) and normals[k] > 0:
                    mu = abs(float(fric[k])) / float(normals[k])
        return forces, mu

    return read_state(scene, sd, held=held, method="newton", residual=float(np.max(np.abs(full))),
                      converged=converged, steps=run.iterations, newton_iterations=run.iterations,
                      forward_calls=run.st.calls, wall_time_s=time.perf_counter() - t0, friction=friction)
