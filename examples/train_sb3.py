"""Train SAC and PPO (Stable-Baselines3, library defaults) on a simgrip env and evaluate them.

Needs the optional extra: ``pip install "simgrip[rl]"`` (Stable-Baselines3 and
PyTorch; a CPU build of PyTorch is enough).

    python examples/train_sb3.py --algo ppo sac --minutes 15 --out runs/pick [--env simgrip/Pick-v1]

For each algorithm: ``algo("MlpPolicy", env)`` with Stable-Baselines3's default hyperparameters on one environment,
trained until ``--steps`` environment steps or ``--minutes`` of the ``--clock``, whichever comes first (the
training stops at the end of the step that crosses the time budget; PPO fills SB3's ``learn(total_timesteps)``
with whole rollouts of 2048 steps a copy: ``--steps 64`` is one rollout and one update; the JSON's ``timesteps``
are the steps taken).  ``--clock cpu`` (default) counts the process's CPU time, what one core gives in that many
minutes whatever else the machine runs; ``--clock wall`` wall-clock time.  Then the deterministic policy runs
``--eval-episodes`` episodes on held-out seeds (``--eval-seed``, ``--eval-seed + 1``, ...; training episodes are
drawn from ``--seed``).

Writes into ``--out`` (created if needed, files written whole):

* ``<algo>_curve.csv``: one row per training episode: ``episode, timesteps, wall_s, cpu_s, episode_return, length, success``;
* ``<algo>_policy.csv``: one row per ``POLICY_WINDOW`` (2048, PPO's rollout) training steps: ``timesteps,
  cpu_s``, then per action ``i`` the mean and standard deviation of the actions the algorithm sampled in that
  window (``action_mean_i``, ``action_std_i``: PPO's Gaussian samples before they are clipped to the action
  bounds, SAC's squashed samples) and PPO's state-independent log standard deviation at the window's end
  (``log_std_i``; empty for SAC, whose standard deviation depends on the state).  It shows how exploration
  evolves: a run whose action means stay near 0 while ``log_std`` falls has stopped exploring;
* ``<algo>_eval.json``: ``{"algo", "env", "timesteps", "wall_s", "episodes",
  "success_rate", "mean_return", "outcomes", "mean_success_length", "mean_discounted_return", ...}`` (also
  printed on one line; ``outcomes`` counts how the held-out episodes ended, ``mean_discounted_return`` is their
  return discounted by the model's ``gamma`` (0.99 by default), what the learner maximises:
  :func:`simgrip.envs.evaluation.outcomes`);
* ``<algo>_model.zip``: the trained policy (with ``--checkpoint-minutes M`` also
  ``<algo>_model_<k M>min.zip`` every ``M`` budget minutes, and the curve so far;
  their held-out results go into ``<algo>_eval.json``);
* ``curves.png``: success rate of the training episodes (moving average over 100 episodes) against environment
  steps and against CPU minutes, for every ``*_curve.csv`` in ``--out`` (so two runs into one folder share a plot).

``--normalize`` wraps the training env in Stable-Baselines3's ``VecNormalize`` (running mean and variance of
the observation and of the discounted return, the library's defaults: clipped at 10, ``gamma = 0.99``, the
algorithms' default), the documented wrapper of SB3's own MuJoCo recipes; its statistics are saved with each
model (``<algo>_vecnormalize.pkl``, ``<algo>_vecnormalize_<k M>min.pkl``) and the held-out evaluation feeds the
policy the observation normalised with the statistics frozen at that point (returns and success are the
env's own, unnormalised).

``--action-offset A0 A1 ...`` trains and evaluates behind :class:`simgrip.envs.action_offset.ActionOffset`:
the env performs ``clip(action + offset)``, so PPO's zero-mean start performs the offset's motion (on the
valve tasks ``-0.4 0.2``, the slow close-and-lift probe; ``-0.2 0.2`` where the crush rule reads the peak,
:data:`simgrip.envs.action_offset.PEAK_PROBE_OFFSET`); ``<algo>_eval.json`` records ``action_offset``.

``--frame-stack N`` trains and evaluates on the last ``N`` observations (Gymnasium's ``FrameStackObservation``,
the issue's "frame stacking": the policy then sees how the forces and the shapes change from step to step;
:func:`simgrip.envs.evaluation.make_env`); ``<algo>_eval.json`` records ``frame_stack``.

``--scripted-start P`` starts that share of the training episodes part-way through the task's scripted
observation-only controller's episode (:class:`simgrip.envs.scripted_start.ScriptedStart`, reference-state
initialisation; the pick-and-place's first successes come from it); the held-out evaluation starts every
episode plainly; ``<algo>_eval.json`` records ``scripted_start``.

``--light-bias P`` draws that share of the training episodes' workpieces from the lightest third of the task's
log mass range (:class:`simgrip.envs.light_bias.LightBias`: the pieces a fast closing crushes); the held-out
evaluation runs the task's own draw; ``<algo>_eval.json`` records ``light_bias``.

``--crush-charge F`` lowers the training reward of every crush by ``F``, from training step ``--crush-charge-from
STEPS`` on (default 0; :class:`simgrip.envs.crush_charge.CrushCharge`: a reward curriculum, the grasp found first
under the task's own reward); the held-out evaluation runs the task's reward; ``<algo>_eval.json`` records
``crush_charge``.  A task without a crush is refused (exit 2).  ``--step-charge C`` lowers every training step's
reward by ``C`` (:class:`simgrip.envs.step_charge.StepCharge`, a cost of time), recorded as ``step_charge``.
``--crush-margin C`` lowers every training step's reward by ``C`` times how far its largest finger force has gone
from 0.8 of the hidden crush limit towards it (:class:`simgrip.envs.crush_margin.CrushMargin`, a dense shaping that
reads the limit the policy never sees), recorded as ``crush_margin``.  Ctrl-C or SIGTERM: one line, exit 130.

``--residual NAME ...`` trains and evaluates behind :class:`simgrip.envs.scripted_residual.ScriptedResidual`:
the task's scripted observation-only controller drives the named actions (``palm_x palm_z``: the palm's path)
and the policy's action is added to its action there; the observation gets the controller's action appended.
Residual policy learning: the wrapper is part of the policy (the held-out evaluation runs behind it too);
``<algo>_eval.json`` records ``residual``.  Not with ``--scripted-start`` or ``--init-from``.  With
``--residual-alone`` the controller drives those actions alone and the policy acts on the others only.
``--sde`` (PPO only) explores by SB3's generalised state-dependent exploration (``use_sde=True``: the noise a
function of the policy's last features, drawn once a rollout), named in ``hyperparameters``.
``--valve-share S`` multiplies the policy's curvature rate by ``S`` before the valve (a restrictor,
:class:`simgrip.envs.valve_share.ValveShare`, part of the policy), recorded as ``valve_share``.  ``--privileged-critic``
(PPO only) gives PPO's value function the hidden hold force and crush limit, and not its policy (an asymmetric
actor-critic, :mod:`simgrip.envs.privileged_critic`), recorded as ``privileged_critic``.  ``--touch-memory`` appends
the first touch's memory to the observation (:class:`simgrip.envs.touch_memory.TouchMemory`, part of the policy),
recorded as ``touch_memory``.

``--init-from MODEL`` (PPO only) starts the training from a PPO policy trained on another task (a curriculum:
the pinch's policy for the pick-and-place), copied by :func:`simgrip.envs.warm_start.transfer_ppo` (observation
entries and actions matched by name; the target's new ones start at weight 0; a difference between the two runs'
``--action-offset`` absorbed into the output bias); ``MODEL``'s folder must hold that
run's ``ppo_eval.json``.  ``<algo>_eval.json`` records ``init_from`` (the model, its env, seed, steps and CPU
time, and ``eval``: the copied policy's held-out success, return and outcomes before any update) and
``cpu_s_with_init``, the CPU time of both trainings (the budget counts this training's alone).

``--gamma G`` changes one hyperparameter, the discount (default 0.99), and the JSON's ``hyperparameters``
says so; the held-out ``mean_discounted_return`` is then at ``G``.  ``--log-std-init X`` (PPO only) changes
another, the policy's initial log standard deviation (``policy_kwargs={"log_std_init": X}``; default 0, a
standard deviation of 1 in every action), also named in ``hyperparameters``, and ``--lr-decay`` a third, the
learning rate, which falls linearly from the library's default to 0 over the budget
(:mod:`simgrip.envs.lr_decay`; a PPO run records each reading of the clock it made, ``lr_fractions``, which
``--replay`` gives back), and ``--ent-coef C`` (PPO only) a fourth, the entropy bonus's coefficient
(default 0).  ``examples/evaluate_policy.py`` re-evaluates a saved model, or a scripted controller, the same way.

``--eval-start`` also evaluates the policy before its first update (a fresh one, or the ``--init-from`` copy) on
the same held-out seeds and records it as ``start`` (``success_rate``, ``mean_return``,
``mean_discounted_return``, ``outcomes``): where the learner begins.  Behind ``--residual`` on every action the
fresh policy's deterministic action is SB3's initial mean, near 0 (its last layer's weights are scaled by 0.01),
so it starts as the scripted controller and ``start`` says how close.  The budget counts the training alone.

``--critic-warmup STEPS`` (PPO only) spends PPO's first ``STEPS`` environment steps (whole rollouts of 2048) with
the policy frozen, so that only its value function learns the starting policy's returns before the policy moves
(:mod:`simgrip.envs.critic_warmup`: residual policy learning's critic warm-up); they count in ``--steps`` and the
budget.  ``<algo>_eval.json`` records ``critic_warmup``: its ``timesteps``, ``cpu_s``, and per update the value
function's ``explained_variance`` on the rollout it learned from (before the update) and ``value_loss``.

``--n-envs N`` trains on ``N`` copies of the env (Stable-Baselines3's ``make_vec_env``: a ``DummyVecEnv`` that steps
them one after the other in this process, copy ``i`` seeded ``--seed + i``): the policy then runs once for ``N``
environment steps and PPO's rollouts hold ``2048 * N`` steps (its updates as many minibatches of 64 more), so a
CPU-minute buys more steps; SAC's default, one gradient step a call of its ``train_freq`` (one vector step), becomes
one per ``N`` environment steps.  ``--n-steps S`` (PPO only) changes the steps a rollout collects from each env
(default 2048; ``--n-envs 4 --n-steps 512`` keeps the default's 2048 steps an update), and ``--batch-size B`` the
transitions of each gradient step (PPO 64, SAC 256; with PPO a divisor of the rollout), each named in
``hyperparameters``.  The evaluation runs one env as always; ``<algo>_eval.json`` records ``n_envs``.

``--select-every M`` runs the policy on validation seeds (``--select-episodes``, ``--select-seed``; never the
held-out ones) every ``M`` budget minutes and keeps the best as the model and every checkpoint
(:mod:`simgrip.envs.selection`: the validations count in the budget); ``<algo>_eval.json``'s ``selection`` lists
them, the one chosen and the last policy's held-out success beside the chosen one's.

``--replay RECORD`` reruns a recorded run (this command being that run's, checked field by field) with the budget
read from the record's steps instead of the clock: it checkpoints and stops at the record's steps however fast this
machine is, and ``<algo>_eval.json``'s ``replay`` sets its results beside the record's, ``identical`` when every one
is equal (on the same machine and software; elsewhere the runs part: :mod:`simgrip.envs.budget_replay`; every run
records its package ``versions``).

``--threads`` sets PyTorch's intra-op threads (default 1: one core per
training; run two trainings side by side to use two cores).
"""

