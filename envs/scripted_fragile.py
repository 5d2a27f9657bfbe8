"""Scripted controllers for the fragile pick tasks (:mod:`simgrip.envs.pick_fragile`).

Both close the fingers slowly while raising the palm slowly, so that the tips
slide up the workpiece's faces until the friction they carry exceeds its
weight and it follows the palm: at that moment the grip force is the least
that holds (``N_hold``).  They differ in how they stop the curvature:

* :class:`ObservationFragilePolicy` (observation only): it watches the
  workpiece's lift (``box_lift`` / ``workpiece_lift``, the workpiece's height
  gain, i.e. it no longer slips in the grip) and freezes the curvature
  command at the *actual* curvature then (the pneumatic lag would otherwise
  carry the force on), plus a margin ``margin`` times the curvature travelled
  since first contact (the force grows about linearly with curvature past the
  onset, so this adds about ``margin`` of the force).  Then it lifts.
* :class:`OracleFragilePolicy` (knows the hidden ``hold_force`` and
  ``crush_limit``): it reads the tactile normal force and freezes the
  curvature once the force reaches the window's geometric middle
  ``sqrt(N_hold N_crush)``, then lifts.

The pick-and-place task (valve ``PlaceFragile-v2``-``v4``): :class:`PlacePolicy` grips with
:class:`PlaceGripPolicy` (the same recipe paced for the pneumatic lag: slow near contact, closing by a fraction of
what is closed, a slower probe), carries and sets down, and follows the observed finger forces while carrying
(closes when the workpiece creeps down in the grip, eases above 1.4 times the force at the freeze).
:class:`AbsolutePlacePolicy` is the controller the retired absolute-command ``PlaceFragile-v0``/``-v1`` were
measured with.

The claw tasks (``PickCradleFragile-v0``, ``PickSphereFragile-v0``) start the same recipe from a claw:
:class:`CradleFragilePolicy` / :class:`SphereFragilePolicy` open the fingers and move the palm to a grasp
height read off the observed workpiece (the box's lower edge, or the sphere's centre, ``depth`` finger lengths
below the palm), close slowly while probing upwards, freeze on lift, and while lifting close a little more
whenever the workpiece slides down in the grip (its observed height relative to the palm);
:class:`OracleCradlePolicy` / :class:`OracleSpherePolicy` also ease the grip while the force is above the
hidden window's middle.  ``CLAW_POLICIES`` maps each task to its (oracle, observation-only) pair.

Observation indices are taken from the env's ``obs_slices`` (both envs), the
actions are ``(curvature command, palm speed)`` (one shared curvature).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["CLAW_POLICIES", "CradleFragilePolicy", "ObservationFragilePolicy", "OracleCradlePolicy",
           "OracleFragilePolicy", "OracleSpherePolicy", "PlaceGripPolicy", "PlacePolicy", "SphereFragilePolicy",
           "AbsolutePlacePolicy"]


#: the closing rate before first contact [action units a step]: the default, and on an env whose crush rule reads
#: the peak within the control step (``crush_at="peak"``, :mod:`simgrip.envs.touch_history`), where a faster first
#: touch's impact crushes light pieces: half of it, chosen on seeds 6100-6149 (``docs/environments.md``, "Forces
#: within a control step")
CLOSING_RATE, PEAK_CLOSING_RATE = 0.008, 0.004


class _Closing:
    """The shared recipe: close slowly while probing upwards, freeze the curvature on a trigger, lift, hold.

    ``rate``: the closing rate before first contact (None: :data:`CLOSING_RATE`, or :data:`PEAK_CLOSING_RATE` on an
    env with ``crush_at="peak"``, chosen at ``reset``)."""

    def __init__(self, *, start: float = 0.6, rate: float | None = None, rel_rate: float = 0.04,
                 min_rate: float = 0.002, probe_speed: float = 0.1, lift_speed: float = 1.0, lift_ramp: int = 10):
        self._rate = rate
        self.start, self.rel_rate, self.min_rate = start, rel_rate, min_rate
        self.rate = CLOSING_RATE if rate is None else rate
        self.probe_speed = probe_speed
        self.lift_speed, self.lift_ramp = lift_speed, lift_ramp

    def reset(self, env, info=None):
        u = env.unwrapped
        if self._rate is None:
            self.rate = PEAK_CLOSING_RATE if getattr(u, "crush_at", "end") == "peak" else CLOSING_RATE
        sl = u.obs_slices
        self._i_kact = sl["kappa_actual"].start
        self._i_lift = sl["box_lift" if "box_lift" in sl else "workpiece_lift"]
        self._i_force = sl["contact_force"]
        self._force_unit = float(u._force_unit)
        self._lift_unit = float(u.target_height)  # the observed lift is in units of the target height [m]
        # closing starts at `start`, or where a valve env already starts the command (a pre-grasp,
        # simgrip.envs.pick_fragile_v4; the v2/v3 valve starts straight, +1)
        self._cmd = min(self.start, getattr(u, "valve_command", self.start))
        self._frozen = None
        self._contact_at = None
        self._lift_steps = 0

    def _forces(self, obs) -> np.ndarray:
        """Per-finger normal forces [N] read from the observation's ``log(1 + F/W)`` (normal, friction pairs)."""
        f = np.asarray(obs[self._i_force])[0::2]
        return np.expm1(f) * self._force_unit

    def _trigger(self, obs) -> bool:  # pragma: no cover - defined by each policy
        raise NotImplementedError

    def _frozen_command(self, obs) -> float:
        return float(obs[self._i_kact])

    def __call__(self, obs):
        kact = float(obs[self._i_kact])
        touching = self._forces(obs).max() > 0.0
        if self._frozen is None:
            if touching and self._contact_at is None:
                self._contact_at = kact
                self._cmd = kact  # stop the lag from carrying the closing on
            if self._contact_at is not None and self._trigger(obs):
                self._frozen = self._frozen_command(obs)
            else:
                if self._contact_at is None:
                    step = self.rate
                else:  # the force grows about linearly past contact: close by a fraction of what is closed
                    step = max(self.min_rate, self.rel_rate * (self._contact_at - kact))
                self._cmd = max(self._cmd - step, -1.0)
                return np.array([self._cmd, self.probe_speed if self._contact_at is not None else 0.0],
                                dtype=np.float32)
        self._lift_steps += 1
        speed = max(self.probe_speed, self.lift_speed * min(1.0, self._lift_steps / self.lift_ramp))
        return np.array([self._frozen, speed], dtype=np.float32)


