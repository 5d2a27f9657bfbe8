r"""The pinch and K-finger tasks without the per-step touch pay: v5, issue 18.

``simgrip/PickFragile-v5`` and ``simgrip/PickMultiFragile-v5`` are ``PickFragile-v4`` and
``PickMultiFragile-v4`` (:mod:`simgrip.envs.pick_fragile_v4`: the pre-grasp start, the valve, the tactile
sensor's scale, masses 5-250 g) with **only the reward changed**: ``w_touch = 0`` (v1-v4: 0.02 a step).  The
draw, the observation, the action, and what success, a crush, a drop and a knock-over are (and when an episode
terminates) are v4's, so every fixed-schedule and scripted baseline of v4 holds for v5 with the same seeds.

Why: v1 paid ``w_touch`` on every step on which every finger touched the workpiece, so that a learner started
with the fingers straight could climb from "fingers open" towards a grasp.  From v4's pre-grasp start the
fingers are 3-10 mm from the workpiece and the one-off ``w_contact`` (v1's first contact of every finger)
already pays finding it; the per-step pay instead made "touch and hold, never lift" a safe local optimum:
``w_contact + w_touch T = 7`` for holding against a lift attempt that, while the grip is not yet right,
ends in a drop (``-w_drop = -5``, the lift progress taken back and the touch steps left forfeited).  PPO
(SB3 defaults, 15 CPU-minutes) settled there in one of three training seeds on each v4 task (held-out return
3-5, palm action near 0: ``docs/baselines/rl_pick_v4``, ``rl_multi_v4``, ``rl_multi_v4_quiet``).  With
``w_touch = 0`` holding returns ``w_contact = 1``, and trying to lift is worth it as soon as one attempt in
seven succeeds (a success returns ``w_contact + w_lift + w_success = 31``, a drop ``w_contact - w_drop = -4``:
``31 p - 4 (1 - p) >= 1``), where v4's hold (~7) asked for about one in three.  Measured with this reward,
PPO's seeds still collapse one in three onto a fixed action (``docs/baselines/rl_pick_v5``, ``rl_multi_v5``).

Rewards: v1's table (:mod:`simgrip.envs.pick_fragile_v1`) with ``reward_touch`` always 0.  Ordering: any
success returns at least ``w_lift + w_success = 30``; no unsuccessful episode returns more than ``w_contact +
w_lift = 11``; never touching returns 0.  Info keys: v4's (:mod:`simgrip.envs.pick_fragile_v4`; ``reset``'s
``info["start_gap"]``), ``reward_touch`` kept (0) so that every fragile task has the same keys.

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
``fingers_touching``   K-finger tasks: how many fingers touch the workpiece
``valid``              no finger through itself or another (``invalid``: the messages, when not)
``reward_*``           v1's terms: ``reward_lift``, ``reward_success``, ``reward_squeeze`` (0),
                       ``reward_drop``, ``reward_crush``, ``reward_contact``, ``reward_touch`` (0)
=====================  ==========================================================================
"""

from __future__ import annotations

from simgrip.envs.pick_fragile_v4 import FragilePickEnvV4, FragilePickMultiEnvV4

__all__ = ["FragilePickEnvV5", "FragilePickMultiEnvV5", "V5_W_TOUCH"]

#: v5's per-step touch pay (v1-v4: 0.02)
V5_W_TOUCH = 0.0


class FragilePickEnvV5(FragilePickEnvV4):
    """``simgrip/PickFragile-v5``: ``PickFragile-v4`` (two-finger pinch from a pre-grasp) with ``w_touch = 0``
    (:mod:`simgrip.envs.pick_fragile_v5`; info ``is_success``, ``workpiece_lift``, ``crushed``, ``dropped``;
    ``reset``'s info ``start_gap``).  Arguments: v4's."""

    def __init__(self, *, w_touch: float = V5_W_TOUCH, **kwargs):
        super().__init__(w_touch=w_touch, **kwargs)


class FragilePickMultiEnvV5(FragilePickMultiEnvV4):
    """``simgrip/PickMultiFragile-v5``: ``PickMultiFragile-v4`` (``K = 3`` fingers around a cylinder from a
    pre-grasp) with ``w_touch = 0`` (:mod:`simgrip.envs.pick_fragile_v5`; info ``is_success``,
    ``workpiece_lift``, ``crushed``, ``dropped``; ``reset``'s info ``start_gap``).  Arguments: v4's."""

    def __init__(self, *, w_touch: float = V5_W_TOUCH, **kwargs):
        super().__init__(w_touch=w_touch, **kwargs)
