"""The env layer's per-step shortcuts (issue 18, item 5: env overhead over bare ``mj_step``) keep every value.

``tests/test_env_step_reference.py`` holds whole episodes to a recorded digest; these tests aim at the
shortcuts themselves, on inputs the recorded episodes may not reach:

* the K-finger observation's tip sums (``_tip_function``: ``_numpy_sum``'s additions written out) equal
  ``_numpy_sum`` to the last bit, the sign of zero included, for every link count it serves, the K fingers' one
  call (``_tips_function``) equals each finger's, and the two-finger observation's compiled shape samples
  (``_shape_function``) equal the running sum and weights they replace;
* both observations' comparison-only clipping (taken when every entry lies inside its bound) gives the bytes
  of the full per-entry clipping, on the envs' own states and on states pushed outside the bounds;
* the action is checked once per step however many layers an env has (by ``CheckedStep.step`` itself for a float
  array of the right shape inside ``[-1, 1]``, else by one ``check_action`` call), and the checks still raise as
  before;
* a pickled K-finger env (its observation holds a compiled function and a view of the data) continues exactly.
"""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest
from gymnasium.error import ResetNeeded

from simgrip.envs import pick_step, valve
from simgrip.envs.pick import PickEnv
from simgrip.envs.pick_fragile_v2 import FragilePickEnvV2, FragilePickMultiEnvV2, FragilePlaceEnvV2
from simgrip.envs.pick_multi import PickMultiEnv
from simgrip.envs.pick_multi_observation import _numpy_sum, _tip_function, _tips_function


def _bits(values) -> list[str]:
    return [float(x).hex() for x in values]  # exact, and tells 0.0 from -0.0


def test_tip_sums_equal_numpy_sum_to_the_bit():
    rng = np.random.default_rng(5)
    for n in range(4, 65):
        tip = _tip_function(n)
        for trial in range(40):
            scale = (1e-9, 1e-3, 1.0, 30.0)[trial % 4]
            c = (rng.normal(0.0, scale, n)).tolist()
            if trial % 5 == 0:  # exact quarter turns: cosines of -0.0 / 0.0 and sums that cancel
                c = [rng.choice((0.0, -0.0, 0.5 * math.pi, -0.5 * math.pi, math.pi)) for _ in range(n)]
            ds = float(rng.uniform(0.01, 1.0))
            want = [_numpy_sum([math.cos(t) for t in c]) * ds, _numpy_sum([math.sin(t) for t in c]) * ds]
            assert _bits(tip(c, ds)) == _bits(want), (n, c)
    for bad in (3, 65):
        with pytest.raises(ValueError, match="n must lie in"):
            _tip_function(bad)


def test_tips_of_all_fingers_equal_each_fingers_tip_to_the_bit():
    """``_tips_function`` (one compiled call for the K fingers of a step) gives the shape rows flattened, then each
    row's ``_tip_function`` result, in order, to the last bit (the sign of zero included)."""
    rng = np.random.default_rng(6)
    for n in (4, 5, 12, 13, 64):
        tip = _tip_function(n)
        for K in (1, 2, 3, 5):
            tips = _tips_function(n, K)
            for trial in range(20):
                rows = rng.normal(0.0, (1e-9, 1.0, 30.0)[trial % 3], (K, n)).tolist()
                if trial % 4 == 0:
                    rows = [[rng.choice((0.0, -0.0, 0.5 * math.pi, math.pi)) for _ in range(n)] for _ in range(K)]
                shapes = rng.normal(0.0, 1.0, (K, 1 + trial % 4)).tolist()
                want = [x for s in shapes for x in s] + [x for c in rows for x in tip(c, 0.25)]
                assert _bits(tips(shapes, rows, 0.25)) == _bits(want), (n, K)
    with pytest.raises(ValueError, match="n must lie in"):
        _tips_function(3, 2)
    with pytest.raises(ValueError, match="fingers"):
        _tips_function(12, 0)


