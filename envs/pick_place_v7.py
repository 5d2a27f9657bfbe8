r"""Pick-and-place paid for setting the workpiece down: ``PlaceFragile-v7``, issue 18.

``simgrip/PlaceFragile-v7`` is ``PlaceFragile-v6`` (:mod:`simgrip.envs.pick_place_v6`: the pinch's pre-grasp
start, no touch pay, no drop penalty, a grip that holds paid once; carry to a target drawn per episode, set down
there) with **only the reward changed**: once the workpiece has been carried, lowering it no longer takes the
lift pay back, and lowering it over the target is paid.  With ``phi = clip(lift / carry_height, 0, 1)`` (the
lift pay's own progress) v7 adds the potential difference ``Psi_t - Psi_{t-1}`` with

    ``Psi = (1 - phi) (w_lift + w_down [place_error <= place_tolerance])`` once carried, ``0`` before and once lost

(``w_down = 10``).  The lift pay of v1-v6 is ``w_lift phi``, so once carried the two together pay ``w_lift``
whatever the height, plus ``w_down (1 - phi)`` over the target: the set-down is worth ``w_down`` and nowhere
costs anything.  A crush, a drop or a knock-over takes the whole of it back, with the lift, as before.  The
draw, the observation, the action, and what success, a crush, a drop and a knock-over are (and when an episode
terminates) are v4's, so every fixed-schedule and scripted baseline of v4 holds for v7 with the same seeds
(``docs/baselines/PlaceFragile-v4-*.json``).

Why (measured; the Gymnasium environments page, "PlaceFragile-v7"): v6's PPO learners (behind the probe offset,
with scripted starts, 45 CPU-minutes) grip, lift and carry, and then hover.  Replayed on the held-out seeds
8000-8049, 15 of one seed's 50 episodes ran out of time with the workpiece held 28-38 mm up, 7 of them within the
place tolerance (1 cm) of the target and 5 more within 1.6 cm (``examples/evaluate_policy.py``'s
``place_timeouts``: 15 / 3 / 6 held up, 7 / 0 / 5 over the target, in the three seeds).  On v1-v6 lowering a
carried workpiece takes back the ``w_lift = 10`` its lift was paid, before the ``w_success = 30`` of a set-down
that has rested ``place_time``: a valley the learner has to cross at random, with nothing paying the way down.  The
sum of a potential's differences over any path is its end value less its start (Ng, Harada and Russell, 1999), so
``Psi`` pays no path more than where it ends is worth; it says which way the set-down is, and the ordering below
keeps every success above every failure.

Measured (that page): PPO with SB3 defaults, 0 % held-out success (seeds 8000-8049) at 5, 10 and 15 CPU-minutes
in each of 3 training seeds; behind the probe offset with scripted starts, the same.  At 15 CPU-minutes the
learners still crush or drop most pieces they grip, before any carry; a two-seed screen at 45 CPU-minutes with
the same aids, 0 % at 15, 30 and 45, none of its timed-out episodes over the target.  Started from the pinch's
PPO policies (:mod:`simgrip.envs.warm_start`, ``--init-from``), the learners crush or drop nearly every piece:
0 % after 10 CPU-minutes, also with targets 0.5-2 cm away.

An option for a learner, not part of the task's definition: ``sideways_after_carry = True`` (default
``False``; ``gym.make(..., sideways_after_carry=True)``, ``--env-kwargs '{"sideways_after_carry": true}'`` in
the example scripts) ignores the palm's sideways command until the workpiece has been carried (``carried``),
so the palm cannot drag a piece it has not lifted: a pick-then-place interface.  With it the env is v7 given
``action[1] = 0`` on every step before the carry (``tests/test_pick_place_v7.py``).

Rewards: v6's plus ``reward_set_down = Psi_t - Psi_{t-1}``.  Ordering: a success returns at least ``w_success +
w_lift + 0.9 w_down = 49`` (the workpiece rests less than 3 mm, a tenth of ``carry_height``, above its start);
no unsuccessful episode more than ``w_contact + w_lift + w_hold + w_place + w_down = 41``, and one that ends in
a crush, a drop or a knock-over no more than ``w_contact + w_hold = 11``; never touching 0.

Info keys: v6's (every ``step``; ``reset``'s info adds ``start_gap`` [m] and ``target_x`` [m]) and one more:

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
``reward_set_down``    ``Psi_t - Psi_{t-1}``: the lift kept once carried, the set-down over the target
``reward_hold``        ``+w_hold`` once, on the step the grip has held ``grip_time`` (kept after)
``reward_place``       ``w_place (psi_t - psi_{t-1})``, the carry towards the target
``reward_*``           v1's terms: ``reward_lift``, ``reward_success``, ``reward_squeeze`` (0),
                       ``reward_drop`` (0), ``reward_crush``, ``reward_contact``, ``reward_touch`` (0)
=====================  ==========================================================================
"""

