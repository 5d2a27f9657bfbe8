"""The pinch's and the K fingers' v4 (simgrip.envs.pick_fragile_v4): v3 started from a pre-grasp, masses to 0.25 kg.

Checked against independent computations: the start shape's clearance is measured afresh with MuJoCo's
distance query on the rest shape of the returned command (the bisection's bracket brackets the drawn gap), no
finger touches the workpiece after the reset's settle, and the per-seed draw (width, friction, palm height,
crush ratio) is the retired v3's exactly.
"""

from __future__ import annotations

import math

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  registers the environments
from simgrip.envs import FRAGILE_ENV_IDS, RETIRED, retired_spec
from simgrip.envs.pick_fragile_v4 import (_BISECTIONS, _SCAN, GAP_RANGE, V4_MASS, FragilePickEnvV4,
                                          FragilePickMultiEnvV4, pre_grasp_curvature)
from simgrip.envs.pick_place_v4 import FragilePlaceEnvV4

V4_IDS = ("simgrip/PickFragile-v4", "simgrip/PickMultiFragile-v4")
V3 = {"simgrip/PickFragile-v4": "simgrip/PickFragile-v3", "simgrip/PickMultiFragile-v4": "simgrip/PickMultiFragile-v3"}
#: every id started from the pre-grasp (PlaceFragile-v4: simgrip.envs.pick_place_v4, the same start)
PRE_GRASP_IDS = V4_IDS + ("simgrip/PlaceFragile-v4",)


def _clearance(model, data, pairs, hinges, unit, k):
    """Least finger-workpiece distance [m] of the rest shape at ``k``, on a copy of the data (independent of
    the module's helper: one mj_forward, then every pair's distance)."""
    d = mujoco.MjData(model)
    d.qpos[:] = data.qpos
    d.qpos[hinges] = unit * k
    mujoco.mj_forward(model, d)
    return min(mujoco.mj_geomDistance(model, d, int(model.pair_geom1[p]), int(model.pair_geom2[p]), 1.0, None)
               for p in pairs)


def _make(env_id, **kwargs):
    """v4 was retired by v5 (simgrip.envs.pick_fragile_v5: only the reward changed): made as it was registered."""
    return gym.make(retired_spec(env_id) if env_id in RETIRED else env_id, **kwargs)


def test_both_are_retired_by_v5():
    assert set(V4_IDS) <= set(RETIRED)
    for old in (*V3.values(), *V4_IDS):
        assert old not in FRAGILE_ENV_IDS


@pytest.mark.parametrize("cls", [FragilePickEnvV4, FragilePickMultiEnvV4, FragilePlaceEnvV4])
def test_the_start_shape_clears_the_workpiece_by_the_drawn_gap(cls):
    env = cls()
    try:
        for seed in range(6):
            env.reset(seed=seed)
            gap = env.start_gap
            assert GAP_RANGE[0] <= gap <= GAP_RANGE[1]
            pairs, hinges, unit = env._pre_grasp_handles()
            m, d = env.model, env.data
            k = pre_grasp_curvature(m, d, pairs, hinges, unit, gap, float(env.kappa_range[0]))
            assert env.kappa_range[0] < k < 0.0
            # the returned command clears it by more than the gap; the bracket's other end (one bisection
            # interval, _SCAN / 2**_BISECTIONS, more curled) by no more: the gap is crossed in between
            step = _SCAN / 2 ** _BISECTIONS
            assert _clearance(m, d, pairs, hinges, unit, k) > gap
            assert _clearance(m, d, pairs, hinges, unit, k - step) <= gap
            # and every less curled shape of the scan clears it by more (the first crossing, not a later one)
            for kk in np.arange(0.0, k, -_SCAN):
                assert _clearance(m, d, pairs, hinges, unit, kk) > gap
    finally:
        env.close()


@pytest.mark.parametrize("env_id", PRE_GRASP_IDS)
def test_an_episode_starts_near_the_workpiece_and_not_touching_it(env_id):
    env = _make(env_id)
    u = env.unwrapped
    sl = u.obs_slices
    try:
        for seed in range(20):
            obs, info = env.reset(seed=seed)
            assert info["start_gap"] == u.start_gap
            # the valve starts at the pre-grasp command, partly curled; no finger touches
            assert obs[sl["kappa_command"]][0] == pytest.approx(u.valve_command, abs=1e-6)
            assert 0.0 < u.valve_command < 0.9
            assert np.all(obs[sl["contact_force"]] == 0.0)
            # closing a little at the valve's full rate touches within a few steps (the start is near)
            a = np.zeros(env.action_space.shape, np.float32)
            a[0] = -1.0
            for t in range(40):
                _, _, term, trunc, i = env.step(a)
                if max(i["normal_force"]) > 0.0 or term:
                    break
            assert max(i["normal_force"]) > 0.0, seed
    finally:
        env.close()


