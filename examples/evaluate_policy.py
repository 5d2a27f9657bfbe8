"""How a policy's episodes end, and what they are worth to a learner that discounts.

Runs a trained Stable-Baselines3 model (``--model ppo_model.zip``, deterministic, as ``train_sb3.py``'s
held-out evaluation runs it) or one of the fragile tasks' scripted controllers (``--policy observation`` or
``oracle``, :mod:`simgrip.envs.baselines`) on episodes seeded ``--seed``, ``--seed + 1``, ... and prints how they
ended (success, crushed, dropped, knocked over, timeout), how long the successes took, and the mean return
discounted by ``--gamma`` (default 0.99, SB3's default): the quantity PPO and SAC maximise.  A learner that
settles below a controller's success rate while its discounted return is above the controller's is not failing
to optimise: under that discount, its faster and riskier policy is worth more.

    python examples/evaluate_policy.py --env simgrip/PickFragile-v7 (--model ZIP [--algo ppo|sac] |
        --policy observation|oracle) [--action-offset A0 A1] [--frame-stack N] [--residual NAME ... [--residual-alone]]
        [--valve-share S] [--touch-memory] [--privileged-critic] [--scripted-start P] [--env-kwargs JSON]
        [--episodes 50] [--seed 8000] [--gamma 0.99] [--crush-charge F ...] [--json]

``--action-offset``, ``--frame-stack``, ``--residual``, ``--residual-alone``, ``--valve-share``, ``--touch-memory``
and ``--privileged-critic`` must be the ones the model was trained with (``train_sb3.py``'s options of those names);
a model trained behind ``VecNormalize`` is not supported here.  Prints one line, or with ``--json`` one JSON
object: ``{"env", "policy", "episodes", "success_rate", "mean_return", "mean_length", "outcomes",
"mean_success_length", "mean_discounted_return", "gamma", "eval_seeds"}``.  Exit 2 naming the option on bad
input; Ctrl-C or SIGTERM: one line, exit 130.

``--scripted-start P`` (with ``--model``) starts that share of the episodes part-way through the scripted
observation-only controller's episode (:class:`simgrip.envs.scripted_start.ScriptedStart`, as
``train_sb3.py --scripted-start`` trains): where a policy trained so has got to.  The JSON then adds
``by_handover``: the outcomes counted per 50 steps of the handover step (``"0-49"``: the plain starts and the
early handovers, ``"50-99"``, ...).

On the pick-and-place the JSON also has ``place_timeouts``: ``{"held_up", "over_target"}``, how many episodes
ran out of time with the workpiece carried and still up (more than 3 mm above its start), and how many of those
held it within the place tolerance of the target: a learner that carries and never sets down.  And
``carried``: ``{"episodes", "outcomes"}``, the episodes that carried the workpiece at some step (lifted the carry
height with both fingers on it: ``info["carried"]`` at the episode's end) and how each of them ended: a grip that
lifts and then fails in the carry (crushed or dropped after the carry began) against one that never lifts.

On a fragile task the JSON also has ``by_mass``: the outcomes counted per third of the task's log mass range
(the hidden mass of each episode; keys ``"5-18 g"``, ...; :func:`simgrip.envs.light_bias.mass_bins`): which
workpieces a policy loses (a fast closing crushes the lightest).  And ``crushed_after_touch``: the crushed episodes
counted by the control steps from the first step any finger pressed on the workpiece (``info["normal_force"]``,
or ``info["peak_normal_force"]`` where the crush rule reads the peak, above 0) to the crush (keys ``"0"``: crushed within the step of the first touch, before the policy could answer
it; ``"1-4"``, ``"5-24"``, ``"25+"``): a crush on touch is the approach's speed, a later one the squeeze.
And ``crush_overrun``: over the crushed episodes, the median and largest relative overrun ``x = (F - L) / L`` of
the crushing step's largest finger force ``F`` over the episode's hidden limit ``L`` (``None`` without a crush):
what a crush charge graded by ``x`` (the fragile tasks' ``w_crush x / (1 + x)``) charges them.
And ``first_touch``: ``{"touches", "read", "end", "above_limit"}``, over the episodes that touched, the median and
largest ratio to the hidden limit of the first touch's step's largest finger force as the crush rule reads it
(``"read"``: :func:`crush_force`, the peak within the step where the env reads it) and at the step's end
(``"end"``, ``info["normal_force"]``), and how many read above the limit: an impact's transient at the touch (the
peak far above the end) against a grip pressed too hard.
And ``crush_weight``: the mean over the episodes of ``gamma ** (n - 1)`` for each crushed episode of ``n`` steps
(0 for the others), what a flat charge of 1 on every crush would take off ``mean_discounted_return``
(:func:`crush_weight`); ``--crush-charge F [F ...]`` adds ``crush_charged_return``, ``{"F":
mean_discounted_return - F * crush_weight}``: what the policy would be worth to the learner were each crush
charged ``F`` more, so two policies' worth can be compared under a charge no env has (two policies with returns
``R_a > R_b`` and weights ``w_a > w_b`` are worth the same at ``F = (R_a - R_b) / (w_a - w_b)``).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import signal
import statistics
import sys

if __name__ == "__main__":  # a Ctrl-C while the modules below load: main's one line and 130 (run_main)
    signal.signal(signal.SIGINT, lambda signum, frame: (os.write(2, b"evaluate_policy: interrupted\n"), os._exit(130)))

import simgrip.envs  # noqa: E402,F401  (registers the simgrip ids)
from simgrip.command_parser import CommandParser
from simgrip.envs.env_options import EnvOptions, make_env
from simgrip.envs.evaluation import (charge, check_env_id, discount, episode_count, json_object, non_negative_int,
                                     outcomes, positive_int, probability, run_episodes, share, summary)
from simgrip.envs.light_bias import episode_mass, mass_bins
from simgrip.envs.outcome import outcome

SCRIPTED = ("observation", "oracle")
HANDOVER_BIN = 50  # env steps per bin of by_handover (1 s at the fragile tasks' 50 Hz)
#: crushed_after_touch's bins: (key, least, most) control steps from the first touch to the crush
TOUCH_BINS = (("0", 0, 0), ("1-4", 1, 4), ("5-24", 5, 24), ("25+", 25, math.inf))


def _scripted(env, name: str):
    """``(act, on_reset)`` of the fragile task's scripted controller ``name`` (through the valve where the env
    has one), as :mod:`simgrip.envs.baselines` runs it."""
    from simgrip.envs.baselines import policy_maker

    make = policy_maker(env, name)
    state = {}

    def on_reset(env_, info, seed):
        state["act"], state["t"] = make(env_, info, seed), 0

    def act(obs):
        a = state["act"](obs, state["t"])
        state["t"] += 1
        return a
    return act, on_reset


def by_handover(results, handovers, width: int = HANDOVER_BIN) -> dict:
    """Outcome counts per ``width`` steps of the handover step (``handovers[i]``: episode ``i``'s
    ``scripted_steps``), keyed ``"lo-hi"`` in increasing order (each bin counted by :func:`outcomes`)."""
    bins: dict[int, list] = {}
    for r, k in zip(results, handovers):
        bins.setdefault(int(k) // width, []).append(r)
    return {f"{b * width}-{b * width + width - 1}": outcomes(rs)["outcomes"] for b, rs in sorted(bins.items())}


def by_mass(results, masses, edges) -> dict:
    """Outcome counts per mass bin (``masses[i]``: episode ``i``'s mass [kg]; ``edges``: increasing bin edges
    [kg], the last bin closed), keyed ``"lo-hi g"`` in increasing order (each bin counted by :func:`outcomes`;
    empty bins kept, as ``{}``)."""
    bins: list[list] = [[] for _ in edges[:-1]]
    for r, m in zip(results, masses):
        i = next((j for j in range(len(edges) - 2) if m < edges[j + 1]), len(edges) - 2)
        bins[i].append(r)
    return {f"{edges[i] * 1e3:.0f}-{edges[i + 1] * 1e3:.0f} g": outcomes(rs)["outcomes"] if rs else {}
            for i, rs in enumerate(bins)}


def crushed_after_touch(results, touch_steps) -> dict:
    """The crushed episodes counted per :data:`TOUCH_BINS` bin of the control steps from the first touch to the
    crush (``touch_steps[i]``: the 1-based step of episode ``i`` whose force (:func:`crush_force`) was first above 0,
    ``None`` if none; the crush is the episode's last step), keyed ``"0"``, ``"1-4"``, ``"5-24"``, ``"25+"`` (every
    bin kept, 0 where empty)."""
    counts = dict.fromkeys((key for key, _, _ in TOUCH_BINS), 0)
    for r, touch in zip(results, touch_steps):
        if outcome(r.info) == "crushed":
            gap = r.length - touch if touch is not None else 0  # (a crush is a touch: None cannot occur)
            counts[next(key for key, lo, hi in TOUCH_BINS if lo <= gap <= hi)] += 1
    return counts


def first_touch(ratios) -> dict | None:
    """``{"touches", "read", "end", "above_limit"}`` of the first touches' force ratios (``ratios[i]``: episode
    ``i``'s ``(read, end)``, its first touch's step's largest :func:`crush_force` and largest ``normal_force`` over
    its ``crush_limit``, ``None`` if it never touched): ``"read"`` and ``"end"`` as ``{"median", "max"}``,
    ``"above_limit"`` the touches whose read ratio exceeds 1 (each a crush in the touch's step); ``None`` when no
    episode touched."""
    pairs = [r for r in ratios if r is not None]
    if not pairs:
        return None
    stats = lambda xs: {"median": float(statistics.median(xs)), "max": float(max(xs))}  # noqa: E731
    return {"touches": len(pairs), "read": stats([r for r, _ in pairs]), "end": stats([e for _, e in pairs]),
            "above_limit": sum(bool(r > 1.0) for r, _ in pairs)}


def crush_force(info) -> list:
    """Each finger's force the crush rule read in a step's ``info`` [N]: ``peak_normal_force`` (the largest within
    the step) where the env reads the peak (``crush_at="peak"``), else ``normal_force`` (the step's end)."""
    return info.get("peak_normal_force", info["normal_force"])


def crush_overrun(results) -> dict | None:
    """``{"crushes", "median", "max"}`` of the relative overrun ``(F - L) / L`` over the crushed episodes: ``F``
    the largest of the last step's :func:`crush_force` [N] (the crushing step's), ``L`` its
    ``info["crush_limit"]`` [N]; ``None`` when no episode was crushed."""
    from simgrip.envs.pick_fragile_v1 import crush_overrun as overrun  # the charge's own x

    x = [overrun(max(crush_force(r.info)), r.info["crush_limit"]) for r in results if outcome(r.info) == "crushed"]
    return {"crushes": len(x), "median": statistics.median(x), "max": max(x)} if x else None


def crush_weight(results, gamma: float) -> float:
    """What one unit of a flat charge on each crush takes off the mean discounted return: the mean over the
    episodes of ``gamma ** (n - 1)`` for a crushed episode of ``n`` steps (the crush is its last step, and the
    charge is paid there as that step's reward, discounted as :func:`~simgrip.envs.evaluation.run_episodes`
    discounts it), 0 for the others.  A flat charge ``F`` on top of the env's own crush penalty makes the mean
    discounted return ``mean_discounted_return - F * crush_weight``."""
    w = [gamma ** (r.length - 1) if outcome(r.info) == "crushed" else 0.0 for r in results]
    return sum(w) / len(w) if w else 0.0


def place_timeouts(results, place_tolerance: float, on_table: float) -> dict:
    """The pick-and-place's timed-out episodes that carried the workpiece and never set it down:
    ``{"held_up": n, "over_target": m}``, ``n`` those that end with it carried and more than ``on_table`` [m]
    above its start (not lost: a timeout), ``m`` of them within ``place_tolerance`` [m] of the target."""
    up = [r for r in results if outcome(r.info) == "timeout" and r.info.get("carried")
          and r.info["workpiece_lift"] > on_table]
    return {"held_up": len(up), "over_target": sum(r.info["place_error"] <= place_tolerance for r in up)}


def carried(results) -> dict:
    """The pick-and-place's episodes that carried the workpiece at some step (``info["carried"]`` at the end:
    it stays set once the workpiece was lifted the carry height with both fingers on it): ``{"episodes": n,
    "outcomes": {outcome: count}}`` over them."""
    rs = [r for r in results if r.info.get("carried")]
    return {"episodes": len(rs), "outcomes": outcomes(rs)["outcomes"] if rs else {}}


def main(argv=None) -> dict:
    p = CommandParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--env", required=True, help="registered env id, e.g. simgrip/PickFragile-v7, or a retired "
                   "simgrip one (simgrip.envs.RETIRED: the models of docs/baselines/ were trained on them)")
    p.add_argument("--env-kwargs", type=json_object, default={}, metavar="JSON",
                   help="keyword arguments of gym.make, as the model was trained with")
    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument("--model", help="a Stable-Baselines3 model file (train_sb3.py's <algo>_model*.zip)")
    what.add_argument("--policy", choices=SCRIPTED, help="a fragile task's scripted controller")
    p.add_argument("--algo", choices=("ppo", "sac"), default="ppo", help="the model's algorithm (default ppo)")
    p.add_argument("--action-offset", type=float, nargs="+", default=None, metavar="A",
                   help="the ActionOffset the model was trained behind")
    p.add_argument("--frame-stack", type=positive_int, default=None, metavar="N",
                   help="the observations stacked when the model was trained (train_sb3.py's --frame-stack)")
    p.add_argument("--residual", nargs="+", default=None, metavar="NAME",
                   help="with --model: the ScriptedResidual the model was trained behind (train_sb3.py's --residual)")
    p.add_argument("--residual-alone", action="store_true",
                   help="with --residual: the controller drove those actions alone (train_sb3.py's --residual-alone)")
    p.add_argument("--valve-share", type=share, default=None, metavar="S",
                   help="with --model: the ValveShare restrictor the model was trained behind (train_sb3.py's "
                        "--valve-share)")
    p.add_argument("--touch-memory", action="store_true",
                   help="with --model: the model observed the first touch's memory (train_sb3.py's --touch-memory)")
    p.add_argument("--privileged-critic", action="store_true",
                   help="with --model: the model's critic read the hidden workpiece (train_sb3.py's "
                        "--privileged-critic; its policy ignores those entries)")
    p.add_argument("--scripted-start", type=probability, default=None, metavar="P",
                   help="with --model: start that share of the episodes part-way through the scripted "
                        "observation-only controller's (simgrip.envs.scripted_start); adds by_handover")
    p.add_argument("--episodes", type=episode_count, default=50, help="episodes (default 50, at most 100000)")
    p.add_argument("--seed", type=non_negative_int, default=8000, help="seed of the first episode (default 8000)")
    p.add_argument("--gamma", type=discount, default=0.99, help="discount of the reported return (default 0.99)")
    p.add_argument("--crush-charge", type=charge, nargs="+", default=None, metavar="F",
                   help="also report the mean discounted return with a flat charge F added to each crush "
                        "(crush_charged_return; a fragile task only)")
    p.add_argument("--json", action="store_true", help="print only a JSON object")
    args = p.parse_args(argv)
    check_env_id(p, args.env, retired=True)  # make_env builds a retired one through its spec
    for name, why in (("action_offset", "the scripted controllers command the env directly"),
                      ("scripted_start", "a scripted controller started part-way is not itself"),
                      ("residual", "the scripted controller alone is --policy observation"),
                      ("valve_share", "the scripted controllers command the valve at its own rate"),
                      ("privileged_critic", "the scripted controllers read the env's own observation"),
                      ("touch_memory", "the scripted controllers read the env's own observation"),
                      ("frame_stack", "the scripted controllers read the env's own observation")):
        value = getattr(args, name)  # a trained policy's option (None or False: not given), not a controller's
        if args.policy is not None and value is not None and value is not False:
            p.error(f"--{name.replace('_', '-')}: only with --model ({why})")
    if args.model is not None:
        import os

        if not os.path.isfile(args.model):
            p.error(f"--model: {args.model!r} is not a file")
    try:
        # (its --crush-charge scores the episodes: not the training wrapper of that name)
        env = make_env(args.env, EnvOptions(env_kwargs=args.env_kwargs or {}, action_offset=args.action_offset,
                                            frame_stack=args.frame_stack, residual=args.residual,
                                            residual_alone=args.residual_alone, valve_share=args.valve_share,
                                            touch_memory=args.touch_memory,
                                            privileged_critic=args.privileged_critic,
                                            scripted_start=args.scripted_start))
    except ValueError as exc:
        p.error(str(exc))
    handovers: list[int] = []
    masses: list[float] = []
    touches: list[int | None] = []  # per episode: the first step with a finger force (crushed_after_touch)
    touch_ratios: list[tuple[float, float] | None] = []  # per episode: its first touch's forces over the limit
    edges = mass_bins(env)
    if args.crush_charge is not None and edges is None:
        env.close()
        p.error(f"--crush-charge: {args.env} has no crush (a fragile task only)")
    try:
        on_reset = None
        if args.model is not None:
            try:
                from stable_baselines3 import PPO, SAC
            except ImportError:
                p.error("--model: needs Stable-Baselines3 (pip install 'simgrip[rl]')")
            try:
                model = {"ppo": PPO, "sac": SAC}[args.algo].load(args.model, device="cpu")
            except Exception as exc:  # noqa: BLE001 - any unreadable model is a bad --model
                p.error(f"--model: cannot load {args.model!r} as {args.algo}: {exc}")
            if model.observation_space.shape != env.observation_space.shape or (
                    model.action_space.shape != env.action_space.shape):
                p.error(f"--model: its spaces do not match {args.env}'s "
                        "(trained with another --frame-stack, --residual, --touch-memory or --privileged-critic?)")
            act = lambda obs: model.predict(obs, deterministic=True)[0]  # noqa: E731
            policy = f"{args.algo} {args.model}"
            if args.scripted_start is not None:
                on_reset = lambda env_, info, seed: handovers.append(info["scripted_steps"])  # noqa: E731
        else:
            try:
                act, on_reset = _scripted(env, args.policy)
            except ValueError as exc:
                p.error(f"--policy: {exc}")
            policy = args.policy
        def on_reset_and_mass(env_, info, seed, then=on_reset):
            masses.append(episode_mass(env_))
            touches.append(None)
            touch_ratios.append(None)
            if then is not None:
                then(env_, info, seed)

        def on_step(info, n):
            if touches[-1] is None and "normal_force" in info and (read := max(crush_force(info))) > 0.0:
                touches[-1] = n
                if "crush_limit" in info:
                    limit = info["crush_limit"]
                    touch_ratios[-1] = (read / limit, max(info["normal_force"]) / limit)

        results = run_episodes(env, act, args.episodes, args.seed, on_reset=on_reset_and_mass, on_step=on_step,
                               gamma=args.gamma)
    finally:
        env.close()
    out = {"env": args.env, "policy": policy, **summary(results), **outcomes(results, args.gamma),
           "eval_seeds": [args.seed, args.seed + args.episodes - 1]}
    if args.residual is not None:
        out["residual"] = list(args.residual)
        if args.residual_alone:
            out["residual_alone"] = True
    if args.valve_share is not None:
        out["valve_share"] = args.valve_share
    if args.touch_memory:
        out["touch_memory"] = True
    if args.privileged_critic:
        out["privileged_critic"] = True
    if args.scripted_start is not None:
        out["scripted_start"] = args.scripted_start
        out["by_handover"] = by_handover(results, handovers)
    if edges is not None:
        out["by_mass"] = by_mass(results, masses, edges)
        out["crushed_after_touch"] = crushed_after_touch(results, touches)
        out["first_touch"] = first_touch(touch_ratios)
        out["crush_overrun"] = crush_overrun(results)
        out["crush_weight"] = w = crush_weight(results, args.gamma)
        if args.crush_charge is not None:
            out["crush_charged_return"] = {f"{F:g}": out["mean_discounted_return"] - F * w for F in args.crush_charge}
    if hasattr(env.unwrapped, "place_tolerance"):  # the pick-and-place: carried, then held up to the end?
        from simgrip.envs.pick_place import ON_TABLE

        out["place_timeouts"] = place_timeouts(results, env.unwrapped.place_tolerance, ON_TABLE)
        out["carried"] = carried(results)
    if args.json:
        print(json.dumps(out))
    else:
        length = out["mean_success_length"]
        print(f"{policy}: success {out['success_rate']:.0%} of {out['episodes']} ({out['outcomes']}), successes end at "
              f"step {'-' if length is None else f'{length:.0f}'} on average, mean return {out['mean_return']:.2f}, "
              f"discounted (gamma {args.gamma:g}) {out['mean_discounted_return']:.2f}")
    return out


if __name__ == "__main__":
    from simgrip.interrupt import run_main

    sys.exit(run_main(main, "evaluate_policy"))
