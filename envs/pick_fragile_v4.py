r"""The fragile pinch and K-finger tasks started from a pre-grasp: v4, issue 18.

``simgrip/PickFragile-v4`` and ``simgrip/PickMultiFragile-v4`` are ``PickFragile-v3`` and
``PickMultiFragile-v3`` (:mod:`simgrip.envs.pick_fragile_v3`: the valve, the tactile sensor's scale) with two
changes:

1. **A pre-grasp start.**  A pick pipeline hands the grasp controller a hand already placed around the
   workpiece with the fingers pre-curled short of it; the controller's job starts there.  Each episode draws
   a gap ``g`` uniform in ``gap_range = (0.003, 0.010)`` m and starts every finger at rest in the shape of
   the curvature command whose rest shape (no gravity, no contact) clears the workpiece by ``g``: the least
   signed distance between the fingers' geoms and the workpiece's (:func:`mujoco.mj_geomDistance`) is ``g``,
   found by bisection on the command (:func:`pre_grasp_curvature`).  The reset's settle then lets the
   fingers sag under gravity (~2 mm nearer).  The valve starts at that command (observed as
   ``kappa_command``; ``reset``'s ``info["start_gap"]`` holds ``g``).  v3 started straight, so every
   controller first travelled ~0.4 of the command's range; closing quickly there left the pneumatic lag a
   backlog of curvature that arrived with the first touch and crushed the light workpieces (the oracle
   crushed 9 of PPO's 50 held-out seeds 8000-8049, all 5-10 g).
2. **The mass range** ``V4_MASS = (0.005, 0.25)`` kg, log-uniform (v2/v3: up to 0.5 kg).  Above ~0.25 kg the
   soft contact creeps under the weight during the hold (MuJoCo's contacts admit a slow slip under a steady
   tangential load): v3's oracle dropped 4 of 50 seeds 6100-6149 and crushed 2 more, every one 0.245-0.49 kg,
   with the grip force at the middle of the window; held by a lower force for longer (a slower lift) it
   dropped 12.  A task whose best controller cannot hold a piece tells a learner nothing.

Everything else (the crush window 1.6-2.6, size and friction, the observation, v1's reward, the info keys of
:mod:`simgrip.envs.pick_fragile_v3`'s table) is v3's.  The draw of width, friction, palm height and crush
ratio per seed is v3's (the gap is drawn after them); the mass is drawn from the new range.

Info keys (every ``step``, v3's; ``reset``'s info adds ``start_gap`` [m], the drawn gap):

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
``reward_lift``        v1's reward terms (:mod:`simgrip.envs.pick_fragile_v1`): lift progress,
``reward_success``     success, squeeze (0), drop or knock-over, crush (graded), first contact
``reward_squeeze``     of every finger, touching
``reward_drop``
``reward_crush``
``reward_contact``
``reward_touch``
=====================  ==========================================================================
"""

from __future__ import annotations

import math

import mujoco

from simgrip.envs.arguments import check_range
from simgrip.envs.pick_fragile_v3 import FragilePickEnvV3, FragilePickMultiEnvV3

__all__ = ["FragilePickEnvV4", "FragilePickMultiEnvV4", "GAP_RANGE", "V4_MASS", "pre_grasp_curvature"]

#: the pre-grasp gap's range [m], drawn uniform per episode
GAP_RANGE = (0.003, 0.010)
#: the workpiece mass range of v4 [kg], drawn log-uniform (v2/v3: (0.005, 0.5))
V4_MASS = (0.005, 0.25)
#: the scan's step in ``kappa_bar`` (a tenth of a radian of tip angle per finger length, ~1 cm of tip travel)
_SCAN = 0.25
#: bisection steps within one scan step: the command found within 0.25 / 2**20 in ``kappa_bar``
_BISECTIONS = 20


def _clearance(model, data, pairs) -> float:
    """The least signed distance [m] between the geoms of the contact ``pairs`` at ``data.qpos``'s pose
    (``mj_kinematics``; distances above 0.2 m are reported as 0.2)."""
    mujoco.mj_kinematics(model, data)
    g1, g2 = model.pair_geom1, model.pair_geom2
    return min(mujoco.mj_geomDistance(model, data, int(g1[p]), int(g2[p]), 0.2, None) for p in pairs)


