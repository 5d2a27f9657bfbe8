r"""The claws paid for reaching the grasp height, not for touching: v5 of the cradle and the sphere, issue 18.

``simgrip/PickCradleFragile-v5`` and ``simgrip/PickSphereFragile-v5`` are ``PickCradleFragile-v4`` and
``PickSphereFragile-v4`` (:mod:`simgrip.envs.pick_fragile_v3`: the hand started at an unknown height, the
valve, the tactile sensor's scale) with **only the reward changed**, so every fixed-schedule and scripted
baseline of v4 holds for v5 with the same seeds:

1. **An approach term.**  ``reward_approach = w_approach (psi_t - psi_{t-1})`` with the potential
   ``psi = -min(|z - z_g| / d, 1)``: ``z`` the workpiece centre's height relative to the palm [m] (observed:
   the last entry of ``box_position`` / ``workpiece_position`` times the finger length), ``z_g`` its value at
   the grasp height the observation-only controllers aim for (:class:`~simgrip.envs.scripted_fragile.
   CradleFragilePolicy`: the box's lower edge half a finger length plus the tip radius below the palm,
   ``z_g = h/2 - l/2 - r_tip`` for a box of height ``h``; :class:`~simgrip.envs.scripted_fragile.
   SphereFragilePolicy`: the sphere's centre half a finger length below it, ``z_g = -l/2``), ``d = 0.2`` m
   (more than any start's distance).  A potential difference (Ng, Harada and Russell 1999), it sums over an
   episode to ``w_approach (psi_end - psi_0)`` whatever the path, so it cannot make a policy that never grasps
   beat one that does; it only tells a learner which way the grasp height is.  ``w_approach = 2``.
2. **No per-step touch pay** (``w_touch = 0``; v1-v4: 0.02), as :mod:`simgrip.envs.pick_fragile_v5`.

Why (measured, ``docs/baselines/rl_cradle_v4``, ``rl_sphere_v4``): PPO with SB3 defaults reached 0 % held-out
success on both v4 claws in all 3 training seeds (1 success in 25,073 training episodes): a claw must first
descend up to 16 cm, open, to a grasp height it reads off the workpiece's position, and no run found it; the
runs settled on touching without lifting (paid ``w_touch`` a step) or on never touching.

Rewards: v1's table (:mod:`simgrip.envs.pick_fragile_v1`) with ``reward_touch`` always 0, plus
``reward_approach``.  Ordering: any success returns at least ``w_lift + w_success - w_approach = 28``; no
unsuccessful episode returns more than ``w_contact + w_lift + w_approach = 13``; never touching returns at
most ``w_approach``.

Info keys (every ``step``; v4's plus ``reward_approach``):

=====================  ==========================================================================
key                    meaning
=====================  ==========================================================================
``is_success``         lifted ``target_height`` and held ``hold_time``, never crushed (terminates)
``workpiece_lift``     workpiece centre's height gain since the start of the episode [m]
``crushed``            a finger's normal force exceeded ``crush_limit`` this step (terminates)
``dropped``            lifted, then sank ``drop_distance`` relative to the palm (terminates)
``knocked_over``       tilted or pushed sideways out of reach (terminates)
``normal_force``       per finger: summed contact normal force on the workpiece [N]
``friction_force``     per finger: friction force magnitude on the workpiece [N]
``side_force``         per finger: horizontal (squeezing) part of the normal force [N]
``hold_time``          time held at the target height [s]
``crush_limit``        this episode's crush limit [N] (hidden from the observation)
``fingers_touching``   the sphere: how many fingers touch it
``valid``              no finger through itself or another (``invalid``: the messages, when not)
``reward_approach``    ``w_approach (psi_t - psi_{t-1})``, the approach term above
``reward_*``           v1's terms: ``reward_lift``, ``reward_success``, ``reward_squeeze`` (0),
                       ``reward_drop``, ``reward_crush``, ``reward_contact``, ``reward_touch`` (0)
=====================  ==========================================================================
"""

from __future__ import annotations

from simgrip.envs.arguments import check_number as _num
from simgrip.envs.pick_fragile_v3 import FragileCradleEnvV4, FragileSphereEnvV4

__all__ = ["APPROACH_SCALE", "FragileCradleEnvV5", "FragileSphereEnvV5", "W_APPROACH"]

#: the approach potential's distance scale ``d`` [m]
APPROACH_SCALE = 0.2
#: the approach term's weight
W_APPROACH = 2.0


class _Approach:
    """v5's claw reward (a mixin before a v4 claw env): the approach potential, ``w_touch = 0``."""

    _psi = 0.0
    _z_g = 0.0  # the episode's grasp offset [m] (set at reset: read once, not every step)

    def __init__(self, *, w_approach: float = W_APPROACH, w_touch: float = 0.0, **kwargs):
        self.w_approach = _num("w_approach", w_approach, positive=False)
        super().__init__(w_touch=w_touch, **kwargs)
        sl = self.obs_slices
        self._i_z = (sl["box_position"] if "box_position" in sl else sl["workpiece_position"]).stop - 1

    def _grasp_offset(self) -> float:
        raise NotImplementedError

    def _potential(self, obs) -> float:
        x = abs(float(obs[self._i_z]) * self.length - self._z_g) / APPROACH_SCALE
        return -(1.0 if x > 1.0 else x)

    def reset(self, *, seed=None, options=None):
        obs, info = super().reset(seed=seed, options=options)
        self._z_g = self._grasp_offset()
        self._psi = self._potential(obs)
        return obs, info

    def _step_checked(self, a: list):
        obs, reward, terminated, truncated, info = super()._step_checked(a)
        psi = self._potential(obs)
        r = self.w_approach * (psi - self._psi)
        self._psi = psi
        info["reward_approach"] = r
        return obs, reward + r, terminated, truncated, info


class FragileCradleEnvV5(_Approach, FragileCradleEnvV4):
    """``simgrip/PickCradleFragile-v5``: ``PickCradleFragile-v4`` (the cradle, hand started at an unknown height)
    paid for approaching the grasp height and not per touching step (:mod:`simgrip.envs.pick_claw_v5`; info
    ``is_success``, ``workpiece_lift``, ``crushed``, ``dropped``, ``reward_approach``).  Arguments: v4's plus
    ``w_approach = 2``; ``w_touch`` defaults to 0."""

    def _grasp_offset(self) -> float:
        return 0.5 * float(self.box_height) - 0.5 * float(self.length) - float(self.r_tip)


class FragileSphereEnvV5(_Approach, FragileSphereEnvV4):
    """``simgrip/PickSphereFragile-v5``: ``PickSphereFragile-v4`` (``K = 3`` fingers around a sphere, hand
    started at an unknown height) paid for approaching the grasp height and not per touching step
    (:mod:`simgrip.envs.pick_claw_v5`; info ``is_success``, ``workpiece_lift``, ``crushed``, ``dropped``,
    ``reward_approach``).  Arguments: v4's plus ``w_approach = 2``; ``w_touch`` defaults to 0."""

    def _grasp_offset(self) -> float:
        return -0.5 * float(self.length)
