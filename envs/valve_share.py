r"""A restrictor between the policy and the valve: the policy closes at most a share of the valve's rate (issue 18).

``ValveShare(env, share)`` passes the action with its curvature entry ``action[0]`` (the valve's rate,
:mod:`simgrip.envs.valve`) multiplied by ``share`` in ``(0, 1]``; the palm's entries pass unchanged.  The task is
the registered one (the valve's rate, its scripted controllers, the crush rule and every baseline are unchanged);
the policy behind the wrapper moves the curvature command at most ``share * kappa_rate`` action units a step.
Every curvature path of the task that closes no faster than that stays reachable, and the learner's mean and
noise act at that scale.

Why (the learning page, "The first touch on the sphere"): on the claws the learners close faster than the
scripted controller as the fingers reach the workpiece, and the impact of that first touch is read by the crush
rule (the peak force within the step) on the light pieces.  A restricted valve caps the closing speed at the
touch, which the learner cannot undo; the restrictor is that cap as a wrapper on the registered task.

Order: innermost of the wrappers that are part of the policy, under
:class:`~simgrip.envs.scripted_residual.ScriptedResidual` and :class:`~simgrip.envs.action_offset.ActionOffset`:
the env's curvature rate is ``share * clip(a + offset)``.  A residual whose controller drives the curvature is
refused (its command would be cut too); on the palm the controller's command passes unchanged.

Equivalence: where the curvature is the policy's (no residual on it), the env behind ``ValveShare(env, s)`` steps
bit for bit as the task made with ``kappa_rate = s * 0.02`` for a power-of-two ``s`` (``1/2``, ``1/4``:
``0.02 * (s * a) == (s * 0.02) * a`` exactly in binary floating point, ``tests/test_valve_share.py``); for other
shares they differ by the rounding of ``s * a`` to the action's float32 (a relative 6e-8 of the command's step).
So the stop-69 screens run with ``--env-kwargs '{"kappa_rate": 0.01}'`` and ``0.005`` are this wrapper's shares
1/2 and 1/4 on the registered task.

Raises ValueError naming ``share`` when it is not a finite number in ``(0, 1]``, ``env`` when the task has no
valve (``kappa_rate``) or no ``Box`` action space.
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np

from simgrip.envs.arguments import check_number

__all__ = ["ValveShare"]


class ValveShare(gym.ActionWrapper):
    """The env's action is the policy's with ``action[0]`` (the valve's rate) times ``share`` (see
    :mod:`simgrip.envs.valve_share`).

    Parameters
    ----------
    env : gymnasium.Env
        A valve task (its unwrapped env has ``kappa_rate``; every fragile task registered).
    share : float
        The share of the valve's rate the policy commands at ``|action[0]| = 1``, in ``(0, 1]`` (1: no restrictor).

    Attributes
    ----------
    share : float
    """

    def __init__(self, env: gym.Env, share):
        super().__init__(env)
        try:
            s = check_number("share", share)  # finite and > 0 (bools refused)
        except ValueError:
            s = math.nan
        if not s <= 1.0:
            raise ValueError(f"share must be a number in (0, 1] (of the valve's rate), got {share!r}")
        u = env.unwrapped
        if not hasattr(u, "kappa_rate"):
            raise ValueError(f"env: {type(u).__name__} has no valve (its curvature action is not a rate)")
        if not isinstance(env.action_space, gym.spaces.Box):
            raise ValueError(f"env: ValveShare needs a Box action space, got {env.action_space!r}")
        self.share = s

    def action(self, action):
        a = np.array(action, dtype=self.action_space.dtype)  # a copy: the caller's action is not changed
        a[0] = a[0] * self.share
        return a
