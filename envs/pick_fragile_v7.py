r"""The fragile suite with a palm driven at a steady speed and a crush rule that reads the peak: issue 18.

``simgrip/PickFragile-v7``, ``simgrip/PickMultiFragile-v7``, ``simgrip/PlaceFragile-v8``,
``simgrip/PickCradleFragile-v6`` and ``simgrip/PickSphereFragile-v6`` are ``PickFragile-v6``,
``PickMultiFragile-v6`` (:mod:`simgrip.envs.pick_fragile_v6`), ``PlaceFragile-v7``
(:mod:`simgrip.envs.pick_place_v7`), ``PickCradleFragile-v5`` and ``PickSphereFragile-v5``
(:mod:`simgrip.envs.pick_claw_v5`) made with two arguments changed, the draw, the observation, the action and
the reward left as they were:

1. **``palm_ramp = True``** (before: False).  A palm action sets the speed of the palm servo's target over the
   control step, which moves along a line within the step (MuJoCo's ``intvelocity`` actuator,
   :mod:`simgrip.envs.palm_servo`) instead of jumping at the step's start and being held: the same target at
   every control step's end, reached as a palm driven at a steady speed moves.  The held target's 2 mm jumps
   (lifting at 0.1 m/s, 50 Hz) jerked the grip every step.
2. **``crush_at = "peak"``** (before: ``"end"``).  The crush rule reads each finger's largest normal force over
   the control step's ``frame_skip`` physics steps (MuJoCo contact sensors with a history,
   :mod:`simgrip.envs.touch_history`; ``info["peak_normal_force"]``), not its value at the step's end only.
   The tactile observation still reads the end of the step, as a skin sampled at the control rate would.

Why (measured; the Gymnasium environments page, "Forces within a control step", ``python -m
simgrip.envs.substep_forces --env OLDER_ID --seeds 8000-8049``, the retired id): under the older versions'
observation-only controller a
finger's force peaked within the step a median 1.02-1.74 times above the end-of-step value the crush rule read
(95th percentile up to 2.9), and 3-18 of each task's successes had a step whose force passed the piece's crush
limit unseen.  With the ramped palm the median ratio is 1.00; what stays is the impact of first touch, a real peak
of the model, which only the peak rule sees.  A workpiece is crushed by the largest force it feels.

Baselines (held-out seeds 6000-6049, the README's table, ``docs/baselines/ID-POLICY.json``; each version is
the older one made with ``palm_ramp=True, crush_at="peak"``, step for step, ``tests/test_pick_fragile_v7.py``):
random and the best constant action 0 % on every task, the best open-loop schedule 22 / 20 / 6 / 8 / 8 %
(pinch, K fingers, place, cradle, sphere); the pinch's, the K fingers' and the claws' scripted controllers close at
:data:`~simgrip.envs.scripted_fragile.PEAK_CLOSING_RATE` before first contact (a faster first touch's impact
crushes light pieces; the place's observation-only controller approaches at its own 0.0025): observation-only 94 / 94 / 100 / 88 / 94 %, the oracles 98 / 98 / 92 / 86 / 80 %.

Info keys (every ``step``): the older versions' (:mod:`simgrip.envs.pick_fragile_v6`,
:mod:`simgrip.envs.pick_place_v7`, :mod:`simgrip.envs.pick_claw_v5`), ``peak_normal_force`` added:

=======================  ==========================================================================
key                      meaning
=======================  ==========================================================================
``is_success``           lifted ``target_height`` and held ``hold_time`` (the place: set down on the
                         target and left), never crushed (terminates)
``workpiece_lift``       workpiece centre's height gain since the start of the episode [m]
``crushed``              a finger's largest normal force within the step exceeded ``crush_limit``
                         (terminates)
``dropped``              lifted, then sank ``drop_distance`` relative to the palm (terminates)
``knocked_over``         tilted or pushed sideways out of reach (terminates)
``normal_force``         per finger: summed contact normal force on the workpiece at the step's end [N]
``peak_normal_force``    per finger: its largest value over the step's physics steps [N]
``friction_force``       per finger: friction force magnitude on the workpiece [N]
``side_force``           per finger: horizontal (squeezing) part of the normal force [N]
``hold_time``            time held at the target height (the place: at ``carry_height``) [s]
``crush_limit``          this episode's crush limit [N] (hidden from the observation)
``fingers_touching``     K fingers and the sphere: how many fingers touch the workpiece
``valid``                no finger through itself or another (``invalid``: the messages, when not)
``place_error``          the place: ``|x - x_t|``, the workpiece's distance from the target [m]
``carried``              the place: lifted ``carry_height`` with both fingers on it, this episode
``gripped``              the place: held ``carry_height`` up, both fingers on it, for ``grip_time``
``target_x``             the place: this episode's target [m]
``reward_*``             the terms: ``reward_lift``, ``reward_success``, ``reward_squeeze`` (0),
                         ``reward_drop`` (0; the claws charge ``w_drop = 5``), ``reward_crush``, ``reward_contact``, ``reward_touch`` (0);
                         the place also ``reward_place``, ``reward_hold``, ``reward_set_down``; the claws
                         ``reward_approach``
=======================  ==========================================================================
"""

