r"""Fragile workpieces: pick tasks where the grip force must be found by feedback (issue 18).

``simgrip/PickFragile-v0`` (Grip I, two-finger pinch) and
``simgrip/PickMultiFragile-v0`` (``K = 3`` fingers around a centred
cylinder by default; other shapes and offsets by argument) are :class:`~simgrip.envs.pick.PickEnv` and
:class:`~simgrip.envs.pick_multi.PickMultiEnv` with two changes:

1. **A crush limit.**  Each episode's workpiece survives a normal force of at
   most ``crush_limit`` [N] on any one finger (the finger's summed contact
   normal force on it, read at the end of every control step, 50 Hz, as a
   tactile sensor reads it; ``crush_at="peak"``: its largest value within the step,
   :mod:`simgrip.envs.touch_history`).  A larger force crushes it: the episode
   terminates as a failure (``info["crushed"]``, reward ``-w_drop`` and the lift
   progress taken back, as for a drop).
2. **A wide draw.**  Mass is log-uniform over a 20-fold range, friction wide,
   and the crush limit is drawn as a ratio ``r`` to the least normal force
   that holds the workpiece, ``N_hold = m g / (K mu)`` (``K`` fingers sharing
   the weight through friction on near-vertical faces): ``crush_limit = r
   N_hold`` with ``r`` log-uniform in ``crush_ratio_range = (1.3, 1.7)`` (narrowed from ``(1.3, 2.0)``,
   issue 18: the fixed schedules' best stood at the 20 % target with no margin).
   The grip force of a soft finger is set by its curvature (the paper's
   Grip I: ``N`` rises with ``|kappa_bar|`` past the onset of contact, from 0
   to ~11 N over the command range for these fingers), so every curvature
   holds only the workpieces whose window ``[N_hold, r N_hold]`` contains
   its force: the curvature that holds a heavy, slippery workpiece crushes a
   light, fragile one, and the one that spares a fragile one drops a heavy
   one.  The windows of two draws overlap only when their ``N_hold`` are
   within a factor ``r`` (at most 1.7) of each other, while ``N_hold`` spans a
   factor ~80 (``20 x 4``).

Physical picture (SI, the ``PickEnv`` finger): workpieces of 10-200 g
(a strawberry, an egg, a plastic cup with some water), friction 0.3-1.2,
crush limits of 0.05-5.6 N per finger (two fingers); a thin cup or a ripe berry is damaged
well below what the fully curled finger presses (~11 N).

What the agent senses is the parent env's observation, unchanged:
finger shapes (tangent angles along each finger), fingertip positions, the
curvature command and its lagged actual value, the palm height, the
workpiece's position and velocity relative to the palm (slip: a workpiece
that does not follow the palm up slides in the grip) and the contact forces
on each finger as ``log(1 + F/W)`` (normal and friction magnitude: a tactile
sensor).  Hidden (never in the observation): the workpiece's mass, friction
and crush limit; ``reset``'s ``info`` and the attributes ``crush_limit``,
``hold_force`` hold them for oracles and analysis.

Info keys (the same in both envs, every ``step``):

=====================  ==========================================================================
key                    meaning
=====================  ==========================================================================
``is_success``         lifted ``target_height`` and held ``hold_time``, never crushed (terminates)
``workpiece_lift``     workpiece centre's height gain since the start of the episode [m]
``crushed``            a finger's normal force exceeded ``crush_limit`` this step (terminates)
``dropped``            lifted, then sank ``drop_distance`` relative to the palm (terminates)
``knocked_over``       tilted > 30 degrees or pushed > 3 cm sideways (terminates)
``normal_force``       per finger: summed contact normal force on the workpiece [N]
``crush_limit``        this episode's crush limit [N] (hidden from the observation)
``reward_crush``       the crush term of this step's reward (``-w_drop`` or 0, plus the taken-back lift)
=====================  ==========================================================================

plus the parent env's reward terms (``reward_lift``, ``reward_success``, ``reward_squeeze``,
``reward_drop``) and force arrays (``friction_force``, ``side_force``, ``hold_time``;
``fingers_touching`` with K fingers).  ``valid`` (no finger through itself or another; else ``invalid``
lists the messages) is checked on the first step, every ``FRAGILE_VALIDITY_EVERY = 25`` steps (0.5 s) and on
every terminating step (:mod:`simgrip.envs.pick_validity`); between checks it repeats the last check's result.
A success declared in an invalid state is taken back (``is_success`` False, the success reward withdrawn).  ``PickFragile`` has no ``box_lift``
(it is ``workpiece_lift``).

Baselines (``python -m simgrip.envs.baselines --env ID --policy P --seeds 6000-6049 --out
docs/baselines/ID-P.json``, 50 seeds no test or tuning used; success, the grids' best member chosen on those
seeds, an optimistic bound for the family; the JSONs are in ``docs/baselines/``):

========================  ======  ==============  ===============  ======  ================
id                        random  best constant   best open-loop   oracle  observation-only
========================  ======  ==============  ===============  ======  ================
``PickFragile-v0``        0 %     16 %            18 %             92 %    92 %
``PickMultiFragile-v0``   0 %     16 %            18 %             84 %    84 %
``PlaceFragile-v0``       0 %     0 %             2 %              84 %    82 %
``PickCradleFragile-v0``  0 %     2 %             42 %             80 %    80 %
``PickSphereFragile-v0``  0 %     0 %             30 %             88 %    98 %
========================  ======  ==============  ===============  ======  ================

The cradle and the sphere (:mod:`~simgrip.envs.pick_cradle_fragile`, :mod:`~simgrip.envs.pick_sphere_fragile`)
miss the issue's 20 % target for fixed schedules: they hold by support, whose contact force scales with the
weight by itself, so one gentle curvature (open-loop, action 0.4-0.5) holds 42 % of the boxes and 30 % of
the spheres inside their windows; their open-loop family is the claw one (``simgrip.envs.baselines``).

The crush ratio's range was chosen on seeds 5000-5049 (observation-only there: 45/50 and 40/50 at
``(1.3, 1.7)``; 43/50 and 38/50 at ``(1.3, 1.6)``; 42/50 and 36/50 at ``(1.3, 1.5)``, Pick / PickMulti): the
narrowest range that keeps the K-finger task's observation-only controller at 80 %.

Reset options: the parent's (``box_width``/``box_mass``/``friction`` or
``width``/``mass``/``friction``/``shape``/...) and ``crush_limit`` [N].
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np

from simgrip.envs.arguments import check_positive as _pos
from simgrip.envs.arguments import check_range as _range
from simgrip.envs.arguments import check_reset
from simgrip.envs.pick import PickEnv
from simgrip.envs.pick_multi import PickMultiEnv
from simgrip.envs.pick_validity import FRAGILE_VALIDITY_EVERY, record_validity
from simgrip.envs.touch_history import TouchPeaks, add_touch_sensors

__all__ = ["FragilePickEnv", "FragilePickMultiEnv", "FRAGILE_DEFAULTS"]

#: the draw shared by both envs: mass [kg] (log-uniform), friction (uniform), crush ratio (log-uniform)
FRAGILE_DEFAULTS = {"mass_range": (0.01, 0.2), "friction_range": (0.3, 1.2), "crush_ratio_range": (1.3, 1.7),
                    "size_range": (0.03, 0.075)}


def _log_uniform(rng, lo: float, hi: float) -> float:
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


class _Fragile:
    """The crush limit and the log-uniform mass draw, shared by both fragile envs (a mixin before the env)."""

    _MASS_KEY = "mass"  # the parent's reset option of the mass
    _PARENT_OPTIONS: tuple = ()
    _final_check = True  # check validity on terminating steps here (False: the subclass does, after its success)
    crush_at = "end"  # which force the crush rule reads: at the control step's end, or its peak within it
    _touch = None  # the peak's reader (crush_at "peak": TouchPeaks)

    def _crush_at(self, crush_at) -> None:
        """Check and set ``crush_at`` (before the parent builds its model: :meth:`_build` reads it)."""
        if not isinstance(crush_at, str) or crush_at not in ("end", "peak"):
            raise ValueError(f"crush_at must be 'end' (the force at the control step's end) or 'peak' (its largest "
                             f"value within the step), got {crush_at!r}")
        self.crush_at = crush_at

    def _build(self):
        """The parent's model; with ``crush_at="peak"`` each finger's touch sensor added (:mod:`simgrip.envs.
        touch_history`) and the model compiled again (the same addresses: a sensor adds no body, joint or geom)."""
        super()._build()
        if self.crush_at != "peak":
            return
        import mujoco

        from simgrip.envs.palm_servo import palm_command

        fs = self.frame_skip
        if hasattr(self, "_models"):  # the K-finger env: one model per workpiece shape
            for shape, pm in self._models.items():
                add_touch_sensors(pm.spec, fingers=self.K, n_links=self.n, frame_skip=fs, workpiece="workpiece")
                pm.model = pm.spec.compile()
                self._datas[shape] = mujoco.MjData(pm.model)
            self._select(self.shapes[0])
        else:
            add_touch_sensors(self.spec, fingers=2, n_links=self.n, frame_skip=fs, workpiece="box")
            self.model = self.spec.compile()
            self.data = mujoco.MjData(self.model)
        self._palm = palm_command(self, self.model)
        self._bind_touch()

    def _bind_touch(self) -> None:
        """The peak's reader for the current model (again after a subclass compiles its own, the place's)."""
        if self.crush_at == "peak":
            self._touch = TouchPeaks(self.model, fingers=getattr(self, "K", 2), frame_skip=self.frame_skip)

    def _fragile_args(self, crush_ratio_range):
        self.crush_ratio_range = _range("crush_ratio_range", crush_ratio_range)
        if self.crush_ratio_range[0] <= 1.0:
            raise ValueError(f"crush_ratio_range must lie above 1 (a limit below the holding force cannot be "
                             f"picked), got {crush_ratio_range!r}")
        self.crush_limit = math.inf
        self.hold_force = 0.0
        self._validity.every = FRAGILE_VALIDITY_EVERY  # checked every k-th step and at every episode end

    def _final_validity(self, info, terminated: bool) -> float:
        """Check ``info["valid"]`` afresh on a terminating step (the probe otherwise runs every
        ``FRAGILE_VALIDITY_EVERY`` steps); a success in an impossible state is taken back.  Returns the reward
        change (``-w_success`` where a success was taken back, else 0)."""
        if not terminated or self._validity.checked:
            return 0.0
        if record_validity(info, self._validity(self.data.qpos.tolist(), self.data, force=True)):
            return 0.0
        if info["is_success"]:
            info["is_success"] = False
            info["reward_success"] = 0.0
            return -self.w_success
        return 0.0

    def _crush_penalty(self, normal_force) -> float:
        """The size of the crush penalty (>= 0) given the step's per-finger normal forces [N]: ``w_drop`` in v0
        (:mod:`simgrip.envs.pick_fragile_v1` grades it by the excess over the limit)."""
        return self.w_drop

    def _episode(self) -> tuple[float, float, int]:  # pragma: no cover - defined by each env
        raise NotImplementedError

    def _hold_force(self) -> float:
        """The least normal force per finger that holds this episode's workpiece [N]: ``m g / (K mu)`` (``K``
        fingers carrying the weight by friction on vertical faces); the cradle overrides it."""
        mass, mu, k = self._episode()
        return mass * self.g / (k * mu)

    def reset(self, *, seed=None, options=None):
        seed, options = check_reset(seed, options, (*self._PARENT_OPTIONS, "crush_limit"))
        crush = options.pop("crush_limit", None)
        gym.Env.reset(self, seed=seed)  # seeds np_random; the parent's reset (seed None) keeps drawing from it
        rng = self.np_random
        lo, hi = self._mass_range
        options.setdefault(self._MASS_KEY, _log_uniform(rng, lo, hi))
        ratio = _log_uniform(rng, *self.crush_ratio_range)
        self._validity.restart()
        obs, info = super().reset(seed=None, options=options)
        self.hold_force = self._hold_force()
        self.crush_limit = self.hold_force * ratio if crush is None else _pos("crush_limit", crush)
        info.update({"crush_limit": self.crush_limit, "hold_force": self.hold_force})
        return obs, info

    def _step_checked(self, a: list):
        obs, reward, terminated, truncated, info = super()._step_checked(a)
        if self._touch is None:
            forces = self._normal  # the parent's info["normal_force"], as floats
        else:  # crush_at "peak": each finger's largest within the step
            forces = self._touch.read(self.data)
            info["peak_normal_force"] = np.array(forces)
        crushed = max(forces) > self.crush_limit
        r_crush = 0.0
        if crushed:
            if info["is_success"]:
                reward -= self.w_success
                info["reward_success"] = 0.0
                info["is_success"] = False
            if not (info["dropped"] or info["knocked_over"]):  # not already charged as lost
                r_crush = -self._crush_penalty(info.get("peak_normal_force", info["normal_force"])) \
                    - self.w_lift * self._phi
                self._phi = 0.0
            terminated = True
            self._needs_reset = True
        info["crushed"] = crushed
        info["reward_crush"] = r_crush
        info["crush_limit"] = self.crush_limit
        lift = info.pop("box_lift", None)  # the two-finger env's name, moved to the end as workpiece_lift
        if lift is not None:
            info["workpiece_lift"] = lift
        if terminated and self._final_check:  # PlaceFragile declares its own success after this and checks there
            reward += self._final_validity(info, terminated)  # (not terminated: 0.0, what it returns)
        return obs, reward + r_crush, terminated, truncated, info


class FragilePickEnv(_Fragile, PickEnv):
    """``simgrip/PickFragile-v0``: :class:`~simgrip.envs.pick.PickEnv` (Grip I by default) with a crush limit.

    See :mod:`simgrip.envs.pick_fragile` for the draw, the sensing and the info table (``info["is_success"]``,
    ``info["workpiece_lift"]``, ``info["crushed"]``, ``info["dropped"]``).  Arguments: those of ``PickEnv``
    with the defaults ``box_mass_range = (0.01, 0.2)`` kg (drawn log-uniform), ``friction_range = (0.3, 1.2)``,
    ``box_width_range = (0.03, 0.075)`` m, ``palm_start = (0.085, 0.09)`` m, plus ``crush_ratio_range =
    (1.3, 1.7)`` and ``crush_at = "end"`` (``"peak"``: the crush rule reads each finger's largest force within
    the control step, ``info["peak_normal_force"]``; :mod:`simgrip.envs.touch_history`).
    """

    _MASS_KEY = "box_mass"
    _PARENT_OPTIONS = ("box_width", "box_mass", "friction", "palm_height")

    def __init__(self, *, crush_ratio_range=FRAGILE_DEFAULTS["crush_ratio_range"],
                 box_mass_range=FRAGILE_DEFAULTS["mass_range"], friction_range=FRAGILE_DEFAULTS["friction_range"],
                 box_width_range=FRAGILE_DEFAULTS["size_range"], palm_start=(0.085, 0.09), crush_at="end", **kwargs):
        self._crush_at(crush_at)
        # palm_start lower than Pick-v1's (0.105, 0.115): the tips meet the box lower, leaving room to slide up
        # its faces while the grip force is found
        super().__init__(box_mass_range=box_mass_range, friction_range=friction_range,
                         box_width_range=box_width_range, palm_start=palm_start, **kwargs)
        self._mass_range = self.box_mass_range
        self._fragile_args(crush_ratio_range)

    def _episode(self):
        return self.box.mass, self.box.friction, 2


class FragilePickMultiEnv(_Fragile, PickMultiEnv):
    """``simgrip/PickMultiFragile-v0``: :class:`~simgrip.envs.pick_multi.PickMultiEnv` with a crush limit.

    See :mod:`simgrip.envs.pick_fragile` for the draw, the sensing and the info table.  Arguments: those of
    ``PickMultiEnv`` (``K = fingers = 3``) with the defaults ``shapes = ("cylinder",)``, ``offset_max = 0``
    (centred), ``palm_start = (0.085, 0.09)`` m (lower than ``PickMulti-v0``'s: the tips meet the cylinder
    lower, leaving room to slide up it while the grip force is found), ``mass_range = (0.01, 0.2)`` kg
    (log-uniform), ``friction_range = (0.3, 1.2)``, ``size_range =
    (0.03, 0.075)`` m, plus ``crush_ratio_range = (1.3, 1.7)`` and ``crush_at = "end"`` (as
    :class:`FragilePickEnv`'s).  ``N_hold = m g / (K mu)`` counts every finger
    as carrying its share through friction on a vertical face (a cylinder's).  Other settings are harder and
    not yet solved by the scripted controllers (issue 18, measured on seeds 5000-5029 with the palm
    started at 0.105-0.115 m): an off-centre
    cylinder (``offset_max = 0.005``: the first finger to touch pushes it, and the largest finger force
    exceeds the mean) 8 of 30 observation-only; spheres (``shapes=("sphere",)``: tilted contact normals,
    so ``N_hold`` above is approximate, and a squeezed sphere is pressed out sideways) 0 of 16 centred with
    this env's closing controller; the sphere task is ``simgrip/PickSphereFragile-v0``
    (:mod:`simgrip.envs.pick_sphere_fragile`: its own ``N_hold`` and a claw controller).
    """

    _MASS_KEY = "mass"
    _PARENT_OPTIONS = ("shape", "width", "mass", "friction", "offset", "yaw", "palm_height")

    def __init__(self, *, crush_ratio_range=FRAGILE_DEFAULTS["crush_ratio_range"],
                 mass_range=FRAGILE_DEFAULTS["mass_range"], friction_range=FRAGILE_DEFAULTS["friction_range"],
                 size_range=FRAGILE_DEFAULTS["size_range"], shapes=("cylinder",), offset_max=0.0,
                 palm_start=(0.085, 0.09), crush_at="end", **kwargs):
        self._crush_at(crush_at)
        super().__init__(mass_range=mass_range, friction_range=friction_range, size_range=size_range, shapes=shapes,
                         offset_max=offset_max, palm_start=palm_start, **kwargs)
        self._mass_range = self.mass_range
        self._fragile_args(crush_ratio_range)

    def _episode(self):
        w = self.workpiece
        return w.mass, w.friction, self.K

