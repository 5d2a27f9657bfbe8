"""simgrip.envs.critic_warmup: PPO's actor held bit for bit while its value function learns."""

import pytest

pytest.importorskip("stable_baselines3")
import torch  # noqa: E402  (Stable-Baselines3's own dependency)
from stable_baselines3 import PPO  # noqa: E402
from stable_baselines3.common.env_util import make_vec_env  # noqa: E402
from stable_baselines3.common.logger import Logger  # noqa: E402
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor  # noqa: E402

from simgrip.envs.critic_warmup import actor_parameters, critic_fit, frozen_actor  # noqa: E402
from simgrip.envs.env_options import make_env  # noqa: E402
from simgrip.envs.evaluation import critic_warmup_conflict  # noqa: E402


def _ppo(**kwargs):
    env = make_vec_env(lambda: make_env("simgrip/PickFragile-v7"), n_envs=1, seed=5)
    model = PPO("MlpPolicy", env, seed=5, verbose=0, n_steps=64, batch_size=32, n_epochs=2, **kwargs)
    model.set_logger(Logger(None, []))  # as train_sb3 does: no SB3-<time> folder per learn()
    return model


def _named(model, params):
    ids = {id(p) for p in params}
    return sorted(n for n, p in model.policy.named_parameters() if id(p) in ids)


def test_actor_parameters_are_the_policy_branch_the_action_head_and_log_std():
    model = _ppo()
    actor = _named(model, actor_parameters(model.policy))
    assert actor == sorted(n for n, _ in model.policy.named_parameters()
                           if n.startswith(("mlp_extractor.policy_net.", "action_net.")) or n == "log_std")
    # what is left is the critic's alone: its branch and its head
    rest = {n for n, _ in model.policy.named_parameters()} - set(actor)
    assert rest and all(n.startswith(("mlp_extractor.value_net.", "value_net.")) for n in rest)


def test_frozen_actor_holds_the_policy_and_trains_the_value_function():
    model = _ppo()
    before = {n: p.detach().clone() for n, p in model.policy.named_parameters()}
    assert critic_fit(model) == {}  # no update yet
    with frozen_actor(model) as params:
        assert params and not any(p.requires_grad for p in params)
        model.learn(total_timesteps=128)  # two rollouts, two updates
    fit = critic_fit(model)
    assert set(fit) == {"explained_variance", "value_loss"} and fit["value_loss"] >= 0.0
    after = dict(model.policy.named_parameters())
    actor = set(_named(model, actor_parameters(model.policy)))
    for name, p in after.items():
        if name in actor:
            assert torch.equal(p, before[name]), name  # bit for bit
        assert p.requires_grad  # every parameter trainable again after the block
    assert any(not torch.equal(after[n], before[n]) for n in after if n.startswith("value_net."))
    model.learn(total_timesteps=64, reset_num_timesteps=False)  # unfrozen: the policy moves
    assert not torch.equal(dict(model.policy.named_parameters())["action_net.weight"], before["action_net.weight"])


def test_a_features_extractor_with_parameters_is_refused():
    import gymnasium as gym

    class Linear(BaseFeaturesExtractor):
        def __init__(self, space: gym.Space):
            super().__init__(space, features_dim=8)
            self.lin = torch.nn.Linear(space.shape[0], 8)

        def forward(self, obs):
            return self.lin(obs)

    model = _ppo(policy_kwargs={"features_extractor_class": Linear})
    with pytest.raises(ValueError, match="features extractor"):
        actor_parameters(model.policy)


def test_critic_warmup_is_ppos_alone():
    assert critic_warmup_conflict(0, ["sac"]) is None and critic_warmup_conflict(2048, ["ppo"]) is None
    for algos in (["sac"], ["ppo", "sac"]):
        assert "--critic-warmup" in critic_warmup_conflict(2048, algos)
