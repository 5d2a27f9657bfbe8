"""Gymnasium environments: API conformance, determinism, vectorisation, rendering, policies."""

import os

import json  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import textwrap  # noqa: E402
import warnings  # noqa: E402

import gymnasium as gym  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from gymnasium.utils.env_checker import check_env  # noqa: E402

import simgrip.envs  # noqa: E402,F401  (registers the ids)
from simgrip.envs import ENV_IDS  # noqa: E402
from simgrip.envs.pick import OBS_LAYOUT, PickEnv  # noqa: E402
from simgrip.envs.scripted import ScriptedPickPolicy  # noqa: E402
from env_checks import assert_sb3_check_env_clean

#: Warnings check_env may raise that we accept (none today); match on the message start.
CHECK_ENV_ALLOWED = ()


def _headless(code: str, tmp_path) -> dict:
    """Run ``code`` in a fresh interpreter with an offscreen GL backend; it prints one JSON object.

    The backend is simgrip's choice (:func:`simgrip.sim.gl.choose_backend`: ``MUJOCO_GL`` if set, else EGL,
    then OSMesa), made by the ``render_backend`` fixture (tests/conftest.py) that the callers request: it
    skips only on a machine with no GL library at all, read from the machine, not from the code under test.
    """
    env = dict(os.environ)
    proc = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=240)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _run(env, actions, seed):
    obs, _ = env.reset(seed=seed)
    out = [obs]
    for a in actions:
        obs, r, term, trunc, info = env.step(a)
        out.append(np.append(obs, r))
        if term or trunc:
            break
    return out


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_check_env_passes_without_warnings(env_id):
    env = gym.make(env_id)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            # rendering is checked headless in a subprocess (test_headless_rendering_check_env_and_frame)
            check_env(env.unwrapped, skip_render_check=True)
    finally:
        env.close()
    messages = [str(w.message) for w in caught]
    unexpected = [msg for msg in messages if not any(msg.startswith(ok) for ok in CHECK_ENV_ALLOWED)]
    assert not unexpected, unexpected


def test_headless_rendering_check_env_and_frame(render_backend, tmp_path):
    """check_env with rgb_array rendering, and a frame that shows fingers and box (CPU only, OSMesa/EGL)."""
    out = _headless(
        """
        import json, warnings
        import gymnasium as gym, numpy as np, simgrip.envs
        from gymnasium.utils.env_checker import check_env
        res = {"warnings": []}
        for env_id in simgrip.envs.ENV_IDS:
            env = gym.make(env_id, render_mode="rgb_array")
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                check_env(env.unwrapped)
            res["warnings"] += [str(w.message) for w in caught]
            env.close()
        env = gym.make("simgrip/Pick-v1", render_mode="rgb_array", width=240, height=180)
        env.reset(seed=0)
        frame = env.render()
        env.close()
        r, g, b = (frame[..., i].astype(int) for i in range(3))
        res["shape"] = list(frame.shape)
        res["dtype"] = str(frame.dtype)
        res["finger"] = int(((r > 150) & (r - b > 80) & (g < 160)).sum())  # orange links
        res["box"] = int(((b > 150) & (b - r > 80)).sum())  # blue box
        res["std"] = float(frame.std())
        # wider than the model's 640-pixel offscreen buffer: failed at the first render with MuJoCo's own message
        env = gym.make("simgrip/PickFragile-v7", render_mode="rgb_array", width=800, height=600)
        env.reset(seed=0)
        res["wide"] = list(env.render().shape)
        env.close()
        print(json.dumps(res))
        """,
        tmp_path,
    )
    unexpected = [msg for msg in out["warnings"] if not any(msg.startswith(ok) for ok in CHECK_ENV_ALLOWED)]
    assert not unexpected, unexpected
    assert out["wide"] == [600, 800, 3]
    assert out["shape"] == [180, 240, 3] and out["dtype"] == "uint8"
    assert out["finger"] > 100, out
    assert out["box"] > 300, out
    assert out["std"] > 20, out


def test_registered_ids_have_time_limits():
    for env_id in ENV_IDS:
        spec = gym.spec(env_id)
        assert spec.max_episode_steps and spec.max_episode_steps > 0
        assert spec.entry_point == "simgrip.envs.pick:PickEnv"


def test_spaces_and_documented_layout():
    env = gym.make("simgrip/Pick-v1")
    assert env.action_space.shape == (2,)
    assert env.observation_space.shape == (19,)
    assert sum(size for _, size in env.unwrapped.obs_layout) == 19
    assert env.unwrapped.obs_layout == OBS_LAYOUT
    obs, info = env.reset(seed=0)
    assert env.observation_space.contains(obs)
    d = info["dimensionless"]
    assert 1.5 < d.D < 2.5 and 0.4 <= d.b <= 0.65
    env.close()
    env = gym.make("simgrip/Pick-v1", per_finger=True, n_links=16, shape_points=6)
    assert env.action_space.shape == (3,)
    assert env.observation_space.shape == (21 + 2 * 6,)
    obs, _ = env.reset(seed=0)
    assert obs.shape == (33,)
    assert sum(size for _, size in env.unwrapped.obs_layout) == 33
    env.close()
    # every documented block is named in the docstring's observation table
    for name, _ in OBS_LAYOUT:
        assert f"``{name}``" in PickEnv.__doc__, name