class ObservationFragilePolicy(_Closing):
    """Observation-only: freeze the curvature when the workpiece follows the palm (lift > ``lift_trigger`` [m]),
    at the actual curvature plus ``margin`` times the curvature closed since contact."""

    def __init__(self, *, margin: float = 0.1, lift_trigger: float = 0.0005, **kwargs):
        super().__init__(**kwargs)
        self.margin, self.lift_trigger = margin, lift_trigger

    def _trigger(self, obs) -> bool:
        return float(np.asarray(obs[self._i_lift]).ravel()[0]) * self._lift_unit > self.lift_trigger

    def _frozen_command(self, obs) -> float:
        kact = float(obs[self._i_kact])
        return max(kact - self.margin * max(self._contact_at - kact, 0.0), -1.0)


class OracleFragilePolicy(_Closing):
    """Knows the hidden window: freeze the curvature once the largest finger force reaches
    ``sqrt(hold_force * crush_limit)`` (read from the env at ``reset``)."""

    def __init__(self, *, probe_speed: float = 0.0, **kwargs):
        super().__init__(probe_speed=probe_speed, **kwargs)

    def reset(self, env, info=None):
        super().reset(env, info)
        u = env.unwrapped
        self._target = math.sqrt(u.hold_force * u.crush_limit)

    def _trigger(self, obs) -> bool:
        return self._forces(obs).max() >= self._target

    def _frozen_command(self, obs) -> float:
        return float(obs[self._i_kact])


