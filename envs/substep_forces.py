"""The fingers' normal forces within a control step, against the value at its end that the env reads.

A fragile env reads each finger's normal force once per control step, after its ``frame_skip`` physics steps:
the tactile observation and the crush rule (``info["crushed"]``: a force above ``crush_limit``) see that
value only.  :func:`step_with_peaks` runs one ``env.step`` and then replays the same control step one physics
step at a time from the state it started in (with the rest angles and ``ctrl`` the step wrote, as
:mod:`simgrip.envs.throughput` replays it; the replay must end in the env's own end state, checked), reading
every finger's normal force after each physics step: its largest value within the step.

:func:`force_peaks` runs the task's scripted controller over episodes and reports how far the peaks rise
above the end-of-step values, how many steps had a peak above the crush limit that the rule did not see, and
how many successes had one.  Measured (``docs/environments.md``, "Forces within a control step")::

    python -m simgrip.envs.substep_forces --env simgrip/PickSphereFragile-v5 --seeds 8000-8049
    python -m simgrip.envs.substep_forces --env simgrip/PickSphereFragile-v5 --seeds 8000-8049 --palm-ramp

(the ids then registered, retired since by the versions that ramp the palm and read the peak,
:mod:`simgrip.envs.pick_fragile_v7`; a retired id is made through :func:`simgrip.envs.retired_spec`).
"""

from __future__ import annotations

import json
import math
import sys

import mujoco
import numpy as np

from simgrip.command_parser import CommandParser

__all__ = ["force_peaks", "step_with_peaks"]

#: a step's peak / end ratio is counted where the end value is at least this share of the crush limit (below it
#: the ratio of two small forces says nothing)
MIN_SHARE = 0.05


def _normals(u, m, d) -> list:
    """Each finger's summed normal force on the workpiece [N] in ``d`` (the env's own reader)."""
    if hasattr(u, "_contact_forces"):  # the two-finger pinch, cradle and place: [n0, t0, n1, t1, s0, s1]
        f = u._contact_forces(m, d)
        return [f[0], f[2]]
    return list(u._forces(d)[0])  # the K-finger envs: (normal, friction, side), one entry per finger


def step_with_peaks(env, action) -> tuple:
    """``env.step(action)``'s five results and each finger's largest normal force within the step [N] (a list).

    ``env`` is a registered pick env (any wrapper; its ``unwrapped`` is stepped through the wrapper).  Raises
    RuntimeError when the replay does not end in the env's end state (the replay would not be that step)."""
    u = env.unwrapped
    m, d = u.model, u.data
    kind = mujoco.mjtState.mjSTATE_INTEGRATION
    start = np.empty(mujoco.mj_stateSize(m, kind))
    mujoco.mj_getState(m, d, start, kind)
    out = env.step(action)
    if u.model is not m:  # (a K-finger env changes models only at reset)
        raise RuntimeError("the env changed its model within a step")
    end = np.empty_like(start)
    mujoco.mj_getState(m, d, end, kind)
    ctrl = d.ctrl.copy()  # what the step wrote (the state below holds the ctrl before it)
    mujoco.mj_setState(m, d, start, kind)  # (the rest angles, model parameters, stay as the step wrote them)
    d.ctrl[:] = ctrl
    peaks = None
    for _ in range(u.frame_skip):
        mujoco.mj_step(m, d)
        f = _normals(u, m, d)
        peaks = f if peaks is None else [max(a, b) for a, b in zip(peaks, f)]
    replayed = np.empty_like(start)
    mujoco.mj_getState(m, d, replayed, kind)
    if not np.array_equal(replayed, end):
        raise RuntimeError(f"the replay left the env's step by {float(np.max(np.abs(replayed - end))):.3g}")
    mujoco.mj_forward(m, d)  # (the end state's derived quantities, as the step left them)
    return (*out, peaks)


