"""Uniformly random actions in a simgrip env: the baseline a learner must beat.

    python examples/random_policy.py [--episodes 20] [--seed 0] [--env simgrip/Pick-v1] [--fingers K] [--json]

``--fingers K`` chooses the finger count of ``simgrip/PickMulti-v0`` (default 3).

Episode ``i`` is reset with seed ``--seed + i`` and its actions are drawn from
the action space seeded the same way, so a run is reproducible.  Prints one
line per episode and a summary, or with ``--json`` only one JSON object:
``{"episodes", "success_rate", "mean_return"}``.
"""

import argparse
import json
import sys

import gymnasium as gym

import simgrip.envs  # noqa: F401  (registers the simgrip ids)
from simgrip.command_parser import CommandParser
from simgrip.envs.evaluation import add_episode_arguments, check_env_id, env_kwargs, run_episodes, summary
from simgrip.interrupt import run_main


def _line(r) -> str:
    end = "success" if r.info["is_success"] else "dropped" if r.info["dropped"] else \
        "knocked over" if r.info["knocked_over"] else "time limit"
    return f"episode {r.index:3d}: return={r.ret:7.1f}  {end}"


def main(argv=None):
    p = CommandParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_episode_arguments(p)
    args = p.parse_args(argv)
    check_env_id(p, args.env)

    env = gym.make(args.env, **env_kwargs(p, args))
    results = run_episodes(env, lambda obs: env.action_space.sample(), args.episodes, args.seed,
                           on_reset=lambda env_, info, seed: env.action_space.seed(seed),
                           on_episode=None if args.json else lambda r: print(_line(r)))
    env.close()
    out = {k: v for k, v in summary(results).items() if k != "mean_length"}
    if args.json:
        print(json.dumps(out))
    else:
        print(f"success rate {out['success_rate']:.0%}, mean return {out['mean_return']:.1f}")
    return out


if __name__ == "__main__":
    sys.exit(run_main(main, "random_policy"))
