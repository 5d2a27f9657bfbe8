"""examples/rl_baselines.py: one process per (algorithm, seed), the aggregate over seeds, bad input, Ctrl-C.

The training tests use a budget of seconds (they check the plumbing, not learning) and are skipped without
Stable-Baselines3 (the ``rl`` extra).
"""

from __future__ import annotations

import importlib.util
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from helpers import rl_baselines_args

SCRIPT = Path(__file__).resolve().parent.parent / "examples" / "rl_baselines.py"
ROOT = SCRIPT.parent.parent


def _module():
    spec = importlib.util.spec_from_file_location("rl_baselines", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _env():
    import simgrip

    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(Path(simgrip.__file__).resolve().parent.parent),
                                         env.get("PYTHONPATH", "")])
    return env


def test_aggregate_mean_min_max_per_checkpoint_and_failed_runs():
    agg = _module().aggregate
    runs = [
        {"algo": "PPO", "seed": 0, "returncode": 0, "success_rate": 0.5, "timesteps": 10,
         "checkpoints": [{"minutes": 5.0, "success_rate": 0.1}, {"minutes": 10.0, "success_rate": 0.4}]},
        {"algo": "PPO", "seed": 1, "returncode": 0, "success_rate": 0.9, "timesteps": 12,
         "checkpoints": [{"minutes": 5.0, "success_rate": 0.3}, {"minutes": 10.0, "success_rate": 0.8}]},
        {"algo": "PPO", "seed": 2, "returncode": 1},
    ]
    s = agg(runs)["ppo"]
    assert s["runs"] == 2 and s["failed"] == 1
    c5, c10 = s["checkpoints"]
    assert c5["minutes"] == 5.0 and c5["n"] == 2 and c5["min"] == 0.1 and c5["max"] == 0.3
    assert c5["mean"] == pytest.approx(0.2, abs=1e-12) and c10["mean"] == pytest.approx(0.6, abs=1e-12)
    assert s["final"]["success_rates"] == [0.5, 0.9] and s["final"]["mean"] == pytest.approx(0.7, abs=1e-12)


@pytest.mark.parametrize("extra, word", [
    (["--jobs", str((os.cpu_count() or 1) + 1)], "--jobs"),
    (["--eval-seeds", "9-3"], "--eval-seeds"),
    (["--minutes", "0"], "--minutes"),
    (["--seeds", "1", "1"], "--seeds"),
    (["--env-kwargs", "[1]"], "--env-kwargs"),
    (["--env-kwargs", "{w_touch: 0}"], "--env-kwargs"),
    (["--gamma", "0"], "--gamma"),
    (["--gamma", "1.5"], "--gamma"),
    (["--gamma", "nan"], "--gamma"),
    (["--log-std-init", "nan"], "--log-std-init"),
    (["--log-std-init", "-6"], "--log-std-init"),
    (["--log-std-init", "-1", "--algo", "sac"], "--log-std-init"),
    (["--log-std-init", "-1", "--algo", "ppo", "sac"], "--log-std-init"),
    (["--critic-warmup", "-1", "--algo", "ppo"], "--critic-warmup"),
    (["--critic-warmup", "2048", "--algo", "sac"], "--critic-warmup"),
    (["--crush-charge", "-1"], "--crush-charge"),
    (["--crush-charge", "inf"], "--crush-charge"),
    (["--crush-charge-from", "100"], "--crush-charge-from"),
    (["--crush-charge", "1", "--crush-charge-from", "-5"], "--crush-charge-from"),
])
def test_bad_arguments_exit_2_with_one_line(extra, word, tmp_path, capsys):
    argv = ["--env", "simgrip/PickFragile-v0", "--out", str(tmp_path / "o"), *extra]
    with pytest.raises(SystemExit) as e:
        _module().main(argv)
    assert e.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert word in err[-1] and "Traceback" not in "\n".join(err)


