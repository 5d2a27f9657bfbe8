"""Scripted pick with the curvature chosen from the elastica reference.

For each randomised box the controller solves the paper's Grip I problem for
the box's b, M and mu_s and takes the gentlest curvature that holds it with a
friction safety factor of 2, ramps the pneumatic command to it, lifts and holds.

    python examples/scripted_pick.py --episodes 20 [--seed 0] [--gif pick.gif]
"""

import argparse

import gymnasium as gym

import simgrip.envs  # noqa: F401  (registers simgrip/Pick-v0)
from simgrip.envs.scripted import ScriptedPickPolicy


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--episodes", type=int, default=20)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--env", default="simgrip/Pick-v0")
    p.add_argument("--gif", default=None, help="also write a GIF of the first episode (needs MUJOCO_GL)")
    args = p.parse_args(argv)

    env = gym.make(args.env)
    policy = ScriptedPickPolicy()
    wins = 0
    for ep in range(args.episodes):
        obs, info = env.reset(seed=args.seed + ep)
        policy.reset(env, info)
        ret = 0.0
        while True:
            obs, reward, terminated, truncated, info = env.step(policy(obs))
            ret += reward
            if terminated or truncated:
                break
        wins += info["is_success"]
        box = env.unwrapped.box
        print(f"episode {ep:3d}: b={box.width * 100:.1f} cm  m={box.mass * 1000:.0f} g  mu={box.friction:.2f}  "
              f"kappa={policy.kappa:+.2f}  N={info['normal_force'].mean():.2f} N  return={ret:7.1f}  "
              f"{'success' if info['is_success'] else 'fail'}")
    env.close()
    print(f"success rate {wins / args.episodes:.0%} over {args.episodes} episodes")
    if args.gif:
        from simgrip.envs.rendering import render_pick_gif

        render_pick_gif(args.gif, seed=args.seed)
        print(f"wrote {args.gif}")


if __name__ == "__main__":
    main()
