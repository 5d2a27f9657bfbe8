r"""``simgrip/PlaceFragile-v0``: pinch a fragile workpiece, carry it to a target and set it down (issue 18).

:class:`FragilePlaceEnv` is :class:`~simgrip.envs.pick_fragile.FragilePickEnv` (Grip I pinch, the
per-episode mass, friction, width and crush limit, see :mod:`simgrip.envs.pick_fragile`) whose palm also
slides along ``x`` on a second stiff, critically damped position servo (``palm_x``, the same gains as the
vertical one).  Per episode a target ``x_t`` is drawn: ``|x_t|`` uniform in ``target_range = (0.04, 0.10)``
m, its side (``+x`` or ``-x``) uniform.

Action ``Box(-1, 1, (3,))``: ``(curvature command, palm x velocity, palm z velocity)``; the velocities are
``a * palm_speed`` (0.1 m/s) integrated into the servo targets (``x`` kept within ``+-x_range = 0.15`` m).

Observation: ``PickFragile-v0``'s 19 entries (fingertip ``x`` now relative to the palm; ``box_lift`` in units
of ``carry_height``; ``hold`` the time the workpiece has rested at the target over ``place_time``) and two
more, in finger lengths: ``workpiece_x`` (the workpiece's centre ``x`` relative to the palm) and
``target_x`` (the target's ``x`` relative to the palm).  Hidden as before: mass, friction, crush limit.

Success (terminates): the workpiece was carried (at least ``carry_height = 0.03`` m above its start, both
fingers on it), and now rests on the table (less than 3 mm above its start) within ``place_tolerance =
0.01`` m of ``x_t`` for ``place_time = 0.3`` s, never crushed or dropped.  Failures as
``PickFragile-v0``: crushed, dropped (sank ``drop_distance`` relative to the palm once lifted), knocked over
(tilted, or pushed more than 3 cm relative to the palm).  Time limit at registration 400 steps (8 s).

Reward: ``PickFragile-v0``'s terms with the lift paid up to ``carry_height`` (and taken back when it is set
down), plus ``w_place (psi_t - psi_{t-1})`` with ``psi = 1 - min(1, |x - x_t| / |x_t - x_0|)`` once carried
(0 once lost), plus ``w_success = 30`` once.  A success returns at least ``w_place + w_success - squeeze``
(> 30), hovering at the target at most ``w_lift + w_place = 20``.

Info keys: ``is_success``, ``workpiece_lift`` [m], ``crushed``, ``dropped`` (the table of
:mod:`simgrip.envs.pick_fragile`) plus ``place_error`` (``|x - x_t|`` [m]), ``carried``, ``reward_place``,
``target_x`` [m], and the rest of that table and of its parent's: ``knocked_over``, ``normal_force``,
``friction_force``, ``side_force``, ``hold_time``, ``crush_limit``, ``reward_crush``, ``reward_lift``,
``reward_success``, ``reward_squeeze``, ``reward_drop``, ``valid`` (checked as in :mod:`simgrip.envs.pick_fragile`: every 25 steps and at every episode end).  Reset options: ``PickFragile-v0``'s and ``target_x`` [m].
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import mujoco
import numpy as np
from gymnasium import spaces

from simgrip.envs.arguments import check_number as _num
from simgrip.envs.arguments import check_positive as _pos
from simgrip.envs.arguments import check_range as _range
from simgrip.envs.pick_contacts import BoxContactForces
from simgrip.envs.pick_fragile import FragilePickEnv
from simgrip.envs.palm_servo import add_palm_servo, palm_command
from simgrip.envs.pick_model import PALM_MASS
from simgrip.envs.pick_validity import FingerValidity
from simgrip.sim.fingers import index_fingers

__all__ = ["FragilePlaceEnv"]

#: [m] resting on the table: less than this above its start
ON_TABLE = 0.003
_EXTRA = (("workpiece_x", 1), ("target_x", 1))


class FragilePlaceEnv(FragilePickEnv):
    """Pick-and-place of a fragile workpiece (``simgrip/PlaceFragile-v0``); see :mod:`simgrip.envs.pick_place`
    (``info["is_success"]``, ``info["workpiece_lift"]``, ``info["crushed"]``, ``info["dropped"]``)."""

    _final_check = False  # the place success is declared in step below, and checked there

    _PARENT_OPTIONS = FragilePickEnv._PARENT_OPTIONS

    def __init__(self, *, target_range=(0.04, 0.10), x_range: float = 0.15, carry_height: float = 0.03,
                 place_tolerance: float = 0.01, place_time: float = 0.3, w_place: float = 10.0,
                 w_success: float = 30.0, **kwargs):
        for bad in ("grip", "target_height", "hold_time", "per_finger"):
            if bad in kwargs:
                raise ValueError(f"{bad} is fixed in the pick-and-place task (use carry_height, place_time)")
        self.x_range = _pos("x_range", x_range)
        self.target_range = _range("target_range", target_range, hi=self.x_range)
        self.carry_height = _pos("carry_height", carry_height)
        self.place_tolerance = _pos("place_tolerance", place_tolerance)
        self.place_time = _pos("place_time", place_time)
        self.w_place = _num("w_place", w_place, positive=False)
        # the parent's own success (lift and hold) never fires: its hold time is out of reach
        super().__init__(grip="I", target_height=self.carry_height, hold_time=1e9, w_success=w_success, **kwargs)
        self.action_space = spaces.Box(-1.0, 1.0, (3,), dtype=np.float32)
        self._action_shape = (3,)
        self.action_names = ("curvature", "palm_x", "palm_z")
        n0 = self.observation_space.shape[0]
        low = np.concatenate([self.observation_space.low, [-10.0, -10.0]])
        high = np.concatenate([self.observation_space.high, [10.0, 10.0]])
        self.observation_space = spaces.Box(low, high, dtype=np.float64)
        self.obs_layout = (*tuple(self.obs_layout), *_EXTRA)
        self.obs_slices = {**self.obs_slices, "workpiece_x": slice(n0, n0 + 1), "target_x": slice(n0 + 1, n0 + 2)}
        self._tip_x = self.obs_slices["tip_position"].start
        self._hold_i = self.obs_slices["hold"].start
        self.target_x = self.target_range[0]
        self._place_state(0.0)

    # ------------------------------------------------------------------ model
    def _build(self):
        """``PickEnv``'s model with a horizontal palm slide ``palm_x`` and its servo, addresses looked up again."""
        super()._build()
        spec = self.spec
        palm = spec.body("palm")
        palm.add_joint(name="palm_x", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0])
        moving = PALM_MASS + 2 * self.rho * self.length + self.box_mass_range[1]
        add_palm_servo(spec, "palm_x_servo", "palm_x", moving, ramp=self.palm_ramp, lo=-self.x_range, hi=self.x_range)
        model = spec.compile()
        self.model, self.data = model, mujoco.MjData(model)
        self._palm = palm_command(self, model)
        self._palm_x = palm_command(self, model, 1, -self.x_range, self.x_range)
        self._bind_touch()  # (crush_at "peak": the touch sensors' reader for this model)

        def joint(name):
            return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)

        self.fingers = fingers = index_fingers(model, 2, self.n, "hand_")
        self._validity = FingerValidity(model, fingers)
        palm_z = joint("palm_z")
        self.palm_qpos, self.palm_dof = int(model.jnt_qposadr[palm_z]), int(model.jnt_dofadr[palm_z])
        self._palm_x_qpos = int(model.jnt_qposadr[joint("palm_x")])
        box = joint("box_free")
        self.box_qpos, self.box_dof = int(model.jnt_qposadr[box]), int(model.jnt_dofadr[box])
        self._spring_idx = fingers.joint_qpos.ravel()
        self._fq = (fingers.hinge_qpos,) if fingers.hinge_qpos is not None else (fingers.joint_qpos,)
        self._contact_forces = BoxContactForces(model, self.box_geom, fingers.finger_of_geom)

    # ------------------------------------------------------------------ episode
    def _place_state(self, x0: float):
        self._x0 = x0
        self._carried = False
        self._place_hold = 0.0
        self._psi = 0.0

    def _extend(self, obs) -> np.ndarray:
        # on Python floats, one array at the end (np.clip's values for finite entries)
        q = self.data.qpos
        px, bx = float(q[self._palm_x_qpos]), float(q[self.box_qpos])
        inv_l = 1.0 / self.length
        vals = np.asarray(obs, dtype=np.float64).tolist()
        vals[self._tip_x] -= px * inv_l
        vals[self._hold_i] = min(self._place_hold / self.place_time, 1.0)
        for x in ((bx - px) * inv_l, (self.target_x - px) * inv_l):
            vals.append(-10.0 if x < -10.0 else (10.0 if x > 10.0 else x))
        return np.array(vals)

    def reset(self, *, seed=None, options=None):
        target = None
        if isinstance(options, Mapping) and "target_x" in options:
            options = dict(options)
            target = options.pop("target_x")
            ok = not isinstance(target, (bool, np.bool_)) and isinstance(target, (int, float, np.number))
            if not ok or not math.isfinite(float(target)) or abs(float(target)) > self.x_range:
                raise ValueError(f"target_x must be a number within +-x_range = {self.x_range} m, got {target!r}")
            target = float(target)
        obs, info = super().reset(seed=seed, options=options)
        rng = self.np_random
        side = 1.0 if rng.uniform() < 0.5 else -1.0
        self.target_x = side * float(rng.uniform(*self.target_range)) if target is None else target
        self._place_state(float(self.data.qpos[self.box_qpos]))
        self._palm_x.reset(self.data, 0.0)  # (held at x = 0 through the settle: the servo's target and ctrl at 0)
        self._dxy = (self._xy0[0], self._xy0[1])  # the box's start relative to the palm (palm at x = 0)
        info["target_x"] = self.target_x
        return self._extend(obs), info

    def _step_checked(self, a: list):
        d = self.data
        self._palm_x.command(d.ctrl, a[1])  # held or ramped, as the vertical slide (envs.palm_servo)
        if not self._needs_reset:  # the knock-over rule's "pushed 3 cm" follows the palm
            self._xy0 = (float(d.qpos[self._palm_x_qpos]) + self._dxy[0], self._dxy[1])
        obs, reward, terminated, truncated, info = super()._step_checked(a)
        q = d.qpos
        bx, gain = float(q[self.box_qpos]), float(q[self.box_qpos + 2]) - self._z0
        both = min(self._normal) > 0.0  # info["normal_force"], as floats
        lost = terminated  # the parent ends an episode only on a loss here (its own success never fires)
        if gain >= self.carry_height and both:
            self._carried = True
        err = abs(bx - self.target_x)
        placed = self._carried and err <= self.place_tolerance and gain < ON_TABLE and not lost
        self._place_hold = self._place_hold + self.dt if placed else 0.0
        success = self._place_hold >= self.place_time - 1e-9
        psi = 0.0 if lost or not self._carried else 1.0 - min(1.0, err / max(abs(self.target_x - self._x0), 1e-9))
        r_place = self.w_place * (psi - self._psi)
        self._psi = psi
        reward += r_place + (self.w_success if success else 0.0)
        if success:
            terminated = True
            self._needs_reset = True
        info.update({"is_success": success, "reward_place": r_place,
                     "reward_success": self.w_success if success else 0.0, "place_error": err,
                     "carried": self._carried, "target_x": self.target_x})
        reward += self._final_validity(info, terminated)  # a success in an impossible state is taken back
        return self._extend(obs), reward, terminated, truncated, info
