"""The fragile tasks' v1 reward (issue 18): the same task as v0, a reward with a learning signal.

v1 must change the reward only: for the same seed and actions, v1 and v0 give bit-identical observations,
terminations and outcome keys (so v0's baselines hold for v1), and v1's reward is exactly the sum of its
documented terms.  Gymnasium's ``check_env`` and determinism over the v1 ids run in ``test_pick_fragile.py``
and ``test_env_determinism.py`` (over ``RETIRED``, which holds v0 and v1 now, built through ``retired_spec``:
``env_checks.make``); SB3's checker and pickling here.
"""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import simgrip.envs  # noqa: F401
from simgrip.envs.pick_fragile_v1 import FragilePickEnvV1, V1_REWARD_DEFAULTS, graded_crush
from env_checks import assert_sb3_check_env_clean, make

PAIRS = [("simgrip/PickFragile-v0", "simgrip/PickFragile-v1"),
         ("simgrip/PickMultiFragile-v0", "simgrip/PickMultiFragile-v1"),
         ("simgrip/PlaceFragile-v0", "simgrip/PlaceFragile-v1"),
         ("simgrip/PickCradleFragile-v0", "simgrip/PickCradleFragile-v1"),
         ("simgrip/PickSphereFragile-v0", "simgrip/PickSphereFragile-v1")]
OUTCOME = ("is_success", "workpiece_lift", "crushed", "dropped", "knocked_over", "crush_limit")
REWARD_KEYS = ("reward_lift", "reward_success", "reward_squeeze", "reward_drop", "reward_crush", "reward_touch",
               "reward_contact", "reward_place")


def _actions(space, n, seed):
    """A grasp-like sequence: the curvature command ramps from open to closed with noise, the palm rises."""
    rng = np.random.default_rng(seed)
    out = []
    for t in range(n):
        a = np.zeros(space.shape, dtype=np.float32)
        a[0] = np.clip(0.8 - 0.02 * t + 0.2 * rng.standard_normal(), -1, 1)
        a[-1] = np.clip(0.4 + 0.3 * rng.standard_normal(), -1, 1)
        out.append(a)
    return out


def _run(env_id, seed, actions):
    env = make(env_id).unwrapped
    obs, info = env.reset(seed=seed)
    rows = [(obs, None, False, info)]
    for a in actions:
        obs, r, term, _, info = env.step(a)
        rows.append((obs, r, term, info))
        if term:
            break
    env.close()
    return rows


@pytest.mark.parametrize("pair", PAIRS, ids=[p[1].split("/")[1] for p in PAIRS])
def test_v1_is_v0_with_another_reward(pair):
    """Same seed and actions: identical observations, terminations and outcomes; v1's reward is its terms' sum."""
    seen = set()
    for seed in (11, 12):
        contacts = 0
        actions = _actions(make(pair[1]).action_space, 90, seed)
        v0, v1 = _run(pair[0], seed, actions), _run(pair[1], seed, actions)
        assert len(v0) == len(v1) > 3
        for (o0, _, t0, i0), (o1, r1, t1, i1) in zip(v0, v1):
            assert np.array_equal(o0, o1) and t0 == t1
            assert all(i0.get(k) == i1.get(k) for k in OUTCOME if k in i0)
            if r1 is not None:
                assert r1 == pytest.approx(sum(i1.get(k, 0.0) for k in REWARD_KEYS), abs=1e-12)
                assert i1["reward_squeeze"] == 0.0
                touching = min(i1["normal_force"]) > 0.0
                seen.add(touching)
                lost = i1["crushed"] or i1["dropped"] or i1["knocked_over"]
                assert i1["reward_touch"] == (V1_REWARD_DEFAULTS["w_touch"] if touching and not lost else 0.0)
                contacts += i1["reward_contact"] > 0.0
                assert i1["reward_contact"] in (0.0, V1_REWARD_DEFAULTS["w_contact"])
        assert contacts <= 1  # paid once per episode
    assert True in seen  # the sequences do reach the workpiece with every finger


def test_graded_crush_closed_form():
    w = V1_REWARD_DEFAULTS["w_crush"]
    assert graded_crush(1.0, 1.0, w) == 0.0 and graded_crush(0.5, 1.0, w) == 0.0  # at (or below) the limit
    assert graded_crush(2.0, 1.0, w) == w / 2  # twice the limit: half
    assert graded_crush(4.0, 1.0, w) == pytest.approx(w * 0.75, rel=1e-15)  # x = 3
    values = [graded_crush(f, 0.2, w) for f in (0.2, 0.3, 1.0, 10.0, 1e6)]
    assert all(a < b for a, b in zip(values, values[1:])) and values[-1] < w


def test_crush_step_charges_the_graded_penalty_and_pickles():
    env = FragilePickEnvV1()
    env.reset(seed=1, options={"box_mass": 0.05, "friction": 1.0, "crush_limit": 0.05})
    for _ in range(3):  # fingers open, palm still: nothing touched, nothing paid
        _, r, term, _, info = env.step(np.array([1.0, 0.0], dtype=np.float32))
        assert not term and info["reward_touch"] == info["reward_contact"] == 0.0 and abs(r) < 1e-6
    twin = pickle.loads(pickle.dumps(env))
    results = []
    for e in (env, twin):
        rewards = []
        for _ in range(100):
            phi = e._phi
            obs, r, term, _, info = e.step(np.array([-1.0, 0.0], dtype=np.float32))
            rewards.append(r)
            if term:
                break
        assert info["crushed"] and term and not info["is_success"]
        # the graded penalty and the lift progress taken back (this step's, after its reward_lift was paid)
        expected = -graded_crush(max(info["normal_force"]), 0.05, e.w_crush) - e.w_lift * phi - info["reward_lift"]
        assert info["reward_crush"] == pytest.approx(expected, abs=1e-12)
        assert -e.w_crush - e.w_lift < info["reward_crush"] <= 0.0
        results.append((obs, rewards))
    assert np.array_equal(results[0][0], results[1][0]) and results[0][1] == results[1][1]


def test_check_env_of_stable_baselines3_on_v1():
    assert_sb3_check_env_clean(("simgrip/PickFragile-v1", "simgrip/PlaceFragile-v1"))


def test_v1_arguments_checked():
    with pytest.raises(ValueError, match="w_touch"):
        FragilePickEnvV1(w_touch=float("nan"))
    with pytest.raises(ValueError, match="w_contact"):
        FragilePickEnvV1(w_contact="a")
    with pytest.raises(ValueError, match="w_crush"):
        FragilePickEnvV1(w_crush=-1.0)