def test_smoke_two_seeds_aggregate_and_plot(tmp_path):
    _needs_sb3()
    out = tmp_path / "runs"
    cmd = [sys.executable, str(SCRIPT), "--env", "simgrip/PickFragile-v0", "--algo", "sac", "--seeds", "0", "1",
           "--minutes", "0.02", "--checkpoint-minutes", "0.01", "--eval-seeds", "8000-8001",
           "--jobs", str(min(2, os.cpu_count() or 1)), "--out", str(out)]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=_env(), cwd=ROOT)
    assert r.returncode == 0, r.stderr[-2000:]
    runs = [json.loads((out / f"sac_seed{s}.json").read_text()) for s in (0, 1)]
    assert [x["seed"] for x in runs] == [0, 1] and all(x["returncode"] == 0 for x in runs)
    assert all(x["eval_seeds"] == [8000, 8001] and x["episodes"] == 2 for x in runs)
    agg = json.loads((out / "aggregate.json").read_text())
    final = agg["summary"]["sac"]["final"]
    rates = [x["success_rate"] for x in runs]
    assert final["success_rates"] == rates and final["min"] == min(rates) and final["max"] == max(rates)
    assert agg["summary"]["sac"]["checkpoints"][0]["minutes"] == 0.01
    assert (out / "learning_curves.png").stat().st_size > 0
    assert (out / "sac_seed0" / "log.txt").exists()


def test_env_kwargs_the_env_does_not_take_exit_2_before_any_run(tmp_path, capsys):
    _needs_sb3()
    argv = ["--env", "simgrip/PickFragile-v7", "--out", str(tmp_path / "o"), "--env-kwargs", '{"w_tuch": 0}']
    with pytest.raises(SystemExit) as e:
        _module().main(argv)
    assert e.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert "--env-kwargs" in err[-1] and "w_tuch" in err[-1]
    assert not (tmp_path / "o").exists()


def _needs_sb3():
    if importlib.util.find_spec("stable_baselines3") is None:  # found without importing torch here
        pytest.skip("needs Stable-Baselines3 (the rl extra)")


