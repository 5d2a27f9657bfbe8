"""Gymnasium environments over simgrip's scene builder (shipped as ``simgrip.envs``).

Importing this package registers the environments (lazy string entry points,
time limits set here, ``step`` never truncates):

================================  ========================================  =========
id                                what                                      max steps
================================  ========================================  =========
``simgrip/Pick-v1``               Grip I: palm-down tip pinch (50 Hz)       200 (4 s)
``simgrip/PickCradle-v1``         Grip III: cradle from a pedestal (50 Hz)  250 (5 s)
``simgrip/PickMulti-v0``          K fingers around a box, cylinder, sphere  200 (4 s)
``simgrip/PickFragile-v0``        Grip I pinch of a fragile workpiece       300 (6 s)
``simgrip/PickMultiFragile-v0``   K fingers around a fragile workpiece      300 (6 s)
``simgrip/PlaceFragile-v0``       pinch, carry to a target, set down        400 (8 s)
``simgrip/PickCradleFragile-v0``  Grip III cradle of a fragile box          300 (6 s)
``simgrip/PickSphereFragile-v0``  K fingers around a fragile sphere         300 (6 s)
``simgrip/...Fragile-v1``         the five above, v1's shaped reward        as v0
``simgrip/PickCradleFragile-v2``  v1's cradle, palm start height 13-29 cm   300 (6 s)
``simgrip/PickSphereFragile-v2``  v1's sphere, palm start height 10-22 cm   300 (6 s)
``simgrip/PickFragile-v2``        v1's pinch, curvature through a valve     300 (6 s)
``simgrip/PickMultiFragile-v2``   v1's K fingers, through a valve           300 (6 s)
``simgrip/PlaceFragile-v2``       v1's pick-and-place, through a valve      400 (8 s)
``simgrip/PickCradleFragile-v3``  v2's cradle, through a valve              300 (6 s)
``simgrip/PickSphereFragile-v3``  v2's sphere, through a valve              300 (6 s)
================================  ========================================  =========

>>> import gymnasium as gym, simgrip.envs
>>> env = gym.make("simgrip/Pick-v1")          # doctest: +SKIP

Extra keyword arguments of ``gym.make`` go to :class:`simgrip.envs.pick.PickEnv`
(:class:`simgrip.envs.pick_multi.PickMultiEnv` for ``PickMulti``).  ``ENV_IDS``
are the two-finger ids (``PickEnv``), ``MULTI_ENV_IDS`` the K-finger ones.
The v0 ids are retired (v1 changed the reward and the observation, see the
version history in :class:`~simgrip.envs.pick.PickEnv`); Gymnasium answers
``gym.make("simgrip/Pick-v0")`` with ``DeprecatedEnv`` naming v1.
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

__all__ = ["ENV_IDS", "FRAGILE_ENV_IDS", "MULTI_ENV_IDS", "register_envs"]

#: id -> (entry point, kwargs, max_episode_steps)
_ENVS = {
    "simgrip/Pick-v1": ("simgrip.envs.pick:PickEnv", {"grip": "I"}, 200),
    "simgrip/PickCradle-v1": ("simgrip.envs.pick:PickEnv", {"grip": "III"}, 250),
    "simgrip/PickMulti-v0": ("simgrip.envs.pick_multi:PickMultiEnv", {}, 200),
    # issue 18: fragile workpieces (a crush limit per episode), see simgrip.envs.pick_fragile
    "simgrip/PickFragile-v0": ("simgrip.envs.pick_fragile:FragilePickEnv", {}, 300),
    "simgrip/PickMultiFragile-v0": ("simgrip.envs.pick_fragile:FragilePickMultiEnv", {}, 300),
    "simgrip/PlaceFragile-v0": ("simgrip.envs.pick_place:FragilePlaceEnv", {}, 400),
    "simgrip/PickCradleFragile-v0": ("simgrip.envs.pick_cradle_fragile:FragileCradleEnv", {}, 300),
    "simgrip/PickSphereFragile-v0": ("simgrip.envs.pick_sphere_fragile:FragileSphereEnv", {}, 300),
    # v1: the same tasks, a reward a default learner can climb (simgrip.envs.pick_fragile_v1)
    "simgrip/PickFragile-v1": ("simgrip.envs.pick_fragile_v1:FragilePickEnvV1", {}, 300),
    "simgrip/PickMultiFragile-v1": ("simgrip.envs.pick_fragile_v1:FragilePickMultiEnvV1", {}, 300),
    "simgrip/PlaceFragile-v1": ("simgrip.envs.pick_fragile_v1:FragilePlaceEnvV1", {}, 400),
    "simgrip/PickCradleFragile-v1": ("simgrip.envs.pick_fragile_v1:FragileCradleEnvV1", {}, 300),
    "simgrip/PickSphereFragile-v1": ("simgrip.envs.pick_fragile_v1:FragileSphereEnvV1", {}, 300),
    # v2: v1 with the hand started at an unknown height (a fixed descent misses the grasp height)
    "simgrip/PickCradleFragile-v2": ("simgrip.envs.pick_cradle_fragile_v2:FragileCradleEnvV2", {}, 300),
    "simgrip/PickSphereFragile-v2": ("simgrip.envs.pick_sphere_fragile_v2:FragileSphereEnvV2", {}, 300),
    # the newest of each: the curvature through a valve (its action a rate), simgrip.envs.pick_fragile_v2
    "simgrip/PickFragile-v2": ("simgrip.envs.pick_fragile_v2:FragilePickEnvV2", {}, 300),
    "simgrip/PickMultiFragile-v2": ("simgrip.envs.pick_fragile_v2:FragilePickMultiEnvV2", {}, 300),
    "simgrip/PlaceFragile-v2": ("simgrip.envs.pick_fragile_v2:FragilePlaceEnvV2", {}, 400),
    "simgrip/PickCradleFragile-v3": ("simgrip.envs.pick_fragile_v2:FragileCradleEnvV3", {}, 300),
    "simgrip/PickSphereFragile-v3": ("simgrip.envs.pick_fragile_v2:FragileSphereEnvV3", {}, 300),
}
ENV_IDS = tuple(k for k, v in _ENVS.items() if v[0] == "simgrip.envs.pick:PickEnv")
MULTI_ENV_IDS = tuple(k for k, v in _ENVS.items() if v[0] == "simgrip.envs.pick_multi:PickMultiEnv")
FRAGILE_ENV_IDS = tuple(k for k, v in _ENVS.items() if v[0].split(":")[0] in (
    "simgrip.envs.pick_fragile", "simgrip.envs.pick_place", "simgrip.envs.pick_cradle_fragile",
    "simgrip.envs.pick_sphere_fragile", "simgrip.envs.pick_fragile_v1", "simgrip.envs.pick_cradle_fragile_v2",
    "simgrip.envs.pick_sphere_fragile_v2", "simgrip.envs.pick_fragile_v2"))


def register_envs() -> None:
    """Register the simgrip environments with Gymnasium (idempotent)."""
    for env_id, (entry, kwargs, steps) in _ENVS.items():
        if env_id not in registry:
            register(id=env_id, entry_point=entry, kwargs=dict(kwargs), max_episode_steps=steps)


register_envs()
