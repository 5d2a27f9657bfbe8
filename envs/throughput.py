"""Throughput of the pick environment against raw ``mj_step`` (for ``simgrip bench``).

``measure_throughput`` steps the environment with random actions in chunks of
``chunk`` control steps (resets excluded from the timing).  After each chunk it
rewinds the simulation to the chunk's start (``mj_getState`` /
``mj_setState``) and integrates exactly the same physics again with bare
:func:`mujoco.mj_step` calls, writing the rest angles and the palm servo target
(all of ``data.ctrl``) that ``step`` wrote: once with one ``mj_step`` call per physics step and once
with ``mj_step(..., nstep=frame_skip)`` (what the environment uses), and once
through :func:`~simgrip.envs.step_floor.floor_step`, the least a Python step
of the environment's interface does (writes, ``mj_step``, the state read back,
an observation array and an ``info`` of the environment's keys).  All
timings therefore cover the same states, contacts included, for the same
number of physics steps; ``replay_max_abs_diff`` checks it (the largest
difference between a replay's end state and the environment's, over every
chunk and the three replays: 0 when the replay is faithful).

The overhead is the environment's extra time (action checks, curvature lag,
contact forces, observation, reward) over the raw stepping.  Both sides are timed
per control step alike: each ``env.step`` call alone, each control step's
``mj_step`` calls alone; the harness's own work (the replay's log of rest angles
and controls, its writes of them before the replay's steps) is outside both
timings.  On a shared
machine the load changes while it runs, so the overhead is the median over
chunks of each chunk's ratio (the environment and its raw replay run within
milliseconds of each other and see the same load); the rates are the best
repeat's totals.
"""

from __future__ import annotations

import time

import mujoco
import numpy as np

from simgrip.envs.step_floor import floor_step

__all__ = ["measure_throughput", "violation_check_times"]


def measure_throughput(steps: int = 2000, *, grip: str = "I", seed: int = 0, repeats: int = 3,
                       chunk: int = 50, env_kwargs=None, clock: str = "wall", env_id: str | None = None) -> dict:
    """Env steps per second, raw physics steps per second and the env's overhead.

    Parameters
    ----------
    steps : int
        Control steps per repeat (each ``frame_skip`` physics steps).
    grip, env_kwargs
        The environment (:class:`~simgrip.envs.pick.PickEnv` arguments).
    env_id : str, optional
        A registered id (``"simgrip/PickFragile-v7"``, ``"simgrip/PickMulti-v0"``: any
        :class:`~simgrip.envs.pick.PickEnv` or :class:`~simgrip.envs.pick_multi.PickMultiEnv`), or a retired one
        made as it was registered, measured instead, made with ``env_kwargs`` (``grip`` is then not used).
    seed : int
        Seeds the random actions and the episodes.
    repeats : int
        Repeats; the rates are the best repeat's.
    chunk : int
        Control steps between switches from the environment to the raw replay.
    clock : {"wall", "cpu"}
        Time with the wall clock (``time.perf_counter``) or this thread's CPU
        time (``time.thread_time``: blind to other processes' load, rates per
        CPU second).

    Returns
    -------
    dict
        ``env_steps_per_s``, ``env_physics_steps_per_s``,
        ``raw_physics_steps_per_s`` (one ``mj_step`` call per physics step),
        ``raw_nstep_physics_steps_per_s`` (``nstep=frame_skip``),
        ``overhead_percent`` (env against the one-call-per-step loop, median of
        the chunks' ratios), ``overhead_vs_nstep_percent``,
        ``floor_overhead_percent`` (the interface's least Python step,
        :mod:`simgrip.envs.step_floor`, against the same loop, the same
        median: the part of ``overhead_percent`` no task code can remove),
        ``frame_skip``, ``timestep``, ``steps``, ``chunks``, ``clock``,
        ``replay_max_abs_diff`` (module docstring).
    """
    from simgrip.envs.pick import PickEnv
    from simgrip.envs.pick_multi import PickMultiEnv

    steps, chunk = int(steps), int(chunk)
    if steps < 1:
        raise ValueError(f"steps must be a positive integer, got {steps!r}")
    if chunk < 1:
        raise ValueError(f"chunk must be a positive integer, got {chunk!r}")
    if int(repeats) < 1:
        raise ValueError(f"repeats must be a positive integer, got {repeats!r}")
    timers = {"wall": time.perf_counter, "cpu": time.thread_time}
    if clock not in timers:
        raise ValueError(f"clock must be 'wall' or 'cpu', got {clock!r}")
    if env_id is None:
        env = PickEnv(grip=grip, **dict(env_kwargs or {}))
    else:
        import gymnasium as gym

        import simgrip.envs  # noqa: F401  (registers the ids)

        env = gym.make(_spec(env_id), **dict(env_kwargs or {})).unwrapped
        if not isinstance(env, (PickEnv, PickMultiEnv)):
            env.close()
            raise ValueError(f"env_id must name a pick env (PickEnv or PickMultiEnv), got {env_id!r}")
    try:
        best, ratios, diff = _measure(env, steps, seed, int(repeats), chunk, timers[clock])
    finally:
        env.close()
    fs = env.frame_skip
    n_phys = steps * fs
    return {
        "steps": steps,
        "frame_skip": fs,
        "timestep": env.timestep,
        "chunks": len(ratios["single"]),
        "clock": clock,
        "env_steps_per_s": steps / best["env"],
        "env_physics_steps_per_s": n_phys / best["env"],
        "raw_physics_steps_per_s": n_phys / best["single"],
        "raw_nstep_physics_steps_per_s": n_phys / best["nstep"],
        "overhead_percent": 100.0 * (float(np.median(ratios["single"])) - 1.0),
        "overhead_vs_nstep_percent": 100.0 * (float(np.median(ratios["nstep"])) - 1.0),
        "floor_overhead_percent": 100.0 * (float(np.median(ratios["floor"])) - 1.0),
        "replay_max_abs_diff": diff,
    }


