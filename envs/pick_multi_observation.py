"""The K-finger pick environment's observation, contact forces and reward terms.

:func:`multi_obs_layout` names the observation's blocks and
:class:`MultiObservation` turns a MuJoCo state into the observation vector of
:class:`simgrip.envs.pick_multi.PickMultiEnv` (its docstring's table says what
each entry means), in the conventions of the two-finger pick
(:mod:`simgrip.envs.pick_observation`): lengths over the finger length,
velocities in lengths per second, curvatures in action units, forces as
``log(1 + F/W)``, every entry clipped to its bound.
:class:`WorkpieceContactForces` sums each finger's contact forces on the
workpiece; :func:`multi_reward` is Pick-v1's reward
(:func:`simgrip.envs.pick_reward.pick_reward`) with the squeeze term averaged
over ``K`` fingers and the least holding force per finger ``m g / (K mu)``.
"""

from __future__ import annotations

import math
from itertools import accumulate

import numpy as np

from simgrip.envs.pick_observation import SPIN_TIME, finger_bounds

__all__ = ["MultiObservation", "MultiReward", "WorkpieceContactForces", "multi_obs_layout", "multi_reward"]


def multi_obs_layout(fingers: int, shape_points: int = 8, shared_curvature: bool = True) -> list[tuple[str, int]]:
    """``(name, size)`` of the observation's blocks, in order (see :class:`~simgrip.envs.pick_multi.PickMultiEnv`)."""
    K = int(fingers)
    nk = 1 if shared_curvature else K
    return [
        ("palm_height", 1),
        ("kappa_command", nk),
        ("kappa_actual", nk),
        ("finger_shape", K * shape_points),
        ("tip_position", 2 * K),
        ("workpiece_position", 3),
        ("workpiece_tilt", 2),
        ("workpiece_velocity", 3),
        ("workpiece_spin", 3),
        ("workpiece_lift", 1),
        ("contact_force", 2 * K),
        ("hold", 1),
    ]


class WorkpieceContactForces:
    """Forces of the workpiece on each of ``K`` fingers [N], read from a MuJoCo state.

    With elliptic friction cones (the pick models') a contact's constraint rows
    in ``data.efc_force`` are its contact-frame force (normal, tangent 1,
    tangent 2, ...) and are read directly.  It runs on every environment step: the contacts' geom pairs are read
    always (one ``tolist``), the constraint forces, addresses and normals only once a workpiece-finger contact is
    found.

    Parameters
    ----------
    fingers : int
    work_geom : int
        Geom id of the workpiece.
    finger_of_geom : array of int
        For each geom of the model, the finger it belongs to, or -1.
    """

    def __init__(self, fingers: int, work_geom: int, finger_of_geom):
        self.K = int(fingers)
        self.work_geom = int(work_geom)
        self._fog = np.asarray(finger_of_geom).tolist()

    def __call__(self, data) -> tuple[list, list, list]:
        """``(normal, friction, side)``, each a list of ``K`` forces [N]: per finger the sum of its contacts'
        normal forces, of their friction magnitudes, and of the normal forces' horizontal (squeezing) components."""
        K = self.K
        normal, friction, side = [0.0] * K, [0.0] * K, [0.0] * K
        if data.ncon == 0:
            return normal, friction, side
        fog, wg = self._fog, self.work_geom
        con = data.contact
        ef = None
        for i, (g1, g2) in enumerate(con.geom.tolist()):
            f = fog[g2] if g1 == wg else (fog[g1] if g2 == wg else -1)
            if f < 0:
                continue
            if ef is None:  # the first workpiece-finger contact: the rest is read once, for all contacts
                adrs = con.efc_address.tolist()
                nx, ny = con.frame[:, 0].tolist(), con.frame[:, 1].tolist()  # the contact normals' x and y
                ef = data.efc_force.tolist()
            adr = adrs[i]
            if adr < 0:
                continue
            fn = ef[adr]
            normal[f] += fn
            friction[f] += math.hypot(ef[adr + 1], ef[adr + 2])
            side[f] += fn * math.hypot(nx[i], ny[i])
        return normal, friction, side