from __future__ import annotations

import argparse
import json
import os
import pickle
import signal
import sys
import time
from pathlib import Path

if __name__ == "__main__":  # a Ctrl-C while the modules below load: main's one line and 130 (run_main)
    signal.signal(signal.SIGINT, lambda signum, frame: (os.write(2, b"train_sb3: interrupted\n"), os._exit(130)))

import numpy as np  # noqa: E402

import simgrip.envs  # noqa: E402,F401  (registers the simgrip ids)
from simgrip.command_parser import CommandParser
from simgrip.envs.budget_replay import compare, load_schedule, policy_digest, versions
from simgrip.envs.env_options import EnvOptions, check_training_env, make_env
from simgrip.envs.evaluation import (GAMMA, add_training_aid_arguments, check_env_id, checkpoint_tag, episode_count,
                                     json_object, non_negative_int, outcomes, positive_int, positive_minutes,
                                     run_episodes, summary, training_conflict, training_files, training_seed)
from simgrip.envs.hyperparameters import budget_decay, hyperparameters, model_kwargs
from simgrip.envs.privileged_critic import policy_for
from simgrip.envs.selection import Selection, SelectionSpec, spec_from
from simgrip.envs.training_logs import ActionWindow, write_curve, write_policy
from simgrip.io import atomic_write, check_output_dir, check_output_files_in, write_json

