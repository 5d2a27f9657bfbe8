"""The hyperparameters a training of ``examples/train_sb3.py`` changes from Stable-Baselines3's defaults.

:func:`model_kwargs` gives the keyword arguments the algorithm is built with, :func:`hyperparameters` the sentence
``<algo>_eval.json`` records of them (which a ``--replay`` must match), and :func:`budget_decay` ``--lr-decay``'s
learning rate.  Each changed hyperparameter is named; nothing else differs from the library's defaults.
"""

from __future__ import annotations

import inspect

from simgrip.envs.lr_decay import BudgetDecay

__all__ = ["budget_decay", "hyperparameters", "model_kwargs"]


def model_kwargs(algo: str, gamma: float | None, log_std_init: float | None, lr_decay=None,
                 ent_coef: float | None = None, n_steps: int | None = None, batch_size: int | None = None,
                 use_sde: bool | None = None) -> dict:
    """The keyword arguments that change the library's defaults: ``gamma``; ``log_std_init`` (PPO only: SAC's
    standard deviation is an output of its network, not a parameter); ``lr_decay``, a
    :class:`simgrip.envs.lr_decay.BudgetDecay` for the learning rate; ``ent_coef``, ``n_steps`` (the steps a
    rollout collects from each env) and ``use_sde`` (gSDE's state-dependent exploration; False or None: off), PPO
    only; ``batch_size``, the transitions of each gradient step.  ValueError naming a PPO-only one given with SAC."""
    kwargs = {k: v for k, v in (("gamma", gamma), ("batch_size", batch_size and int(batch_size))) if v is not None}
    for name, value, kind in (("ent_coef", ent_coef, float), ("n_steps", n_steps, int),
                              ("use_sde", use_sde or None, bool)):
        if value is not None:
            if algo != "ppo":
                raise ValueError(f"{name}: PPO only, got algo {algo!r}")
            kwargs[name] = kind(value)
    kwargs.update({} if lr_decay is None else {"learning_rate": lr_decay})
    if log_std_init is not None:
        if algo != "ppo":
            raise ValueError(f"log_std_init: PPO only, got algo {algo!r}")
        kwargs["policy_kwargs"] = {"log_std_init": float(log_std_init)}
    return kwargs


def budget_decay(algo: str, budget_s: float, clock: str, replay=None) -> BudgetDecay:
    """``--lr-decay``'s schedule: the algorithm's default rate falling to 0 over ``budget_s`` seconds of ``clock``
    (a replay's: the record's readings, ``replay``)."""
    from stable_baselines3 import PPO, SAC

    initial = inspect.signature({"ppo": PPO, "sac": SAC}[algo]).parameters["learning_rate"].default
    return BudgetDecay(initial, budget_s, clock, replay=replay)


def hyperparameters(gamma: float | None, log_std_init: float | None, lr_decay=None, ent_coef: float | None = None,
                    n_steps: int | None = None, batch_size: int | None = None, use_sde: bool | None = None) -> str:
    """The JSON's ``hyperparameters``: the library's defaults, and which ones this run changed (``use_sde`` named
    only where True, so that every record made before it reads as it did)."""
    changed = [f"{k} = {v!r}" for k, v in (("gamma", gamma), ("log_std_init", log_std_init), ("ent_coef", ent_coef),
                                           ("n_steps", n_steps), ("batch_size", batch_size),
                                           ("use_sde", use_sde or None)) if v is not None] + \
        ([] if lr_decay is None else [f"learning_rate = {lr_decay.initial!r} falling linearly to 0 over the budget"])
    return "Stable-Baselines3 defaults" + (" but " + ", ".join(changed) if changed else "")
