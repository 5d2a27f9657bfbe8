"""Learned baselines over several training seeds: one Stable-Baselines3 run per (algorithm, seed), aggregated.

Needs the optional extra: ``pip install "simgrip[rl]"`` (Stable-Baselines3 and a CPU build of PyTorch).

    python examples/rl_baselines.py --env simgrip/PickFragile-v0 --algo ppo sac --seeds 0 1 2 \\
        --minutes 15 --checkpoint-minutes 5 --eval-seeds 8000-8049 --jobs 2 --out runs/pick_fragile

(``docs/baselines/rl_pick_fragile/``: 0 % for all six runs on v0; the same command on
``simgrip/PickFragile-v1``, the shaped reward of :mod:`simgrip.envs.pick_fragile_v1`, with ``--algo ppo --seeds 0
--jobs 1``: ``docs/baselines/rl_pick_fragile_v1/``, 0 % at 5, 10 and 15 CPU-minutes.)

Each (algorithm, seed) is trained by ``examples/train_sb3.py`` (library defaults, one environment, one torch
thread, ``--minutes`` of the process's CPU time, a checkpoint every ``--checkpoint-minutes``) in a *separate
process*, at most ``--jobs`` at once (default 1, at most the machine's cores: each run uses one core, so its
CPU budget buys the same training whatever else runs).  Every checkpoint and the final policy are evaluated
deterministically on the held-out seeds ``--eval-seeds A-B`` (contiguous; training draws its episodes from
the training seed's stream, not from these).

Writes into ``--out``:

* ``<algo>_seed<S>/``: that run's folder (``train_sb3.py``'s files: ``<algo>_eval.json`` with the held-out
  success of every checkpoint, ``<algo>_curve.csv``, ``<algo>_policy.csv`` (the exploration noise per rollout),
  the models, and ``log.txt``, the run's output);
* ``<algo>_seed<S>.json``: the run's result (a copy of its ``<algo>_eval.json``, plus ``returncode``);
* ``aggregate.json``: per algorithm and checkpoint (CPU minutes): ``n`` runs, ``mean``, ``min``, ``max`` and
  every run's held-out ``success_rates`` (fractions in [0, 1]), and the same for the final policies; the
  command line, the seeds and the budget;
* ``learning_curves.png``: held-out success against CPU minutes, each algorithm's mean with the min-max band
  over the seeds and each seed's curve.

``--normalize`` passes ``train_sb3.py``'s option of that name to every run: training behind SB3's
``VecNormalize`` (observation and return, the library's defaults), evaluated with its frozen observation
statistics; ``aggregate.json`` then names the wrapper.  ``--action-offset A0 A1 ...`` likewise passes that
option (:class:`simgrip.envs.action_offset.ActionOffset`: the env performs ``clip(action + offset)``, so that
PPO's zero-mean start performs the offset's motion) and ``aggregate.json`` records ``action_offset``;
``--frame-stack N`` passes that option too (the last ``N`` observations, Gymnasium's ``FrameStackObservation``),
recorded as ``frame_stack``; ``--scripted-start P`` passes that option (that share of the training episodes
starts part-way through the scripted observation-only controller's episode,
:class:`simgrip.envs.scripted_start.ScriptedStart`; evaluation starts plainly), recorded as ``scripted_start``;
``--light-bias P`` passes that option (that share of the training episodes' workpieces drawn from the light end
of the mass range, :class:`simgrip.envs.light_bias.LightBias`; evaluation draws the task's own), recorded as
``light_bias``; ``--residual NAME ...`` passes that option (the task's scripted observation-only controller
drives the named actions and the policy's action is added to it, in training and evaluation alike,
:class:`simgrip.envs.scripted_residual.ScriptedResidual`), recorded as ``residual``, and ``--residual-alone`` too
(the controller drives them alone and the policy acts on the other actions only), recorded as ``residual_alone``;
``--valve-share S`` (a restrictor: :class:`simgrip.envs.valve_share.ValveShare`), ``--touch-memory`` (the observation
gains the first touch's memory: :mod:`simgrip.envs.touch_memory`) and ``--privileged-critic`` (PPO's critic reads the
hidden workpiece: :mod:`simgrip.envs.privileged_critic`) pass those options, recorded so;
``--init-from DIR`` (PPO only) starts each seed ``S`` from ``DIR/ppo_seed<S>/ppo_model.zip``, the policy of an
earlier ``rl_baselines.py`` run of the same seed on another task (a curriculum: the pinch's policies for the
pick-and-place; :mod:`simgrip.envs.warm_start`), recorded as ``init_from`` with that run's command
(``init_command``); checkpoints count this run's own CPU minutes, to which the source's budget adds;
``--gamma G`` passes the discount instead of the default 0.99, and ``--log-std-init X`` (PPO only) the policy's
initial log standard deviation instead of 0, ``--lr-decay`` a learning rate falling linearly to 0 over the budget
(:mod:`simgrip.envs.lr_decay`), and ``--ent-coef C`` (PPO only) the entropy bonus's coefficient, each named in every
JSON's ``hyperparameters``.  ``--eval-start`` passes that option (each run also evaluates its policy before the
first update, ``start``) and ``aggregate.json`` gives those rates per algorithm as ``start`` (as a checkpoint's);
``--critic-warmup STEPS`` (PPO only) passes that option (each run's first steps with the policy frozen, its value
function alone learning, :mod:`simgrip.envs.critic_warmup`), recorded as ``critic_warmup``; ``--crush-charge F`` and
``--crush-charge-from STEPS`` pass those options (each crush's training reward lowered by ``F`` from training step
``STEPS`` on, :mod:`simgrip.envs.crush_charge`), recorded as ``crush_charge``; ``--step-charge C`` passes that
option (every training step's reward lowered by ``C``, :mod:`simgrip.envs.step_charge`), recorded as
``step_charge``; ``--crush-margin C`` passes that option (each step's training reward lowered by ``C`` times how
near its largest finger force came to the hidden crush limit, :mod:`simgrip.envs.crush_margin`), recorded as
``crush_margin``; ``--n-envs N`` passes that option (each run trains on ``N`` copies of the env stepped one after the
other in its own process, SB3's ``DummyVecEnv``: still one core a run), recorded as ``n_envs`` and in
``hyperparameters``; ``--n-steps S`` (PPO only) passes PPO's steps a rollout collects from each env and
``--batch-size B`` the transitions of each gradient step, and ``--sde`` (PPO only) gSDE's exploration, each named in
``hyperparameters``; ``--select-every M``
(with ``--select-episodes E``, ``--select-seed S``) passes those options (every ``M`` budget minutes each run
validates its policy on seeds apart from ``--eval-seeds`` and keeps the best, :mod:`simgrip.envs.selection`, the
validations inside the budget), recorded as ``selection``.

Batches of one experiment run apart (some seeds here, others there or later, each with this command but for
``--seeds``, ``--jobs`` and ``--out``) are combined into one folder, as if run at once, by

    python examples/rl_baselines.py --combine BATCH [BATCH ...] --out OUT

which checks that the batches are the same experiment (every field of their ``aggregate.json`` but the seeds,
the summary and the command is equal) over different seeds, copies their ``<algo>_seed<S>.json``, and writes
``aggregate.json`` (the seeds merged, the summary recomputed, ``combined_from``: each batch's command) and
``learning_curves.png``; the runs' folders (models, logs) stay in the batches.

A recorded batch is rerun at its record's steps, whatever this machine's speed, by its own command with ``--replay
FOLDER`` (the batch's folder, e.g. ``docs/baselines/rl_pick_v7_peak_log_std_gamma``): each run checkpoints and stops
at its record's steps instead of at the clock's, and its JSON's ``replay`` sets its results beside the record's
(``identical`` when all are equal: on the same machine and software they are; elsewhere the runs part, and the
replay is a new draw at the same steps; :mod:`simgrip.envs.budget_replay`, which says what cannot be replayed).

Ctrl-C, or SIGTERM (``kill``, ``timeout``, a batch scheduler), stops every running child (SIGTERM, then SIGKILL
after 5 s) and exits 130 with one line.  Exit 2 (one
line) on a bad argument, 1 when a run failed (its log names why; the others are still aggregated).
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from simgrip.command_parser import CommandParser
from simgrip.envs.env_options import EnvOptions
from simgrip.envs.selection import spec_from
from simgrip.interrupt import kill_descendants, signals_as_interrupt

ALGOS = ("ppo", "sac")
TRAIN_SCRIPT = Path(__file__).resolve().with_name("train_sb3.py")


def _seed_range(text: str) -> tuple[int, int]:
    """``A-B`` (inclusive, 0 <= A <= B, at most ``MAX_EPISODES`` seeds: one evaluation episode each) or one seed
    ``A``."""
    from simgrip.envs.evaluation import MAX_EPISODES  # (imported when used, as build_parser's types)

    parts = text.split("-")
    try:
        lo, hi = (int(parts[0]), int(parts[-1])) if len(parts) in (1, 2) else (None, None)
    except ValueError:
        lo = hi = None
    if lo is None or lo < 0 or hi < lo:
        raise argparse.ArgumentTypeError(f"expected a seed range A-B with 0 <= A <= B, got {text!r}")
    if hi - lo + 1 > MAX_EPISODES:
        raise argparse.ArgumentTypeError(f"at most {MAX_EPISODES} seeds (one evaluation episode each), got {text!r}")
    return lo, hi


def run_command(algo: str, seed: int, args, folder: Path) -> list[str]:
    """The ``train_sb3.py`` command line of one run (one algorithm, one training seed, one torch thread)."""
    lo, hi = args.eval_seeds
    cmd = [sys.executable, str(TRAIN_SCRIPT), "--algo", algo, "--env", args.env, "--seed", str(seed),
           "--minutes", repr(args.minutes), "--clock", "cpu", "--steps", str(args.steps), "--threads", "1",
           "--eval-seed", str(lo), "--eval-episodes", str(hi - lo + 1), "--out", str(folder)]
    if args.checkpoint_minutes:
        cmd += ["--checkpoint-minutes", repr(args.checkpoint_minutes)]
    if args.env_kwargs:
        cmd += ["--env-kwargs", json.dumps(args.env_kwargs)]
    if args.normalize:
        cmd += ["--normalize"]
    if args.action_offset is not None:
        cmd += ["--action-offset", *[repr(float(x)) for x in args.action_offset]]
    cmd += [] if args.frame_stack is None else ["--frame-stack", str(args.frame_stack)]
    cmd += [] if args.gamma is None else ["--gamma", repr(args.gamma)]
    cmd += [] if args.log_std_init is None else ["--log-std-init", repr(args.log_std_init)]
    cmd += ["--lr-decay"] * args.lr_decay + ["--privileged-critic"] * args.privileged_critic + ["--sde"] * args.sde
    cmd += ["--touch-memory"] * args.touch_memory
    if args.ent_coef is not None:
        cmd += ["--ent-coef", repr(args.ent_coef)]
    if args.scripted_start is not None:
        cmd += ["--scripted-start", repr(args.scripted_start)]
    if args.light_bias is not None:
        cmd += ["--light-bias", repr(args.light_bias)]
    if args.residual is not None:
        cmd += ["--residual", *args.residual, *(["--residual-alone"] if args.residual_alone else [])]
    cmd += [] if args.valve_share is None else ["--valve-share", repr(args.valve_share)]
    if args.init_from is not None:
        cmd += ["--init-from", str(init_model(args.init_from, algo, seed))]
    cmd += ["--eval-start"] * args.eval_start
    if args.critic_warmup:
        cmd += ["--critic-warmup", str(args.critic_warmup)]
    if args.crush_charge is not None:
        cmd += ["--crush-charge", repr(args.crush_charge), "--crush-charge-from", str(args.crush_charge_from)]
    if args.step_charge is not None:
        cmd += ["--step-charge", repr(args.step_charge)]
    if args.crush_margin is not None:
        cmd += ["--crush-margin", repr(args.crush_margin)]
    if args.n_envs != 1:
        cmd += ["--n-envs", str(args.n_envs)]
    cmd += [] if args.n_steps is None else ["--n-steps", str(args.n_steps)]
    cmd += [] if args.batch_size is None else ["--batch-size", str(args.batch_size)]
    spec = spec_from(args)
    if spec is not None:
        cmd += ["--select-every", repr(spec.every_minutes), "--select-episodes", str(spec.episodes),
                "--select-seed", str(spec.seed)]
    if getattr(args, "replay", None) is not None:
        cmd += ["--replay", str(replay_record(args.replay, algo, seed))]
    return cmd


def replay_record(folder, algo: str, seed: int) -> Path:
    """The record ``--replay FOLDER`` replays for ``(algo, seed)``: the batch's ``<algo>_seed<S>.json``."""
    return Path(folder) / f"{algo}_seed{seed}.json"


