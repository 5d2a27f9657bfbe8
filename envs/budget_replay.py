"""A learned run's budget replayed in environment steps: the record's steps on a machine of another speed.

A training's budget is CPU time (``examples/train_sb3.py --minutes M``), and what a CPU-minute buys moves with
the machine: the place task's aided command took 715k-719k steps in 15 CPU-minutes when its record was made and
480k-539k on later days (``docs/learning.md``, "The budget replayed in steps").  A record's numbers
therefore reproduce only within the spread that the machine's speed adds.  Every decision the budget makes is
taken at a step, and the record keeps those steps: each checkpoint's ``timesteps`` (the step at which the time
spent first reached ``k`` checkpoint periods) and the final ``timesteps`` (the step at which it reached the
budget).  :class:`ReplaySchedule` is a clock that reads those steps instead of the time: at each recorded step it
gives exactly the budget time the decision there needed, and between two of them a time in between (linear in the
steps, always short of the next decision's time), so a replayed run (``train_sb3.py --replay RECORD``,
``rl_baselines.py --replay FOLDER``) checkpoints and stops at the record's steps whatever the machine's speed.

The training itself is deterministic in the steps (its seed fixes the environment's and the learner's random numbers;
one torch thread), so a replay on the same machine and software trains the same policy bit for bit, and its held-out
results equal the record's: ``replay["identical"]`` in the replay's ``<algo>_eval.json`` says whether the final steps,
success rate, mean return and outcomes, every checkpoint's steps, success rate and mean return, and (where the record
has one) the final policy's digest, :func:`policy_digest`, are equal (measured: the pinch's aided command run for 4
CPU-minutes and replayed on the same machine, identical over 168k steps and 82 updates).  Other versions of MuJoCo,
PyTorch, Stable-Baselines3 or NumPy, or another CPU's arithmetic (the learner's matrix kernels follow the instruction
set), change the last bits of the physics or of an update, after which the runs part: the replay is then a run of the
same steps, a new sample of the recipe at the record's step count (measured: seed 0 of the pinch's discount batch,
recorded a day earlier when the machine gave 1.7 times the steps per CPU-minute, replayed at its 968,002 steps, gave
66 / 84 / 68 % at its checkpoints against the record's 80 / 70 / 84 %, parted by the first checkpoint; the record, made
before runs recorded their versions, cannot say whether the host or a package differed).  Each run records the versions
it ran with (``versions``).

A learning rate that falls over the budget (``--lr-decay``) read the clock at every update; a PPO run records what
each reading gave (``lr_fractions``, :class:`simgrip.envs.lr_decay.BudgetDecay`), and its replay is given those
instead of the clock (``identical`` then also asks that the replay read them all, no more and no fewer).

What cannot be replayed (refused before any training, naming why): a run whose budget was not what stopped it
(stopped by its ``--steps`` cap: rerun that command), a learning rate that falls over the budget in a record that
did not keep its readings (SAC's, and runs recorded before they were kept), validations within the budget
(``--select-every``: when each ran depended on what the earlier ones cost), and a record of another experiment
(algorithm, env, seed, budget, clock, hyperparameters, environment options, held-out seeds: each must be the
command's own).
"""

from __future__ import annotations

import bisect
import json
import math
from dataclasses import dataclass
from pathlib import Path

from simgrip.envs.lr_decay import budget_shares

__all__ = ["IDENTITY_KEYS", "OPTION_KEYS", "ReplaySchedule", "compare", "load_schedule", "policy_digest", "versions"]

#: the fields of a run's record that a replay's command must give alike (besides the options below)
IDENTITY_KEYS = ("algo", "env", "seed", "clock", "budget_minutes", "hyperparameters", "eval_seeds")
#: :meth:`simgrip.envs.env_options.EnvOptions.record`'s keys (each recorded only where set)
OPTION_KEYS = ("env_kwargs", "action_offset", "residual", "residual_alone", "valve_share", "touch_memory",
               "privileged_critic", "frame_stack", "scripted_start", "light_bias", "crush_charge", "step_charge",
               "crush_margin")