class PlaceGripPolicy(ObservationFragilePolicy):
    """Observation-only grip for pick-and-place of a fragile workpiece (the first part of :class:`PlacePolicy`).

    :class:`ObservationFragilePolicy`'s recipe (close while probing upwards, freeze on lift plus a margin) with
    the closing paced so that the pneumatic lag (``kappa_tau`` = 0.1 s, 5 control steps) cannot carry the force
    through a light workpiece's window before the lift is seen:

    * approach: the command moves at ``fast_rate`` (action units per step) down to ``approach``, then at
      ``approach_rate`` until first contact (contact comes at an actual curvature of 0.48-0.59 over the width
      range 0.03-0.075 m: measured by a quasi-static closing at palm height 0.087 m).  At first contact the
      command is set back to the actual curvature (through a valve the command, ``5 approach_rate`` ahead of the
      actual, is brought back within a step);
    * after contact: the command moves by ``rel_rate`` times the curvature closed since contact per step (the
      force grows about linearly with it: about that relative force increase per step), at least ``min_rate``
      (a 5 g workpiece on grippy skin, ``N_hold`` = 0.02 N, holds at ~0.007 action units past contact: ~14
      steps at 0.0005) and at most ``max_rate`` (the valve's rate);
    * the palm probes upwards at ``probe_speed`` (0.05: 0.1 mm per step), half
      :class:`ObservationFragilePolicy`'s: a heavy workpiece's tips slide up its faces until it lifts, and at 0.1
      they reached its upper edge (dropped while carried);  the lift trigger ``lift_trigger`` [m] is one step of
      that probe (a workpiece that follows the palm is seen within a step or two);
    * the freeze: the actual curvature plus ``margin`` (0.05) of the curvature closed since contact (about 5 %
      more force; :class:`PlacePolicy` closes further when the workpiece creeps down in the grip).

    Tuned on seeds 6100-6199 of ``PlaceFragile-v3`` (checked on 6200-6249); figures in :class:`PlacePolicy`.
    """

    def __init__(self, *, approach: float = 0.66, fast_rate: float = 0.02, approach_rate: float = 0.0025,
                 min_rate: float = 0.0005, rel_rate: float = 0.08, max_rate: float = 0.02,
                 lift_trigger: float = 0.0001, margin: float = 0.05, probe_speed: float = 0.05, **kwargs):
        super().__init__(margin=margin, lift_trigger=lift_trigger, min_rate=min_rate, rel_rate=rel_rate,
                         probe_speed=probe_speed, **kwargs)
        self.approach, self.fast_rate, self.approach_rate = approach, fast_rate, approach_rate
        self.max_rate = max_rate

    def reset(self, env, info=None):
        super().reset(env, info)
        self._i_kcmd = env.unwrapped.obs_slices["kappa_command"].start
        self._cmd = None  # set from the first observation (the command where the env starts it)

    def __call__(self, obs):
        if self._cmd is None:
            self._cmd = float(obs[self._i_kcmd])
        if self._frozen is not None:
            return super().__call__(obs)
        kact = float(obs[self._i_kact])
        if self._contact_at is None and self._forces(obs).max() > 0.0:
            self._contact_at = kact
            self._cmd = kact  # brake: the lag would carry the closing on
        if self._contact_at is not None and self._trigger(obs):
            self._frozen = self._frozen_command(obs)
            return super().__call__(obs)
        if self._contact_at is None:
            step = self.fast_rate if self._cmd > self.approach else self.approach_rate
        else:
            step = min(max(self.min_rate, self.rel_rate * (self._contact_at - kact)), self.max_rate)
        self._cmd = max(self._cmd - step, -1.0)
        return np.array([self._cmd, self.probe_speed if self._contact_at is not None else 0.0], dtype=np.float32)


