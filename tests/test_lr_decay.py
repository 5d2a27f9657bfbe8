"""The learning rate falling to 0 over the budget (issue 18's training aids): :class:`simgrip.envs.lr_decay.BudgetDecay`
and ``train_sb3.py --lr-decay`` / ``rl_baselines.py --lr-decay``.

The schedule is checked on a clock the test moves (its value is linear in the time spent, whatever SB3's progress
says), and the training script on one PPO update: the rate that update used is the schedule's at that moment,
below the library's and above 0, and the saved model keeps the schedule.
"""

from __future__ import annotations

import json
import math
import pickle

import pytest

from simgrip.envs import lr_decay
from simgrip.envs.lr_decay import BudgetDecay
from helpers import load_example as _example, rl_baselines_args


@pytest.fixture
def clock(monkeypatch):
    """A CPU clock the test sets: ``clock[0]`` seconds."""
    now = [100.0]
    monkeypatch.setitem(lr_decay._CLOCKS, "cpu", lambda: now[0])
    return now


def test_the_rate_falls_linearly_to_zero_over_the_budget_whatever_sb3s_progress(clock):
    decay = BudgetDecay(3e-4, 60.0)
    for spent, expected in ((0.0, 3e-4), (15.0, 2.25e-4), (30.0, 1.5e-4), (59.999, 3e-4 * 0.001 / 60), (60.0, 0.0),
                            (600.0, 0.0)):
        clock[0] = 100.0 + spent
        for progress in (1.0, 0.5, 0.0):  # SB3's step-based progress is not read
            assert math.isclose(decay(progress), expected, rel_tol=1e-9, abs_tol=1e-18), (spent, progress)
    assert decay.fraction_left() == 0.0


def test_start_restarts_the_budget(clock):
    decay = BudgetDecay(1.0, 10.0)
    clock[0] = 105.0
    assert decay(1.0) == 0.5
    decay.start()  # e.g. after an evaluation before the training
    assert decay(1.0) == 1.0
    clock[0] = 107.5
    assert decay(1.0) == 0.75


def test_start_at_a_reading_of_the_clock_counts_from_it(clock):
    """The training script starts the schedule at its budget's start, a reading taken before the model was built."""
    clock[0] = 130.0
    decay = BudgetDecay(1.0, 60.0)
    decay.start(at=100.0)
    assert decay.started == 100.0 and decay(1.0) == 0.5
    clock[0] = 160.0
    assert decay(1.0) == 0.0  # the budget's end on the budget's own count, not 60 s after the schedule was made
    for bad in (math.nan, math.inf, "100", True):
        with pytest.raises(ValueError, match="at"):
            decay.start(at=bad)


def test_each_call_keeps_its_reading_and_a_replay_returns_the_readings_in_order(clock):
    decay = BudgetDecay(1e-3, 100.0, "cpu")
    rates = []
    for t in (100.0, 125.0, 125.0, 150.0, 300.0):
        clock[0] = t
        rates.append(decay(0.3))
    assert decay.readings == [1.0, 0.75, 0.75, 0.5, 0.0]
    assert rates == [1e-3 * s for s in decay.readings]
    again = BudgetDecay(1e-3, 100.0, "cpu", replay=decay.readings)
    clock[0] = 900.0  # the clock is not read: the record's readings are
    assert [again(0.9) for _ in range(5)] == rates and again.readings == decay.readings
    with pytest.raises(RuntimeError, match="read its learning rate 6 times; the record kept 5 readings"):
        again(0.9)
    for bad in ([1.2], [-0.1], [math.nan], ["0.5"], [True]):
        with pytest.raises(ValueError, match="replay"):
            BudgetDecay(1e-3, 100.0, "cpu", replay=bad)


def test_it_pickles_with_its_numbers_and_clock():
    decay = BudgetDecay(3e-4, 900.0, "wall")
    again = pickle.loads(pickle.dumps(decay))
    assert (again.initial, again.budget_s, again.clock, again.started) == (3e-4, 900.0, "wall", decay.started)
    assert repr(again) == "BudgetDecay(0.0003, 900.0, 'wall')"
    decay(1.0)  # its readings and a replay's shares stay behind: a saved model holds the schedule, not its history
    replayed = BudgetDecay(3e-4, 900.0, "wall", replay=[1.0, 0.5])
    for d in (decay, replayed):
        back = pickle.loads(pickle.dumps(d))
        assert back.readings == [] and back.replay is None and back.initial == 3e-4
    old = BudgetDecay(3e-4, 900.0, "wall")  # pickled before the readings were kept: without them
    state = {k: v for k, v in old.__dict__.items() if k not in ("readings", "replay")}
    restored = BudgetDecay.__new__(BudgetDecay)
    restored.__setstate__(state)
    assert restored.readings == [] and restored.replay is None and 0.0 <= restored(1.0) <= 3e-4


@pytest.mark.parametrize("args, word", [((0.0, 60.0), "initial"), ((-3e-4, 60.0), "initial"),
                                        ((math.nan, 60.0), "initial"), ((True, 60.0), "initial"),
                                        ((3e-4, 0.0), "budget_s"), ((3e-4, math.inf), "budget_s"),
                                        ((3e-4, "60"), "budget_s")])
def test_bad_numbers_are_refused_by_name(args, word):
    with pytest.raises(ValueError, match=word):
        BudgetDecay(*args)


def test_an_unknown_clock_is_refused():
    with pytest.raises(ValueError, match="clock"):
        BudgetDecay(3e-4, 60.0, "gpu")


def test_lr_decay_reaches_every_run_command_and_the_aggregate_names_it(tmp_path):
    mod = _example("rl_baselines")
    args = rl_baselines_args(mod, lr_decay=True)
    assert "--lr-decay" in mod.run_command("ppo", 0, args, tmp_path)
    args.lr_decay = False
    assert "--lr-decay" not in mod.run_command("ppo", 0, args, tmp_path)  # the library's constant rate


def test_train_sb3_lr_decay_uses_the_schedule_and_says_so(tmp_path):
    """One rollout (2048 steps) and one update within a budget of 2 CPU-minutes: the update's rate is SB3's default
    times the share of the budget left then, so strictly between 0 and 3e-4, and the saved model's schedule is the
    budget's."""
    pytest.importorskip("stable_baselines3")
    import time

    from stable_baselines3 import PPO

    before = time.process_time()
    _example("train_sb3").main(["--algo", "ppo", "--env", "simgrip/PickFragile-v7", "--steps", "64",
                                "--minutes", "2", "--lr-decay", "--eval-episodes", "1", "--eval-seed", "8310",
                                "--out", str(tmp_path)])
    trained = json.loads((tmp_path / "ppo_eval.json").read_text())
    assert trained["hyperparameters"] == ("Stable-Baselines3 defaults but learning_rate = 0.0003 falling linearly "
                                          "to 0 over the budget")
    spent = trained["cpu_s"]  # the whole training's CPU time, the update inside it
    model = PPO.load(tmp_path / "ppo_model.zip", device="cpu")
    assert isinstance(model.learning_rate, BudgetDecay)
    assert (model.learning_rate.initial, model.learning_rate.budget_s) == (3e-4, 120.0)
    assert before <= model.learning_rate.started <= time.process_time() - spent  # from the budget's start
    used = model.policy.optimizer.param_groups[0]["lr"]
    assert 3e-4 * (1.0 - spent / 120.0) <= used < 3e-4, (used, spent)