ALGOS = ("ppo", "sac")
#: training steps per row of ``<algo>_policy.csv`` (PPO's default rollout length)
POLICY_WINDOW = 2048


def evaluate(model, env_id: str, episodes: int, seed0: int, options: EnvOptions | None = None,
             normalizer=None) -> dict:
    """Run the deterministic policy of ``model`` for ``episodes`` episodes on seeds ``seed0 + i`` (the env made
    with ``options`` less their training aids, :meth:`simgrip.envs.env_options.EnvOptions.evaluation`, as it was
    trained; ``normalizer``: the ``VecNormalize`` it was trained behind, whose frozen observation statistics then
    normalise what the policy sees)."""
    env = make_env(env_id, None if options is None else options.evaluation())
    see = (lambda obs: obs) if normalizer is None else normalizer.normalize_obs
    try:
        gamma = getattr(model, "gamma", GAMMA)  # an SB3 model's own; anything else with predict(): SB3's default
        results = run_episodes(env, lambda obs: model.predict(see(obs), deterministic=True)[0], episodes, seed0,
                               gamma=gamma)
    finally:
        env.close()
    return {**summary(results), **outcomes(results, gamma), "eval_seeds": [seed0, seed0 + episodes - 1]}


def _log_std(model):
    """PPO's state-independent log standard deviation (a NumPy array), or None (SAC; gSDE's is per feature)."""
    p = None if getattr(model, "use_sde", False) else getattr(model.policy, "log_std", None)
    return None if p is None or not hasattr(p, "detach") else p.detach().cpu().numpy().ravel()


