r"""The fragile tasks, v1: the same tasks with a reward a default learner can climb (issue 18).

``simgrip/PickFragile-v1``, ``simgrip/PickMultiFragile-v1``, ``simgrip/PlaceFragile-v1``,
``simgrip/PickCradleFragile-v1`` and ``simgrip/PickSphereFragile-v1`` are their v0 envs
(:mod:`simgrip.envs.pick_fragile`, :mod:`simgrip.envs.pick_place`, :mod:`simgrip.envs.pick_cradle_fragile`,
:mod:`simgrip.envs.pick_sphere_fragile`) with **only the reward changed**: the draw, the observation, the
action, and what success, a crush, a drop and a knock-over are (and when an episode terminates) are v0's, line
for line (v1 calls v0's ``step`` and adds to its reward), so every fixed-schedule and scripted baseline of v0
holds for v1 with the same seeds.

Why (measured, ``docs/baselines/rl_pick_fragile/``): under v0's reward, random actions crush the workpiece
within 3-8 steps, so nearly every early episode ends at ``-w_drop = -10`` while keeping the fingers open
returns exactly 0; PPO and SAC with SB3 defaults settled on "fingers open" in all six runs (0 % success).  v1
pays the steps of a grasp the learner can reach before it can succeed (making contact with every finger,
keeping it, raising the workpiece), grades the crush penalty by how hard the limit was overrun (0 at the
limit: squeezing less is better even among crushes, and a gentle crush costs mostly the touch and lift it
ends), and drops the squeeze term (it read the hidden mass and friction every step; the crush limit now bounds
the grip).

A first design (no contact term, a crush penalty ``w_crush (1 + x / (1 + x)) / 2`` with ``w_crush = 5``) was
measured and rejected: PPO (SB3 defaults, seed 0) drove the curvature command past the fingers-open end and
stayed there (0 successes in 2264 training episodes, return exactly 0 from ~190k steps on), as under v0.  With
the initial exploration noise (``sigma = 1`` on each action) every curvature crushes within ~7-26 steps (12 of
12 seeds at every mean command), so only a reward in which touching and then crushing gently beats never
touching leaves a gradient away from "fingers open".

Measured with this reward (``python examples/rl_baselines.py --env simgrip/PickFragile-v1 --algo ppo --seeds 0
--minutes 15 --checkpoint-minutes 5 --eval-seeds 8000-8049 --jobs 1 --out OUT``, one seed, run at ``nice 19``;
``docs/baselines/rl_pick_fragile_v1/``): **0 % held-out success** at 5, 10 and 15 CPU-minutes (143k, 285k,
448k steps), 0 successes in 7004 training episodes.  The learner does climb this reward (mean training return
0.19 over the first 336 episodes, 2.7 over the last 583; episodes 8 -> 110 steps long), but to a local optimum:
close gently, keep touching, never lift (held-out return 4.4, 3.7, 3.4 at the checkpoints; on 3 of the first 8
held-out seeds it touches for the whole 300 steps with lift < 5 mm, the others crush a light workpiece within
3-12 steps).  The issue's 80 % is not reached: lifting while touching has yet to pay more than touching alone.

Rewards (every term in ``info``; ``T`` the registered time limit):

==================  ====================================================================  ==================
term (info key)     value per step                                                        over an episode
==================  ====================================================================  ==================
``reward_contact``  ``+w_contact`` once, on the first step on which every finger's        ``w_contact`` (1)
                    normal force on the workpiece is > 0 (tactile contact: sensed)
``reward_touch``    ``+w_touch`` when every finger's normal force on the workpiece is     ``<= w_touch T``
                    > 0 and the step did not end in a crush, drop or knock-over           (6; Place 8)
``reward_lift``     ``w_lift (phi_t - phi_{t-1})``, ``phi = clip(lift / target, 0, 1)``,  ``<= w_lift`` (10)
                    0 once lost or crushed (v0's; the lift is observed)
``reward_place``    PlaceFragile only: v0's ``w_place (psi_t - psi_{t-1})``               ``<= w_place`` (10)
``reward_success``  ``w_success`` once, on the terminating success step (v0's)            20 (Place 30)
``reward_crush``    on the crushing step: ``-w_crush x / (1 + x)``, ``x = (F - L) / L``,  ``(-w_crush, 0]``
                    ``F`` the largest finger normal force of the step (the reading that   plus the lift
                    defines the crush), ``L`` the hidden ``crush_limit``; plus the lift   taken back
                    progress taken back (``-w_lift phi``, as v0)
``reward_drop``     ``-w_drop`` once on a drop or knock-over (v0's term, v1's weight)     ``-w_drop`` (-5)
``reward_squeeze``  0 (``w_squeeze = 0``: v0's term read the hidden mass and friction)    0
==================  ====================================================================  ==================

Defaults: ``w_contact = 1``, ``w_touch = 0.02``, ``w_crush = 2``, ``w_drop = 5``, ``w_squeeze = 0``;
``w_lift``, ``w_success`` (and PlaceFragile's ``w_place``) as v0.  Ordering: any success returns at least
``w_lift + w_success = 30`` (Place: ``w_place + w_success = 40``); no unsuccessful episode returns more than
``w_contact + w_touch T + w_lift`` (17; Place ``w_contact + w_touch T + w_lift + w_place = 29``).  Never
touching returns 0; a crush gives up the lift earned and every later touch step, and costs up to ``w_crush``
more the harder the limit was overrun.  A flat charge on every training crush, whatever its overrun, is a learner's
option outside the task (:mod:`simgrip.envs.crush_charge`).

What each term reads: ``reward_contact`` and ``reward_touch`` the fingers' tactile normal forces (in the
observation as ``contact_force``); ``reward_lift`` and ``reward_place`` the workpiece's position (observed
relative to the palm); the success, drop and knock-over terms fixed weights paid at their events.  The only
hidden property a term reads is the crush limit ``L`` (and the grade's force ``F`` against it), used **only for
the penalty at the moment of the crush**, the event that ends the episode.  The grade uses the same
end-of-control-step reading (50 Hz) that the crush rule uses, so nothing is charged for an excess that rule did
not see.  No term pays a holding force approaching the slip threshold ``N_hold = m g / (K mu)``: that threshold
is hidden, and its sensed consequence, the workpiece rising with the palm instead of sliding in the grip, is
what ``reward_lift`` pays.

Info keys (every ``step``): v0's, unchanged in meaning (:mod:`simgrip.envs.pick_fragile`,
:mod:`simgrip.envs.pick_place`), plus ``reward_contact`` and ``reward_touch``:

=====================  ==========================================================================
key                    meaning
=====================  ==========================================================================
``is_success``         the episode ended in success (v0's rule; terminates)
``workpiece_lift``     workpiece centre's height gain since the start of the episode [m]
``crushed``            a finger's normal force exceeded ``crush_limit`` this step (terminates)
``dropped``            lifted, then sank ``drop_distance`` relative to the palm (terminates)
``knocked_over``       tilted > 30 degrees or pushed > 3 cm sideways (terminates)
``normal_force``       per finger: summed contact normal force on the workpiece [N]
``friction_force``     per finger: friction force magnitude on the workpiece [N]
``side_force``         per finger: horizontal (squeezing) part of the normal force [N]
``hold_time``          time held at the target height [s]
``crush_limit``        this episode's crush limit [N] (hidden from the observation)
``fingers_touching``   K-finger envs: how many fingers touch the workpiece
``valid``              no finger through itself or another (``invalid``: the messages, when not)
``reward_*``           the terms of the table above (``reward_lift``, ``reward_success``,
                       ``reward_squeeze``, ``reward_drop``, ``reward_crush``, ``reward_contact``,
                       ``reward_touch``;
                       PlaceFragile also ``reward_place``)
``place_error``        PlaceFragile: ``|x - x_t|`` [m]; ``carried``: lifted ``carry_height`` with
                       both fingers on it; ``target_x``: the target [m]
=====================  ==========================================================================
"""

