"""Guarded steps of the full-contact dynamics: no point moves through a capsule between two steps.

MuJoCo sees a contact only once two geoms overlap (it has no speculative contact), so a step that moves a link
farther than the gap to another geom plus a capsule's radius may carry it through.  :class:`GuardedSteps`
undoes such a step and retries it with more damping.  The bound is measured, not assumed:

* the motion: every finger node's displacement in 3-D (the hinge chain's nodes ``sum_{i<k} ds (cos phi_i,
  sin phi_i)`` in the finger's vertical plane) and the workpiece's (its translation plus its turn times its
  largest half size);
* the clearance (:meth:`GuardedSteps.clearance`): a lower bound on the gap between capsules at least three links
  apart, capsules of different fingers, and a capsule and the workpiece (its exact signed distance: box,
  cylinder, sphere).

Each point may move ``(r_link + clearance) / 2``: two points closing on each other approach by at most the gap
plus ``r_link``, so capsules that were apart overlap by at most half their contact distance after the step,
and MuJoCo pushes them apart at the next.  Works on the planar :class:`~simgrip.sim.scene.Scene` (with
:class:`~simgrip.settle.integrator.Dyn`) and the K-finger :class:`~simgrip.gripper.scene.GripperScene` (with
:class:`FullGripperDynamics`); both expose a damping ``factor``.
"""

from __future__ import annotations

import math

import numpy as np

from simgrip.settle.dynamics import DYN_VTOL
from simgrip.settle.state import SettleError

__all__ = ["FULL_GUARD_GROWTH", "FULL_GUARD_MAX", "FULL_STEP_RADII", "GuardedSteps"]

#: Largest motion of a finger point in one step over ``r_link``, beyond half the clearance.
FULL_STEP_RADII = 0.5
#: Damping growth of a rejected step, and the largest damping factor tried.
FULL_GUARD_GROWTH = 4.0
FULL_GUARD_MAX = 4.0 ** 8


