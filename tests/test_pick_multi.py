"""simgrip/PickMulti-v0: API conformance, determinism, rendering, argument checks, scripted vs random baselines."""

import copy
import json
import math
import os
import pickle
import subprocess
import sys
import textwrap
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import simgrip
import simgrip.envs  # noqa: F401  (registers the ids)
from simgrip.envs import ENV_IDS, MULTI_ENV_IDS
from simgrip.envs.pick_multi import PickMultiEnv
from simgrip.envs.pick_multi_observation import multi_obs_layout
from simgrip.envs.scripted_multi import ObservationMultiPolicy, ScriptedMultiPolicy

ENV_ID = "simgrip/PickMulti-v0"
#: Few links keep the episodes cheap; the grips are the same problem at any n.
FAST = dict(n_links=6)


def _rollout(env, seed, steps=40, action_seed=0):
    obs, info = env.reset(seed=seed)
    rng = np.random.default_rng(action_seed)
    out = [obs]
    for _ in range(steps):
        obs, r, term, trunc, _ = env.step(rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
        out.append(np.append(obs, r))
        if term or trunc:
            break
    return info, out


def _success_rate(make_policy, fingers, episodes, seed0):
    env = gym.make(ENV_ID, fingers=fingers, **FAST)
    wins = 0
    try:
        for ep in range(episodes):
            obs, info = env.reset(seed=seed0 + ep)
            act = make_policy(env, info, seed0 + ep)
            while True:
                obs, _, term, trunc, info = env.step(act(obs))
                if term or trunc:
                    break
            wins += bool(info["is_success"])
    finally:
        env.close()
    return wins / episodes


def test_registered_with_a_time_limit_and_apart_from_the_two_finger_ids():
    assert ENV_ID in MULTI_ENV_IDS and ENV_ID not in ENV_IDS
    spec = gym.spec(ENV_ID)
    assert spec.entry_point == "simgrip.envs.pick_multi:PickMultiEnv" and spec.max_episode_steps == 200


@pytest.mark.parametrize("kwargs", [dict(fingers=3), dict(fingers=4, shared_curvature=False)])
def test_check_env_passes_without_warnings(kwargs):
    env = gym.make(ENV_ID, **FAST, **kwargs)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            check_env(env.unwrapped, skip_render_check=True)  # rendering: test_headless_render_*
    finally:
        env.close()
    assert not [str(w.message) for w in caught]


@pytest.mark.parametrize("fingers,shared", [(3, True), (4, False), (2, True)])
def test_spaces_follow_the_documented_layout(fingers, shared):
    env = PickMultiEnv(fingers=fingers, shared_curvature=shared, shape_points=5, **FAST)
    nk = 1 if shared else fingers
    assert env.action_space.shape == (nk + 1,)
    size = (16 + 9 * fingers) if shared else (14 + 11 * fingers)  # 16 + (P + 4) K, 14 + (P + 6) K with P = 5
    assert env.observation_space.shape == (size,)
    assert env.obs_layout == multi_obs_layout(fingers, 5, shared)
    assert sum(n for _, n in env.obs_layout) == size
    shapes = set()
    for seed in range(12):
        obs, info = env.reset(seed=seed)
        assert env.observation_space.contains(obs)
        shapes.add(info["shape"])
        obs, *_ = env.step(env.action_space.sample())
        assert env.observation_space.contains(obs)
    assert shapes == ({"box", "cylinder", "sphere"} if fingers in (2, 4) else {"cylinder", "sphere"})
    env.close()


def test_randomisation_seeded_in_range_and_overridable():
    env = PickMultiEnv(fingers=4, size_range=(0.045, 0.05), mass_range=(0.03, 0.031), friction_range=(0.7, 0.9),
                       offset_max=0.004, yaw_range=(-0.1, 0.1), **FAST)
    seen = set()
    for seed in range(6):
        _, info = env.reset(seed=seed)
        assert 0.045 <= info["width"] <= 0.05 and 0.03 <= info["mass"] <= 0.031 and 0.7 <= info["friction"] <= 0.9
        assert math.hypot(*info["offset"]) <= 0.004 and -0.1 <= info["yaw"] <= 0.1
        # the workpiece starts where it was drawn (settled on the table)
        x, y = env.data.qpos[env.work_qpos:env.work_qpos + 2]
        assert math.hypot(x - info["offset"][0], y - info["offset"][1]) < 1e-3
        _, again = env.reset(seed=seed)
        assert again["width"] == info["width"] and again["shape"] == info["shape"]
        seen.add(round(info["width"], 9))
    assert len(seen) == 6
    _, info = env.reset(seed=0, options={"shape": "box", "width": 0.05, "mass": 0.04, "friction": 1.0,
                                         "offset": (0.0, 0.0), "yaw": 0.0})
    assert (info["shape"], info["width"], info["mass"], info["friction"]) == ("box", 0.05, 0.04, 1.0)
    assert env.model.geom_size[env._pm.work_geom][0] == pytest.approx(0.025)
    for bad in ({"shape": "cone"}, {"width": -1.0}, {"offset": (math.nan, 0.0)}, {"yaw": math.inf}, {"size": 1}):
        with pytest.raises(ValueError):
            env.reset(options=bad)
    env.close()


def test_same_seed_same_observations_and_rewards():
    a, b = PickMultiEnv(**FAST), PickMultiEnv(**FAST)
    for seed in (3, 8):
        info_a, run_a = _rollout(a, seed)
        info_b, run_b = _rollout(b, seed)
        assert info_a["shape"] == info_b["shape"]
        assert len(run_a) == len(run_b)
        for x, y in zip(run_a, run_b):
            np.testing.assert_array_equal(x, y)
    # and again on the same instance, after another episode
    _, again = _rollout(a, 3)
    _, first = _rollout(b, 3)
    for x, y in zip(again, first):
        np.testing.assert_array_equal(x, y)
    a.close()
    b.close()


@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
def test_copied_env_continues_exactly_like_the_original(how):
    env = PickMultiEnv(fingers=4, shared_curvature=False, **FAST)
    env.reset(seed=1)
    rng = np.random.default_rng(0)
    for _ in range(10):
        env.step(rng.uniform(-1, 1, 5))
    twin = pickle.loads(pickle.dumps(env)) if how == "pickle" else copy.deepcopy(env)
    for a in rng.uniform(-1, 1, size=(30, 5)):
        o1, r1, t1, *_ = env.step(a)
        o2, r2, t2, *_ = twin.step(a)
        np.testing.assert_array_equal(o1, o2)
        assert (r1, t1) == (r2, t2)
        if t1:
            break
    assert twin.model is not env.model
    twin.reset(seed=2)  # every shape's model travels
    env.close()
    twin.close()


def test_bad_constructor_arguments_name_the_parameter():
    cases = [
        (dict(fingers=1), "fingers"),
        (dict(fingers=2.5), "fingers"),
        (dict(fingers=3, shapes=("box",)), "shapes"),
        (dict(fingers=3, shapes=("box", "cylinder")), "shapes"),
        (dict(shapes=("cube",)), "shapes"),
        (dict(shapes=()), "shapes"),
        (dict(size_range=(math.nan, 0.05)), "size_range"),
        (dict(mass_range=(0.02, math.nan)), "mass_range"),
        (dict(friction_range=(math.nan, math.nan)), "friction_range"),
        (dict(yaw_range=(math.nan, 0.1)), "yaw_range"),
        (dict(offset_max=math.nan), "offset_max"),
        (dict(workpiece_height=math.nan), "workpiece_height"),
        (dict(kappa_range=(0.0, -10.0)), "kappa_range"),
        (dict(shared_curvature=1), "shared_curvature"),
        (dict(n_links=1), "n_links"),
        (dict(render_mode="human"), "render_mode"),
        (dict(camera="nowhere"), "camera"),
        (dict(fingers=12, size_range=(0.01, 0.02)), "size_range"),
    ]
    for kwargs, name in cases:
        with pytest.raises(ValueError, match=name):
            PickMultiEnv(**{**FAST, **kwargs})


def test_invalid_actions_raise_and_step_after_the_end_needs_reset():
    env = PickMultiEnv(**FAST)
    with pytest.raises(gym.error.ResetNeeded):
        env.step(np.zeros(2))
    env.reset(seed=0)
    with pytest.raises(ValueError, match="finite"):
        env.step(np.array([np.nan, 0.0]))
    with pytest.raises(ValueError, match="shape"):
        env.step(np.zeros(4))
    env.close()


def test_scripted_controller_picks_and_the_random_policy_does_not():
    def scripted(env, info, seed):
        pol = ScriptedMultiPolicy()
        pol.reset(env, info)
        return pol

    def random(env, info, seed):
        env.action_space.seed(seed)
        return lambda obs: env.action_space.sample()

    assert _success_rate(scripted, 3, 8, seed0=7000) >= 0.8
    assert _success_rate(scripted, 4, 8, seed0=8000) >= 0.8
    assert _success_rate(scripted, 2, 6, seed0=8500) >= 0.8
    assert _success_rate(random, 3, 15, seed0=9000) < 0.1


class _Blind:
    """The env as the observation policy may see it: its configuration, never the episode's workpiece or state."""

    HIDDEN = ("workpiece", "model", "data", "physical_params", "dimensionless", "np_random")

    def __init__(self, env):
        self._env = env

    @property
    def unwrapped(self):
        return self

    def __getattr__(self, name):
        if name in self.HIDDEN or name.startswith("_"):
            raise AssertionError(f"the observation policy read env.{name}")
        return getattr(self._env, name)


@pytest.mark.parametrize("fingers, seed0", [(3, 11000), (4, 12000)])
def test_observation_policy_picks_without_reading_the_workpiece(fingers, seed0):
    guesses = []

    def honest(env, info, seed):
        pol = ObservationMultiPolicy()
        pol.reset(_Blind(env.unwrapped), info)

        def act(obs):
            a = pol(obs)
            if len(guesses) == seed - seed0:  # the plan is made on the first observation
                truth = env.unwrapped.workpiece  # read here by the test, not by the policy
                guesses.append((pol.details["shape_guess"] == "sphere", truth.shape == "sphere",
                                abs(truth.width - 0.06) < 1e-3))
            return a
        return act

    assert _success_rate(honest, fingers, 20, seed0=seed0) >= 0.8
    # the centre height tells a sphere from a box or cylinder (60 mm tall) unless the sphere is about 60 mm wide
    assert len(guesses) == 20 and all(g == t for g, t, near in guesses if not near)


def test_make_vec_sync():
    envs = gym.make_vec(ENV_ID, num_envs=2, vectorization_mode="sync", **FAST)
    try:
        obs, _ = envs.reset(seed=[1, 2])
        assert obs.shape == (2, 52)
        for _ in range(5):
            obs, rew, term, trunc, _ = envs.step(envs.action_space.sample())
        assert obs.shape == (2, 52) and rew.shape == (2,) and np.all(np.isfinite(obs))
    finally:
        envs.close()


def test_headless_render_returns_an_image_of_the_right_shape(render_backend, tmp_path):
    # render_backend (tests/conftest.py): skips only where the machine has no GL library at all
    code = """
        import json, warnings
        import gymnasium as gym, numpy as np, simgrip.envs
        from gymnasium.utils.env_checker import check_env
        env = gym.make("simgrip/PickMulti-v0", fingers=4, n_links=6, render_mode="rgb_array", width=200, height=150)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            check_env(env.unwrapped)
        frames = []
        for shape in ("box", "sphere"):
            env.reset(seed=0, options={"shape": shape})
            frames.append(env.render())
        env.close()
        f = frames[0]
        r, g, b = (f[..., i].astype(int) for i in range(3))
        print(json.dumps({"warnings": [str(w.message) for w in caught], "shapes": [list(x.shape) for x in frames],
                          "dtype": str(f.dtype), "finger": int(((r > 150) & (r - b > 80) & (g < 160)).sum()),
                          "work": int(((b > 150) & (b - r > 80)).sum()), "std": float(f.std()),
                          "differ": bool(np.any(frames[0] != frames[1]))}))
    """
    # the child imports the simgrip this process imported (not another installed copy)
    root = os.path.dirname(os.path.dirname(simgrip.__file__))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [root, os.environ.get("PYTHONPATH")])))
    proc = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=240)
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert not out["warnings"], out["warnings"]
    assert out["shapes"] == [[150, 200, 3]] * 2 and out["dtype"] == "uint8"
    assert out["finger"] > 50 and out["work"] > 100 and out["std"] > 20 and out["differ"], out