class _PlaceCarry:
    """The carry and set-down shared by :class:`PlacePolicy` (valve envs) and :class:`AbsolutePlacePolicy`; each
    defines ``_default_grip_policy()`` and ``_check_env(unwrapped_env)`` (refuses the other kind of env)."""

    _feedback = True  # follow the observed finger forces from the freeze on (ease / close on creep)
    _x_while_lifting = True  # the palm moves towards the target already while lifting

    def __init__(self, grip=None, *, ramp: float = 0.02, align: float = 0.003, lower_speed: float = 0.4,
                 down: float = 0.05, x_step: float = 0.05, slip_distance: float = 0.0015, slip_window: int = 10,
                 slip_frac: float | None = None, slip_cap: float = 0.3, ease: float = 1.4, ease_frac: float = 0.01):
        self.grip = self._default_grip_policy() if grip is None else grip
        self.ramp, self.align, self.lower_speed, self.down = ramp, align, lower_speed, down
        self.x_step = x_step  # the largest change of the palm's x command per step (its acceleration: inertial
        # loads m a press one finger harder, and a fragile workpiece's window is narrow)
        if slip_frac is None:  # an oracle grip freezes in the hidden window's middle: closing on creep crushes it
            slip_frac = 0.0 if isinstance(self.grip, OracleFragilePolicy) else 0.05
        self.slip_distance, self.slip_window, self.slip_frac, self.slip_cap = (slip_distance, slip_window,
                                                                               slip_frac, slip_cap)
        self.ease, self.ease_frac = ease, ease_frac

    def reset(self, env, info=None):
        u = env.unwrapped
        self._check_env(u)
        self.grip.reset(env, info)
        sl = u.obs_slices
        self._i_lift = sl["box_lift"].start
        self._i_wx, self._i_tx = sl["workpiece_x"].start, sl["target_x"].start
        self._i_wz = sl["box_position"].stop - 1
        self._length = float(u.length)
        self._phase = "grip"
        self._ax = 0.0
        self._slip_hist = []  # the workpiece's heights relative to the palm [m] over the last slip_window steps
        self._slipped = 0.0  # the fractions closed by _regrip so far
        self._n_freeze = None  # the largest finger force at the freeze [N]

    def _regrip(self, obs):
        """Close by ``slip_frac`` of the curvature closed since contact when the workpiece crept down in the grip by
        more than ``slip_distance`` over the last ``slip_window`` steps (at most ``slip_cap`` of it in all)."""
        g = self.grip
        hist = self._slip_hist
        hist.append(float(obs[self._i_wz]) * self._length)
        if len(hist) <= self.slip_window or self._phase == "rest" or g._contact_at is None:
            return
        del hist[0]
        if hist[-1] < hist[0] - self.slip_distance:
            closed = max(g._contact_at - g._frozen, 0.0)
            if self._slipped + self.slip_frac <= self.slip_cap + 1e-9:
                g._frozen = max(g._frozen - self.slip_frac * closed, -1.0)
                self._slipped += self.slip_frac
            hist.clear()

    def __call__(self, obs):
        a_k, a_z = (float(v) for v in self.grip(obs))
        if self.grip._frozen is None:
            return np.array([a_k, 0.0, a_z], dtype=np.float32)
        if self._feedback and self.slip_frac > 0.0:  # the force feedback (observation grips): ease, or close
            g = self.grip
            f = float(g._forces(obs).max())
            if self._n_freeze is None:
                self._n_freeze = f  # the largest finger force when the lift was seen: about N_hold [N]
            if f > self.ease * self._n_freeze and g._contact_at is not None:
                g._frozen = min(g._frozen + self.ease_frac * max(g._contact_at - g._frozen, 0.0), 1.0)
                self._slip_hist.clear()
            else:
                self._regrip(obs)
            a_k = g._frozen
        lift = float(obs[self._i_lift])  # in units of the carry height
        err = (float(obs[self._i_tx]) - float(obs[self._i_wx])) * self._length  # [m]
        want = float(np.clip(err / self.ramp, -1.0, 1.0))
        a_x = self._ax = self._ax + float(np.clip(want - self._ax, -self.x_step, self.x_step))
        if self._phase == "grip" and lift >= 1.0:
            self._phase = "carry"
        if self._phase == "grip":  # towards the target already while lifting (a shorter carry: less creep)
            return np.array([a_k, a_x if self._x_while_lifting else 0.0, a_z], dtype=np.float32)
        if self._phase == "carry" and abs(err) < self.align:
            self._phase = "lower"
        if self._phase == "carry":
            return np.array([a_k, a_x, 0.0], dtype=np.float32)
        if lift <= self.down:
            self._phase = "rest"
        return np.array([a_k, a_x, -self.lower_speed if self._phase == "lower" else 0.0], dtype=np.float32)


