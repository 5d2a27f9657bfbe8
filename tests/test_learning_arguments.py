"""Bad input to the learning commands is refused before any work, exit 2 naming the option (issue 18; the brief's
"robust"): values each command accepted before and then failed on hours later, or ran silently.

Each case was found by trying the commands as a hostile user would: a training seed NumPy cannot take (the run
started, then SB3 raised), ``--minutes inf`` (ran, printed ``Infinity`` as JSON), more torch threads than cores
(they only share them, and eat a CPU-time budget), a repeated algorithm (the second overwrote the first), a
checkpoint period longer than the budget (no checkpoint), a frame stack longer than an episode (290 GiB asked
of the allocator), a seed range of 10^14 episodes (MemoryError), an empty ``--out`` (stdout instead), and output
paths below the top folder that only the children wrote: a FIFO ``log.txt`` hung ``rl_baselines`` for ever, a
file where a run's folder goes and a FIFO checkpoint failed after the training.
"""

from __future__ import annotations

import os

import pytest

from helpers import load_example

def _refused(main, argv, capsys, *needles):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    err = capsys.readouterr().err
    assert exc.value.code == 2, err
    assert len(err.strip().splitlines()) == 1, err  # one line (simgrip.command_parser), the usage left to --help
    last = err.strip().splitlines()[-1]
    assert "error:" in last and "Traceback" not in err, err
    for needle in needles:
        assert needle in last, (needle, err)


TRAIN = ["--algo", "ppo", "--env", "simgrip/PickFragile-v7", "--steps", "64", "--eval-episodes", "1"]


@pytest.mark.parametrize("extra, needles", [
    (["--seed", str(2**32)], ["--seed", "4294967295"]),
    (["--minutes", "inf"], ["--minutes"]),
    (["--checkpoint-minutes", "inf"], ["--checkpoint-minutes"]),
    (["--minutes", "1", "--checkpoint-minutes", "5"], ["--checkpoint-minutes", "larger than --minutes"]),
    (["--threads", str((os.cpu_count() or 1) + 1)], ["--threads", "cores"]),
    (["--eval-episodes", "100001"], ["--eval-episodes", "100000"]),
    (["--frame-stack", "1000000"], ["--frame-stack", "300 steps"]),
    (["--minutes", "1e308"], ["--minutes", "a week"]),  # (ran: an audit)
    (["--minutes", "0.05", "--checkpoint-minutes", "0.000001"], ["--checkpoint-minutes", "at most 1000"]),
])
def test_train_sb3_refuses(extra, needles, tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    main = load_example("train_sb3").main
    _refused(main, TRAIN + extra + ["--out", str(tmp_path / "run")], capsys, *needles)
    assert not (tmp_path / "run").exists()


def test_train_sb3_refuses_a_repeated_algorithm(tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    argv = ["--algo", "ppo", "ppo", "--env", "simgrip/PickFragile-v7", "--out", str(tmp_path / "run")]
    _refused(load_example("train_sb3").main, argv, capsys, "--algo", "repeated")


def test_train_sb3_checks_its_checkpoints_before_training(tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    (tmp_path / "run").mkdir()
    os.mkfifo(tmp_path / "run" / "ppo_model_10min.zip")  # the second of 15 // 5 + 1 checkpoints checked
    _refused(load_example("train_sb3").main, TRAIN + ["--minutes", "15", "--checkpoint-minutes", "5", "--out",
                                                      str(tmp_path / "run")], capsys, "ppo_model_10min.zip", "FIFO")


RL = ["--env", "simgrip/PickFragile-v7", "--algo", "ppo", "--seeds", "0", "--minutes", "10", "--checkpoint-minutes",
      "5", "--eval-seeds", "8000-8000"]


@pytest.mark.parametrize("make, needles", [
    (lambda run: (run.mkdir(parents=True), os.mkfifo(run / "log.txt")), ["ppo_seed0/log.txt", "FIFO"]),
    (lambda run: (run.parent.mkdir(), run.write_text("")), ["ppo_seed0", "not a folder"]),
    (lambda run: (run.mkdir(parents=True), os.mkfifo(run / "ppo_model_5min.zip")), ["ppo_model_5min.zip", "FIFO"]),
])
def test_rl_baselines_checks_each_runs_folder_before_any_run(make, needles, tmp_path, capsys):
    """The run folders, their ``log.txt`` (which the driver opens) and what each child's train_sb3.py writes."""
    pytest.importorskip("stable_baselines3")
    make(tmp_path / "runs" / "ppo_seed0")
    _refused(load_example("rl_baselines").main, RL + ["--out", str(tmp_path / "runs")], capsys, "--out", *needles)


@pytest.mark.parametrize("extra, needles", [
    (["--seeds", str(2**32)], ["--seeds", "4294967295"]),
    (["--eval-seeds", "0-100000"], ["--eval-seeds", "100000 seeds"]),
    (["--frame-stack", "301"], ["--frame-stack", "300 steps"]),
    (["--minutes", "1e308"], ["--minutes", "a week"]),
    (["--minutes", "0.05", "--checkpoint-minutes", "0.000001"], ["--checkpoint-minutes", "at most 1000"]),
])
def test_rl_baselines_refuses(extra, needles, tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    _refused(load_example("rl_baselines").main, RL + extra + ["--out", str(tmp_path / "runs")], capsys, *needles)
    assert not (tmp_path / "runs").exists()


def test_evaluate_policy_refuses_more_episodes_than_any_rate_needs(capsys):
    argv = ["--env", "simgrip/PickFragile-v7", "--policy", "observation", "--episodes", "100001"]
    _refused(load_example("evaluate_policy").main, argv, capsys, "--episodes", "100000")


@pytest.mark.parametrize("value", ["-inf", "-1e6", "-0.5"])
def test_a_negative_number_reaches_its_option_in_one_line(value, capsys):
    """The examples parse as the ``simgrip`` command does (:mod:`simgrip.command_parser`): a negative number is a
    value (``--gamma -inf`` was "expected one argument"), and the error is one line, not argparse's usage block
    (4-13 lines: an audit)."""
    argv = ["--env", "simgrip/PickFragile-v7", "--policy", "observation", "--gamma", value]
    _refused(load_example("evaluate_policy").main, argv, capsys, "--gamma")


@pytest.mark.parametrize("extra, needles", [
    (["--seeds", "0-99999999999999"], ["--seeds", "100000 seeds"]),
    (["--seeds", "0-1", "--out", ""], ["--out"]),
])
def test_baselines_refuses(extra, needles, capsys):
    from simgrip.envs.baselines import main

    _refused(main, ["--env", "simgrip/PickFragile-v7", "--policy", "random", *extra], capsys, *needles)
