r"""Pick-and-place with a crush never cheaper than a drop: ``PlaceFragile-v5``, issue 18.

``simgrip/PlaceFragile-v5`` is ``PlaceFragile-v4`` (:mod:`simgrip.envs.pick_place_v4`: the pinch's pre-grasp
start, no touch pay; carry to a target drawn per episode, set down there) with **only the reward changed**:
``w_drop = 0`` (v1-v4: 5), as the pinch's and the K fingers' v6 (:mod:`simgrip.envs.pick_fragile_v6`).  The
draw, the observation, the action, and what success, a crush, a drop and a knock-over are (and when an episode
terminates) are v4's, so every fixed-schedule and scripted baseline of v4 holds for v5 with the same seeds
(``docs/baselines/PlaceFragile-v4-*.json``).

Why: v4 charged a drop (or a knock-over) ``w_drop = 5`` on top of the lift it takes back, but a crush only the
graded ``w_crush x / (1 + x)`` (below ``w_crush = 2`` for any overrun ``x`` of the hidden limit): a learner that
must risk one failure or the other was paid to risk the crush.  With ``w_drop = 0`` a crush costs at least what
a drop with the same progress costs.  The learned results (PPO, the Gymnasium environments page, "Pick-and-place
from scripted starts") were run as v4 with ``--env-kwargs '{"w_drop": 0.0}'``, step for step this env
(``tests/test_pick_place_v5.py``).

Rewards: v4's (v1's table, :mod:`simgrip.envs.pick_fragile_v1`, plus ``w_place``) with ``reward_touch`` and
``reward_drop`` always 0.  Ordering: a success returns at least ``w_place + w_success = 40``; no unsuccessful
episode more than ``w_contact + w_lift + w_place = 21``; never touching 0.

Info keys: v4's (every ``step``; ``reset``'s info adds ``start_gap`` [m] and ``target_x`` [m]):

=====================  ==========================================================================
key                    meaning
=====================  ==========================================================================
``is_success``         carried and set down on the target for ``place_time``, never crushed (terminates)
``workpiece_lift``     workpiece centre's height gain since the start of the episode [m]
``crushed``            a finger's normal force exceeded ``crush_limit`` this step (terminates)
``dropped``            lifted, then sank ``drop_distance`` relative to the palm (terminates)
``knocked_over``       tilted or pushed sideways out of reach (terminates)
``place_error``        ``|x - x_t|``: the workpiece's distance from the target [m]
``carried``            lifted ``carry_height`` with both fingers on it, this episode
``target_x``           this episode's target [m]
``normal_force``       per finger: summed contact normal force on the workpiece [N]
``friction_force``     per finger: friction force magnitude on the workpiece [N]
``side_force``         per finger: horizontal (squeezing) part of the normal force [N]
``hold_time``          time held at the target height [s] (the pick's; unused by the place)
``crush_limit``        this episode's crush limit [N] (hidden from the observation)
``valid``              no finger through itself or another (``invalid``: the messages, when not)
``reward_place``       ``w_place (psi_t - psi_{t-1})``, the carry towards the target
``reward_*``           v1's terms: ``reward_lift``, ``reward_success``, ``reward_squeeze`` (0),
                       ``reward_drop`` (0), ``reward_crush``, ``reward_contact``, ``reward_touch`` (0)
=====================  ==========================================================================
"""

from __future__ import annotations

from simgrip.envs.pick_fragile_v6 import V6_W_DROP
from simgrip.envs.pick_place_v4 import FragilePlaceEnvV4

__all__ = ["FragilePlaceEnvV5"]


class FragilePlaceEnvV5(FragilePlaceEnvV4):
    """``simgrip/PlaceFragile-v5``: ``PlaceFragile-v4`` (pinch from a pre-grasp, carry to a target, set down)
    with ``w_drop = 0`` (:mod:`simgrip.envs.pick_place_v5`; info ``is_success``, ``workpiece_lift``, ``crushed``,
    ``dropped``, ``place_error``, ``carried``, ``target_x``; ``reset``'s info ``start_gap``).  Arguments: v4's."""

    def __init__(self, *, w_drop: float = V6_W_DROP, **kwargs):
        super().__init__(w_drop=w_drop, **kwargs)
