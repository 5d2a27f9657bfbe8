"""The valve-commanded curvature (simgrip.envs.valve) and the valve versions of the fragile tasks
(simgrip.envs.pick_fragile_v2).

Determinism, reset/step API and the info keys of the registered ids are covered with every fragile id in
``test_env_determinism.py`` and ``test_pick_fragile.py`` (``FRAGILE_ENV_IDS`` holds them); here: the valve's
integration rule against its definition, that it is the earlier version's env driven through the same
command, argument checks, and SB3's checker.
"""

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401
from simgrip.envs.pick_fragile_v1 import FragilePickEnvV1
from simgrip.envs.pick_fragile_v2 import V2_CRUSH_RATIO, V2_MASS, FragilePickEnvV2
from simgrip.envs.valve import KAPPA_RATE, absolute_to_valve
from env_checks import assert_sb3_check_env_clean

VALVE_IDS = ("simgrip/PickFragile-v7", "simgrip/PickMultiFragile-v7", "simgrip/PlaceFragile-v8",
             "simgrip/PickCradleFragile-v6", "simgrip/PickSphereFragile-v6")


@pytest.mark.parametrize("env_id", VALVE_IDS)
def test_the_command_is_the_clipped_running_sum_of_the_rates(env_id):
    env = gym.make(env_id)
    u = env.unwrapped
    obs, _ = env.reset(seed=3)
    n = env.action_space.shape[0]
    rates = np.random.default_rng(0).uniform(-1.5, 1.5, 40)  # past +-1: clipped to +-1 like any action
    rates[10:25] = -1.0  # drive the command through its lower end...
    rates[25:30] = 0.0   # ...and hold it
    c = float(obs[u.obs_slices["kappa_command"]][0])
    for r in rates.astype(np.float32).tolist():  # the rate as the env receives it (float32)
        c = min(max(c + KAPPA_RATE * min(max(r, -1.0), 1.0), -1.0), 1.0)
        obs, _, terminated, truncated, _ = env.step(np.r_[r, np.zeros(n - 1)].astype(np.float32))
        assert u.valve_command == pytest.approx(c, abs=1e-12)
        assert obs[u.obs_slices["kappa_command"]][0] == pytest.approx(c, abs=1e-6)  # float32 observation
        if terminated or truncated:
            break
    env.close()


def test_a_valve_env_is_its_v1_env_driven_by_the_command_the_valve_reaches():
    """The same seed and the command sequence the valve reaches give v1 (absolute command) the same episode:
    the valve changes what the action means, nothing else (the draw set equal)."""
    v2, v1 = FragilePickEnvV2(), FragilePickEnvV1(crush_ratio_range=V2_CRUSH_RATIO, box_mass_range=V2_MASS)
    o2, i2 = v2.reset(seed=11)
    o1, i1 = v1.reset(seed=11)
    assert i1["crush_limit"] == i2["crush_limit"] and np.array_equal(o1, o2)
    rng = np.random.default_rng(1)
    for t in range(60):
        a = rng.uniform(-1, 1, 2).astype(np.float32)
        a[0] = -0.6 if t < 40 else 0.0
        o2, r2, te2, tr2, f2 = v2.step(a)
        o1, r1, te1, tr1, f1 = v1.step(np.array([v2.valve_command, a[1]]))
        assert np.array_equal(o1, o2) and r1 == r2 and te1 == te2
        if te1:
            break


def test_absolute_to_valve_reaches_a_target_at_the_valve_rate():
    assert absolute_to_valve(0.5, 1.0, 0.02) == -1.0  # far: full rate
    assert absolute_to_valve(0.99, 1.0, 0.02) == pytest.approx(-0.5)  # near: the step that lands on it
    assert absolute_to_valve(1.0, 1.0, 0.02) == 0.0


@pytest.mark.parametrize("bad", [0.0, -0.01, float("nan"), float("inf"), 2.5, "fast", None, True, np.True_])
def test_bad_kappa_rate_is_refused_by_name(bad):  # True ran as a rate of 1.0, 50 times the default
    with pytest.raises(ValueError, match="kappa_rate"):
        gym.make("simgrip/PickFragile-v7", kappa_rate=bad)


def test_a_nan_rate_is_refused_like_any_action():
    env = gym.make("simgrip/PickFragile-v7")
    env.reset(seed=0)
    with pytest.raises(ValueError, match="finite"):
        env.step(np.array([np.nan, 0.0], dtype=np.float32))


def test_sb3_check_env_is_clean_on_the_valve_ids():
    assert_sb3_check_env_clean(VALVE_IDS)
