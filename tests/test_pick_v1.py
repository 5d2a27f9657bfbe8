"""PickEnv v1: the reward ranks success above every failure, the episode's end is guarded, the
observation is well scaled with no constant or mirrored entries."""

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  (registers the ids)
from simgrip.envs.pick import PickEnv
from simgrip.envs.scripted import ScriptedPickPolicy


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



@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
def test_state_check_of_a_copied_env_reads_the_copy(how):
    import copy
    import pickle

    from simgrip.sim.checks import PhysicsError, StateCheck, invalid_state

    env = PickEnv()
    env.reset(seed=0)
    twin = pickle.loads(pickle.dumps(env)) if how == "pickle" else copy.deepcopy(env)
    twin.data.qvel[twin.box_dof] = np.nan
    with pytest.raises(PhysicsError, match="step diverged"):  # the copy's check sees the copy's data
        twin.step(np.zeros(2))
    env.step(np.zeros(2))  # the original's data is untouched
    check = StateCheck(env.data)
    assert check() is None
    env.data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number = 1
    assert check() == invalid_state(env.data) and "mjWARN_BADQACC" in check()
    check.clear()
    assert check() is None and invalid_state(env.data) is None
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


# ------------------------------------------- step against a reference computed from the state
def _reference_forces(env):
    """Per finger (normal, friction magnitude, horizontal part of the normal) [N]: contact by contact through
    mujoco.mj_contactForce (the documented API), not the constraint rows the env reads."""
    m, d = env.model, env.data
    fog = np.asarray(env.fingers.finger_of_geom)
    out, cf = np.zeros((2, 3)), np.zeros(6)
    for i in range(d.ncon):
        c = d.contact[i]
        g1, g2 = c.geom
        other = g2 if g1 == env.box_geom else (g1 if g2 == env.box_geom else -1)
        if other < 0 or fog[other] < 0:
            continue
        mujoco.mj_contactForce(m, d, i, cf)
        out[fog[other]] += (cf[0], np.hypot(cf[1], cf[2]), cf[0] * abs(c.frame[0]))
    return out


def _reference_obs(env, kcmd, kact, z0, hold, forces):
    """The observation as the docstring's table defines it, from the MuJoCo state (the per-finger layout,
    reduced to finger 0 and the box's z without per_finger)."""
    from simgrip.envs.pick_observation import SPIN_TIME

    d, L, n, K = env.data, env.length, env.n, env.shape_points
    lo, hi = env.kappa_range
    W = env.g * np.mean(env.box_mass_range)
    palm_z, palm_v = d.qpos[env.palm_qpos], d.qvel[env.palm_dof]
    s_link, s_k = (np.arange(n) + 0.5) / n, (np.arange(K) + 0.5) / K
    shape = [np.interp(s_k, s_link, np.cumsum(d.qpos[env.joint_qpos[f]])) for f in (0, 1)]
    tips = [d.geom_xpos[env.tip_geom[f]] for f in (0, 1)]
    bq, bd = env.box_qpos, env.box_dof
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, d.qpos[bq + 3:bq + 7])
    b = {
        "palm_height": [palm_z / L],
        "kappa_command": [2 * (k - lo) / (hi - lo) - 1 for k in kcmd],
        "kappa_actual": [2 * (k - lo) / (hi - lo) - 1 for k in kact],
        "finger_shape": np.concatenate(shape),
        "tip_position": [tips[0][0] / L, (tips[0][2] - palm_z) / L, tips[1][0] / L, (tips[1][2] - palm_z) / L],
        "box_position": [d.qpos[bq] / L, (d.qpos[bq + 2] - palm_z) / L],
        "box_tilt": [np.arctan2(R[2], R[8])],  # the box's z axis (third column) towards +x
        "box_velocity": [d.qvel[bd] / L, (d.qvel[bd + 2] - palm_v) / L],
        "box_spin": [d.qvel[bd + 4] * SPIN_TIME],
        "box_lift": [(d.qpos[bq + 2] - z0) / env.target_height],
        "contact_force": np.log1p(forces[:, :2] / W).ravel(),
        "hold": [min(hold / env.hold_time, 1.0)],
    }
    if not env.per_finger:
        b = {name: v[:size] if name not in ("box_position", "box_velocity") else v[1:]
             for name, v in b.items() for name2, size in env.obs_layout if name2 == name}
    obs = np.concatenate([np.asarray(b[name], dtype=float) for name, _ in env.obs_layout])
    return np.clip(obs, env.observation_space.low, env.observation_space.high)


