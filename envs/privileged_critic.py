r"""An asymmetric actor-critic: the value function sees the hidden workpiece, the policy does not (issue 18).

A fragile task hides what decides a grip: the least force that holds the workpiece (its weight over twice its
friction) and the force that crushes it.  The policy must act on what it senses, but PPO's value function is a
training device only: it can be given what the simulator knows, so that a step towards a crush or a slip is
valued as such rather than as the average over the workpieces that look alike (Pinto et al., "Asymmetric Actor
Critic for Image-Based Robot Learning", RSS 2018; OpenAI et al., "Learning dexterous in-hand manipulation",
IJRR 2020).  Two parts:

* :class:`PrivilegedObservation` appends :data:`N_PRIVILEGED` entries to the task's observation, from the hidden
  ``hold_force`` ``H`` and ``crush_limit`` ``C`` of its unwrapped env and the largest finger force ``F`` the crush
  rule read in the step (``info["peak_normal_force"]``, else ``info["normal_force"]``; 0 after ``reset``):

  ======  ====================================  ==============================================
  entry   value                                 what it tells the critic
  ======  ====================================  ==============================================
  0       ``log(C / H)``                        the window between slipping and crushing
  1       ``log(1 + H / W)``                    the force that holds (``W`` the task's force unit)
  2       ``min(F / C, 10)``                    how near the grip is to the crush (1: crushed)
  3       ``log(1 + F / H)``                    how far past the least hold it is
  ======  ====================================  ==============================================

* :class:`AsymmetricActorCriticPolicy`, SB3's ``MlpPolicy`` for PPO with separate feature extractors whose policy
  extractor (:class:`ActorView`) sets those last entries to zero: the actor's output does not depend on them (its
  first layer's weights for them get no gradient), the critic reads the whole observation.  ``train_sb3.py
  --privileged-critic`` trains behind both (PPO only); evaluation runs the same wrapper, which the policy ignores
  (``tests/test_privileged_critic.py`` checks that changing the entries does not change an action).

Raises ValueError naming ``env`` where the task has no hidden crush limit (not a fragile task) or its observation
is not a flat ``Box``.
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np

from simgrip.envs.touch_history import read_forces

__all__ = ["N_PRIVILEGED", "ActorView", "AsymmetricActorCriticPolicy", "PrivilegedObservation", "policy_for"]

#: the entries :class:`PrivilegedObservation` appends (module docstring's table)
N_PRIVILEGED = 4
#: the bound of entry 2 (a force ten times the crush limit); entries 0, 1 and 3 are below it on every task
NEAR_MAX = 10.0


class PrivilegedObservation(gym.Wrapper):
    """The task's observation with :data:`N_PRIVILEGED` hidden entries appended (module docstring's table).

    Parameters
    ----------
    env : gymnasium.Env
        A fragile task (its unwrapped env has ``hold_force`` and ``crush_limit``), possibly wrapped; its
        observation a one-dimensional ``Box``.
    """

    def __init__(self, env: gym.Env):
        super().__init__(env)
        u = env.unwrapped
        if not (hasattr(u, "crush_limit") and hasattr(u, "hold_force")):
            raise ValueError(f"env: {type(u).__name__} is not a fragile task (no hidden crush limit to give "
                             "the critic)")
        space = env.observation_space
        if not isinstance(space, gym.spaces.Box) or len(space.shape) != 1:
            raise ValueError(f"env: the privileged critic needs a flat Box observation, got {space!r}")
        self._task = u
        self._unit = float(getattr(u, "_force_unit", 1.0))
        low = np.concatenate([space.low, np.zeros(N_PRIVILEGED)]).astype(space.dtype)
        high = np.concatenate([space.high, np.full(N_PRIVILEGED, np.inf)]).astype(space.dtype)
        self.observation_space = gym.spaces.Box(low, high, dtype=space.dtype)

    def privileged(self, force: float) -> np.ndarray:
        """The appended entries for the largest finger force ``force`` [N] (the module docstring's table), the
        episode's hidden hold force and crush limit as drawn at the last ``reset``."""
        hold, crush = self._hidden
        return np.array([*self._episode, min(force / crush, NEAR_MAX), math.log1p(force / hold)],
                        dtype=self.observation_space.dtype)

    def _with(self, obs, force: float) -> np.ndarray:
        return np.concatenate([np.asarray(obs, dtype=self.observation_space.dtype), self.privileged(force)])

    def reset(self, **kwargs):
        obs, info = self.env.reset(**kwargs)
        hold, crush = float(self._task.hold_force), float(self._task.crush_limit)  # drawn anew at each reset
        if not (hold > 0.0 and math.isfinite(crush) and crush >= hold):
            raise ValueError(f"env: hold force {hold!r} and crush limit {crush!r} give no window")
        self._hidden = (hold, crush)
        self._episode = (math.log(crush / hold), math.log1p(hold / self._unit))  # entries 0 and 1: the episode's
        return self._with(obs, 0.0), info

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        force = max(float(f) for f in read_forces(info))
        return self._with(obs, force), reward, terminated, truncated, info


def policy_for(options):
    """The policy an SB3 model is built with for ``options`` (:class:`~simgrip.envs.env_options.EnvOptions`, or
    None): :class:`AsymmetricActorCriticPolicy` where ``options.privileged_critic``, else ``"MlpPolicy"``."""
    return _classes()[1] if getattr(options, "privileged_critic", False) else "MlpPolicy"


def _actor_view_class():
    """:class:`ActorView`, built on first use (torch is imported only by the training scripts)."""
    import torch as th
    from stable_baselines3.common.preprocessing import get_flattened_obs_dim
    from stable_baselines3.common.torch_layers import BaseFeaturesExtractor

    class ActorView(BaseFeaturesExtractor):
        """The flattened observation with its last ``n_privileged`` entries set to 0 (the policy's features)."""

        def __init__(self, observation_space, n_privileged: int = N_PRIVILEGED):
            super().__init__(observation_space, get_flattened_obs_dim(observation_space))
            self.n_privileged = int(n_privileged)
            self.flatten = th.nn.Flatten()

        def forward(self, observations):
            x = self.flatten(observations)
            kept = x.shape[1] - self.n_privileged
            return th.cat([x[:, :kept], th.zeros_like(x[:, kept:])], dim=1)

    return ActorView


def _policy_class():
    from stable_baselines3.common.policies import ActorCriticPolicy

    view = _actor_view_class()

    class AsymmetricActorCriticPolicy(ActorCriticPolicy):
        """SB3's ``MlpPolicy`` with the actor's features :class:`ActorView` (its last ``n_privileged`` entries
        zero) and the critic's the whole observation; every other argument is ``ActorCriticPolicy``'s
        (``share_features_extractor`` is always False)."""

        def __init__(self, *args, n_privileged: int = N_PRIVILEGED, **kwargs):
            kwargs["share_features_extractor"] = False
            self.n_privileged = int(n_privileged)
            super().__init__(*args, **kwargs)

        def _build(self, lr_schedule) -> None:
            self.pi_features_extractor = view(self.observation_space, self.n_privileged)
            super()._build(lr_schedule)

    AsymmetricActorCriticPolicy.__module__ = __name__
    AsymmetricActorCriticPolicy.__qualname__ = "AsymmetricActorCriticPolicy"
    view.__module__, view.__qualname__ = __name__, "ActorView"
    return view, AsymmetricActorCriticPolicy


def _classes() -> tuple:
    """``(ActorView, AsymmetricActorCriticPolicy)``, made once, on first use."""
    if "AsymmetricActorCriticPolicy" not in globals():
        view, policy = _policy_class()
        globals().update(ActorView=view, AsymmetricActorCriticPolicy=policy)
    return globals()["ActorView"], globals()["AsymmetricActorCriticPolicy"]


def __getattr__(name):
    # the torch classes are made on first access, so that importing the wrapper does not import torch (the rl
    # extra is optional); a saved model names its policy class by this module's path, which this resolves
    names = ("ActorView", "AsymmetricActorCriticPolicy")
    if name in names:
        return _classes()[names.index(name)]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
