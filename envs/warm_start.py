r"""A policy learned on one task as the starting point of another: a pick-first curriculum (issue 18).

The pick-and-place (:mod:`simgrip.envs.pick_place`) asks for the pinch's grip and then a carry and a set-down.
Learned from scratch within 15 CPU-minutes it fails at the grip (the Gymnasium environments page, "Where the
learning target stands"), while the pinch alone is learned (``PickFragile-v6``). A curriculum hands the place's
learner the pinch's policy: :func:`transfer_ppo` copies a trained Stable-Baselines3 PPO policy into a fresh PPO
model of another env, matching the observation entries and the actions **by name**:

* the observation: each env's ``obs_layout`` (``(name, size)`` pairs, the entries' order); an entry of the
  target env whose name and size the source has gets the source's input weights (the first layer of the policy
  and of the value network), every other entry (the place's ``workpiece_x`` and ``target_x``) weight 0, so that
  it does not change the copied policy until training gives it a weight.  Entries are copied as they are, in
  each task's own units (``box_lift`` is in units of each task's own lift height: the pinch's 6 cm, the place's
  carry height 3 cm);
* the action: each env's ``action_names`` (the pinch ``("curvature", "palm_z")``, the place ``("curvature",
  "palm_x", "palm_z")``); a target action the source has gets the source's output row and log standard
  deviation, a new one (the place's ``palm_x``) a zero row and bias (mean action 0, the action offset's
  motion) and log standard deviation 0 (PPO's initial one).  Where the two runs train behind different action
  offsets (:mod:`simgrip.envs.action_offset`: the env performs ``clip(a + offset)``), a shared action's bias
  is shifted by ``offset_source - offset_target``, so that the env performs the same motion: exactly, wherever
  both runs' actions lie within the bounds (SB3 clips an action to them before the offset is added);
* every hidden layer and the value head as they are; the optimiser starts afresh.

So the copied policy's mean actions and value on a target observation equal the source's on the same named
entries (``tests/test_warm_start.py``), and training goes on from there with the library's defaults.

Measured (the Gymnasium environments page, "Pick first, then place"): it has not yet helped.  The pinch's
policies (88 / 86 / 86 % on their task) crush or drop nearly every place piece (39 + 9 and 20 + 28 of 50),
before and after 10 CPU-minutes of fine-tuning (0 %); the cradle started from them reaches 14 / 50 / 6 % at 15
CPU-minutes, against 60 / 0 / 46 % from scratch.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["Transfer", "action_names", "check_init_from", "check_source", "load_source", "plan_transfer",
           "prepare_transfer", "source_record", "transfer_ppo"]


def action_names(env) -> tuple[str, ...]:
    """The names of ``env``'s actions in order (the unwrapped env's ``action_names``); ``ValueError`` if it
    has none or their number differs from the action space's."""
    names = getattr(env.unwrapped, "action_names", None)
    n = int(np.prod(env.action_space.shape))
    if names is None or len(names) != n:
        raise ValueError(f"env {env.unwrapped.__class__.__name__} names no actions (action_names), "
                         "so no policy can be transferred to or from it")
    return tuple(names)


def _obs_columns(env) -> dict[str, tuple[int, int]]:
    layout = getattr(env.unwrapped, "obs_layout", None)
    if layout is None:
        raise ValueError(f"env {env.unwrapped.__class__.__name__} names no observation entries (obs_layout)")
    if env.observation_space.shape is None or len(env.observation_space.shape) != 1:
        raise ValueError(f"env {env.unwrapped.__class__.__name__}: its observation is not flat (a frame stack "
                         "cannot be transferred)")
    cols, start = {}, 0
    for name, size in layout:
        cols[name] = (start, int(size))
        start += int(size)
    if start != env.observation_space.shape[0]:
        raise ValueError(f"env {env.unwrapped.__class__.__name__}: its obs_layout covers {start} entries of the "
                         f"observation's {env.observation_space.shape[0]} (a frame stack cannot be transferred)")
    return cols


@dataclass(frozen=True)
class Transfer:
    """Which target entries take which source entries (:func:`plan_transfer`).

    ``obs_pairs``: ``(target column, source column)``; ``act_pairs``: ``(target action, source action)``;
    ``new_obs`` and ``new_actions``: the target's names the source lacks (started at weight 0); ``bias_shift``:
    per target action, ``offset_source - offset_target`` (0 for a new one)."""

    obs_pairs: tuple[tuple[int, int], ...]
    act_pairs: tuple[tuple[int, int], ...]
    new_obs: tuple[str, ...]
    new_actions: tuple[str, ...]
    n_obs: int
    n_actions: int
    bias_shift: tuple[float, ...]
    source_shape: tuple[int, int]  # the source env's (observation, action) sizes


