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

#: Warnings check_env may raise that we accept (none today); match on the message start.
CHECK_ENV_ALLOWED = ()


def _headless(code: str, tmp_path) -> dict:
    """Run ``code`` in a fresh interpreter with an offscreen GL backend; it prints one JSON object.

    The backend is simgrip's choice (:func:`simgrip.sim.gl.choose_backend`: ``MUJOCO_GL`` if set, else EGL,
    then OSMesa); the test skips, saying why, only where no backend works at all.
    """
    from simgrip.sim.gl import RenderingUnavailable, choose_backend

    try:
        choose_backend()
    except RenderingUnavailable as exc:
        pytest.skip(str(exc))
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


def test_headless_rendering_check_env_and_frame(tmp_path):
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
        print(json.dumps(res))
        """,
        tmp_path,
    )
    unexpected = [msg for msg in out["warnings"] if not any(msg.startswith(ok) for ok in CHECK_ENV_ALLOWED)]
    assert not unexpected, unexpected
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
    assert env._palm_target == ctrl0[0] and env._hold == 0.0 and env._lifted_rel is None
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


def test_render_png_and_gif(tmp_path):
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


# ---------------------------------------------------------------- reward (v1)
def _return(actions_fn, seed, env_id="simgrip/Pick-v1", **kwargs):
    """Roll one episode; ``actions_fn(t, obs, env)`` gives the action. Returns (return, last info, steps, terms)."""
    env = gym.make(env_id, **kwargs)
    obs, info = env.reset(seed=seed)
    total, terms, t = 0.0, np.zeros(4), 0
    while True:
        obs, r, term, trunc, info = env.step(actions_fn(t, obs, env.unwrapped))
        parts = np.array([info["reward_lift"], info["reward_success"], info["reward_squeeze"], info["reward_drop"]])
        assert r == pytest.approx(parts.sum(), abs=1e-12)  # the terms in info are the reward
        total += r
        terms += parts
        t += 1
        if term or trunc:
            break
    env.close()
    return total, info, t, terms


class _Hover:
    """The oracle's grip, but the palm stops 3 cm short of the target: the box hovers below it, never succeeds."""

    def __call__(self, t, obs, env):
        if t == 0:
            self.pol = ScriptedPickPolicy(extra_lift=-0.03)
            self.pol.reset(env)
        return self.pol(obs)


class _Drop:
    """The oracle's grip and lift, then the fingers open halfway up."""

    def __call__(self, t, obs, env):
        if t == 0:
            self.pol = ScriptedPickPolicy()
            self.pol.reset(env)
        a = self.pol(obs)
        if obs[env.obs_slices["box_lift"]][0] > 0.5 or getattr(self, "opened", False):
            self.opened = True
            a[0] = 1.0
        return a


def _press_on_top(t, obs, env):
    """Straight fingers, palm driven down onto the box top."""
    return np.array([1.0, -1.0], dtype=np.float32)


def test_reward_ranks_success_above_every_way_of_not_succeeding():
    from simgrip.envs.scripted import ObservationPickPolicy

    env = PickEnv()
    w_lift, w_success, w_squeeze, w_drop = env.w_lift, env.w_success, env.w_squeeze, env.w_drop
    T = gym.spec("simgrip/Pick-v1").max_episode_steps
    assert w_squeeze * T <= w_drop  # dropping never pays more than going on squeezing
    assert w_success - w_squeeze * T > 0  # any success beats the best failure (hovering: at most w_lift)

    successes, failures = {}, {}
    for seed in (0, 1, 2):
        pol = ScriptedPickPolicy()
        honest = ObservationPickPolicy()

        def oracle(t, obs, env, pol=pol):
            if t == 0:
                pol.reset(env)
            return pol(obs)

        def observed(t, obs, env, pol=honest):
            if t == 0:
                pol.reset(env)
            return pol(obs)

        successes[f"oracle{seed}"] = _return(oracle, seed)
        successes[f"observation{seed}"] = _return(observed, seed)
        successes[f"full_squeeze_lift{seed}"] = _return(lambda t, o, e: np.array([-1.0, 1.0]), seed)
        failures[f"hover{seed}"] = _return(_Hover(), seed)
        failures[f"drop{seed}"] = _return(_Drop(), seed)
        failures[f"nothing{seed}"] = _return(lambda t, o, e: np.array([1.0, 0.0]), seed)
        failures[f"full_squeeze_no_lift{seed}"] = _return(lambda t, o, e: np.array([-1.0, 0.0]), seed)
        failures[f"press_on_top{seed}"] = _return(_press_on_top, seed)
        failures[f"random{seed}"] = _return(lambda t, o, e, rng=np.random.default_rng(seed): rng.uniform(-1, 1, 2),
                                            seed)
    for name, (ret, info, steps, terms) in successes.items():
        assert info["is_success"], name
        assert ret >= w_lift + w_success - w_squeeze * steps - 1e-9, name
        assert terms[0] == pytest.approx(w_lift * 1.0), name  # progress paid once: sums to w_lift at the target
    for name, (ret, info, steps, terms) in failures.items():
        assert not info["is_success"], name
        assert ret < w_lift, name
        assert terms[0] <= w_lift * (1 + 1e-12), name
    best_failure = max(r for r, *_ in failures.values())
    worst_success = min(r for r, *_ in successes.values())
    assert worst_success > best_failure + 0.5 * w_success, (worst_success, best_failure)
    # hovering below the target earns its progress but no more: not per step
    for seed in (0, 1, 2):
        ret, info, steps, terms = failures[f"hover{seed}"]
        assert steps == T and 0.3 * w_lift < terms[0] < w_lift
    # dropping the box takes its progress back and costs w_drop: worse than doing nothing
    for seed in (0, 1, 2):
        ret, info, steps, terms = failures[f"drop{seed}"]
        assert info["dropped"] and steps < T
        assert terms[0] == pytest.approx(0.0, abs=1e-12) and terms[3] == -w_drop
        assert ret < failures[f"nothing{seed}"][0] - 0.5 * w_drop
    # the gentle oracle grip pays less squeeze than the full curl
    assert successes["oracle0"][3][2] > successes["full_squeeze_lift0"][3][2]