def force_peaks(env_id: str, seeds, *, policy: str = "observation", env_kwargs=None) -> dict:
    """Within-step force peaks under the task's scripted ``policy`` (``"observation"`` or ``"oracle"``) over the
    episodes ``seeds``.

    Returns a dict: ``steps`` (steps with an end force of at least :data:`MIN_SHARE` of the crush limit),
    ``ratio_median``, ``ratio_p95``, ``ratio_max`` (the largest finger's peak over its end value),
    ``unseen_steps`` (steps whose peak crossed the crush limit while the end value did not: the rule saw no
    crush), ``outcomes`` (how the episodes ended), ``unseen_successes`` (successes with such a step: a crush
    under a rule that reads the peak), ``env``, ``policy``, ``seeds``, ``env_kwargs``, ``crush_at``.  On an env
    whose rule reads the peak (``crush_at="peak"``, the registered fragile ids) such a step is a crush, so
    ``unseen_steps`` and ``unseen_successes`` are None."""
    import gymnasium as gym

    import simgrip.envs  # noqa: F401  (registers the ids)
    from simgrip.envs.outcome import outcome
    from simgrip.envs.scripted_policies import policy_maker

    from simgrip.envs import make_spec

    env = gym.make(make_spec(env_id), **dict(env_kwargs or {}))
    try:
        make = policy_maker(env, policy)
        ratios, unseen, ends, unseen_ok = [], 0, {}, 0
        for seed in seeds:
            obs, info = env.reset(seed=int(seed))
            act = make(env, info, int(seed))
            t, crossed = 0, False
            while True:
                obs, _, term, trunc, info, peaks = step_with_peaks(env, act(obs, t))
                t += 1
                limit, end = float(info["crush_limit"]), [float(v) for v in info["normal_force"]]
                if max(peaks) > limit >= max(end):
                    unseen += 1
                    crossed = True
                if max(end) >= MIN_SHARE * limit:
                    ratios.append(max(p / e for p, e in zip(peaks, end) if e > 0.0))
                if term or trunc:
                    break
            key = outcome(info)
            ends[key] = ends.get(key, 0) + 1
            unseen_ok += crossed and key == "success"
        crush_at = env.unwrapped.crush_at
    finally:
        env.close()
    if crush_at == "peak":  # (a peak over the limit ended the episode: nothing went unseen)
        unseen = unseen_ok = None
    r = np.array(ratios) if ratios else np.array([math.nan])
    return {"env": env_id, "policy": policy, "seeds": [int(seeds[0]), int(seeds[-1])], "episodes": len(seeds),
            "env_kwargs": dict(env_kwargs or {}), "steps": len(ratios), "ratio_median": float(np.median(r)),
            "ratio_p95": float(np.percentile(r, 95)), "ratio_max": float(np.max(r)), "unseen_steps": unseen,
            "outcomes": dict(sorted(ends.items())),
            "unseen_successes": None if unseen_ok is None else int(unseen_ok), "crush_at": crush_at}


def main(argv=None) -> int:
    from simgrip.envs.baselines import _json_object, _seeds
    from simgrip.interrupt import run_main

    p = CommandParser(prog="python -m simgrip.envs.substep_forces",
                                description="The fingers' normal forces within a control step against the value "
                                            "at its end, under the task's scripted controller (JSON on stdout).")
    p.add_argument("--env", required=True, help="a fragile pick id, registered or retired")
    p.add_argument("--seeds", default="8000-8049", type=_seeds, help="A-B, inclusive (default 8000-8049)")
    p.add_argument("--policy", default="observation", choices=("observation", "oracle"))
    p.add_argument("--palm-ramp", action="store_true",
                   help="the env made with palm_ramp=True (the registered fragile ids ramp it already)")
    p.add_argument("--env-kwargs", type=_json_object, default=None, metavar="JSON",
                   help="gym.make's keyword arguments, a JSON object ('{\"palm_ramp\": false, \"crush_at\": "
                        "\"end\"}': a registered id as the versions before it)")

    def run(argv) -> int:
        args = p.parse_args(argv)
        from simgrip.envs import FRAGILE_ENV_IDS, RETIRED

        if args.env not in FRAGILE_ENV_IDS and args.env not in RETIRED:
            p.error(f"--env must be a fragile id, registered ({', '.join(FRAGILE_ENV_IDS)}) or retired, "
                    f"got {args.env!r}")
        kwargs = dict(args.env_kwargs or {})
        if args.palm_ramp:
            if kwargs.get("palm_ramp", True) is not True:
                p.error("--palm-ramp contradicts --env-kwargs' palm_ramp")
            kwargs["palm_ramp"] = True
        try:
            rec = force_peaks(args.env, args.seeds, policy=args.policy, env_kwargs=kwargs or None)
        except (TypeError, ValueError) as exc:  # a keyword the env refuses
            p.error(f"--env-kwargs: {exc}")
        print(json.dumps(rec, indent=1))
        return 0

    return run_main(run, "python -m simgrip.envs.substep_forces", argv)


if __name__ == "__main__":
    sys.exit(main())
