r"""A learning rate that falls linearly to zero over a training's time budget (issue 18's training aids).

``BudgetDecay(initial, budget_s, clock)`` is a Stable-Baselines3 learning-rate schedule (a callable SB3 calls with
its ``progress_remaining`` before every update; ``learning_rate=`` of ``PPO`` or ``SAC``) whose value is

    ``initial * max(0, 1 - spent / budget_s)``,

``spent`` the seconds since :meth:`~BudgetDecay.start` on ``clock``: this process's CPU time (``"cpu"``,
``time.process_time``, what ``examples/train_sb3.py --clock cpu`` budgets) or the wall clock (``"wall"``).  It
ignores SB3's own progress, which counts environment steps against a step budget the time budget stops long
before.  This is the linear annealing of the RL Baselines3 Zoo's ``lin_3e-4`` schedules, with the budget's
time in place of its steps.  Like every time-budgeted run, the rate at a given step depends on the machine's
speed; runs stay comparable at equal CPU time.

Why (the Gymnasium environments page, "Where the learning target stands"): with SB3's constant rate
(3e-4), PPO on the K fingers can lose in its last five CPU-minutes what it learned. For example, one seed fell
from 60 % to 36 % held-out success.  A rate that reaches zero at the budget's end makes the last updates
small.

Replays (:mod:`simgrip.envs.budget_replay`): every reading of the clock a call made is kept, in call order, as the
share of the budget it left (:attr:`BudgetDecay.readings`; ``examples/train_sb3.py`` records them as ``lr_fractions``
in a PPO run's ``<algo>_eval.json``: one as the model is built, then two an update, as SB3 reads its schedule once
to log the rate and once to set it; SAC reads it at every step, too often to record).
``BudgetDecay(..., replay=fractions)`` returns those shares in the same order instead of reading the clock, so a
replay (``--replay``) trains with the record's rates to the last bit, on a machine of any speed.

Pickled with the model (SB3 saves its ``lr_schedule``): it holds numbers and the clock's name only (the readings
and a replay's shares are left out).
"""

from __future__ import annotations

import math
import time

__all__ = ["BudgetDecay", "budget_shares"]

_CLOCKS = {"cpu": time.process_time, "wall": time.perf_counter}


def budget_shares(values) -> tuple:
    """``values`` (a list or tuple: a record's ``lr_fractions``) as a tuple of floats, each a share of the budget left
    in ``[0, 1]``; ValueError otherwise (a bool is not a share)."""
    if not isinstance(values, (list, tuple)) or not all(
            isinstance(x, (int, float)) and not isinstance(x, bool) and 0.0 <= x <= 1.0 for x in values):
        raise ValueError("replay must be shares of the budget left, each a number in [0, 1]")
    return tuple(float(x) for x in values)


class BudgetDecay:
    """``initial`` falling linearly to 0 over ``budget_s`` seconds of ``clock`` from :meth:`start` (module
    docstring).

    Parameters
    ----------
    initial : float
        The rate at the start, finite and > 0 (SB3's PPO and SAC default: 3e-4).
    budget_s : float
        Seconds of ``clock`` over which it falls to 0, finite and > 0.
    clock : {"cpu", "wall"}
        This process's CPU time or the wall clock.
    replay : sequence of float, optional
        The shares of the budget left that a recorded run's calls read (its :attr:`readings`), returned in call
        order instead of the clock's: a replay's rates are the record's.  Each in ``[0, 1]``.

    Attributes
    ----------
    readings : list of float
        The share of the budget left that each call so far returned its rate for, in call order.
    """

    def __init__(self, initial: float, budget_s: float, clock: str = "cpu", replay=None):
        for name, value in (("initial", initial), ("budget_s", budget_s)):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                    or value <= 0:
                raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
        if clock not in _CLOCKS:
            raise ValueError(f"clock must be 'cpu' or 'wall', got {clock!r}")
        self.initial, self.budget_s, self.clock = float(initial), float(budget_s), clock
        self.readings = []
        self.replay = None if replay is None else budget_shares(replay)
        self.start()

    def start(self, at: float | None = None) -> None:
        """Start the budget now, or at ``at``, a reading of ``clock`` in seconds (the training's budget's own start:
        ``examples/train_sb3.py`` passes the reading its budget starts from, before the model is built, and again
        after any evaluation before the training)."""
        if at is not None and (isinstance(at, bool) or not isinstance(at, (int, float)) or not math.isfinite(at)):
            raise ValueError(f"at must be a finite reading of the clock, got {at!r}")
        self.started = _CLOCKS[self.clock]() if at is None else float(at)

    def fraction_left(self) -> float:
        """The share of the budget not yet spent, in [0, 1]."""
        return max(0.0, 1.0 - (_CLOCKS[self.clock]() - self.started) / self.budget_s)

    def __call__(self, progress_remaining: float) -> float:
        """The rate now (SB3's ``progress_remaining`` is not used: module docstring); in a replay the record's rate
        for this call.  Raises RuntimeError when a replay calls more often than its record did."""
        if self.replay is None:
            share = self.fraction_left()
        else:
            k = len(self.readings)
            if k >= len(self.replay):
                raise RuntimeError(f"--replay: the training read its learning rate {k + 1} times; the record "
                                   f"kept {len(self.replay)} readings (the runs differ)")
            share = self.replay[k]
        self.readings.append(share)
        return self.initial * share

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state["readings"], state["replay"] = [], None
        return state

    def __setstate__(self, state: dict) -> None:  # (a schedule pickled before the readings were kept has none)
        self.__dict__.update({"replay": None, **state, "readings": []})

    def __repr__(self) -> str:
        return f"BudgetDecay({self.initial!r}, {self.budget_s!r}, {self.clock!r})"