from __future__ import annotations

from simgrip.envs.arguments import check_number as _num
from simgrip.envs.pick_cradle_fragile import FragileCradleEnv
from simgrip.envs.pick_fragile import FragilePickEnv, FragilePickMultiEnv
from simgrip.envs.pick_place import FragilePlaceEnv
from simgrip.envs.pick_sphere_fragile import FragileSphereEnv

__all__ = ["crush_overrun", "FragilePickEnvV1", "FragilePickMultiEnvV1", "FragilePlaceEnvV1", "FragileCradleEnvV1",
           "FragileSphereEnvV1", "V1_REWARD_DEFAULTS", "graded_crush"]

#: v1's reward weights (the others are v0's)
V1_REWARD_DEFAULTS = {"w_contact": 1.0, "w_touch": 0.02, "w_crush": 2.0, "w_drop": 5.0, "w_squeeze": 0.0}


def crush_overrun(force: float, limit: float) -> float:
    """The relative overrun ``x = max(force - limit, 0) / limit`` of a crush limit (``force``, ``limit`` [N],
    ``limit > 0``): what :func:`graded_crush` charges by."""
    return max(force - limit, 0.0) / limit


def graded_crush(force: float, limit: float, w_crush: float) -> float:
    """The size (>= 0) of v1's crush penalty: ``w_crush x / (1 + x)``, ``x = max(force - limit, 0) / limit``
    (``force``, ``limit`` [N], ``limit > 0``): 0 at the limit, ``w_crush / 2`` at twice it, rising towards
    ``w_crush`` for an overrun many times the limit (bounded, so one hard squeeze cannot outweigh an episode)."""
    x = crush_overrun(force, limit)
    return w_crush * x / (1.0 + x)


