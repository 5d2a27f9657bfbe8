"""Gymnasium environments over simgrip's scene builder (shipped as ``simgrip.envs``).

Importing this package registers the environments (lazy string entry points,
time limits set here, ``step`` never truncates):

================================  ========================================  =========
id                                what                                      max steps
================================  ========================================  =========
``simgrip/Pick-v1``               Grip I: palm-down tip pinch (50 Hz)       200 (4 s)
``simgrip/PickCradle-v1``         Grip III: cradle from a pedestal (50 Hz)  250 (5 s)
``simgrip/PickMulti-v0``          K fingers around a box, cylinder, sphere  200 (4 s)
``simgrip/PickFragile-v7``        Grip I pinch of a fragile workpiece       300 (6 s)
``simgrip/PickMultiFragile-v7``   K fingers around a fragile workpiece      300 (6 s)
``simgrip/PlaceFragile-v8``       pinch, carry to a target, set down        400 (8 s)
``simgrip/PickCradleFragile-v6``  Grip III cradle, hand start height drawn  300 (6 s)
``simgrip/PickSphereFragile-v6``  K fingers around a sphere, height drawn   300 (6 s)
================================  ========================================  =========

The five fragile tasks (a hidden crush limit per episode) command the curvature through a valve (the action
is its rate, :mod:`simgrip.envs.pick_fragile_v2`) and observe the contact forces on a tactile sensor's scale
(:mod:`simgrip.envs.pick_fragile_v3`); the pinch, the K fingers and the pick-and-place start from a pre-grasp
(:mod:`simgrip.envs.pick_fragile_v4`, :mod:`simgrip.envs.pick_place_v4`); none pays reward per touching step, the
claws pay for approaching the grasp height (:mod:`simgrip.envs.pick_fragile_v5`, :mod:`simgrip.envs.pick_claw_v5`);
the pinch, the K fingers and the pick-and-place charge no drop penalty, so a crush is never cheaper than a drop
(:mod:`simgrip.envs.pick_fragile_v6`, :mod:`simgrip.envs.pick_place_v5`); the pick-and-place pays a grip that
holds the workpiece up 0.5 s, the pinch's success, as a milestone (:mod:`simgrip.envs.pick_place_v6`), and
keeps the lift pay of a carried workpiece as it is lowered, paying its set-down over the target
(:mod:`simgrip.envs.pick_place_v7`); the palm's target moves along a line within each control step and the crush
rule reads each finger's largest force within it (:mod:`simgrip.envs.pick_fragile_v7`).
Their older versions are retired, not registered: ``PickFragile`` and ``PickMultiFragile`` v0-v6,
``PickCradleFragile`` and ``PickSphereFragile`` v0-v5 and ``PlaceFragile`` v0-v7 (``RETIRED``);
``gym.make(retired_spec("simgrip/PickFragile-v2"))`` still builds one exactly, with its time limit.

>>> import gymnasium as gym, simgrip.envs
>>> env = gym.make("simgrip/Pick-v1")          # doctest: +SKIP

Extra keyword arguments of ``gym.make`` go to :class:`simgrip.envs.pick.PickEnv`
(:class:`simgrip.envs.pick_multi.PickMultiEnv` for ``PickMulti``).  ``ENV_IDS``
are the two-finger ids (``PickEnv``), ``MULTI_ENV_IDS`` the K-finger ones.
``FRAGILE_ENV_IDS`` are the registered fragile ids.
The v0 ids of ``Pick`` and ``PickCradle`` are retired (v1 changed the reward and the observation, see the
version history in :class:`~simgrip.envs.pick.PickEnv`); Gymnasium answers
``gym.make("simgrip/Pick-v0")`` with ``DeprecatedEnv`` naming v1, and a retired fragile id with
``DeprecatedEnv`` naming its newest version.
"""

from __future__ import annotations

from gymnasium.envs.registration import EnvSpec, register, registry

__all__ = ["ENV_IDS", "FRAGILE_ENV_IDS", "MULTI_ENV_IDS", "RETIRED", "make_spec", "register_envs", "retired_spec"]

