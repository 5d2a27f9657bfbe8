"""PlaceFragile-v3's observation-only pick-and-place controller (:class:`~simgrip.envs.scripted_fragile.PlacePolicy`
with its :class:`~simgrip.envs.scripted_fragile.PlaceGripPolicy`), issue 18."""

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  (registers the ids)
from simgrip.envs import retired_spec
from simgrip.envs.scripted_fragile import ObservationFragilePolicy, PlaceGripPolicy, PlacePolicy
from simgrip.envs.valve import absolute_to_valve

# light workpieces on grippy skin (N_hold = m g / (2 mu) = 0.022 N at 5 g), the crush ratio at the log-middle of
# the draw (1.6-2.6): the window is [N_hold, 2.04 N_hold]
LIGHT = {"friction": 1.1, "box_width": 0.05, "target_x": 0.06, "crush_ratio": 2.04}


def _run(grip, options):
    env = gym.make(retired_spec("simgrip/PlaceFragile-v3"))  # started straight: the grip's whole closing
    u = env.unwrapped
    obs, info = env.reset(seed=0, options={k: v for k, v in options.items() if k != "crush_ratio"})
    obs, info = env.reset(seed=0, options={**{k: v for k, v in options.items() if k != "crush_ratio"},
                                           "crush_limit": options["crush_ratio"] * u.hold_force})
    pol = PlacePolicy(grip)
    pol.reset(env, info)
    peak = 0.0
    while True:
        a = np.array(pol(obs), dtype=np.float32)
        a[0] = absolute_to_valve(a[0], u.valve_command, u.kappa_rate)  # as simgrip.envs.baselines runs it
        obs, _, term, trunc, info = env.step(a)
        peak = max(peak, max(info["normal_force"]))
        if term or trunc:
            env.close()
            return info, peak / u.hold_force


@pytest.mark.parametrize("mass", [0.005, 0.01])
def test_place_grip_catches_a_light_workpiece(mass):
    info, peak = _run(PlaceGripPolicy(), {**LIGHT, "box_mass": mass})
    assert info["is_success"] and not info["crushed"], info
    assert peak < LIGHT["crush_ratio"]


def test_the_pick_grip_crushes_the_lightest():
    # the pick task's grip (full valve rate into the contact): the lag carries the force through the window
    info, peak = _run(ObservationFragilePolicy(), {**LIGHT, "box_mass": 0.005})
    assert info["crushed"] and peak > LIGHT["crush_ratio"]


def test_place_policy_grip_by_env_and_feedback_only_with_an_observation_grip():
    from simgrip.envs.scripted_fragile import OracleFragilePolicy
    assert PlacePolicy().slip_frac > 0.0
    assert PlacePolicy(OracleFragilePolicy()).slip_frac == 0.0
    # the valve task gets the place grip; the retired absolute-command PlaceFragile-v0 the controller its stored
    # baselines were measured with (AbsolutePlacePolicy: ObservationFragilePolicy's grip, no force feedback); each
    # refuses the other kind of env, naming the one to use
    from simgrip.envs import RETIRED, retired_spec
    from simgrip.envs.scripted_fragile import AbsolutePlacePolicy
    for env_id, policy, grip, other in (("simgrip/PlaceFragile-v4", PlacePolicy, PlaceGripPolicy, AbsolutePlacePolicy),
                                        ("simgrip/PlaceFragile-v0", AbsolutePlacePolicy, ObservationFragilePolicy,
                                         PlacePolicy)):
        env = gym.make(retired_spec(env_id) if env_id in RETIRED else env_id)
        _, info = env.reset(seed=0)
        pol = policy()
        pol.reset(env, info)
        assert type(pol.grip) is grip
        with pytest.raises(TypeError, match=policy.__name__):
            other().reset(env, info)
        env.close()
    with pytest.raises(TypeError):
        PlaceGripPolicy(no_such_argument=1)