def test_squeeze_penalty_counts_only_side_contacts_and_is_bounded():
    env = PickEnv()
    env.reset(seed=0)
    pressed = []
    for t in range(40):
        obs, r, term, trunc, info = env.step(_press_on_top(t, None, env))
        pressed.append((info["normal_force"].sum(), info["side_force"].sum(), info["reward_squeeze"]))
        assert not term
    normal, side, squeeze = np.array(pressed).T
    assert normal.max() > 5 * env.box.mass * env.g  # the fingers press hard on the top...
    assert side.max() < 0.05 * normal.max()  # ...which is not a squeeze
    assert squeeze.min() > -0.01 * env.w_squeeze
    env.reset(seed=0)
    for _ in range(40):
        _, r, *_, info = env.step(np.array([-1.0, 0.0]))  # full curl: squeezes the sides hard
        assert -env.w_squeeze <= info["reward_squeeze"] <= 0.0
    assert info["reward_squeeze"] < -0.5 * env.w_squeeze
    env.close()


def test_step_after_the_end_raises_until_reset():
    env = PickEnv()
    with pytest.raises(gym.error.ResetNeeded):
        env.step(np.zeros(2))  # before the first reset
    env.reset(seed=0)
    t = 0
    while True:
        _, r, term, trunc, info = env.step(np.array([-1.0, 1.0]))
        t += 1
        if term:
            break
        assert t < 200
    assert info["is_success"] and info["reward_success"] == env.w_success
    with pytest.raises(gym.error.ResetNeeded):
        env.step(np.array([-1.0, 1.0]))  # no second success bonus
    env.reset(seed=0)
    _, r, term, *_ = env.step(np.array([-1.0, 1.0]))
    assert not term
    env.close()
    wrapped = gym.make("simgrip/Pick-v1")  # through Gymnasium's wrappers (OrderEnforcing, PassiveEnvChecker)
    with pytest.raises(gym.error.ResetNeeded):
        wrapped.step(np.zeros(2))
    wrapped.reset(seed=0)
    while not wrapped.step(np.array([-1.0, 1.0]))[2]:
        pass
    with pytest.raises(gym.error.ResetNeeded):
        wrapped.step(np.zeros(2))
    wrapped.close()


def test_diverged_physics_raises_physics_error():
    from simgrip.sim.checks import PhysicsError

    env = PickEnv()
    env.reset(seed=0)
    env.data.qvel[env.box_dof] = np.nan
    with pytest.raises(PhysicsError, match="step diverged"):
        env.step(np.zeros(2))
    with pytest.raises(gym.error.ResetNeeded):
        env.step(np.zeros(2))
    env.reset(seed=0)
    env.step(np.zeros(2))
    env.close()