@dataclass(frozen=True)
class ReplaySchedule:
    """Budget seconds as a function of the training's steps (module docstring).

    ``anchors``: ``(timesteps, seconds)`` pairs, both non-decreasing, from ``(0, 0.0)`` to ``(timesteps,
    budget_s)``: each checkpoint's step and period, then the final step and the budget.  ``source``: the record's
    path; ``record``: its contents (what :func:`compare` compares with); ``lr_fractions``: with ``--lr-decay``, the
    shares of the budget its learning rate read, in call order (:class:`simgrip.envs.lr_decay.BudgetDecay`)."""

    anchors: tuple
    budget_s: float
    source: str
    record: dict
    lr_fractions: tuple | None = None

    @property
    def timesteps(self) -> int:
        """The record's final steps, where the replay stops."""
        return int(self.anchors[-1][0])

    def seconds(self, timesteps: int) -> float:
        """The budget time [s] the clock reads after ``timesteps`` steps: at an anchor's step its time (the largest,
        where several share the step), strictly between two anchors' steps a time strictly below the later one's."""
        anchors = self.anchors
        lo = bisect.bisect_right(anchors, (timesteps, math.inf))  # the first anchor beyond timesteps
        if lo == len(anchors):  # at or past the last step: the budget (the clock never reads past it)
            return self.budget_s
        s_a, t_a = anchors[lo - 1]
        s_b, t_b = anchors[lo]
        if timesteps == s_a:
            return float(t_a)
        t = t_a + (t_b - t_a) * (timesteps - s_a) / (s_b - s_a)
        return min(t, math.nextafter(t_b, -math.inf))


def versions() -> dict:
    """The versions of what a training's numbers depend on (Python and the packages that compute), as a run
    records them (``versions``); a package that is not installed is None."""
    import platform
    from importlib import metadata

    found = {"python": platform.python_version()}
    for name in ("mujoco", "numpy", "gymnasium", "stable-baselines3", "torch"):
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            found[name] = None
    return found


def policy_digest(model) -> str:
    """A digest of a Stable-Baselines3 model's policy: SHA-256 (its first 16 hex digits) of every parameter's name,
    shape, dtype and bytes, in the policy's order.  Equal digests are the same network to the last bit; a run records
    its final policy's (``policy_digest``), and a replay's ``identical`` asks for the record's."""
    import hashlib

    h = hashlib.sha256()
    for name, tensor in model.policy.state_dict().items():
        a = tensor.detach().cpu().contiguous().numpy()
        h.update(f"{name}:{a.shape}:{a.dtype}:".encode())
        h.update(a.tobytes())
    return h.hexdigest()[:16]


def _read(path) -> dict:
    try:
        record = json.loads(Path(path).read_text())
    except (OSError, ValueError) as e:
        raise ValueError(f"--replay: cannot read the record {str(path)!r} ({e})") from None
    if not isinstance(record, dict):
        raise ValueError(f"--replay: {str(path)!r} is not a run's record (a JSON object)")
    return record


