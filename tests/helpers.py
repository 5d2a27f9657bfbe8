"""Small helpers shared by several test modules (not tests themselves): loading an example script, a process's life."""

from __future__ import annotations

import importlib.util
from pathlib import Path


def load_example(name: str, tag: str = ""):
    """``examples/<name>.py`` imported as a module (the examples are scripts, not a package)."""
    path = Path(__file__).resolve().parents[1] / "examples" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"example_{name}{tag}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def train_and_evaluate_again(env: str, options: list, out: Path, tag: str):
    """``train_sb3.py`` (PPO, 64 steps, 2 held-out episodes from seed 8040) on ``env`` behind the policy's
    ``options`` into ``out``, then ``evaluate_policy.py`` on its saved model with the same options and episodes:
    ``(train, evaluate, record, again)``, the two loaded scripts, the training's ``ppo_eval.json`` and the
    evaluation's JSON (whose figures the caller compares with the record's)."""
    import json

    train, ev = load_example("train_sb3", tag), load_example("evaluate_policy", tag)
    train.main(["--algo", "ppo", "--env", env, "--steps", "64", *options, "--eval-episodes", "2", "--eval-seed",
                "8040", "--out", str(out)])
    record = json.loads((out / "ppo_eval.json").read_text())
    again = ev.main(["--env", env, "--model", str(out / "ppo_model.zip"), *options, "--episodes", "2", "--seed",
                     "8040", "--json"])
    return train, ev, record, again


def rl_baselines_args(mod, env: str = "simgrip/PickFragile-v7", **overrides):
    """``examples/rl_baselines.py``'s parsed options (``mod`` is the loaded script) as its ``main`` passes them to
    ``run_command``: the script's own parser's defaults, so a new option cannot be missing, a short budget, ``env``,
    and ``overrides`` (each must be an option the parser has)."""
    args = mod.build_parser().parse_args(["--env", env, "--minutes", "1", "--steps", "10",
                                          "--eval-seeds", "8000-8001", "--out", "unused"])
    for name, value in overrides.items():
        assert hasattr(args, name), name
        setattr(args, name, value)
    return args


def assert_passes_flag(mod, env: str, name: str, folder: Path) -> None:
    """``examples/rl_baselines.py`` (``mod``, the loaded script) passes the on/off option ``name`` (its attribute,
    ``"touch_memory"`` for ``--touch-memory``) to a run's command where it is on, and not where it is off."""
    option = "--" + name.replace("_", "-")
    args = rl_baselines_args(mod, env, **{name: True})
    assert option in mod.run_command("ppo", 0, args, folder)
    setattr(args, name, False)
    assert option not in mod.run_command("ppo", 0, args, folder)


def alive(pid: int) -> bool:
    """Whether process ``pid`` exists and is not a zombie (``/proc``; Linux)."""
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def nan_position_step(x=None):
    """One ``mj_step`` of a free ball whose position is NaN: MuJoCo warns once (``mjWARN_BADQPOS``, "Nan, Inf or
    huge value in QPOS") through its warning handler and resets the state; returns the warning's count (1).
    ``x`` is ignored (a task for :func:`simgrip.parallel.runner.run_tasks`)."""
    import mujoco

    m = mujoco.MjModel.from_xml_string("<mujoco><worldbody><body><freejoint/><geom size='.1'/></body>"
                                       "</worldbody></mujoco>")
    d = mujoco.MjData(m)
    d.qpos[0] = float("nan")
    mujoco.mj_step(m, d)
    return int(d.warning[mujoco.mjtWarning.mjWARN_BADQPOS].number)
