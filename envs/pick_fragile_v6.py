r"""The pinch and K-finger tasks with a crush never cheaper than a drop: v6, issue 18.

``simgrip/PickFragile-v6`` and ``simgrip/PickMultiFragile-v6`` are ``PickFragile-v5`` and
``PickMultiFragile-v5`` (:mod:`simgrip.envs.pick_fragile_v5`: v4's pre-grasp start, valve, tactile scale and
draw, without the per-step touch pay) with **only the reward changed**: ``w_drop = 0`` (v1-v5: 5).  The draw,
the observation, the action, and what success, a crush, a drop and a knock-over are (and when an episode
terminates) are v4's, so every fixed-schedule and scripted baseline of v4 holds for v6 with the same seeds
(``docs/baselines/PickFragile-v4-*.json``, ``PickMultiFragile-v4-*.json``).

Why: both failures end the episode and take back the lift earned; on top of that v5 charged a drop ``w_drop =
5`` but a crush only the graded ``w_crush x / (1 + x)`` (``x`` the relative overrun of the hidden limit: 0
just over it, below ``w_crush = 2`` for any overrun).  A learner that must risk one failure or the other was
paid to risk the crush, the very failure a fragile task is about, and PPO's policies on v5 squeezed: behind the
probe offset (:mod:`simgrip.envs.action_offset`) they crushed 9-12 of 50 held-out pieces.  With ``w_drop = 0``
a crush costs at least what a drop with the same progress costs (the lift taken back), and more the harder
the limit was overrun.

Measured with this reward (as v5 with ``--env-kwargs '{"w_drop": 0.0}'``, step for step the same env:
``tests/test_pick_fragile_v6.py``), PPO with SB3 defaults, held-out success on seeds 8000-8049 at 15
CPU-minutes (Gymnasium environments page: "Is it the drop penalty?" and "Crushing was cheaper than
dropping"):

================  ===========================================  ============================================
task              SB3 defaults, seeds 0-2                      behind ``ActionOffset((-0.4, 0.2))``, seeds 0-5
================  ===========================================  ============================================
pinch             80 / 0 / 84 % (seed 1 never closes)          86 / 84 / 74 / 80 / 80 / 0 %
K fingers         0 / 78 / 72 %                                66 / 68 / 88 / 72 / 64 / 46 %
================  ===========================================  ============================================

The K fingers behind the offset with :class:`~simgrip.envs.light_bias.LightBias` ``(0.5)`` in training (half the
training pieces drawn from the lightest third of the mass range; evaluation is the task's own draw, ``--light-bias
0.5``): 72 / 90 / 80 / 80 / 82 / 84 %, seeds 0-5 (the environments page, "Light pieces more often in training").

Rewards: v1's table (:mod:`simgrip.envs.pick_fragile_v1`) with ``reward_touch`` and ``reward_drop`` always 0.
Ordering: any success returns at least ``w_lift + w_success = 30``; no unsuccessful episode returns more than
``w_contact + w_lift = 11``, and one that ends in a drop, a knock-over or a crush no more than ``w_contact = 1``
(the lift taken back); never touching returns 0.  Info keys: v4's (:mod:`simgrip.envs.pick_fragile_v4`;
``reset``'s ``info["start_gap"]``), ``reward_touch`` and ``reward_drop`` kept (0) so that every fragile task
has the same keys.

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
                       ``reward_drop`` (0), ``reward_crush``, ``reward_contact``, ``reward_touch`` (0)
=====================  ==========================================================================
"""

from __future__ import annotations

from simgrip.envs.pick_fragile_v5 import FragilePickEnvV5, FragilePickMultiEnvV5

__all__ = ["FragilePickEnvV6", "FragilePickMultiEnvV6", "V6_W_DROP"]

#: v6's drop (and knock-over) penalty (v1-v5: 5)
V6_W_DROP = 0.0


class FragilePickEnvV6(FragilePickEnvV5):
    """``simgrip/PickFragile-v6``: ``PickFragile-v5`` (two-finger pinch from a pre-grasp, no touch pay) with
    ``w_drop = 0`` (:mod:`simgrip.envs.pick_fragile_v6`; info ``is_success``, ``workpiece_lift``, ``crushed``,
    ``dropped``; ``reset``'s info ``start_gap``).  Arguments: v4's."""

    def __init__(self, *, w_drop: float = V6_W_DROP, **kwargs):
        super().__init__(w_drop=w_drop, **kwargs)


class FragilePickMultiEnvV6(FragilePickMultiEnvV5):
    """``simgrip/PickMultiFragile-v6``: ``PickMultiFragile-v5`` (``K = 3`` fingers around a cylinder from a
    pre-grasp, no touch pay) with ``w_drop = 0`` (:mod:`simgrip.envs.pick_fragile_v6`; info ``is_success``,
    ``workpiece_lift``, ``crushed``, ``dropped``; ``reset``'s info ``start_gap``).  Arguments: v4's."""

    def __init__(self, *, w_drop: float = V6_W_DROP, **kwargs):
        super().__init__(w_drop=w_drop, **kwargs)