def _state_and_start(pid: int) -> tuple[str, str] | None:
    """A process's state letter and start time (clock ticks since boot) from ``/proc/PID/stat``; None when gone.
    The start time tells a process from a later one given the same pid (pids wrap at ``pid_max``)."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = text[text.rindex(")") + 2:].split()  # after "pid (comm) ": state is field 3, starttime field 22
    return fields[0], fields[19]


def _children(pid: int) -> list[int]:
    try:
        text = Path(f"/proc/{pid}/task/{pid}/children").read_text()
    except OSError:
        return []
    return [int(c) for c in text.split()]


@pytest.mark.skipif(not Path("/proc/self/task").exists(), reason="reads the child list from /proc")
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_ctrl_c_or_sigterm_stops_every_child_with_one_line(tmp_path, signum):
    """Ctrl-C, and SIGTERM (a `kill`, `timeout`, a batch scheduler), stop the trainings too: each runs in its own
    session, so only the driver can stop it (before SIGTERM was handled it left them running to their budget)."""
    _needs_sb3()
    cmd = [sys.executable, str(SCRIPT), "--env", "simgrip/PickFragile-v0", "--algo", "ppo", "--seeds", "0",
           "--minutes", "10", "--eval-seeds", "8000-8001", "--out", str(tmp_path / "runs")]
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=_env(), cwd=ROOT)
    try:
        deadline = time.monotonic() + 60
        kids = []
        while not kids and time.monotonic() < deadline and p.poll() is None:
            time.sleep(0.2)
            kids = _children(p.pid)
        assert kids, "the driver started no training process"
        started = {k: _state_and_start(k) for k in kids}
        p.send_signal(signum)
        _, err = p.communicate(timeout=30)
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
    alive = []
    for k in kids:  # gone (or a zombie nobody waits for: not running), or its pid now another process's
        now = _state_and_start(k)
        if not (now is None or now[0] in ("Z", "X") or started[k] is None or now[1] != started[k][1]):
            alive.append(k)
            os.kill(k, signal.SIGKILL)  # a failing run leaves no training behind
    assert p.returncode == 130
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "interrupted" in lines[0]
    assert not alive, alive


@pytest.mark.skipif(not Path("/proc/self/task").exists(), reason="finds the stray child through /proc")
def test_an_interrupt_as_a_child_starts_stops_that_child_too(tmp_path, monkeypatch):
    """A signal that comes after a child is forked and before the driver has listed it (inside Popen, which waits for
    the exec, or just after; the window the test above hit on a loaded machine) leaves that child in no list, in a
    session of its own: ``run_all`` kills it all the same."""
    mod = _module()
    real, started = subprocess.Popen, []

    def popen_then_interrupt(*args, **kwargs):
        started.append(real(*args, **kwargs))
        raise KeyboardInterrupt  # as if the signal came before Popen returned

    monkeypatch.setattr(mod.subprocess, "Popen", popen_then_interrupt)
    with pytest.raises(KeyboardInterrupt):
        mod.run_all([("ppo", 0, [sys.executable, "-c", "import time; time.sleep(60)"], tmp_path / "run")], 1)
    child, = started
    try:
        assert child.wait(timeout=10) == -signal.SIGKILL  # stopped, not left to run its budget
    finally:
        child.kill()


def test_normalize_reaches_every_run_command(tmp_path):
    mod = _module()
    args = rl_baselines_args(mod, normalize=True)
    assert "--normalize" in mod.run_command("ppo", 0, args, tmp_path)
    args.normalize = False
    assert "--normalize" not in mod.run_command("ppo", 0, args, tmp_path)


def test_action_offset_reaches_every_run_command(tmp_path):
    mod = _module()
    args = rl_baselines_args(mod, action_offset=[-0.4, 0.2])
    cmd = mod.run_command("ppo", 0, args, tmp_path)
    i = cmd.index("--action-offset")
    assert [float(x) for x in cmd[i + 1:i + 3]] == [-0.4, 0.2]
    args.action_offset = None
    assert "--action-offset" not in mod.run_command("ppo", 0, args, tmp_path)


def test_gamma_reaches_every_run_command(tmp_path):
    mod = _module()
    args = rl_baselines_args(mod, gamma=0.995)
    cmd = mod.run_command("ppo", 0, args, tmp_path)
    assert float(cmd[cmd.index("--gamma") + 1]) == 0.995
    args.gamma = None
    assert "--gamma" not in mod.run_command("ppo", 0, args, tmp_path)  # the library's default, not written


def test_log_std_init_reaches_every_run_command(tmp_path):
    mod = _module()
    args = rl_baselines_args(mod, log_std_init=-1.0)
    cmd = mod.run_command("ppo", 0, args, tmp_path)
    assert float(cmd[cmd.index("--log-std-init") + 1]) == -1.0
    args.log_std_init = None
    assert "--log-std-init" not in mod.run_command("ppo", 0, args, tmp_path)  # the library's default, not written


def test_critic_warmup_reaches_every_run_command(tmp_path):
    mod = _module()
    args = rl_baselines_args(mod, critic_warmup=40960)
    cmd = mod.run_command("ppo", 0, args, tmp_path)
    assert cmd[cmd.index("--critic-warmup") + 1] == "40960"
    args.critic_warmup = 0
    assert "--critic-warmup" not in mod.run_command("ppo", 0, args, tmp_path)  # none: not written


def test_crush_charge_reaches_every_run_command(tmp_path):
    mod = _module()
    args = rl_baselines_args(mod, crush_charge=20.0, crush_charge_from=262144)
    cmd = mod.run_command("ppo", 0, args, tmp_path)
    assert float(cmd[cmd.index("--crush-charge") + 1]) == 20.0 and cmd[cmd.index("--crush-charge-from") + 1] == "262144"
    args.crush_charge = None
    assert "--crush-charge" not in mod.run_command("ppo", 0, args, tmp_path)  # none: not written


def test_crush_charge_is_refused_where_nothing_crushes(tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        _module().main(["--env", "simgrip/Pick-v1", "--crush-charge", "1", "--out", str(tmp_path / "o")])
    assert e.value.code == 2 and "--crush-charge" in capsys.readouterr().err.strip().splitlines()[-1]


def test_eval_start_reaches_every_run_command_and_the_aggregate(tmp_path):
    mod = _module()
    assert "--eval-start" in mod.run_command("ppo", 0, rl_baselines_args(mod, eval_start=True), tmp_path)
    assert "--eval-start" not in mod.run_command("ppo", 0, rl_baselines_args(mod), tmp_path)
    runs = [{"algo": "PPO", "seed": s, "returncode": 0, "success_rate": 0.5, "timesteps": 10,
             "start": {"success_rate": rate}} for s, rate in ((0, 0.96), (1, 0.9))]
    start = mod.aggregate(runs)["ppo"]["start"]
    assert start["success_rates"] == [0.96, 0.9] and start["min"] == 0.9 and start["max"] == 0.96
    assert "start" not in mod.aggregate([{k: v for k, v in r.items() if k != "start"} for r in runs])["ppo"]


def test_frame_stack_reaches_every_run_command(tmp_path):
    mod = _module()
    args = rl_baselines_args(mod, frame_stack=3)
    cmd = mod.run_command("ppo", 0, args, tmp_path)
    assert cmd[cmd.index("--frame-stack") + 1] == "3"
    args.frame_stack = None
    assert "--frame-stack" not in mod.run_command("ppo", 0, args, tmp_path)


@pytest.mark.parametrize("value", ["0", "-2", "1.5", "x"])
def test_a_bad_frame_stack_exits_2_naming_it(value, tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        _module().main(["--env", "simgrip/PickFragile-v7", "--out", str(tmp_path / "o"), "--frame-stack", value])
    assert e.value.code == 2 and "--frame-stack" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("option, env_id", [("--scripted-start", "simgrip/PlaceFragile-v8"),
                                            ("--light-bias", "simgrip/PickMultiFragile-v7")])
def test_a_training_aid_reaches_every_run_command(option, env_id, tmp_path):
    mod = _module()
    name = option[2:].replace("-", "_")
    args = rl_baselines_args(mod, env=env_id, **{name: 0.5})
    cmd = mod.run_command("ppo", 0, args, tmp_path)
    assert float(cmd[cmd.index(option) + 1]) == 0.5
    setattr(args, name, None)
    assert option not in mod.run_command("ppo", 0, args, tmp_path)


@pytest.mark.parametrize("option, env_id, value", [
    ("--scripted-start", "simgrip/PlaceFragile-v8", "1.5"), ("--scripted-start", "simgrip/PlaceFragile-v8", "nan"),
    ("--scripted-start", "simgrip/PlaceFragile-v8", "x"), ("--scripted-start", "simgrip/Pick-v1", "0.5"),
    ("--light-bias", "simgrip/PickMultiFragile-v7", "1.5"), ("--light-bias", "simgrip/PickMultiFragile-v7", "nan"),
    ("--light-bias", "simgrip/Pick-v1", "0.5")])
def test_a_bad_training_aid_exits_2_naming_it(option, env_id, value, tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        _module().main(["--env", env_id, "--out", str(tmp_path / "o"), option, value])
    assert e.value.code == 2 and option in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def _batch(folder: Path, seeds, rates, **fields) -> Path:
    """A batch folder as ``main`` writes it (no training): ``aggregate.json`` and one ``ppo_seed<S>.json`` a
    seed, each run's held-out success ``rates[i]`` at 5 and 10 CPU-minutes and at the end."""
    folder.mkdir(parents=True)
    results = []
    for s, rate in zip(seeds, rates):
        r = {"algo": "PPO", "seed": s, "returncode": 0, "success_rate": rate, "timesteps": 100 + s,
             "checkpoints": [{"minutes": 5.0, "success_rate": rate / 2}, {"minutes": 10.0, "success_rate": rate}]}
        (folder / f"ppo_seed{s}.json").write_text(json.dumps(r))
        results.append(r)
    head = {"env": "simgrip/PickFragile-v7", "algos": ["ppo"], "seeds": list(seeds), "minutes": 10.0,
            "checkpoint_minutes": 5.0, "clock": "cpu", "eval_seeds": [8000, 8049],
            "hyperparameters": "Stable-Baselines3 defaults, one env, one torch thread",
            "summary": _module().aggregate(results), "command": ["rl_baselines.py", "--seeds", *map(str, seeds)],
            **fields}
    (folder / "aggregate.json").write_text(json.dumps(head))
    return folder


