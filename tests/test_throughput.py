"""Env throughput against raw mj_step: figures reported, arguments checked (no timing asserted)."""

from __future__ import annotations

import pytest

from simgrip.envs.throughput import measure_throughput, violation_check_times


@pytest.mark.parametrize("clock", ["wall", "cpu"])
def test_throughput_reports_every_figure(clock):
    r = measure_throughput(steps=40, repeats=1, chunk=10, clock=clock)
    assert r["clock"] == clock and r["steps"] == 40 and r["chunks"] >= 4
    for key in ("env_steps_per_s", "raw_physics_steps_per_s", "raw_nstep_physics_steps_per_s"):
        assert r[key] > 0
    assert r["env_physics_steps_per_s"] == pytest.approx(r["env_steps_per_s"] * r["frame_skip"])
    assert r["overhead_percent"] > -100 and r["overhead_vs_nstep_percent"] > -100
    assert r["floor_overhead_percent"] > -100 and r["replay_max_abs_diff"] == 0.0  # the floor's replay too


@pytest.mark.parametrize("kwargs, name", [(dict(steps=0), "steps"), (dict(chunk=0), "chunk"),
                                          (dict(repeats=0), "repeats"), (dict(clock="sundial"), "clock")])
def test_bad_arguments_are_named(kwargs, name):
    with pytest.raises(ValueError, match=name):
        measure_throughput(**kwargs)


@pytest.mark.parametrize("env_id", ["simgrip/PickMulti-v0", "simgrip/PlaceFragile-v8"])
def test_replay_covers_the_same_physics(env_id):
    """The raw replay ends every chunk in the environment's state, bit for bit: K fingers (a new model per
    shape after a reset) and the second palm servo (all of ctrl replayed)."""
    r = measure_throughput(steps=60, repeats=1, chunk=10, clock="cpu", env_id=env_id)
    assert r["chunks"] >= 6 and r["replay_max_abs_diff"] == 0.0


def test_env_id_must_be_a_registered_or_retired_pick_env():
    # a retired id is measured as it was registered (the speed page names the ids of the day)
    from simgrip.envs.throughput import _spec

    r = measure_throughput(steps=20, repeats=1, chunk=10, clock="cpu", env_id="simgrip/PickSphereFragile-v5")
    assert r["chunks"] == 2 and r["replay_max_abs_diff"] == 0.0
    import gymnasium as gym

    u = gym.make(_spec("simgrip/PickSphereFragile-v5")).unwrapped
    assert (u.palm_ramp, u.crush_at) == (False, "end")  # the held palm and the end-of-step rule, as registered
    u.close()
    with pytest.raises(ValueError, match="env_id"):
        measure_throughput(steps=10, env_id="simgrip/NoSuch-v0")
    with pytest.raises(ValueError, match="env_id"):
        measure_throughput(steps=10, env_id="CartPole-v1")


def test_violation_check_times_both_ways_on_the_claws_invalid_states():
    """Random actions curl the sphere claws through each other: the states reach chain_violations, timed both ways,
    and both ways give the same messages on each."""
    r = violation_check_times("simgrip/PickSphereFragile-v6", steps=1500, repeats=1)
    assert r["checks"] == 60 and r["states"] > 0 and r["same"] is True  # FRAGILE_VALIDITY_EVERY = 25 steps
    assert r["batched_us"] > 0 and r["pruned_us"] > 0
    with pytest.raises(ValueError, match="env_id"):
        violation_check_times("simgrip/NoSuch-v0", steps=10)