def test_sphere_choice_is_the_planar_choice_at_the_equator_and_holds_below_it():
    from simgrip.envs.scripted import choose_kappa
    from simgrip.envs.scripted_multi import choose_kappa_sphere
    from simgrip.params import PhysicalParams

    p = PhysicalParams(length=0.1, EI=3e-3, rho=0.15, g=9.81, m=0.04 / 3, b=0.058, mu_s=0.8,
                       gamma=0.08).dimensionless()
    k_eq, d_eq = choose_kappa_sphere(p, 0.0, safety=2.0, kappas=np.arange(-2.5, -7.01, -0.25))
    k_planar, d_planar = choose_kappa("I", p, safety=2.0)
    assert k_eq == k_planar
    assert d_eq["normal_force"] == pytest.approx(d_planar["normal_force"], rel=1e-6)
    k_low, d_low = choose_kappa_sphere(p, -0.35, safety=2.0)
    assert d_low["normal_force"] > 0 and d_low["required_mu"] <= p.mu_s / 2.0
    # the tips below the equator push up as well as in: the centre lies above the tips
    assert d_low["centre_height"] > d_low["tip"][1]


def test_two_finger_reward_is_pick_v1s():
    from simgrip.envs.pick_multi_observation import multi_reward
    from simgrip.envs.pick_reward import pick_reward

    kw = dict(phi=0.4, phi_prev=0.3, success=False, lost=False, g=9.81, friction=0.7, w_lift=10.0, w_success=20.0,
              w_squeeze=0.04, w_drop=10.0, squeeze_margin=2.0)
    for sides in ((0.0, 0.0), (0.3, 1.7), (5.0, 0.1)):
        r2, t2 = pick_reward(side_forces=sides, box_mass=0.05, **kw)
        rk, tk = multi_reward(side_forces=sides, mass=0.05, **kw)
        assert rk == pytest.approx(r2, rel=1e-12, abs=1e-15)
        assert tk == pytest.approx(t2, rel=1e-12, abs=1e-15)


