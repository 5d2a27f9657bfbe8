"""Env arguments (:mod:`simgrip.envs.arguments`): every constructor argument is checked by name;
pickled and deep-copied envs continue exactly like the original."""

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  (registers the ids)
from simgrip.envs import ENV_IDS
from simgrip.envs.pick import PickEnv


# -------------------------------------------------------- arguments (issue 12)
BAD_ARGUMENTS = {
    "n_links": [0, 2.5, "12", None, True],
    "length": [0, -0.1, float("nan"), float("inf"), "x", None],
    "EI": [0, float("nan")], "rho": [-1, float("inf")], "g": [0, float("nan")],
    "box_width_range": [(0.05, 0.01), (0.05, float("nan")), 0.05, (0.1, 0.3)],
    "box_mass_range": [(-0.01, 0.02), ("a", "b")], "friction_range": [(0, 1), None],
    "box_height": [0, float("nan"), 1.01], "box_depth": [-1, "deep", 1e9],  # 1e9: knocked over by step 1, unnamed
    "per_finger": ["yes", 1, None],
    "kappa_range": [(0, 0), (1, -1), (float("-inf"), 0)],
    "kappa_tau": [-0.1, float("nan"), "slow"],
    "palm_speed": [0, float("nan")], "palm_range": [(0.2, 0.1), (0, 0.2)], "palm_start": [(0.01, 0.02), (0.3, 0.4)],
    "target_height": [0, float("nan")], "hold_time": [-1, float("nan"), float("inf")],
    "w_lift": [-1, float("nan")], "w_success": [float("inf")], "w_squeeze": [-0.1, "x"], "w_drop": [float("nan")],
    "squeeze_margin": [0, float("nan")], "drop_distance": [0, float("inf")],
    # the upper bounds: 1e12 built and failed at the first reset in mj_step's argument parsing, without a name
    "timestep": [0, float("nan"), -0.002, 0.04, 1e12], "frame_skip": [0, 2.5, float("nan"), True, 501, 1e12],
    "settle_time": [float("nan"), -1, float("inf"), 10.5, 1e12],
    "finger_damping_time": [float("nan"), -0.01, float("inf")],
    # r_tip 1e-9 failed in MuJoCo's compiler ("mass and inertia of moving bodies"), not naming it
    "shape_points": [1, 3.5, float("nan"), 1001, 1e12], "r_tip": [0, float("nan"), 1e-9, 1.0], "spin_friction": [-1, float("nan")],
    "impratio": [0, float("nan")], "finger_armature": [-1, float("nan")],
    "width": [0, 10.5, float("nan"), 8193, 1e12], "height": [-1, "tall", 1e12], "camera": ["nope", 3, ""], "palm_ramp": ["yes", 1, None],
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


SHARED_ARGUMENTS = ("n_links", "length", "EI", "rho", "g", "r_tip", "kappa_range", "kappa_tau", "palm_speed",
                    "palm_range", "palm_start", "target_height", "hold_time", "w_lift", "w_success", "w_squeeze",
                    "w_drop", "squeeze_margin", "drop_distance", "timestep", "frame_skip", "settle_time",
                    "finger_damping_time", "shape_points", "spin_friction", "impratio", "finger_armature", "width",
                    "height", "camera")


@pytest.mark.parametrize("name", SHARED_ARGUMENTS)
def test_shared_arguments_are_refused_alike_by_both_pick_envs(name):
    """The arguments PickEnv and PickMultiEnv share are checked by one implementation (set_finger_arguments,
    set_task_arguments, check_camera): the same bad value, the same message."""
    from simgrip.envs.pick_multi import PickMultiEnv

    for value in BAD_ARGUMENTS[name]:
        with pytest.raises(ValueError, match=rf"\b{name}\b") as one:
            PickEnv(**{name: value})
        with pytest.raises(ValueError, match=rf"\b{name}\b") as other:
            PickMultiEnv(**{name: value})
        if name != "camera" or not isinstance(value, str) or value == "":  # a missing camera lists the model's
            assert str(one.value) == str(other.value)


# -------------------------------------------------------- reset's seed and options (issue 16, section 8)
@pytest.mark.parametrize("env_id", ["simgrip/Pick-v1", "simgrip/PickMulti-v0"])
def test_reset_takes_numpy_integer_seeds_as_the_same_seed(env_id):
    """The README says seeds are integers >= 0: NumPy's integers are (Gymnasium itself refuses np.int64)."""
    env = gym.make(env_id)
    try:
        a, _ = env.reset(seed=3)
        for seed in (np.int64(3), np.uint8(3), np.int32(3)):
            b, _ = env.reset(seed=seed)
            assert np.array_equal(a, b)
    finally:
        env.close()


@pytest.mark.parametrize("env_id", ["simgrip/Pick-v1", "simgrip/PickMulti-v0"])
@pytest.mark.parametrize("kwargs, name", [
    ({"seed": -1}, "seed"), ({"seed": 3.0}, "seed"), ({"seed": True}, "seed"), ({"seed": "3"}, "seed"),
    ({"options": "str"}, "options"), ({"options": ["box_width"]}, "options"), ({"options": 3}, "options"),
    ({"options": {"nonsense": 1}}, "unknown reset options"),
    # a palm height outside palm_range was clipped into it silently (1e12 m started the palm at 0.25 m)
    ({"options": {"palm_height": 1e12}}, "palm_height"), ({"options": {"palm_height": 0.01}}, "palm_height"),
    ({"options": {"palm_height": float("nan")}}, "palm_height"), ({"options": {"palm_height": True}}, "palm_height"),
])
def test_reset_refuses_bad_seeds_and_options_by_name(env_id, kwargs, name):
    """``reset(options='str')`` said "dictionary update sequence element #0"; now ValueError naming it."""
    env = gym.make(env_id)
    try:
        with pytest.raises(ValueError, match=rf"^{name}\b"):
            env.reset(**kwargs)
    finally:
        env.close()


@pytest.mark.parametrize("env_id", ["simgrip/Pick-v1", "simgrip/PickMulti-v0", "simgrip/PickSphereFragile-v6"])
def test_a_palm_height_within_palm_range_is_the_episodes(env_id):
    env = gym.make(env_id)
    try:
        lo, hi = env.unwrapped.palm_range
        for h in (lo, 0.5 * (lo + hi), hi):
            _, info = env.reset(seed=0, options={"palm_height": h})
            assert info["palm_height"] == h
        with pytest.raises(ValueError, match=r"palm_height must lie in .* \(palm_range\)"):
            env.reset(seed=0, options={"palm_height": hi * (1 + 1e-9)})
    finally:
        env.close()


@pytest.mark.parametrize("env_id", ["simgrip/PickMulti-v0", "simgrip/PickMultiFragile-v7",
                                    "simgrip/PickSphereFragile-v6"])
@pytest.mark.parametrize("kwargs, name", [
    ({"mass_range": (0.01, 1000.0)}, "mass_range"), ({"friction_range": (0.1, 1e12)}, "friction_range"),
    ({"offset_max": 1e12}, "offset_max"), ({"offset_max": 0.1}, "offset_max"),
])
def test_k_finger_draw_ranges_are_checked_at_construction(env_id, kwargs, name):
    """They were checked only on the draws: ``mass_range=(0.01, 1000)`` built and reset seeds 0-3, then seed 4
    raised "M must lie in [0, 10000]" without naming the range (a training run meets it hours in)."""
    with pytest.raises(ValueError, match=rf"^{name}\b"):
        gym.make(env_id, **kwargs)


@pytest.mark.parametrize("env_id", ["simgrip/Pick-v1", "simgrip/PickMulti-v0"])
def test_hold_time_zero_still_needs_the_lift(env_id):
    """``hold_time = 0`` (allowed: success on the first step at the target) is no success before the lift: it
    once declared success on the first step, the workpiece still on the table (``hold >= 0 - 1e-9``)."""
    env = gym.make(env_id, hold_time=0.0)
    env.reset(seed=3)
    _, _, terminated, _, info = env.step(np.zeros(env.action_space.shape, np.float32))
    lift = info["box_lift"] if "box_lift" in info else info["workpiece_lift"]
    assert not info["is_success"] and not terminated and lift < 0.01
    env.close()