@pytest.mark.parametrize("n_links, shape_points", [(12, 8), (5, 3), (20, 7), (2, 2)])
def test_shape_samples_equal_the_running_sum_and_weights_to_the_bit(n_links, shape_points):
    """The compiled finger shape (``_shape_function``) against ``itertools.accumulate`` and the weighted sums it
    replaced, for both fingers, contiguous (a slice) and scattered (a list) hinge addresses."""
    from itertools import accumulate

    from simgrip.envs.pick_observation import PickObservation

    rng = np.random.default_rng(n_links)
    size = 2 * n_links + 30
    scattered = rng.permutation(np.arange(3, size))[:2 * n_links]
    for hinges in ((slice(7, 7 + 2 * n_links),), scattered):
        obs = PickObservation(n_links=n_links, shape_points=shape_points, per_finger=True, kappa_range=(-10.0, 0.0),
                              length=0.1, target_height=0.06, hold_time=0.5, force_unit=0.4, palm_qpos=0,
                              palm_dof=0, box_qpos=0, box_dof=0, tips=(0, 1), hinge_qpos=hinges)
        for trial in range(50):
            q = (rng.normal(0.0, (1e-6, 0.3, 3.0)[trial % 3], size)).tolist()
            for f in (0, 1):
                h = obs._hinges[f]
                c = list(accumulate(q[h] if type(h) is slice else [q[j] for j in h]))
                want = [wa * c[i] + wb * c[i + 1] for i, wa, wb in obs._lerp]
                assert _bits(obs.finger_shape(q, f)) == _bits(want)
        copy = pickle.loads(pickle.dumps(obs))  # the compiled functions are made again
        assert _bits(copy.finger_shape(q, 1)) == _bits(obs.finger_shape(q, 1))


def _pick_inputs(env):
    """PickObservation.observe's arguments for the env's current state (what its step passes)."""
    d = env.data
    (k0, k1), (c0, c1) = env._kcmd, env._kact
    forces = env._contact_forces(env.model, d)
    return [d.qpos.tolist(), d.qvel.tolist(), env._tips[0], env._tips[1], k0, k1, c0, c1, forces, env._z0, env._hold]


def _multi_inputs(env):
    """MultiObservation.observe's arguments for the env's current state."""
    d = env.data
    return [d.qpos, d.qpos.tolist(), d.qvel.tolist(), list(env._kcmd), list(env._kact), env._forces(d), env._z0,
            env._hold]


def _both_ways(obs_maker, args) -> tuple[bytes, bytes]:
    fast = obs_maker.observe(*args)
    obs_maker._fast_clip = False
    try:
        full = obs_maker.observe(*args)
    finally:
        del obs_maker._fast_clip  # back to the class's True
    assert np.all(fast >= obs_maker.low) and np.all(fast <= obs_maker.high)
    return fast.tobytes(), full.tobytes()


def _pushed_pick(args, k: int):
    """The arguments with one group of entries pushed outside (or onto) its bound."""
    q, v, tip0, tip1, k0, k1, c0, c1, forces, z0, hold = args
    q, v, forces = list(q), list(v), list(forces)
    if k == 0:
        forces = [f * 1e12 + 1e12 for f in forces]  # log(1 + F/W) beyond 20
    elif k == 1:
        q = [x + 40.0 for x in q]  # the palm beyond 10 l, the hinges' shape beyond +-20 rad
    elif k == 2:
        v = [x - 1e4 for x in v]  # the box's velocity beyond -100 l/s
    else:
        tip0 = np.asarray(tip0) + 1.0  # the tip 10 l out (beyond 5)
    return [q, v, tip0, tip1, k0, k1, c0, c1, forces, z0, hold]


@pytest.mark.parametrize("make", [lambda: PickEnv(), lambda: FragilePickEnvV2()], ids=["pick", "fragile-v2"])
def test_two_finger_observation_clips_as_the_full_clip(make):
    env = make()
    rng = np.random.default_rng(7)
    obs, _ = env.reset(seed=3)
    checked = 0
    for t in range(120):
        obs, _, term, _, _ = env.step(rng.uniform(-1.0, 1.0, env.action_space.shape).astype(np.float32))
        args = _pick_inputs(env)
        fast, full = _both_ways(env._observe, args)
        assert fast == full == obs.tobytes(), t  # (the env's own observation: the inputs are the step's)
        fast, full = _both_ways(env._observe, _pushed_pick(args, t % 4))
        assert fast == full, t
        checked += 1
        if term:
            env.reset(seed=3 + t)
    assert checked == 120
    env.close()


