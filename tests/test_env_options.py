"""The options that shape a training or evaluation env (simgrip.envs.env_options)."""

from __future__ import annotations

import argparse

import pytest

pytest.importorskip("gymnasium")

import simgrip.envs  # noqa: E402,F401  (registers the ids)
from simgrip.envs.env_options import EnvOptions, check_training_env, make_env  # noqa: E402

MULTI = "simgrip/PickMultiFragile-v7"
EVERY_AID = EnvOptions(env_kwargs={"w_touch": 0.0}, action_offset=(-0.2, 0.2), frame_stack=2, light_bias=0.5,
                       crush_charge=(10.0, 4096), step_charge=0.005, crush_margin=0.2)


def _args(**given) -> argparse.Namespace:
    names = ("env", "env_kwargs", "action_offset", "frame_stack", "residual", "scripted_start", "light_bias",
             "crush_charge", "crush_charge_from", "step_charge", "crush_margin")
    return argparse.Namespace(**{name: given.get(name) for name in names})


def test_from_args_reads_every_option_and_pairs_the_charge_with_its_start():
    args = _args(env=MULTI, env_kwargs={"w_touch": 0.0}, action_offset=[-0.2, 0.2], frame_stack=2,
                 light_bias=0.5, crush_charge=10.0, crush_charge_from=4096, step_charge=0.005, crush_margin=0.2)
    assert EnvOptions.from_args(args) == EVERY_AID
    assert EnvOptions.from_args(_args(crush_charge=3.0)).crush_charge == (3.0, 0)  # from the first step
    plain = EnvOptions.from_args(_args(env=MULTI))
    assert plain == EnvOptions() and not plain.shaped()
    assert EnvOptions.from_args(_args(residual=["palm_z"])).residual == ("palm_z",)
    # a script without an option (evaluate_policy.py has no --light-bias) reads it as None
    assert EnvOptions.from_args(argparse.Namespace(action_offset=[0.1, 0.0])) == EnvOptions(action_offset=(0.1, 0.0))


def test_evaluation_keeps_the_policys_wrappers_and_drops_the_training_aids():
    ev = EVERY_AID.evaluation()
    assert ev == EnvOptions(env_kwargs={"w_touch": 0.0}, action_offset=(-0.2, 0.2), frame_stack=2)
    assert EnvOptions(residual=("palm_z",), scripted_start=0.5).evaluation() == EnvOptions(residual=("palm_z",))
    for name in ("action_offset", "frame_stack", "residual", "scripted_start", "light_bias", "crush_charge",
                 "step_charge", "crush_margin"):
        assert EnvOptions(**{name: (1,) if name in ("action_offset", "residual", "crush_charge") else 1}).shaped()


def test_record_names_each_option_set_and_its_wrapper_in_the_json_order():
    keys, wrappers = EVERY_AID.record()
    assert keys == {"env_kwargs": {"w_touch": 0.0}, "action_offset": [-0.2, 0.2], "frame_stack": 2,
                    "light_bias": 0.5, "crush_charge": {"charge": 10.0, "start": 4096}, "step_charge": 0.005,
                    "crush_margin": 0.2}
    assert wrappers == ["ActionOffset([-0.2, 0.2])", "FrameStackObservation(2)", "LightBias(0.5) in training",
                        "CrushCharge(10.0, from step 4096) in training", "StepCharge(0.005) in training",
                        "CrushMargin(0.2) in training"]
    keys, wrappers = EnvOptions(residual=("palm_x", "palm_z"), scripted_start=None, frame_stack=1).record()
    assert keys == {"residual": ["palm_x", "palm_z"]} and wrappers == ["ScriptedResidual(['palm_x', 'palm_z'])"]
    assert EnvOptions().record() == ({}, [])


def test_make_env_wraps_in_the_documented_order_innermost_first():
    from gymnasium.wrappers import FrameStackObservation

    from simgrip.envs.action_offset import ActionOffset
    from simgrip.envs.crush_charge import CrushCharge
    from simgrip.envs.crush_margin import CrushMargin
    from simgrip.envs.light_bias import LightBias
    from simgrip.envs.step_charge import StepCharge

    env = make_env(MULTI, EVERY_AID)
    try:
        chain, e = [], env
        while e is not e.unwrapped:
            chain.append(type(e))
            e = e.env
        ours = [c for c in chain if c in (FrameStackObservation, ActionOffset, CrushMargin, StepCharge, CrushCharge,
                                          LightBias)]
        assert ours == [FrameStackObservation, ActionOffset, CrushMargin, StepCharge, CrushCharge, LightBias]
        assert env.unwrapped.w_touch == 0.0
    finally:
        env.close()
    plain = make_env(MULTI, EVERY_AID.evaluation())
    try:
        assert not any(isinstance(w, (LightBias, StepCharge, CrushCharge, CrushMargin)) for w in _layers(plain))
    finally:
        plain.close()


def _layers(env):
    while env is not env.unwrapped:
        yield env
        env = env.env


def test_check_training_env_names_the_option_the_env_refuses_and_builds_nothing_unshaped(monkeypatch):
    with pytest.raises(ValueError, match="^--light-bias:"):
        check_training_env(_args(env="simgrip/Pick-v1", light_bias=0.5))  # not a fragile task
    with pytest.raises(ValueError, match="^--crush-charge:"):
        check_training_env(_args(env="simgrip/Pick-v1", crush_charge=10.0, crush_charge_from=0))
    import simgrip.envs.env_options as mod

    monkeypatch.setattr(mod, "make_env", lambda *a, **k: pytest.fail("built an env no option shapes"))
    check_training_env(_args(env=MULTI))
