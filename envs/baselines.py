"""Non-learned baselines of the fragile pick tasks, one command each, written as JSON (issue 18).

``python -m simgrip.envs.baselines --env simgrip/PickFragile-v7 --policy constant --seeds 5000-5049 --out F.json``

``--env``: a registered fragile id (``simgrip.envs.FRAGILE_ENV_IDS``) or a retired one (``simgrip.envs.RETIRED``,
built through :func:`~simgrip.envs.retired_spec`: the stored JSONs of ``docs/baselines/`` name them).

Policies (actions ``(curvature command, palm speed)`` in ``[-1, 1]``; ``PlaceFragile-v0``:
``(curvature, palm x, palm z)``):

=============== ==============================================================================================
``random``      uniform actions, the action space seeded with the episode seed
``constant``    every action of a grid (``--grid``): curvature ``a_k`` in ``KAPPA_GRID``, palm ``a_p`` in
                ``PALM_GRID``, held for the whole episode; ``success_rate`` is the best of the grid *on the
                evaluated seeds themselves* (an optimistic bound for the family)
``openloop``    every schedule of the family "ramp the curvature command linearly from straight (+1; where a
                valve env starts it, ``PickFragile-v4``'s pre-grasp) to ``a_k``
                over ``R`` steps, hold it; palm still until ``R + 10`` steps, then up at ``a_p``", over the
                grid ``a_k`` x ``RAMP_GRID`` x ``PALM_GRID`` (best of the grid on the evaluated seeds)
``constant``    (``PlaceFragile-v0``: ``a_k`` x palm ``x`` command ``a_x`` in ``(-0.5, 0.5)``, palm ``z`` 0.5)
``openloop``    (``PlaceFragile-v0``: ramp (from straight, or a valve env's pre-grasp) to ``a_k`` over 25
                steps, lift 20 steps, carry at full speed to ``-x`` or ``+x`` over ``PLACE_DISTANCES``, lower
                20 steps; grid ``a_k`` x side x distance)
``openloop``    (``PickCradleFragile-v0``, ``PickSphereFragile-v0``: claw open while the palm moves for a
                fixed time to the scripted controller's grasp height for the mid-range workpiece, then ramp
                from the claw to ``a_k`` over ``R`` steps, wait 10, lift at ``a_p``; a constant action cannot
                lower the palm and then lift)
``openloop``    (``PickCradleFragile-v2``, ``PickSphereFragile-v2``: the env's ``openloop_grid``, the claw
                schedule above with the descent ``descent_shift`` steps longer or shorter, see
                :data:`simgrip.envs.pick_cradle_fragile_v2.OPENLOOP_GRID`)
``oracle``      :class:`~simgrip.envs.scripted_fragile.OracleFragilePolicy` (knows the hidden window; for
                ``PlaceFragile-v0``/``-v1`` inside :class:`~simgrip.envs.scripted_fragile.AbsolutePlacePolicy`,
                for a valve PlaceFragile inside :class:`~simgrip.envs.scripted_fragile.PlacePolicy`)
``observation`` :class:`~simgrip.envs.scripted_fragile.ObservationFragilePolicy` (the observation only;
                ``PlaceFragile-v0``/``-v1``: :class:`~simgrip.envs.scripted_fragile.AbsolutePlacePolicy`, a
                valve PlaceFragile: :class:`~simgrip.envs.scripted_fragile.PlacePolicy`;
                the cradle and the sphere: ``CLAW_POLICIES`` of :mod:`simgrip.envs.scripted_fragile`)
``constant``    (a valve env, :mod:`simgrip.envs.valve`: the curvature action is a rate, held it ramps the
                command to an end of its range: ``VALVE_GRID`` x ``PALM_GRID``)
``openloop``,   (a valve env: the absolute-command family or controller above, each step's command reached
``oracle``,     through the valve as fast as it allows, :func:`~simgrip.envs.valve.absolute_to_valve`)
``observation``
=============== ==============================================================================================

``--residual NAME ...`` (``constant`` and ``openloop`` only; the names: every action of the env but its curvature,
e.g. ``palm_x palm_z``) evaluates the grids behind :class:`~simgrip.envs.scripted_residual.ScriptedResidual`: the
scripted observation-only controller moves the palm, and the member commands the curvature alone, the palm's
residual 0 (what ``train_sb3.py --residual`` learns from, without the feedback): ``constant`` a valve rate of
``VALVE_GRID`` held (an absolute-command env: ``a_k`` of ``KAPPA_GRID``), ``openloop`` the command driven to
``a_k`` of ``KAPPA_GRID`` as fast as the valve allows and held.  The record adds ``residual``.

``--member JSON`` runs one member of a grid alone (recorded as ``member``): the member a record chose on its
seeds (its ``best``), evaluated on others, e.g. the pinch's open-loop member chosen on 6100–6149 on 1000 seeds
no test uses (``--policy openloop --member '{"kappa": 0.3, "ramp_steps": 50, "palm": 0.5}' --seeds
10000-10999``).

``--grid coarse`` uses every other curvature and one ramp/palm value (for tests).  Output: ``env``,
``policy``, ``seeds``, ``success_rate`` (the best member's for the grids), ``outcomes`` (counts of
success / crushed / dropped / knocked_over / timeout) and, for the grids, every member's success rate.
Exit 2 (one line) on a bad argument; Ctrl-C or SIGTERM: one line, exit 130, no file written.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter

import gymnasium as gym
import numpy as np

from simgrip.command_parser import CommandParser
from simgrip.envs.outcome import outcome
from simgrip.envs.scripted_policies import controller, policy_maker
from simgrip.envs.scripted_policies import task as _task
from simgrip.envs.scripted_policies import through_valve as _through_valve

__all__ = ["KAPPA_GRID", "PALM_GRID", "PLACE_DISTANCES", "RAMP_GRID", "VALVE_GRID", "evaluate", "main", "policy_maker",
           "run_policy"]

KAPPA_GRID = tuple(round(float(a), 2) for a in np.linspace(-1.0, 0.6, 17))  # 0.1 apart: force steps of ~0.3 N
PALM_GRID = (0.25, 0.5, 1.0)
RAMP_GRID = (1, 50)  # steps: 0.02 s, 1 s
PLACE_DISTANCES = (0.05, 0.08)  # [m] carried by the pick-and-place open-loop family
_WAIT = 10  # steps between the end of the ramp and the lift
#: a valve env's constant curvature actions (rates, :mod:`simgrip.envs.valve`): from full rate to the slowest
#: that still reaches first contact within the episode (0.07 x 0.02 x 300 steps = 0.42 of the ~0.5 travelled)
VALVE_GRID = (-1.0, -0.5, -0.3, -0.2, -0.15, -0.1, -0.07, 0.0)


def run_policy(env, make_act, seeds) -> Counter:
    """Outcomes of one policy over ``seeds``: ``make_act(env, info, seed)`` returns ``act(obs, t)``."""
    counts = Counter()
    for seed in seeds:
        obs, info = env.reset(seed=int(seed))
        act = make_act(env, info, int(seed))
        t = 0
        while True:
            obs, _, terminated, truncated, info = env.step(act(obs, t))
            t += 1
            if terminated or truncated:
                break
        counts[outcome(info)] += 1
    return counts


def _constant(*a):
    a = np.array(a, dtype=np.float32)
    return lambda env, info, seed: (lambda obs, t: a)


def _openloop(a_k, ramp, a_p):
    def make(env, info, seed):
        start = getattr(env.unwrapped, "valve_command", 1.0)  # straight (+1), or a valve env's pre-grasp

        def act(obs, t):
            k = start + (a_k - start) * min(1.0, (t + 1) / ramp)
            return np.array([k, a_p if t >= ramp + _WAIT else 0.0], dtype=np.float32)
        return act
    return make


def _place_openloop(a_k, side, distance):
    """Ramp the curvature to ``a_k`` over 25 steps, wait 10, lift at full speed for 20 steps (4 cm), move the
    palm ``side`` (+-1) at full speed for ``distance`` [m], lower at full speed for 20 steps, rest."""
    ramp, up = 25, 20
    t_move = ramp + _WAIT + up
    n_move = int(round(distance / 0.1 / 0.02))  # palm_speed 0.1 m/s, control step 0.02 s

    def make(env, info, seed):
        start = getattr(env.unwrapped, "valve_command", 1.0)  # straight (+1), or a valve env's pre-grasp

        def act(obs, t):
            k = start + (a_k - start) * min(1.0, (t + 1) / ramp)
            x = side if t_move <= t < t_move + n_move else 0.0
            z = 1.0 if ramp + _WAIT <= t < t_move else -1.0 if t_move + n_move <= t < t_move + n_move + up else 0.0
            return np.array([k, x, z], dtype=np.float32)
        return act
    return make


def _grasp_height(u, depth: float) -> float:
    """The scripted claw controllers' palm height [m] for the env's mid-range workpiece (its configuration, no
    observation): the cradle's box edge, or a sphere's centre, ``depth`` finger lengths below the palm."""
    if getattr(u, "grip", None) == "III":
        from simgrip.envs.pick_model import PEDESTAL_HEIGHT
        return PEDESTAL_HEIGHT + depth * u.length + u.r_tip
    return 0.25 * sum(u.size_range) + depth * u.length


def _claw_openloop(a_k, ramp, a_p, claw=0.68, depth=0.5, shift=0):
    """Cradle and sphere: claw open (``claw``), the palm moved at full speed for the steps that take a palm
    started mid-range (``palm_start``) to the scripted controller's grasp height for the mid-range workpiece
    (:func:`_grasp_height`) plus ``shift`` steps, ramp the curvature to ``a_k`` over ``ramp`` steps, wait, lift at
    ``a_p``."""
    def make(env, info, seed):
        u = env.unwrapped
        travel = _grasp_height(u, depth) - 0.5 * sum(u.palm_start)
        n_move, v = max(int(round(abs(travel) / (u.palm_speed * u.dt))) + shift, 0), float(np.sign(travel))

        def act(obs, t):
            if t < n_move:
                return np.array([claw, v], dtype=np.float32)
            k = claw + (a_k - claw) * min(1.0, (t - n_move + 1) / ramp)
            return np.array([k, a_p if t >= n_move + ramp + _WAIT else 0.0], dtype=np.float32)
        return act
    return make


def _random(env, info, seed):
    space = env.action_space
    space.seed(seed)
    return lambda obs, t: space.sample()


def _members(policy: str, grid: str, place: bool, claw: str | None = None, family_grid: dict | None = None,
             valve: bool = False, through_valve: bool = False):
    if valve and policy == "constant":  # a constant valve action: ramp at that rate (to an end of the range)
        rates = VALVE_GRID if grid == "full" else VALVE_GRID[::3]
        palms = PALM_GRID if grid == "full" else (0.5,)
        if place:
            xs = (-0.5, 0.5) if grid == "full" else (0.5,)
            return [({"kappa_rate_action": k, "palm_x": x, "palm": 0.5}, _constant(k, x, 0.5))
                    for k in rates for x in xs]
        return [({"kappa_rate_action": k, "palm": p}, _constant(k, p)) for k in rates for p in palms]
    if valve and policy != "random":  # the absolute-command families and controllers, through the valve
        return [(params, _through_valve(make))
                for params, make in _members(policy, grid, place, claw, family_grid, through_valve=True)]
    kappas = KAPPA_GRID if grid == "full" else KAPPA_GRID[::2]
    palms = PALM_GRID if grid == "full" else (0.5,)
    ramps = RAMP_GRID if grid == "full" else (25,)
    if place and policy == "constant":  # (curvature, palm x, palm z)
        xs = (-0.5, 0.5) if grid == "full" else (0.5,)  # a constant palm z never sets the workpiece down
        return [({"kappa": k, "palm_x": x, "palm": 0.5}, _constant(k, x, 0.5)) for k in kappas for x in xs]
    if place and policy == "openloop":
        dists = PLACE_DISTANCES if grid == "full" else (0.07,)
        return [({"kappa": k, "side": sd, "distance": dd}, _place_openloop(k, sd, dd))
                for k in kappas for sd in (-1.0, 1.0) for dd in dists]
    if policy == "constant":
        return [({"kappa": k, "palm": p}, _constant(k, p)) for k in kappas for p in palms]
    if policy == "openloop" and family_grid:  # an env's own claw family (v2: the descent time shifted too)
        g = {k: (v if grid == "full" else v[len(v) // 2:len(v) // 2 + 1]) for k, v in family_grid.items()}
        return [({"kappa": k, "ramp_steps": r, "palm": p, "descent_shift": d}, _claw_openloop(k, r, p, shift=d))
                for k in g["kappa"] for r in g["ramp_steps"] for p in g["palm"] for d in g["descent_shift"]]
    if policy == "openloop":
        family = _claw_openloop if claw else _openloop
        return [({"kappa": k, "ramp_steps": r, "palm": p}, family(k, r, p))
                for k in kappas for r in ramps for p in palms]
    if policy == "random":
        return [({}, _random)]
    return [({}, controller(policy, place, claw, through_valve))]


def _curvature_only(value):
    """``make`` of a policy that commands every curvature channel ``value(unwrapped_env)`` and the rest 0."""
    def make(env, info, seed):
        u = env.unwrapped
        curv = np.array([not n.startswith("palm") for n in u.action_names])
        a = np.zeros(env.action_space.shape, dtype=np.float32)

        def act(obs, t):
            a[curv] = value(u)
            return a.copy()
        return act
    return make


def _residual_members(policy: str, grid: str, valve: bool) -> list:
    """The curvature-only members behind ``--residual`` (module docstring)."""
    from simgrip.envs.valve import absolute_to_valve

    kappas = KAPPA_GRID if grid == "full" else KAPPA_GRID[::2]
    if policy == "constant" and valve:
        rates = VALVE_GRID if grid == "full" else VALVE_GRID[::3]
        return [({"kappa_rate_action": k}, _curvature_only(lambda u, k=k: k)) for k in rates]
    if policy == "constant" or not valve:
        return [({"kappa": k}, _curvature_only(lambda u, k=k: k)) for k in kappas]
    return [({"kappa": k}, _curvature_only(lambda u, k=k: absolute_to_valve(k, u.valve_command, u.kappa_rate)))
            for k in kappas]


def _behind_residual(env, policy: str, residual):
    """``env`` behind ``ScriptedResidual(env, residual)``; ValueError naming ``--residual`` when ``policy`` is not
    ``constant``/``openloop`` or ``residual`` does not name every action but the curvature."""
    from simgrip.envs.scripted_residual import ScriptedResidual

    if policy not in ("constant", "openloop"):
        raise ValueError(f"--residual: constant and openloop only, not {policy!r} (the controller alone is "
                         "--policy observation)")
    palm = [n for n in getattr(env.unwrapped, "action_names", ()) if n.startswith("palm")]
    if sorted(residual) != sorted(palm):
        raise ValueError(f"--residual: every palm action of the env ({' '.join(palm)}), got {' '.join(residual)}")
    try:
        return ScriptedResidual(env, residual)
    except ValueError as e:
        raise ValueError(f"--residual: {e}") from None


def evaluate(env_id: str, policy: str, seeds, grid: str = "full", residual=None, env_kwargs=None,
             member=None) -> dict:
    """Run ``policy`` on ``env_id`` (``gym.make``, its registered time limit; a retired id of
    ``simgrip.envs.RETIRED`` through :func:`~simgrip.envs.retired_spec`, its time limit as it was registered)
    over ``seeds``, behind the scripted palm where ``residual`` names its actions (module docstring), the env
    made with ``env_kwargs`` (``gym.make``'s keywords, recorded as ``env_kwargs`` when given); the JSON record.
    ``member``, a dict of one grid member's parameters (a record's ``best``, without ``success_rate``), runs that
    member alone (recorded as ``member``): a member tuned on some seeds, evaluated on others.
    ValueError naming ``--residual`` or ``--member`` (the env closed first) or, from the env, the keyword."""
    from simgrip.envs import make_spec

    env = gym.make(make_spec(env_id), **dict(env_kwargs or {}))
    try:
        if residual is not None:
            members = _residual_members(policy, grid, _task(env)[3])
            env = _behind_residual(env, policy, residual)
        else:
            members = _members(policy, grid, *_task(env))
        if member is not None:
            members = _the_member(members, member)
        rows = []
        for params, make in members:
            counts = run_policy(env, make, seeds)
            rows.append({**params, "success_rate": counts["success"] / len(seeds), "outcomes": dict(counts)})
    finally:
        env.close()
    best = max(rows, key=lambda r: r["success_rate"])
    out = {"env": env_id, "policy": policy, "seeds": [int(seeds[0]), int(seeds[-1])], "episodes": len(seeds),
           "success_rate": best["success_rate"], "outcomes": best["outcomes"]}
    if member is not None:
        out["member"] = {k: v for k, v in best.items() if k not in ("success_rate", "outcomes")}
    if residual is not None:
        out["residual"] = list(residual)
    if env_kwargs:
        out["env_kwargs"] = dict(env_kwargs)
    if len(rows) > 1:
        out.update({"grid": grid, "best": {k: v for k, v in best.items() if k != "outcomes"}, "members": rows})
    return out


def _the_member(members: list, member: dict) -> list:
    """The one ``(params, make)`` of ``members`` whose parameters are ``member``'s (every key, equal values)."""
    keys = sorted(members[0][0]) if members else []
    if not isinstance(member, dict) or sorted(member) != keys:
        raise ValueError(f"--member must name this grid's parameters {keys}, got {member!r}")
    found = [(p, make) for p, make in members if all(p[k] == member[k] for k in keys)]
    if not found:
        raise ValueError(f"--member {json.dumps(member)} is not a member of the grid (--grid, --policy)")
    return found[:1]