def plan_transfer(source_env, target_env, source_offset=None, target_offset=None) -> Transfer:
    """Match ``target_env``'s observation entries and actions to ``source_env``'s by name (see the module);
    ``source_offset``, ``target_offset``: the action offsets each run trains behind (``None``: none).

    ``ValueError`` when either env lacks the names, or when no action or no observation entry is shared."""
    src_cols, dst_cols = _obs_columns(source_env), _obs_columns(target_env)
    obs_pairs, new_obs = [], []
    for name, (start, size) in dst_cols.items():
        if name in src_cols and src_cols[name][1] == size:
            obs_pairs += [(start + k, src_cols[name][0] + k) for k in range(size)]
        else:
            new_obs.append(name)
    src_act, dst_act = action_names(source_env), action_names(target_env)
    act_pairs = [(i, src_act.index(name)) for i, name in enumerate(dst_act) if name in src_act]
    if not obs_pairs or not act_pairs:
        raise ValueError(f"the source env shares no {'observation entry' if not obs_pairs else 'action'} with "
                         "the target env")
    src_off = np.zeros(len(src_act)) if source_offset is None else np.asarray(source_offset, dtype=float)
    dst_off = np.zeros(len(dst_act)) if target_offset is None else np.asarray(target_offset, dtype=float)
    if src_off.shape != (len(src_act),) or dst_off.shape != (len(dst_act),):
        raise ValueError("--action-offset: one number per action of each env is needed")
    shift = [0.0] * len(dst_act)
    for i, j in act_pairs:
        shift[i] = float(src_off[j] - dst_off[i])
    return Transfer(tuple(obs_pairs), tuple(act_pairs), tuple(new_obs),
                    tuple(n for n in dst_act if n not in src_act), sum(s for _, s in dst_cols.values()),
                    len(dst_act), tuple(shift), (sum(s for _, s in src_cols.values()), len(src_act)))


def _check_source_model(source, plan: Transfer) -> None:
    sp = source.policy
    if sp.observation_space.shape != (plan.source_shape[0],) or sp.action_space.shape != (plan.source_shape[1],):
        raise ValueError(f"--init-from: a model of {sp.observation_space.shape[0]} observations and "
                         f"{sp.action_space.shape[0]} actions, not of the env its record names "
                         f"({plan.source_shape[0]} and {plan.source_shape[1]})")


def transfer_ppo(source, target, plan: Transfer) -> None:
    """Copy the PPO policy ``source`` (an SB3 ``PPO`` with the default ``MlpPolicy``) into ``target`` (a PPO of
    the target env, same architecture), in place, as ``plan`` says (see the module)."""
    import torch

    sp, tp = source.policy, target.policy
    for model, who in ((source, "source"), (target, "target")):
        if type(model).__name__ != "PPO" or not hasattr(model.policy, "log_std"):
            raise ValueError(f"{who}: a PPO model with a Gaussian MlpPolicy is needed, got {type(model).__name__}")
    if tp.observation_space.shape != (plan.n_obs,) or tp.action_space.shape != (plan.n_actions,):
        raise ValueError("target: its spaces are not the planned env's")
    _check_source_model(source, plan)
    src_state, dst_state = sp.state_dict(), tp.state_dict()
    if set(src_state) != set(dst_state):
        raise ValueError("source and target policies differ in architecture")
    dst_obs = torch.tensor([d for d, _ in plan.obs_pairs])
    src_obs = torch.tensor([s for _, s in plan.obs_pairs])
    dst_act = torch.tensor([d for d, _ in plan.act_pairs])
    src_act = torch.tensor([s for _, s in plan.act_pairs])
    first = {n for n, p in src_state.items() if n.endswith(".0.weight") and "mlp_extractor" in n}
    new = {}
    with torch.no_grad():
        for name, value in src_state.items():
            out = dst_state[name].clone()
            if name in first:  # the first layer of the policy and the value networks: input columns
                out.zero_()
                out[:, dst_obs] = value[:, src_obs]
            elif name == "action_net.weight":
                out.zero_()
                out[dst_act] = value[src_act]
            elif name in ("action_net.bias", "log_std"):
                out.zero_()
                out[dst_act] = value[src_act]
                if name == "action_net.bias":
                    out += torch.tensor(plan.bias_shift, dtype=out.dtype)
            else:
                if value.shape != out.shape:
                    raise ValueError(f"source and target policies differ in {name}: {tuple(value.shape)} against "
                                     f"{tuple(out.shape)}")
                out = value.clone()
            new[name] = out
    tp.load_state_dict(new)