def _check_replay(args, jobs) -> str | None:
    """Why ``--replay`` cannot replay one of the runs ``jobs`` (None: it can): each run's record must be there and
    be that run's, checked by ``train_sb3.py``'s own rule on the command it will run
    (:mod:`simgrip.envs.budget_replay`)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("_train_sb3", TRAIN_SCRIPT)
    train_sb3 = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(train_sb3)
    parser = train_sb3.build_parser()
    for algo, seed, cmd, _ in jobs:
        record = replay_record(args.replay, algo, seed)
        if not record.is_file():
            return f"--replay: no record of {algo} seed {seed} in {str(args.replay)!r} (expected {record.name})"
        try:
            train_sb3.replay_schedule(parser.parse_args(cmd[2:]))
        except ValueError as e:
            return f"{e} ({record})"
    return None


def hyperparameters(args) -> str:
    """``aggregate.json``'s ``hyperparameters``: the library's defaults, the envs a run steps and its one torch
    thread, and each hyperparameter ``args`` changes."""
    return "Stable-Baselines3 defaults, " + ("one env" if args.n_envs == 1 else f"{args.n_envs} envs (DummyVecEnv)") \
        + ", one torch thread" + "".join(f"; but {k} = {v!r}" for k, v in (
            ("gamma", args.gamma), ("log_std_init", args.log_std_init), ("ent_coef", args.ent_coef),
            ("n_steps", args.n_steps), ("batch_size", args.batch_size)) if v is not None) \
        + ("; but the learning rate falls linearly to 0 over the budget" if args.lr_decay else "") \
        + ("; but use_sde = True" if args.sde else "")


def init_model(folder, algo: str, seed: int) -> Path:
    """The model a run of ``--init-from folder`` starts from: that folder's run of the same algorithm and seed."""
    return Path(folder) / f"{algo}_seed{seed}" / f"{algo}_model.zip"