from __future__ import annotations

from simgrip.envs.arguments import check_bool
from simgrip.envs.arguments import check_number as _num
from simgrip.envs.pick_place_v6 import FragilePlaceEnvV6
from simgrip.envs.pick_reward import progress

__all__ = ["FragilePlaceEnvV7", "V7_W_DOWN", "set_down_potential"]

#: v7's pay for lowering a carried workpiece over the target (v1-v6: none; the lift was taken back)
V7_W_DOWN = 10.0


def set_down_potential(lift: float, carry_height: float, over_target: bool, w_lift: float, w_down: float) -> float:
    """``Psi = (1 - phi) (w_lift + w_down [over_target])``, ``phi = clip(lift / carry_height, 0, 1)``: v7's
    potential for a carried workpiece not lost (:mod:`simgrip.envs.pick_place_v7`; 0 otherwise, the caller's
    case).  ``lift``, ``carry_height`` [m]; ``w_lift``, ``w_down`` reward units."""
    phi = progress(lift, carry_height, False)  # the lift pay's own progress
    return (1.0 - phi) * (w_lift + (w_down if over_target else 0.0))


class FragilePlaceEnvV7(FragilePlaceEnvV6):
    """``simgrip/PlaceFragile-v7``: ``PlaceFragile-v6`` (pinch from a pre-grasp, a held grip paid, carry to a
    target, set down) whose carried workpiece keeps its lift pay when lowered and is paid ``w_down`` for being
    lowered over the target (:mod:`simgrip.envs.pick_place_v7`; info ``is_success``, ``workpiece_lift``,
    ``crushed``, ``dropped``, ``place_error``, ``carried``, ``gripped``, ``target_x``, ``reward_set_down``;
    ``reset``'s info ``start_gap``).  Arguments: v6's plus ``w_down = 10`` and ``sideways_after_carry = False``
    (the palm's sideways command ignored until carried: a learner's option, see the module docstring)."""

    def __init__(self, *, w_down: float = V7_W_DOWN, sideways_after_carry: bool = False, **kwargs):
        self.w_down = _num("w_down", w_down, positive=False)
        self.sideways_after_carry = check_bool("sideways_after_carry", sideways_after_carry)
        self._psi_down = 0.0
        super().__init__(**kwargs)

    def reset(self, *, seed=None, options=None):
        self._psi_down = 0.0
        return super().reset(seed=seed, options=options)

    def _step_checked(self, a: list):
        if self.sideways_after_carry and not self._carried:
            a = [a[0], 0.0, *a[2:]]
        obs, reward, terminated, truncated, info = super()._step_checked(a)
        lost = info["crushed"] or info["dropped"] or info["knocked_over"]
        psi = 0.0
        if info["carried"] and not lost:
            psi = set_down_potential(info["workpiece_lift"], self.carry_height,
                                     info["place_error"] <= self.place_tolerance, self.w_lift, self.w_down)
        r_down = psi - self._psi_down
        self._psi_down = psi
        info["reward_set_down"] = r_down
        return obs, reward + r_down, terminated, truncated, info