@pytest.mark.parametrize("env_id", V4_IDS)
def test_the_draw_is_v3s_but_for_the_mass(env_id):
    new, old = _make(env_id), gym.make(retired_spec(V3[env_id]))
    try:
        masses = []
        for seed in range(30):
            _, fn = new.reset(seed=seed)
            _, fo = old.reset(seed=seed)
            for key in fn:
                if key in ("box_mass", "mass", "hold_force", "crush_limit", "dimensionless", "start_gap"):
                    continue
                assert fn[key] == fo[key], key
            masses.append(fn.get("box_mass", fn.get("mass")))
            un, uo = new.unwrapped, old.unwrapped
            # the crush ratio: the same draw over the new holding force
            assert un.crush_limit / un.hold_force == pytest.approx(uo.crush_limit / uo.hold_force, rel=1e-12)
        assert V4_MASS[0] <= min(masses) and max(masses) <= V4_MASS[1]
        # log-uniform over a 50x range: 30 draws spread over most of it
        assert math.log(max(masses) / min(masses)) > 0.5 * math.log(V4_MASS[1] / V4_MASS[0])
    finally:
        new.close()
        old.close()


@pytest.mark.parametrize("env_id", V4_IDS)
def test_same_seed_same_episode(env_id):
    a, b = _make(env_id), _make(env_id)
    try:
        oa, ia = a.reset(seed=7)
        ob, ib = b.reset(seed=7)
        assert np.array_equal(oa, ob) and ia["start_gap"] == ib["start_gap"]
        rng = np.random.default_rng(0)
        for _ in range(30):
            act = rng.uniform(-1, 1, a.action_space.shape).astype(np.float32)
            ra, rb = a.step(act), b.step(act)
            assert np.array_equal(ra[0], rb[0]) and ra[1] == rb[1]
    finally:
        a.close()
        b.close()


@pytest.mark.parametrize("bad", [(0.0, 0.01), (-0.01, 0.01), (0.01, 0.003), (0.003, float("inf")), "near", None])
def test_bad_gap_range_names_it(bad):
    with pytest.raises(ValueError, match="gap_range"):
        _make("simgrip/PickFragile-v4", gap_range=bad)


def _observation_only(env, seeds) -> str:
    """One letter per seed: S success, C crushed, D dropped, o otherwise (the observation-only controller
    driven through the valve as ``simgrip.envs.baselines`` drives it)."""
    from simgrip.envs.scripted_fragile import ObservationFragilePolicy
    from simgrip.envs.valve import absolute_to_valve

    u, out = env.unwrapped, []
    for seed in seeds:
        obs, info = env.reset(seed=seed)
        pol = ObservationFragilePolicy()
        pol.reset(env, info)
        while True:
            a = np.array(pol(obs), dtype=np.float32)
            a[0] = absolute_to_valve(a[0], u.valve_command, u.kappa_rate)
            obs, _, term, trunc, i = env.step(a)
            if term or trunc:
                break
        out.append("S" if i["is_success"] else "C" if i["crushed"] else "D" if i["dropped"] else "o")
    return "".join(out)


def test_the_first_touch_no_longer_crushes():
    """The failure v4 removes, on the first 12 of PPO's held-out seeds (8000-8011; 5 of their workpieces weigh
    5-10 g): v3's observation-only controller, closing from straight, crushed light pieces at the first touch
    (the lag's backlog); from the pre-grasp the same controller holds at least 10 of 12 (the issue's 80 %)
    and crushes fewer."""
    old, new = gym.make(retired_spec("simgrip/PickFragile-v3")), _make("simgrip/PickFragile-v4")
    try:
        was, now = _observation_only(old, range(8000, 8012)), _observation_only(new, range(8000, 8012))
    finally:
        old.close()
        new.close()
    assert was.count("C") >= 2, was
    assert now.count("S") >= 10 and now.count("C") < was.count("C"), (was, now)
