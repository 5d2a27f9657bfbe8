"""Newton-KKT in the chain's own coordinates: ``O(n)`` per iteration, exact Jacobian.

Same equations, contact set, friction bookkeeping and acceptance as
:class:`~simgrip.settle.newton.Newton` (which it extends), but the inner Newton
iteration runs on :class:`~simgrip.settle.chain_model.ChainModel`: the forces
and their exact Jacobian in link angles (tridiagonal), bordered by the
workpiece dof, the contact and stick rows and the auxiliary unknowns of the
low-rank constraint curvature, solved by :func:`~simgrip.settle.banded.solve_bordered`.
Two fingers stack their link angles into one tridiagonal (no coupling between
the fingers) and share the border: the workpiece's ``x, z, ry`` and both
fingers' contact and stick rows.
Contact rows are ``dist + N / K_c = 0`` (length units); the line search and
the convergence test use the residual in MuJoCo's dofs (hinge moments are
suffix sums of the link-angle forces).  ``K_c`` is MuJoCo's, read back at each
accepted state; it moves with the configuration (~3e-6 relative over the
first step of a Grip I start, enough to put the contact row ~1e3 times above
its floor), so a quadratic-phase step is followed by a chord step with its own
Jacobian (:meth:`ChainNewton._chord`) rather than a whole second iteration.

MuJoCo stays the judge: the contact set is MuJoCo's (``mj_geomDistance``),
``K_c`` is read back from MuJoCo's contact force at each converged solve, and
the reported residual is MuJoCo's force balance at the final state.  Without
contacts that balance is evaluated in ``O(n)`` (``mj_passive`` and ``mj_rne``
at rest: springs and gravity are all there is) so that nothing in a free-rod
settle costs more than ``O(n)``.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from simgrip.settle.banded import _ALL, _ANY, _MAX, _ONES, lstsq_vector, solve_bordered
from simgrip.settle.chain_model import ChainModel, eligible
from simgrip.settle.newton import FLOOR_ULPS, PEN_MAX, Newton
from simgrip.settle.pinch import evaluators
from simgrip.settle.state import SettleError
from simgrip.settle.statics import angle_floor
from simgrip.sim.scene import Scene

__all__ = ["ChainNewton"]

#: Newton iterations one solve may take (exact Jacobian: a solve needing more is failing, e.g. a
#: workpiece falling with no equilibrium to reach).
CHAIN_SOLVE_ITERS = 60
#: The analytic contact rows are polished to this many ulps of ``K_c l`` when one step gets there.
CHAIN_FLOOR_ULPS = 2.0
#: A full Newton step that cut the scaled residual at least this much (quadratic convergence: the Jacobian hardly
#: changed over it) is followed by a chord step for MuJoCo's ``K_c`` read back at the new state (:meth:`_chord`).
CHORD_GAIN = 1e-3
#: ... and only when ``K_c`` moved by at most this (relative) over the step: the chord's Jacobian carries the old
#: compliance ``1 / K_c`` on the contact rows, so it leaves about this fraction of its correction.  A smooth move
#: is ~3e-6 over a cold Grip I start's step; a contact that changes shape jumps (8 % measured in a warm sweep at
#: ``kappa_bar = -7``, where a chord left 1/30 of the residual and the full Newton step was needed anyway).
CHORD_KC_RTOL = 1e-4


def _norm(x) -> float:
    """``float(np.linalg.norm(x))`` of a 1-D float array: the same ``sqrt(x . x)`` without its argument handling."""
    return math.sqrt(float(x.dot(x)))


def _positions_only(m) -> bool:
    """:func:`~simgrip.settle.statics.sync_scene` computes positions only (no contact pairs, or contacts off)."""
    return m.npair == 0 or bool(int(m.opt.disableflags) & int(mujoco.mjtDisableBit.mjDSBL_CONTACT))


class ChainNewton(Newton):
    """:class:`Newton` with the inner iteration in link angles (one- and two-finger scenes, see ``eligible``)."""

    def __init__(self, scene: Scene):
        if not eligible(scene):
            raise ValueError(f"scene: the chain Newton covers workpieces fixed, sliding in z or free in x, z, ry "
                             f"with finger 0 along +x; got joints {tuple(scene.workpiece_joints)}")
        super().__init__(scene, scene.data)  # the scene's own MjData as scratch (the solve owns its state)
        self.model = ChainModel(scene)
        self._ev = evaluators(self.model)  # (nodes, internal, pair_term, stick_term: pinch.py's for one finger)
        #: MuJoCo's contact distance minus the analytic one (round-off, over l), per pair
        self.dist_shift = np.zeros(len(self.pairs))
        self._memo = {}  # the state's geometry within one inner solve (_at)
        self._judged = None  # (positions key, q, scaled MuJoCo residual) of a start :meth:`solve` found at rest

    def _update_kc(self, q, at=None, moved_wanted: bool = True) -> bool:
        """Read MuJoCo's contact stiffness and its contact distances' round-off at ``q``.

        ``at``: the inner solve's state ``(phi, w)`` whose :meth:`ChainModel.join` is ``q``; the round-off
        (``dist_shift``) is then MuJoCo's distance at ``q`` less the analytic one at that very state, the one
        the contact rows evaluate (and its distances, :meth:`_distances`, are computed once).  Without it the
        analytic distance is evaluated at ``split(q)``.
        """
        mark, self._stick_mark = getattr(self, "_stick_mark", None), None
        self._forces_ready = mark is not None and self._stick_mark_holds(mark, q)
        moved = super()._update_kc(q, moved_wanted)  # MuJoCo's balance at q is now in the scratch data
        sd, cm = self.st.d, self.model
        self._inverse_mark = (self.st.calls, sd.efc_force.tobytes())  # (full_residual's reuse of this evaluation)
        if at is not None:
            da = self._distances(*at)
        else:
            phi, w = cm.split(q)
            da = cm.pair_distances(phi, cm.nodes(phi), w)
        lows = self._kc_low  # (each pair's least contact distance at q, as Newton._update_kc read it)
        for p in self.normal_active:
            if p in lows:
                self.dist_shift[p] = lows[p] / self.scene.length - da[p]
        return moved  # (Newton._update_kc's key at q covers the round-off too: Newton.solve reads q once)

    def stick_now(self) -> int:
        """:meth:`Newton.stick_now`, remembering its MuJoCo evaluation (:meth:`_stick_mark_holds`)."""
        out = super().stick_now()
        d = self.st.d
        self._stick_mark = (self.st.calls, self.kinematics_calls, d.qpos.tobytes(), d.efc_force.tobytes(),
                            self._kc_key(d.qpos)[3:] if d is self.scene.data else None)  # (the model's part)
        return out

    def _stick_mark_holds(self, mark, q) -> bool:
        """The data holds :meth:`stick_now`'s ``mj_inverse``, made at ``q`` with today's model, untouched since (counts
        of evaluations and kinematics, state and constraint forces the same bits): ``forces(q)`` would repeat it."""
        d = self.st.d
        if d is not self.scene.data or mark[4] is None or mark[0] != self.st.calls or mark[1] != self.kinematics_calls:
            return False
        qb = np.asarray(q, dtype=float).tobytes()
        return (qb == mark[2] and d.qpos.tobytes() == qb and d.efc_force.tobytes() == mark[3]
                and not _ANY(d.qvel) and not _ANY(d.qacc) and self._kc_key(q)[3:] == mark[4])

    # -- MuJoCo's balance without the O(n^3) mass matrix when there is no contact ------------
    def _contacts_active(self) -> bool:
        return self._contacts_on() if hasattr(self, "_flags") else bool(self.pairs)

    def rest_forces(self, q) -> np.ndarray:
        """MuJoCo's static imbalance at ``q`` (dimensional); ``O(n)`` when contacts are off."""
        m = self.scene.model
        off = int(m.opt.disableflags) & int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
        if self.pairs and not off:
            return self.st.forces(q)
        d = self.st.d
        d.qpos[:] = q
        d.qvel[:] = 0.0
        d.qfrc_applied[:] = self.scene.data.qfrc_applied
        current = self.positions_current()  # (the settle's last _commit computed them at this very state)
        if not current:
            mujoco.mj_kinematics(m, d)
            mujoco.mj_comPos(m, d)
        mujoco.mj_passive(m, d)
        mujoco.mj_rne(m, d, 0, d.qfrc_bias)
        self.st.calls += 1
        self._positions_at = self._positions_key() if d is self.scene.data else None
        return d.qfrc_applied + d.qfrc_passive - d.qfrc_bias

    def full_residual(self, q) -> np.ndarray:
        m = self.scene.model
        if self.pairs and not (int(m.opt.disableflags) & int(mujoco.mjtDisableBit.mjDSBL_CONTACT)):
            if self._inverse_current(q):
                # the solve's last K_c read (mj_inverse) at this very state, still in the data: not made twice
                d = self.st.d
                r = d.qfrc_applied - d.qfrc_inverse
                if self.sticks:
                    _, G = self.st.stick_rows(self.sticks)
                    r = r + G.T @ self.friction_forces()
                return r / self.st.fscale
            return super().full_residual(q)
        judged, self._judged = self._judged, None
        if (judged is not None and judged[0] == self._positions_key() and np.array_equal(judged[1], q)
                and judged[3] == self._balance_inputs()):
            return judged[2]  # (solve's own judgement at this very state: the same MuJoCo calls, not made twice)
        return self.rest_forces(q) / self.st.fscale

    # -- a contact-free state that is already at rest: judged once ---------------------------
    def solve(self, tol: float, max_iter: int, *, frozen=(), at_rest: bool = False) -> tuple[bool, str]:
        """:meth:`Newton.solve`; ``at_rest``: the caller has just put a contact-free scene at the hinge chain's
        equilibrium (:func:`~simgrip.settle.closing.start_free`), so MuJoCo alone judges it first.

        Without contacts or sticks, and with the workpiece (if any) frozen, the inner Newton's first test
        is whether the analytic residual at the start is below ``tol`` (or the angles' round-off floor);
        then it takes no step and commits ``join(split(q))``.  That state's MuJoCo residual (``O(n)``:
        :meth:`rest_forces`) is what the settle's judge reports; evaluated first, it decides the same
        way (the analytic and MuJoCo balances are the same equations, apart in round-off) and the judge
        reuses it.  Otherwise (not at rest, contacts on, not finite) the Newton solve runs as ever.  A free
        rod so settles with one ``mj_passive`` and ``mj_rne`` (issue 19: its fixed cost).
        """
        if at_rest and self._at_rest(tol, frozen):
            return True, "ok"
        return super().solve(tol, max_iter, frozen=frozen)

    def _at_rest(self, tol: float, frozen) -> bool:
        sc = self.scene
        m, d = sc.model, sc.data
        flags = int(m.opt.disableflags)
        if (self.pairs and not flags & int(mujoco.mjtDisableBit.mjDSBL_CONTACT)) or self.sticks or self.st.d is not d:
            return False
        cm = self.model
        fz = {int(j) for j in frozen}
        if any(int(j) not in fz for j in cm.wd):
            return False  # a free workpiece dof: its weight is a row the solve must take
        self._flags = flags
        self.normal_active, self.N = [], np.zeros(0)
        q = d.qpos.copy()
        phi, w = cm.split(q)
        qq = cm.join(q, phi, w)  # the state the inner solve would commit
        r = self.rest_forces(qq) / self.st.fscale  # (leaves d at qq, at rest, its positions computed)
        free = np.ones(m.nv, bool)
        free[list(fz)] = False
        rf = r[free]
        res = float(np.abs(rf).max()) if rf.size else 0.0
        if not math.isfinite(res) or not (res < tol or res < angle_floor(sc, qq)):
            return False
        self._judged = (self._positions_key(), qq, r, self._balance_inputs())
        return True

    def _inverse_current(self, q) -> bool:
        """The data holds the last ``K_c`` read's ``mj_inverse`` at ``q``, today's model (:meth:`_kc_current`), no
        evaluation since (count; constraint forces the same bits), positions computed at ``q`` (:meth:`_commit`)."""
        mark, done = getattr(self, "_inverse_mark", None), getattr(self, "_committed", None)
        d = self.st.d
        if mark is None or done is None or d is not self.scene.data or mark[0] != self.st.calls:
            return False
        q = np.asarray(q, dtype=float)
        if done[0] != self.kinematics_calls or done[1] != q.tobytes() or d.qpos.tobytes() != done[1]:
            return False
        return self._kc_current(q) and mark[1] == d.efc_force.tobytes() and not _ANY(d.qvel) and not _ANY(d.qacc)

    def _balance_inputs(self) -> tuple:
        """What MuJoCo's balance at rest reads besides the positions: rest angles, stiffness, gravity and the
        applied forces (a judgement is reused only while they are unchanged)."""
        m = self.scene.model
        return (m.qpos_spring.tobytes(), m.jnt_stiffness.tobytes(), m.opt.gravity.tobytes(), int(m.opt.disableflags),
                self.scene.data.qfrc_applied.tobytes())

    def _commit(self, q) -> None:
        """Leave the scene's data at ``q`` at rest, its positions computed (``mj_kinematics``, ``mj_comPos``).

        Not ``mj_forward`` (``O(n^3)`` in the serial chain's dense mass matrix: ~2 ms at ``n = 256``): its
        contacts and constraint forces would be read by nothing.  Every reader of forces evaluates MuJoCo at
        the state itself (:meth:`Statics.forces`: ``stick_now``, the judge's :meth:`full_residual`) and the
        settle ends with :func:`~simgrip.settle.statics.sync_scene`; ``mj_forward`` leaves ``qacc_warmstart``
        as it finds it, so that last sync gives the data it gave after an ``mj_forward`` here.
        """
        d = self.scene.data
        d.qpos[:] = q
        d.qvel[:] = 0.0
        m = self.scene.model
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        self._committed = (self.kinematics_calls, d.qpos.tobytes())  # (positions at this q: _inverse_current)
        # a contact-free scene's sync is these two: remembered, for the judge's balance and the settle's last sync
        self._positions_at = self._positions_key() if self.st.d is d and _positions_only(m) else None

    def _positions_key(self) -> tuple:
        """What the positions (``mj_kinematics``, ``mj_comPos``) of the scene's data depend on: its ``qpos``, the
        model's body frames and whether contacts are off (a contact-free scene's sync computes only them)."""
        m, d = self.scene.model, self.scene.data
        # (the counts of the solve's own MuJoCo evaluations: any evaluation since, at whatever state, invalidates)
        return (d.qpos.tobytes(), m.body_pos.tobytes(), m.body_quat.tobytes(), self.st.calls, self.kinematics_calls,
                _positions_only(m))

    def positions_current(self) -> bool:
        """The scene's data holds ``mj_kinematics`` and ``mj_comPos`` of its current ``qpos`` (computed by this
        solve on a contact-free scene, nothing they depend on changed since), and a sync would compute only
        them: :func:`~simgrip.settle.statics.sync_scene` would recompute the same numbers."""
        at = getattr(self, "_positions_at", None)
        return at is not None and self.st.d is self.scene.data and at == self._positions_key() and at[-1]

    # -- the analytic residual ------------------------------------------------------------
    def _system(self, phi, w, N, lam, stick_act, with_jacobian: bool):
        """Residual pieces (and the bordered Jacobian) at ``(phi, w)`` for the current sets."""
        cm = self.model
        n, yf = cm.n, self.yf
        nw = yf.size
        nodes = self._at("nodes", phi, w, self._ev[0], phi) if (self.normal_active or self.sticks) else None
        F, diag, off = self._at("internal", phi, w, self._ev[1], phi)
        Fw = self._fw  # (the workpiece's weight and applied force on its free dofs: fixed through a solve)
        act = self.normal_active
        pterms = [self._at(("pair", p), phi, w, self._ev[2], p, phi, nodes, w) for p in act]
        sterms = [self._stick_at(i, phi, w, nodes) for i in range(len(self.sticks))] if self.sticks else []
        mu = {i: float(self.scene.model.pair_friction[self._pair_of(s)][0]) for i, s in enumerate(self.sticks)
              if i in self.sliding} if self.sliding else {}  # (only the sliding sticks' friction enters)
        coef = []  # (term, multiplier) pairs of the force
        for k, t in enumerate(pterms):
            coef.append((t, N[k]))
        for j, i in enumerate(stick_act):
            coef.append((sterms[i], lam[j]))
        slide = []  # (stick term, index of its pair's N, sign mu)
        for i, sign in self.sliding.items():
            p = self._pair_of(self.sticks[i])
            if p in act:
                k = act.index(p)
                slide.append((sterms[i], k, sign * mu[i]))
                coef.append((sterms[i], sign * mu[i] * N[k]))
        for t, c in coef:
            F = F + c * t.grad[:n]
            Fw = Fw + c * t.grad[n:][yf]
        gn = np.array([t.value + self.dist_shift[p] + N[k] / self.kc_dl[p] for k, (t, p) in enumerate(zip(pterms, act))])
        gs = np.array([sterms[i].value for i in stick_act])
        R = np.concatenate([cm.to_q(F), Fw, gn, gs])
        self._parts = (F, Fw, gn, gs)  # (the last state's pieces in the Jacobian's rows: a chord step's right side)
        if not with_jacobian:
            return R, None
        # the Jacobian is assembled only when a step is taken (a converged state needs none)
        return R, lambda: self._jacobian(n, nw, diag, off, coef, pterms, sterms, slide, stick_act, act, F, Fw, gn, gs)

    def _jacobian(self, n, nw, diag, off, coef, pterms, sterms, slide, stick_act, act, F, Fw, gn, gs):
        """The bordered Jacobian of :meth:`_system` from its terms (``solve_bordered``'s arguments)."""
        yf = self.yf
        # border: [free workpiece dofs (nw), aux z (sum of ranks), N (len act), lambda (len stick_act)]
        for t, c in coef:
            diag = diag + c * t.diag
        ranks = [t.S.shape[0] for t, _ in coef]
        nz, nn, ns = sum(ranks), len(act), len(stick_act)
        k = nw + nz + nn + ns
        P = np.zeros((n, k))
        Q = np.zeros((k, n))
        E = np.zeros((k, k))
        col = nw
        for (t, c), r in zip(coef, ranks):
            if r:
                P[:, col:col + r] = c * t.U[:n]
                Q[col:col + r] = t.S @ t.U[:n].T
                E[col:col + r, col:col + r] = -np.eye(r)
                Uy = t.U[n:][yf]
                E[:nw, col:col + r] = c * Uy
                E[col:col + r, :nw] = t.S @ Uy.T
            col += r
        for j, t in enumerate(pterms):
            a = nw + nz + j
            P[:, a] = t.grad[:n]
            Q[a] = t.grad[:n]
            E[a, a] = 1.0 / self.kc_dl[act[j]]
            E[:nw, a] = t.grad[n:][yf]
            E[a, :nw] = t.grad[n:][yf]
        for t, kk, smu in slide:
            a = nw + nz + kk
            P[:, a] += smu * t.grad[:n]
            E[:nw, a] += smu * t.grad[n:][yf]
        for j, i in enumerate(stick_act):
            a = nw + nz + nn + j
            t = sterms[i]
            P[:, a] = t.grad[:n]
            Q[a] = t.grad[:n]
            E[:nw, a] = t.grad[n:][yf]
            E[a, :nw] = t.grad[n:][yf]
        rhs_phi = -F
        rhs_b = np.zeros(k)
        rhs_b[:nw] = -Fw
        rhs_b[nw + nz:nw + nz + nn] = -gn
        rhs_b[nw + nz + nn:] = -gs
        return diag, off, P, Q, E, rhs_phi, rhs_b, nz

    def _step(self, jac):
        diag, off, P, Q, E, r1, r2, nz = jac
        dphi, y = solve_bordered(diag, off, P, Q, E, r1, r2)
        nw = self.yf.size
        dw = np.zeros(self.model.nw)
        dw[self.yf] = y[:nw]
        nn = len(self.normal_active)
        return dphi, dw, y[nw + nz:nw + nz + nn], y[nw + nz + nn:]

    # -- the state's geometry, once per state ------------------------------------------------
    def _at(self, key, phi, w, fn, *args):
        """``fn(*args)`` computed once per state ``(phi, w)`` of an inner solve.

        A state's arrays are never written in place (every trial step builds new ones), so a
        result found at the very same objects (``is``) is the result ``fn`` would compute again,
        bit for bit; the one entry per ``key`` is the last state's.  Only what depends on the state
        and on what stays fixed through a solve is kept (nodes, spring and gravity forces, contact
        pair terms: not the stick terms, whose anchors move at every iteration); :meth:`_newton`
        starts each solve empty (the rest angles and contact set change between solves).
        """
        hit = self._memo.get(key)
        if hit is not None and hit[0] is phi and hit[1] is w:
            return hit[2]
        out = fn(*args)
        self._memo[key] = (phi, w, out)
        return out

    def _stick_at(self, i, phi, w, nodes):
        """Stick ``i``'s term at the state ``(phi, w)`` (:meth:`ChainModel.stick_term`), computed once per state and
        anchoring: a stick's anchors are replaced (new arrays, :meth:`Stick.reanchor`), never edited in place, so
        the same state with the same anchor arrays and offset gives the same term bit for bit."""
        s = self.sticks[i]
        anchors, values = (s.local_f, s.local_w, s.t_local), (s.offset, s.body_f, s.t_body)
        hit = self._memo.get(("stick", i))
        if (hit is not None and hit[0] is phi and hit[1] is w and hit[2][0] is anchors[0] and hit[2][1] is anchors[1]
                and hit[2][2] is anchors[2] and hit[3] == values):
            return hit[4]
        out = self._ev[3](s, phi, nodes, w)
        self._memo[("stick", i)] = (phi, w, anchors, values, out)
        return out

    def _distances(self, phi, w) -> np.ndarray:
        """Every pair's analytic signed distance at the state ``(phi, w)`` (:meth:`_at`)."""
        cm = self.model
        return self._at("dist", phi, w, cm.pair_distances, phi, self._at("nodes", phi, w, self._ev[0], phi), w)

    # -- Newton -------------------------------------------------------------------------
    def _newton(self, q, idx, tol, max_iter, contacts):
        sc = self.scene
        cm = self.model
        self._memo = {}
        free = set(np.asarray(idx, dtype=int).tolist())  # (the free dofs: only membership is read)
        self.yf = np.array([j for j, dof in enumerate(cm.wd.tolist()) if dof in free], dtype=int)  # free workpiece dofs
        self._fw = cm.workpiece_force()[self.yf]  # (read once a solve: _system adds to it, never in place)
        L, W = sc.length, sc.force_scale
        self.kc_dl = self.kc * L / W
        N = self.N.copy() / W
        stick_act = [i for i in range(len(self.sticks)) if i not in self.sliding]
        if self.lam.size != len(self.sticks):
            self.lam = np.zeros(len(self.sticks))
        lam = self.lam[stick_act].copy() / W
        phi, w = cm.split(q)
        nf = cm.n + self.yf.size
        def read_kc(ph, ww, at_q=None):  # MuJoCo's K_c at an accepted state (one mj_inverse; 'moved' not asked)
            if contacts and self.normal_active:
                self._update_kc(cm.join(q, ph, ww) if at_q is None else at_q, at=(ph, ww), moved_wanted=False)
                self.kc_dl = self.kc * L / W

        def stiffen(NN):  # a contact the forces would press deeper than PEN_STIFFEN: stiffer (Newton.stiffen)
            if contacts and self.stiffen(NN * W, grow_only=True):
                self.kc_dl = self.kc * L / W

        read_kc(phi, w, at_q=q)  # (at q itself, = join(split(q)) to round-off: stick_now's evaluation if current)
        anchored = False
        if (N.size and not _ALL(N)) or (lam.size and not _ALL(lam)):
            if self.sticks:  # (the first iteration's anchoring, done first: the estimate's stick terms are its)
                self._reanchor(cm.join(q, phi, w))
                anchored = True
            N, lam = self._estimate_multipliers(phi, w, N, lam, stick_act)
        stiffen(N)

        def state_q(ph, ww):
            return cm.join(q, ph, ww)

        def finish(conv, why, qq, NN, ll):
            self._memo = {}
            self.N = NN * W
            self.lam[stick_act] = ll * W
            return conv, why, qq

        polished = False
        dist_at = None  # (phi, w, pair distances) of the last accepted state
        max_iter = min(max_iter, self.iterations + CHAIN_SOLVE_ITERS)
        while True:
            if self.sticks and not anchored:
                self._reanchor(state_q(phi, w))
            anchored = False
            R, jacobian = self._system(phi, w, N, lam, stick_act, True)
            if not _ALL(np.isfinite(R)):
                self._memo = {}
                raise SettleError("settle diverged (non-finite residual)")
            res_f = float(_MAX(np.abs(R[:nf])))
            rows = self._row_scale(len(N), len(stick_act))  # (contact rows in force units: this state's K_c)
            res_c = float(_MAX(np.abs(R[nf:] * rows))) if R.size > nf else 0.0
            # (r < max(tol, floor), a floor evaluated only where tol does not decide; contact rows first)
            if (res_c < tol or res_c < self.noise_floor()) and (
                    res_f < tol or res_f < angle_floor(sc, state_q(phi, w))):
                # the analytic contact rows resolve ~1 ulp of K_c l, far below MuJoCo's distance
                # round-off (the floor): one more step when they are above a few ulps and improving
                if polished or res_c < tol or res_c < CHAIN_FLOOR_ULPS / FLOOR_ULPS * self.noise_floor():
                    break
                polished = True
            if contacts and self.yf.size and not self.normal_active and np.any(cm.workpiece_force()[self.yf] != 0.0):
                # a free workpiece with no contact left carries its weight alone: no equilibrium (a drop)
                return finish(False, "stalled", state_q(phi, w), N, lam)
            if self.iterations >= max_iter:
                if self.budget is not None and self.iterations >= self.budget:
                    return finish(False, f"Newton iteration budget max_steps={self.budget} spent", state_q(phi, w), N, lam)
                return finish(False, "max_iter", state_q(phi, w), N, lam)
            # (the acceptance's scaled residual: only a step needs it)
            scale = np.concatenate([np.ones(nf), rows])  # rows in force units
            res = float(_MAX(np.abs(R * scale))) if R.size else 0.0
            self.iterations += 1
            try:
                jac = jacobian()
                dphi, dw, dN, dl = self._step(jac)
            except (np.linalg.LinAlgError, ValueError):
                if polished:
                    break
                return finish(False, "stalled", state_q(phi, w), N, lam)
            merit = _norm(R)
            if contacts and dist_at is not None and dist_at[0] is phi and dist_at[1] is w:
                d0 = dist_at[2]  # computed at this very state when it was accepted
            else:
                d0 = self._distances(phi, w) if contacts else None
            inact = [p for p in range(len(self.pairs)) if p not in self.normal_active] if contacts else []
            step, accepted = 1.0, False
            for _ in range(50):
                ph, ww = phi + step * dphi, w + step * dw
                Nn, ln = N + step * dN, lam + step * dl
                Rn, _ = self._system(ph, ww, Nn, ln, stick_act, False)
                ok = bool(_ALL(np.isfinite(Rn)))
                if ok and inact:  # pairs not yet touching: no tunnelling (move at most half their gap)
                    dn = self._distances(ph, ww)
                    ok = all(dn[p] > -PEN_MAX or d0[p] <= 0 for p in inact) and all(
                        d0[p] - dn[p] <= max(0.5 * d0[p], 0.0) + PEN_MAX for p in inact if d0[p] > 0)
                mn = _norm(Rn) if ok else math.inf
                if ok and (mn < (1.0 - 1e-4 * step) * merit or (
                        float(_MAX(np.abs(Rn * scale))) < 0.5 * res and mn < max(2.0 * merit, 1e-3 * tol ** 0.5))):
                    accepted = True
                    break
                step *= 0.5
            if not accepted:
                if polished:  # already within the floor: the polishing step is round-off bound
                    break
                return finish(False, "stalled", state_q(phi, w), N, lam)
            phi, w, N, lam = ph, ww, Nn, ln
            kc_was, shift_was = self.kc_dl, self.dist_shift.copy()  # (read_kc replaces the one, edits the other)
            read_kc(phi, w)
            stiffen(N)
            chord = (contacts and step == 1.0 and not inact and self.friction_at == "centreline"
                     and self.iterations < max_iter and float(_MAX(np.abs(Rn * scale))) <= CHORD_GAIN * res)
            for last in (False, True):  # the step's state, then (at most once) the chord step's
                if contacts:  # a pair that starts touching joins the set at once
                    dn = self._distances(phi, w)
                    dist_at = (phi, w, dn)
                    newp = [p for p in range(len(self.pairs)) if p not in self.normal_active and dn[p] < 0.0]
                    if newp:
                        self.normal_active = self.normal_active + newp
                        N = np.append(N, np.zeros(len(newp)))
                        chord = False
                got = None if last or not chord else self._chord(jac, N, kc_was, shift_was)
                if got is None:
                    break
                phi, w, N, lam = phi + got[0], w + got[1], N + got[2], lam + got[3]
                read_kc(phi, w)
                stiffen(N)
        return finish(True, "ok", state_q(phi, w), N, lam)

    def _chord(self, jac, N, kc_was, shift_was):
        """A chord step after a quadratic-phase Newton step: MuJoCo's ``K_c`` and distance round-off read back at the
        new state; ``(dphi, dw, dN, dlambda)``, or None when they did not move (or the solve fails).

        ``K_c`` is MuJoCo's soft contact at rest read at each accepted state (:meth:`_update_kc`); it moves with the
        configuration (~1e-6 relative for a 1e-6 rad turn of a link: the contact's inverse inertia), and a
        Newton step that moved the state puts the contact rows ``dist + N / K_c`` off by that change alone.
        The step's Jacobian (``jac``, ``_jacobian``'s arguments) is the state's to the step's size: the
        residual of the step's state (the line search's pieces, the contact rows with the new ``K_c`` and
        distance shift) solved with it is Newton's next step up to ``O(|step|)`` relative, without assembling
        and factoring another bordered system or a line search.  The next iteration evaluates the state as
        ever (sticks re-anchored, full residual) and decides: converged, or another Newton step.  It counts
        as an iteration (budgets).  Taken only with the friction on the centreline (the point contact): there
        re-anchoring a stick keeps its constraint, while friction at the surface follows the rolling contact
        point, whose re-anchoring moves the friction's arm and needs the next Newton step anyway (measured:
        the chord then adds an iteration, the surface settles of Grips I/II take 6 instead of 4).
        """
        F, Fw, gn, gs = self._parts
        act = self.normal_active
        if len(act) != gn.size:
            return None
        ka = self.kc_dl[act]
        if not float(_MAX(np.abs(ka / kc_was[act] - 1.0))) <= CHORD_KC_RTOL:
            return None
        moved = (self.dist_shift[act] - shift_was[act]) + N * (1.0 / ka - 1.0 / kc_was[act])
        if float(_MAX(np.abs(moved * ka))) < CHAIN_FLOOR_ULPS / FLOOR_ULPS * self.noise_floor():
            return None  # (a move below the contact rows' polishing floor: the next test decides without it)
        diag, off, P, Q, E, _, _, nz = jac
        nw, nn = self.yf.size, len(act)
        rb = np.zeros(E.shape[0])
        rb[:nw] = -Fw
        rb[nw + nz:nw + nz + nn] = -(gn + moved)
        rb[nw + nz + nn:] = -gs
        self.iterations += 1
        try:
            out = self._step((diag, off, P, Q, E, -F, rb, nz))
        except (np.linalg.LinAlgError, ValueError):
            return None
        return out if _ALL(np.isfinite(np.concatenate(out))) else None  # (every piece finite)

    def _estimate_multipliers(self, phi, w, N, lam, stick_act):
        """Least-squares multipliers at a fixed state: ``min |F + G_n' N + G_s' lambda|`` (hinge rows in q).

        New contacts and sticks start at zero force; the first Newton step would
        otherwise spend itself on the whole load.  Normal forces are kept >= 0.
        """
        cm = self.model
        n, yf = cm.n, self.yf
        nodes = self._at("nodes", phi, w, self._ev[0], phi)
        F, _, _ = self._at("internal", phi, w, self._ev[1], phi)
        b = np.concatenate([cm.to_q(F), self._fw])  # (self._fw: workpiece_force()[yf], read at the solve's start)
        cols = [self._at(("pair", p), phi, w, self._ev[2], p, phi, nodes, w).grad for p in self.normal_active]
        cols += [self._stick_at(i, phi, w, nodes).grad for i in stick_act]
        if not cols:
            return N, lam
        G = np.empty((cols[0].size, len(cols)))  # (n + nw, columns): np.stack(cols, 1)'s values, written in
        for j, col in enumerate(cols):
            G[:, j] = col
        A = np.empty((n + yf.size, G.shape[1]))
        # every column's hinge rows at once: to_q's suffix sums run down each column in the same order
        A[:n] = G[:n].reshape(cm.fingers, cm.nl, -1)[:, ::-1].cumsum(axis=1)[:, ::-1].reshape(n, -1)
        A[n:] = G[n:][yf]
        # (lstsq, not the normal equations: their round-off flips the sign test of a zero multiplier, issue 19)
        x = lstsq_vector(A, -b, 1e-12)
        nn = len(self.normal_active)
        if not _ALL(np.isfinite(x)) or _ANY(x[:nn] < 0.0):
            return N, lam
        return x[:nn], x[nn:]

    def _row_scale(self, nn, ns) -> np.ndarray:
        """Contact rows (length units) -> force units ``K_c`` (the acceptance of :class:`Newton`)."""
        return np.concatenate((self.kc_dl[self.normal_active][:nn], _ONES[:ns] if ns <= 4 else np.ones(ns)))

