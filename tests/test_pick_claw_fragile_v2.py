"""The claw tasks v2 (``PickCradleFragile-v2``, ``PickSphereFragile-v2``): v1 with the palm started at a height
drawn from a 16 cm (cradle) or 12 cm (sphere) range, so that a fixed descent misses the grasp height, and the
cradle's box at most 6.5 cm wide (issue 18).

Gymnasium's ``check_env``, the info keys and determinism run for these ids in ``tests/test_pick_fragile.py`` and
``tests/test_env_determinism.py`` (``RETIRED`` holds them, v1 and v2 retired: built through ``retired_spec``,
``env_checks.make``); here: v2 is v1 but for the draw, the
documented start heights, SB3's checker, pickling mid-episode, headless rendering, and the gap between the
observation-only controller and the tuned open-loop schedule on seeds 7600-7611 (cradle) and 7620-7631
(sphere), which no other test uses (the ranges and the open-loop member were chosen on seeds 5000-5049; the
reported baselines use 6000-6049 and 6100-6149).  Bounds from the binomial spread of n = 12 episodes
(``scipy.stats.binom``):

* observation-only controller: at least 8 of 12 (a controller at the issue's 0.8 scores <= 7 with P = 0.073; at
  the tuning seeds' 0.84-0.92, P <= 0.033).
* the open-loop member tuned on seeds 5000-5049 (``docs/baselines/*-v2-openloop-tune.json``): at most 5 of 12.  A
  schedule at the issue's 20 % (the cradle's member on seeds 5000-5049) reaches 6 with P = 0.019 (the
  sphere's, 10 %, with P = 0.0005); one that solves the task (0.8) stays <= 5 with P = 0.0039.  It cannot
  tell 20 % from 40 % (that is what the 50-seed JSONs are for); it catches a v2 whose start height no longer
  matters.
"""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import simgrip.envs  # noqa: F401
from simgrip.envs.baselines import _claw_openloop, evaluate, run_policy
from simgrip.envs.pick_cradle_fragile_v2 import CRADLE_V2_PALM_START, CRADLE_V2_WIDTH, FragileCradleEnvV2
from simgrip.envs.pick_sphere_fragile_v2 import SPHERE_V2_PALM_START, FragileSphereEnvV2
from env_checks import assert_headless_frame, assert_sb3_check_env_clean, make

IDS = ("simgrip/PickCradleFragile-v2", "simgrip/PickSphereFragile-v2")
#: v1 with v2's draw where it differs (the cradle's box width), the start height set per episode below
V1 = {"simgrip/PickCradleFragile-v2": ("simgrip/PickCradleFragile-v1", {"box_width_range": CRADLE_V2_WIDTH}),
      "simgrip/PickSphereFragile-v2": ("simgrip/PickSphereFragile-v1", {})}
GAP_SEEDS = {"simgrip/PickCradleFragile-v2": list(range(7600, 7612)),
             "simgrip/PickSphereFragile-v2": list(range(7620, 7632))}
#: the open-loop member (kappa, ramp steps, palm, descent shift) best on seeds 5000-5049 (ties: the grid's first)
TUNED = {"simgrip/PickCradleFragile-v2": (0.5, 50, 1.0, -5), "simgrip/PickSphereFragile-v2": (0.4, 1, 1.0, -10)}


def _claw_actions(n):
    return [np.array([0.68 - 0.01 * t, -1.0 if t < 15 else 0.3], dtype=np.float32) for t in range(n)]


@pytest.mark.parametrize("env_id", IDS)
def test_v2_is_v1_but_for_the_draw(env_id):
    """Started at the same palm height (``options``), with the same width range, v2 and v1 give the same episode
    bit for bit (the reward, the observation and the physics are v1's)."""
    out = []
    for eid, kwargs in ((env_id, {}), V1[env_id]):
        env = make(eid, **kwargs).unwrapped
        obs, info = env.reset(seed=4, options={"palm_height": 0.12})
        rows = [obs, info["crush_limit"]]
        for a in _claw_actions(30):
            obs, r, term, trunc, info = env.step(a)
            rows.append((obs, r, term, info["is_success"], info["crushed"], info["workpiece_lift"]))
            if term:
                break
        env.close()
        out.append(rows)
    assert len(out[0]) == len(out[1]) > 10
    for x, y in zip(out[0], out[1]):
        assert all(np.array_equal(a, b) for a, b in zip(np.atleast_1d(x) if not isinstance(x, tuple) else x,
                                                        np.atleast_1d(y) if not isinstance(y, tuple) else y))


@pytest.mark.parametrize("env_id, start", [(IDS[0], CRADLE_V2_PALM_START), (IDS[1], SPHERE_V2_PALM_START)])
def test_palm_start_drawn_over_the_documented_range(env_id, start):
    env = make(env_id).unwrapped
    z = []
    for seed in range(20):
        obs, _ = env.reset(seed=seed)
        z.append(float(obs[env.obs_slices["palm_height"]][0]) * env.length)  # observed, in finger lengths
    env.close()
    # the palm settles on its target within the reset (a spring-driven mocap: sub-mm); 20 uniform draws span
    # more than half the range with P = 1 - 20 (1/2)^19 - ... > 0.9999
    assert start[0] - 1e-3 <= min(z) and max(z) <= start[1] + 1e-3
    assert max(z) - min(z) > 0.5 * (start[1] - start[0])


def test_palm_range_and_start_checked():
    with pytest.raises(ValueError, match="palm_start"):
        FragileCradleEnvV2(palm_start=(0.13, 0.35))
    with pytest.raises(ValueError, match="palm_start"):
        FragileSphereEnvV2(palm_start=(0.2, 0.1))


def test_check_env_of_stable_baselines3_on_v2():
    assert_sb3_check_env_clean(IDS)


@pytest.mark.parametrize("env_id", IDS)
def test_pickle_mid_episode_continues_exactly(env_id):
    env = make(env_id).unwrapped
    env.reset(seed=11, options={"crush_limit": 100.0})  # no crush: the episode runs on
    for a in _claw_actions(20):
        env.step(a)
    twin = pickle.loads(pickle.dumps(env))
    for _ in range(10):
        a = np.array([0.4, 0.2], dtype=np.float32)
        o1, r1, *_ = env.step(a)
        o2, r2, *_ = twin.step(a)
        assert np.array_equal(o1, o2) and r1 == r2
    assert twin.crush_limit == env.crush_limit and twin.palm_start == env.palm_start


@pytest.mark.parametrize("env_id", IDS)
def test_headless_render(env_id, render_backend):
    assert_headless_frame(env_id)


@pytest.mark.parametrize("env_id", IDS)
def test_observation_only_beats_the_tuned_open_loop_schedule(env_id):
    seeds = GAP_SEEDS[env_id]
    obs_only = evaluate(env_id, "observation", seeds)
    assert obs_only["outcomes"].get("success", 0) >= 8, obs_only
    env = make(env_id)
    try:
        counts = run_policy(env, _claw_openloop(*TUNED[env_id][:3], shift=TUNED[env_id][3]), seeds)
    finally:
        env.close()
    assert counts["success"] <= 5, counts
