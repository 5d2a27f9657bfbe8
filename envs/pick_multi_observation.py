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
        if data.ncon == 0:  # (measured: the MuJoCo reads below cost less after this one, issue 18)
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
                frames = con.frame.tolist()  # each contact's frame, its normal (x, y, z) first: one read
                ef = data.efc_force.tolist()
            adr = adrs[i]
            if adr < 0:
                continue
            fn = ef[adr]
            normal[f] += fn
            friction[f] += math.hypot(ef[adr + 1], ef[adr + 2])
            frame = frames[i]
            side[f] += fn * math.hypot(frame[0], frame[1])  # the normal's horizontal part
        return normal, friction, side


_accumulate = np.add.accumulate


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


def _sum_source(n: int) -> str:
    """:func:`_numpy_sum`'s additions over the names ``x0 .. x{n-1}`` written out, as one expression."""
    m = n - n % 4
    xs = [f"x{i}" for i in range(n)]
    total = "(({}) + ({})) + (({}) + ({}))".format(*(" + ".join(xs[j:m:4]) for j in range(4)))
    for i in range(m, n):
        total = f"({total}) + {xs[i]}"
    return total


def _check_links(n: int) -> None:
    if not 4 <= n <= 64:
        raise ValueError(f"n must lie in [4, 64] (numpy's pairwise block), got {n!r}")


def _tip_function(n: int):
    """``tip(c, ds) -> [X, Z]``: ``[_numpy_sum(cos c) * ds, _numpy_sum(sin c) * ds]`` for the ``n`` link angles
    ``c`` (``4 <= n <= 64``), compiled once per ``n`` with :func:`_numpy_sum`'s additions written out (the same
    operations in the same order: equal to the last bit, ``tests/test_pick_multi.py``), without its loops and
    lists (issue 18: the K-finger observation runs on every step)."""
    _check_links(n)
    total, names = _sum_source(n), ", ".join(f"x{i}" for i in range(n))
    src = (f"def tip(c, ds, cos=math.cos, sin=math.sin):\n    {names}, = map(cos, c)\n    X = 0.0 + ({total})\n"
           f"    {names}, = map(sin, c)\n    return [X * ds, (0.0 + ({total})) * ds]\n")
    scope = {"math": math}
    exec(compile(src, f"<pick_multi_observation tip n={n}>", "exec"), scope)  # noqa: S102 - our own source
    return scope["tip"]