def _check_against_reference(env, seed, policy):
    """Roll one episode and recompute every step's observation, reward, end and info from the state."""
    from simgrip.chain import chain_springs
    from simgrip.profiles import Uniform

    obs, info = env.reset(seed=seed)
    d = env.data
    lo, hi = env.kappa_range
    unit_rest = chain_springs(Uniform(1.0), env.n).rest
    alpha = 1.0 - np.exp(-env.dt / env.kappa_tau)
    z0, xy0 = d.qpos[env.box_qpos + 2], d.qpos[env.box_qpos:env.box_qpos + 2].copy()
    kact, hold, phi, lifted_rel = np.zeros(2), 0.0, 0.0, None
    np.testing.assert_allclose(obs, _reference_obs(env, (0, 0), kact, z0, 0.0, _reference_forces(env)),
                               rtol=0, atol=1e-12)
    mg = env.box.mass * env.g
    allow = env.squeeze_margin * mg / (2 * env.box.friction)
    steps = 0
    for t in range(300):
        action = policy(t, obs, env)
        a = np.clip(np.asarray(action, dtype=float), -1, 1)
        obs, r, term, trunc, info = env.step(action)
        steps += 1
        kcmd = lo + (a[:-1] + 1) / 2 * (hi - lo)
        kcmd = kcmd if env.per_finger else np.repeat(kcmd, 2)
        kact = kact + alpha * (kcmd - kact)
        for f in (0, 1):  # the rest angles written for the step
            np.testing.assert_allclose(env.model.qpos_spring[env.joint_qpos[f]], kact[f] * unit_rest, atol=1e-15)
        forces = _reference_forces(env)
        box_z, rel = d.qpos[env.box_qpos + 2], d.qpos[env.box_qpos + 2] - d.qpos[env.palm_qpos]
        gain = box_z - z0
        both = forces[0, 0] > 0 and forces[1, 0] > 0
        if lifted_rel is None and gain > 0.005 and both:
            lifted_rel = rel
        dropped = lifted_rel is not None and rel < lifted_rel - env.drop_distance
        R = np.zeros(9)
        mujoco.mju_quat2Mat(R, d.qpos[env.box_qpos + 3:env.box_qpos + 7])
        knocked = R[8] < np.cos(np.radians(30)) or np.hypot(*(d.qpos[env.box_qpos:env.box_qpos + 2] - xy0)) > 0.03
        hold = hold + env.dt if gain >= env.target_height and both else 0.0
        success = hold >= env.hold_time - 1e-9
        lost = (dropped or knocked) and not success
        phi_new = 0.0 if lost else float(np.clip(gain / env.target_height, 0, 1))
        x = np.maximum(forces[:, 2] - allow, 0) / mg
        terms = (env.w_lift * (phi_new - phi), env.w_success * success, -env.w_squeeze * np.mean(x / (1 + x)),
                 -env.w_drop * lost)
        phi = phi_new
        np.testing.assert_allclose(obs, _reference_obs(env, kcmd, kact, z0, hold, forces), rtol=0, atol=1e-12,
                                   err_msg=f"step {t}")
        assert r == pytest.approx(sum(terms), rel=0, abs=1e-12)
        for key, value in zip(("reward_lift", "reward_success", "reward_squeeze", "reward_drop"), terms):
            assert info[key] == pytest.approx(value, rel=0, abs=1e-12), key
        assert (term, trunc) == (success or lost, False)
        assert (info["is_success"], info["dropped"], info["knocked_over"]) == (
            success, dropped and not success, knocked and not success)
        assert info["box_lift"] == pytest.approx(gain, rel=0, abs=1e-15)
        assert info["hold_time"] == pytest.approx(hold, rel=0, abs=1e-12)
        for key, col in (("normal_force", 0), ("friction_force", 1), ("side_force", 2)):
            assert isinstance(info[key], np.ndarray) and info[key].shape == (2,)
            np.testing.assert_allclose(info[key], forces[:, col], rtol=1e-12, atol=1e-12, err_msg=key)
        if term:
            break
    return steps, info, forces


class _Oracle:
    def __call__(self, t, obs, env):
        if t == 0:
            self.pol = ScriptedPickPolicy()
            self.pol.reset(env)
        return self.pol(obs)