def _measure(env, steps: int, seed: int, repeats: int, chunk: int, timer) -> tuple[dict, dict, float]:
    """Best total seconds per mode over the repeats, every chunk's env / raw time ratio per raw mode, and the
    replays' largest deviation from the environment's end state."""
    fs = env.frame_skip
    idx = env.joint_qpos.ravel()  # the finger hinges' rest angles live at these qpos_spring entries
    kind = mujoco.mjtState.mjSTATE_INTEGRATION
    log_spring = np.empty((chunk, idx.size))
    if np.array_equal(idx, np.arange(idx[0], idx[0] + idx.size)):
        idx = slice(int(idx[0]), int(idx[0]) + idx.size)  # the builder makes them contiguous: a slice copies less
    best = {"env": np.inf, "single": np.inf, "nstep": np.inf, "floor": np.inf}
    ratios = {"single": [], "nstep": [], "floor": []}
    obs_size = env.observation_space.shape[0]
    diff = 0.0
    for r in range(repeats):
        rng = np.random.default_rng(seed + r)
        actions = rng.uniform(-1, 1, size=(steps, env.action_space.shape[0])).astype(np.float32)
        m, d, spring, start, end, log_ctrl, ctrl = _bind(env, kind, chunk, seed + 1000 * r)
        total = {"env": 0.0, "single": 0.0, "nstep": 0.0, "floor": 0.0}
        i = 0
        while i < steps:
            mujoco.mj_getState(m, d, start, kind)
            spring0 = spring[idx].copy()
            n, done, t_env = 0, False, 0.0
            while n < chunk and i + n < steps and not done:
                a = actions[i + n]
                t0 = timer()  # each step timed alone, as the replay times each control step's physics
                _, _, term, trunc, info = env.step(a)
                t_env += timer() - t0
                log_spring[n] = spring[idx]  # the replay's log, outside the timing as the replay's writes are
                log_ctrl[n] = ctrl
                n += 1
                done = term or trunc
            total["env"] += t_env
            mujoco.mj_getState(m, d, end, kind)
            floor = floor_step(m, d, frame_skip=fs, obs_size=obs_size, info=info, spring_index=idx)
            elapsed = {}
            for mode in ("single", "nstep", "floor"):
                mujoco.mj_setState(m, d, start, kind)
                spring[idx] = spring0
                t = 0.0
                for k in range(n):
                    if mode == "floor":  # the floor's step writes them itself, as the environment's does
                        row_spring, row_ctrl = log_spring[k], log_ctrl[k]
                        t0 = timer()
                        floor(row_spring, row_ctrl)
                        t += timer() - t0
                        continue
                    spring[idx] = log_spring[k]
                    ctrl[:] = log_ctrl[k]
                    t0 = timer()
                    if mode == "single":
                        for _ in range(fs):
                            mujoco.mj_step(m, d)
                    else:
                        mujoco.mj_step(m, d, nstep=fs)
                    t += timer() - t0
                total[mode] += t
                elapsed[mode] = t
                replayed = np.empty_like(end)
                mujoco.mj_getState(m, d, replayed, kind)
                diff = max(diff, float(np.max(np.abs(replayed - end))))
            for mode in ("single", "nstep"):
                ratios[mode].append(t_env / elapsed[mode])
            ratios["floor"].append(elapsed["floor"] / elapsed["single"])
            mujoco.mj_setState(m, d, end, kind)
            spring[idx] = log_spring[n - 1]
            i += n
            if done:  # PickMulti: another shape is another model
                m, d, spring, start, end, log_ctrl, ctrl = _bind(env, kind, chunk, seed + 1000 * r + i)
        for key in best:
            best[key] = min(best[key], total[key])
    return best, ratios, diff


