"""``evaluate_policy.py``'s ``first_touch`` (issue 18): the force of each episode's first touch over its hidden
crush limit, as the crush rule reads it (the peak within the step) and at the step's end.

Checked against the episodes replayed here with the same scripted controller, and against the env's own crush rule:
a touch read above the limit is a crush in the touch's step (``crushed_after_touch["0"]``), and none other is.
"""

from __future__ import annotations


import simgrip.envs  # noqa: F401
from helpers import load_example as _example


def test_first_touch_summarises_the_touches_and_skips_episodes_that_never_touched():
    summary = _example("evaluate_policy").first_touch([(2.0, 0.25), None, (0.5, 0.5), (0.25, 0.125)])
    assert summary == {"touches": 3, "read": {"median": 0.5, "max": 2.0}, "end": {"median": 0.25, "max": 0.5},
                       "above_limit": 1}
    assert _example("evaluate_policy").first_touch([None, None]) is None


def test_first_touch_is_the_episodes_first_forces_and_a_read_above_the_limit_is_a_crush_on_touch():
    """The sphere's observation-only controller on seeds 8000-8006 (it crushes 8006's piece in the step of the first
    touch: an impact's peak within the step, where the step's end reads less than the limit), replayed here step by
    step with the same controller."""
    import gymnasium as gym

    module = _example("evaluate_policy")
    out = module.main(["--env", "simgrip/PickSphereFragile-v6", "--policy", "observation", "--episodes", "7",
                       "--seed", "8000", "--json"])
    env = gym.make("simgrip/PickSphereFragile-v6")
    act, on_reset = module._scripted(env, "observation")
    firsts, crushed_on_touch = [], 0
    for seed in range(8000, 8007):
        obs, info = env.reset(seed=seed)
        on_reset(env, info, seed)
        first = None
        while True:
            obs, _, terminated, truncated, info = env.step(act(obs))
            if first is None and max(info["peak_normal_force"]) > 0.0:
                first = (max(info["peak_normal_force"]) / info["crush_limit"],
                         max(info["normal_force"]) / info["crush_limit"])
                crushed_on_touch += bool(info["crushed"])
            if terminated or truncated:
                break
        firsts.append(first)
    env.close()
    assert None not in firsts and crushed_on_touch == 1
    reads, ends = sorted(r for r, _ in firsts), sorted(e for _, e in firsts)
    assert out["first_touch"] == {"touches": 7, "read": {"median": reads[3], "max": reads[6]},
                                  "end": {"median": ends[3], "max": ends[6]}, "above_limit": 1}
    assert out["crushed_after_touch"]["0"] == 1 and reads[6] > 1.0 > ends[6]
