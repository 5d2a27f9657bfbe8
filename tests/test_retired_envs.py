"""The retired fragile ids (issue 18): not registered, Gymnasium's deprecation names the newest version, and
``simgrip.envs.retired_spec`` still builds each exactly as it was registered.

The retired tasks' behaviour (check_env, determinism, the bit-for-bit step reference, the baselines' gaps) is
tested in their own modules through ``retired_spec``; here: the retirement itself.
"""

from __future__ import annotations

import importlib

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs
from simgrip.envs import FRAGILE_ENV_IDS, RETIRED, retired_spec

#: each fragile task's newest registered version (the tactile scale, simgrip.envs.pick_fragile_v3; the pre-grasp, _v4;
#: no per-step touch pay, _v5; no drop penalty, _v6; the claws' approach term, pick_claw_v5; the place's pre-grasp,
#: pick_place_v4, no drop penalty, pick_place_v5, the grip's pay, pick_place_v6, and the set-down's, pick_place_v7;
#: every task's ramped palm and peak crush rule, pick_fragile_v7)
NEWEST = {"simgrip/PickFragile": "v7", "simgrip/PickMultiFragile": "v7", "simgrip/PlaceFragile": "v8",
          "simgrip/PickCradleFragile": "v6", "simgrip/PickSphereFragile": "v6"}
RETIRED_IDS = [f"{name}-v{k}" for name, newest in NEWEST.items() for k in range(int(newest[1:]))]


def _class(entry_point: str) -> type:
    module, name = entry_point.split(":")
    return getattr(importlib.import_module(module), name)


def test_the_retired_ids_are_exactly_the_older_versions_and_none_is_registered():
    assert sorted(RETIRED) == sorted(RETIRED_IDS)
    assert not [i for i in RETIRED if i in gym.registry]
    assert sorted(FRAGILE_ENV_IDS) == sorted(f"{name}-{v}" for name, v in NEWEST.items())
    assert all(i in gym.registry for i in FRAGILE_ENV_IDS)
    # the paper's grasps and the K-finger task stay registered
    assert all(i in gym.registry for i in ("simgrip/Pick-v1", "simgrip/PickCradle-v1", "simgrip/PickMulti-v0"))


@pytest.mark.parametrize("env_id", RETIRED_IDS)
def test_make_of_a_retired_id_is_deprecated_naming_the_newest_version(env_id):
    name = env_id.rsplit("-", 1)[0]
    newest = f"{name}-{NEWEST[name]}"
    # Gymnasium warns that the version is out of date, then raises DeprecatedEnv with the pointer
    with pytest.warns(DeprecationWarning, match="out of date"):
        with pytest.raises(gym.error.DeprecatedEnv, match=newest):
            gym.make(env_id)


@pytest.mark.parametrize("env_id", RETIRED_IDS)
def test_retired_spec_builds_it_as_registered_and_it_steps(env_id):
    entry, kwargs, steps = RETIRED[env_id]
    spec = retired_spec(env_id)
    assert (spec.id, spec.entry_point, spec.kwargs, spec.max_episode_steps) == (env_id, entry, kwargs, steps)
    spec.kwargs["bogus"] = 1  # a fresh copy: editing it leaves RETIRED as it was
    assert RETIRED[env_id][1] == kwargs and "bogus" not in retired_spec(env_id).kwargs
    env = gym.make(retired_spec(env_id))
    try:
        assert type(env.unwrapped) is _class(entry) and env.spec.max_episode_steps == steps
        assert isinstance(env, gym.wrappers.TimeLimit) and env._max_episode_steps == steps
        obs, info = env.reset(seed=0)
        assert env.observation_space.contains(obs) and "crush_limit" in info
        for _ in range(3):
            obs, r, term, trunc, info = env.step(env.action_space.sample())
            assert env.observation_space.contains(obs) and np.isfinite(r) and "is_success" in info
    finally:
        env.close()
    # the newest version of the task subclasses the retired class (what the RETIRED docs state)
    name = env_id.rsplit("-", 1)[0]
    newest = simgrip.envs._ENVS[f"{name}-{NEWEST[name]}"][0]
    assert issubclass(_class(newest), _class(entry))


def test_make_keyword_arguments_reach_the_retired_class():
    with pytest.raises(ValueError, match="crush_ratio_range"):
        gym.make(retired_spec("simgrip/PickFragile-v0"), crush_ratio_range=(0.5, 2.0))
    env = gym.make(retired_spec("simgrip/PickFragile-v1"), max_episode_steps=7)
    try:
        assert env._max_episode_steps == 7
    finally:
        env.close()


@pytest.mark.parametrize("bad, why", [("simgrip/PickFragile-v7", "registered"), ("simgrip/Pick-v0", "retired"),
                                      ("simgrip/NoSuch-v0", "retired"), (None, "retired")])
def test_retired_spec_of_anything_else_is_a_value_error_naming_it(bad, why):
    with pytest.raises(ValueError, match=f"env_id: {bad!r}.*{why}"):
        retired_spec(bad)