# ----------------------------------------------------------- observation (v1)
@pytest.mark.parametrize("per_finger", [False, True])
def test_observation_has_no_constant_entries_and_is_in_finger_lengths(per_finger):
    from simgrip.envs.scripted import ObservationPickPolicy

    env = PickEnv(per_finger=per_finger)
    rows = []
    for seed in range(4):
        obs, info = env.reset(seed=seed)
        pol = ObservationPickPolicy()
        pol.reset(env, info)
        rng = np.random.default_rng(seed)
        rows.append(obs)
        for t in range(200):
            a = pol(obs) if seed % 2 == 0 else rng.uniform(-1, 1, env.action_space.shape)
            obs, r, term, trunc, info = env.step(a)
            rows.append(obs)
            assert env.observation_space.contains(obs)
            if term:
                break
    rows = np.array(rows)
    names = [name for name, size in env.obs_layout for _ in range(size)]
    spread = rows.std(axis=0)
    constant = [(int(i), names[i]) for i in np.flatnonzero(spread < 1e-6)]
    assert not constant, constant
    # well scaled for a network: no entry's spread exceeds ~20 units
    big = [(names[i], float(spread[i])) for i in np.flatnonzero(spread > 20)]
    assert not big, big
    # lengths in finger lengths: the palm and tips match the simulation state divided by the length
    sl, L, d = env.obs_slices, env.length, env.data
    assert obs[sl["palm_height"]][0] == pytest.approx(d.qpos[env.palm_qpos] / L)
    tip0 = d.geom_xpos[env.tip_geom[0]]
    np.testing.assert_allclose(obs[sl["tip_position"]][:2], [tip0[0] / L, (tip0[2] - d.qpos[env.palm_qpos]) / L])
    assert np.all(np.abs(obs[sl["tip_position"]]) <= 1.0 + 1e-9)  # the tips are within one finger length
    box_z = d.qpos[env.box_qpos + 2]
    assert obs[sl["box_position"]][-1] == pytest.approx((box_z - d.qpos[env.palm_qpos]) / L)
    assert obs[sl["box_lift"]][0] == pytest.approx((box_z - env._z0) / env.target_height)
    env.close()


def test_symmetric_layout_leaves_out_only_mirrored_entries():
    """Without per_finger, finger 1 mirrors finger 0 and the box stays on the axis: the 37-entry
    per-finger observation of the same run carries nothing the 19 entries do not."""
    env2 = PickEnv(per_finger=True)
    env1 = PickEnv()
    rng = np.random.default_rng(3)
    o1, _ = env1.reset(seed=3)
    o2, _ = env2.reset(seed=3)
    s1, s2 = env1.obs_slices, env2.obs_slices
    for _ in range(80):
        a = rng.uniform(-1, 1, 2)
        o1, r1, t1, *_ = env1.step(a)
        o2, r2, t2, *_ = env2.step(np.array([a[0], a[0], a[1]]))
        assert r1 == pytest.approx(r2, abs=1e-6)
        K = env1.shape_points
        np.testing.assert_allclose(o2[s2["finger_shape"]][K:], o2[s2["finger_shape"]][:K], atol=1e-6)
        np.testing.assert_allclose(o2[s2["tip_position"]][2:] * [-1, 1], o2[s2["tip_position"]][:2], atol=1e-6)
        np.testing.assert_allclose(o2[s2["contact_force"]][2:], o2[s2["contact_force"]][:2], atol=1e-6)
        assert abs(o2[s2["box_position"]][0]) < 1e-6 and abs(o2[s2["box_tilt"]][0]) < 1e-6
        for name, sl in s1.items():
            idx = range(sl.stop - sl.start)
            sub = o2[s2[name]]
            mine = sub[[1]] if name in ("box_position", "box_velocity") else sub[list(idx)]
            np.testing.assert_allclose(o1[sl], mine, atol=1e-6, err_msg=name)
        if t1:
            break


# -------------------------------------------------------- arguments (issue 12)
BAD_ARGUMENTS = {
    "n_links": [0, 2.5, "12", None, True],
    "length": [0, -0.1, float("nan"), float("inf"), "x", None],
    "EI": [0, float("nan")], "rho": [-1, float("inf")], "g": [0, float("nan")],
    "box_width_range": [(0.05, 0.01), (0.05, float("nan")), 0.05, (0.1, 0.3)],
    "box_mass_range": [(-0.01, 0.02), ("a", "b")], "friction_range": [(0, 1), None],
    "box_height": [0, float("nan")], "box_depth": [-1, "deep"],
    "per_finger": ["yes", 1, None],
    "kappa_range": [(0, 0), (1, -1), (float("-inf"), 0)],
    "kappa_tau": [-0.1, float("nan"), "slow"],
    "palm_speed": [0, float("nan")], "palm_range": [(0.2, 0.1), (0, 0.2)], "palm_start": [(0.01, 0.02), (0.3, 0.4)],
    "target_height": [0, float("nan")], "hold_time": [-1, float("nan"), float("inf")],
    "w_lift": [-1, float("nan")], "w_success": [float("inf")], "w_squeeze": [-0.1, "x"], "w_drop": [float("nan")],
    "squeeze_margin": [0, float("nan")], "drop_distance": [0, float("inf")],
    "timestep": [0, float("nan"), -0.002], "frame_skip": [0, 2.5, float("nan"), True],
    "settle_time": [float("nan"), -1, float("inf")],
    "finger_damping_time": [float("nan"), -0.01, float("inf")],
    "shape_points": [1, 3.5, float("nan")], "r_tip": [0, float("nan")], "spin_friction": [-1, float("nan")],
    "impratio": [0, float("nan")], "finger_armature": [-1, float("nan")],
    "width": [0, 10.5, float("nan")], "height": [-1, "tall"], "camera": ["nope", 3, ""],
}