def test_combine_merges_batches_as_one_run_would(tmp_path):
    mod = _module()
    a = _batch(tmp_path / "a", [0, 1], [0.2, 0.8], action_offset=[-0.4, 0.2])
    b = _batch(tmp_path / "b", [2], [0.5], action_offset=[-0.4, 0.2])
    out = tmp_path / "out"
    assert mod.main(["--combine", str(a), str(b), "--out", str(out)]) == 0
    agg = json.loads((out / "aggregate.json").read_text())
    one = _batch(tmp_path / "one", [0, 1, 2], [0.2, 0.8, 0.5], action_offset=[-0.4, 0.2])  # all seeds at once
    assert agg["summary"] == json.loads((one / "aggregate.json").read_text())["summary"]
    assert agg["seeds"] == [0, 1, 2] and agg["action_offset"] == [-0.4, 0.2]
    assert agg["combined_from"] == [["rl_baselines.py", "--seeds", "0", "1"], ["rl_baselines.py", "--seeds", "2"]]
    assert agg["command"][1:] == ["--combine", str(a), str(b), "--out", str(out)]
    final = agg["summary"]["ppo"]["final"]
    assert final["success_rates"] == [0.2, 0.8, 0.5] and final["mean"] == pytest.approx(0.5, abs=1e-12)
    for s in (0, 1, 2):
        assert json.loads((out / f"ppo_seed{s}.json").read_text())["seed"] == s
    assert (out / "learning_curves.png").stat().st_size > 0


