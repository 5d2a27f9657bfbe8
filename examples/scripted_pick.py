"""Scripted pick: the elastica oracle, or the honest controller that sees only the observation.

``--policy oracle`` (default) reads the episode's true box (width, mass,
friction) and solves the paper's Grip I (or III) problem for the gentlest
curvature that holds it with a friction safety factor of 2, ramps the
pneumatic command to it, lifts and holds.  ``--policy observation`` sees only
what a learned policy sees: it grips with one curvature for the whole
randomised range and curls further when it sees the box slip.

    python examples/scripted_pick.py [--episodes 20] [--seed 0] [--env simgrip/Pick-v1]
                                     [--policy oracle|observation] [--json] [--gif pick.gif]

Prints one line per episode and a summary, or with ``--json`` only one JSON
object: ``{"episodes", "success_rate", "mean_return"}``.
"""

import argparse
import json

import gymnasium as gym
import numpy as np

import simgrip.envs  # noqa: F401  (registers the simgrip ids)
from simgrip.envs.scripted import ObservationPickPolicy, ScriptedPickPolicy

POLICIES = {"oracle": ScriptedPickPolicy, "observation": ObservationPickPolicy}


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
    p.add_argument("--policy", choices=sorted(POLICIES), default="oracle",
                   help="oracle (reads the true box) or observation (sees only the observation)")
    p.add_argument("--json", action="store_true", help="print only a JSON summary")
    p.add_argument("--gif", default=None, help="also write a GIF of the first episode (oracle policy)")
    args = p.parse_args(argv)
    if args.env not in gym.registry:
        p.error(f"--env: unknown id {args.env!r}")

    env = gym.make(args.env)
    policy = POLICIES[args.policy]()
    wins, returns = 0, []
    for ep in range(args.episodes):
        obs, info = env.reset(seed=args.seed + ep)
        policy.reset(env, info)
        ret = 0.0
        while True:
            obs, reward, terminated, truncated, info = env.step(policy(obs))
            ret += float(reward)
            if terminated or truncated:
                break
        wins += bool(info["is_success"])
        returns.append(ret)
        if not args.json:
            box = env.unwrapped.box
            print(f"episode {ep:3d}: b={box.width * 100:.1f} cm  m={box.mass * 1000:.0f} g  mu={box.friction:.2f}  "
                  f"kappa={policy.kappa:+.2f}  N={info['normal_force'].mean():.2f} N  return={ret:7.1f}  "
                  f"{'success' if info['is_success'] else 'fail'}")
    env.close()
    summary = {"episodes": args.episodes, "success_rate": wins / args.episodes, "mean_return": float(np.mean(returns))}
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"success rate {summary['success_rate']:.0%} over {args.episodes} episodes, "
              f"mean return {summary['mean_return']:.1f}")
    if args.gif:
        from simgrip.envs.rendering import render_pick_gif

        render_pick_gif(args.gif, seed=args.seed)
        print(f"wrote {args.gif}")
    return summary


if __name__ == "__main__":
    main()
