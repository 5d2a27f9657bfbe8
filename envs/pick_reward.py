"""The pick environment's reward terms (see the Rewards table of :class:`simgrip.envs.pick.PickEnv`).

``reward = lift + success + squeeze + drop``: progress paid as height gained (a
potential difference), a one-off success bonus, a bounded penalty for
squeezing the box's sides beyond what holds it, and a one-off drop penalty.
:class:`PickReward` holds the weights and one box's constants (made once per
episode, called every step); :func:`pick_reward` is the same as one call,
returning the sum and the terms (for ``info``).
"""

from __future__ import annotations

__all__ = ["PickReward", "pick_reward", "progress"]


def progress(gain: float, target_height: float, lost: bool) -> float:
    """The progress potential ``phi = clip(gain / target_height, 0, 1)``, 0 once the box is lost (gain [m])."""
    if lost:
        return 0.0
    # min(max(x, 0.0), 1.0) written out (per step; the same value: max keeps x unless 0.0 > x, NaN and -0.0
    # included, min keeps it unless 1.0 < it)
    x = gain / target_height
    x = 0.0 if 0.0 > x else x
    return 1.0 if 1.0 < x else x


class PickReward:
    """One episode's reward: the weights and the box's constants, bound once.

    Parameters
    ----------
    box_mass, g, friction
        The episode's box mass [kg], gravity [m/s^2] and finger-box friction.
    w_lift, w_success, w_squeeze, w_drop, squeeze_margin
        The weights and the squeeze allowance (times the least normal force that holds the box).
    """

    __slots__ = ("w_lift", "w_success", "w_squeeze", "w_drop", "weight", "allow")

    def __init__(self, *, box_mass: float, g: float, friction: float, w_lift: float, w_success: float,
                 w_squeeze: float, w_drop: float, squeeze_margin: float):
        self.w_lift, self.w_success, self.w_squeeze, self.w_drop = w_lift, w_success, w_squeeze, w_drop
        self.weight = box_mass * g
        # the least total normal force that holds the box by friction on two sides is m g / (2 mu) per side
        self.allow = squeeze_margin * self.weight / (2.0 * friction)

    def __call__(self, phi: float, phi_prev: float, success: bool, lost: bool, s0: float, s1: float) -> tuple:
        """``(reward, lift, success, squeeze, drop)`` of one step.

        ``phi``, ``phi_prev``: progress (:func:`progress`) after and before the step; ``success``, ``lost``: the
        step ends the episode with a success, or with the box dropped or knocked over; ``s0``, ``s1``: horizontal
        (squeezing) component of each finger's normal forces on the box [N].
        """
        r_lift = self.w_lift * (phi - phi_prev)
        # squeeze beyond what holds the box, side contacts only, bounded per step
        weight, allow = self.weight, self.allow
        x0, x1 = s0 - allow, s1 - allow  # max(x, 0.0) / weight, written out (max keeps x unless 0.0 > x)
        x0 = (0.0 if 0.0 > x0 else x0) / weight
        x1 = (0.0 if 0.0 > x1 else x1) / weight
        r_squeeze = -0.5 * self.w_squeeze * (x0 / (1.0 + x0) + x1 / (1.0 + x1))
        r_success = self.w_success if success else 0.0
        r_drop = -self.w_drop if lost else 0.0
        return r_lift + r_success + r_squeeze + r_drop, r_lift, r_success, r_squeeze, r_drop


def pick_reward(*, phi: float, phi_prev: float, success: bool, lost: bool, side_forces, box_mass: float,
                g: float, friction: float, w_lift: float, w_success: float, w_squeeze: float, w_drop: float,
                squeeze_margin: float) -> tuple[float, dict]:
    """One step's reward and its terms (:class:`PickReward` for one call).

    Parameters
    ----------
    phi, phi_prev : float
        Progress (:func:`progress`) after and before the step.
    success, lost : bool
        The step ends the episode with a success, or with the box dropped or knocked over.
    side_forces : (float, float)
        Horizontal (squeezing) component of each finger's normal forces on the box [N].
    box_mass, g, friction
        The episode's box mass [kg], gravity [m/s^2] and finger-box friction.
    w_lift, w_success, w_squeeze, w_drop, squeeze_margin
        The weights and the squeeze allowance (times the least normal force that holds the box).

    Returns
    -------
    (float, dict)
        The reward and ``{"reward_lift", "reward_success", "reward_squeeze", "reward_drop"}``.
    """
    s0, s1 = side_forces
    reward, r_lift, r_success, r_squeeze, r_drop = PickReward(
        box_mass=box_mass, g=g, friction=friction, w_lift=w_lift, w_success=w_success, w_squeeze=w_squeeze,
        w_drop=w_drop, squeeze_margin=squeeze_margin)(phi, phi_prev, success, lost, s0, s1)
    return reward, {"reward_lift": r_lift, "reward_success": r_success, "reward_squeeze": r_squeeze,
                    "reward_drop": r_drop}