class PlacePolicy(_PlaceCarry):
    """Pick-and-place on a valve env (``PlaceFragile-v2``-``v4``): grip and lift with ``grip`` (a
    :class:`PlaceGripPolicy` by default, or an :class:`OracleFragilePolicy`) up to the carry height, carry the workpiece over the target (palm ``x``
    speed proportional to the observed ``target_x - workpiece_x``, saturating ``ramp`` [m] away, changing that
    speed by at most ``x_step`` per step, from the freeze on: while lifting too), lower it until it stops sinking
    on the table (the observed lift below ``down`` of the carry height), and wait there.  Actions ``(curvature,
    palm x, palm z)``.

    With an observation-only grip, from the freeze on, the grip follows the observed finger forces:

    * creep: whenever the workpiece has crept ``slip_distance`` [m] down relative to the palm (its observed
      height relative to the palm) over the last ``slip_window`` steps, close by ``slip_frac`` of the curvature
      closed since contact (about that fraction more force), at most ``slip_cap`` of it in all.  A heavy
      workpiece held near ``N_hold`` creeps down its soft grip at ~0.3 mm per step and is dropped (2 cm) within
      the carry; a window of 10 steps does not answer the bounce of the lift's start;
    * ease: while the largest finger force is above ``ease`` times its value at the freeze (about ``N_hold``;
      every crush limit is at least 1.6 ``N_hold``), open by ``ease_frac`` of the curvature closed since contact
      per step instead (a heavy workpiece swinging in the grip at the carry's start, or closed on by the creep
      rule, presses one finger harder).

    ``slip_frac`` None: 0.05, or 0 with an :class:`OracleFragilePolicy` grip (frozen in the hidden window's
    middle; both rules off: with the creep rule the oracle crushed more, 67 instead of 68 % on seeds 6100-6199
    and 48 instead of 60 % on 6200-6249, measured with the carry started from rest).

    It outputs an absolute curvature command (as the grips do); :mod:`simgrip.envs.baselines` turns it into the
    valve's rate (``absolute_to_valve``).  The retired absolute-command ``PlaceFragile-v0``/``-v1`` are driven by
    :class:`AbsolutePlacePolicy` (``reset`` refuses them here, naming it).

    ``PlaceFragile-v3`` (``python -m simgrip.envs.baselines --policy observation``, ``--policy oracle``), success
    on seeds 6100-6199 (tuned on) / 6200-6249 (checked) / 6000-6049 (held out): observation 65 / 60 / 74 % with
    :class:`ObservationFragilePolicy`'s grip, the palm still in ``x`` until lifted (then at once at the speed
    ramped meanwhile) and no force feedback, 85 / 82 / 82 %
    with these defaults; the oracle 68 / 60 / 78 % then, 76 / 68 / 82 % now.  Left (observation): heavy
    workpieces (> 0.15 kg, most of them slippery) knocked over or crushed while carried."""

    def _default_grip_policy(self):
        return PlaceGripPolicy()

    def _check_env(self, u) -> None:
        from simgrip.envs.valve import ValveCommand

        if not isinstance(u, ValveCommand):
            raise TypeError(f"PlacePolicy drives a valve env (PlaceFragile-v2-v4), not {type(u).__name__}: "
                            "use AbsolutePlacePolicy for the absolute-command PlaceFragile-v0/-v1")


class AbsolutePlacePolicy(_PlaceCarry):
    """Pick-and-place on the retired absolute-command ``PlaceFragile-v0``/``-v1`` (crush ratio 1.3-1.7): the
    controller their stored baselines were measured with, :class:`PlacePolicy`'s carry and set-down with
    :class:`ObservationFragilePolicy`'s grip by default, no force feedback and the palm still in ``x`` until
    lifted (:class:`PlacePolicy`'s defaults gave 62 % there instead of 82 % on seeds 6000-6049 of
    ``PlaceFragile-v0``; the oracle 76 instead of 84 %).  Arguments as :class:`PlacePolicy`'s (the force
    feedback's are not used)."""

    _feedback = False
    _x_while_lifting = False

    def _default_grip_policy(self):
        return ObservationFragilePolicy()

    def _check_env(self, u) -> None:
        from simgrip.envs.valve import ValveCommand

        if isinstance(u, ValveCommand):
            raise TypeError(f"AbsolutePlacePolicy drives an absolute-command env (PlaceFragile-v0, -v1), not the "
                            f"valve env {type(u).__name__}: use PlacePolicy")


