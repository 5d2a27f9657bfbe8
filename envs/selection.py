"""The best policy of a training's validations, chosen within its budget (issue 18 item 4's model selection).

A training with ``--select-every M`` (``examples/train_sb3.py``, ``examples/rl_baselines.py``) stops every ``M``
budget minutes, runs its deterministic policy on ``--select-episodes E`` validation episodes, seeds ``S`` to
``S + E - 1`` (``--select-seed S``, default :data:`VALIDATION_SEED`: seeds that no held-out evaluation, test or
published figure uses; a validation range that meets the held-out seeds is refused), and keeps the policy with the
most validation successes (ties: the higher mean return; ties again: the earlier policy).  That kept policy is
the training's result: its model file, and every checkpoint's (the best validated by the checkpoint's time).
The held-out evaluation then runs it on the held-out seeds as before, so its success rate is an honest estimate
of the chosen policy's, however lucky the validations that chose it; the last policy's held-out success is
recorded beside it (``selection["last"]``), to show what the choice bought.

**The validations count in the budget.**  They run in the training's process on the budget's own clock, so
their time is spent budget: a run of ``--minutes 15 --select-every 1`` trains for 15 minutes less its
validations.  The last validation is started early enough to end at the budget: each starts when the time spent
plus :data:`COST_FACTOR` times the dearest validation so far reaches its due time (``k M`` minutes, or the
budget), so a run ends within a few seconds of its budget (``selection["cpu_s"]`` is their total,
``selection["validations"]`` each one's start, steps, successes and cost).

Why: the pinch's and the K fingers' learners can pass 80 % at one checkpoint and fall back at the next (the
pinch's seed 6: 86 % at 10 CPU-min, 66 % at 15), so a last policy is a draw from a moving curve.
Stable-Baselines3's ``EvalCallback`` keeps its best model the same way; this one counts its cost in the budget,
never looks at the held-out seeds, and ranks by success, the target's measure.  What it bought (the learning page,
``docs/learning.md``, "The best of validations kept"): nothing within 15 CPU-minutes on the pinch and the K
fingers, whose seeds there plateau or climb; the validations cost 6-8 % of the budget.  The validations draw no
random number, so a run with them trains the same policy as without them, step for step
(``tests/test_selection.py``), on less of the budget.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

__all__ = ["COST_FACTOR", "MAX_VALIDATIONS", "VALIDATION_SEED", "Selection", "SelectionSpec", "selection_conflict",
           "spec_from"]

#: the first validation seed by default: 20000-20049 meet no seed range the records, tests and figures use
VALIDATION_SEED = 20_000
#: a validation starts when ``spent + COST_FACTOR * (the dearest so far)`` reaches its due time
COST_FACTOR = 1.5
#: the most validations a training runs (``--minutes / --select-every``)
MAX_VALIDATIONS = 1000


@dataclass(frozen=True)
class SelectionSpec:
    """How a training chooses its policy: every ``every_minutes`` budget minutes, ``episodes`` validation
    episodes on seeds ``seed`` to ``seed + episodes - 1``."""

    every_minutes: float
    episodes: int = 50
    seed: int = VALIDATION_SEED

    @property
    def seeds(self) -> tuple[int, int]:
        """The first and last validation seed."""
        return self.seed, self.seed + self.episodes - 1


def selection_conflict(args, eval_seeds: tuple[int, int]) -> str | None:
    """Why the parsed options ``select_every``, ``select_episodes``, ``select_seed`` (with ``minutes`` and
    ``normalize``) cannot go together with the held-out seeds ``eval_seeds`` (first, last), or None: the other two
    without ``--select-every``, a period longer than the budget, more than :data:`MAX_VALIDATIONS` validations,
    ``--normalize`` (a chosen policy would need the statistics of its own time) or validation seeds that meet the
    held-out ones."""
    every = args.select_every
    if every is None:
        if args.select_episodes is not None or args.select_seed is not None:
            return "--select-episodes and --select-seed: only with --select-every"
        return None
    if every > args.minutes:
        return f"--select-every: larger than --minutes ({every:g} > {args.minutes:g}: no validation would run)"
    if args.minutes / every > MAX_VALIDATIONS:
        return (f"--select-every: {args.minutes:g} / {every:g} minutes is {args.minutes / every:.3g} validations; "
                f"at most {MAX_VALIDATIONS}")
    if args.normalize:
        return "--select-every: not with --normalize (the chosen policy would need VecNormalize's statistics of its time)"
    spec = spec_from(args)
    lo, hi = spec.seeds
    if lo <= eval_seeds[1] and eval_seeds[0] <= hi:
        return (f"--select-seed: the validation seeds {lo}-{hi} meet the held-out seeds "
                f"{eval_seeds[0]}-{eval_seeds[1]} (a policy chosen on them would be judged on them)")
    return None


def spec_from(args) -> SelectionSpec | None:
    """The :class:`SelectionSpec` of the parsed options, or None without ``--select-every``."""
    if args.select_every is None:
        return None
    return SelectionSpec(float(args.select_every),
                         SelectionSpec.episodes if args.select_episodes is None else int(args.select_episodes),
                         VALIDATION_SEED if args.select_seed is None else int(args.select_seed))


class Selection:
    """The validations of one training and the best policy so far (module docstring).

    Parameters
    ----------
    spec : SelectionSpec
    budget_s : float
        The budget in seconds of the training's clock.
    validate : callable
        ``validate(model) -> dict`` with ``success_rate`` and ``mean_return``: the deterministic policy on the
        validation episodes.
    save : callable
        ``save(model)``: keep ``model`` as the best so far (the training writes its model file).
    """

    def __init__(self, spec: SelectionSpec, budget_s: float, validate: Callable, save: Callable):
        self.spec, self.budget_s = spec, float(budget_s)
        self._validate, self._save = validate, save
        self.validations: list[dict] = []
        self.best: int | None = None  # index into validations
        self.cost = 0.0  # the dearest validation so far [s of the budget's clock]
        self.final = False  # the validation due at the budget has run

    def due(self) -> float:
        """The time [s] the next validation is due: ``k M`` minutes, at most the budget."""
        return min(60.0 * self.spec.every_minutes * (len(self.validations) + 1), self.budget_s)

    def step(self, model, now: float, timesteps: int, spent: Callable[[], float]) -> tuple[float, bool]:
        """Validate ``model`` if one is due at ``now`` (seconds spent).  Returns the seconds spent after it
        (``spent()`` read again only where a validation ran) and whether the validation due at the budget has run
        (the training then stops)."""
        if self.final or now + COST_FACTOR * self.cost < self.due():
            return now, self.final
        self.run(model, now, timesteps, spent)
        return spent(), self.final

    def run(self, model, now: float, timesteps: int, spent: Callable[[], float]) -> None:
        """Validate ``model`` now (``now``: seconds spent; ``spent()`` reads the clock again after it)."""
        final = self.due() >= self.budget_s
        result = self._validate(model)
        cost = spent() - now
        self.cost = max(self.cost, cost)
        row = {"minutes": round(now / 60.0, 4), "timesteps": int(timesteps),
               "success_rate": float(result["success_rate"]), "mean_return": float(result["mean_return"]),
               "cpu_s": round(cost, 3)}
        self.validations.append(row)
        if self.best is None or _rank(row) > _rank(self.validations[self.best]):
            self.best = len(self.validations) - 1
            self._save(model)
        self.final = self.final or final

    def record(self) -> dict:
        """``selection`` of ``<algo>_eval.json``: the spec, every validation, the one chosen and their cost."""
        return {"every_minutes": self.spec.every_minutes, "episodes": self.spec.episodes,
                "seeds": list(self.spec.seeds), "validations": self.validations, "chosen": self.best,
                "cpu_s": round(sum(v["cpu_s"] for v in self.validations), 3)}


def _rank(row: dict) -> tuple[float, float]:
    return row["success_rate"], row["mean_return"]
