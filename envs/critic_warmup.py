"""Critic warm-up for PPO: fit the value function to the starting policy's returns before the policy moves.

A residual learner (:class:`simgrip.envs.scripted_residual.ScriptedResidual` on every action) starts as a working
controller: SB3's fresh PPO policy has a deterministic action near 0 (its action head's weights are scaled by
0.01), so it is the controller plus its exploration noise.  PPO's first updates weigh each action by its advantage,
estimated (GAE) from the rewards and the value function ``V(s)``; a value function that has not yet seen a return
(SB3's starts near 0 everywhere) makes those estimates mostly the returns themselves, and the first updates move the
policy on them.  The residual-learning literature fits the critic first, the policy held (Silver et al. 2018,
"Residual Policy Learning"; Johannink et al. 2019, "Residual Reinforcement Learning for Robot Control").

For PPO that is its usual loop with the actor's parameters frozen: the rollouts are collected by the starting
policy, noise included (the policy whose value the advantages will need), and each update's loss reaches only the
value function (the policy's ratio is 1, its entropy fixed).  :func:`actor_parameters` names the actor's
parameters (SB3's ``MlpPolicy``: the MLP's policy branch, the action head and the state-independent log standard
deviation); :func:`frozen_actor` freezes them for a block (``requires_grad`` off, so PyTorch's Adam skips them:
they come out bit for bit as they went in) and :func:`critic_fit` reads how well the value function predicted the
last rollout's returns before that update (SB3's ``train/explained_variance``, out of sample); :func:`warm_up` runs
PPO's loop that way and records each update's fit.

``examples/train_sb3.py --critic-warmup STEPS`` runs it before the training, the CPU time counted in the budget.
"""

from __future__ import annotations

from contextlib import contextmanager

__all__ = ["actor_parameters", "critic_fit", "frozen_actor", "warm_up"]


def actor_parameters(policy) -> list:
    """The parameters of an SB3 ``ActorCriticPolicy`` that only the actor uses: ``mlp_extractor.policy_net``,
    ``action_net`` and ``log_std`` (the Gaussian policy's).  A features extractor with parameters would be shared
    with the critic or be the actor's own: refused (``ValueError``), as neither freezing it nor training it
    would hold the policy while the critic learns alone; ``MlpPolicy``'s (a flatten) has none."""
    extractors = {id(m): m for m in (getattr(policy, name, None) for name in
                                     ("features_extractor", "pi_features_extractor", "vf_features_extractor"))
                  if m is not None}
    if any(True for m in extractors.values() for _ in m.parameters()):
        raise ValueError("critic warm-up: the policy's features extractor has parameters (MlpPolicy's has none)")
    import torch

    params = list(policy.mlp_extractor.policy_net.parameters()) + list(policy.action_net.parameters())
    if isinstance(getattr(policy, "log_std", None), torch.nn.Parameter):
        params.append(policy.log_std)
    return params


@contextmanager
def frozen_actor(model):
    """Within the block, ``model``'s (an SB3 PPO's) actor parameters do not learn (:func:`actor_parameters`);
    afterwards each is as trainable as before."""
    params = actor_parameters(model.policy)
    before = [p.requires_grad for p in params]
    try:
        for p in params:
            p.requires_grad_(False)
        yield params
    finally:
        for p, flag in zip(params, before):
            p.requires_grad_(flag)


def critic_fit(model) -> dict:
    """What SB3's PPO recorded of its last update: ``explained_variance`` (1 - Var(G - V) / Var(G) over the
    rollout it learned from, ``V`` the value function before that update; 1 is a perfect prediction, 0 no better
    than a constant, negative worse) and ``value_loss`` (the update's mean squared error of the value function,
    reward units squared).  Empty before the first update."""
    logger = getattr(model, "_logger", None)  # (SB3 configures it at the first learn)
    if logger is None:
        return {}
    seen = logger.name_to_value
    return {key: float(seen[f"train/{key}"]) for key in ("explained_variance", "value_loss")
            if f"train/{key}" in seen}


def warm_up(model, steps: int, callback=None) -> dict:
    """Run ``model.learn(steps)`` (an SB3 PPO's, in whole rollouts; ``callback`` as ``learn``'s, e.g. a budget that
    may stop it) inside :func:`frozen_actor`.  Returns the fit of every update made, in order:
    ``explained_variance`` and ``value_loss`` (lists, :func:`critic_fit`); a rollout the callback stopped is not
    followed by an update and adds nothing."""
    from stable_baselines3.common.callbacks import BaseCallback

    fits = []

    class Fits(BaseCallback):
        """SB3 records an update's fit after the rollout it learns from: read it when the next rollout starts."""
        pending = False

        def _on_rollout_start(self) -> None:
            if self.pending:
                fits.append(critic_fit(self.model))
            self.pending = False

        def _on_rollout_end(self) -> None:  # (only a finished rollout gets here, and an update follows it)
            self.pending = True

        def _on_step(self) -> bool:
            return True

    fit_cb = Fits()
    with frozen_actor(model):
        model.learn(total_timesteps=steps, callback=[fit_cb] if callback is None else [callback, fit_cb])
    if fit_cb.pending:  # the last update's
        fits.append(critic_fit(model))
    return {key: [f.get(key) for f in fits] for key in ("explained_variance", "value_loss")}
