r"""The fragile cradle, v2: the hand starts at an unknown height (issue 18), ``simgrip/PickCradleFragile-v2``.

``simgrip/PickCradleFragile-v1`` (:mod:`simgrip.envs.pick_fragile_v1`: v0's task,
:mod:`simgrip.envs.pick_cradle_fragile`, with v1's shaped reward) with **two changes to the draw**: the palm
starts at a height drawn uniformly from ``palm_start = (0.13, 0.29)`` m (v0 and v1: ``(0.13, 0.14)``), i.e. the
hand arrives above the box at a height the controller must read rather than assume; and the box is at most
6.5 cm wide (``box_width_range = (0.04, 0.065)`` m; v0 and v1: up to 7.5 cm).  The box's height (3.5 cm), the
pedestal (4 cm), the crush window (``crush_limit = r m g / 2`` per finger, ``r`` log-uniform in ``(1.5, 2.5)``), the
reward (v1's, unchanged: its table is in :mod:`simgrip.envs.pick_fragile_v1`), the observation and the action
are v1's.

Why: in v0 the hold is support, whose force grows with the weight by itself, so one gentle curvature cradles
many boxes inside their window; what made v0's fixed schedule work (42 % held out) was that a fixed descent
time put the fingers under the box's lower edges, because the box's height relative to the hand barely varied
(1 cm).  With a 16 cm spread a fixed descent ends anywhere from 8 cm above to 8 cm below the grasp height:
too high, the tips close above the box's lower edge and squeeze its sides (a crush) or miss it; too low, the
palm and fingers press the box down on its pedestal (knocked over or crushed).  The palm's range (the palm
target height is kept in it) is ``palm_range = (0.05, 0.3)`` m (v0: ``(0.05, 0.25)``, raised to hold the higher
starts); every grasp height and start lies inside it.

The width: with v1's ``(0.04, 0.075)`` m and the wider start, the observation-only controller held 43 of 50 on
seeds 5000-5049 but **39 of 50 (78 %) on the held-out seeds 6000-6049**; 12 of its 18 crushes on the two sets
were of boxes wider than 6.5 cm (29 % of that range): 6 while closing, before the box left the pedestal (the
closing links pressing the box's sides), 6 during the lift.  The width was then capped at 6.5 cm (chosen on
seeds 5000-5049: observation-only 46 of 50, best open-loop 10 of 50), so seeds 6000-6049 are **not untouched**
by that choice; seeds 6100-6149, untouched, are reported beside them.

Per episode (SI):

====================  =========================================  ================================
drawn                 range                                      sensed by the agent?
====================  =========================================  ================================
palm start height     uniform ``(0.13, 0.29)`` m                 yes: ``palm_height``, and the
                                                                 box's position relative to the
                                                                 palm (``box_position``)
box width             uniform ``(0.04, 0.065)`` m                no (only through contact and
                                                                 the finger shapes)
box mass              log-uniform ``(0.01, 0.2)`` kg             no (hidden)
friction              uniform ``(0.3, 1.2)``                     no (hidden)
crush ratio ``r``     log-uniform ``(1.5, 2.5)``                 no (hidden; ``crush_limit``)
====================  =========================================  ================================

Sensed every step (:class:`~simgrip.envs.pick.PickEnv`'s observation): finger shapes, tips, curvature command
and actual value, palm height, the box's position and velocity relative to the palm, its lift, the fingers'
contact forces as ``log(1 + F/W)`` (a tactile sensor).  Hidden: mass, friction, crush limit (``reset``'s
``info`` and the attributes ``crush_limit``, ``hold_force`` hold them for oracles only).

Info keys (every ``step``; the same as the other fragile envs, v1's reward terms):

=====================  ==========================================================================
key                    meaning
=====================  ==========================================================================
``is_success``         lifted ``target_height`` (8 cm) and held ``hold_time``, never crushed (terminates)
``workpiece_lift``     box centre's height gain since the start of the episode [m]
``crushed``            a finger's normal force exceeded ``crush_limit`` this step (terminates)
``dropped``            lifted, then sank ``drop_distance`` relative to the palm: fell out (terminates)
``knocked_over``       tilted > 30 degrees or pushed > 3 cm sideways (terminates)
``normal_force``       per finger: summed contact normal force on the box [N]
``friction_force``     per finger: friction force magnitude on the box [N]
``side_force``         per finger: horizontal (squeezing) part of the normal force [N]
``hold_time``          time held at the target height [s]
``crush_limit``        this episode's crush limit [N] (hidden from the observation)
``valid``              no finger through itself or another (``invalid``: the messages, when not)
``reward_*``           v1's terms: ``reward_lift``, ``reward_success``, ``reward_squeeze`` (0),
                       ``reward_drop``, ``reward_crush``, ``reward_contact``, ``reward_touch``
=====================  ==========================================================================

Baselines: ``python -m simgrip.envs.baselines --env simgrip/PickCradleFragile-v2 --policy P --seeds A-B --out
docs/baselines/PickCradleFragile-v2-P.json`` (files: ``P.json`` seeds 6000-6049, ``P-6100.json`` seeds
6100-6149, ``openloop-tune.json`` seeds 5000-5049).  The open-loop family is :data:`OPENLOOP_GRID` (the claw
schedule of :mod:`simgrip.envs.baselines` with the descent time shifted by ``descent_shift`` steps); its best
member on seeds 5000-5049 (``kappa`` 0.5, ``ramp_steps`` 50, full lift speed, ``descent_shift`` -5: 10 of 50)
is then run on the held-out seeds; "optimistic" is the family's best on the held-out seeds themselves.  The
observation-only controller is :class:`~simgrip.envs.scripted_fragile.CradleFragilePolicy`: it reads the
grasp height off the observed palm height and box position, so the start height costs it only descent time;
the oracle (:class:`~simgrip.envs.scripted_fragile.OracleCradlePolicy`) also reads the hidden window.
Success, 95 % Clopper-Pearson interval, 50 episodes each:

========================================  ====================  ====================
policy                                    seeds 6000-6049       seeds 6100-6149
========================================  ====================  ====================
random                                    0 % (0-7 %)
best constant (on the seeds themselves)   0 % (0-7 %)
open-loop, tuned on 5000-5049             14 % (6-27 %)         4 % (0.5-14 %)
open-loop, optimistic                     14 % (6-27 %)         12 % (4.5-24 %)
observation-only                          96 % (86-99.5 %)      88 % (76-95 %)
oracle                                    96 % (86-99.5 %)
========================================  ====================  ====================

The constant grid (``KAPPA_GRID`` x ``PALM_GRID``, 51 actions) cannot lower the palm around the box and then lift
it.  Seeds 6000-6049 informed the width cap (see above); seeds 6100-6149 were run once, after every choice.
"""