def _numpy_sum(x: list) -> float:
    """``sum(x)`` in the order of numpy's pairwise summation of a contiguous row of ``4 <= len(x) <= 64`` (four
    partial sums over blocks of four, combined pairwise, then the remainder, then added to the reduction's 0),
    so that a Python sum equals ``np.add.reduce`` to the last bit (the tips' ``np.exp(1j theta).sum(axis=1)``
    before issue 18; ``tests/test_env_step_reference.py`` holds the observation to it)."""
    n = len(x)
    r0, r1, r2, r3 = x[0], x[1], x[2], x[3]
    m = n - n % 4
    for i in range(4, m, 4):
        r0 += x[i]
        r1 += x[i + 1]
        r2 += x[i + 2]
        r3 += x[i + 3]
    total = (r0 + r1) + (r2 + r3)
    for i in range(m, n):
        total += x[i]
    return 0.0 + total


class MultiObservation:
    """Turns the state of a K-finger pick model into the environment's observation vector.

    Parameters
    ----------
    fingers, n_links, shape_points, shared_curvature, kappa_range, length, target_height, hold_time
        As :class:`~simgrip.envs.pick_multi.PickMultiEnv`'s arguments (SI units).
    force_unit : float
        Forces are observed as ``log(1 + F / force_unit)`` [N].
    palm_qpos, palm_dof, work_qpos, work_dof : int
        Addresses of the palm slide and the workpiece's free joint.
    hinge_qpos : index
        qpos index of the fingers' hinges, finger 0 first (``K * n_links``).

    Attributes
    ----------
    layout, slices, low, high
        ``(name, size)`` blocks, their slices and the bounds of the observation.
    """

    def __init__(self, *, fingers, n_links, shape_points, shared_curvature, kappa_range, length, target_height,
                 hold_time, force_unit, palm_qpos, palm_dof, work_qpos, work_dof, hinge_qpos):
        self.K, self.n, self.P = int(fingers), int(n_links), int(shape_points)
        self.layout = multi_obs_layout(self.K, self.P, shared_curvature)
        lo, hi = kappa_range
        bounds = {**finger_bounds(kappa_range), "workpiece_position": (-10, 10), "workpiece_tilt": (-1, 1),
                  "workpiece_velocity": (-100, 100), "workpiece_spin": (-100, 100), "workpiece_lift": (-20, 20)}
        self.slices, lows, highs = {}, [], []
        for name, size in self.layout:
            self.slices[name] = slice(len(lows), len(lows) + size)
            lows += [bounds[name][0]] * size
            highs += [bounds[name][1]] * size
        self.low, self.high = np.array(lows, dtype=np.float64), np.array(highs, dtype=np.float64)
        self.kappa_range = (float(lo), float(hi))
        self.inv_l = 1.0 / length
        self.target_height, self.hold_time, self.force_unit = target_height, hold_time, force_unit
        self.palm_qpos, self.palm_dof = palm_qpos, palm_dof
        self.work_qpos, self.work_dof = work_qpos, work_dof
        self._ds = 1.0 / self.n  # link length over l
        self.hinge_qpos = hinge_qpos
        # shape sampling: tangent angles at s/l = (k+1/2)/P, interpolated between link midpoints, from the
        # link angles (cumulative hinge angles), as the two-finger observation
        n, P = self.n, self.P
        s_link = (np.arange(n) + 0.5) / n
        s_k = (np.arange(P) + 0.5) / P
        interp = np.array([np.interp(s_k, s_link, e) for e in np.eye(n)]).T  # link angles -> theta(s_k)
        self._interp_t = np.ascontiguousarray(interp.T)
        self._k_scale = (2.0 / (hi - lo), -2.0 * lo / (hi - lo) - 1.0)  # curvature -> action units
        self._shape_start = self.slices["finger_shape"].start
        self._tip_start = self.slices["tip_position"].start
        self._tail_start = self.slices["workpiece_position"].start
        self._low_l, self._high_l = self.low.tolist(), self.high.tolist()
        # the fingers' hinges in qpos: a slice (the builder's contiguous block) or a list of addresses
        self._hq = hinge_qpos if isinstance(hinge_qpos, slice) else np.asarray(hinge_qpos).ravel().tolist()
        self._python_tips = 4 <= n <= 64  # _numpy_sum's range (else numpy sums the tips, as it always did)

    def __call__(self, data, forces, kappa_cmd, kappa, z0: float, hold: float) -> np.ndarray:
        """The observation of ``data``: ``forces`` are :class:`WorkpieceContactForces`' ``(normal, friction,
        side)``; ``kappa_cmd``, ``kappa`` the commanded and actual curvatures (arrays of 1 or K); ``z0`` the
        workpiece's starting height [m]; ``hold`` the time held at the target [s]."""
        return self.observe(data.qpos, data.qpos.tolist(), data.qvel.tolist(), np.asarray(kappa_cmd, float).tolist(),
                            np.asarray(kappa, float).tolist(), forces, z0, hold)

    def observe(self, qpos, q: list, v: list, kappa_cmd, kappa, forces, z0: float, hold: float) -> np.ndarray:
        """The observation from values already read (the environment's step): ``qpos`` the array
        ``data.qpos`` (the fingers' block is read from it), ``q``, ``v`` its and ``data.qvel``'s lists,
        ``kappa_cmd``, ``kappa`` sequences of floats; the rest as :meth:`__call__`."""
        # everything from qpos / qvel (after the step; MuJoCo's xpos / xmat are those before its last
        # integration), on Python floats but for the shape samples' product, clipped in Python, one array at the end
        # (issue 18: right after the physics every numpy call costs several microseconds)
        inv_l, K, n = self.inv_l, self.K, self.n
        palm_z, palm_v = q[self.palm_qpos], v[self.palm_dof]
        wq, wd = self.work_qpos, self.work_dof
        # header: palm height, curvature command and actual curvature in action units
        a, b = self._k_scale
        vals = [palm_z * inv_l]
        vals += [a * k + b for k in kappa_cmd]
        vals += [a * k + b for k in kappa]
        if self._python_tips:
            # link angles (cumulative hinge angles, np.cumsum's order); the shape samples by one product (BLAS, as
            # before); the tips by the chain's forward kinematics in each finger's plane, X + iZ = ds sum exp(i theta),
            # in Python floats summed in numpy's order (_numpy_sum)
            hq = self._hq
            qh = q[hq] if type(hq) is slice else [q[j] for j in hq]
            theta = [list(accumulate(qh[f * n:(f + 1) * n])) for f in range(K)]
            vals += np.dot(np.array(theta), self._interp_t).ravel().tolist()
            ds, cos, sin = self._ds, math.cos, math.sin
            for c in theta:
                vals += [_numpy_sum([cos(t) for t in c]) * ds, _numpy_sum([sin(t) for t in c]) * ds]
        else:
            theta = np.cumsum(qpos[self.hinge_qpos].reshape(K, n), axis=1)
            vals += np.dot(theta, self._interp_t).ravel().tolist()
            tip = np.exp(1j * theta).sum(axis=1) * self._ds
            for X, Z in zip(tip.real.tolist(), tip.imag.tolist()):
                vals += [X, Z]
        x, y, z, qw, qx, qy, qz = q[wq:wq + 7]
        vx, vy, vz, wx, wy, wz = v[wd:wd + 6]
        # rotation matrix of the unit quaternion (qw, qx, qy, qz); the free joint's angular velocity is in
        # the body frame: turned into the world frame
        r00, r01, r02 = 1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qw * qz), 2 * (qx * qz + qw * qy)
        r10, r11, r12 = 2 * (qx * qy + qw * qz), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qw * qx)
        r20, r21, r22 = 2 * (qx * qz - qw * qy), 2 * (qy * qz + qw * qx), 1 - 2 * (qx * qx + qy * qy)
        st = SPIN_TIME
        vals += [x * inv_l, y * inv_l, (z - palm_z) * inv_l, r02, r12,
                 vx * inv_l, vy * inv_l, (vz - palm_v) * inv_l,
                 (r00 * wx + r01 * wy + r02 * wz) * st, (r10 * wx + r11 * wy + r12 * wz) * st,
                 (r20 * wx + r21 * wy + r22 * wz) * st, (z - z0) / self.target_height]
        fu = self.force_unit
        normal, friction, _ = forces
        log1p = math.log1p
        for fn, ff in zip(normal, friction):
            vals += [log1p(max(fn, 0.0) / fu), log1p(max(ff, 0.0) / fu)]
        vals.append(min(hold / self.hold_time, 1.0) if self.hold_time > 0 else 0.0)
        # clipped to the bounds in Python (np.maximum / np.minimum's results for finite values), one array
        return np.array([lo_ if x < lo_ else (hi_ if x > hi_ else x) for x, lo_, hi_ in zip(vals, self._low_l, self._high_l)])