#: id -> (entry point, kwargs, max_episode_steps)
_ENVS = {
    "simgrip/Pick-v1": ("simgrip.envs.pick:PickEnv", {"grip": "I"}, 200),
    "simgrip/PickCradle-v1": ("simgrip.envs.pick:PickEnv", {"grip": "III"}, 250),
    "simgrip/PickMulti-v0": ("simgrip.envs.pick_multi:PickMultiEnv", {}, 200),
    # the newest of each: the palm's target ramped within the control step and the crush rule on each finger's
    # peak force within it (simgrip.envs.pick_fragile_v7), over the versions retired below
    "simgrip/PickFragile-v7": ("simgrip.envs.pick_fragile_v7:FragilePickEnvV7", {}, 300),
    "simgrip/PickMultiFragile-v7": ("simgrip.envs.pick_fragile_v7:FragilePickMultiEnvV7", {}, 300),
    "simgrip/PlaceFragile-v8": ("simgrip.envs.pick_fragile_v7:FragilePlaceEnvV8", {}, 400),
    "simgrip/PickCradleFragile-v6": ("simgrip.envs.pick_fragile_v7:FragileCradleEnvV6", {}, 300),
    "simgrip/PickSphereFragile-v6": ("simgrip.envs.pick_fragile_v7:FragileSphereEnvV6", {}, 300),
}
#: Retired ids (issue 18), not registered: id -> (entry point, kwargs, max_episode_steps), as they were
#: registered.  Each task's newest version (in ``_ENVS``) subclasses its class; ``gym.make`` of a retired id
#: raises ``gymnasium.error.DeprecatedEnv`` naming that version; :func:`retired_spec` builds one exactly
#: (the stored baselines in ``docs/baselines/`` and the reference of ``tests/test_env_step_reference.py``
#: were recorded over them).
RETIRED = {
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
    # the curvature through a valve (its action a rate; cradle and sphere v3), simgrip.envs.pick_fragile_v2
    "simgrip/PickFragile-v2": ("simgrip.envs.pick_fragile_v2:FragilePickEnvV2", {}, 300),
    "simgrip/PickMultiFragile-v2": ("simgrip.envs.pick_fragile_v2:FragilePickMultiEnvV2", {}, 300),
    "simgrip/PlaceFragile-v2": ("simgrip.envs.pick_fragile_v2:FragilePlaceEnvV2", {}, 400),
    "simgrip/PickCradleFragile-v3": ("simgrip.envs.pick_fragile_v2:FragileCradleEnvV3", {}, 300),
    "simgrip/PickSphereFragile-v3": ("simgrip.envs.pick_fragile_v2:FragileSphereEnvV3", {}, 300),
    # the tactile forces on the sensor's scale (simgrip.envs.pick_fragile_v3), started straight
    "simgrip/PickFragile-v3": ("simgrip.envs.pick_fragile_v3:FragilePickEnvV3", {}, 300),
    "simgrip/PickMultiFragile-v3": ("simgrip.envs.pick_fragile_v3:FragilePickMultiEnvV3", {}, 300),
    "simgrip/PlaceFragile-v3": ("simgrip.envs.pick_fragile_v3:FragilePlaceEnvV3", {}, 400),
    # started from a pre-grasp, masses up to 0.25 kg (simgrip.envs.pick_fragile_v4), paying every touch step
    "simgrip/PickFragile-v4": ("simgrip.envs.pick_fragile_v4:FragilePickEnvV4", {}, 300),
    "simgrip/PickMultiFragile-v4": ("simgrip.envs.pick_fragile_v4:FragilePickMultiEnvV4", {}, 300),
    # the hand started at an unknown height, the tactile scale (simgrip.envs.pick_fragile_v3), paying every touch step
    "simgrip/PickCradleFragile-v4": ("simgrip.envs.pick_fragile_v3:FragileCradleEnvV4", {}, 300),
    "simgrip/PickSphereFragile-v4": ("simgrip.envs.pick_fragile_v3:FragileSphereEnvV4", {}, 300),
    # the pre-grasp without the per-step touch pay (simgrip.envs.pick_fragile_v5), charging a drop 5
    "simgrip/PickFragile-v5": ("simgrip.envs.pick_fragile_v5:FragilePickEnvV5", {}, 300),
    "simgrip/PickMultiFragile-v5": ("simgrip.envs.pick_fragile_v5:FragilePickMultiEnvV5", {}, 300),
    # pick-and-place from a pre-grasp without the touch pay (simgrip.envs.pick_place_v4), charging a drop 5
    "simgrip/PlaceFragile-v4": ("simgrip.envs.pick_place_v4:FragilePlaceEnvV4", {}, 400),
    # pick-and-place without the drop penalty (simgrip.envs.pick_place_v5), not paying a grip that holds
    "simgrip/PlaceFragile-v5": ("simgrip.envs.pick_place_v5:FragilePlaceEnvV5", {}, 400),
    # pick-and-place paying a grip that holds (simgrip.envs.pick_place_v6); lowering takes the lift pay back
    "simgrip/PlaceFragile-v6": ("simgrip.envs.pick_place_v6:FragilePlaceEnvV6", {}, 400),
    # the valve, the tactile scale (simgrip.envs.pick_fragile_v3), the pinch and the K fingers from a pre-grasp
    # (simgrip.envs.pick_fragile_v4) without the touch pay (v5) and the drop penalty (simgrip.envs.pick_fragile_v6);
    # the place paying the set-down (simgrip.envs.pick_place_v7); the claws paid for the approach
    # (simgrip.envs.pick_claw_v5): the palm's target held over each control step, the crush rule at its end
    "simgrip/PickFragile-v6": ("simgrip.envs.pick_fragile_v6:FragilePickEnvV6", {}, 300),
    "simgrip/PickMultiFragile-v6": ("simgrip.envs.pick_fragile_v6:FragilePickMultiEnvV6", {}, 300),
    "simgrip/PlaceFragile-v7": ("simgrip.envs.pick_place_v7:FragilePlaceEnvV7", {}, 400),
    "simgrip/PickCradleFragile-v5": ("simgrip.envs.pick_claw_v5:FragileCradleEnvV5", {}, 300),
    "simgrip/PickSphereFragile-v5": ("simgrip.envs.pick_claw_v5:FragileSphereEnvV5", {}, 300),
}
ENV_IDS = tuple(k for k, v in _ENVS.items() if v[0] == "simgrip.envs.pick:PickEnv")
MULTI_ENV_IDS = tuple(k for k, v in _ENVS.items() if v[0] == "simgrip.envs.pick_multi:PickMultiEnv")
FRAGILE_ENV_IDS = tuple(k for k, v in _ENVS.items()
                        if v[0].split(":")[0] in ("simgrip.envs.pick_fragile_v3", "simgrip.envs.pick_fragile_v4",
                                                  "simgrip.envs.pick_fragile_v5", "simgrip.envs.pick_fragile_v6",
                                                  "simgrip.envs.pick_claw_v5", "simgrip.envs.pick_place_v7",
                                                  "simgrip.envs.pick_fragile_v7"))


