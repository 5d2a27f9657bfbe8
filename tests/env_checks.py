"""Checks several environment test modules make the same way (imported by them; not a test module)."""

import warnings

import gymnasium as gym
import numpy as np
import pytest


def make(env_id: str, **kwargs) -> gym.Env:
    """``gym.make`` of a registered id, or of a retired simgrip id through ``simgrip.envs.retired_spec`` (its
    class, keyword arguments and time limit as they were registered)."""
    from simgrip.envs import RETIRED, retired_spec

    return gym.make(retired_spec(env_id) if env_id in RETIRED else env_id, **kwargs)


def assert_sb3_check_env_clean(env_ids) -> None:
    """Stable-Baselines3's ``check_env`` passes every id (registered or retired) without a warning (skips without
    SB3)."""
    sb3_checker = pytest.importorskip("stable_baselines3.common.env_checker")
    for env_id in env_ids:
        env = make(env_id)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            sb3_checker.check_env(env.unwrapped)
        env.close()
        assert not [str(w.message) for w in caught]


def assert_headless_frame(env_id) -> None:
    """A 96 x 72 ``rgb_array`` frame of ``env_id`` after a reset is an image, not a blank (callers request the
    ``render_backend`` fixture, tests/conftest.py: it skips only where the machine has no GL library at all)."""
    env = make(env_id, render_mode="rgb_array", width=96, height=72)
    try:
        env.reset(seed=0)
        frame = env.render()
    finally:
        env.close()
    assert frame.shape == (72, 96, 3) and frame.dtype == np.uint8 and frame.std() > 0


def spoiled_controller(env, seed: int):
    """The fragile task's observation-only controller, spoiled by ``seed % 3``: 0 as it is, 1 its valve opened at
    full rate once the workpiece is 4 mm up (a drop), 2 its valve closed at full rate from step 5 (a crush).
    Returns ``(start(info), act(obs, t, info))``."""
    from simgrip.envs.baselines import policy_maker

    make_act = policy_maker(env, "observation")
    mode, state = seed % 3, {}

    def start(info):
        state["act"] = make_act(env, info, seed)

    def act(obs, t, info):
        a = np.array(state["act"](obs, t), dtype=np.float32)
        if mode == 1 and info.get("workpiece_lift", 0.0) > 0.004:
            a[0] = 1.0
        elif mode == 2 and t >= 5:
            a[0] = -1.0
        return a
    return start, act


def step_beside(new, old, a, same_keys) -> tuple:
    """One step of ``new`` and of ``old`` (its previous version) with the action ``a``: the same observation,
    flags and ``same_keys`` (those ``old``'s info has) asserted.  Returns ``(obs, r_new, r_old, done, i_new,
    i_old)``."""
    o_new, r_new, te_new, tr_new, i_new = new.step(a)
    o_old, r_old, te_old, tr_old, i_old = old.step(a)
    np.testing.assert_array_equal(o_new, o_old)
    assert (te_new, tr_new) == (te_old, tr_old)
    for k in same_keys:
        if k in i_old:
            assert np.array_equal(i_new[k], i_old[k]), k
    return o_new, r_new, r_old, te_new or tr_new, i_new, i_old


def assert_the_same_less_the_drop_penalty(new, old, seeds, steps: int, same_keys) -> tuple:
    """Step ``new`` (no drop penalty) beside ``old`` (its previous version) with :func:`spoiled_controller`'s
    actions over ``seeds``: the same observations, flags and ``same_keys``; ``new``'s ``reward_drop`` always 0
    and its reward ``old``'s less ``old``'s ``reward_drop``.  Returns ``(ends, drop_charged)``: the outcome
    counts (``simgrip.envs.outcome``) and how many steps ``old`` charged a drop."""
    from collections import Counter

    from simgrip.envs.outcome import outcome

    ends, drop_charged = Counter(), 0
    for seed in seeds:
        o_new, i_new = new.reset(seed=seed)
        o_old, i_old = old.reset(seed=seed)
        np.testing.assert_array_equal(o_new, o_old)
        start, act = spoiled_controller(new, seed)
        start(i_new)
        for t in range(steps):
            o_new, r_new, r_old, done, i_new, i_old = step_beside(new, old, act(o_new, t, i_new), same_keys)
            assert i_new["reward_drop"] == 0.0
            drop_charged += i_old["reward_drop"] < 0.0
            assert r_new == pytest.approx(r_old - i_old["reward_drop"], abs=1e-12)
            if done:
                break
        ends[outcome(i_new)] += 1
    return ends, drop_charged


def assert_step_for_step_equal(a, b, seeds, steps: int, rng_seed: int = 3) -> None:
    """``a`` and ``b`` stepped beside each other with the same uniform random actions from ``reset(seed)`` for
    each of ``seeds`` (at most ``steps`` steps each): the same observations, rewards and flags."""
    rng = np.random.default_rng(rng_seed)
    for seed in seeds:
        a.reset(seed=seed)
        b.reset(seed=seed)
        for _ in range(steps):
            act = rng.uniform(-1, 1, a.action_space.shape).astype(np.float32)
            oa, ra, ta, tra, _ = a.step(act)
            ob, rb, tb, trb, _ = b.step(act)
            np.testing.assert_array_equal(oa, ob)
            assert (ra, ta, tra) == (rb, tb, trb)
            if ta or tra:
                break


def spoiled_episode(env, seed: int, steps: int) -> tuple[float, dict]:
    """One episode of :func:`spoiled_controller` from ``reset(seed)``, at most ``steps`` steps: ``(its return, the
    last info)``."""
    obs, info = env.reset(seed=seed)
    start, act = spoiled_controller(env, seed)
    start(info)
    total = 0.0
    for t in range(steps):
        obs, r, term, trunc, info = env.step(act(obs, t, info))
        total += r
        if term or trunc:
            break
    return total, info


def spoiled_returns(env_id: str, seeds, steps: int) -> tuple[list[tuple[int, str, float]], dict, object]:
    """:func:`spoiled_episode` of ``env_id`` (registered or retired) for each of ``seeds``: ``(rows, ends, env)``
    with ``rows`` the ``(seed, outcome, return)`` of each episode, ``ends`` the outcome counts and ``env`` the
    (closed) env's unwrapped instance, whose reward weights the caller's ordering checks read."""
    from collections import Counter

    from simgrip.envs.outcome import outcome

    env = make(env_id)
    rows = []
    try:
        for seed in seeds:
            total, info = spoiled_episode(env, seed, steps)
            rows.append((seed, outcome(info), total))
    finally:
        env.close()
    return rows, Counter(end for _, end, _ in rows), env.unwrapped