class MultiReward:
    """One episode's reward for ``K`` fingers: :func:`multi_reward` with the weights and the workpiece's
    constants bound once (made per episode, called every step; the same arithmetic).

    Parameters
    ----------
    fingers : int
        ``K``.
    mass, g, friction, w_lift, w_success, w_squeeze, w_drop, squeeze_margin
        As :func:`multi_reward`.
    """

    __slots__ = ("K", "w_lift", "w_success", "w_squeeze", "w_drop", "weight", "allow")

    def __init__(self, *, fingers: int, mass: float, g: float, friction: float, w_lift: float, w_success: float,
                 w_squeeze: float, w_drop: float, squeeze_margin: float):
        self.K = int(fingers)
        self.w_lift, self.w_success, self.w_squeeze, self.w_drop = w_lift, w_success, w_squeeze, w_drop
        self.weight = mass * g
        self.allow = squeeze_margin * self.weight / (self.K * friction)

    def __call__(self, phi: float, phi_prev: float, success: bool, lost: bool, side_forces) -> tuple:
        """``(reward, lift, success, squeeze, drop)`` of one step (arguments as :func:`multi_reward`'s)."""
        weight, allow = self.weight, self.allow
        xs = [max(s - allow, 0.0) / weight for s in side_forces]
        r_squeeze = -self.w_squeeze * sum(x / (1.0 + x) for x in xs) / self.K
        r_lift = self.w_lift * (phi - phi_prev)
        r_success = self.w_success if success else 0.0
        r_drop = -self.w_drop if lost else 0.0
        return r_lift + r_success + r_squeeze + r_drop, r_lift, r_success, r_squeeze, r_drop