def source_record(model_path) -> dict:
    """The training record of a saved PPO model: ``<folder>/ppo_eval.json`` beside ``model_path`` (what
    ``examples/train_sb3.py`` writes: the env, its keyword arguments, wrappers, seed and CPU time).
    ``ValueError`` naming the file when the model or its record is missing or unreadable."""
    path = Path(model_path)
    if not path.is_file():
        raise ValueError(f"--init-from: no model file {str(path)!r}")
    rec_path = path.with_name("ppo_eval.json")
    try:
        rec = json.loads(rec_path.read_text())
    except (OSError, ValueError) as e:
        raise ValueError(f"--init-from: needs the run's record {str(rec_path)!r} beside the model ({e})") from None
    if not isinstance(rec, dict) or rec.get("algo") != "PPO" or not isinstance(rec.get("env"), str):
        raise ValueError(f"--init-from: {str(rec_path)!r} is not a PPO run's record")
    return rec


def load_source(model_path):
    """The saved PPO model at ``model_path`` (on the CPU); ``ValueError`` naming ``--init-from`` when it cannot be
    loaded as one."""
    from stable_baselines3 import PPO

    try:
        return PPO.load(model_path, device="cpu")
    except Exception as e:  # a zip of something else, a truncated file, another library's format
        raise ValueError(f"--init-from: cannot load {str(model_path)!r} as a PPO model ({type(e).__name__})") from None


def check_source(rec: dict, *, normalize: bool = False, frame_stack: int | None = None) -> None:
    """Refuse a source run that cannot start the target's training (``ValueError`` naming the option): trained
    behind ``VecNormalize`` or a frame stack, or a target that would train behind one.  ``rec``: the source's
    record (:func:`source_record`); ``normalize``, ``frame_stack``: the target's options."""
    if normalize or "VecNormalize" in rec.get("wrapper", ""):
        raise ValueError("--init-from: a run with VecNormalize cannot be transferred (--normalize)")
    if (frame_stack or 1) > 1 or (rec.get("frame_stack") or 1) > 1:
        raise ValueError("--init-from: a frame-stacked policy cannot be transferred (--frame-stack)")


def prepare_transfer(model_path, target_env, target_offset=None, *, normalize: bool = False,
                     frame_stack: int | None = None):
    """Everything ``--init-from model_path`` needs, checked before any training: the source run's record
    (:func:`source_record`, :func:`check_source` against the target's ``normalize`` and ``frame_stack``), the plan
    onto ``target_env`` (:func:`plan_transfer`, the source env built from its record; ``target_offset``: the
    target's action offset) and the loaded source model, checked to be of the env its record names.  Returns
    ``(record, plan, model)``; ``ValueError`` naming the option otherwise."""
    from simgrip.envs.env_options import EnvOptions, make_env

    rec = source_record(model_path)
    check_source(rec, normalize=normalize, frame_stack=frame_stack)
    src_env = make_env(rec["env"], EnvOptions(env_kwargs=rec.get("env_kwargs") or {}))
    try:
        plan = plan_transfer(src_env, target_env, rec.get("action_offset"), target_offset)
    finally:
        src_env.close()
    source = load_source(model_path)
    _check_source_model(source, plan)
    return rec, plan, source


def check_init_from(model_path, env_id: str, env_kwargs=None, target_offset=None, *, normalize: bool = False,
                    frame_stack: int | None = None, residual=None, touch_memory: bool = False) -> None:
    """:func:`prepare_transfer` onto a fresh ``env_id`` (made with ``env_kwargs``, closed after): the example
    scripts' check of ``--init-from`` before any training (``ValueError`` naming the option; refused with a
    ``residual``, whose observation has the controller's action appended, and with ``touch_memory``, whose
    observation has the touch's memory appended)."""
    from simgrip.envs.env_options import EnvOptions, make_env

    if residual is not None:
        raise ValueError("--init-from: not with --residual (the observation has the controller's action appended)")
    if touch_memory:
        raise ValueError("--init-from: not with --touch-memory (the observation has the touch's memory appended)")

    env = make_env(env_id, EnvOptions(env_kwargs=env_kwargs or {}))
    try:
        prepare_transfer(model_path, env, target_offset, normalize=normalize, frame_stack=frame_stack)
    finally:
        env.close()