from __future__ import annotations

from simgrip.envs.pick_fragile_v1 import FragileCradleEnvV1

__all__ = ["CRADLE_V2_PALM_RANGE", "CRADLE_V2_PALM_START", "CRADLE_V2_WIDTH", "FragileCradleEnvV2", "OPENLOOP_GRID"]

#: v2's palm start range [m] (v0/v1: (0.13, 0.14))
CRADLE_V2_PALM_START = (0.13, 0.29)
#: v2's palm target range [m] (v0/v1: (0.05, 0.25))
CRADLE_V2_PALM_RANGE = (0.05, 0.3)
#: v2's box width range [m] (v0/v1: (0.04, 0.075))
CRADLE_V2_WIDTH = (0.04, 0.065)

#: the open-loop family searched by ``python -m simgrip.envs.baselines --policy openloop``: claw open (action
#: 0.68) while the palm moves down at full speed for the steps that take a palm started mid-range to the grasp
#: height of the scripted controller for the mid-range box, plus ``descent_shift`` steps (0.2 cm each); then a
#: linear ramp to ``kappa`` over ``ramp_steps``, 10 steps' wait, lift at ``palm``.  The curvatures are those of
#: v0's full 17-value grid at which any v0 member succeeded on seeds 6000-6049 (0.3-0.5; every other curvature:
#: 0 of 50, ``docs/baselines/PickCradleFragile-v0-openloop.json``); the palm speed v0's best (full speed).
OPENLOOP_GRID = {"kappa": (0.3, 0.4, 0.5), "ramp_steps": (1, 50), "palm": (1.0,),
                 "descent_shift": (-10, -5, 0, 5, 10)}


class FragileCradleEnvV2(FragileCradleEnvV1):
    """``simgrip/PickCradleFragile-v2``: :class:`~simgrip.envs.pick_fragile_v1.FragileCradleEnvV1` with the palm
    started at a height drawn from ``palm_start = (0.13, 0.29)`` m, kept in ``palm_range = (0.05, 0.3)`` m, and
    the box width from ``box_width_range = (0.04, 0.065)`` m (see
    :mod:`simgrip.envs.pick_cradle_fragile_v2` for the draw, what is sensed, and the info table:
    ``info["is_success"]``, ``info["workpiece_lift"]``, ``info["crushed"]``, ``info["dropped"]``).  Arguments:
    v1's (v0's plus the reward weights)."""

    openloop_grid = OPENLOOP_GRID

    def __init__(self, *, palm_start=CRADLE_V2_PALM_START, palm_range=CRADLE_V2_PALM_RANGE,
                 box_width_range=CRADLE_V2_WIDTH, **kwargs):
        super().__init__(palm_start=palm_start, palm_range=palm_range, box_width_range=box_width_range, **kwargs)