class CradleFragilePolicy(ObservationFragilePolicy):
    """Observation-only cradle (Grip III, ``PickCradleFragile-v0``): open the fingers into a claw (``claw``, in
    action units) while lowering the palm until the workpiece's lower edge is ``depth`` finger lengths below it
    (read off the observed workpiece height), then close slowly while raising the palm slowly, freeze when the
    workpiece leaves the pedestal (:class:`ObservationFragilePolicy`'s trigger and margin) and lift; while
    lifting, close by ``slip_step`` (action units) each time the workpiece has slid ``slip_distance`` [m] further
    down relative to the palm (its observed relative height: slip in the grip)."""

    def __init__(self, *, claw: float = 0.68, depth: float = 0.5, descend_speed: float = 1.0,
                 margin: float = 0.1, tip_gap: float = 2.0, slip_distance: float = 0.001, slip_step: float = 0.01,
                 **kwargs):
        kwargs.setdefault("start", claw)
        super().__init__(margin=margin, **kwargs)
        self.claw, self.depth, self.descend_speed, self.tip_gap = claw, depth, descend_speed, tip_gap
        self.slip_distance, self.slip_step = slip_distance, slip_step

    def reset(self, env, info=None):
        super().reset(env, info)
        u = env.unwrapped
        sl = u.obs_slices
        self._i_palm = sl["palm_height"].start
        self._i_wz = sl["box_position"].stop - 1 if "box_position" in sl else sl["workpiece_position"].stop - 1
        self._L, self._r_tip = float(u.length), float(u.r_tip)
        self._half_h = 0.5 * float(getattr(u, "box_height", 0.0))
        self._dz = float(u.palm_speed) * float(u.dt)
        self._i_tipx = sl["tip_position"].start  # finger 0's tip x relative to the palm [l]
        self._grasp = None
        self._slip_ref = None  # the workpiece's height relative to the palm when the curvature was last set [m]

    def _grasp_height(self, palm: float, rel_z: float) -> float:
        """The palm height [m] that puts the box's lower edge ``depth`` finger lengths (plus the tip radius) below
        the palm, from the palm height and the observed box centre relative to it [m]."""
        bottom = palm + rel_z - self._half_h
        return bottom + self.depth * self._L + self._r_tip

    def _trigger(self, obs) -> bool:
        # also stop closing where the tips would meet under a narrow workpiece (the fingers do not collide with
        # each other: closed further they would pass through each other)
        tips_meet = abs(float(obs[self._i_tipx])) * self._L <= self.tip_gap * self._r_tip
        return tips_meet or super()._trigger(obs)

    def __call__(self, obs):
        palm = float(obs[self._i_palm]) * self._L
        if self._grasp is None:
            self._grasp = self._grasp_height(palm, float(obs[self._i_wz]) * self._L)
            self._palm_cmd = palm
        if abs(self._palm_cmd - self._grasp) > 1e-9:
            v = float(np.clip((self._grasp - self._palm_cmd) / self._dz, -self.descend_speed, self.descend_speed))
            self._palm_cmd += v * self._dz
            return np.array([self.claw, v], dtype=np.float32)
        if self._frozen is not None:  # slipping down the fingers (the observed position relative to the palm)
            rel_z = float(obs[self._i_wz]) * self._L
            if self._slip_ref is None:
                self._slip_ref = rel_z
            elif rel_z < self._slip_ref - self.slip_distance:
                self._frozen = max(self._frozen - self.slip_step, -1.0)  # close a little
                self._slip_ref = rel_z
        return super().__call__(obs)



class SphereFragilePolicy(CradleFragilePolicy):
    """Observation-only K-finger pick of a sphere (``PickSphereFragile-v0``): :class:`CradleFragilePolicy` with the
    palm brought to ``depth`` finger lengths above the sphere's observed centre (the tips reach below its
    equator), then the same slow closing, freeze on lift and lift."""

    def _grasp_height(self, palm: float, rel_z: float) -> float:
        return palm + rel_z + self.depth * self._L


class _OracleClaw:
    """The claw controllers' oracle (knows the hidden window): once lifting, open the curvature by ``min_rate``
    per step while the largest finger force is above ``sqrt(hold_force * crush_limit)`` (read at ``reset``)."""

    def reset(self, env, info=None):
        super().reset(env, info)
        u = env.unwrapped
        self._target = math.sqrt(u.hold_force * u.crush_limit)

    def __call__(self, obs):
        a = super().__call__(obs)
        if self._frozen is not None and self._forces(obs).max() > self._target:
            self._frozen = min(self._frozen + self.min_rate, 1.0)
            a[0] = self._frozen
        return a


class OracleCradlePolicy(_OracleClaw, CradleFragilePolicy):
    """:class:`CradleFragilePolicy` that also eases the grip above the hidden window's middle (an oracle)."""


class OracleSpherePolicy(_OracleClaw, SphereFragilePolicy):
    """:class:`SphereFragilePolicy` that also eases the grip above the hidden window's middle (an oracle)."""


#: the claw tasks' (oracle, observation-only) controllers, by task
CLAW_POLICIES = {"cradle": (OracleCradlePolicy, CradleFragilePolicy),
                 "sphere": (OracleSpherePolicy, SphereFragilePolicy)}
