r"""Pick-and-place paid for a grip that holds: ``PlaceFragile-v6``, issue 18.

``simgrip/PlaceFragile-v6`` is ``PlaceFragile-v5`` (:mod:`simgrip.envs.pick_place_v5`: the pinch's pre-grasp start,
no touch pay, no drop penalty; carry to a target drawn per episode, set down there) with **only the reward
changed**: a grip that has held the workpiece ``carry_height`` up, both fingers on it, for ``grip_time`` (0.5 s,
the pinch's ``hold_time``) is paid ``w_hold = 10`` once, and keeps that pay whatever happens next (as the contact
pay is kept).  The state it is paid in is checked for fingers through themselves or each other on that step
(``info["valid"]``, fresh there whatever the every-25-steps schedule says); a grip in an impossible state is not
paid until a valid step.  The draw, the observation, the action, and what success, a crush, a drop and a knock-over
are (and when an episode terminates) are v4's, so every fixed-schedule and scripted baseline of v4 holds for v6
with the same seeds (``docs/baselines/PlaceFragile-v4-*.json``).

Why: the pinch (``PickFragile-v6``) ends its episode with a success when the grip has held its workpiece up
0.5 s, and its pay is banked there; PPO learns that behind the probe offset (:mod:`simgrip.envs.action_offset`;
the pinch's v5 found 69 and 88 successes in its first 81,920 steps, seeds 0 and 1).  On v3-v5 the same grip is a
waypoint: the episode goes on, and the crush or the drop that a policy which cannot yet stop closing meets next
takes the lift back, so every episode returned at most the contact pay and the reward had nothing to climb (v5
behind the same offset, the same steps: 0 of 1,368 and 0 of 1,541 training episodes returned more than 1).  v6
pays the pinch's milestone and keeps it (the Gymnasium environments page, "PlaceFragile-v6").

Measured (that page): the same screens on v6 found 45 of 1,189 and 140 of 1,709 training episodes returning more
than 1.  PPO with SB3 defaults behind the offset ``(-0.4, 0, 0.2)`` with
:class:`~simgrip.envs.scripted_start.ScriptedStart` ``(0.5)`` in training learns to grip, lift and hold, then
loses the piece: 0 % held-out success (seeds 8000-8049) at 15, 30 and 45 CPU-minutes in each of 3 training seeds.

Rewards: v5's (v1's table, :mod:`simgrip.envs.pick_fragile_v1`, plus ``w_place``; ``reward_touch`` and
``reward_drop`` always 0) plus ``reward_hold``: ``+w_hold`` once, on the step the grip has held ``grip_time``.
Ordering: a success returns at least ``w_place + w_success = 40`` (a carry may start before the hold is paid);
no unsuccessful episode more than ``w_contact + w_lift + w_hold + w_place = 31``, and one that ends in a crush, a
drop or a knock-over no more than ``w_contact + w_hold = 11`` (the lift and the carry taken back); never
touching 0.

Info keys: v5's (every ``step``; ``reset``'s info adds ``start_gap`` [m] and ``target_x`` [m]) and two more:

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
``gripped``            held ``carry_height`` up, both fingers on it, for ``grip_time``, this episode
``target_x``           this episode's target [m]
``normal_force``       per finger: summed contact normal force on the workpiece [N]
``friction_force``     per finger: friction force magnitude on the workpiece [N]
``side_force``         per finger: horizontal (squeezing) part of the normal force [N]
``hold_time``          time held at ``carry_height`` or above, both fingers on it [s]
``crush_limit``        this episode's crush limit [N] (hidden from the observation)
``valid``              no finger through itself or another (``invalid``: the messages, when not)
``reward_hold``        ``+w_hold`` once, on the step the grip has held ``grip_time`` (kept after)
``reward_place``       ``w_place (psi_t - psi_{t-1})``, the carry towards the target
``reward_*``           v1's terms: ``reward_lift``, ``reward_success``, ``reward_squeeze`` (0),
                       ``reward_drop`` (0), ``reward_crush``, ``reward_contact``, ``reward_touch`` (0)
=====================  ==========================================================================
"""

from __future__ import annotations

from simgrip.envs.arguments import check_number as _num
from simgrip.envs.arguments import check_positive as _pos
from simgrip.envs.pick_place_v5 import FragilePlaceEnvV5
from simgrip.envs.pick_validity import record_validity

__all__ = ["FragilePlaceEnvV6", "V6_W_HOLD", "V6_GRIP_TIME"]

#: v6's pay for a grip that holds (v1-v5: none)
V6_W_HOLD = 10.0
#: how long the grip must hold the workpiece ``carry_height`` up [s] (the pinch's ``hold_time``)
V6_GRIP_TIME = 0.5


class FragilePlaceEnvV6(FragilePlaceEnvV5):
    """``simgrip/PlaceFragile-v6``: ``PlaceFragile-v5`` (pinch from a pre-grasp, carry to a target, set down)
    paying ``w_hold`` once for a grip held ``grip_time`` (:mod:`simgrip.envs.pick_place_v6`; info
    ``is_success``, ``workpiece_lift``, ``crushed``, ``dropped``, ``place_error``, ``carried``, ``gripped``,
    ``target_x``; ``reset``'s info ``start_gap``).  Arguments: v5's plus ``w_hold = 10`` and ``grip_time = 0.5``
    s."""

    def __init__(self, *, w_hold: float = V6_W_HOLD, grip_time: float = V6_GRIP_TIME, **kwargs):
        self.w_hold = _num("w_hold", w_hold, positive=False)
        self.grip_time = _pos("grip_time", grip_time)
        self._gripped = False
        super().__init__(**kwargs)

    def reset(self, *, seed=None, options=None):
        self._gripped = False
        return super().reset(seed=seed, options=options)

    def _step_checked(self, a: list):
        obs, reward, terminated, truncated, info = super()._step_checked(a)
        r_hold = 0.0
        lost = info["crushed"] or info["dropped"] or info["knocked_over"]
        if not self._gripped and not lost and info["hold_time"] >= self.grip_time - 1e-9 and self._valid_now(info):
            r_hold = self.w_hold
            self._gripped = True
        info["gripped"] = self._gripped
        info["reward_hold"] = r_hold
        return obs, reward + r_hold, terminated, truncated, info

    def _valid_now(self, info) -> bool:
        """Whether this step's state is valid, checked now where the every-k schedule did not (a grip through a
        finger is not paid; ``info["valid"]`` / ``info["invalid"]`` then hold the fresh check)."""
        if self._validity.checked:
            return info["valid"]
        return record_validity(info, self._validity.check_now(self.data.qpos.tolist(), self.data))