def pre_grasp_curvature(model, data, pairs, hinge_qpos, unit_rest, gap: float, curled: float) -> float:
    """The least curled curvature ``kappa_bar`` in ``[curled, 0]`` whose rest shape clears the workpiece by
    ``gap`` [m] (the first the closing fingers reach).

    ``hinge_qpos`` are the fingers' hinge addresses in ``qpos`` and ``unit_rest`` their rest angles per unit
    curvature (the same shapes); ``pairs`` the finger-workpiece contact pairs; ``curled`` the most curled
    curvature of the command's range (negative: the fingers curl towards the workpiece).  The clearance of
    the rest shape (the rest of ``data.qpos`` as it is) is scanned from straight towards ``curled`` in steps
    of :data:`_SCAN` until it drops to ``gap``, then bisected in that step; the command returned is the
    bracket's open end (clearance just above ``gap``).  0 (straight) where the straight fingers clear it by
    ``gap`` or less, or where no shape of the range comes that near (a fully curled finger rolls up past a
    small workpiece: the clearance is not monotone in the curvature, hence the scan).  ``data.qpos`` is left
    at the returned shape.
    """
    def clearance(k):
        data.qpos[hinge_qpos] = unit_rest * k
        return _clearance(model, data, pairs)

    open_ = 0.0
    if clearance(open_) > gap:
        steps = max(1, math.ceil(-curled / _SCAN))
        for i in range(1, steps + 1):
            closed = max(curled, -i * _SCAN)
            if clearance(closed) <= gap:
                for _ in range(_BISECTIONS):
                    mid = 0.5 * (open_ + closed)
                    if clearance(mid) > gap:
                        open_ = mid
                    else:
                        closed = mid
                break
            open_ = closed
        else:  # never that near: start straight
            open_ = 0.0
    clearance(open_)
    return open_


class _PreGrasp:
    """v4's pre-grasp start and mass range (a mixin before a v3 env); ``gap_range`` [m]."""

    _MASS_ARG = "box_mass_range"

    def __init__(self, *, gap_range=GAP_RANGE, **kwargs):
        self.gap_range = check_range("gap_range", gap_range)
        if not (self.gap_range[0] > 0.0 and math.isfinite(self.gap_range[1])):
            raise ValueError(f"gap_range must be two finite gaps above 0 m, got {gap_range!r}")
        kwargs.setdefault(self._MASS_ARG, V4_MASS)
        self.start_gap = math.nan
        super().__init__(**kwargs)

    def _start_shape(self):
        # called by the parent's reset after the workpiece and the palm are placed, before the settle
        gap = float(self.np_random.uniform(*self.gap_range))
        pairs, hinges, unit = self._pre_grasp_handles()
        k = pre_grasp_curvature(self.model, self.data, pairs, hinges, unit, gap, float(self.kappa_range[0]))
        self._start_kappa(k)
        self.start_gap = gap

    def reset(self, *, seed=None, options=None):
        obs, info = super().reset(seed=seed, options=options)
        info["start_gap"] = self.start_gap
        return obs, info


class FragilePickEnvV4(_PreGrasp, FragilePickEnvV3):
    """``simgrip/PickFragile-v4``: ``PickFragile-v3`` (two-finger pinch through the valve) started from a
    pre-grasp, masses 5-250 g (:mod:`simgrip.envs.pick_fragile_v4`; info ``is_success``, ``workpiece_lift``,
    ``crushed``, ``dropped``; ``reset``'s info ``start_gap``).  Arguments: v3's plus ``gap_range = (0.003,
    0.010)`` m; ``box_mass_range`` defaults to ``V4_MASS``."""

    def _pre_grasp_handles(self):
        return self._finger_pair_ids, self._spring_idx, self._unit_rest2.ravel()

    def _start_kappa(self, k: float):
        self._kcmd = self._kact = (k, k)
        self._set_rest(k, k)


class FragilePickMultiEnvV4(_PreGrasp, FragilePickMultiEnvV3):
    """``simgrip/PickMultiFragile-v4``: ``PickMultiFragile-v3`` (``K = 3`` fingers around a cylinder) started
    from a pre-grasp, masses 5-250 g (:mod:`simgrip.envs.pick_fragile_v4`; info ``is_success``,
    ``workpiece_lift``, ``crushed``, ``dropped``; ``reset``'s info ``start_gap``).  Arguments: v3's plus
    ``gap_range``; ``mass_range`` defaults to ``V4_MASS``."""

    _MASS_ARG = "mass_range"

    def _pre_grasp_handles(self):
        return self._pm.finger_pairs, self._pm.fingers.joint_qpos.ravel(), self._unit_rest.ravel()

    def _start_kappa(self, k: float):
        self._kcmd = [k] * len(self._kcmd)
        self._kact = [k] * len(self._kact)
        self._set_kappa(self._kact)
