"""The observations' second comparison-only case (curled fingers, issue 18 item 5) clips as the full clip.

``MultiObservation.observe`` (and ``PickObservation.observe``, the two-finger one, alike) returns its entries unclipped when every entry is inside its bound: first with every
shape, tip and workpiece entry within +-5 (the usual state), then, for a claw curled past 5 rad (the sphere task:
a third of its steps), with the shape samples against their own bound (+-20 rad by default) and the rest as
before.  Here, on states of that second kind (hinges curled so the samples reach beyond -5 rad, within -20) and
on the same states pushed outside a bound (a tilt beyond 1, a velocity beyond 100, shapes beyond -20), the result
equals the per-entry clip of every entry (``_fast_clip = False``) to the bit, and on the env's own rollouts of the
sphere task and of the cradle (two fingers, a sixth of its random steps curled past 5 rad) too.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from simgrip.envs.pick_multi import PickMultiEnv

sys.path.insert(0, str(Path(__file__).parent))
from test_env_hot_path import _both_ways  # noqa: E402  (observe with and without the comparison-only case)


@pytest.mark.parametrize("fingers", [3, 4])
def test_curled_fingers_clip_as_the_full_clip(fingers):
    env = PickMultiEnv(fingers=fingers)
    env.reset(seed=5)
    rng = np.random.default_rng(9)
    d, ob = env.data, env._observe
    joints = env.joint_qpos.ravel()
    shape = env.obs_slices["finger_shape"]
    lo, hi = float(ob.low[shape][0]), float(ob.high[shape][0])
    second = 0
    for t in range(60):
        qp = np.array(d.qpos)
        curl = rng.uniform(5.5, 0.9 * -lo)  # total turning [rad]: samples beyond -5, inside the bound
        qp[joints] = -curl / env.n + rng.normal(0.0, 0.02, joints.size)
        forces = env._forces(d)
        args = [qp, qp.tolist(), d.qvel.tolist(), list(env._kcmd), list(env._kact), forces, env._z0, env._hold]
        fast, full = _both_ways(ob, args)
        assert fast == full, t
        o = np.frombuffer(fast)
        samples = o[shape]
        if samples.min() < -5.0 and samples.min() >= lo and samples.max() <= hi:
            second += 1  # the second case's state: the first test fails on the samples alone
        # pushed outside a bound: the tilt (a non-unit quaternion), the velocity, the shapes beyond the bound
        k = t % 3
        pushed = np.array(qp)
        v = d.qvel.tolist()
        if k == 0:
            wq = env.work_qpos
            pushed[wq + 3:wq + 7] = (1.5, 0.0, 1.5, 0.0)
        elif k == 1:
            v = [x - 1e4 for x in v]
        else:
            pushed[joints] = pushed[joints] * 4.0  # beyond -20 rad
        args = [pushed, pushed.tolist(), v, list(env._kcmd), list(env._kact), forces, env._z0, env._hold]
        fast, full = _both_ways(ob, args)
        assert fast == full, (t, k)
    assert second == 60
    env.close()


def test_sphere_task_rollout_clips_as_the_full_clip():
    import gymnasium as gym

    import simgrip.envs  # noqa: F401  (registers the ids)

    env = gym.make("simgrip/PickSphereFragile-v6").unwrapped
    rng = np.random.default_rng(3)
    env.reset(seed=7)
    curled = 0
    for t in range(200):
        a = rng.uniform(-1.0, 1.0, env.action_space.shape)
        a[0] = rng.uniform(-1.0, 0.2)  # the valve's rate, mostly curling: the claw curls past 5 rad
        obs, _, term, trunc, _ = env.step(a.astype(np.float32))
        d = env.data
        args = [d.qpos, d.qpos.tolist(), d.qvel.tolist(), list(env._kcmd), list(env._kact), env._forces(d), env._z0,
                env._hold]
        fast, full = _both_ways(env._observe, args)
        assert fast == full == obs.tobytes(), t
        curled += bool(obs[env.obs_slices["finger_shape"]].min() < -5.0)
        if term or trunc:
            env.reset(seed=7 + t)
    assert curled > 20  # the second case occurred (else this proves nothing about it)
    env.close()


def _pick_inputs(env, q=None, v=None):
    """PickObservation.observe's arguments for the env's current state (what its step passes)."""
    d = env.data
    (k0, k1), (c0, c1) = env._kcmd, env._kact
    forces = env._contact_forces(env.model, d)
    q = d.qpos.tolist() if q is None else q
    v = d.qvel.tolist() if v is None else v
    return [q, v, env._tips[0], env._tips[1], k0, k1, c0, c1, forces, env._z0, env._hold]


def test_cradle_rollout_clips_as_the_full_clip():
    import gymnasium as gym

    import simgrip.envs  # noqa: F401  (registers the ids)

    env = gym.make("simgrip/PickCradleFragile-v6").unwrapped
    rng = np.random.default_rng(0)
    env.reset(seed=0)
    shape = env.obs_slices["finger_shape"]
    hinges = env.joint_qpos[0]
    curled = 0
    for t in range(300):
        a = rng.uniform(-1.0, 1.0, env.action_space.shape)
        a[0] = rng.uniform(-1.0, 0.2)  # the valve's rate, mostly curling
        obs, _, term, trunc, _ = env.step(a.astype(np.float32))
        args = _pick_inputs(env)
        fast, full = _both_ways(env._observe, args)
        assert fast == full == obs.tobytes(), t
        if obs[shape].min() < -5.0:
            curled += 1
            # the same state pushed outside a bound: the shapes beyond -20 rad, the box's velocity beyond 100 l/s
            q = list(args[0])
            for a in hinges:
                q[a] *= 6.0
            fast, full = _both_ways(env._observe, _pick_inputs(env, q=q))
            assert fast == full, t
            fast, full = _both_ways(env._observe, _pick_inputs(env, v=[x - 1e4 for x in args[1]]))
            assert fast == full, t
        if term or trunc:
            env.reset(seed=t)
    assert curled > 20, curled  # the second case occurred (else this proves nothing about it)
    env.close()