def load_schedule(path, identity: dict, *, checkpoint_minutes: float | None, lr_decay: bool = False,
                  selection: bool = False) -> ReplaySchedule:
    """The schedule of the run recorded at ``path`` (``train_sb3.py``'s ``<algo>_eval.json``, or
    ``rl_baselines.py``'s ``<algo>_seed<S>.json``), checked against the replay's command.

    ``identity``: the command's own values of :data:`IDENTITY_KEYS` and of the options it sets
    (:data:`OPTION_KEYS`); ``checkpoint_minutes``: its checkpoint period; ``lr_decay``: whether it decays the
    learning rate (the record must keep its readings); ``selection``: whether it validates within the budget
    (refused).  Raises ValueError naming what differs or why the run cannot be replayed (module docstring)."""
    if selection:
        raise ValueError("--replay: --select-every cannot be replayed (when each validation ran depended on what the "
                         "earlier ones cost)")
    record = _read(path)
    if record.get("returncode", 0) != 0 or "success_rate" not in record or "timesteps" not in record:
        raise ValueError(f"--replay: {str(path)!r} records no finished run")
    if "selection" in record:
        raise ValueError(f"--replay: {str(path)!r} validated within its budget (--select-every), which cannot be "
                         "replayed")
    defaults = {"n_envs": 1}  # (recorded only where it differs)
    for key in (*IDENTITY_KEYS, *OPTION_KEYS, "n_envs"):
        have, want = record.get(key, defaults.get(key)), identity.get(key, defaults.get(key))
        if key == "algo" and have is not None:
            have = str(have).lower()
        if have != want:
            raise ValueError(f"--replay: the record's {key} is {have!r}, this command's {want!r}")
    budget = 60.0 * float(record["budget_minutes"])
    spent = float(record["cpu_s"] if record["clock"] == "cpu" else record["wall_s"])
    final = int(record["timesteps"])
    if spent < budget:
        raise ValueError(f"--replay: {str(path)!r} was stopped by its step cap at {final} steps, not by its budget; "
                         f"rerun its command with --steps {final}")
    checkpoints = record.get("checkpoints") or []
    periods = [float(c["minutes"]) for c in checkpoints]
    if checkpoints:
        want = [round(checkpoint_minutes * (k + 1), 6) for k in range(len(checkpoints))] if checkpoint_minutes \
            else None
        if want != periods:
            raise ValueError(f"--replay: the record's checkpoints are at {periods} minutes; this command's "
                             f"--checkpoint-minutes {checkpoint_minutes} gives others")
    elif checkpoint_minutes and checkpoint_minutes <= float(record["budget_minutes"]) + 1e-9:
        raise ValueError(f"--replay: the record has no checkpoints; this command's --checkpoint-minutes "
                         f"{checkpoint_minutes} adds some")
    fractions = None
    if lr_decay:
        try:  # (BudgetDecay's own check of a replay's shares)
            fractions = budget_shares(record.get("lr_fractions"))
        except ValueError:
            fractions = ()
        if not fractions:
            raise ValueError(f"--replay: --lr-decay cannot be replayed from {str(path)!r}: it does not keep its "
                             "learning rate's readings of the clock (lr_fractions: SAC's are not kept, nor were any "
                             "before they were recorded)")
    anchors = [(0, 0.0)] + [(int(c["timesteps"]), 60.0 * float(c["minutes"])) for c in checkpoints] + [(final, budget)]
    if any(b[0] < a[0] or b[1] < a[1] for a, b in zip(anchors, anchors[1:])):
        raise ValueError(f"--replay: {str(path)!r}'s checkpoints are out of order")
    return ReplaySchedule(tuple(anchors), budget, str(path), record, fractions)


def compare(result: dict, record: dict) -> dict:
    """``result`` (a replay's held-out results) beside ``record``'s: per quantity ``[replay, record]``, and
    ``identical``: the final steps, success rate, mean return and outcomes, every checkpoint's steps, success rate
    and mean return, and where the record kept them the final policy's digest (:func:`policy_digest`) and the
    learning rate's readings (``lr_readings``: how many each made), all equal."""
    keys = ("timesteps", "success_rate", "mean_return", "outcomes")
    out = {k: [result.get(k), record.get(k)] for k in keys}
    same = all(a == b for a, b in out.values())
    cps = []
    for mine, theirs in zip(result.get("checkpoints") or [], record.get("checkpoints") or []):
        row = {"minutes": mine.get("minutes")}
        for k in ("timesteps", "success_rate", "mean_return"):
            row[k] = [mine.get(k), theirs.get(k)]
            same = same and mine.get(k) == theirs.get(k)
        cps.append(row)
    same = same and len(result.get("checkpoints") or []) == len(record.get("checkpoints") or [])
    if "policy_digest" in record:
        out["policy_digest"] = [result.get("policy_digest"), record["policy_digest"]]
        same = same and out["policy_digest"][0] == out["policy_digest"][1]
    if "lr_fractions" in record:
        mine, theirs = result.get("lr_fractions") or [], record["lr_fractions"]
        out["lr_readings"] = [len(mine), len(theirs)]
        same = same and mine == theirs
    return {**out, "checkpoints": cps, "identical": bool(same)}
