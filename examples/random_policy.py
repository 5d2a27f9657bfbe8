"""Uniformly random actions in a simgrip env: the baseline a learner must beat.

    python examples/random_policy.py [--episodes 20] [--seed 0] [--env simgrip/Pick-v1] [--json]

Episode ``i`` is reset with seed ``--seed + i`` and its actions are drawn from
the action space seeded the same way, so a run is reproducible.  Prints one
line per episode and a summary, or with ``--json`` only one JSON object:
``{"episodes", "success_rate", "mean_return"}``.
"""

import argparse
import json

import gymnasium as gym
import numpy as np

import simgrip.envs  # noqa: F401  (registers the simgrip ids)


def _count(text):
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return v


def _seed(text):
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}") from None
    if v < 0:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}")
    return v


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--episodes", type=_count, default=20, help="number of episodes (default 20)")
    p.add_argument("--seed", type=_seed, default=0, help="seed of the first episode (default 0)")
    p.add_argument("--env", default="simgrip/Pick-v1", help="registered env id (default simgrip/Pick-v1)")
    p.add_argument("--json", action="store_true", help="print only a JSON summary")
    args = p.parse_args(argv)
    if args.env not in gym.registry:
        p.error(f"--env: unknown id {args.env!r}")

    env = gym.make(args.env)
    wins, returns = 0, []
    for ep in range(args.episodes):
        env.action_space.seed(args.seed + ep)
        obs, info = env.reset(seed=args.seed + ep)
        ret = 0.0
        while True:
            obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
            ret += float(reward)
            if terminated or truncated:
                break
        wins += bool(info["is_success"])
        returns.append(ret)
        if not args.json:
            end = "success" if info["is_success"] else "dropped" if info["dropped"] else \
                "knocked over" if info["knocked_over"] else "time limit"
            print(f"episode {ep:3d}: return={ret:7.1f}  {end}")
    env.close()
    summary = {"episodes": args.episodes, "success_rate": wins / args.episodes, "mean_return": float(np.mean(returns))}
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"success rate {summary['success_rate']:.0%}, mean return {summary['mean_return']:.1f}")
    return summary


if __name__ == "__main__":
    main()