from __future__ import annotations

from simgrip.envs.pick_claw_v5 import FragileCradleEnvV5, FragileSphereEnvV5
from simgrip.envs.pick_fragile_v6 import FragilePickEnvV6, FragilePickMultiEnvV6
from simgrip.envs.pick_place_v7 import FragilePlaceEnvV7

__all__ = ["FragileCradleEnvV6", "FragilePickEnvV7", "FragilePickMultiEnvV7", "FragilePlaceEnvV8",
           "FragileSphereEnvV6", "RAMP_PEAK"]

#: the two arguments these versions change (their older versions': ``palm_ramp=False, crush_at="end"``)
RAMP_PEAK = {"palm_ramp": True, "crush_at": "peak"}


class _RampPeak:
    """The two defaults changed (a mixin before the older version's class): ``palm_ramp = True``,
    ``crush_at = "peak"``; both stay arguments."""

    def __init__(self, *, palm_ramp: bool = True, crush_at: str = "peak", **kwargs):
        super().__init__(palm_ramp=palm_ramp, crush_at=crush_at, **kwargs)


class FragilePickEnvV7(_RampPeak, FragilePickEnvV6):
    """``simgrip/PickFragile-v7``: ``PickFragile-v6`` (two-finger pinch from a pre-grasp) with the palm's target
    ramped within each control step and the crush rule on each finger's peak force within it
    (:mod:`simgrip.envs.pick_fragile_v7`; info ``is_success``, ``workpiece_lift``, ``crushed``, ``dropped``,
    ``peak_normal_force``).  Arguments: v6's, with the defaults ``palm_ramp = True``, ``crush_at = "peak"``."""


class FragilePickMultiEnvV7(_RampPeak, FragilePickMultiEnvV6):
    """``simgrip/PickMultiFragile-v7``: ``PickMultiFragile-v6`` (``K = 3`` fingers around a cylinder from a
    pre-grasp) with the palm's target ramped and the crush rule on the peak (:mod:`simgrip.envs.pick_fragile_v7`;
    info ``is_success``, ``workpiece_lift``, ``crushed``, ``dropped``, ``peak_normal_force``).  Arguments: v6's,
    with the defaults ``palm_ramp = True``, ``crush_at = "peak"``."""


class FragilePlaceEnvV8(_RampPeak, FragilePlaceEnvV7):
    """``simgrip/PlaceFragile-v8``: ``PlaceFragile-v7`` (pinch from a pre-grasp, carry to a target, set down)
    with both palm targets ramped and the crush rule on the peak (:mod:`simgrip.envs.pick_fragile_v7`; info
    ``is_success``, ``workpiece_lift``, ``crushed``, ``dropped``, ``peak_normal_force``, ``place_error``).
    Arguments: v7's, with the defaults ``palm_ramp = True``, ``crush_at = "peak"``."""


class FragileCradleEnvV6(_RampPeak, FragileCradleEnvV5):
    """``simgrip/PickCradleFragile-v6``: ``PickCradleFragile-v5`` (the cradle, hand started at an unknown height)
    with the palm's target ramped and the crush rule on the peak (:mod:`simgrip.envs.pick_fragile_v7`; info
    ``is_success``, ``workpiece_lift``, ``crushed``, ``dropped``, ``peak_normal_force``).  Arguments: v5's, with
    the defaults ``palm_ramp = True``, ``crush_at = "peak"``."""


class FragileSphereEnvV6(_RampPeak, FragileSphereEnvV5):
    """``simgrip/PickSphereFragile-v6``: ``PickSphereFragile-v5`` (``K = 3`` fingers around a sphere, hand started
    at an unknown height) with the palm's target ramped and the crush rule on the peak
    (:mod:`simgrip.envs.pick_fragile_v7`; info ``is_success``, ``workpiece_lift``, ``crushed``, ``dropped``,
    ``peak_normal_force``).  Arguments: v5's, with the defaults ``palm_ramp = True``, ``crush_at = "peak"``."""