class _ShapedV1:
    """v1's reward on top of a v0 fragile env (a mixin placed before it): the contact and touch terms, the graded
    crush penalty (through :meth:`_crush_penalty`, the hook v0's crush rule calls) and v1's default weights."""

    _touched = False  # every finger has touched the workpiece this episode (reward_contact paid)

    def __init__(self, *, w_contact: float = V1_REWARD_DEFAULTS["w_contact"],
                 w_touch: float = V1_REWARD_DEFAULTS["w_touch"], w_crush: float = V1_REWARD_DEFAULTS["w_crush"],
                 w_drop: float = V1_REWARD_DEFAULTS["w_drop"], w_squeeze: float = V1_REWARD_DEFAULTS["w_squeeze"],
                 **kwargs):
        self.w_contact = _num("w_contact", w_contact, positive=False)
        self.w_touch = _num("w_touch", w_touch, positive=False)
        self.w_crush = _num("w_crush", w_crush, positive=False)
        super().__init__(w_drop=w_drop, w_squeeze=w_squeeze, **kwargs)

    def _crush_penalty(self, normal_force) -> float:
        return graded_crush(max(normal_force.tolist()), self.crush_limit, self.w_crush)

    def reset(self, *, seed=None, options=None):
        self._touched = False
        return super().reset(seed=seed, options=options)

    def _step_checked(self, a: list):
        obs, reward, terminated, truncated, info = super()._step_checked(a)
        lost = info["crushed"] or info["dropped"] or info["knocked_over"]
        touching = min(self._normal) > 0.0  # info["normal_force"], as floats
        r_touch = self.w_touch if touching and not lost else 0.0
        r_contact = 0.0
        if touching and not self._touched:  # the first contact of every finger (paid even on a crushing step)
            self._touched = True
            r_contact = self.w_contact
        info["reward_contact"] = r_contact
        info["reward_touch"] = r_touch
        return obs, reward + r_contact + r_touch, terminated, truncated, info


class FragilePickEnvV1(_ShapedV1, FragilePickEnv):
    """``simgrip/PickFragile-v1``: :class:`~simgrip.envs.pick_fragile.FragilePickEnv` with v1's reward (see
    :mod:`simgrip.envs.pick_fragile_v1`: the terms; ``info["is_success"]``, ``info["workpiece_lift"]``,
    ``info["crushed"]``, ``info["dropped"]`` as v0).  Arguments: v0's plus ``w_contact = 1``, ``w_touch =
    0.02``, ``w_crush = 2`` (and the defaults ``w_drop = 5``, ``w_squeeze = 0``)."""


class FragilePickMultiEnvV1(_ShapedV1, FragilePickMultiEnv):
    """``simgrip/PickMultiFragile-v1``: :class:`~simgrip.envs.pick_fragile.FragilePickMultiEnv` with v1's reward
    (:mod:`simgrip.envs.pick_fragile_v1`; the info keys ``is_success``, ``workpiece_lift``, ``crushed``,
    ``dropped`` as v0).  ``reward_contact`` and ``reward_touch`` ask every one of the ``K`` fingers to touch."""


class FragilePlaceEnvV1(_ShapedV1, FragilePlaceEnv):
    """``simgrip/PlaceFragile-v1``: :class:`~simgrip.envs.pick_place.FragilePlaceEnv` with v1's reward
    (:mod:`simgrip.envs.pick_fragile_v1`; ``reward_place`` and ``w_success = 30`` as v0; the info keys
    ``is_success``, ``workpiece_lift``, ``crushed``, ``dropped`` as v0)."""


class FragileCradleEnvV1(_ShapedV1, FragileCradleEnv):
    """``simgrip/PickCradleFragile-v1``: :class:`~simgrip.envs.pick_cradle_fragile.FragileCradleEnv` with v1's
    reward (:mod:`simgrip.envs.pick_fragile_v1`; info keys ``is_success``, ``workpiece_lift``, ``crushed``,
    ``dropped`` as v0)."""


class FragileSphereEnvV1(_ShapedV1, FragileSphereEnv):
    """``simgrip/PickSphereFragile-v1``: :class:`~simgrip.envs.pick_sphere_fragile.FragileSphereEnv` with v1's
    reward (:mod:`simgrip.envs.pick_fragile_v1`; info keys ``is_success``, ``workpiece_lift``, ``crushed``,
    ``dropped`` as v0)."""