def _save(model, path: Path) -> None:
    with atomic_write(path, "wb") as fh:
        model.save(fh)


def _save_normalizer(vec_normalize, path: Path) -> None:
    """The ``VecNormalize``'s statistics (pickled as ``VecNormalize.save`` does: without its env), whole."""
    with atomic_write(path, "wb") as fh:
        pickle.dump(vec_normalize, fh)


def _load_normalizer(path: Path):
    with open(path, "rb") as fh:
        return pickle.load(fh)


def _warm_start(model, train_env, init_from: str, action_offset) -> dict:
    """Copy the PPO policy saved at ``init_from`` into ``model`` (:mod:`simgrip.envs.warm_start`); returns what
    ``<algo>_eval.json`` records of it."""
    from simgrip.envs.warm_start import prepare_transfer, transfer_ppo

    rec, plan, source = prepare_transfer(init_from, train_env, action_offset)
    transfer_ppo(source, model, plan)
    return {"model": str(init_from), "algo": "PPO", "env": rec["env"], "seed": rec.get("seed"),
            "timesteps": rec.get("timesteps"), "cpu_s": rec.get("cpu_s"),
            **({"action_offset": rec["action_offset"]} if rec.get("action_offset") is not None else {}),
            **({"env_kwargs": rec["env_kwargs"]} if rec.get("env_kwargs") else {}),
            "new_observation": list(plan.new_obs), "new_actions": list(plan.new_actions)}