def test_bound_reward_is_multi_reward_bit_for_bit():
    """The env's per-episode MultiReward returns multi_reward's sum and terms exactly (the same arithmetic)."""
    from simgrip.envs.pick_multi_observation import MultiReward, multi_reward

    rng = np.random.default_rng(4)
    for K in (2, 3, 5):
        w = dict(g=9.81, friction=float(rng.uniform(0.3, 1.2)), w_lift=10.0, w_success=20.0, w_squeeze=0.04,
                 w_drop=10.0, squeeze_margin=2.0)
        bound = MultiReward(fingers=K, mass=0.03, **w)
        for _ in range(50):
            step = dict(phi=float(rng.uniform()), phi_prev=float(rng.uniform()), success=bool(rng.uniform() < 0.2),
                        lost=bool(rng.uniform() < 0.2))
            sides = rng.uniform(0.0, 3.0, K).tolist()
            r, terms = multi_reward(side_forces=sides, mass=0.03, **step, **w)
            assert bound(step["phi"], step["phi_prev"], step["success"], step["lost"], sides) == (r, *terms.values())


def test_contact_forces_and_tips_against_mujoco_and_the_chain():
    """The forces read from efc_force against mj_contactForce; the observed tips against the hinge chain's
    forward kinematics (simgrip.chain.link_positions) in each finger's plane."""
    import mujoco

    from simgrip.chain import link_positions

    env = PickMultiEnv(fingers=3, **FAST)
    obs, info = env.reset(seed=11, options={"shape": "cylinder"})
    pol = ScriptedMultiPolicy()
    pol.reset(env, info)
    touched = False
    for _ in range(80):
        obs, _, term, _, info = env.step(pol(obs))
        m, d = env.model, env.data
        normal = np.zeros(3)
        friction = np.zeros(3)
        f6 = np.zeros(6)
        owner = env.fingers.finger_of_geom
        for i in range(d.ncon):
            g1, g2 = d.contact.geom[i]
            k = owner[g2] if g1 == env._pm.work_geom else owner[g1] if g2 == env._pm.work_geom else -1
            if k >= 0:
                mujoco.mj_contactForce(m, d, i, f6)
                normal[k] += f6[0]
                friction[k] += math.hypot(f6[1], f6[2])
        np.testing.assert_allclose(info["normal_force"], normal, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(info["friction_force"], friction, rtol=1e-12, atol=1e-12)
        touched |= bool(np.all(normal > 0))
        tips = obs[env.obs_slices["tip_position"]].reshape(3, 2)
        q = d.qpos[env.joint_qpos]
        for k in range(3):
            end = link_positions(np.cumsum(q[k]), 1.0 / env.n)[-1]  # (X, Y) over l, in the finger's plane
            np.testing.assert_allclose(tips[k], end, atol=1e-9)
        if term:
            break
    assert touched
    env.close()


def test_check_env_of_stable_baselines3():
    sb3_checker = pytest.importorskip("stable_baselines3.common.env_checker")
    env = gym.make(ENV_ID, **FAST)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sb3_checker.check_env(env.unwrapped)
    env.close()
    assert not [str(w.message) for w in caught]
