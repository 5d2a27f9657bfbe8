"""The static solve's contact set and friction bookkeeping, around a Newton-KKT inner solve.

Unknowns: the free dofs' positions, a normal force ``N`` per touching contact
pair and a friction force ``lambda`` per sticking contact.  Equations::

    r_free(q) + G_n(q)' N + G_s(q)' lambda (+ sliding friction) = 0
    K_c dist(q) + N = 0                (MuJoCo's soft contact law at rest)
    t . (p_f(q) - p_w(q)) = 0          (sticking)

``r_free`` is MuJoCo's generalised force with contacts off and ``dist`` the
pairs' signed distances (``mj_geomDistance``).  :class:`Newton` keeps what the
inner solve does not own: the contact set (unilateral: a pair with ``N < 0``
leaves the set, a penetrating one joins it), ``K_c`` read back from MuJoCo's
own contact force at the solution and the solve repeated until they agree (so
that the full MuJoCo residual, contacts on, vanishes; writing the stiff contact
as a compliant constraint keeps Newton well conditioned), the sticks (MuJoCo's
friction is velocity based and creeps at rest, so sticking is a constraint
whose multiplier is the friction force; the friction cone ``|lambda| <= mu N``
decides hold or slip) and MuJoCo's residual as the judge.  The inner Newton
iteration, exact and ``O(n)``, is :class:`~simgrip.settle.chain_newton.ChainNewton`'s.
Contact-law rows are accepted at their round-off floor (:data:`FLOOR_ULPS` ulps
of ``K_c l``, more for a long, much-turned chain: :meth:`Newton.floor_ulps`).

Contact depth: :func:`~simgrip.settle.statics.configure_statics` sizes ``K_c`` for a
force of ``rho g l`` (``p ~ 1e-6 l``), but a stiff finger pinches far harder (Grip I at
``D = 1e4``: ``N ~ 7e4 rho g l``, ``p = N / K_c ~ 4e-3 l``, deeper than the tip's radius:
the tip's centre passes the face and the solve fails).  A pair whose normal force would
press it deeper than :data:`PEN_STIFFEN` is made stiffer by a power of :data:`STIFFEN_STEP`
(:meth:`Newton.stiffen`: the pair's ``solref`` in MuJoCo's direct stiffness form) and solved
again; the stiffness is read back from MuJoCo as before.
"""

from __future__ import annotations

import math
import time

import mujoco
import numpy as np

from simgrip.settle.banded import _F64, _MAX
from simgrip.settle.state import SettledState, read_state
from simgrip.settle.statics import CONTACT_STIFFNESS, Statics, Stick, centreline_point, sync_scene
from simgrip.sim.contacts import normal_force
from simgrip.sim.scene import Scene

__all__ = ["FLOOR_ULPS", "Newton", "PEN_MAX", "PEN_STIFFEN", "SOLVE_ITERS", "STIFFEN_MAX", "STIFFEN_STEP", "read_newton"]

