"""The fragile cradle (``PickCradleFragile-v0``) and sphere (``PickSphereFragile-v0``) tasks (issue 18).

Both ids are retired (``simgrip.envs.RETIRED``): built here through ``retired_spec`` (``env_checks.make``).
check_env, the info keys and determinism run for these ids in ``tests/test_pick_fragile.py`` (parametrised over
``FRAGILE_ENV_IDS`` and ``RETIRED``); here: the crush windows' physical definitions, argument checks, the
documented info keys, pickling mid-episode, headless rendering and the observation-only controller's success on
held-out seeds.

The controller tests run on seeds 7400-7411 (cradle) and 7420-7431 (sphere), which no other test uses (the
ranges were chosen on seeds 5000-5049, the reported baselines use 6000-6049).  Bounds from the binomial spread of n = 12
episodes (``scipy.stats.binom``):

* observation-only controller: at least 8 of 12.  A controller whose true rate is 0.8 (the issue's target)
  scores <= 7 with P = 0.073; one at 0.9 with P = 0.0043 (measured on seeds 6000-6049: sphere 49/50, cradle
  40/50).
* fixed schedules (sphere only: the claw open-loop family at its best curvatures, actions 0.3-0.6, and the coarse
  constant grid): each at most 6 of 12.  This catches a fixed schedule that solves the task (a member at 0.8
  stays <= 6 with P = 0.019) but not one at the issue's 20 % target: on seeds 6000-6049 the best open-loop
  schedule holds 30 % of the spheres (``docs/baselines/PickSphereFragile-v0-openloop.json``), above the target,
  and a member at 0.3 reaches 7 of 12 with P = 0.039.  The cradle's best open-loop schedule holds 42 % (seeds
  6000-6049), so its fixed schedules are not tested; neither task meets the target.
"""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest

import simgrip.envs  # noqa: F401
from simgrip.envs.baselines import evaluate
from simgrip.envs.pick_cradle_fragile import FragileCradleEnv
from simgrip.envs.pick_sphere_fragile import FragileSphereEnv
from env_checks import assert_headless_frame, make

IDS = ("simgrip/PickCradleFragile-v0", "simgrip/PickSphereFragile-v0")
GAP_SEEDS = {"simgrip/PickCradleFragile-v0": list(range(7400, 7412)),
             "simgrip/PickSphereFragile-v0": list(range(7420, 7432))}


def test_crush_windows_are_the_documented_physical_bounds():
    cradle = FragileCradleEnv()
    sphere = FragileSphereEnv()
    for seed in range(4):
        _, info = cradle.reset(seed=seed)
        # the cradle: each finger bears its share of the weight on a support
        assert info["hold_force"] == pytest.approx(0.5 * info["box_mass"] * cradle.g, rel=1e-12)
        assert 1.5 <= info["crush_limit"] / info["hold_force"] <= 2.5
        assert 0.04 <= info["box_width"] <= 0.075 and cradle.grip == "III"
        _, info = sphere.reset(seed=seed)
        # the sphere: the least normal force of a contact force m g / K pointing up, on the friction cone's edge
        mu = info["friction"]
        assert info["hold_force"] == pytest.approx(info["mass"] * sphere.g / (3 * math.sqrt(1 + mu * mu)), rel=1e-12)
        assert 1.5 <= info["crush_limit"] / info["hold_force"] <= 2.5
        assert info["shape"] == "sphere" and 0.04 <= info["width"] <= 0.09
    with pytest.raises(ValueError, match="grip"):
        FragileCradleEnv(grip="I")
    with pytest.raises(ValueError, match="shapes"):
        FragileSphereEnv(shapes=("box",))
    with pytest.raises(ValueError, match="crush_ratio_range"):
        FragileSphereEnv(crush_ratio_range=(0.9, 2.0))


@pytest.mark.parametrize("env_id", IDS)
def test_every_info_key_is_documented(env_id):
    env = make(env_id)
    env.reset(seed=0)
    _, _, _, _, info = env.step(env.action_space.sample())
    u = env.unwrapped
    doc = (type(u).__doc__ or "") + (__import__(type(u).__module__, fromlist=["_"]).__doc__ or "")
    missing = [k for k in info if f"``{k}``" not in doc]
    assert not missing and "``is_success``" in doc, missing
    env.close()


@pytest.mark.parametrize("env_id", IDS)
def test_pickle_mid_episode_continues_exactly(env_id):
    env = make(env_id).unwrapped
    env.reset(seed=11, options={"crush_limit": 100.0})  # no crush: the episode runs on
    for t in range(20):
        env.step(np.array([0.68 - 0.01 * t, -0.5 if t < 10 else 0.0], dtype=np.float32))
    twin = pickle.loads(pickle.dumps(env))
    for t in range(10):
        a = np.array([0.4, 0.2], dtype=np.float32)
        o1, r1, *_ = env.step(a)
        o2, r2, *_ = twin.step(a)
        assert np.array_equal(o1, o2) and r1 == r2
    assert twin.crush_limit == env.crush_limit


@pytest.mark.parametrize("env_id", IDS)
def test_headless_render(env_id, render_backend):
    assert_headless_frame(env_id)


def test_cradle_crush_terminates_as_failure():
    env = FragileCradleEnv()
    obs, info = env.reset(seed=2, options={"box_mass": 0.02, "crush_limit": 0.02})
    for t in range(150):  # lower the open claw around the box, then curl hard
        a = np.array([0.68 if t < 20 else -1.0, -1.0 if t < 20 else 0.0], dtype=np.float32)
        obs, r, term, trunc, info = env.step(a)
        if term:
            break
    assert term and info["crushed"] and not info["is_success"] and max(info["normal_force"]) > 0.02


@pytest.mark.parametrize("env_id", IDS)
def test_observation_only_controller_on_held_out_seeds(env_id):
    """The observation-only claw controller holds at least 8 of 12 held-out episodes (the fixed schedules: the
    sphere's test below; see the module docstring)."""
    obs_only = evaluate(env_id, "observation", GAP_SEEDS[env_id])
    assert obs_only["outcomes"].get("success", 0) >= 8, obs_only


def test_sphere_fixed_schedules_stay_below_the_target_on_held_out_seeds():
    """The claw open-loop family around its best curvatures on seeds 6000-6049 (actions 0.3-0.6, the grid's
    0.1 steps; a fast and a slow ramp), and every constant curvature with the palm going up (coarse grid):
    each at most 6 of 12 (see the module docstring for the bound)."""
    from simgrip.envs.baselines import _claw_openloop, run_policy

    env_id = "simgrip/PickSphereFragile-v0"
    seeds = GAP_SEEDS[env_id]
    env = make(env_id)
    try:
        for a_k in (0.3, 0.4, 0.5, 0.6):
            for ramp, palm in ((1, 0.5), (50, 1.0)):
                counts = run_policy(env, _claw_openloop(a_k, ramp, palm), seeds)
                assert counts["success"] <= 6, (a_k, ramp, palm, dict(counts))
    finally:
        env.close()
    rec = evaluate(env_id, "constant", seeds, grid="coarse")
    assert max(m["outcomes"].get("success", 0) for m in rec["members"]) <= 6, rec["best"]