class GuardedSteps:
    """Physics steps of ``dyn`` (a ``Dyn`` or :class:`FullGripperDynamics`) bounded as the module says."""

    def __init__(self, scene, dyn):
        self.scene, self.dyn = scene, dyn
        self.q = np.asarray(scene.joint_qpos)
        F, n1 = scene.fingers, scene.n + 1
        if hasattr(scene, "azimuths"):  # K fingers, each in its vertical plane at azimuth a_k
            a = np.asarray(scene.azimuths, dtype=float)
            self.axes = np.stack([np.cos(a), np.sin(a), np.zeros(F)], axis=1)
            self.shape, self.half = scene.workpiece, np.asarray(scene.size, dtype=float)
            self.wq = np.asarray(scene.workpiece_qpos, dtype=int)
            self.free = True
        else:
            self.axes = np.stack([np.asarray(scene.mirror, float), np.zeros(F), np.zeros(F)], axis=1)
            self.shape, self.half = "box", np.asarray(scene.box_half, dtype=float)
            self.wq = np.asarray(scene.workpiece_qpos, dtype=int)
            self.names = tuple(scene.workpiece_joints)
            self.free = False
        self.body_pos = (np.array(scene.model.body_pos[scene.workpiece_body], dtype=float)
                         if scene.workpiece_body >= 0 else np.zeros(3))
        f_of = np.repeat(np.arange(F), n1)
        k_of = np.tile(np.arange(n1), F)
        # node pairs the clearance leaves out: one finger's nodes fewer than 2 apart (links 1 and 2 apart)
        self.near = (f_of[:, None] == f_of[None, :]) & (np.abs(k_of[:, None] - k_of[None, :]) < 2)
        # and two fingers' nodes next to their common clamp (their first links are excluded from contact)
        self.near |= (f_of[:, None] != f_of[None, :]) & (k_of[:, None] + k_of[None, :] <= 1)
        self.rejected = 0
        self.limit = FULL_STEP_RADII * scene.r_link * scene.length
        self.last = 0.0  # the last accepted step's motion [m]

    # -- geometry ------------------------------------------------------------------------------------------
    def nodes(self, qpos) -> np.ndarray:
        """Every finger's nodes ``(fingers, n + 1, 3)`` [m] in the world from the hinge angles in ``qpos``."""
        phi = np.cumsum(qpos[self.q], axis=1)
        ds = self.scene.length / self.scene.n
        X = np.concatenate([np.zeros((phi.shape[0], 1)), np.cumsum(ds * np.cos(phi), axis=1)], axis=1)
        Z = np.concatenate([np.zeros((phi.shape[0], 1)), np.cumsum(ds * np.sin(phi), axis=1)], axis=1)
        return X[..., None] * self.axes[:, None, :] + Z[..., None] * np.array([0.0, 0.0, 1.0])

    def pose(self, qpos) -> tuple[np.ndarray, np.ndarray]:
        """The workpiece's centre [m] and rotation matrix at ``qpos``."""
        if self.free:
            c = np.array(qpos[self.wq[:3]], dtype=float)
            w, x, y, z = (float(v) for v in qpos[self.wq[3:7]])
            R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                          [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                          [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
            return c, R
        c, ang = self.body_pos.copy(), 0.0
        for name, a in zip(self.names, self.wq):
            if name == "x":
                c[0] += float(qpos[a])
            elif name == "z":
                c[2] += float(qpos[a])
            else:  # ry: a hinge about y
                ang = float(qpos[a])
        ca, sa = math.cos(ang), math.sin(ang)
        return c, np.array([[ca, 0.0, sa], [0.0, 1.0, 0.0], [-sa, 0.0, ca]])

    def workpiece_distance(self, pts, qpos) -> np.ndarray:
        """Signed distance [m] of the points ``pts`` (..., 3) to the workpiece's surface (negative inside)."""
        c, R = self.pose(qpos)
        p = (pts - c) @ R  # in the body frame
        h = self.half
        if self.shape == "sphere":
            return np.linalg.norm(p, axis=-1) - h[0]
        if self.shape == "cylinder":  # axis along the body's z, radius h[0], half height h[1]
            dr = np.hypot(p[..., 0], p[..., 1]) - h[0]
            dz = np.abs(p[..., 2]) - h[1]
            return np.hypot(np.maximum(dr, 0.0), np.maximum(dz, 0.0)) + np.minimum(np.maximum(dr, dz), 0.0)
        q = np.abs(p) - h
        return np.linalg.norm(np.maximum(q, 0.0), axis=-1) + np.minimum(q.max(axis=-1), 0.0)

    def clearance(self, nodes, qpos) -> float:
        """A lower bound [m] on the gap between capsules that may touch (see the module docstring).

        Every point of a link lies within ``ds / 2`` of one of its end nodes, so links whose nodes are at least
        ``D`` apart have capsules at least ``D - ds - 2 r_link`` apart, and a link whose nodes are ``D`` from the
        workpiece is ``D - ds/2 - r_link`` from it (signed distances are 1-Lipschitz).  Links one and two apart
        on one finger are left out: MuJoCo filters parent and child, and links two apart cannot touch while the
        two hinges between them turn by less than ``pi/2``
        (:func:`~simgrip.sim.full_contact.next_but_one_separated`); where a hinge turns more, the bound is 0.
        """
        sc = self.scene
        ds, r = sc.length / sc.n, sc.r_link * sc.length
        if np.any(np.abs(qpos[self.q][:, 1:]) >= 0.5 * math.pi):
            return 0.0
        pts = nodes.reshape(-1, 3)
        dist = np.linalg.norm(pts[:, None, :] - pts[None, :, :], axis=-1)
        dist[self.near] = math.inf
        gap = float(dist.min()) - ds - 2.0 * r
        if sc.workpiece_body >= 0:
            gap = min(gap, float(self.workpiece_distance(pts, qpos).min()) - 0.5 * ds - r)
        return max(0.0, gap)

    def moved(self, q0, nodes0) -> float:
        """Largest displacement [m] of a finger node since ``q0`` (nodes ``nodes0``) plus the workpiece's."""
        d = self.dyn.d
        out = float(np.max(np.linalg.norm(self.nodes(d.qpos) - nodes0, axis=-1)))
        if self.scene.workpiece_body >= 0 and self.wq.size:
            c0, R0 = self.pose(q0)
            c1, R1 = self.pose(d.qpos)
            turn = math.acos(max(-1.0, min(1.0, 0.5 * (float(np.trace(R0.T @ R1)) - 1.0))))
            out += float(np.linalg.norm(c1 - c0)) + turn * float(np.linalg.norm(self.half))
        return out

    # -- stepping ------------------------------------------------------------------------------------------
    def step(self) -> None:
        """One accepted physics step (retried with the damping times :data:`FULL_GUARD_GROWTH` while it moves
        farther than the bound; the factor halves after each accepted step)."""
        dyn, d = self.dyn, self.dyn.d
        q0, v0, t0 = d.qpos.copy(), d.qvel.copy(), d.time
        nodes0 = self.nodes(q0)
        self.limit = FULL_STEP_RADII * self.scene.r_link * self.scene.length + 0.5 * self.clearance(nodes0, q0)
        while True:
            dyn.step()
            self.last = self.moved(q0, nodes0)
            if self.last <= self.limit or dyn.factor >= FULL_GUARD_MAX:
                break
            d.qpos[:], d.qvel[:], d.time = q0, v0, t0
            self.rejected += 1
            dyn.factor *= FULL_GUARD_GROWTH
        if dyn.factor > 1.0:
            dyn.factor = max(1.0, 0.5 * dyn.factor)

    def run(self, tol: float, budget: int, watch=None, vtol: float = DYN_VTOL) -> tuple[bool, str]:
        """Step until the velocity is below ``vtol`` and MuJoCo's static residual below ``tol``
        (:func:`~simgrip.settle.integrator.run_to_rest`'s test, one guarded step at a time)."""
        dyn = self.dyn
        while True:
            if dyn.velocity() < vtol:
                r = dyn.residual()
                if not math.isfinite(r):
                    raise SettleError("full-contact settle diverged (non-finite residual)")
                if r < tol:
                    return True, "ok"
            if watch is not None:
                why = watch()
                if why:
                    return False, why
            if dyn.steps >= budget:
                return False, "max_steps"
            self.step()
