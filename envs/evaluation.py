"""Running a policy over seeded episodes, and the command-line options that say which.

The baselines of the pick environments (``examples/random_policy.py``,
``examples/scripted_pick.py``, the held-out evaluation of
``examples/train_sb3.py``) all do the same thing: reset episode ``i`` with seed
``seed0 + i``, act until the episode ends, and summarise success and return.
:func:`run_episodes` is that loop; :func:`add_episode_arguments` the options
``--episodes --seed --env --fingers --json`` they share, validated by argparse (exit 2
naming the option).
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from simgrip.envs.outcome import outcome  # outcomes() counts with it; also importable from here
from simgrip.envs.selection import selection_conflict

__all__ = ["EpisodeResult", "GAMMA", "add_episode_arguments", "add_training_aid_arguments", "charge", "check_env_id",
           "critic_warmup_conflict",
           "discount", "entropy_coefficient", "env_kwargs", "json_object", "log_std", "log_std_init_conflict",
           "outcome", "outcomes", "positive_minutes", "positive_int", "non_negative_int", "probability", "run_episodes",
           "summary", "checkpoint_tag", "training_conflict", "training_files", "training_seed", "episode_count",
           "env_count", "rollout_steps", "minibatch_size", "MAX_EPISODES", "MAX_ENVS", "MAX_TRAINING_SEED"]

#: the discount of the returns :func:`run_episodes` also reports: Stable-Baselines3's default ``gamma`` (PPO, SAC)
GAMMA = 0.99


def _int_at_least(name: str, lo: int, expected: str, doc: str, hi: int | None = None):
    """An argparse type: an integer ``>= lo`` (and ``<= hi`` when given), refused with ``expected`` in the message."""
    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}") from None
        if v < lo or (hi is not None and v > hi):
            raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}")
        return v

    parse.__name__, parse.__qualname__, parse.__doc__ = name, name, doc
    return parse


positive_int = _int_at_least("positive_int", 1, "a positive integer", "argparse type: an integer >= 1.")
non_negative_int = _int_at_least("non_negative_int", 0, "an integer >= 0", "argparse type: an integer >= 0 (seeds).")

#: the largest training seed: NumPy's legacy seeding, which Stable-Baselines3's ``set_random_seed`` calls, takes
#: ``0 <= seed < 2**32``
MAX_TRAINING_SEED = 2**32 - 1
#: the most evaluation episodes a command runs: 100,000 already puts a success rate's 95 % interval within
#: +-0.31 % (the normal approximation at p = 1/2), finer than any result needs; more only runs for hours
MAX_EPISODES = 100_000
#: the longest training budget ``--minutes`` (a week: the project's runs take 15 to 45 CPU-minutes)
MAX_TRAINING_MINUTES = 7 * 24 * 60
#: the most environments a training steps side by side (``--n-envs``): SB3's ``DummyVecEnv`` steps them one after
#: the other in the training's own process, so past a few dozen they only lengthen PPO's rollouts (2048 steps each)
MAX_ENVS = 64
#: the most checkpoints a training takes (``--minutes / --checkpoint-minutes``; each is evaluated on its episodes)
MAX_CHECKPOINTS = 1000


training_seed = _int_at_least(
    "training_seed", 0, f"an integer seed in [0, {MAX_TRAINING_SEED}] (NumPy's seeding, which Stable-Baselines3 uses)",
    "argparse type: a training seed, an integer in ``[0, MAX_TRAINING_SEED]``.", hi=MAX_TRAINING_SEED)
rollout_steps = _int_at_least(
    "rollout_steps", 2, "a number of steps in [2, 1048576]",
    "argparse type: PPO's steps a rollout collects from each env, an integer in ``[2, 2**20]``.", hi=2**20)
minibatch_size = _int_at_least(
    "minibatch_size", 2, "a minibatch size in [2, 1048576]",
    "argparse type: the transitions of one gradient step, an integer in ``[2, 2**20]``.", hi=2**20)
env_count = _int_at_least(
    "env_count", 1, f"a number of environments in [1, {MAX_ENVS}]",
    "argparse type: the environments a training steps side by side, an integer in ``[1, MAX_ENVS]``.", hi=MAX_ENVS)
episode_count = _int_at_least(
    "episode_count", 1, f"a number of episodes in [1, {MAX_EPISODES}] (more buys nothing a success rate needs)",
    "argparse type: a number of evaluation episodes, an integer in ``[1, MAX_EPISODES]``.", hi=MAX_EPISODES)


def _number_in(text: str, ok, interval: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number in {interval}, got {text!r}") from None
    if not ok(x):  # NaN fails too
        raise argparse.ArgumentTypeError(f"expected a number in {interval}, got {text!r}")
    return x


def discount(text: str) -> float:
    """argparse type: a discount ``gamma`` in (0, 1]."""
    return _number_in(text, lambda g: 0.0 < g <= 1.0, "(0, 1]")


def log_std(text: str) -> float:
    """argparse type: a PPO policy's initial log standard deviation, in [-5, 1] (natural log; SB3's default 0)."""
    return _number_in(text, lambda x: -5.0 <= x <= 1.0, "[-5, 1]")


def entropy_coefficient(text: str) -> float:
    """argparse type: PPO's entropy coefficient, in [0, 1] (SB3's default 0: no entropy bonus)."""
    return _number_in(text, lambda x: 0.0 <= x <= 1.0, "[0, 1]")


def log_std_init_conflict(log_std_init, algos, init_from) -> str | None:
    """Why ``--log-std-init`` cannot go with these options (``algos``: the names of the algorithms to train;
    ``init_from``: a warm start, or None), or None: PPO only (SAC's standard deviation is its network's output), and
    not with a warm start (the copied policy brings its own log standard deviation)."""
    if log_std_init is None:
        return None
    if set(algos) != {"ppo"}:
        return "--log-std-init: PPO only (--algo ppo)"
    if init_from is not None:
        return "--log-std-init: not with --init-from (the copied policy brings its own log standard deviation)"
    return None


def critic_warmup_conflict(steps, algos) -> str | None:
    """Why ``--critic-warmup`` cannot go with these algorithms, or None: PPO only (SAC's critic learns off-policy
    from its first steps; :mod:`simgrip.envs.critic_warmup` freezes an on-policy actor-critic's actor)."""
    if steps and set(algos) != {"ppo"}:
        return "--critic-warmup: PPO only (--algo ppo)"
    return None


def training_conflict(args) -> str | None:
    """The first reason the parsed options of ``train_sb3.py`` / ``rl_baselines.py`` (both have ``algo``,
    ``log_std_init``, ``ent_coef``, ``init_from``, ``critic_warmup``, ``crush_charge``, ``crush_charge_from``,
    ``minutes``, ``checkpoint_minutes``, ``n_steps``, ``batch_size``, ``n_envs``, ``normalize``, the ``select_*``
    options and the held-out seeds: ``eval_seeds``, or ``eval_seed`` and ``eval_episodes``) cannot go together, or
    None:
    :func:`log_std_init_conflict`, :func:`critic_warmup_conflict`, ``--n-steps``, ``--ent-coef``,
    ``--privileged-critic`` or ``--sde`` with SAC (the last two also with ``--init-from``), a
    ``--batch-size`` that does not divide PPO's rollout,
    ``--crush-charge-from`` without ``--crush-charge``, :func:`simgrip.envs.selection.selection_conflict`, a checkpoint period longer than the budget (no checkpoint
    would be taken), a budget over :data:`MAX_TRAINING_MINUTES` or more than :data:`MAX_CHECKPOINTS` checkpoints.
    The options alone decide (nothing is imported)."""
    algos = args.algo if isinstance(args.algo, (list, tuple)) else [args.algo]
    why = log_std_init_conflict(args.log_std_init, algos, args.init_from) or \
        critic_warmup_conflict(args.critic_warmup, algos)
    if why:
        return why
    if args.n_steps is not None and set(algos) != {"ppo"}:
        return "--n-steps: PPO only (--algo ppo; SAC collects no rollouts)"
    rollout = (args.n_steps or 2048) * args.n_envs  # PPO's steps an update
    if args.batch_size is not None and "ppo" in algos and rollout % args.batch_size:
        return (f"--batch-size: {args.batch_size} does not divide PPO's rollout of {rollout} steps (--n-steps times "
                "--n-envs), so each epoch's last minibatch would be cut short")
    if args.ent_coef is not None and set(algos) != {"ppo"}:
        return "--ent-coef: PPO only (--algo ppo; SAC tunes its own entropy coefficient)"
    if args.crush_charge_from and args.crush_charge is None:
        return "--crush-charge-from: only with --crush-charge"
    for name, option, why in (("sde", "--sde", "SAC's own use_sde is not offered"), ("privileged_critic",
                              "--privileged-critic", "the asymmetric policy is PPO's actor-critic")):
        if getattr(args, name, False) and set(algos) != {"ppo"}:
            return f"{option}: PPO only (--algo ppo; {why})"
        if getattr(args, name, False) and args.init_from is not None:
            return f"{option}: not with --init-from (the copied policy was built without it)"
    why = selection_conflict(args, args.eval_seeds if hasattr(args, "eval_seeds")
                             else (args.eval_seed, args.eval_seed + args.eval_episodes - 1))
    if why:
        return why
    if args.minutes > MAX_TRAINING_MINUTES:
        return f"--minutes: at most {MAX_TRAINING_MINUTES} (a week), got {args.minutes:g}"
    if args.checkpoint_minutes and args.checkpoint_minutes > args.minutes:
        return "--checkpoint-minutes: larger than --minutes (no checkpoint would be taken)"
    if args.checkpoint_minutes and args.minutes / args.checkpoint_minutes > MAX_CHECKPOINTS:
        return (f"--checkpoint-minutes: {args.minutes:g} / {args.checkpoint_minutes:g} minutes is "
                f"{args.minutes / args.checkpoint_minutes:.3g} checkpoints, each evaluated; at most {MAX_CHECKPOINTS}")
    return None


def positive_minutes(text: str) -> float:
    """argparse type: a budget or a period in minutes, finite and > 0."""
    return _number_in(text, lambda x: 0.0 < x < math.inf, "(0, inf)")


def probability(text: str) -> float:
    """argparse type: a probability in [0, 1]."""
    return _number_in(text, lambda p: 0.0 <= p <= 1.0, "[0, 1]")


def share(text: str) -> float:
    """argparse type: a share in (0, 1]."""
    return _number_in(text, lambda x: 0.0 < x <= 1.0, "(0, 1]")


def charge(text: str) -> float:
    """argparse type: a charge in reward units, finite and >= 0."""
    return _number_in(text, lambda x: 0.0 <= x < math.inf, "[0, inf)")


def add_episode_arguments(parser: argparse.ArgumentParser, *, episodes: int = 20) -> None:
    """Add ``--episodes N``, ``--seed S`` (first episode's seed), ``--env ID`` and ``--json``."""
    parser.add_argument("--episodes", type=episode_count, default=episodes,
                        help=f"number of episodes, 1 to {MAX_EPISODES} (default {episodes})")
    parser.add_argument("--seed", type=non_negative_int, default=0, help="seed of the first episode (default 0)")
    parser.add_argument("--env", default="simgrip/Pick-v1", help="registered env id (default simgrip/Pick-v1)")
    parser.add_argument("--fingers", type=positive_int, default=None,
                        help="fingers K of simgrip/PickMulti-v0 (default: the env's, 3); other envs have two")
    parser.add_argument("--json", action="store_true", help="print only a JSON summary")


def add_training_aid_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the training aids ``examples/train_sb3.py`` applies and ``examples/rl_baselines.py`` passes to each of
    its runs, with the same names, checks and meanings: ``--normalize``, ``--action-offset A ...``,
    ``--frame-stack N``, ``--gamma G``, ``--log-std-init X``, ``--scripted-start P``, ``--light-bias P``,
    ``--residual NAME ...``, ``--residual-alone``, ``--valve-share S``, ``--touch-memory``, ``--privileged-critic``,
    ``--crush-charge F``, ``--crush-charge-from STEPS``, ``--step-charge C``, ``--crush-margin C``, ``--lr-decay``,
    ``--ent-coef C``, ``--n-steps S``, ``--batch-size B``, ``--sde``, ``--select-every M``, ``--select-episodes E``,
    ``--select-seed S`` (each off by default) and ``--n-envs N`` (default 1)."""
    add = parser.add_argument
    add("--normalize", action="store_true",
        help="train behind SB3's VecNormalize (observation and return, library defaults; default off)")
    add("--action-offset", type=float, nargs="+", default=None, metavar="A",
        help="train and evaluate behind simgrip.envs.action_offset.ActionOffset: the env performs clip(action + "
             "offset); one number per action (the valve tasks' probe: -0.4 0.2; -0.2 0.2 where the crush rule "
             "reads the peak; default none)")
    add("--frame-stack", type=positive_int, default=None, metavar="N",
        help="train and evaluate on the last N observations (Gymnasium's FrameStackObservation; default 1: the "
             "env's own)")
    add("--gamma", type=discount, default=None,
        help="the discount, in (0, 1], instead of the library default 0.99 (recorded in the JSON)")
    add("--log-std-init", type=log_std, default=None, metavar="X",
        help="PPO only: the policy's initial log standard deviation, in [-5, 1], instead of the library default 0 "
             "(recorded in the JSON)")
    add("--scripted-start", type=probability, default=None, metavar="P",
        help="start that share of the training episodes part-way through the scripted observation-only "
             "controller's episode (simgrip.envs.scripted_start; evaluation starts plainly; default none)")
    add("--light-bias", type=probability, default=None, metavar="P",
        help="draw that share of the training episodes' workpieces from the lightest third of the mass range "
             "(simgrip.envs.light_bias; evaluation draws the task's own; default none)")
    add("--residual", nargs="+", default=None, metavar="NAME",
        help="train and evaluate behind simgrip.envs.scripted_residual.ScriptedResidual: the task's scripted "
             "observation-only controller drives these actions (the place's palm: palm_x palm_z) and the policy's "
             "action is added to it (default none)")
    add("--residual-alone", action="store_true",
        help="with --residual: the controller drives those actions alone, and the policy acts on the others only "
             "(its action space loses them; default off: the policy's action is added on every action)")
    add("--valve-share", type=share, default=None, metavar="S",
        help="train and evaluate behind simgrip.envs.valve_share.ValveShare: the policy's curvature rate times S "
             "before the valve, in (0, 1], a restrictor (it closes at most S of the valve's rate; default none)")
    add("--touch-memory", action="store_true",
        help="train and evaluate behind simgrip.envs.touch_memory.TouchMemory: the observation gains the first "
             "touch's memory (touched, curvature closed and workpiece risen since it; default off)")
    add("--privileged-critic", action="store_true",
        help="PPO only: train and evaluate behind simgrip.envs.privileged_critic, the value function also reading the "
             "hidden hold force and crush limit, the policy not (an asymmetric actor-critic; default off)")
    add("--crush-charge", type=charge, default=None, metavar="F",
        help="lower the training reward of every crush by F (simgrip.envs.crush_charge; a fragile task only; "
             "evaluation runs the task's own reward; default none)")
    add("--crush-charge-from", type=non_negative_int, default=0, metavar="STEPS",
        help="with --crush-charge: charge the crushes from this training step on (default 0)")
    add("--step-charge", type=charge, default=None, metavar="C",
        help="lower the training reward of every step by C, a cost of time (simgrip.envs.step_charge; evaluation "
             "runs the task's own reward; default none)")
    add("--crush-margin", type=charge, default=None, metavar="C",
        help="lower the training reward of every step by C times how far its largest finger force has gone from 0.8 "
             "of the hidden crush limit to the limit (simgrip.envs.crush_margin; a fragile task only; evaluation runs "
             "the task's own reward; default none)")
    add("--lr-decay", action="store_true",
        help="the learning rate falls linearly from the library default to 0 over the time budget "
             "(simgrip.envs.lr_decay; recorded in the JSON; default off: constant)")
    add("--ent-coef", type=entropy_coefficient, default=None, metavar="C",
        help="PPO only: the entropy bonus's coefficient, in [0, 1], instead of the library default 0 (recorded in "
             "the JSON)")
    add("--n-steps", type=rollout_steps, default=None, metavar="S",
        help="PPO only: the steps a rollout collects from each env, instead of the library default 2048 (with "
             "--n-envs N the rollout holds S * N steps: --n-envs 4 --n-steps 512 keeps the default's 2048 an update; "
             "recorded in the JSON)")
    add("--batch-size", type=minibatch_size, default=None, metavar="B",
        help="the transitions of each gradient step, instead of the library default (PPO 64, SAC 256); with PPO "
             "it must divide the rollout's steps, --n-steps times --n-envs (recorded in the JSON)")
    add("--sde", action="store_true",
        help="PPO only: explore by gSDE, SB3's generalised state-dependent exploration (use_sde=True: the noise a "
             "function of the policy's last features, its matrix drawn once a rollout; named in the JSON; default "
             "off: SB3's independent Gaussian noise every step)")
    add("--select-every", type=positive_minutes, default=None, metavar="M",
        help="every M budget minutes run the policy on the validation seeds and keep the best so far as the "
             "result (simgrip.envs.selection: the validations' time counts in the budget; the held-out evaluation "
             "runs the chosen policy; recorded in the JSON; default off: the last policy)")
    add("--select-episodes", type=episode_count, default=None, metavar="E",
        help="with --select-every: validation episodes (default 50)")
    add("--select-seed", type=non_negative_int, default=None, metavar="S",
        help="with --select-every: the first validation seed (default 20000; the seeds must not meet the held-out "
             "ones)")
    add("--n-envs", type=env_count, default=1, metavar="N",
        help=f"train on N copies of the env, stepped one after the other in the training's process (SB3's "
             f"make_vec_env: DummyVecEnv, copy i seeded --seed + i; PPO's rollouts become N times as long, the "
             f"policy run once per N steps; 1 to {MAX_ENVS}; recorded in the JSON; default 1)")


def check_env_id(parser: argparse.ArgumentParser, env_id: str, *, retired: bool = False) -> None:
    """Exit 2 naming ``--env`` when ``env_id`` is not a registered simgrip pick env (with ``retired=True``: nor a
    retired simgrip id of ``simgrip.envs.RETIRED``, which :func:`simgrip.envs.env_options.make_env` builds):
    another library's env (``CartPole-v1``) has no ``is_success`` and no pick policy, and failed mid-run."""
    import gymnasium as gym

    from simgrip.envs import RETIRED

    if env_id not in gym.registry and not (retired and env_id in RETIRED):
        parser.error(f"--env: unknown id {env_id!r}")
    if not env_id.startswith("simgrip/"):
        parser.error(f"--env: {env_id!r} is not a simgrip env (simgrip/...: the scripts read its pick info keys)")


def env_kwargs(parser: argparse.ArgumentParser, args: argparse.Namespace) -> dict:
    """``gym.make`` keyword arguments from the options; exit 2 naming ``--fingers`` where the env has no such choice."""
    if getattr(args, "fingers", None) is None:
        return {}
    from simgrip.envs import MULTI_ENV_IDS

    if args.env not in MULTI_ENV_IDS:
        parser.error(f"--fingers: {args.env} has two fingers; the finger count is chosen for {', '.join(MULTI_ENV_IDS)}")
    from simgrip.gripper.scene import MAX_FINGERS

    if not 2 <= args.fingers <= MAX_FINGERS:
        parser.error(f"--fingers: 2 to {MAX_FINGERS}, got {args.fingers}")
    return {"fingers": args.fingers}


def json_object(text: str) -> dict:
    """An argparse type: a JSON object (``--env-kwargs '{"w_touch": 0}'``: ``gym.make``'s keyword arguments)."""
    import json

    try:
        value = json.loads(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a JSON object, got {text!r}") from None
    if not isinstance(value, dict):
        raise argparse.ArgumentTypeError(f"expected a JSON object, got {text!r}")
    return value


@dataclass(frozen=True)
class EpisodeResult:
    """One finished episode: its index, seed, undiscounted return, length in env steps, last ``info`` and its
    return discounted by ``gamma`` per step (``sum_t gamma^t r_t``, ``t`` from 0: what a learner with that
    discount maximises from the reset)."""

    index: int
    seed: int
    ret: float
    length: int
    info: dict
    discounted: float = float("nan")


def run_episodes(env, act: Callable[[Any], Any], episodes: int, seed0: int, *,
                 on_reset: Callable[[Any, dict, int], None] | None = None,
                 on_episode: Callable[[EpisodeResult], None] | None = None,
                 on_step: Callable[[dict, int], None] | None = None,
                 gamma: float = GAMMA) -> list[EpisodeResult]:
    """Run ``episodes`` episodes of ``env``, episode ``i`` reset with seed ``seed0 + i``.

    ``act(obs)`` returns the action; ``on_reset(env, info, seed)``, if given, is
    called after each reset (a policy's own reset, seeding an action space);
    ``on_episode(result)`` after each episode (printing a line); ``on_step(info, n)`` after each step, with that
    step's ``info`` and its number ``n`` in the episode (1 for the first); ``gamma`` the discount of :attr:`EpisodeResult.discounted`.
    """
    results = []
    for i in range(episodes):
        seed = seed0 + i
        obs, info = env.reset(seed=seed)
        if on_reset is not None:
            on_reset(env, info, seed)
        ret, disc, weight, n = 0.0, 0.0, 1.0, 0
        while True:
            obs, reward, terminated, truncated, info = env.step(act(obs))
            ret += float(reward)
            disc += weight * float(reward)
            weight *= gamma
            n += 1
            if on_step is not None:
                on_step(info, n)
            if terminated or truncated:
                break
        result = EpisodeResult(i, seed, ret, n, info, disc)
        results.append(result)
        if on_episode is not None:
            on_episode(result)
    return results


def summary(results: list[EpisodeResult]) -> dict:
    """``{"episodes", "success_rate", "mean_return", "mean_length"}`` of finished episodes."""
    n = len(results)
    return {"episodes": n, "success_rate": sum(bool(r.info["is_success"]) for r in results) / n,
            "mean_return": float(np.mean([r.ret for r in results])),
            "mean_length": float(np.mean([r.length for r in results]))}


def outcomes(results: list[EpisodeResult], gamma: float = GAMMA) -> dict:
    """How finished episodes ended and what they were worth to a learner discounting by ``gamma`` (the
    ``gamma`` :func:`run_episodes` was given): ``{"outcomes": {outcome: count}`` (:func:`outcome`),
    ``"mean_success_length"`` (env steps of the successful episodes; ``None`` without one),
    ``"mean_discounted_return"``, ``"gamma"}``."""
    counts: dict[str, int] = {}
    for r in results:
        key = outcome(r.info)
        counts[key] = counts.get(key, 0) + 1
    lengths = [r.length for r in results if r.info.get("is_success")]
    return {"outcomes": dict(sorted(counts.items())),
            "mean_success_length": float(np.mean(lengths)) if lengths else None,
            "mean_discounted_return": float(np.mean([r.discounted for r in results])), "gamma": float(gamma)}


def checkpoint_tag(period: float, k: int) -> str:
    """The name part of ``train_sb3.py``'s ``k``-th checkpoint every ``period`` budget minutes (``"10min"``), in its
    files ``<algo>_model_<tag>.zip`` and ``<algo>_vecnormalize_<tag>.pkl``."""
    return f"{period * k:g}min"


def training_files(algos, *, minutes: float, checkpoint_minutes: float | None = None,
                   normalize: bool = False) -> list[str]:
    """The names of the files ``examples/train_sb3.py`` writes into its ``--out`` for ``algos``: per algorithm
    ``<algo>_curve.csv``, ``_policy.csv``, ``_model.zip``, ``_eval.json`` (with ``normalize``
    ``_vecnormalize.pkl``), and every checkpoint's ``<algo>_model_<k M>min.zip`` (``_vecnormalize_<k M>min.pkl``)
    that ``minutes`` of budget can reach with ``checkpoint_minutes = M`` (one more than the budget divides into,
    for a last step that crosses both), then ``curves.png``.  So that every one is checked before any training
    (:func:`simgrip.io.check_output_files_in`)."""
    kinds = ["curve.csv", "policy.csv", "model.zip", "eval.json"] + (["vecnormalize.pkl"] if normalize else [])
    if checkpoint_minutes:
        for k in range(1, int(minutes / checkpoint_minutes + 1e-9) + 2):
            tag = checkpoint_tag(checkpoint_minutes, k)
            kinds += [f"model_{tag}.zip"] + ([f"vecnormalize_{tag}.pkl"] if normalize else [])
    return [f"{a}_{kind}" for a in algos for kind in kinds] + ["curves.png"]