def _check_init(p: argparse.ArgumentParser, args, algos: list[str]) -> str | None:
    """Refuse an ``--init-from`` that cannot start every run (exit 2 naming it); returns the source's command."""
    from simgrip.envs.warm_start import check_init_from

    if algos != ["ppo"]:
        p.error("--init-from: PPO only (--algo ppo)")
    for seed in args.seeds:
        try:
            check_init_from(init_model(args.init_from, "ppo", seed), args.env, args.env_kwargs, args.action_offset,
                            normalize=args.normalize, frame_stack=args.frame_stack, residual=args.residual,
                            touch_memory=args.touch_memory)
        except ValueError as e:
            p.error(f"{e} (seed {seed})")
    try:
        command = json.loads((Path(args.init_from) / "aggregate.json").read_text()).get("command")
    except (OSError, ValueError, AttributeError):
        command = None
    return command


def _child_env() -> dict:
    """The children's environment: one thread per math library, and the simgrip this driver imported."""
    import simgrip

    env = dict(os.environ)
    for key in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        env[key] = "1"
    root = str(Path(simgrip.__file__).resolve().parent.parent)
    env["PYTHONPATH"] = os.pathsep.join([root] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else []))
    return env


def run_all(jobs: list[tuple[str, int, list[str], Path]], max_jobs: int, poll: float = 0.2) -> dict:
    """Run ``(algo, seed, command, folder)`` jobs, at most ``max_jobs`` at once; returns ``{(algo, seed):
    returncode}``.  On KeyboardInterrupt every running child is terminated (then killed after 5 s), any other
    descendant killed, and the interrupt re-raised."""
    env = _child_env()
    pending, running, codes = list(jobs), {}, {}
    try:
        while pending or running:
            while pending and len(running) < max_jobs:
                algo, seed, cmd, folder = pending.pop(0)
                folder.mkdir(parents=True, exist_ok=True)
                with open(folder / "log.txt", "w") as log:  # (the child writes through its own copy)
                    # own session: a terminal's Ctrl-C reaches the driver only, which stops the children itself
                    proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, env=env, start_new_session=True)
                running[(algo, seed)] = proc
            for key, proc in list(running.items()):
                if proc.poll() is not None:
                    codes[key] = proc.returncode
                    del running[key]
            time.sleep(poll)
    except KeyboardInterrupt:
        _stop(running)
        kill_descendants()  # a child forked as the signal came, before Popen returned: in no list, in its own session
        raise
    return codes