def _spec(env_id):
    """What ``gym.make`` makes ``env_id`` from: a registered id itself, a retired one's
    :func:`~simgrip.envs.retired_spec` (the speed page's figures name the ids registered when they were measured);
    ValueError naming ``env_id`` otherwise."""
    import gymnasium as gym

    from simgrip.envs import RETIRED, make_spec

    if not isinstance(env_id, str) or (env_id not in gym.registry and env_id not in RETIRED):
        raise ValueError(f"env_id must be a registered or retired id, got {env_id!r}")
    return make_spec(env_id)


def _bind(env, kind, chunk: int, seed: int) -> tuple:
    """Reset ``env`` with ``seed`` and bind what the loop reads: the (new) model and data, the rest angles'
    view, state buffers and the control log (``PickMultiEnv`` holds one model per workpiece shape)."""
    env.reset(seed=seed)
    m, d = env.model, env.data
    size = mujoco.mj_stateSize(m, kind)
    return m, d, m.qpos_spring, np.empty(size), np.empty(size), np.empty((chunk, m.nu)), d.ctrl


def violation_check_times(env_id: str, *, steps: int = 4000, seed: int = 0, repeats: int = 7) -> dict:
    """What a validity check costs in the states that reach :func:`~simgrip.validity.chain_violations`, both ways.

    Steps the pick env ``env_id`` (registered, or retired: made as it was registered) with uniform random actions (``numpy.random.default_rng(seed)``,
    episodes reset with seeds ``seed, seed + 1, ...``), keeps the fingers' nodes at every checked step whose state is
    invalid (``info["valid"]`` False: the check went to ``chain_violations``), then times the env's own
    ``_violations`` on them with ``batch=True`` (every pair of links at once, :mod:`simgrip.link_pairs`) and
    ``batch=False`` (pruned, a finger and a pair of fingers at a time): the least of ``repeats`` passes over all of
    them, each way, interleaved.  Returns ``states``, ``checks``, ``steps``, ``batched_us`` and ``pruned_us`` (per
    state; None where no state was invalid) and ``same`` (both ways gave the same messages on every state).
    """
    import gymnasium as gym

    import simgrip.envs  # noqa: F401  (registers the ids)

    spec = _spec(env_id)
    for name, value in (("steps", steps), ("repeats", repeats)):
        if int(value) < 1:
            raise ValueError(f"{name} must be a positive integer, got {value!r}")
    env = gym.make(spec).unwrapped
    try:
        probe = env._validity
        rng = np.random.default_rng(seed)
        env.reset(seed=seed)
        episode, states, checks = seed, [], 0
        for _ in range(int(steps)):
            _, _, term, trunc, info = env.step(rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
            checks += probe.checked
            if probe.checked and not info["valid"]:
                states.append(probe._world(env.data))
            if term or trunc:
                episode += 1
                env.reset(seed=episode)
        best, found = {True: np.inf, False: np.inf}, {}
        for _ in range(int(repeats)):
            for batch in (True, False):
                t0 = time.perf_counter()
                messages = [probe._violations(W, batch=batch) for W in states]
                best[batch] = min(best[batch], time.perf_counter() - t0)
                found[batch] = messages  # (the same every pass: the last one's are compared)
    finally:
        env.close()
    k = len(states)
    return {"steps": int(steps), "checks": checks, "states": k, "batched_us": 1e6 * best[True] / k if k else None,
            "pruned_us": 1e6 * best[False] / k if k else None, "same": found[True] == found[False]}
