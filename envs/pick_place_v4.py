r"""Pick-and-place started from a pre-grasp, without the per-step touch pay: ``PlaceFragile-v4``, issue 18.

``simgrip/PlaceFragile-v4`` is ``PlaceFragile-v3`` (:mod:`simgrip.envs.pick_place`: pinch the workpiece, carry
it to a target ``x_t`` drawn per episode and set it down there; the valve, the tactile sensor's scale of
:mod:`simgrip.envs.pick_fragile_v3`) with the two changes that made the pinch learnable, and nothing else:

1. **The pre-grasp start** of :mod:`simgrip.envs.pick_fragile_v4`: each episode draws a gap ``g`` uniform in
   ``gap_range = (0.003, 0.010)`` m and starts both fingers at rest in the shape of the curvature command whose
   rest shape clears the workpiece by ``g`` (:func:`~simgrip.envs.pick_fragile_v4.pre_grasp_curvature`); the
   valve starts at that command (``reset``'s ``info["start_gap"]`` holds ``g``); masses 5-250 g, log-uniform
   (``V4_MASS``; v3: up to 0.5 kg, where the soft contact creeps under the weight during a carry).
2. **No pay per touching step** (``w_touch = 0``; v1-v3: 0.02), as :mod:`simgrip.envs.pick_fragile_v5`.

Why (measured, ``docs/baselines/rl_place_v3``): PPO with SB3 defaults reached 0 % held-out success on v3 in all
3 training seeds after 15 CPU-minutes, return 0: started straight, no run ever touched the workpiece (0
successes in 7,329 training episodes).  A pick pipeline hands the grasp controller a hand placed around the
workpiece; the task starts there, as the pinch's v4 does.

The target's draw, the carry height (0.03 m), the place tolerance (0.01 m), the place time (0.3 s), the
action ``(curvature valve rate, palm x velocity, palm z velocity)``, the observation and v1's reward with
``w_place`` are v3's.  The draw of width, friction, palm height and crush ratio per seed is v3's (the gap is
drawn after them, then the target); the mass is drawn from the new range.  Ordering (v1's,
:mod:`simgrip.envs.pick_fragile_v1`, with ``w_touch = 0``): a success returns at least ``w_place + w_success =
40``; no unsuccessful episode (hovering over the target, never set down, included) more than ``w_contact +
w_lift + w_place = 21``; never touching 0.

Info keys (every ``step``; ``reset``'s info adds ``start_gap`` [m] and ``target_x`` [m]):

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
                       ``reward_drop``, ``reward_crush``, ``reward_contact``, ``reward_touch`` (0)
=====================  ==========================================================================
"""

from __future__ import annotations

from simgrip.envs.pick_fragile_v3 import FragilePlaceEnvV3
from simgrip.envs.pick_fragile_v4 import FragilePickEnvV4, _PreGrasp
from simgrip.envs.pick_fragile_v5 import V5_W_TOUCH

__all__ = ["FragilePlaceEnvV4"]


class FragilePlaceEnvV4(_PreGrasp, FragilePlaceEnvV3):
    """``simgrip/PlaceFragile-v4``: ``PlaceFragile-v3`` (pinch, carry to a target, set down) started from a
    pre-grasp, masses 5-250 g, ``w_touch = 0`` (:mod:`simgrip.envs.pick_place_v4`; info ``is_success``,
    ``workpiece_lift``, ``crushed``, ``dropped``, ``place_error``, ``carried``, ``target_x``; ``reset``'s info
    ``start_gap``).  Arguments: v3's plus ``gap_range = (0.003, 0.010)`` m; ``box_mass_range`` defaults to
    ``V4_MASS``."""

    def __init__(self, *, w_touch: float = V5_W_TOUCH, **kwargs):
        super().__init__(w_touch=w_touch, **kwargs)

    # the pinch's own (both read the env's attributes: here the place model's hinge addresses, which its palm x
    # slide shifts from the pick model's)
    _pre_grasp_handles = FragilePickEnvV4._pre_grasp_handles
    _start_kappa = FragilePickEnvV4._start_kappa