def multi_reward(*, phi: float, phi_prev: float, success: bool, lost: bool, side_forces, mass: float, g: float,
                 friction: float, w_lift: float, w_success: float, w_squeeze: float, w_drop: float,
                 squeeze_margin: float) -> tuple[float, dict]:
    """One step's reward and its terms (``reward_lift``, ``reward_success``, ``reward_squeeze``, ``reward_drop``).

    As :func:`simgrip.envs.pick_reward.pick_reward` with ``K = len(side_forces)`` fingers: the squeeze term is
    ``-w_squeeze * mean_f x_f / (1 + x_f)``, ``x_f = max(0, S_f - squeeze_margin * m g / (K mu)) / (m g)``
    (``S_f`` finger ``f``'s horizontal normal force [N]); for ``K = 2`` the two agree.
    """
    K = len(side_forces)
    weight = mass * g
    allow = squeeze_margin * weight / (K * friction)
    xs = [max(s - allow, 0.0) / weight for s in side_forces]
    r_squeeze = -w_squeeze * sum(x / (1.0 + x) for x in xs) / K
    r_lift = w_lift * (phi - phi_prev)
    r_success = w_success if success else 0.0
    r_drop = -w_drop if lost else 0.0
    return r_lift + r_success + r_squeeze + r_drop, {
        "reward_lift": r_lift, "reward_success": r_success, "reward_squeeze": r_squeeze, "reward_drop": r_drop}
