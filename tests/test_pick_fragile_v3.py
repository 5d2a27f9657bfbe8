"""The fragile tasks' v3 (cradle, sphere v4): v2's task with the tactile forces on the sensor's scale
(simgrip.envs.pick_fragile_v3).

Checked against the retired v2 built exactly as it was registered: the same seed and actions give the same
physics, rewards and infos bit for bit, and the same observation but for the contact-force entries, which are
v2's forces re-expressed on the new scale (``log(1 + F / 0.01 N)`` where v2 observed ``log(1 + F / W2)``).
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  registers the environments
from simgrip.envs import FRAGILE_ENV_IDS, RETIRED, retired_spec
from simgrip.envs.pick_fragile_v3 import TACTILE_RESOLUTION, FragilePickEnvV3

#: each v3 id and the retired version it changes
PREVIOUS = {"simgrip/PickFragile-v3": "simgrip/PickFragile-v2",
            "simgrip/PickMultiFragile-v3": "simgrip/PickMultiFragile-v2",
            "simgrip/PlaceFragile-v3": "simgrip/PlaceFragile-v2",
            "simgrip/PickCradleFragile-v4": "simgrip/PickCradleFragile-v3",
            "simgrip/PickSphereFragile-v4": "simgrip/PickSphereFragile-v3"}


#: the v3 pinch and K fingers, retired by v4 (simgrip.envs.pick_fragile_v4, which keeps v3's tactile scale) and v4 by
#: v5 and v6 (simgrip.envs.pick_fragile_v5, _v6: the same but for the reward); the claws' v4 retired by v5
#: (pick_claw_v5: the reward);
#: PlaceFragile-v3 by v4 (simgrip.envs.pick_place_v4: the pre-grasp and no touch pay), v4 by v5, v5 by v6 and v6
#: by v7 (pick_place_v5, _v6, _v7: the reward)
V4 = {"simgrip/PickFragile-v7": "simgrip/PickFragile-v3", "simgrip/PickMultiFragile-v7": "simgrip/PickMultiFragile-v3",
      "simgrip/PickCradleFragile-v6": "simgrip/PickCradleFragile-v4",
      "simgrip/PickSphereFragile-v6": "simgrip/PickSphereFragile-v4",
      "simgrip/PlaceFragile-v8": "simgrip/PlaceFragile-v3"}


def _make(env_id, **kwargs):
    return gym.make(retired_spec(env_id) if env_id in RETIRED else env_id, **kwargs)


def test_every_registered_fragile_id_is_a_tactile_version():
    registered = {V4.get(k, k) for k in FRAGILE_ENV_IDS}
    assert sorted(PREVIOUS) == sorted(registered)


@pytest.mark.parametrize("env_id", sorted(PREVIOUS))
def test_same_physics_and_infos_as_the_previous_version_forces_rescaled(env_id):
    new, old = _make(env_id), gym.make(retired_spec(PREVIOUS[env_id]))
    try:
        un, uo = new.unwrapped, old.unwrapped
        assert un._force_unit == TACTILE_RESOLUTION and uo._force_unit > 10 * TACTILE_RESOLUTION
        cf = un.obs_slices["contact_force"]
        assert cf == uo.obs_slices["contact_force"]
        rest = np.ones(un.observation_space.shape[0], bool)
        rest[cf] = False
        on, _ = new.reset(seed=21)
        oo, _ = old.reset(seed=21)
        rng = np.random.default_rng(5)
        touched = 0
        # closing on average (the valve's -1 curls); the claws' hands, started above the workpiece, descending
        mean = np.zeros(new.action_space.shape)
        mean[0], mean[1] = -0.4, (-0.5 if "Cradle" in env_id or "Sphere" in env_id else 0.0)
        for _ in range(300):  # (contact after 20-190 steps, a crush a few steps later)
            a = np.clip(rng.normal(mean, 0.5), -1, 1).astype(np.float32)
            on, rn, tn, trn, fn = new.step(a)
            oo, ro, to, tro, fo = old.step(a)
            assert (rn, tn, trn) == (ro, to, tro)
            assert np.array_equal(on[rest], oo[rest])
            assert fn.keys() == fo.keys()
            for k in fn:
                assert np.array_equal(np.asarray(fn[k]), np.asarray(fo[k])), k
            force = np.expm1(oo[cf]) * uo._force_unit  # the forces v2 observed [N]
            np.testing.assert_allclose(on[cf], np.log1p(force / TACTILE_RESOLUTION), rtol=1e-12, atol=1e-12)
            touched += bool(np.max(force) > 0.0)
            if tn or trn:
                break
        assert touched  # the comparison covered contact, not only zeros
    finally:
        new.close()
        old.close()


def test_a_light_workpieces_window_is_resolved():
    """What the scale buys: the crush window of the lightest workpiece, ``N_hold``..``r N_hold`` with ``N_hold``
    ~0.02 N, spans ``log r`` (> 0.4) of the observation instead of < 0.02 under v2's mean-weight scale."""
    env = FragilePickEnvV3()
    _, info = env.reset(seed=0, options={"box_mass": 0.005, "friction": 1.2})
    hold, crush = info["hold_force"], info["crush_limit"]
    assert hold < 0.03
    w2 = env.g * float(np.mean(env.box_mass_range))  # v2's scale: the mean weight
    assert math.log1p(crush / w2) - math.log1p(hold / w2) < 0.02
    span = math.log1p(crush / env.tactile_resolution) - math.log1p(hold / env.tactile_resolution)
    assert span > 0.4
    env.close()


@pytest.mark.parametrize("env_id", ["simgrip/PickFragile-v3", "simgrip/PickFragile-v4"])
def test_tactile_resolution_argument(env_id):
    env = _make(env_id, tactile_resolution=0.5)
    assert env.unwrapped.tactile_resolution == 0.5 and env.unwrapped._force_unit == 0.5
    env.close()
    for bad in (0, -0.01, float("nan"), float("inf"), "soft", None, True):  # True ran as 1 N
        with pytest.raises(ValueError, match="tactile_resolution"):
            _make(env_id.replace("Pick", "PickMulti"), tactile_resolution=bad)
