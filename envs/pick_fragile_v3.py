r"""The fragile tasks with a tactile sensor that resolves their forces: v3 (cradle and sphere v4), issue 18.

``simgrip/PickFragile-v3``, ``simgrip/PickMultiFragile-v3``, ``simgrip/PlaceFragile-v3``,
``simgrip/PickCradleFragile-v4`` and ``simgrip/PickSphereFragile-v4`` are the valve versions of
:mod:`simgrip.envs.pick_fragile_v2` (``PickFragile-v2`` ... ``PickSphereFragile-v3``) with **one change: the
tactile observation's scale**.  Every contact force ``F`` (per finger: normal, friction magnitude) is observed
as ``log(1 + F / W)``; v2 took ``W`` as the task's mean workpiece weight (2.5 N for the pinch's 5-500 g draw),
v3 takes the sensor's resolution ``W = TACTILE_RESOLUTION = 0.01`` N (a tactile skin resolving ~10 mN; the
entry's bound, 20, is reached at ``F ~ 5e6`` N, never).

Why: a fragile workpiece's window is multiplicative, ``N_hold <= N <= r N_hold`` (``r = 1.6-2.6``), and its
``N_hold`` spans 0.02-8 N over the draw.  With ``W = 2.5`` N the window of a 5 g berry, 0.02-0.05 N, is
observed as 0.008-0.02: a feature a default MLP cannot tell from no contact.  With ``W = 0.01`` N the entry is
``~log(F / W)`` above a few ``W``: the window is a band of the same width, ``log r = 0.47-0.96``, whatever the
workpiece, and a crushed berry reads as differently from a held one as a crushed cup from a held cup.
Nothing the agent senses is added (v2 observed the same force, compressed); the hidden properties stay
hidden, and every fixed schedule is unaffected (the physics and the draw are v2's, so the constant-action and
open-loop baselines are v2's).  The scripted controllers read the force through ``env._force_unit`` and act
as on v2.

Measured while designing (Stable-Baselines3 PPO defaults, one env, one torch thread; held-out seeds
8000-8019; v2 through a wrapper that rescales the observed forces, ``/tmp`` harness): the two training seeds
that reached 0 % on ``PickFragile-v2`` after 15 CPU-minutes (seeds 1 and 2 of
``docs/baselines/rl_pick_v2/``: one settled on touching without lifting, one on never touching) reached 20 %
and 40 % after 5 CPU-minutes with the rescaled forces.  The registered results are in the README's table
(``docs/baselines/rl_pick_v3/``, ``rl_multi_v3/``).

Everything else (the draw, the valve, v1's reward, the info keys) is the previous version's.  ``PickFragile-v3`` and
``PickMultiFragile-v3`` are retired: :mod:`simgrip.envs.pick_fragile_v4` starts them from a pre-grasp.

Info keys (every ``step``, the same in all five; PlaceFragile adds four, below):

=====================  ==========================================================================
key                    meaning
=====================  ==========================================================================
``is_success``         lifted ``target_height`` and held ``hold_time``, never crushed (terminates;
                       PlaceFragile: carried and set down on the target, :mod:`simgrip.envs.pick_place`)
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
``reward_lift``        v1's reward terms (:mod:`simgrip.envs.pick_fragile_v1`): lift progress,
``reward_success``     success, squeeze (0), drop or knock-over, crush (graded), first contact
``reward_squeeze``     of every finger, touching
``reward_drop``
``reward_crush``
``reward_contact``
``reward_touch``
``reward_place``       PlaceFragile: progress towards the target (v0's term)
``place_error``        PlaceFragile: ``|x - x_t|``, the workpiece's distance from the target [m]
``carried``            PlaceFragile: the workpiece has been carried (lifted ``carry_height``)
``target_x``           PlaceFragile: the target's ``x`` [m]
=====================  ==========================================================================
"""

from __future__ import annotations

import math

import numpy as np