def _random(seed, scale=1.3):
    """Uniform actions, some outside [-1, 1] (the env clips them)."""
    rng = np.random.default_rng(seed)
    return lambda t, obs, env: rng.uniform(-scale, scale, env.action_space.shape)


@pytest.mark.parametrize("grip, per_finger, seed, policy", [
    ("I", False, 1, "oracle"), ("III", False, 1, "oracle"), ("I", False, 0, "full_curl"), ("I", False, 0, "random"),
    ("I", True, 2, "random"), ("III", True, 1, "oracle")])
def test_step_matches_a_reference_computed_from_the_state(grip, per_finger, seed, policy):
    """Every step's observation, reward terms, end and info equal what the docstring defines, recomputed
    from the MuJoCo state by a plain reference (contact forces through mj_contactForce, finger shapes by
    np.interp, the box's tilt from its rotation matrix), to rounding."""
    env = PickEnv(grip=grip, per_finger=per_finger)
    policies = {"oracle": _Oracle(), "random": _random(seed),
                "full_curl": lambda t, obs, env: np.array([-1.0, 1.0])}  # squeezes hard: the squeeze term counts
    steps, info, forces = _check_against_reference(env, seed, policies[policy])
    if policy in ("oracle", "full_curl"):
        assert info["is_success"]  # the episode reached the end that matters: held at the target
        assert forces[0, 0] > 0 and forces[1, 0] > 0 and steps > 20
    if policy == "full_curl":
        assert info["reward_squeeze"] < -0.1 * env.w_squeeze
    env.close()


@pytest.mark.parametrize("n, K", [(2, 2), (3, 8), (12, 8), (40, 8), (5, 50)])
def test_finger_shape_is_the_interpolated_link_angle(n, K):
    """The observed tangent angles are np.interp of the link angles (cumulative hinge angles) at link
    midpoints, end values held beyond them (K > n samples fall outside the first and last midpoints)."""
    from simgrip.envs.pick_observation import PickObservation

    obs = PickObservation(n_links=n, shape_points=K, per_finger=True, kappa_range=(-10.0, 0.0), length=0.1,
                          target_height=0.06, hold_time=0.5, force_unit=0.4, palm_qpos=0, palm_dof=0, box_qpos=1,
                          box_dof=1, tips=(0, 1), hinge_qpos=slice(8, 8 + 2 * n))
    spread = PickObservation(n_links=n, shape_points=K, per_finger=True, kappa_range=(-10.0, 0.0), length=0.1,
                             target_height=0.06, hold_time=0.5, force_unit=0.4, palm_qpos=0, palm_dof=0, box_qpos=1,
                             box_dof=1, tips=(0, 1), hinge_qpos=np.arange(8, 8 + 4 * n, 2))  # not contiguous
    rng = np.random.default_rng(n)
    s_link, s_k = (np.arange(n) + 0.5) / n, (np.arange(K) + 0.5) / K
    for _ in range(20):
        q = rng.normal(size=8 + 4 * n)
        for f in (0, 1):
            ref = np.interp(s_k, s_link, np.cumsum(q[8 + f * n:8 + (f + 1) * n]))
            np.testing.assert_allclose(obs.finger_shape(q.tolist(), f), ref, rtol=0, atol=1e-13)
            ref = np.interp(s_k, s_link, np.cumsum(q[8 + 2 * f * n:8 + 2 * (f + 1) * n:2]))
            np.testing.assert_allclose(spread.finger_shape(q.tolist(), f), ref, rtol=0, atol=1e-13)


def test_contact_forces_read_from_constraint_rows_equal_mj_contact_force():
    """The elliptic-cone fast path (efc_force rows) and the general one (mj_contactForce) agree, with the
    fingers on the box."""
    from simgrip.envs.pick_contacts import BoxContactForces

    env = PickEnv()
    env.reset(seed=0)
    touched = 0
    for _ in range(40):
        env.step(np.array([-1.0, 0.5]))  # full curl, lift: both fingers on the box
        fast = env._contact_forces(env.model, env.data)
        general = BoxContactForces(env.model, env.box_geom, env.fingers.finger_of_geom)
        general._elliptic = False
        np.testing.assert_allclose(general(env.model, env.data), fast, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(fast, _reference_forces(env).ravel()[[0, 1, 3, 4, 2, 5]], rtol=1e-12,
                                   atol=1e-12)
        touched += fast[0] > 0 and fast[2] > 0
    assert touched > 20
    env.close()