@pytest.mark.parametrize("name", sorted(BAD_ARGUMENTS))
def test_every_constructor_argument_is_validated_by_name(name):
    for value in BAD_ARGUMENTS[name]:
        with pytest.raises(ValueError, match=rf"\b{name}\b"):
            PickEnv(**{name: value})


def test_every_constructor_argument_has_bad_values_listed():
    import inspect

    params = set(inspect.signature(PickEnv.__init__).parameters) - {"self", "grip", "render_mode"}
    assert params == set(BAD_ARGUMENTS)


def test_nan_damping_and_settle_time_rejected_before_any_step():
    with pytest.raises(ValueError, match="finger_damping_time"):
        gym.make("simgrip/Pick-v1", finger_damping_time=float("nan"))
    with pytest.raises(ValueError, match="settle_time"):
        gym.make("simgrip/Pick-v1", settle_time=float("nan"))


# ----------------------------------------------------------- pickling (issue 12)
@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_copied_env_continues_exactly_like_the_original(how, env_id):
    import copy
    import pickle

    env = gym.make(env_id)
    env.reset(seed=4)
    rng = np.random.default_rng(0)
    for _ in range(25):
        env.step(rng.uniform(-1, 1, 2))
    twin = pickle.loads(pickle.dumps(env)) if how == "pickle" else copy.deepcopy(env)
    actions = rng.uniform(-1, 1, size=(60, 2))
    for k, a in enumerate(actions):
        o1, r1, t1, u1, i1 = env.step(a)
        o2, r2, t2, u2, i2 = twin.step(a)
        np.testing.assert_array_equal(o1, o2)
        assert (r1, t1, u1) == (r2, t2, u2)
        if t1 or u1:
            break
    # the copy is independent: stepping it does not move the original, and the RNG goes on alike
    assert twin.unwrapped.model is not env.unwrapped.model
    o1, _ = env.reset()
    o2, _ = twin.reset()
    np.testing.assert_array_equal(o1, o2)
    env.close()
    twin.close()


def test_check_env_of_stable_baselines3():
    sb3_checker = pytest.importorskip("stable_baselines3.common.env_checker")
    for env_id in ENV_IDS:
        env = gym.make(env_id)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            sb3_checker.check_env(env.unwrapped)
        env.close()
        assert not [str(w.message) for w in caught]


# ------------------------------------------------------------------ examples
def _example(name):
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "examples" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"example_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("name, argv", [
    ("scripted_pick", ["--policy", "oracle"]), ("scripted_pick", ["--policy", "observation"]), ("random_policy", []),
])
def test_examples_print_a_json_summary(name, argv, capsys):
    summary = _example(name).main(["--episodes", "2", "--seed", "7", "--json", *argv])
    out = json.loads(capsys.readouterr().out.strip())
    assert out == summary
    assert set(out) == {"episodes", "success_rate", "mean_return"} and out["episodes"] == 2
    if name == "scripted_pick":
        assert out["success_rate"] == 1.0


def test_random_policy_documents_only_its_options():
    module = _example("random_policy")
    doc = module.__doc__
    for option in ("--episodes", "--seed", "--env", "--json"):
        assert option in doc
    import re

    assert set(re.findall(r"--[a-z][a-z-]*", doc)) == {"--episodes", "--seed", "--env", "--json"}
    with pytest.raises(SystemExit):
        module.main(["--vector", "4"])


def test_train_sb3_smoke(tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    module = _example("train_sb3")
    module.main(["--algo", "sac", "--steps", "120", "--eval-episodes", "1", "--out", str(tmp_path)])
    res = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert res["algo"] == "SAC" and res["timesteps"] >= 120 and res["episodes"] == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["curves.png", "sac_curve.csv", "sac_eval.json",
                                                           "sac_model.zip"]
