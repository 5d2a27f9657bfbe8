"""Scripted pick: the elastica oracle, or the honest controller that sees only the observation.

``--policy oracle`` (default) reads the episode's true box (width, mass,
friction) and solves the paper's Grip I (or III) problem for the gentlest
curvature that holds it with a friction safety factor of 2, ramps the
pneumatic command to it, lifts and holds.  ``--policy observation`` sees only
what a learned policy sees: it grips with one curvature for the whole
randomised range and curls further when it sees the box slip.  With
``--env simgrip/PickMulti-v0`` (K fingers around a box, cylinder or sphere) the
oracle is :class:`simgrip.envs.scripted_multi.ScriptedMultiPolicy`: the same
per-finger planar theory (an inclined contact on a sphere); the observation
policy is :class:`~simgrip.envs.scripted_multi.ObservationMultiPolicy` (the
theory's worst case over the randomised ranges, curling further on slip).

    python examples/scripted_pick.py [--episodes 20] [--seed 0] [--env simgrip/Pick-v1] [--fingers K]
                                     [--policy oracle|observation] [--json] [--gif pick.gif]

Prints one line per episode and a summary, or with ``--json`` only one JSON
object: ``{"episodes", "success_rate", "mean_return"}``.
"""

import argparse
import json
import sys

import gymnasium as gym

import simgrip.envs  # noqa: F401  (registers the simgrip ids)
from simgrip.command_parser import CommandParser
from simgrip.envs.evaluation import add_episode_arguments, check_env_id, env_kwargs, run_episodes, summary
from simgrip.envs.pick_multi import PickMultiEnv
from simgrip.envs.scripted import ObservationPickPolicy, ScriptedPickPolicy
from simgrip.envs.scripted_multi import ObservationMultiPolicy, ScriptedMultiPolicy
from simgrip.interrupt import run_main

POLICIES = {"oracle": ScriptedPickPolicy, "observation": ObservationPickPolicy}
MULTI_POLICIES = {"oracle": ScriptedMultiPolicy, "observation": ObservationMultiPolicy}


def main(argv=None):
    p = CommandParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_episode_arguments(p)
    p.add_argument("--policy", choices=sorted(POLICIES), default="oracle",
                   help="oracle (reads the true box or workpiece) or observation (sees only the observation)")
    p.add_argument("--gif", default=None, help="also write a GIF of the first episode (oracle policy)")
    args = p.parse_args(argv)
    check_env_id(p, args.env)

    env = gym.make(args.env, **env_kwargs(p, args))
    multi = isinstance(env.unwrapped, PickMultiEnv)  # K fingers: the per-finger theory's oracle
    if multi and args.gif:
        p.error(f"--env {args.env}: no --gif (two-finger ids only)")
    if args.gif is not None:  # simgrip.io's output-path policy, before any episode runs
        from simgrip.io import check_output_file

        try:
            check_output_file(args.gif, "--gif", create=False)
        except ValueError as exc:
            env.close()
            p.error(str(exc))
    policy = (MULTI_POLICIES if multi else POLICIES)[args.policy]()

    def line(r):
        box = env.unwrapped.workpiece if multi else env.unwrapped.box
        shape = f"{box.shape:8s} " if multi else ""
        print(f"episode {r.index:3d}: {shape}b={box.width * 100:.1f} cm  m={box.mass * 1000:.0f} g  mu={box.friction:.2f}  "
              f"kappa={policy.kappa:+.2f}  N={r.info['normal_force'].mean():.2f} N  return={r.ret:7.1f}  "
              f"{'success' if r.info['is_success'] else 'fail'}")

    results = run_episodes(env, policy, args.episodes, args.seed,
                           on_reset=lambda env_, info, seed: policy.reset(env_, info),
                           on_episode=None if args.json else line)
    env.close()
    out = {k: v for k, v in summary(results).items() if k != "mean_length"}
    if args.json:
        print(json.dumps(out))
    else:
        print(f"success rate {out['success_rate']:.0%} over {args.episodes} episodes, "
              f"mean return {out['mean_return']:.1f}")
    if args.gif:
        from simgrip.envs.rendering import render_pick_gif

        render_pick_gif(args.gif, seed=args.seed)
        print(f"wrote {args.gif}")
    return out


if __name__ == "__main__":
    sys.exit(run_main(main, "scripted_pick"))