def test_combine_merges_replays_of_records_in_several_folders(tmp_path):
    """Replays (``replay``: the folder of their records) combine whether their records share a folder or not; a
    replay does not combine with a batch that is not one."""
    mod = _module()
    a = _batch(tmp_path / "a", [0], [0.2], replay="/r/x")
    b = _batch(tmp_path / "b", [1], [0.8], replay="/r/y")
    c = _batch(tmp_path / "c", [2], [0.5], replay="/r/y")
    assert mod.main(["--combine", str(a), str(b), str(c), "--out", str(tmp_path / "o")]) == 0
    assert json.loads((tmp_path / "o" / "aggregate.json").read_text())["replay"] == ["/r/x", "/r/y"]
    assert mod.main(["--combine", str(b), str(c), "--out", str(tmp_path / "o2")]) == 0
    assert json.loads((tmp_path / "o2" / "aggregate.json").read_text())["replay"] == "/r/y"
    plain = _batch(tmp_path / "p", [3], [0.5])
    with pytest.raises(SystemExit) as e:
        mod.main(["--combine", str(a), str(plain), "--out", str(tmp_path / "o3")])
    assert e.value.code == 2


@pytest.mark.parametrize("case, word", [
    ("other_minutes", "'minutes' differs"), ("other_aid", "'action_offset' differs"), ("seed_twice", "seed 1"),
    ("one_batch", "at least two"), ("missing_run", "ppo_seed2.json"), ("out_is_a_batch", "--out"),
    ("not_a_folder", "not a folder"),
])
def test_combine_refuses_what_is_not_one_experiment(case, word, tmp_path, capsys):
    a = _batch(tmp_path / "a", [0, 1], [0.2, 0.8], action_offset=[-0.4, 0.2])
    other = {"other_minutes": dict(minutes=15.0, action_offset=[-0.4, 0.2]), "other_aid": {}}.get(
        case, dict(action_offset=[-0.4, 0.2]))
    b = _batch(tmp_path / "b", [1] if case == "seed_twice" else [2], [0.5], **other)
    if case == "missing_run":
        (b / "ppo_seed2.json").unlink()
    batches = {"one_batch": [a], "not_a_folder": [a, tmp_path / "nothing"]}.get(case, [a, b])
    out = a if case == "out_is_a_batch" else tmp_path / "out"
    with pytest.raises(SystemExit) as e:
        _module().main(["--combine", *map(str, batches), "--out", str(out)])
    assert e.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert word in err[-1] and "Traceback" not in "\n".join(err)
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
