"""The fragile tasks' scripted controllers as ``make(env, info, seed) -> act(obs, t)`` (issue 18).

What :mod:`simgrip.envs.baselines` runs as its ``oracle`` and ``observation`` rows, and what the training aids
that drive an episode with the observation-only controller build on (:mod:`simgrip.envs.scripted_start`,
:mod:`simgrip.envs.scripted_residual`): :func:`policy_maker` picks the task's controller
(:mod:`simgrip.envs.scripted_fragile`) and, on a valve env, turns its absolute curvature command into the valve's
rate (:func:`through_valve`).  Kept apart from the baselines' grids and command line so that those aids and
the baselines can use each other without an import circle.
"""

from __future__ import annotations

import numpy as np

__all__ = ["controller", "policy_maker", "scripted", "task", "through_valve"]


def task(env) -> tuple:
    """``(place, claw, openloop_grid, valve)`` of a fragile env: a pick-and-place (three actions), the claw
    (``"cradle"``, ``"sphere"`` or None), the env's own open-loop grid (or None), a valve env."""
    from simgrip.envs.valve import ValveCommand

    u = env.unwrapped
    place = env.action_space.shape[0] == 3
    claw = "cradle" if getattr(u, "grip", None) == "III" else "sphere" if getattr(u, "shapes", ()) == (
        "sphere",) else None
    return place, claw, getattr(u, "openloop_grid", None), isinstance(u, ValveCommand)


def scripted(cls):
    """``make`` of a controller class: a fresh ``cls()`` reset on the episode's env and first info."""
    def make(env, info, seed):
        pol = cls()
        pol.reset(env, info)
        return lambda obs, t: pol(obs)
    return make


def through_valve(make):
    """Run an absolute-command policy (``make``'s ``act``) on a valve env: each step's curvature command becomes
    the valve action that moves towards it as fast as the valve allows (:func:`~simgrip.envs.valve.absolute_to_valve`;
    a one-step ramp becomes a full-rate ramp)."""
    from simgrip.envs.valve import absolute_to_valve

    def make_valve(env, info, seed):
        act, u = make(env, info, seed), env.unwrapped

        def valve_act(obs, t):
            a = np.array(act(obs, t), dtype=np.float32)
            a[0] = absolute_to_valve(a[0], u.valve_command, u.kappa_rate)
            return a
        return valve_act
    return make_valve


def controller(policy: str, place: bool, claw: str | None, valve: bool):
    """``make`` of the scripted controller ``policy`` (``"oracle"`` or ``"observation"``) of a task
    (:func:`task`'s ``place``, ``claw``; ``valve``: the pick-and-place's valve-env controller, else the retired
    absolute-command one), in absolute curvature commands (:func:`through_valve` for a valve env)."""
    from simgrip.envs.scripted_fragile import (AbsolutePlacePolicy, ObservationFragilePolicy, OracleFragilePolicy,
                                               PlacePolicy)
    if claw:
        from simgrip.envs.scripted_fragile import CLAW_POLICIES
        oracle, observation = CLAW_POLICIES[claw]
    elif place:
        cls = PlacePolicy if valve else AbsolutePlacePolicy  # a valve env, or the retired v0/v1
        oracle, observation = (lambda: cls(OracleFragilePolicy())), cls
    else:
        oracle, observation = OracleFragilePolicy, ObservationFragilePolicy
    return scripted({"oracle": oracle, "observation": observation}[policy])


def policy_maker(env, policy: str):
    """``make(env, info, seed) -> act(obs, t)`` of the fragile task's scripted controller ``policy``
    (``"observation"`` or ``"oracle"``; through the valve where ``env`` has one), as
    :func:`simgrip.envs.baselines.evaluate` runs it.  ValueError naming ``policy`` when it is not one of them,
    or ``env`` is not a fragile task."""
    if policy not in ("observation", "oracle"):
        raise ValueError(f"policy must be 'observation' or 'oracle', got {policy!r}")
    if not hasattr(env.unwrapped, "crush_ratio_range"):
        raise ValueError(f"policy: the scripted controllers are the fragile tasks' ({env.unwrapped.__class__.__name__} "
                         "is not one)")
    place, claw, _, valve = task(env)
    make = controller(policy, place, claw, valve)
    return through_valve(make) if valve else make