def _seeds(text: str) -> list[int]:
    try:
        lo, _, hi = text.partition("-")
        lo, hi = int(lo), int(hi or lo)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--seeds must be A-B (integers), got {text!r}") from None
    if lo < 0 or hi < lo:
        raise argparse.ArgumentTypeError(f"--seeds must be A-B with 0 <= A <= B, got {text!r}")
    from simgrip.envs.evaluation import MAX_EPISODES

    if hi - lo + 1 > MAX_EPISODES:
        raise argparse.ArgumentTypeError(f"at most {MAX_EPISODES} seeds (one episode each), got {text!r}")
    return list(range(lo, hi + 1))


def _json_object(text: str) -> dict:
    from simgrip.envs.evaluation import json_object  # (imported when used, as the other helpers)

    return json_object(text)


def main(argv=None) -> int:
    """The command line; returns the exit status (2 on a bad argument)."""
    import simgrip.envs  # noqa: F401  (registers the ids)
    from simgrip.envs import FRAGILE_ENV_IDS, RETIRED
    from simgrip.io import atomic_write, check_output_file

    p = CommandParser(prog="python -m simgrip.envs.baselines", description=__doc__.splitlines()[0])
    # the retired ids too: the stored JSONs of docs/baselines/ were written with them
    p.add_argument("--env", required=True, choices=FRAGILE_ENV_IDS + tuple(RETIRED), metavar="ID",
                   help="a fragile pick id: " + ", ".join(FRAGILE_ENV_IDS) + ", or a retired one (simgrip.envs.RETIRED)")
    p.add_argument("--policy", required=True, choices=("random", "constant", "openloop", "oracle", "observation"))
    p.add_argument("--seeds", type=_seeds, default=_seeds("5000-5049"), help="A-B, inclusive (default 5000-5049)")
    p.add_argument("--grid", choices=("full", "coarse"), default="full")
    p.add_argument("--residual", nargs="+", default=None, metavar="NAME",
                   help="constant/openloop: the palm actions the scripted controller drives, the member the "
                        "curvature alone (simgrip.envs.scripted_residual)")
    p.add_argument("--member", type=_json_object, default=None, metavar="JSON",
                   help="constant/openloop: run this member of the grid alone, e.g. a record's best chosen on other "
                        "seeds ('{\"kappa\": 0.3, \"ramp_steps\": 50, \"palm\": 0.5}')")
    p.add_argument("--env-kwargs", type=_json_object, default=None, metavar="JSON",
                   help="gym.make's keyword arguments, a JSON object ('{\"crush_at\": \"end\"}')")
    p.add_argument("--out", help="JSON file (default: stdout)")
    args = p.parse_args(argv)
    if args.out is not None:
        try:
            check_output_file(args.out, "--out")
        except (ValueError, OSError) as e:
            p.error(str(e))
    try:
        record = evaluate(args.env, args.policy, args.seeds, args.grid, args.residual, args.env_kwargs, args.member)
    except ValueError as e:
        ours = str(e).startswith(("--residual", "--member"))
        if not ours and not args.env_kwargs:
            raise
        p.error(str(e) if ours else f"--env-kwargs: {e}")
    except Exception as e:  # a keyword the env does not take, or a setting the controllers do not drive
        if not args.env_kwargs:  # (per_finger: three actions, read as the place's; render_mode "human": no display)
            raise
        p.error(f"--env-kwargs: {type(e).__name__}: {e} (with {json.dumps(args.env_kwargs)})")
    text = json.dumps(record, indent=1) + "\n"
    if args.out is not None:
        with atomic_write(args.out, "w", option="--out") as f:
            f.write(text)
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    from simgrip.interrupt import run_main

    sys.exit(run_main(main, "baselines"))