#: A Newton step may not push a pair that was not touching deeper than this (over l).
PEN_MAX = 1e-4
#: Contact-law residuals ``K_c dist + N`` below this many ulps of ``K_c l`` are round-off
#: (geom distances carry ~1e-14 l of round-off: capsule-capsule closest points).
FLOOR_ULPS = 64.0
#: ``K_c`` read back from MuJoCo is updated when it moved by more than this (relative).
KC_RTOL = 1e-13
#: Newton iterations allowed to one solve (quadratic convergence: a solve needing more is failing).
SOLVE_ITERS = 200
#: A pair pressed deeper than this (over l) is stiffened (:meth:`Newton.stiffen`); pairs of the paper's
#: standard cases (``p <= 3e-6 l``) keep the configured stiffness and their results.  A stiffened pair
#: settles between ``PEN_STIFFEN / STIFFEN_STEP`` and ``PEN_STIFFEN`` deep: ``<= 1e-5 l``, 30 times
#: below the ``n = 32`` chain's tip error (~3e-4 l) that the comparison with the BVP tolerates.
PEN_STIFFEN = 1e-5
#: Contact stiffness factors are powers of this (path-independent settled states, :meth:`Newton.stiffen`).
STIFFEN_STEP = 10.0
#: Machine epsilon (``np.finfo(float).eps``, looked up once: the floors are evaluated every iteration).
_EPS = float(np.finfo(float).eps)
_ZERO = (0.0,)
_SPHERE = int(mujoco.mjtGeom.mjGEOM_SPHERE)
#: Largest stiffness factor (a weightless workpiece needs ~1e14: MuJoCo weighs its contact by the workpiece's
#: inverse mass; a contact needing more is flagged by :func:`simgrip.validity.check_contact_depth`).
STIFFEN_MAX = 1e16
#: A factor falls back a step only when the force fits the lower one with this relative margin (the force
#: moves by ~``PEN_STIFFEN`` relative between factors: 100 times less).
STIFFEN_HYSTERESIS = 1e-3


# ---------------------------------------------------------------------------
# Newton-KKT