def test_v0_ids_are_retired_with_a_pointer_to_v1():
    for old, new in (("simgrip/Pick-v0", "simgrip/Pick-v1"), ("simgrip/PickCradle-v0", "simgrip/PickCradle-v1")):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with pytest.raises(gym.error.DeprecatedEnv, match=new):
                gym.make(old)


def test_same_seed_same_actions_identical_observations():
    rng = np.random.default_rng(7)
    actions = rng.uniform(-1, 1, size=(60, 2)).astype(np.float32)
    env = gym.make("simgrip/Pick-v1")
    first = _run(env, actions, seed=11)
    # a different episode in between, then the same seed again: reset restores everything
    _run(env, rng.uniform(-1, 1, size=(40, 2)), seed=99)
    second = _run(env, actions, seed=11)
    env.close()
    fresh = gym.make("simgrip/Pick-v1")
    third = _run(fresh, actions, seed=11)
    fresh.close()
    assert len(first) == len(second) == len(third)
    for a, b, c in zip(first, second, third):
        np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(a, c)


def test_reset_restores_rest_angles_control_and_warmstart():
    env = PickEnv()
    env.reset(seed=3)
    m, d = env.model, env.data
    spring0 = m.qpos_spring.copy()
    ctrl0 = d.ctrl.copy()
    qpos0 = d.qpos.copy()
    warm0 = d.qacc_warmstart.copy()
    for _ in range(30):
        env.step(np.array([-1.0, 1.0]))
    assert not np.array_equal(m.qpos_spring, spring0)
    env.reset(seed=3)
    np.testing.assert_array_equal(m.qpos_spring, spring0)
    np.testing.assert_array_equal(d.ctrl, ctrl0)
    np.testing.assert_array_equal(d.qpos, qpos0)
    np.testing.assert_array_equal(d.qacc_warmstart, warm0)  # solver warm start
    assert env._palm.target == ctrl0[0] and env._hold == 0.0 and env._lifted_rel is None
    assert np.all(env._kappa == 0) and np.all(env._kappa_cmd == 0)
    env.close()


def test_curvature_lag_and_rest_angles_at_run_time():
    from simgrip.chain import chain_springs
    from simgrip.profiles import Uniform

    env = PickEnv(kappa_tau=0.1, n_links=10)
    env.reset(seed=0)
    model_id = id(env.model)
    lo, hi = env.kappa_range
    target = -4.0
    a = np.array([2 * (target - lo) / (hi - lo) - 1, 0.0])
    kappa = 0.0
    for _ in range(5):
        obs, *_ = env.step(a)
        kappa = target + (kappa - target) * np.exp(-env.dt / 0.1)
        # curvatures are observed in action units: a = 2 (kappa - lo) / (hi - lo) - 1
        np.testing.assert_allclose(obs[env.obs_slices["kappa_command"]], a[0], rtol=1e-12)
        np.testing.assert_allclose(obs[env.obs_slices["kappa_actual"]], 2 * (kappa - lo) / (hi - lo) - 1, rtol=1e-12)
        rest = chain_springs(Uniform(kappa), 10).rest
        np.testing.assert_allclose(env.model.qpos_spring[env.joint_qpos], np.vstack([rest, rest]), atol=1e-14)
    assert id(env.model) == model_id  # no recompilation
    env.close()


def test_randomisation_seeded_and_in_range():
    env = PickEnv(box_width_range=(0.045, 0.05), box_mass_range=(0.03, 0.031), friction_range=(0.7, 0.9))
    seen = set()
    for seed in range(5):
        _, info = env.reset(seed=seed)
        assert 0.045 <= info["box_width"] <= 0.05
        assert 0.03 <= info["box_mass"] <= 0.031
        assert 0.7 <= info["box_friction"] <= 0.9
        seen.add(round(info["box_width"], 9))
        _, again = env.reset(seed=seed)
        assert again["box_width"] == info["box_width"]
    assert len(seen) == 5
    _, info = env.reset(options={"box_width": 0.05, "box_mass": 0.04, "friction": 1.0})
    assert (info["box_width"], info["box_mass"], info["box_friction"]) == (0.05, 0.04, 1.0)
    with pytest.raises(ValueError, match="reset options"):
        env.reset(options={"width": 1})
    env.close()


@pytest.mark.parametrize("mode", ["sync", "async"])
def test_make_vec(mode):
    envs = gym.make_vec("simgrip/Pick-v1", num_envs=2, vectorization_mode=mode)
    try:
        obs, info = envs.reset(seed=[1, 2])
        assert obs.shape == (2, 19)
        for _ in range(5):
            obs, rew, term, trunc, info = envs.step(envs.action_space.sample())
        assert obs.shape == (2, 19) and rew.shape == (2,)
    finally:
        envs.close()