from simgrip.envs.pick_fragile_v2 import (FragileCradleEnvV3, FragilePickEnvV2, FragilePickMultiEnvV2,
                                          FragilePlaceEnvV2, FragileSphereEnvV3)

__all__ = ["FragilePickEnvV3", "FragilePickMultiEnvV3", "FragilePlaceEnvV3", "FragileCradleEnvV4",
           "FragileSphereEnvV4", "TACTILE_RESOLUTION"]

#: v3's tactile scale ``W`` [N]: contact forces are observed as ``log(1 + F / W)`` (v2: the mean weight)
TACTILE_RESOLUTION = 0.01


class _Tactile:
    """v3's tactile scale (a mixin before a v2 fragile env): ``tactile_resolution`` [N], default 0.01."""

    def __init__(self, *, tactile_resolution: float = TACTILE_RESOLUTION, **kwargs):
        try:
            if isinstance(tactile_resolution, (bool, np.bool_)):  # True is not a force (it was 1 N)
                raise TypeError
            w = float(tactile_resolution)
        except (TypeError, ValueError):
            raise ValueError(f"tactile_resolution must be a positive number of newtons, "
                             f"got {tactile_resolution!r}") from None
        if not (math.isfinite(w) and w > 0.0):
            raise ValueError(f"tactile_resolution must be a positive number of newtons, got {tactile_resolution!r}")
        self._tactile_unit = w  # read by the parent's __init__ (PickEnv / PickMultiEnv) as the scale W
        super().__init__(**kwargs)

    @property
    def tactile_resolution(self) -> float:
        """The tactile scale ``W`` [N]: each contact force ``F`` is observed as ``log(1 + F / W)``."""
        return self._tactile_unit


class FragilePickEnvV3(_Tactile, FragilePickEnvV2):
    """``simgrip/PickFragile-v3``: ``PickFragile-v2`` (two-finger pinch through the valve) with the tactile
    forces observed on the sensor's scale (:mod:`simgrip.envs.pick_fragile_v3`; info ``is_success``,
    ``workpiece_lift``, ``crushed``, ``dropped``).  Arguments: v2's plus ``tactile_resolution = 0.01`` N."""


class FragilePickMultiEnvV3(_Tactile, FragilePickMultiEnvV2):
    """``simgrip/PickMultiFragile-v3``: ``PickMultiFragile-v2`` (``K = 3`` fingers around a cylinder) with the
    tactile forces on the sensor's scale (:mod:`simgrip.envs.pick_fragile_v3`; info ``is_success``,
    ``workpiece_lift``, ``crushed``, ``dropped``)."""


class FragilePlaceEnvV3(_Tactile, FragilePlaceEnvV2):
    """``simgrip/PlaceFragile-v3``: ``PlaceFragile-v2`` (pick, carry, set down) with the tactile forces on the
    sensor's scale (:mod:`simgrip.envs.pick_fragile_v3`; info ``is_success``, ``workpiece_lift``, ``crushed``,
    ``dropped``, ``place_error``, ``carried``, ``target_x``)."""


class FragileCradleEnvV4(_Tactile, FragileCradleEnvV3):
    """``simgrip/PickCradleFragile-v4``: ``PickCradleFragile-v3`` (the cradle through the valve, hand started at
    an unknown height) with the tactile forces on the sensor's scale (:mod:`simgrip.envs.pick_fragile_v3`; info
    ``is_success``, ``workpiece_lift``, ``crushed``, ``dropped``)."""


class FragileSphereEnvV4(_Tactile, FragileSphereEnvV3):
    """``simgrip/PickSphereFragile-v4``: ``PickSphereFragile-v3`` (``K = 3`` fingers around a sphere, hand
    started at an unknown height) with the tactile forces on the sensor's scale
    (:mod:`simgrip.envs.pick_fragile_v3`; info ``is_success``, ``workpiece_lift``, ``crushed``, ``dropped``)."""