@pytest.mark.parametrize("make", [lambda: PickMultiEnv(fingers=3), lambda: FragilePickMultiEnvV2()],
                         ids=["multi", "multi-fragile-v2"])
def test_multi_observation_clips_as_the_full_clip(make):
    env = make()
    rng = np.random.default_rng(8)
    env.reset(seed=4)
    for t in range(120):
        obs, _, term, _, _ = env.step(rng.uniform(-1.0, 1.0, env.action_space.shape).astype(np.float32))
        args = _multi_inputs(env)
        fast, full = _both_ways(env._observe, args)
        assert fast == full == obs.tobytes(), t
        qpos, q, v, kc, ka, (normal, friction, side), z0, hold = args
        k = t % 4
        if k == 0:
            pushed = [qpos, q, v, kc, ka, ([f * 1e12 + 1e12 for f in normal], friction, side), z0, hold]
        elif k == 1:
            qp = np.array(qpos) + 40.0  # a new array: the hinge view is bound again
            pushed = [qp, qp.tolist(), v, kc, ka, (normal, friction, side), z0, hold]
        elif k == 2:
            pushed = [qpos, q, [x - 1e4 for x in v], kc, ka, (normal, friction, side), z0, hold]
        else:  # a non-unit quaternion: a tilt entry of 4.5, beyond its bound 1 but inside the others' 5
            qp = np.array(qpos)
            wq = env.work_qpos
            qp[wq + 3:wq + 7] = (1.5, 0.0, 1.5, 0.0)
            pushed = [qp, qp.tolist(), v, kc, ka, (normal, friction, side), z0, hold]
        fast, full = _both_ways(env._observe, pushed)
        assert fast == full, t
        if term:
            env.reset(seed=4 + t)
    env.close()


@pytest.mark.parametrize("cls", [FragilePickEnvV2, FragilePickMultiEnvV2, FragilePlaceEnvV2, PickEnv, PickMultiEnv])
def test_the_action_is_checked_once_per_step(cls, monkeypatch):
    calls = []
    for module in (pick_step, valve):
        if not hasattr(module, "check_action"):  # (the valve is a layer of the checked chain: it checks nothing)
            continue
        orig = module.check_action

        def counted(action, shape, _orig=orig):
            calls.append(shape)
            return _orig(action, shape)
        monkeypatch.setattr(module, "check_action", counted)
    env = cls()
    with pytest.raises(ResetNeeded):
        env.step(np.zeros(env.action_space.shape, np.float32))
    env.reset(seed=1)
    calls.clear()
    rng = np.random.default_rng(2)
    steps = inside = 0
    for _ in range(15):
        a = rng.uniform(-1.2, 1.2, env.action_space.shape).astype(np.float32)
        a[0] = 1.1 if steps % 3 else 0.5  # some actions entirely inside [-1, 1], most not
        inside += bool(np.all(np.abs(a) <= 1.0))
        _, _, term, _, _ = env.step(a)
        steps += 1
        if term:
            break
    # an action of the right shape and dtype entirely inside [-1, 1] is checked by CheckedStep.step itself (what
    # check_action would return is its list unchanged); every other one by one check_action call
    assert inside and len(calls) == steps - inside
    with pytest.raises(ValueError, match="finite"):
        env.step(np.full(env.action_space.shape, np.nan, np.float32))
    with pytest.raises(ValueError, match="shape"):
        env.step(np.zeros(env.action_space.shape[0] + 1, np.float32))
    env.close()


def test_pickled_multi_env_continues_exactly():
    env = FragilePickMultiEnvV2()
    env.reset(seed=11)
    rng = np.random.default_rng(11)
    actions = rng.uniform(-0.3, 0.3, (40, env.action_space.shape[0])).astype(np.float32)
    for a in actions[:10]:
        env.step(a)
    copy = pickle.loads(pickle.dumps(env))
    for a in actions[10:]:
        o1, r1, t1, _, _ = env.step(a)
        o2, r2, t2, _, _ = copy.step(a)
        assert o1.tobytes() == o2.tobytes() and r1 == r2 and t1 == t2
        if t1:
            break
    env.close()
    copy.close()
