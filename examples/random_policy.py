"""Uniformly random actions in simgrip/Pick-v0: the baseline a learner must beat.

    python examples/random_policy.py --episodes 20 [--seed 0] [--vector 4]
"""

import argparse

import gymnasium as gym
import numpy as np

import simgrip.envs  # noqa: F401  (registers simgrip/Pick-v0)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--episodes", type=int, default=20)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--env", default="simgrip/Pick-v0")
    args = p.parse_args(argv)

    env = gym.make(args.env)
    wins, returns = 0, []
    for ep in range(args.episodes):
        env.action_space.seed(args.seed + ep)
        obs, info = env.reset(seed=args.seed + ep)
        ret = 0.0
        while True:
            obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
            ret += reward
            if terminated or truncated:
                break
        wins += info["is_success"]
        returns.append(ret)
        end = "success" if info["is_success"] else "dropped" if info["dropped"] else \
            "knocked over" if info["knocked_over"] else "time limit"
        print(f"episode {ep:3d}: return={ret:7.1f}  {end}")
    env.close()
    print(f"success rate {wins / args.episodes:.0%}, mean return {np.mean(returns):.1f}")


if __name__ == "__main__":
    main()
