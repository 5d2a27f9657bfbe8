"""The Gymnasium environments' speed for ``simgrip bench`` (issue 18, item 5), measured in the bench's run.

* every registered id (:data:`simgrip.envs.ENV_IDS`, ``MULTI_ENV_IDS``, ``FRAGILE_ENV_IDS``): env steps per second
  and the env's overhead over bare ``mj_step`` on the same states
  (:func:`simgrip.envs.throughput.measure_throughput`, this thread's CPU time, the median over chunks of each
  chunk's ratio), against the issue's target :data:`ENV_OVERHEAD_TARGET`, beside the interface's floor (the least
  Python step of the env's interface on the same states, :mod:`simgrip.envs.step_floor`);
* the validity check of an invalid claw state, every pair of links at once against pruned
  (:func:`simgrip.envs.throughput.violation_check_times` on :data:`CLAW_IDS`: the states random actions curl
  through each other).

Quick: 300 control steps and one repeat per id, 1500 random steps per claw; full: 1000 steps and 3 repeats (the
speed page's figures), 4000 steps and 7 passes.
"""

from __future__ import annotations

__all__ = ["CLAW_IDS", "ENV_OVERHEAD_TARGET", "env_speed", "envs_md"]

#: Issue 18, item 5: the env's overhead over bare ``mj_step`` [%], at most.
ENV_OVERHEAD_TARGET = 10.0
#: The envs whose random actions reach the exact validity check (the claws).
CLAW_IDS = ("simgrip/PickCradleFragile-v6", "simgrip/PickSphereFragile-v6")


def env_speed(quick: bool = False) -> dict:
    """``{"throughput": {id: measure_throughput's dict}, "validity": {id: violation_check_times' dict}}``."""
    from simgrip.envs import ENV_IDS, FRAGILE_ENV_IDS, MULTI_ENV_IDS
    from simgrip.envs.throughput import measure_throughput, violation_check_times

    steps, repeats = (300, 1) if quick else (1000, 3)
    throughput = {env_id: measure_throughput(steps=steps, repeats=repeats, clock="cpu", env_id=env_id)
                  for env_id in ENV_IDS + MULTI_ENV_IDS + FRAGILE_ENV_IDS}
    validity = {env_id: violation_check_times(env_id, steps=1500 if quick else 4000, repeats=1 if quick else 7)
                for env_id in CLAW_IDS}
    return {"throughput": throughput, "validity": validity}


def envs_md(speed: dict) -> list[str]:
    """``summary.md``'s section for :func:`env_speed`'s record (nothing for an empty one)."""
    if not speed:
        return []
    L = ["", "## Gymnasium pick environments", "",
         f"Overhead over bare `mj_step` on the same states (CPU time, median of the chunks' ratios; issue 18: "
         f"at most {ENV_OVERHEAD_TARGET:g} %):", "",
         "| env | env steps/s | raw mj_step steps/s | overhead | met | interface floor |",
         "|---|---|---|---|---|---|"]
    for env_id, e in speed.get("throughput", {}).items():
        met = "yes" if e["overhead_percent"] <= ENV_OVERHEAD_TARGET else "no"
        L.append(f"| {env_id} | {e['env_steps_per_s']:.0f} | {e['raw_physics_steps_per_s']:.0f} | "
                 f"{e['overhead_percent']:.1f} % | {met} | {e['floor_overhead_percent']:.1f} % |")
    L += ["", "The interface floor is the least Python step of the env's interface replayed on the same states "
          "(`simgrip.envs.step_floor`): the part of the overhead no task code can remove."]
    if speed.get("validity"):
        L += ["", "The validity check of an invalid state (random actions; every pair of links at once against a "
              "finger and a pair of fingers at a time):", "",
              "| env | invalid states | every pair at once | pruned | same messages |", "|---|---|---|---|---|"]
        for env_id, v in speed["validity"].items():
            times = (f"{v['batched_us']:.0f} µs | {v['pruned_us']:.0f} µs" if v["states"] else "— | —")
            L.append(f"| {env_id} | {v['states']} | {times} | {'yes' if v['same'] else 'NO'} |")
    return L
