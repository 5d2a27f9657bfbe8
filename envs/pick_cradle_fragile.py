r"""The fragile cradle: Grip III with a crush limit (issue 18), ``simgrip/PickCradleFragile-v0``.

:class:`~simgrip.envs.pick_fragile.FragilePickEnv` on the cradle scene of ``simgrip/PickCradle-v1``
(:class:`~simgrip.envs.pick.PickEnv` with ``grip="III"``): the box (3.5 cm tall) stands on a narrow 4 cm pedestal,
the two fingers curl under its lower edges and carry it on their links.  The hold is **support**, not friction:
each finger carries half the weight at the box's lower edge (its corner on the finger's links or tip).

**Crush window.**  The workpiece survives a normal force of at most ``crush_limit`` [N] on any one finger (the
finger's summed contact normal force on it, read at the end of every control step, 50 Hz, as a tactile sensor
reads it); more crushes it (the episode terminates as a failure, ``info["crushed"]``).  The least force a finger
must bear is its share of the weight, ``N_hold = m g / 2`` (a support whose contact normal is vertical; a
tilted support with friction ``mu`` needs ``m g / (2 (cos t + mu sin t))``, a little less, and a finger that
also presses the box's side needs more).  ``crush_limit = r N_hold`` with ``r`` log-uniform in
``crush_ratio_range = (1.5, 2.5)``.  Too little curvature and the corners slide off the sagging fingers (a
drop: the box falls out of the cradle); more curvature presses the corners harder (the fingers' elastic squeeze
comes on top of the weight, and does not scale with it), which crushes a light box long before it troubles a
heavy one: mass is log-uniform over 10-200 g, so the squeeze that a 200 g box shrugs off is 20 times the
weight share of a 10 g one.

The draw (SI): mass log-uniform in ``(0.01, 0.2)`` kg, friction uniform in ``(0.3, 1.2)``, box width uniform in
``(0.04, 0.075)`` m (narrower boxes bring the tips together under the box; the fingers do not collide with each
other in the model, so closed further they would pass through each other and the state is invalid), palm start
``(0.13, 0.14)`` m (above the box: a controller must lower the palm around it first).

The observation, reward and sensing are :class:`~simgrip.envs.pick_fragile.FragilePickEnv`'s (those of
``PickEnv``: finger shapes, tips, curvature command and actual value, palm height, the box's height and velocity
relative to the palm, its lift, the fingers' contact forces as ``log(1 + F/W)``); hidden: mass, friction, crush
limit (``reset``'s ``info`` and the attributes ``crush_limit``, ``hold_force`` hold them for oracles).

Info keys (every ``step``; the same as the other fragile envs):

=====================  ==========================================================================
key                    meaning
=====================  ==========================================================================
``is_success``         lifted ``target_height`` (8 cm) and held ``hold_time``, never crushed (terminates)
``workpiece_lift``     box centre's height gain since the start of the episode [m]
``crushed``            a finger's normal force exceeded ``crush_limit`` this step (terminates)
``dropped``            lifted, then sank ``drop_distance`` relative to the palm: fell out (terminates)
``knocked_over``       tilted > 30 degrees or pushed > 3 cm sideways (terminates)
``normal_force``       per finger: summed contact normal force on the box [N]
``crush_limit``        this episode's crush limit [N] (hidden from the observation)
``reward_crush``       the crush term of this step's reward (``-w_drop`` or 0, plus the taken-back lift)
=====================  ==========================================================================

plus ``PickEnv``'s reward terms (``reward_lift``, ``reward_success``, ``reward_squeeze``, ``reward_drop``), the
per-finger ``friction_force`` and ``side_force`` [N], ``hold_time`` [s] and ``valid`` (``invalid``: the
messages) as in :mod:`simgrip.envs.pick_fragile`.

Baselines on held-out seeds 6000-6049 (``python -m simgrip.envs.baselines --env simgrip/PickCradleFragile-v0
--policy P --seeds 6000-6049 --out docs/baselines/PickCradleFragile-v0-P.json``): random 0 %, best constant 2 %,
best open-loop 42 %, oracle 80 %, observation-only 80 %.  The open-loop family here is the cradle's (lower the
palm with the claw open for a fixed time to the scripted controller's grasp height, ramp to a constant
curvature at a rate of the grid, lift at a speed of the grid); a constant action cannot both lower the palm
around the box and lift it, so the constant family's 2 % says little.  **The issue's target (fixed schedules
<= 20 %) is not met**: the hold is support, and a support's force scales with the weight by itself, so one
gentle curvature (action 0.4, ``kappa_bar = -3``) cradles 42 % of the boxes inside their windows.  The
observation-only controller's largest force (no limit, seeds 5000-5049) has quartiles 0.93, 1.0, 1.5
``N_hold``; the upper tail comes from boxes whose edge slides off the last link onto the tip during the lift.
The crush ratio range was chosen on seeds 5000-5049 (with that spread the controller would hold 75 % at
``(1.3, 1.7)``, 85 % at ``(1.5, 2.5)``).
"""

from __future__ import annotations

from simgrip.envs.pick_fragile import FRAGILE_DEFAULTS, FragilePickEnv

__all__ = ["FragileCradleEnv", "CRADLE_DEFAULTS"]

#: the cradle's draw where it differs from :data:`~simgrip.envs.pick_fragile.FRAGILE_DEFAULTS`
CRADLE_DEFAULTS = {"crush_ratio_range": (1.5, 2.5), "size_range": (0.04, 0.075), "palm_start": (0.13, 0.14)}


class FragileCradleEnv(FragilePickEnv):
    """``simgrip/PickCradleFragile-v0``: the Grip III cradle with a crush limit ``r m g / 2`` per finger.

    See :mod:`simgrip.envs.pick_cradle_fragile` for the window, the draw and the info table
    (``info["is_success"]``, ``info["workpiece_lift"]``, ``info["crushed"]``, ``info["dropped"]``).  Arguments:
    those of :class:`~simgrip.envs.pick_fragile.FragilePickEnv` (``grip`` is fixed to ``"III"``) with the defaults
    ``crush_ratio_range = (1.5, 2.5)``, ``box_width_range = (0.04, 0.075)`` m, ``palm_start = (0.13, 0.14)`` m,
    ``box_mass_range = (0.01, 0.2)`` kg, ``friction_range = (0.3, 1.2)``.
    """

    def __init__(self, *, crush_ratio_range=CRADLE_DEFAULTS["crush_ratio_range"],
                 box_width_range=CRADLE_DEFAULTS["size_range"], palm_start=CRADLE_DEFAULTS["palm_start"],
                 box_mass_range=FRAGILE_DEFAULTS["mass_range"], friction_range=FRAGILE_DEFAULTS["friction_range"],
                 **kwargs):
        if "grip" in kwargs and kwargs["grip"] not in ("III", "cradle"):
            raise ValueError(f"grip must be 'III' (the cradle) for PickCradleFragile, got {kwargs['grip']!r}")
        kwargs.pop("grip", None)
        super().__init__(grip="III", crush_ratio_range=crush_ratio_range, box_width_range=box_width_range,
                         palm_start=palm_start, box_mass_range=box_mass_range, friction_range=friction_range,
                         **kwargs)

    def _hold_force(self) -> float:
        """Each finger's share of the weight, ``m g / 2`` [N]: the least normal force a vertical support bears."""
        return 0.5 * self.box.mass * self.g