def retired_spec(env_id: str) -> EnvSpec:
    """The :class:`~gymnasium.envs.registration.EnvSpec` of a retired id (a key of ``RETIRED``), exactly as it
    was registered (entry point, keyword arguments, ``max_episode_steps``): ``gym.make(retired_spec(env_id))``
    builds it, keyword arguments of ``gym.make`` going to its class as for a registered id.

    Raises ValueError naming ``env_id`` when it is not a retired id (a registered one is made by its id)."""
    if not isinstance(env_id, str) or env_id not in RETIRED:
        registered = isinstance(env_id, str) and env_id in _ENVS
        raise ValueError(f"env_id: {env_id!r} is not a retired simgrip id"
                         + ("; it is registered: gym.make it by its id" if registered else
                            f" (retired: {', '.join(RETIRED)})"))
    entry, kwargs, steps = RETIRED[env_id]
    return EnvSpec(id=env_id, entry_point=entry, kwargs=dict(kwargs), max_episode_steps=steps)


def make_spec(env_id):
    """What ``gym.make`` builds ``env_id`` from: a retired id's :func:`retired_spec`, anything else as it is (a
    registered id; ``gym.make`` names an unknown one)."""
    return retired_spec(env_id) if isinstance(env_id, str) and env_id in RETIRED else env_id


def register_envs() -> None:
    """Register the simgrip environments with Gymnasium (idempotent)."""
    for env_id, (entry, kwargs, steps) in _ENVS.items():
        if env_id not in registry:
            register(id=env_id, entry_point=entry, kwargs=dict(kwargs), max_episode_steps=steps)


register_envs()