def train(algo: str, env_id: str, *, steps: int, minutes: float, seed: int, out: Path,
          eval_episodes: int, eval_seed: int, clock: str = "cpu", checkpoint_minutes: float | None = None,
          options: EnvOptions | None = None, normalize: bool = False, gamma: float | None = None,
          init_from: str | None = None, log_std_init: float | None = None, eval_start: bool = False,
          critic_warmup: int = 0, lr_decay: bool = False, ent_coef: float | None = None, n_envs: int = 1,
          n_steps: int | None = None, batch_size: int | None = None, selection: SelectionSpec | None = None,
          replay=None, use_sde: bool = False) -> dict:
    """Train ``algo`` with library defaults within the budget, write its curve, model and evaluation
    (``options``: the env's keyword arguments and wrappers, :class:`simgrip.envs.env_options.EnvOptions`: training
    behind all of them, evaluation behind those that are part of the policy, the action offset, the residual and
    the frame stack; ``normalize``: train behind SB3's ``VecNormalize`` with its defaults; ``gamma``: the
    algorithm's discount instead of its default 0.99, the one hyperparameter changed; ``init_from``: a saved PPO
    model of another run to start from, :mod:`simgrip.envs.warm_start`; ``log_std_init``: PPO's initial log
    standard deviation instead of 0; ``eval_start``: evaluate the policy before its first update as well, recorded
    as ``start``; ``critic_warmup``: PPO's first steps, in whole rollouts, with the policy frozen so that only the
    value function learns, :mod:`simgrip.envs.critic_warmup`; within ``steps`` and the budget; ``lr_decay``: the
    library's learning rate falling linearly to 0 over the budget, on its clock,
    :class:`simgrip.envs.lr_decay.BudgetDecay`; ``ent_coef``: PPO's entropy coefficient instead of 0; ``n_envs``:
    copies of the training env stepped one after the other, SB3's ``DummyVecEnv``, copy ``i`` seeded ``seed + i``;
    ``n_steps``: PPO's steps a rollout collects from each env instead of 2048; ``batch_size``: the transitions of
    each gradient step instead of the library's (PPO 64, SAC 256); ``selection``: validate the policy
    periodically within the budget and keep the best, :mod:`simgrip.envs.selection`; ``replay``: a
    :class:`simgrip.envs.budget_replay.ReplaySchedule`, the budget read from a record's steps instead of the clock,
    and the held-out results compared with the record's as ``replay``; ``use_sde``: PPO explores by gSDE,
    :mod:`simgrip.envs.hyperparameters`)."""
    options = EnvOptions() if options is None else options
    from stable_baselines3 import PPO, SAC
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.logger import Logger

    cls = {"ppo": PPO, "sac": SAC}[algo]
    rows = []
    policy_rows, window = [], ActionWindow()
    t_start, c_start = time.perf_counter(), time.process_time()
    budget = 60.0 * minutes
    spent = (lambda: time.process_time() - c_start) if clock == "cpu" else (lambda: time.perf_counter() - t_start)
    progress = [0]  # the steps taken, as the last callback saw them (what a replay's clock reads)
    if replay is not None:
        spent = lambda: replay.seconds(progress[0])  # noqa: E731

    checkpoints = []
    best = out / f"{algo}_model.zip"  # with a selection: the best validated policy so far
    chooser = None if selection is None else Selection(
        selection, budget, lambda m: evaluate(m, env_id, selection.episodes, selection.seed, options),
        lambda m: _save(m, best))
    normalizers = {}  # a checkpoint's model file -> its VecNormalize statistics (with --normalize)

    class Budget(BaseCallback):
        """Record every finished training episode; checkpoint; stop when the budget is spent."""

        def _on_step(self) -> bool:
            progress[0] = self.num_timesteps
            now = spent()  # one reading serves the checkpoints and the stop: the last checkpoint is never skipped
            # (read again after a validation: at the last one every checkpoint up to the budget is due)
            now, stop = (now, False) if chooser is None else chooser.step(self.model, now, self.num_timesteps, spent)
            while checkpoint_minutes and (now >= 60.0 * checkpoint_minutes * (len(checkpoints) + 1) or stop and
                                          checkpoint_minutes * (len(checkpoints) + 1) <= minutes + 1e-9):
                # the curve so far and the policy, so that a run stopped early can still be evaluated
                tag = checkpoint_tag(checkpoint_minutes, len(checkpoints) + 1)
                path = out / f"{algo}_model_{tag}.zip"
                if chooser is not None and chooser.best is not None:  # the best validated by now
                    with atomic_write(path, "wb") as fh:
                        fh.write(best.read_bytes())
                else:
                    _save(self.model, path)
                if normalize:
                    normalizers[path.name] = out / f"{algo}_vecnormalize_{tag}.pkl"
                    _save_normalizer(env, normalizers[path.name])
                write_curve(out / f"{algo}_curve.csv", rows)
                write_policy(out / f"{algo}_policy.csv", policy_rows)
                checkpoints.append({"minutes": round(checkpoint_minutes * (len(checkpoints) + 1), 6),
                                    "timesteps": int(self.num_timesteps), "file": path.name,
                                    **({} if chooser is None else {"validation": chooser.best})})
            window.add(self.locals["actions"])
            if window.n >= POLICY_WINDOW:
                policy_rows.append(window.row(int(self.num_timesteps), time.process_time() - c_start,
                                              _log_std(self.model)))
            for info in self.locals.get("infos", ()):
                ep = info.get("episode")
                if ep is not None:
                    rows.append((len(rows), self.num_timesteps, round(time.perf_counter() - t_start, 3),
                                 round(time.process_time() - c_start, 3), float(ep["r"]), int(ep["l"]),
                                 int(bool(info.get("is_success", False)))))
            return now < budget and not stop

    # make_vec_env calls the maker (gym.make of the id, or of a retired id's spec), then seeds and wraps in Monitor
    env = make_vec_env(lambda: make_env(env_id, options), n_envs=n_envs, seed=seed)
    if normalize:
        from stable_baselines3.common.vec_env import VecNormalize

        env = VecNormalize(env)  # SB3's defaults; the Monitor inside still records the env's own returns
    decay = budget_decay(algo, budget, clock, None if replay is None else replay.lr_fractions) if lr_decay else None
    if decay is not None:  # on the budget's own clock, from the budget's start (before the model is built)
        decay.start(c_start if clock == "cpu" else t_start)
    model = cls(policy_for(options), env, seed=seed, verbose=0, **model_kwargs(algo, gamma, log_std_init, decay,
                                                                       ent_coef, n_steps, batch_size, use_sde))
    model.set_logger(Logger(None, []))  # no output; SB3's own would make an empty /tmp/SB3-<time> per learn()
    init = start = None
    if init_from is not None:
        init = _warm_start(model, env.envs[0] if hasattr(env, "envs") else env.venv.envs[0], init_from,
                           options.action_offset)
    if init_from is not None or eval_start:  # the policy before any update, evaluated once for both records
        # (VecNormalize's statistics as they start; --init-from excludes --normalize)
        before = evaluate(model, env_id, eval_episodes, eval_seed, options, env if normalize else None)
        if init is not None:  # what the curriculum hands over: the copied policy on the held-out seeds
            init["eval"] = {k: before[k] for k in ("success_rate", "mean_return", "outcomes")}
        if eval_start:
            start = {k: before[k] for k in ("success_rate", "mean_return", "mean_discounted_return", "outcomes")}
        t_start, c_start = time.perf_counter(), time.process_time()  # the budget is the training's alone
        if decay is not None:
            decay.start(c_start if clock == "cpu" else t_start)
    warmup = None
    if critic_warmup:  # the value function fitted to the starting policy's returns, the policy held
        from simgrip.envs.critic_warmup import warm_up

        fit = warm_up(model, min(critic_warmup, steps), Budget())
        warmup = {"timesteps": int(model.num_timesteps), "cpu_s": round(time.process_time() - c_start, 1), **fit}
    if not critic_warmup or (model.num_timesteps < steps and spent() < budget):  # after a warm-up: from its state
        model.learn(total_timesteps=steps - model.num_timesteps, callback=Budget(),
                    reset_num_timesteps=not critic_warmup)
    if chooser is not None and not chooser.final:  # stopped by --steps: the last policy is a candidate too
        chooser.run(model, spent(), model.num_timesteps, spent)
    wall, cpu = time.perf_counter() - t_start, time.process_time() - c_start
    env.close()

    write_curve(out / f"{algo}_curve.csv", rows)
    if window.n:  # the last, partial window
        policy_rows.append(window.row(int(model.num_timesteps), cpu, _log_std(model)))
    write_policy(out / f"{algo}_policy.csv", policy_rows)
    if chooser is None:
        _save(model, best)
    normalizer = None
    if normalize:
        _save_normalizer(env, out / f"{algo}_vecnormalize.pkl")
        normalizer = _load_normalizer(out / f"{algo}_vecnormalize.pkl")
    result = {"algo": algo.upper(), "env": env_id, "timesteps": int(model.num_timesteps), "wall_s": round(wall, 1), "cpu_s": round(cpu, 1),
              "clock": clock, "budget_minutes": minutes,
              "train_episodes": len(rows), "seed": seed, "n_envs": n_envs,
              "hyperparameters": hyperparameters(gamma, log_std_init, decay, ent_coef, n_steps, batch_size, use_sde),
              "versions": versions()}
    if decay is not None and algo == "ppo":  # what a replay reads instead of the clock (envs.lr_decay)
        result["lr_fractions"] = list(decay.readings)
    keys, wrappers = options.record()
    result.update(keys)
    if n_envs > 1:
        wrappers.append(f"DummyVecEnv of {n_envs} copies in training")
    if normalize:
        wrappers.append("VecNormalize (SB3 defaults: observation and return)")
    if init is not None:
        result["init_from"] = init
        result["cpu_s_with_init"] = round(cpu + float(init.get("cpu_s") or 0.0), 1)
        wrappers.append(f"started from {init['algo']} on {init['env']} (warm start)")
    if warmup is not None:
        result["critic_warmup"] = warmup
        wrappers.append(f"critic warm-up: {warmup['timesteps']} steps with the policy frozen")
    if wrappers:
        result["wrapper"] = ", ".join(wrappers)
    if start is not None:
        result["start"] = start
    if chooser is not None:  # the held-out success of the chosen policy, and of the last beside it
        last = evaluate(model, env_id, eval_episodes, eval_seed, options)
        result["selection"] = {**chooser.record(), "last": {k: last[k] for k in ("success_rate", "mean_return", "outcomes")}}
        model = cls.load(best)
    result["policy_digest"] = policy_digest(model)  # the saved policy's, to the last bit (envs.budget_replay)
    result.update(evaluate(model, env_id, eval_episodes, eval_seed, options, normalizer))
    for cp in checkpoints:  # the held-out success of each checkpoint: how soon the target was reached
        cp_model = cls.load(out / cp["file"])
        cp_norm = _load_normalizer(normalizers[cp["file"]]) if normalize else None
        cp.update({k: v for k, v in evaluate(cp_model, env_id, eval_episodes, eval_seed, options, cp_norm).items()
                   if k in ("success_rate", "mean_return")})
    if checkpoints:
        result["checkpoints"] = checkpoints
    if replay is not None:
        result["replay"] = {"from": replay.source, **compare(result, replay.record)}
    write_json(out / f"{algo}_eval.json", result)
    return result


