r"""K fingers around a fragile sphere (issue 18): ``simgrip/PickSphereFragile-v0``.

:class:`~simgrip.envs.pick_fragile.FragilePickMultiEnv` (``K = 3`` fingers around the palm axis) with the
workpiece a sphere resting on the table, centred under the palm.  A sphere is not held by friction on vertical
faces: the tips curl under its equator and each contact's normal tilts up, so the support is part geometry,
part friction.

**Crush window.**  The sphere survives a normal force of at most ``crush_limit`` [N] on any one finger (the
finger's summed contact normal force on it at the end of every control step, 50 Hz, as a tactile sensor reads
it); more crushes it (the episode terminates as a failure, ``info["crushed"]``).  The least normal force with
which ``K`` fingers can carry the weight is ``N_hold = m g / (K sqrt(1 + mu^2))``: each finger carries ``m g /
K`` upwards, and a contact force of that size has the least normal component when it lies on the edge of the
friction cone, pointing straight up (the contact normal then tilted ``atan(mu)`` from vertical; a contact on the
equator needs ``m g / (K mu)``, one at the bottom ``m g / K``).  It is a lower bound on every finger's force in
a quasi-static hold, so ``crush_limit = r N_hold`` with ``r`` log-uniform in ``crush_ratio_range = (1.5, 2.5)``
leaves a window of width ``r`` above the best possible grip.  Closing further presses the tips harder into the
sphere (the fingers' elastic squeeze, which does not scale with the weight), and too little curvature lets the
sphere slip through the fingers (a drop).

The draw (SI): diameter uniform in ``(0.04, 0.09)`` m, an egg to an orange (narrower spheres bring the tips
together under them; the fingers do not collide with each other in the model), mass log-uniform in
``(0.01, 0.2)`` kg, friction uniform in ``(0.3, 1.2)``, centred (``offset_max = 0``), palm start ``(0.1, 0.105)``
m (above the largest sphere; a controller moves the palm to its grasp height).

Sensing is :class:`~simgrip.envs.pick_multi.PickMultiEnv`'s observation (finger shapes, tips, curvature command
and actual value, palm height, the sphere's position, tilt, velocity and spin relative to the palm, its lift, the
fingers' contact forces as ``log(1 + F/W)``); hidden: mass, friction, crush limit (``reset``'s ``info`` and the
attributes ``crush_limit``, ``hold_force`` hold them for oracles).  The diameter is not in the observation, but
the sphere's centre height above the table (palm height plus its relative ``z``) is its radius.

Info keys (every ``step``; the same as the other fragile envs):

=====================  ==========================================================================
key                    meaning
=====================  ==========================================================================
``is_success``         lifted ``target_height`` and held ``hold_time``, never crushed (terminates)
``workpiece_lift``     sphere centre's height gain since the start of the episode [m]
``crushed``            a finger's normal force exceeded ``crush_limit`` this step (terminates)
``dropped``            lifted, then sank ``drop_distance`` relative to the palm (terminates)
``knocked_over``       pushed > 3 cm sideways (a sphere does not tip over; terminates)
``normal_force``       per finger: summed contact normal force on the sphere [N]
``crush_limit``        this episode's crush limit [N] (hidden from the observation)
``reward_crush``       the crush term of this step's reward (``-w_drop`` or 0, plus the taken-back lift)
=====================  ==========================================================================

plus :class:`~simgrip.envs.pick_multi.PickMultiEnv`'s reward terms (``reward_lift``, ``reward_success``,
``reward_squeeze``, ``reward_drop``), the per-finger ``friction_force`` and ``side_force`` [N],
``fingers_touching``, ``hold_time`` [s] and ``valid`` (``invalid``: the messages) as in
:mod:`simgrip.envs.pick_fragile`.

Baselines on held-out seeds 6000-6049 (``python -m simgrip.envs.baselines --env simgrip/PickSphereFragile-v0
--policy P --seeds 6000-6049 --out docs/baselines/PickSphereFragile-v0-P.json``): random 0 %, best constant
0 %, best open-loop 30 %, oracle 88 %, observation-only 98 %.  The open-loop family is the claw one (the palm
moved for a fixed time to the scripted controller's grasp height for the mid-range sphere, ramp to a constant
curvature at a rate of the grid, lift at a speed of the grid).  **The issue's target (fixed schedules <= 20 %)
is not met**: below the equator the hold is largely support, whose force scales with the weight by itself, so
one gentle curvature (action 0.5, ``kappa_bar = -2.5``) holds 30 % of the spheres inside their windows; most of
its failures push a sphere whose size does not match its fixed grasp height away (knocked over, 21 of 50) or
crush a light one (14).  History: with diameters ``(0.04, 0.075)`` m and the palm started at ``(0.085, 0.09)``
m the same run gave open-loop 48 %, observation-only 98 %; the diameter range was widened after that run (so
these seeds are no longer untouched by the choice).  On seeds 5000-5049 the widened task gave observation-only
43/50 at ``crush_ratio_range = (1.5, 2.5)``, and with the earlier palm start the open-loop curvatures 0.4 and
0.5 held 3-4 of 30 (seeds 5000-5029; ``(1.6, 2.6)``: 6 of 30), an estimate the held-out 30 % shows optimistic.
The oracle eases the grip above the window's middle and so drops or
crushes a few more spheres than the observation-only controller (88 %).
"""

from __future__ import annotations

import math

from simgrip.envs.pick_fragile import FRAGILE_DEFAULTS, FragilePickMultiEnv

__all__ = ["FragileSphereEnv", "SPHERE_DEFAULTS"]

#: the sphere's draw where it differs from :data:`~simgrip.envs.pick_fragile.FRAGILE_DEFAULTS`
SPHERE_DEFAULTS = {"crush_ratio_range": (1.5, 2.5), "size_range": (0.04, 0.09), "palm_start": (0.1, 0.105)}


class FragileSphereEnv(FragilePickMultiEnv):
    """``simgrip/PickSphereFragile-v0``: ``K`` fingers around a fragile sphere, crush limit
    ``r m g / (K sqrt(1 + mu^2))`` per finger.

    See :mod:`simgrip.envs.pick_sphere_fragile` for the window, the draw and the info table
    (``info["is_success"]``, ``info["workpiece_lift"]``, ``info["crushed"]``, ``info["dropped"]``).  Arguments:
    those of :class:`~simgrip.envs.pick_fragile.FragilePickMultiEnv` (``shapes`` fixed to ``("sphere",)``) with
    the defaults ``crush_ratio_range = (1.5, 2.5)``, ``size_range = (0.04, 0.09)`` m, ``palm_start = (0.1, 0.105)``
    m.
    """

    def __init__(self, *, crush_ratio_range=SPHERE_DEFAULTS["crush_ratio_range"],
                 size_range=SPHERE_DEFAULTS["size_range"], mass_range=FRAGILE_DEFAULTS["mass_range"],
                 palm_start=SPHERE_DEFAULTS["palm_start"], **kwargs):
        shapes = kwargs.pop("shapes", ("sphere",))
        if tuple(shapes) != ("sphere",):
            raise ValueError(f"shapes must be ('sphere',) for PickSphereFragile, got {shapes!r}")
        super().__init__(crush_ratio_range=crush_ratio_range, size_range=size_range, mass_range=mass_range,
                         shapes=("sphere",), palm_start=palm_start, **kwargs)

    def _hold_force(self) -> float:
        """The least normal force per finger that carries the weight, ``m g / (K sqrt(1 + mu^2))`` [N]."""
        w = self.workpiece
        return w.mass * self.g / (self.K * math.sqrt(1.0 + w.friction ** 2))