def test_invalid_actions_raise_and_out_of_bounds_clip():
    env = PickEnv()
    env.reset(seed=0)
    with pytest.raises(ValueError, match="finite"):
        env.step(np.array([np.nan, 0.0]))
    with pytest.raises(ValueError, match="shape"):
        env.step(np.zeros(3))
    with pytest.raises(ValueError, match="numbers"):
        env.step("close")
    env.reset(seed=0)
    o_big, *_ = env.step(np.array([-5.0, 0.0]))
    env.reset(seed=0)
    o_one, *_ = env.step(np.array([-1.0, 0.0]))
    np.testing.assert_array_equal(o_big, o_one)
    assert o_one[env.obs_slices["kappa_command"]][0] == -1.0  # command at the documented bound
    env.close()


def test_bad_constructor_arguments():
    with pytest.raises(ValueError, match="grip"):
        PickEnv(grip="II")
    with pytest.raises(ValueError, match="render_mode"):
        PickEnv(render_mode="human")
    with pytest.raises(ValueError, match="box_width_range"):
        PickEnv(box_width_range=(0.05, 0.01))


def test_render_png_and_gif(render_backend, tmp_path):
    out = _headless(
        """
        import json
        from pathlib import Path
        from PIL import Image
        from simgrip.envs.rendering import render_grip_png, render_pick_gif
        res = {}
        info = render_grip_png("grip.png", seed=1, width=160, height=120)
        res["normal_force"] = info["normal_force"]
        with Image.open("grip.png") as im:
            res["png_size"] = list(im.size)
        info = render_pick_gif("pick.gif", seed=1, width=96, height=72, every=10)
        with Image.open("pick.gif") as im:
            res["gif_frames"] = im.n_frames
        res["frames"] = info["frames"]
        res["is_success"] = info["is_success"]
        res["files"] = sorted(p.name for p in Path(".").iterdir())
        print(json.dumps(res))
        """,
        tmp_path,
    )
    assert out["png_size"] == [160, 120]
    assert min(out["normal_force"]) > 0  # the picture shows a grip, not open fingers
    assert out["gif_frames"] == out["frames"] > 3
    assert out["is_success"]
    assert out["files"] == ["grip.png", "pick.gif"]  # no temporary leftovers


def test_measure_throughput_reports_figures():
    from simgrip.envs.throughput import measure_throughput

    r = measure_throughput(steps=60, repeats=1)
    for key in ("env_steps_per_s", "raw_physics_steps_per_s", "overhead_percent", "overhead_vs_nstep_percent"):
        assert np.isfinite(r[key])
    assert r["env_steps_per_s"] > 0 and r["frame_skip"] == 10


def _episodes(policy_fn, n, seed0, env_id="simgrip/Pick-v1"):
    env = gym.make(env_id)
    wins = 0
    for ep in range(n):
        obs, info = env.reset(seed=seed0 + ep)
        act = policy_fn(env, info, ep)
        while True:
            obs, r, term, trunc, info = env.step(act(obs))
            if term or trunc:
                break
        wins += bool(info["is_success"])
    env.close()
    return wins / n


def _scripted(env, info, ep):
    pol = ScriptedPickPolicy()
    pol.reset(env, info)
    return pol


def test_scripted_elastica_controller_succeeds():
    rate = _episodes(_scripted, 20, seed0=2000)
    assert rate >= 0.9, rate


def test_scripted_controller_cradles_the_box():
    env = gym.make("simgrip/PickCradle-v1")
    obs, info = env.reset(seed=5)
    pol = _scripted(env, info, 0)
    u = env.unwrapped
    while True:
        obs, r, term, trunc, info = env.step(pol(obs))
        if term or trunc:
            break
    assert info["is_success"]
    # a cradle, not a pinch: the fingertips end under the box, inside its width and below its bottom
    sl, L = u.obs_slices, u.length
    half = 0.5 * u.box.width / L
    tips = obs[sl["tip_position"]].reshape(-1, 2)  # (x, z) relative to the palm, finger lengths (finger 0)
    bottom = obs[sl["box_position"]][-1] - 0.5 * u.box_height / L
    assert np.all(np.abs(tips[:, 0]) < half) and np.all(tips[:, 1] < bottom)
    env.close()
    rate = _episodes(_scripted, 10, seed0=4000, env_id="simgrip/PickCradle-v1")
    assert rate >= 0.9, rate


def test_random_policy_rarely_succeeds():
    def random_policy(env, info, ep):
        space = env.action_space
        space.seed(ep)
        return lambda obs: space.sample()

    rate = _episodes(random_policy, 20, seed0=3000)
    assert rate < 0.1, rate


def test_honest_scripted_controller_sees_only_the_observation():
    """The observation-only controller (no true mass or friction) still picks both grips."""
    from simgrip.envs.scripted import ObservationPickPolicy

    def honest(env, info, ep):
        pol = ObservationPickPolicy()
        pol.reset(env, info)
        return pol

    assert _episodes(honest, 20, seed0=5000) >= 0.9
    assert _episodes(honest, 10, seed0=6000, env_id="simgrip/PickCradle-v1") >= 0.9


def test_check_env_of_stable_baselines3():
    assert_sb3_check_env_clean(ENV_IDS)