def _stop(running: dict) -> None:
    for proc in running.values():
        proc.send_signal(signal.SIGTERM)  # (Popen's own check: nothing once it has exited)
    deadline = time.monotonic() + 5.0
    for proc in running.values():
        try:
            proc.wait(timeout=max(0.0, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def _stats(values: list[float]) -> dict:
    return {"n": len(values), "mean": sum(values) / len(values), "min": min(values), "max": max(values),
            "success_rates": values}


def aggregate(results: list[dict]) -> dict:
    """Per algorithm: held-out success at each checkpoint (``minutes``) and of the final policy over the runs
    that finished (``mean``, ``min``, ``max``, ``success_rates``; fractions in [0, 1]), and before their first
    update as ``start`` where the runs evaluated it (``--eval-start``)."""
    out = {}
    for algo in sorted({r["algo"].lower() for r in results}):
        done = [r for r in results if r["algo"].lower() == algo and r.get("returncode") == 0]
        entry = {"runs": len(done), "failed": sum(1 for r in results if r["algo"].lower() == algo) - len(done)}
        by_minute = {}
        for r in done:
            for cp in r.get("checkpoints", ()):
                by_minute.setdefault(float(cp["minutes"]), []).append(float(cp["success_rate"]))
        entry["checkpoints"] = [{"minutes": m, **_stats(v)} for m, v in sorted(by_minute.items())]
        starts = [float(r["start"]["success_rate"]) for r in done if "start" in r]
        if starts:  # --eval-start: the policies before their first update
            entry["start"] = _stats(starts)
        if done:
            entry["final"] = {"timesteps": [int(r["timesteps"]) for r in done],
                              **_stats([float(r["success_rate"]) for r in done])}
        out[algo] = entry
    return out


def plot(summary: dict, results: list[dict], path: Path) -> None:
    """Held-out success against CPU minutes: each algorithm's mean, min-max band and every seed's curve."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from simgrip.io import atomic_write

    fig, ax = plt.subplots(figsize=(6.4, 4.0), constrained_layout=True)
    for i, (algo, entry) in enumerate(summary.items()):
        color = f"C{i}"
        cps = entry["checkpoints"]
        if cps:
            m = [c["minutes"] for c in cps]
            ax.plot(m, [c["mean"] for c in cps], "o-", color=color,
                    label=f"{algo.upper()} mean of {max(c['n'] for c in cps)} seeds")
            ax.fill_between(m, [c["min"] for c in cps], [c["max"] for c in cps], color=color, alpha=0.2,
                            label=f"{algo.upper()} min-max")
        for r in results:
            if r["algo"].lower() == algo and r.get("returncode") == 0 and r.get("checkpoints"):
                ax.plot([c["minutes"] for c in r["checkpoints"]], [c["success_rate"] for c in r["checkpoints"]],
                        color=color, lw=0.7, alpha=0.5)
    ax.set_xlabel("training budget (CPU minutes, one core)")
    ax.set_ylabel("held-out success (deterministic policy)")
    ax.set_ylim(-0.02, 1.02)
    ax.grid(alpha=0.3)
    if summary:
        ax.legend(fontsize=8)
    with atomic_write(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=110)
    plt.close(fig)


#: the fields of a batch's aggregate.json that may differ between batches of one experiment
_PER_BATCH = ("seeds", "summary", "command", "combined_from", "note")


def _read_json(path: Path, what: str) -> dict:
    try:
        value = json.loads(path.read_text())
    except (OSError, ValueError) as e:
        raise ValueError(f"--combine: cannot read {what} {path}: {e}") from None
    if not isinstance(value, dict):
        raise ValueError(f"--combine: {path} is not a JSON object")
    return value


def combine(batches: list[Path]) -> tuple[dict, list[dict]]:
    """``(aggregate, results)`` of batches of one experiment, as :func:`main` would have written them had it run
    every seed at once: the first batch's fields, the seeds merged (sorted), the summary recomputed with
    :func:`aggregate`, ``combined_from`` the batches' commands.  ``results``: every run's ``<algo>_seed<S>.json``.

    Raises ValueError naming ``--combine`` when a batch lacks a file, the batches differ in a field other than
    ``_PER_BATCH`` (the field named; replays of records in several folders: ``replay`` lists them), or a seed is in
    two batches."""
    if len(batches) < 2:
        raise ValueError(f"--combine: at least two batch folders, got {len(batches)}")
    if len(set(b.resolve() for b in batches)) != len(batches):
        raise ValueError("--combine: a batch folder is named twice")
    heads = [_read_json(b / "aggregate.json", "the batch's aggregate") for b in batches]
    first = heads[0]
    for b, head in zip(batches[1:], heads[1:]):
        for key in sorted(set(first) | set(head)):
            if key not in _PER_BATCH and first.get(key) != head.get(key) and not (key == "replay" and key in head
                                                                               and key in first):
                raise ValueError(f"--combine: {b} is not the experiment of {batches[0]}: {key!r} differs "
                                 f"({head.get(key)!r}, not {first.get(key)!r})")
    seeds: list[int] = []
    for b, head in zip(batches, heads):
        got = head.get("seeds")
        if not isinstance(got, list) or not got:
            raise ValueError(f"--combine: {b / 'aggregate.json'} names no seeds")
        again = sorted(set(got) & set(seeds))
        if again:
            raise ValueError(f"--combine: seed {again[0]} is in two batches ({b} and an earlier one)")
        seeds += got
    results = []
    for b, head in zip(batches, heads):
        for algo in first.get("algos", ()):
            for seed in head["seeds"]:
                results.append(_read_json(b / f"{algo}_seed{seed}.json", "the run's result"))
    combined = {k: v for k, v in first.items() if k not in _PER_BATCH}
    folders = list(dict.fromkeys(head["replay"] for head in heads if "replay" in head))
    combined.update(seeds=sorted(seeds), summary=aggregate(results), combined_from=[h.get("command") for h in heads],
                    **({"replay": folders} if len(folders) > 1 else {}))
    return combined, results


def _print_summary(summary: dict) -> None:
    for algo, entry in summary.items():
        final = entry.get("final")
        text = (f"held-out success mean {final['mean']:.2f} (min {final['min']:.2f}, max {final['max']:.2f})"
                if final else "no run finished")
        print(f"{algo.upper()}: {entry['runs']} runs, {text}", flush=True)


def _main_combine(argv: list[str]) -> int:
    p = CommandParser(prog="rl_baselines.py --combine",
                                description="Combine batches of one experiment (see the module docstring).")
    p.add_argument("--combine", nargs="+", required=True, metavar="BATCH", help="the batches' --out folders")
    p.add_argument("--out", required=True, help="output folder (not one of the batches)")
    args = p.parse_args(argv)
    from simgrip.io import check_output_dir, check_output_files_in, write_json

    batches = [Path(b) for b in args.combine]
    try:
        for b in batches:
            if not b.is_dir():
                raise ValueError(f"--combine: {b} is not a folder")
        combined, results = combine(batches)
        out = check_output_dir(args.out, "--out")
        if any(out.resolve() == b.resolve() for b in batches):
            raise ValueError(f"--out: {out} is one of the batches (write the combination elsewhere)")
        names = [f"{r['algo'].lower()}_seed{r['seed']}.json" for r in results]
        check_output_files_in(out, names + ["aggregate.json", "learning_curves.png"], "--out")
    except ValueError as e:
        p.error(str(e))
    for r in results:
        write_json(out / f"{r['algo'].lower()}_seed{r['seed']}.json", r)
    combined["command"] = [Path(sys.argv[0]).name] + argv
    write_json(out / "aggregate.json", combined)
    plot(combined["summary"], results, out / "learning_curves.png")
    _print_summary(combined["summary"])
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The run mode's options (``--combine`` has its own); tests build ``run_command``'s arguments from it."""
    from simgrip.envs.evaluation import (add_training_aid_arguments, json_object, non_negative_int, positive_int,
                                         positive_minutes, training_seed)

    p = CommandParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--env", required=True, help="registered env id, e.g. simgrip/PickFragile-v7, or a retired "
                   "simgrip one (simgrip.envs.RETIRED: the runs of docs/baselines/ name them)")
    p.add_argument("--env-kwargs", type=json_object, default={}, metavar="JSON",
                   help="keyword arguments of gym.make as a JSON object, e.g. '{\"w_touch\": 0}' (an ablation; "
                        "default none)")
    p.add_argument("--algo", nargs="+", choices=ALGOS, default=list(ALGOS), help="algorithms (default ppo sac)")
    p.add_argument("--seeds", nargs="+", type=training_seed, default=[0, 1, 2],
                   help="training seeds (default 0 1 2; each at most 2**32 - 1)")
    p.add_argument("--minutes", type=positive_minutes, default=15.0, help="CPU-minute budget per run (default 15)")
    p.add_argument("--checkpoint-minutes", type=positive_minutes, default=None,
                   help="evaluate a checkpoint every so many CPU minutes (default: the final policy only)")
    p.add_argument("--steps", type=positive_int, default=10_000_000, help="environment-step cap per run (PPO: whole rollouts of 2048)")
    p.add_argument("--eval-seeds", type=_seed_range, default=(8000, 8049),
                   help="held-out evaluation seeds A-B, inclusive (default 8000-8049)")
    p.add_argument("--jobs", type=positive_int, default=1, help="runs at once (default 1, at most the cores)")
    add_training_aid_arguments(p)
    p.add_argument("--init-from", default=None, metavar="DIR",
                   help="PPO only: start each seed S from DIR/ppo_seed<S>/ppo_model.zip, an earlier run's policy "
                        "on another task (simgrip.envs.warm_start; default: fresh policies)")
    p.add_argument("--eval-start", action="store_true",
                   help="each run also evaluates its policy before the first update (JSON: start)")
    p.add_argument("--critic-warmup", type=non_negative_int, default=0, metavar="STEPS",
                   help="PPO only: each run's first STEPS steps (whole rollouts of 2048) with the policy frozen, "
                        "only the value function learning (simgrip.envs.critic_warmup; default 0: none)")
    p.add_argument("--replay", default=None, metavar="FOLDER",
                   help="rerun the batch recorded in FOLDER (its <algo>_seed<S>.json, this command being its own) "
                        "with each run checkpointed and stopped at its record's steps instead of the clock's "
                        "(simgrip.envs.budget_replay); each run's JSON compares the results as replay")
    p.add_argument("--out", required=True, help="output folder")
    return p


def main(argv=None) -> int:
    args_in = sys.argv[1:] if argv is None else list(argv)
    if "--combine" in args_in:
        return _main_combine(args_in)
    p = build_parser()
    args = p.parse_args(argv)
    cores = os.cpu_count() or 1
    if args.jobs > cores:
        p.error(f"--jobs: at most the {cores} cores of this machine, got {args.jobs}")
    from simgrip.envs.evaluation import training_conflict  # imported when used

    why = training_conflict(args)  # the options alone decide
    if why:
        p.error(why)
    if len(set(args.seeds)) != len(args.seeds):
        p.error(f"--seeds: repeated seed in {args.seeds}")
    import simgrip.envs  # noqa: F401  (registers the ids)
    from simgrip.envs.evaluation import check_env_id, training_files
    from simgrip.io import check_output_dir, check_output_files_in, write_json

    check_env_id(p, args.env, retired=True)  # train_sb3.py builds a retired one
    from simgrip.envs.env_options import check_training_env

    try:  # refused before any run starts, the env built once
        check_training_env(args)
    except ValueError as e:
        p.error(str(e))
    import importlib.util

    # after the options and the env are checked (a bad one is named whether the rl extra is there or not)
    if any(importlib.util.find_spec(m) is None for m in ("stable_baselines3", "torch")):  # found, not imported:
        p.error('needs Stable-Baselines3 and PyTorch: pip install "simgrip[rl]"')  # the children import them
    algos = list(dict.fromkeys(args.algo))
    init_command = _check_init(p, args, algos) if args.init_from is not None else None
    try:
        out = check_output_dir(args.out, "--out")
        names = [f"{a}_seed{s}.json" for a in algos for s in args.seeds] + ["aggregate.json", "learning_curves.png"]
        check_output_files_in(out, names, "--out")
        for a in algos:  # each run's folder, its log and what its train_sb3.py writes there
            for s in args.seeds:
                folder = check_output_dir(out / f"{a}_seed{s}", "--out", create=False)
                check_output_files_in(folder, ["log.txt"] + training_files(
                    [a], minutes=args.minutes, checkpoint_minutes=args.checkpoint_minutes,
                    normalize=args.normalize), "--out")
    except ValueError as e:
        p.error(str(e))
    jobs = [(a, s, run_command(a, s, args, out / f"{a}_seed{s}"), out / f"{a}_seed{s}") for a in algos
            for s in args.seeds]
    if args.replay is not None:
        why = _check_replay(args, jobs)
        if why:
            p.error(why)
    try:
        with signals_as_interrupt():  # SIGTERM too: the children run in their own sessions, only we can stop them
            codes = run_all(jobs, args.jobs)
    except KeyboardInterrupt:
        print(f"rl_baselines: interrupted; stopped the running trainings (finished results stay in {out})",
              file=sys.stderr, flush=True)
        return 130
    results = []
    for algo, seed, _, folder in jobs:
        result = {"algo": algo.upper(), "seed": seed}
        try:
            result.update(json.loads((folder / f"{algo}_eval.json").read_text()))
        except (OSError, ValueError):
            pass
        result["returncode"] = codes[(algo, seed)]
        if result["returncode"] == 0 and "success_rate" not in result:
            result["returncode"] = -1  # finished without its result file: counted as failed
        write_json(out / f"{algo}_seed{seed}.json", result)
        results.append(result)
    summary = aggregate(results)
    lo, hi = args.eval_seeds
    write_json(out / "aggregate.json", {
        "env": args.env, "algos": algos, "seeds": args.seeds, "minutes": args.minutes,
        "checkpoint_minutes": args.checkpoint_minutes, "clock": "cpu", "eval_seeds": [lo, hi],
        "hyperparameters": hyperparameters(args), "summary": summary,
        **EnvOptions.from_args(args).record()[0],  # the options' keys, as each run's <algo>_eval.json has them
        **({"critic_warmup": args.critic_warmup} if args.critic_warmup else {}),
        **({"n_envs": args.n_envs} if args.n_envs != 1 else {}),
        **({"selection": {"every_minutes": spec.every_minutes, "episodes": spec.episodes, "seeds": list(spec.seeds)}}
           if (spec := spec_from(args)) is not None else {}),
        **({"init_from": str(args.init_from), "init_command": init_command} if args.init_from is not None else {}),
        **({"wrapper": "VecNormalize (SB3 defaults: observation and return)"} if args.normalize else {}),
        **({"replay": str(args.replay)} if args.replay is not None else {}),
        "command": [Path(sys.argv[0]).name] + list(sys.argv[1:] if argv is None else argv)})
    plot(summary, results, out / "learning_curves.png")
    _print_summary(summary)
    for r in results:
        rep = r.get("replay")
        if rep:
            (mine, theirs) = rep["success_rate"]
            print(f"{r['algo']} seed {r['seed']}: {'identical to' if rep['identical'] else 'differs from'} the "
                  f"record ({mine} against {theirs} held-out success, {rep['timesteps'][0]} steps)", flush=True)
    failed = [f"{a}_seed{s}" for (a, s), c in codes.items() if c != 0]
    if failed or any(r["returncode"] != 0 for r in results):
        bad = failed or [f"{r['algo'].lower()}_seed{r['seed']}" for r in results if r["returncode"] != 0]
        print(f"rl_baselines: {len(bad)} run(s) failed, see their log.txt: {' '.join(bad)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    from simgrip.interrupt import run_main

    sys.exit(run_main(main, "rl_baselines"))