def plot_curves(out: Path, window: int = 100) -> Path | None:
    """Plot every ``*_curve.csv`` in ``out`` into ``out/curves.png``; returns its path (None if no curves)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    curves = sorted(out.glob("*_curve.csv"))
    if not curves:
        return None
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), constrained_layout=True)
    plotted = 0
    for path in curves:
        data = np.genfromtxt(path, delimiter=",", names=True)
        if data.size < 2:
            continue
        plotted += 1
        succ = np.atleast_1d(data["success"]).astype(float)
        # trailing mean over the last `window` episodes (fewer at the start)
        c = np.concatenate(([0.0], np.cumsum(succ)))
        i = np.arange(1, succ.size + 1)
        avg = (c[i] - c[np.maximum(i - window, 0)]) / np.minimum(i, window)
        label = path.name.split("_")[0].upper()
        axes[0].plot(np.atleast_1d(data["timesteps"]), avg, label=label)
        clock = "cpu_s" if "cpu_s" in data.dtype.names else "wall_s"
        axes[1].plot(np.atleast_1d(data[clock]) / 60.0, avg, label=label)
    for ax, xlabel in zip(axes, ("environment steps", "CPU minutes (one core)")):
        ax.set_xlabel(xlabel)
        ax.set_ylabel(f"training success (last {window} episodes)")
        ax.set_ylim(-0.02, 1.02)
        ax.grid(alpha=0.3)
        if plotted:
            ax.legend()
    axes[0].set_xscale("log")
    target = out / "curves.png"
    with atomic_write(target, "wb") as fh:
        fig.savefig(fh, format="png", dpi=110)
    plt.close(fig)
    return target


def build_parser() -> argparse.ArgumentParser:
    p = CommandParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--algo", nargs="+", choices=ALGOS, default=list(ALGOS), help="algorithms, trained one after the other")
    p.add_argument("--env", default="simgrip/Pick-v1",
                   help="registered env id, or a retired simgrip one (simgrip.envs.RETIRED; default simgrip/Pick-v1)")
    p.add_argument("--env-kwargs", type=json_object, default={}, metavar="JSON",
                   help="keyword arguments of gym.make as a JSON object, e.g. '{\"w_touch\": 0}' (default none)")
    p.add_argument("--minutes", type=positive_minutes, default=15.0, help="time budget per algorithm (default 15)")
    p.add_argument("--clock", choices=("cpu", "wall"), default="cpu",
                   help="what --minutes counts: the process's CPU time (default) or wall-clock time")
    p.add_argument("--checkpoint-minutes", type=positive_minutes, default=None,
                   help="also save the policy (and the curve so far) every so many budget minutes, "
                        "and evaluate each checkpoint at the end")
    p.add_argument("--steps", type=positive_int, default=10_000_000,
                   help="environment-step budget per algorithm (PPO: whole rollouts of 2048 steps, as SB3's learn; "
                        "the steps taken are the JSON's timesteps)")
    p.add_argument("--seed", type=training_seed, default=0, help="training seed (default 0; at most 2**32 - 1)")
    p.add_argument("--eval-episodes", type=episode_count, default=50,
                   help="held-out evaluation episodes (default 50, at most 100000)")
    p.add_argument("--eval-seed", type=non_negative_int, default=1_000_000, help="first evaluation seed (default 1000000)")
    p.add_argument("--threads", type=positive_int, default=1,
                   help="PyTorch threads (default 1; at most the machine's cores)")
    add_training_aid_arguments(p)
    p.add_argument("--init-from", default=None, metavar="MODEL",
                   help="PPO only: start from this saved PPO model of another run (its folder holds its "
                        "ppo_eval.json), copied by simgrip.envs.warm_start (default: a fresh policy)")
    p.add_argument("--eval-start", action="store_true",
                   help="also evaluate the policy before its first update on the held-out seeds (JSON: start)")
    p.add_argument("--critic-warmup", type=non_negative_int, default=0, metavar="STEPS",
                   help="PPO only: its first STEPS environment steps (rounded up to whole rollouts of 2048) with the "
                        "policy frozen, so that only the value function learns (simgrip.envs.critic_warmup; "
                        "within --steps and --minutes; default 0: none)")
    p.add_argument("--replay", default=None, metavar="RECORD",
                   help="checkpoint and stop at the steps of the run recorded in RECORD (its <algo>_eval.json, or "
                        "rl_baselines.py's <algo>_seed<S>.json) instead of at the clock's, this command being that "
                        "run's; the JSON's replay compares the results (simgrip.envs.budget_replay)")
    p.add_argument("--out", required=True, help="output folder")
    return p


def replay_schedule(args):
    """The :class:`simgrip.envs.budget_replay.ReplaySchedule` of ``args.replay`` for the command ``args`` (None
    without ``--replay``); ValueError naming what the record and the command disagree on."""
    if args.replay is None:
        return None
    if len(args.algo) != 1:
        raise ValueError(f"--replay: one --algo, the record's (got {' '.join(args.algo)})")
    identity = {"algo": args.algo[0], "env": args.env, "seed": args.seed, "clock": args.clock,
                "budget_minutes": args.minutes, "n_envs": args.n_envs,
                "hyperparameters": hyperparameters(args.gamma, args.log_std_init, budget_decay(
                    args.algo[0], 60.0 * args.minutes, args.clock) if args.lr_decay else None, args.ent_coef,
                    args.n_steps, args.batch_size, args.sde),
                "eval_seeds": [args.eval_seed, args.eval_seed + args.eval_episodes - 1],
                **EnvOptions.from_args(args).record()[0]}
    schedule = load_schedule(args.replay, identity, checkpoint_minutes=args.checkpoint_minutes,
                             lr_decay=args.lr_decay, selection=spec_from(args) is not None)
    if args.steps < schedule.timesteps:
        raise ValueError(f"--replay: --steps {args.steps} stops before the record's {schedule.timesteps} steps")
    return schedule


def main(argv=None) -> int:
    p = build_parser()
    args = p.parse_args(argv)
    why = training_conflict(args)  # before the rl extra is looked for
    if why:
        p.error(why)
    if len(set(args.algo)) != len(args.algo):
        p.error(f"--algo: repeated algorithm in {args.algo} (each writes the same files)")
    cores = os.cpu_count() or 1
    if args.threads > cores:
        p.error(f"--threads: at most the {cores} cores of this machine (more only share them), got {args.threads}")
    check_env_id(p, args.env, retired=True)
    try:  # refused before any training, the env built once
        check_training_env(args)
    except ValueError as e:
        p.error(str(e))
    try:  # after the options and the env are checked: a bad one is named whether the rl extra is there or not
        import stable_baselines3  # noqa: F401
        import torch
    except ImportError:
        p.error('needs Stable-Baselines3 and PyTorch: pip install "simgrip[rl]"')
    try:
        schedule = replay_schedule(args)
    except ValueError as e:
        p.error(str(e))
    if args.init_from is not None:
        if args.algo != ["ppo"]:
            p.error("--init-from: PPO only (--algo ppo)")
        from simgrip.envs.warm_start import check_init_from

        try:
            check_init_from(args.init_from, args.env, args.env_kwargs, args.action_offset, normalize=args.normalize,
                            frame_stack=args.frame_stack, residual=args.residual,
                            touch_memory=args.touch_memory)
        except ValueError as e:
            p.error(str(e))
    try:  # simgrip.io's output-path policy: a folder, and no FIFO/device/folder where a result file goes
        out = check_output_dir(args.out, "--out")
        check_output_files_in(out, training_files(args.algo, minutes=args.minutes,
                                                  checkpoint_minutes=args.checkpoint_minutes,
                                                  normalize=args.normalize), "--out")
    except ValueError as e:
        p.error(str(e))
    torch.set_num_threads(args.threads)
    for algo in args.algo:
        result = train(algo, args.env, steps=args.steps, minutes=args.minutes, seed=args.seed, out=out,
                       eval_episodes=args.eval_episodes, eval_seed=args.eval_seed, clock=args.clock,
                       checkpoint_minutes=args.checkpoint_minutes, options=EnvOptions.from_args(args),
                       normalize=args.normalize, gamma=args.gamma, init_from=args.init_from,
                       log_std_init=args.log_std_init, eval_start=args.eval_start, lr_decay=args.lr_decay,
                       ent_coef=args.ent_coef, critic_warmup=args.critic_warmup, n_envs=args.n_envs,
                       n_steps=args.n_steps, batch_size=args.batch_size, selection=spec_from(args), replay=schedule,
                       use_sde=args.sde)
        print(json.dumps(result), flush=True)
    plot_curves(out)
    return 0


if __name__ == "__main__":
    from simgrip.interrupt import run_main

    sys.exit(run_main(main, "train_sb3"))