class Newton:
    """Contact set, ``K_c``, sticks and MuJoCo's residual around an inner Newton-KKT solve (``_newton``).

    Equations (dimensional)::

        r_free(q) + G_n(q)' N + G_s(q)' lambda (+ sliding friction) = 0
        dist(q) + N / K_c = 0              (MuJoCo's contact law at rest)
        t . (p_f(q) - p_w(q)) = 0          (sticking)

    ``r_free`` is MuJoCo's generalised force with contacts off; ``K_c`` is read
    from MuJoCo's own contact force (``efc_force / penetration``) so that, at
    convergence, the full MuJoCo residual (contacts on) vanishes: that residual
    is what :func:`settle` checks and reports.  Writing the stiff contact as
    a compliant constraint keeps Newton well conditioned (a pure penalty would
    force tiny steps along the face).  The inner solve is
    :class:`~simgrip.settle.chain_newton.ChainNewton`'s; this class holds the
    MuJoCo side: the contact set (``mj_geomDistance``), ``K_c`` and the reported residual.
    """

    #: a contact's force (mj_contactForce's output buffer of :meth:`_update_kc`) and the hinges' qpos addresses
    #: (fingers, n; :meth:`floor_ulps`): made on first use, per solve
    _f6 = _jq = None

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
        #: Largest factor by which :meth:`stiffen` raised a pair's contact stiffness (1: none); the
        #: contact floor's cap scales with it (:func:`simgrip.settle.settle`).
        self.stiffening = 1.0
        #: Per pair: the factor :meth:`stiffen` applied to its configured stiffness.
        self.kc_factor = np.ones(m.npair)
        self._tc0 = None  # the configured solref time constants (read at the first stiffen)
        self._kc_raised: list = [None] * m.npair  # per pair: K_c read before its last raise (saturation test)
        self._floor_memo = None  # floor_ulps' last (qpos bytes, value)
        #: ``mj_kinematics`` calls of the solve on its data (contact distances, sticks' anchors): a count, so that
        #: positions known to be current can be told stale
        self.kinematics_calls = 0

    def spent(self) -> bool:
        """The settle's Newton iteration budget is used up."""
        return self.budget is not None and self.iterations >= self.budget

    def _contacts_on(self) -> bool:
        return bool(self.pairs) and not (self._flags & int(mujoco.mjtDisableBit.mjDSBL_CONTACT))

    # -- geometry -------------------------------------------------------------
    def _dists(self, q) -> np.ndarray:
        """Signed distance of every pair at ``q`` (dimensional); kinematics on the scratch data."""
        m, sd = self.scene.model, self.st.d
        sd.qpos[:] = q
        mujoco.mj_kinematics(m, sd)
        self.kinematics_calls += 1
        L = self.scene.length
        return np.array([mujoco.mj_geomDistance(m, sd, g1, g2, L, None) for g1, g2 in self.pairs])

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
        idx = free.nonzero()[0]  # (np.flatnonzero's answer for a 1-D mask, without its wrappers)
        q = d.qpos.copy()
        if not contacts:
            self.normal_active, self.N = [], np.zeros(0)
        limit = self.iterations + max_iter
        if self.budget is not None:
            limit = min(limit, self.budget)
        if contacts:  # initial contact set: touching pairs and the sticks' pairs
            need = {self._pair_of(s) for s in self.sticks}
            if len(need | set(self.normal_active)) < len(self.pairs):  # (else every pair is in: no distance read)
                dist = self._dists(q)
                need |= {p for p in range(len(self.pairs)) if dist[p] <= 0.0}
            for p in sorted(need - set(self.normal_active)):
                self.normal_active.append(p)
                self.N = np.concatenate((self.N, _ZERO))  # (np.append's values: a 0.0 after N)
        for _outer in range(8):
            conv, why, q = self._newton(q, idx, tol, limit, contacts)
            if not conv:
                self._commit(q)
                return False, why
            if not contacts:
                self._commit(q)
                return True, "ok"
            # contact set and MuJoCo consistency
            changed = False
            keep = [k for k, p in enumerate(self.normal_active) if self.N[k] >= 0.0]
            if len(keep) != len(self.normal_active):
                self.normal_active = [self.normal_active[k] for k in keep]
                self.N = self.N[keep]
                changed = True
            # (the distances only where a pair is out of the set: one that penetrates joins it)
            dist = self._dists(q) if len(self.normal_active) < len(self.pairs) else None
            for p in range(len(self.pairs)) if dist is not None else ():
                if p not in self.normal_active and dist[p] < 0.0:
                    self.normal_active.append(p)
                    self.N = np.append(self.N, 0.0)
                    changed = True
            if not changed and self.stiffen(self.N):
                changed = True  # the contact pressed deeper than PEN_STIFFEN: solve again, stiffer
            if not changed and not self._kc_current(q) and self._update_kc(q):
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
        act = self.normal_active
        # (one pair, a Grip I/II finger's: its K_c itself, without the fancy index and reduction)
        kc = float(self.kc[act[0]]) if len(act) == 1 else float(self.kc[act].max())
        ph = self.scene.physical  # (the scene's length and force_scale, read through one property)
        return self.floor_ulps() * _EPS * kc * ph.length / ph.force_scale

    def floor_ulps(self) -> float:
        """Round-off of a contact distance in ulps of ``l``: :data:`FLOOR_ULPS`, or the chain's bound if larger.

        A node of an ``n``-link chain is a sum of ``n`` link vectors ``ds (cos phi_k, sin phi_k)``
        with ``phi_k`` a running sum of hinge angles: the angle sums carry up to ``k eps |phi|``,
        which moves the node by up to ``sum_k ds k eps Phi ~ n eps Phi l / 2``, and the vector sum
        adds up to ``n eps l`` (``Phi = max |phi_k|``, read at the scene's current state).
        """
        sc = self.scene
        q = np.asarray(sc.data.qpos)
        memo = self._floor_memo  # the last state's (qpos bytes, value): a solve asks ~8 times, mostly at one state
        if memo is not None and memo[0] == q.tobytes():
            return memo[1]
        jq = self._jq
        if jq is None:
            jq = self._jq = np.asarray(sc.joint_qpos)
        phi = q[jq].cumsum(axis=-1)
        big = float(_MAX(np.abs(phi), axis=None)) if phi.size else 0.0
        out = max(FLOOR_ULPS, sc.n * (1.0 + 0.5 * big))
        self._floor_memo = (q.tobytes(), out)
        return out

    def stiffen(self, N, *, grow_only: bool = False) -> bool:
        """Size every active pair's contact stiffness for its normal force ``N`` [N]; True if any changed.

        A pair's factor over the configured stiffness (:attr:`kc_factor`) is a
        power of :data:`STIFFEN_STEP`: the smallest that keeps its depth ``N /
        K_c`` at most :data:`PEN_STIFFEN` (1 where the configured stiffness does).
        ``K_c`` is MuJoCo's, read back (:meth:`_update_kc`); MuJoCo's ``K_c`` at
        rest goes as its reference stiffness, set to ``factor`` times the
        configured one (:meth:`_set_solref`), so a pair too deep by ``r`` goes up by
        ``ceil(log r)`` steps and one that would fit a lower factor comes down
        to it.  Powers of a fixed step make the settled state a function of the
        final force alone, not of the path the solve took to it.  A factor
        falls back only when the force fits the lower one with a margin of
        :data:`STIFFEN_HYSTERESIS` (no cycling at a step's edge), never while
        ``grow_only`` (inside a solve, so that a hard-pressed contact does not
        pass its face before it converges).  A pair whose read-back ``K_c`` did
        not follow its last raise (MuJoCo's soft contact saturates where the
        workpiece's inverse mass dominates, e.g. ``M = 0``) is not raised again;
        none goes above :data:`STIFFEN_MAX` (the depth check of
        :func:`simgrip.validity.check_contact_depth` then speaks).  The model's
        ``pair_solref`` is restored by the settle (:func:`.statics.restore_options`).
        """
        m, L = self.scene.model, self.scene.length
        if self._tc0 is None:
            self._tc0 = m.pair_solref[:, 0].copy()  # as configure_statics set it
        lstep = math.log(STIFFEN_STEP)
        changed = False
        for k, p in enumerate(self.normal_active):
            if k >= len(N) or not N[k] > 0.0:
                continue
            old = float(self.kc_factor[p])
            over = float(N[k]) / float(self.kc[p]) / (PEN_STIFFEN * L)  # depth over the largest allowed
            if over > 1.0:
                raised = self._kc_raised[p]
                if raised is not None and float(self.kc[p]) < 2.0 * raised:
                    continue  # the last raise did not take (saturated): no further
                f = min(old * STIFFEN_STEP ** math.ceil(math.log(over) / lstep - 1e-12), STIFFEN_MAX)
            elif grow_only or old <= 1.0:
                continue
            else:
                down = math.floor(math.log((1.0 - STIFFEN_HYSTERESIS) / over) / lstep + 1e-12) if over > 0 else 0
                f = max(old / STIFFEN_STEP ** max(down, 0), 1.0)
            if f == old:
                continue
            self._kc_raised[p] = float(self.kc[p]) if f > old else None
            self._set_solref(p, f)
            self.kc[p] *= f / old  # until read back
            self.kc_factor[p] = f
            changed = True
        if changed:  # (else kc_factor is as the last assignment of stiffening left it: __init__, here, restore_contact)
            self.stiffening = float(np.max(self.kc_factor)) if self.kc_factor.size else 1.0
        return changed

    def _set_solref(self, p: int, f: float) -> None:
        """Pair ``p``'s ``solref`` for ``f`` times the configured stiffness, in MuJoCo's direct form.

        MuJoCo's reference stiffness from a time constant is ``1 / (dmax^2 tc^2)``
        with the product clamped at ``1e-15`` (a limit a weightless workpiece reaches:
        its contact is ``~1e-10`` as stiff, MuJoCo weighing it by its inverse mass);
        the direct form ``(-stiffness, -damping)`` has no such clamp:
        ``stiffness = f / tc0^2`` (times ``dmax^2`` in MuJoCo's convention: the same
        constraint stiffness) and the damping of a time constant ``tc0 / sqrt(f)``
        (critical, as the configured ``dampratio`` 1; it does not enter the balance at rest).
        """
        m = self.scene.model
        tc = self._tc0[p] / math.sqrt(f)
        m.pair_solref[p, 0] = -1.0 / tc ** 2
        m.pair_solref[p, 1] = -2.0 / tc

    def contact_snapshot(self) -> tuple:
        """The solve's contact state (set, forces, stiffness and its factors, the model's ``solref``), for
        :meth:`restore_contact`."""
        return (list(self.normal_active), self.N.copy(), self.kc.copy(), self.kc_factor.copy(),
                self.scene.model.pair_solref.copy(), list(self._kc_raised))

    def restore_contact(self, snap: tuple) -> None:
        """Put back a :meth:`contact_snapshot`."""
        act, N, kc, fac, solref, raised = snap
        self.normal_active, self.N, self._kc_raised = list(act), N.copy(), list(raised)
        self.kc[:], self.kc_factor[:] = kc, fac
        self.scene.model.pair_solref[:] = solref
        self.stiffening = float(np.max(self.kc_factor)) if self.kc_factor.size else 1.0

    def _kc_key(self, q) -> tuple:
        """Everything a read of ``K_c`` at ``q`` (:meth:`_update_kc`) depends on: the state, the contact
        set, the stiffness it leaves and the model's contact and workpiece parameters (arrays as their bytes:
        equal bytes are equal values; a signed zero that differs only asks for one read more)."""
        m = self.scene.model
        qb = q.tobytes() if type(q) is np.ndarray and q.dtype is _F64 else np.asarray(q, dtype=float).tobytes()
        return (qb, list(self.normal_active), self.kc.tobytes(),
                m.pair_solref.tobytes(), m.pair_solimp.tobytes(), m.pair_friction.tobytes(), m.body_pos.tobytes(),
                int(m.opt.disableflags))

    def _kc_current(self, q) -> bool:
        """``K_c`` was read at exactly this ``q`` and nothing it depends on changed since: a second read
        (one ``mj_inverse``) would find the same stiffness and report no move."""
        key = getattr(self, "_kc_at", None)
        return key is not None and key == self._kc_key(q)

    def _update_kc(self, q, moved_wanted: bool = True) -> bool:
        """Read MuJoCo's contact stiffness at ``q``; True if it moved enough to matter (``moved_wanted`` False:
        a caller that ignores the answer, the inner solve's reads at each accepted state; it is then False and
        the noise floor the test compares with is not evaluated; ``K_c`` is read and kept all the same)."""
        m, sd = self.scene.model, self.st.d
        self._kc_at = None
        ready, self._forces_ready = getattr(self, "_forces_ready", False), False
        if not ready:  # (else the data holds MuJoCo's balance at q already: ChainNewton's stick_now mark)
            self.st.forces(q)
        moved = False
        self._kc_low = lows = {}  # each touching pair's least contact distance [m] at q (ChainNewton's round-off)
        ncon = sd.ncon
        con = sd.contact  # (one view of MuJoCo's contact arrays: each ``sd.contact`` builds a new one)
        dist = con.dist
        g1, g2 = con.geom1[:ncon].tolist(), con.geom2[:ncon].tolist()
        f6 = self._f6
        if f6 is None:  # (made at the first read: a settle without contacts never needs it)
            f6 = self._f6 = np.zeros(6)
        for k, p in enumerate(self.normal_active):
            a, b = self.pairs[p]  # (pair_contacts' test, on the lists read once for every pair)
            cons = [i for i in range(ncon) if (g1[i] == a and g2[i] == b) or (g1[i] == b and g2[i] == a)]
            if not cons:
                continue
            low = fn = None  # (min() and sum() of the contacts' distances and normal forces, as loops)
            for c in cons:
                v = float(dist[c])
                if low is None or v < low:
                    low = v
                mujoco.mj_contactForce(m, sd, c, f6)  # (normal_force's read, into one buffer)
                f = float(f6[0])
                fn = f if fn is None else fn + f
            lows[p] = low
            pen = -low
            if pen > 0 and fn > 0:
                kc = fn / pen
                if abs(kc - self.kc[p]) > KC_RTOL * kc:
                    moved = moved or (moved_wanted and abs(kc - self.kc[p]) * pen
                                      > 0.1 * self.noise_floor() * self.scene.force_scale)
                    self.kc[p] = kc
        self._kc_at = self._kc_key(q)
        return moved

    def _newton(self, q, idx, tol, max_iter, contacts):
        """One Newton-KKT solve at a fixed contact set: ``(converged, why, q)`` (the subclass's inner iteration)."""
        raise NotImplementedError

    def _reanchor(self, q) -> None:
        """Move every stick's anchors to its pair's current contact point."""
        m, sd = self.scene.model, self.st.d
        sd.qpos[:] = q
        mujoco.mj_kinematics(m, sd)
        self.kinematics_calls += 1
        ft = None
        for s in self.sticks:
            g = s.geoms[0]
            if self.friction_at == "centreline" and int(m.geom_type[g]) == _SPHERE:
                # (a sphere's centreline point is its centre, whatever the contact point: centreline_point's answer)
                s.reanchor(sd, np.array(sd.geom_xpos[g]))
                continue
            ft = np.zeros(6) if ft is None else ft
            mujoco.mj_geomDistance(m, sd, g, s.geoms[1], self.scene.length, ft)
            s.reanchor(sd, self._anchor(sd, g, 0.5 * (ft[:3] + ft[3:])))

    def _anchor(self, d, geom, point) -> np.ndarray:
        """Where the sticking friction acts: the contact ``point``, or (point contact) the finger's centreline there."""
        return centreline_point(self.scene.model, d, geom, point) if self.friction_at == "centreline" else point

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
        wg = set(map(int, sc.workpiece_geoms))
        con = sd.contact  # (one view of the contact arrays)
        geom1, geom2 = con.geom1[:sd.ncon].tolist(), con.geom2[:sd.ncon].tolist()
        for f in range(sc.fingers):
            mine = set(map(int, sc.contact_geoms[f]))
            best = None
            for i in range(sd.ncon):
                g1, g2 = geom1[i], geom2[i]
                if g1 in mine and g2 in wg:
                    fn = normal_force(m, sd, i)
                    if best is None or fn > best[0]:
                        best = (fn, i, g1, g2)
            if best is None:
                continue
            _, i, g1, g2 = best
            p = self._anchor(sd, g1, np.array(con.pos[i]))
            bf, bw = int(m.geom_bodyid[g1]), int(m.geom_bodyid[g2])
            n0, n1, n2 = con.frame[i][:3].tolist()
            # in-plane tangent: np.cross((0, 1, 0), normal) term by term (the same products and differences)
            t = np.array([1.0 * n2 - 0.0 * n1, 0.0 * n0 - 0.0 * n2, 0.0 * n1 - 1.0 * n0])
            tn = math.sqrt(float(t.dot(t)))  # (np.linalg.norm's own sqrt(t . t) of a 1-D float vector)
            if tn < 1e-6:  # out-of-plane normal (tip deep in the box): no planar stick
                continue
            t /= tn
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
        r = self.st.forces(q)
        if self.sticks:
            _, G = self.st.stick_rows(self.sticks)
            r = r + G.T @ self.friction_forces()
        return r / self.st.fscale


def read_newton(scene: Scene, run: Newton, t0: float, held: bool, converged: bool) -> SettledState:
    """The settled state of the static solve: MuJoCo's contacts plus the sticking friction forces."""
    if run.st.d is not scene.data:
        sync_scene(scene)  # (on the scene's own data the judge's call below brings it to the state)
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

    return read_state(scene, sd, held=held, method="newton", residual=float(np.abs(full).max()),
                      converged=converged, steps=run.iterations, newton_iterations=run.iterations,
                      forward_calls=run.st.calls, wall_time_s=time.perf_counter() - t0, friction=friction)