def _tips_function(n: int, fingers: int):
    """``tips(shapes, rows, ds) -> [*shapes[0], ..., *shapes[K-1], X_0, Z_0, X_1, Z_1, ...]``: the ``fingers``
    rows of ``shapes`` (the shape samples) flattened, then :func:`_tip_function`'s ``tip(c, ds)`` of each of the
    ``fingers`` rows of link angles ``rows`` (each a sequence of ``n`` angles), the same operations in the same
    order, in one compiled call (issue 18: one call per step instead of ``K`` and the lists between them)."""
    _check_links(n)
    K = int(fingers)
    if K < 1:
        raise ValueError(f"fingers must be a positive integer, got {fingers!r}")
    total, names = _sum_source(n), ", ".join(f"x{i}" for i in range(n))
    body = "".join(f"    {names}, = map(cos, c{f})\n    X{f} = 0.0 + ({total})\n"
                   f"    {names}, = map(sin, c{f})\n    Z{f} = 0.0 + ({total})\n" for f in range(K))
    rows = ", ".join(f"c{f}" for f in range(K))
    heads = ", ".join(f"h{f}" for f in range(K))
    out = ", ".join([f"*h{f}" for f in range(K)] + [f"X{f} * ds, Z{f} * ds" for f in range(K)])
    src = (f"def tips(shapes, rows, ds, cos=math.cos, sin=math.sin):\n    {heads}, = shapes\n    {rows}, = rows\n"
           f"{body}    return [{out}]\n")
    scope = {"math": math}
    exec(compile(src, f"<pick_multi_observation tips n={n} K={K}>", "exec"), scope)  # noqa: S102 - our own source
    return scope["tips"]


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

    #: clip by comparisons only when every entry is inside its bound (:meth:`observe`; False: clip every entry,
    #: the same values, for tests)
    _fast_clip = True

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
        # the tilt's index in the list of the shape, tip, workpiece and lift entries (observe)
        self._tilt_at = self.slices["workpiece_tilt"].start - self.slices["finger_shape"].start
        # the shape samples' count and bound [rad] (observe's second comparison-only case)
        self._n_shape = self.K * self.P
        self._shape_lo, self._shape_hi = (float(x) for x in bounds["finger_shape"])
        self._low_l, self._high_l = self.low.tolist(), self.high.tolist()
        self._python_tips = 4 <= n <= 64  # _numpy_sum's range (else numpy sums the tips, as it always did)
        self._tips = _tips_function(n, self.K) if self._python_tips else None
        self._qpos = self._hinge_view = None  # observe's view of the hinges and the qpos array it views

    def __getstate__(self):
        # the compiled tips function and the view of one MjData's qpos are made again (__setstate__, observe)
        state = self.__dict__.copy()
        state["_tips"] = state["_qpos"] = state["_hinge_view"] = None
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._tips = _tips_function(self.n, self.K) if self._python_tips else None

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
        # header: curvature command and actual curvature in action units
        a, b = self._k_scale
        if len(kappa_cmd) == 1:  # one shared command (the default): the comprehensions below, written out
            kk = [a * kappa_cmd[0] + b, a * kappa[0] + b]
        else:
            kk = [a * k + b for k in kappa_cmd]
            kk += [a * k + b for k in kappa]
        if self._python_tips:
            # link angles (cumulative hinge angles: np.cumsum, sequential as itertools.accumulate was); the shape
            # samples by one product (BLAS, as before); the tips by the chain's forward kinematics in each finger's
            # plane, X + iZ = ds sum exp(i theta), in Python floats summed in numpy's order (_numpy_sum, _tip)
            if qpos is not self._qpos:  # the (K, n) view of the hinges, bound once per data (qpos is one array)
                self._qpos, self._hinge_view = qpos, qpos[self.hinge_qpos].reshape(K, n)
            theta = _accumulate(self._hinge_view, 1)  # np.cumsum(..., axis=1) without its wrapper
            mid = self._tips(np.dot(theta, self._interp_t).tolist(), theta.tolist(), self._ds)
        else:
            theta = np.cumsum(qpos[self.hinge_qpos].reshape(K, n), axis=1)
            mid = np.dot(theta, self._interp_t).ravel().tolist()
            tip = np.exp(1j * theta).sum(axis=1) * self._ds
            for X, Z in zip(tip.real.tolist(), tip.imag.tolist()):
                mid += [X, Z]
        x, y, z, qw, qx, qy, qz = q[wq:wq + 7]
        vx, vy, vz, wx, wy, wz = v[wd:wd + 6]
        # rotation matrix of the unit quaternion (qw, qx, qy, qz); the free joint's angular velocity is in
        # the body frame: turned into the world frame
        r00, r01, r02 = 1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qw * qz), 2 * (qx * qz + qw * qy)
        r10, r11, r12 = 2 * (qx * qy + qw * qz), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qw * qx)
        r20, r21, r22 = 2 * (qx * qz - qw * qy), 2 * (qy * qz + qw * qx), 1 - 2 * (qx * qx + qy * qy)
        st = SPIN_TIME
        mid += [x * inv_l, y * inv_l, (z - palm_z) * inv_l, r02, r12,
                vx * inv_l, vy * inv_l, (vz - palm_v) * inv_l,
                (r00 * wx + r01 * wy + r02 * wz) * st, (r10 * wx + r11 * wy + r12 * wz) * st,
                (r20 * wx + r21 * wy + r22 * wz) * st, (z - z0) / self.target_height]
        fu = self.force_unit
        normal, friction, _ = forces
        log1p = math.log1p
        fl = []
        for fn, ff in zip(normal, friction):  # max(f, 0.0), written out
            fl += [log1p((0.0 if 0.0 > fn else fn) / fu), log1p((0.0 if 0.0 > ff else ff) / fu)]
        p = palm_z * inv_l
        hold_obs = min(hold / self.hold_time, 1.0) if self.hold_time > 0 else 0.0  # in [0, 1] (hold >= 0)
        # the usual case, clipped by comparisons only (identity inside the bounds): the shape, tip, position,
        # velocity, spin and lift entries (bounds +-5 or wider) within +-5, the tilt within +-1, the curvatures
        # within +-2 (their bounds: +-2 or wider), the palm height in [0, 10], the forces at most 20 (at least 0:
        # log1p of a quotient >= 0; a NaN stays NaN either way).  Else every entry is clipped to its bound, as
        # always (np.maximum / np.minimum's results for finite values; _fast_clip False: always)
        t0 = self._tilt_at
        if (self._fast_clip and -5.0 <= min(mid) and max(mid) <= 5.0 and -1.0 <= mid[t0] <= 1.0
                and -1.0 <= mid[t0 + 1] <= 1.0 and -2.0 <= min(kk) and max(kk) <= 2.0 and 0.0 <= p <= 10.0
                and max(fl) <= 20.0):
            return np.array([p, *kk, *mid, *fl, hold_obs])
        vals = [p, *kk, *mid, *fl, hold_obs]
        # next the curled fingers' case (a claw's shape samples beyond -5 rad): the same test with the shape samples
        # against their own bound, still identity inside the bounds
        S = self._n_shape
        shape, rest = mid[:S], mid[S:]
        if (self._fast_clip and self._shape_lo <= min(shape) and max(shape) <= self._shape_hi and -5.0 <= min(rest)
                and max(rest) <= 5.0 and -1.0 <= mid[t0] <= 1.0 and -1.0 <= mid[t0 + 1] <= 1.0 and -2.0 <= min(kk)
                and max(kk) <= 2.0 and 0.0 <= p <= 10.0 and max(fl) <= 20.0):
            return np.array(vals)
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
        # sum of x / (1 + x), x = max(s - allow, 0) / weight, per finger, as multi_reward: max written out (it keeps
        # its first argument unless 0.0 > it) and the sum as sum's own float loop (from 0.0, in order)
        total = 0.0
        for s in side_forces:
            x = s - allow
            x = (0.0 if 0.0 > x else x) / weight
            total += x / (1.0 + x)
        r_squeeze = -self.w_squeeze * total / self.K
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
